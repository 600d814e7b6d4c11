/*
 * u64div.c - 64-bit unsigned division from 32-bit divisions (contract in u64div.h).
 */
#include "u64div.h"

#include <stddef.h>

#define HALF 65536u /* the base of the 16-bit digits */

/* leading zero bits of x != 0 (the M4's CLZ) */
static uint32_t lead_zeros(uint32_t x)
{
    return (uint32_t)__builtin_clz(x);
}

/* (u1:u0) / v for u1 < v (so the quotient fits 32 bits), the remainder into *r: two
 * 16-bit quotient digits, each estimated by one 32-bit division by the normalised
 * divisor's high half and corrected at most twice (Hacker's Delight 9-3, divlu) */
static uint32_t div_2by1(uint32_t u1, uint32_t u0, uint32_t v, uint32_t *r)
{
    const uint32_t s = lead_zeros(v);
    const uint32_t vn = v << s;
    const uint32_t vn1 = vn >> 16;
    const uint32_t vn0 = vn & 0xFFFFu;
    const uint32_t un32 = (s == 0u) ? u1 : ((u1 << s) | (u0 >> (32u - s)));
    const uint32_t un10 = u0 << s;
    const uint32_t un1 = un10 >> 16;
    const uint32_t un0 = un10 & 0xFFFFu;

    uint32_t q1 = un32 / vn1;
    uint32_t rhat = un32 - (q1 * vn1);
    while ((q1 >= HALF) || ((q1 * vn0) > ((rhat * HALF) + un1))) {
        q1--;
        rhat += vn1;
        if (rhat >= HALF) {
            break;
        }
    }
    const uint32_t un21 = ((un32 * HALF) + un1) - (q1 * vn);

    uint32_t q0 = un21 / vn1;
    rhat = un21 - (q0 * vn1);
    while ((q0 >= HALF) || ((q0 * vn0) > ((rhat * HALF) + un0))) {
        q0--;
        rhat += vn1;
        if (rhat >= HALF) {
            break;
        }
    }
    *r = (((un21 * HALF) + un0) - (q0 * vn)) >> s;
    return (q1 * HALF) + q0;
}

uint64_t u64_divmod(uint64_t n, uint64_t d, uint64_t *rem)
{
    const uint32_t nh = (uint32_t)(n >> 32);
    const uint32_t nl = (uint32_t)n;
    const uint32_t dh = (uint32_t)(d >> 32);
    uint64_t q;
    uint64_t r;
    if (dh == 0u) {
        const uint32_t dl = (uint32_t)d;
        uint32_t r32;
        if (nh == 0u) { /* both 32-bit: one UDIV */
            const uint32_t q32 = nl / dl;
            r32 = nl - (q32 * dl);
            q = q32;
        } else if (nh < dl) { /* a 32-bit quotient */
            q = div_2by1(nh, nl, dl, &r32);
        } else { /* the high word first, then its remainder with the low word */
            const uint32_t qh = nh / dl;
            const uint32_t ql = div_2by1(nh - (qh * dl), nl, dl, &r32);
            q = ((uint64_t)qh << 32) | ql;
        }
        r = r32;
    } else {
        /* d >= 2^32, so the quotient fits 32 bits: estimated from n / 2 and the divisor's
         * 32 leading bits, it is the quotient or one above it (Hacker's Delight 9-5,
         * divDu); dh != 0 so s < 32, and (n / 2) >> 32 < 2^31 <= v1 */
        const uint32_t s = lead_zeros(dh);
        const uint32_t v1 = (uint32_t)((d << s) >> 32);
        const uint64_t n2 = n >> 1;
        uint32_t unused;
        const uint32_t q1 = div_2by1((uint32_t)(n2 >> 32), (uint32_t)n2, v1, &unused);
        uint64_t q0 = ((uint64_t)q1 << s) >> 31;
        if (q0 != 0u) {
            q0--;
        }
        r = n - (q0 * d);
        if (r >= d) {
            q0++;
            r -= d;
        }
        q = q0;
    }
    if (rem != NULL) {
        *rem = r;
    }
    return q;
}

#if defined(__ARM_EABI__)
/* libgcc's __aeabi_uldivmod and __aeabi_ldivmod call it for a non-zero divisor */
uint64_t __udivmoddi4(uint64_t n, uint64_t d, uint64_t *rem);

uint64_t __udivmoddi4(uint64_t n, uint64_t d, uint64_t *rem)
{
    return u64_divmod(n, d, rem);
}
#endif
