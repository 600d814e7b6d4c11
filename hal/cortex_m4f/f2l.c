/*
 * f2l.c - float to 64-bit integer conversions from the IEEE 754 bits (contracts in f2l.h).
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

#if defined(__ARM_EABI__)
/* The RTABI helpers use the base procedure call standard: the float arrives in r0 even
 * in a hard-float (-mfloat-abi=hard) program, hence pcs("aapcs"). */
int64_t __aeabi_f2lz(float x) __attribute__((pcs("aapcs")));
uint64_t __aeabi_f2ulz(float x) __attribute__((pcs("aapcs")));

int64_t __aeabi_f2lz(float x)
{
    return f2l_to_i64(x);
}

uint64_t __aeabi_f2ulz(float x)
{
    return f2l_to_u64(x);
}
#endif
