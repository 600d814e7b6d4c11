/*
 * nav_trig.c - float32 sine, cosine, arc tangent and arc sine of the firmware's own.
 *
 * Why not libm: sinf/cosf/atan2f/asinf of glibc (host) and newlib (Cortex-M4F) round
 * differently in the last bit, so the same input log would give different output frames
 * on the two targets. These functions use only + - * / and sqrtf (IEEE 754 correctly
 * rounded on both: SSE on x86-64, VFPv4-SP on the M4F) with -ffp-contract=off, so they
 * return the same bits everywhere (docs/numeric-design.md, issue #8's bit-exactness).
 *
 * Method (the classic Cody-Waite / Cephes scheme, written out here):
 * - sin, cos: x = n pi/2 + r with n the nearest integer to x 2/pi and |r| <= pi/4, pi/2
 *   split into three parts of which the first two have at most 11 significant bits, so
 *   n * part is exact for |n| < 2^13 (|x| < 12867 rad); then a degree-7 (sine) or
 *   degree-8 (cosine) minimax polynomial in r picked by n mod 4. The polynomial
 *   coefficients are Cephes' single-precision minimax sets (S. Moshier, "Methods and
 *   Programs for Mathematical Functions", 1989), relative error below 2^-24 on
 *   [-pi/4, pi/4].
 * - atan2: the ratio t = min(|x|,|y|) / max(|x|,|y|) in [0, 1], reduced with
 *   atan t = pi/4 + atan((t - 1) / (t + 1)) when t > tan(pi/8), a degree-9 odd
 *   polynomial on |u| <= tan(pi/8), then the octant.
 * - asin: a degree-11 odd polynomial for |x| <= 1/2; for 1/2 < |x| <= 1
 *   asin x = pi/2 - 2 asin(sqrt((1 - |x|) / 2)).
 * Accuracy against the double libm (tests/test_trig.c, whose bounds these are; measured
 * worst in brackets): sin/cos within 2 ulp for |x| <= pi (1.55); for pi < |x| <= 12867 an
 * absolute error below 2^-23 (9.4e-8; near the zeros at multiples of pi/2 that is many
 * ulp of a tiny result: the reduction steps round at the scale of x, not of the result);
 * atan2 within 3.5 ulp (2.9); asin within 3 ulp (2.4). Beyond |x| = 12867 sin/cos lose
 * accuracy in proportion to |x| (no navigation angle gets there: the core keeps angles
 * wrapped to [-pi, pi]); beyond 2^18 rad, and for a NaN or an infinite argument, they
 * return NaN rather than a meaningless number.
 */
#include "nav_types.h"

#include <math.h>

#if !defined(NAV_REAL_DOUBLE)

/* pi/2 = PIO2_A + PIO2_B + PIO2_C; A and B have 11 significant bits (exact products
 * with |n| < 2^13), C is pi/2 - A - B rounded to float */
#define PIO2_A 1.5703125f                 /* 0x3FC90000 */
#define PIO2_B 4.837512969970703125e-4f   /* 0x39FDA000 */
#define PIO2_C 7.54978995e-8f             /* pi/2 - A - B */
#define TWO_OVER_PI 0.636619772f
#define PI_F 3.14159274f                  /* float(pi) */
#define PIO2_F 1.57079637f                /* float(pi/2) */
#define PIO4_F 0.785398185f               /* float(pi/4) */
#define SIN_IS_X 2.44140625e-4f           /* 2^-12 */
#define TAN_PI_8 0.414213562f
#define REDUCE_MAX 12867.0f               /* 2^13 pi/2: |n| <= 2^13 */
#define WRAP_MAX 262144.0f                /* 2^18: largest argument accepted */

/* sin r, |r| <= pi/4 (Cephes sinf coefficients) */
static float sin_kernel(float r)
{
    const float z = r * r;
    return r + r * z * ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f);
}

/* cos r, |r| <= pi/4 (Cephes cosf coefficients) */
static float cos_kernel(float r)
{
    const float z = r * r;
    return 1.0f - 0.5f * z +
           z * z * ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z +
                    4.166664568298827e-2f);
}

/* r = x - n pi/2 with |r| <= pi/4 (about), n mod 4 in *quadrant. |x| <= REDUCE_MAX. */
static float reduce_pio2(float x, unsigned *quadrant)
{
    const float t = x * TWO_OVER_PI;
    const int32_t n = (int32_t)(t >= 0.0f ? t + 0.5f : t - 0.5f);
    const float fn = (float)n;
    *quadrant = (unsigned)n & 3u;
    return ((x - fn * PIO2_A) - fn * PIO2_B) - fn * PIO2_C;
}

/* the argument wrapped to |x| <= REDUCE_MAX; NaN for NaN, infinities and |x| > WRAP_MAX */
static float wrap_argument(float x)
{
    if (!isfinite(x) || x > WRAP_MAX || x < -WRAP_MAX) {
        return (x - x) / (x - x);
    }
    if (x > REDUCE_MAX || x < -REDUCE_MAX) {
        /* x - 2 pi round(x / 2 pi): whole turns < 2^16, so whole * 4 A (8 bits) is exact
         * and the other two products round: an absolute error near |x| 2^-24 */
        const float turns = x * (0.5f * TWO_OVER_PI);
        const float whole = (float)(int32_t)(turns >= 0.0f ? turns + 0.5f : turns - 0.5f);
        return ((x - whole * (4.0f * PIO2_A)) - whole * (4.0f * PIO2_B)) -
               whole * (4.0f * PIO2_C);
    }
    return x;
}

float navf_sin(float x)
{
    unsigned q;
    const float w = wrap_argument(x);
    if (isnan(w)) {
        return w;
    }
    if (w < SIN_IS_X && w > -SIN_IS_X) {
        return w; /* x^3/6 is below half an ulp of x; keeps the sign of -0 */
    }
    const float r = reduce_pio2(w, &q);
    switch (q) {
    case 0u:
        return sin_kernel(r);
    case 1u:
        return cos_kernel(r);
    case 2u:
        return -sin_kernel(r);
    default:
        return -cos_kernel(r);
    }
}

float navf_cos(float x)
{
    unsigned q;
    const float w = wrap_argument(x);
    if (isnan(w)) {
        return w;
    }
    const float r = reduce_pio2(w, &q);
    switch (q) {
    case 0u:
        return cos_kernel(r);
    case 1u:
        return -sin_kernel(r);
    case 2u:
        return -cos_kernel(r);
    default:
        return sin_kernel(r);
    }
}

/* atan t for 0 <= t <= 1 */
static float atan_unit(float t)
{
    float base = 0.0f;
    float u = t;
    if (t > TAN_PI_8) {
        base = PIO4_F;
        u = (t - 1.0f) / (t + 1.0f);
    }
    const float z = u * u;
    /* Cephes atanf coefficients, |u| <= tan(pi/8) */
    const float p = (((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z -
                     3.33329491539e-1f);
    return base + (u + u * z * p);
}

float navf_atan2(float y, float x)
{
    if (isnan(x) || isnan(y)) {
        return x + y; /* NaN */
    }
    const float ax = x < 0.0f ? -x : x;
    const float ay = y < 0.0f ? -y : y;
    float a;
    if (!(ay > 0.0f)) {
        a = 0.0f;
    } else if (!(ax < ay) && !(ax > ay)) {
        a = PIO4_F; /* also both infinite */
    } else if (ay > ax) {
        a = PIO2_F - atan_unit(ax / ay); /* ax / ay in [0, 1); 0 when ay is infinite */
    } else {
        a = atan_unit(ay / ax);
    }
    /* the sign bits, also of -0.0: atan2(+-0, -0) = +-pi, atan2(-0, +0) = -0 */
    if (signbit(x)) {
        a = PI_F - a;
    }
    return signbit(y) ? -a : a;
}

/* asin x for |x| <= 1/2, odd polynomial (Cephes asinf coefficients) */
static float asin_small(float x)
{
    const float z = x * x;
    const float p = ((((4.2163199048e-2f * z + 2.4181311049e-2f) * z + 4.5470025998e-2f) * z +
                      7.4953002686e-2f) * z + 1.6666752422e-1f);
    return x + x * z * p;
}

float navf_asin(float x)
{
    const float ax = x < 0.0f ? -x : x;
    if (!(ax <= 1.0f)) {
        return (x - x) / (x - x); /* NaN for |x| > 1 and NaN */
    }
    if (ax <= 0.5f) {
        return asin_small(x);
    }
    const float s = sqrtf(0.5f * (1.0f - ax));
    const float a = PIO2_F - 2.0f * asin_small(s);
    return x < 0.0f ? -a : a;
}

#else
/* the double reference variant uses libm (nav_types.h); ISO C wants a declaration here */
typedef int nav_trig_unused_t;
#endif
