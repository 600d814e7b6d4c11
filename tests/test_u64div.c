/*
 * test_u64div.c - the 64-bit division of the Cortex-M4F images (hal/cortex_m4f/u64div.c,
 * their __udivmoddi4) against the host compiler's own 64-bit division and remainder.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "u64div.h"

/* a small deterministic generator (xorshift64*) */
static uint64_t next_random(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return *s * UINT64_C(2685821657736338717);
}

static void check(uint64_t n, uint64_t d)
{
    uint64_t r = UINT64_C(0xDEADBEEF);
    const uint64_t q = u64_divmod(n, d, &r);
    assert_true(q == n / d);
    assert_true(r == n % d);
    assert_true(u64_divmod(n, d, NULL) == n / d);
}

/* random dividends and divisors of every pair of bit lengths (1..64 each), so every
 * branch: both 32-bit, a 32-bit quotient, a 64-bit quotient, a divisor of 33..64 bits */
static void test_random_lengths_match_c(void **state)
{
    (void)state;
    uint64_t s = UINT64_C(0x9E3779B97F4A7C15);
    unsigned checked = 0u;
    for (unsigned ln = 1u; ln <= 64u; ln++) {
        for (unsigned ld = 1u; ld <= 64u; ld++) {
            for (unsigned k = 0u; k < 600u; k++) {
                const uint64_t n = next_random(&s) >> (64u - ln);
                const uint64_t d = (next_random(&s) >> (64u - ld)) | (UINT64_C(1) << (ld - 1u));
                check(n, d);
                checked++;
            }
        }
    }
    print_message("%u random divisions checked against the compiler's\n", checked);
}

/* the edges: powers of two and their neighbours, all-ones, n = d and n = d +- 1, and the
 * divisors whose estimates need the corrections (high half 0x8000, low half large) */
static void test_edges_match_c(void **state)
{
    (void)state;
    uint64_t v[64 * 5 + 16];
    unsigned m = 0u;
    for (unsigned e = 0u; e < 64u; e++) {
        const uint64_t p = UINT64_C(1) << e;
        v[m++] = p;
        v[m++] = p - 1u;
        v[m++] = p + 1u;
        v[m++] = ~p;
        v[m++] = p | (p >> 1) | 1u;
    }
    const uint64_t extra[16] = {
        UINT64_MAX, UINT64_MAX - 1u, 0x80000000u, 0x8000FFFFu, 0x80008000u, 0xFFFF0000u,
        0xFFFFFFFFu, 0x0000FFFF0000FFFFu, 0x80000000FFFFFFFFu, 0x800000007FFFFFFFu,
        0x7FFFFFFF80000000u, 0xFFFFFFFF00000000u, 1000000u, 1000u, 200u, 0x123456789ABCDEFu};
    for (unsigned k = 0u; k < 16u; k++) {
        v[m++] = extra[k];
    }
    for (unsigned i = 0u; i < m; i++) {
        check(0u, v[i] == 0u ? 1u : v[i]);
        for (unsigned j = 0u; j < m; j++) {
            if (v[j] != 0u) {
                check(v[i], v[j]);
            }
        }
    }
    /* the firmware's: microseconds to milliseconds and seconds, counts modulo rates */
    check(UINT64_C(4102444800000000), 1000u);
    check(UINT64_C(4102444800000123), 1000000u);
    check(UINT64_C(123456789012), 200u);
}

/* the correction steps of each digit: divisors with a normalised high half at 0x8000
 * (the largest estimate error) against random dividends */
static void test_worst_estimates_match_c(void **state)
{
    (void)state;
    uint64_t s = UINT64_C(0x0123456789ABCDEF);
    for (unsigned k = 0u; k < 2000000u; k++) {
        const unsigned shift = k % 33u;
        const uint64_t d = (UINT64_C(0x80000000) | (next_random(&s) & 0xFFFFu)) >> (shift % 32u)
                           << (shift == 32u ? 32u : 0u);
        const uint64_t n = next_random(&s) >> (k % 64u);
        check(n, d == 0u ? 1u : d);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_lengths_match_c),
        cmocka_unit_test(test_edges_match_c),
        cmocka_unit_test(test_worst_estimates_match_c),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
