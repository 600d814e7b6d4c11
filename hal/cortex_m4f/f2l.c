/*
 * f2l.c - float to 64-bit integer conversions from the IEEE 754 bits, and 64-bit integer
 * to float conversions with the FPU's 32-bit VCVT (contracts in f2l.h).
 */
#include "f2l.h"

#include <string.h>

#define EXP_BIAS 127
#define MANT_BITS 23

/* |x| truncated toward zero, saturated to 2^64 - 1; x given as (exponent, mantissa) */
static uint64_t magnitude_trunc(uint32_t exp_field, uint32_t mant_field)
{
    if (exp_field < (uint32_t)EXP_BIAS) {
        return 0u; /* |x| < 1, zeros and subnormals */
    }
    const uint32_t e = exp_field - (uint32_t)EXP_BIAS; /* |x| in [2^e, 2^(e+1)) */
    if (e >= 64u) {
        return UINT64_MAX; /* also infinities (exp_field 255); NaN is handled before */
    }
    const uint64_t m = (uint64_t)(mant_field | (1u << MANT_BITS)); /* 24 bits */
    return e >= (uint32_t)MANT_BITS ? m << (e - (uint32_t)MANT_BITS)
                                    : m >> ((uint32_t)MANT_BITS - e);
}

static void split(float x, uint32_t *sign, uint32_t *exp_field, uint32_t *mant_field)
{
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits);
    *sign = bits >> 31;
    *exp_field = (bits >> MANT_BITS) & 0xFFu;
    *mant_field = bits & ((1u << MANT_BITS) - 1u);
}

int64_t f2l_to_i64(float x)
{
    uint32_t sign, exp_field, mant_field;
    split(x, &sign, &exp_field, &mant_field);
    if (exp_field == 0xFFu && mant_field != 0u) {
        return 0; /* NaN */
    }
    const uint64_t mag = magnitude_trunc(exp_field, mant_field);
    if (sign != 0u) {
        return mag >= (UINT64_C(1) << 63) ? INT64_MIN : -(int64_t)mag;
    }
    return mag > (uint64_t)INT64_MAX ? INT64_MAX : (int64_t)mag;
}

uint64_t f2l_to_u64(float x)
{
    uint32_t sign, exp_field, mant_field;
    split(x, &sign, &exp_field, &mant_field);
    if (sign != 0u || (exp_field == 0xFFu && mant_field != 0u)) {
        return 0u; /* negative (also -0.5 truncates to 0) or NaN */
    }
    return magnitude_trunc(exp_field, mant_field);
}

float f2l_from_u64(uint64_t x)
{
    const uint32_t hi = (uint32_t)(x >> 32);
    const uint32_t lo = (uint32_t)x;
    if (hi == 0u) {
        return (float)lo; /* one VCVT, rounded to nearest, ties to even */
    }
    /* x has 64 - c significant bits, c in [0, 31]: its 32 leading bits, with the bits
     * below them ORed into the lowest one (a sticky bit, well below the rounding position
     * of a 24-bit significand), round to the float x rounds to; scaling that by
     * 2^(31 - c) and by 2 is exact (powers of two, the result below 2^64) */
    const uint32_t c = (uint32_t)__builtin_clz(hi);
    uint32_t top = hi;
    uint32_t rest = lo;
    if (c != 0u) {
        top = (hi << c) | (lo >> (32u - c));
        rest = lo << c;
    }
    const uint32_t rounded_as_x = top | (rest != 0u ? 1u : 0u);
    const uint32_t scale = UINT32_C(1) << (31u - c);
    return (float)rounded_as_x * (float)scale * 2.0f;
}

float f2l_from_i64(int64_t x)
{
    /* the magnitude as unsigned (also of INT64_MIN); rounding is symmetric about 0 */
    const uint64_t mag = x < 0 ? 0u - (uint64_t)x : (uint64_t)x;
    const float f = f2l_from_u64(mag);
    return x < 0 ? -f : f;
}

#if defined(__ARM_EABI__)
/* The RTABI helpers use the base procedure call standard: the float arrives in r0 even
 * in a hard-float (-mfloat-abi=hard) program, hence pcs("aapcs"). */
int64_t __aeabi_f2lz(float x) __attribute__((pcs("aapcs")));
uint64_t __aeabi_f2ulz(float x) __attribute__((pcs("aapcs")));
float __aeabi_l2f(int64_t x) __attribute__((pcs("aapcs")));
float __aeabi_ul2f(uint64_t x) __attribute__((pcs("aapcs"), noinline));

int64_t __aeabi_f2lz(float x)
{
    return f2l_to_i64(x);
}

uint64_t __aeabi_f2ulz(float x)
{
    return f2l_to_u64(x);
}
/* libgcc's int64-to-float helpers sit in its soft-float adder (_arm_addsubsf3.o), which
 * they pull into the image with them: 540 bytes for a conversion the FPU does in a few
 * instructions. These give the same float (IEEE 754, round to nearest, ties to even). */
float __aeabi_ul2f(uint64_t x)
{
    return f2l_from_u64(x);
}

float __aeabi_l2f(int64_t x)
{
    /* f2l_from_i64 through the one copy of the unsigned conversion */
    const float f = __aeabi_ul2f(x < 0 ? 0u - (uint64_t)x : (uint64_t)x);
    return x < 0 ? -f : f;
}
#endif
