/*
 * test_trig.c - the firmware's own float32 trig (firmware/nav/nav_trig.c) against the
 * double-precision libm of the host, over dense pseudo-random sweeps.
 *
 * Tolerances, in units in the last place (ulp) of the float nearest the exact value:
 * sin/cos 2 ulp on |x| <= pi (the minimax kernel's 2^-24 relative error, about 1 ulp,
 * plus the final rounding and the reduction's last bit); an absolute 2^-23 on
 * |x| <= 12867 (the reduction steps round at the scale of x, not of the reduced
 * argument, so near a zero of sin or cos the error is small in absolute terms only); atan2 3.5 ulp (the quotient's rounding, the kernel's 1 ulp,
 * and the subtraction from pi/2 or pi, each about 1 ulp); asin 3 ulp (the sqrt and the
 * pi/2 - 2 s p(s) step near |x| = 1). The sweeps are repeatable (xorshift, fixed seed).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <math.h>
#include <string.h>
#include <cmocka.h>

#include "nav_types.h"

#define N_SWEEP 1000000

static uint64_t rng_state;

static double uniform(void) /* [0, 1) */
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* the spacing of floats at |ref| (the smallest subnormal below FLT_MIN) */
static double ulp_at(double ref)
{
    const double a = fabs(ref);
    int e;
    if (a < 1.17549435e-38) {
        return ldexp(1.0, -149);
    }
    (void)frexp(a, &e);
    return ldexp(1.0, e - 24);
}

/* bit-for-bit equality (also tells -0 from +0) */
static int same_bits(float a, float b)
{
    uint32_t ua;
    uint32_t ub;
    memcpy(&ua, &a, sizeof ua);
    memcpy(&ub, &b, sizeof ub);
    return ua == ub;
}

static double ulp_error(float got, double ref)
{
    return fabs((double)got - ref) / ulp_at(ref);
}

static void test_sin_cos_within_2_ulp_on_plus_minus_pi(void **state)
{
    (void)state;
    rng_state = 0x9E3779B97F4A7C15u;
    double worst = 0.0;
    for (int i = 0; i < N_SWEEP; i++) {
        const float x = (float)((2.0 * uniform() - 1.0) * M_PI);
        worst = fmax(worst, ulp_error(navf_sin(x), sin((double)x)));
        worst = fmax(worst, ulp_error(navf_cos(x), cos((double)x)));
    }
    print_message("sin/cos on [-pi, pi]: worst %.3f ulp\n", worst);
    assert_true(worst <= 2.0);
}

static void test_sin_cos_absolute_error_up_to_12867_rad(void **state)
{
    (void)state;
    rng_state = 0x2545F4914F6CDD1Du;
    double worst = 0.0;
    for (int i = 0; i < N_SWEEP; i++) {
        const float x = (float)((2.0 * uniform() - 1.0) * 12867.0);
        worst = fmax(worst, fabs((double)navf_sin(x) - sin((double)x)));
        worst = fmax(worst, fabs((double)navf_cos(x) - cos((double)x)));
    }
    print_message("sin/cos on [-12867, 12867]: worst absolute error %.3g\n", worst);
    assert_true(worst <= ldexp(1.0, -23));
}

static void test_sin_cos_exact_points_and_symmetry(void **state)
{
    (void)state;
    assert_true(same_bits(navf_sin(0.0f), 0.0f));
    assert_true(same_bits(navf_sin(-0.0f), -0.0f));
    assert_true(same_bits(navf_cos(0.0f), 1.0f));
    /* odd / even, bit for bit, so a mirrored drive gives mirrored results */
    rng_state = 0x1234567u;
    for (int i = 0; i < 10000; i++) {
        const float x = (float)(uniform() * 100.0);
        assert_true(same_bits(navf_sin(-x), -navf_sin(x)));
        assert_true(same_bits(navf_cos(-x), navf_cos(x)));
    }
    /* tiny arguments: sin x = x */
    assert_true(same_bits(navf_sin(1e-20f), 1e-20f));
}

static void test_sin_cos_reject_what_has_no_meaningful_value(void **state)
{
    (void)state;
    assert_true(isnan(navf_sin(NAN)) && isnan(navf_cos(NAN)));
    assert_true(isnan(navf_sin(INFINITY)) && isnan(navf_cos(-INFINITY)));
    assert_true(isnan(navf_sin(3e5f)) && isnan(navf_cos(-3e38f)));
    /* just inside the accepted range: finite and within [-1, 1] */
    const float s = navf_sin(2.6e5f);
    assert_true(isfinite(s) && fabsf(s) <= 1.0f);
    assert_true(fabs((double)s - sin(2.6e5)) < 1e-2);
}

static void test_atan2_within_3_5_ulp(void **state)
{
    (void)state;
    rng_state = 0x7F4A7C159E3779B9u;
    double worst = 0.0;
    for (int i = 0; i < N_SWEEP; i++) {
        const float y = (float)((2.0 * uniform() - 1.0) * pow(10.0, 8.0 * uniform() - 4.0));
        const float x = (float)((2.0 * uniform() - 1.0) * pow(10.0, 8.0 * uniform() - 4.0));
        worst = fmax(worst, ulp_error(navf_atan2(y, x), atan2((double)y, (double)x)));
    }
    print_message("atan2: worst %.3f ulp\n", worst);
    assert_true(worst <= 3.5);
}

static void test_atan2_signed_zeros_axes_and_infinities(void **state)
{
    (void)state;
    const float pi = (float)M_PI;
    const float pio2 = (float)M_PI_2;
    assert_true(same_bits(navf_atan2(0.0f, 1.0f), 0.0f));
    assert_true(same_bits(navf_atan2(-0.0f, 1.0f), -0.0f));
    assert_true(same_bits(navf_atan2(0.0f, -0.0f), pi));
    assert_true(same_bits(navf_atan2(-0.0f, -0.0f), -pi));
    assert_true(same_bits(navf_atan2(0.0f, -1.0f), pi));
    assert_true(same_bits(navf_atan2(1.0f, 0.0f), pio2));
    assert_true(same_bits(navf_atan2(-1.0f, -0.0f), -pio2));
    assert_true(same_bits(navf_atan2(INFINITY, 1.0f), pio2));
    assert_true(same_bits(navf_atan2(1.0f, INFINITY), 0.0f));
    assert_true(same_bits(navf_atan2(1.0f, -INFINITY), pi));
    assert_true(same_bits(navf_atan2(INFINITY, INFINITY), (float)M_PI_4));
    assert_true(fabs((double)navf_atan2(-INFINITY, -INFINITY) + 3.0 * M_PI_4) < 4e-7);
    assert_true(isnan(navf_atan2(NAN, 1.0f)) && isnan(navf_atan2(1.0f, NAN)));
    /* the four quadrants of a unit circle, 1 ulp apart from libm at most there */
    for (int k = -179; k <= 180; k++) {
        const double a = (double)k * M_PI / 180.0;
        const float got = navf_atan2((float)sin(a), (float)cos(a));
        assert_true(fabs((double)got - a) < 4.0 * ulp_at(a) + 1e-7);
    }
}

static void test_asin_within_3_ulp_and_domain(void **state)
{
    (void)state;
    rng_state = 0x4F6CDD1D2545F491u;
    double worst = 0.0;
    for (int i = 0; i < N_SWEEP; i++) {
        const float x = (float)(2.0 * uniform() - 1.0);
        worst = fmax(worst, ulp_error(navf_asin(x), asin((double)x)));
    }
    print_message("asin: worst %.3f ulp\n", worst);
    assert_true(worst <= 3.0);
    assert_true(same_bits(navf_asin(1.0f), (float)M_PI_2) && same_bits(navf_asin(-1.0f), -(float)M_PI_2));
    assert_true(same_bits(navf_asin(0.0f), 0.0f) && same_bits(navf_asin(-0.0f), -0.0f));
    assert_true(isnan(navf_asin(1.0000001f)) && isnan(navf_asin(-2.0f)) && isnan(navf_asin(NAN)));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sin_cos_within_2_ulp_on_plus_minus_pi),
        cmocka_unit_test(test_sin_cos_absolute_error_up_to_12867_rad),
        cmocka_unit_test(test_sin_cos_exact_points_and_symmetry),
        cmocka_unit_test(test_sin_cos_reject_what_has_no_meaningful_value),
        cmocka_unit_test(test_atan2_within_3_5_ulp),
        cmocka_unit_test(test_atan2_signed_zeros_axes_and_infinities),
        cmocka_unit_test(test_asin_within_3_ulp_and_domain),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
