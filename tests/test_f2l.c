/*
 * test_f2l.c - the double-free float to 64-bit integer conversions of the Cortex-M4F
 * images (hal/cortex_m4f/f2l.c) against the host compiler's own conversions (x86-64
 * cvttss2si, exact by IEEE 754) wherever C defines the result, and their saturation
 * where it does not; and the conversions back (f2l_from_i64/u64, the M4F's
 * __aeabi_l2f/__aeabi_ul2f) against the host's (x86-64 cvtsi2ss, rounded to nearest even).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <math.h>
#include <string.h>
#include <cmocka.h>

#include "f2l.h"

static float from_bits(uint32_t b)
{
    float x;
    memcpy(&x, &b, sizeof x);
    return x;
}

/* every float with |x| < 2^63 (signed) or 0 <= x < 2^64 (unsigned), by a stride through
 * the bit patterns that hits every exponent and many mantissas, plus the neighbours of
 * each power of two */
static void test_matches_c_conversion_wherever_c_defines_it(void **state)
{
    (void)state;
    unsigned checked = 0u;
    for (uint64_t b = 0u; b < 0x7F800000u; b += 997u) {
        for (int s = 0; s < 2; s++) {
            const float x = from_bits((uint32_t)b | (s ? 0x80000000u : 0u));
            if (fabsf(x) < 9.2233720e18f) {
                assert_int_equal(f2l_to_i64(x), (int64_t)x);
                checked++;
            }
            if (x > -1.0f && x < 1.8446743e19f) {
                assert_true(f2l_to_u64(x) == (uint64_t)x);
                checked++;
            }
        }
    }
    for (int e = -3; e < 63; e++) {
        const float p = ldexpf(1.0f, e);
        const float around[3] = {nextafterf(p, 0.0f), p, nextafterf(p, INFINITY)};
        for (int k = 0; k < 3; k++) {
            if (around[k] < 9.2233720e18f) {
                assert_int_equal(f2l_to_i64(around[k]), (int64_t)around[k]);
                assert_int_equal(f2l_to_i64(-around[k]), (int64_t)-around[k]);
            }
            assert_true(f2l_to_u64(around[k]) == (uint64_t)around[k]);
        }
    }
    print_message("%u conversions checked against the compiler's\n", checked);
}

static void test_truncates_toward_zero(void **state)
{
    (void)state;
    assert_int_equal(f2l_to_i64(2.9f), 2);
    assert_int_equal(f2l_to_i64(-2.9f), -2);
    assert_int_equal(f2l_to_i64(-0.5f), 0);
    assert_true(f2l_to_u64(0.999f) == 0u);
    assert_true(f2l_to_u64(-0.999f) == 0u);
    assert_int_equal(f2l_to_i64(16777217.0f), 16777216); /* the float nearest */
    assert_int_equal(f2l_to_i64(-1.0e18f), (int64_t)-1.0e18f);
}

static void test_saturates_where_c_is_undefined(void **state)
{
    (void)state;
    assert_true(f2l_to_i64(NAN) == 0 && f2l_to_u64(NAN) == 0u);
    assert_true(f2l_to_i64(INFINITY) == INT64_MAX);
    assert_true(f2l_to_i64(-INFINITY) == INT64_MIN);
    assert_true(f2l_to_i64(1e19f) == INT64_MAX);
    assert_true(f2l_to_i64(-9.2233720e18f) == INT64_MIN); /* exactly -2^63: in range */
    assert_true(f2l_to_i64(-1e19f) == INT64_MIN);
    assert_true(f2l_to_u64(INFINITY) == UINT64_MAX);
    assert_true(f2l_to_u64(1e20f) == UINT64_MAX);
    assert_true(f2l_to_u64(-5.0f) == 0u);
    assert_true(f2l_to_u64(-INFINITY) == 0u);
}

/* a small deterministic generator (xorshift64*) for the integers to convert */
static uint64_t next_random(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return *s * UINT64_C(2685821657736338717);
}

/* the same float, bit for bit (also tells -0 from +0) */
static int same(float a, float b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

static void check_back(uint64_t u)
{
    assert_true(same(f2l_from_u64(u), (float)u));
    const int64_t i = (int64_t)u;
    assert_true(same(f2l_from_i64(i), (float)i));
}

/* every bit length, the neighbours of each power of two and of each rounding boundary
 * (the halfway points between floats, ties to even both ways, with and without sticky
 * bits far below), and random integers of every length */
static void test_to_float_matches_c_conversion(void **state)
{
    (void)state;
    unsigned checked = 0u;
    for (unsigned e = 0u; e < 64u; e++) {
        const uint64_t p = UINT64_C(1) << e;
        for (uint64_t d = 0u; d < 5u; d++) {
            check_back(p + d);
            check_back(p - d);
            check_back(~(p + d));
            checked += 3u;
        }
        if (e >= 25u) {
            /* p + k ulp/2 around the 24-bit significand's rounding position */
            const uint64_t half = UINT64_C(1) << (e - 24u);
            for (uint64_t k = 0u; k < 8u; k++) {
                const uint64_t base = p + k * half;
                check_back(base);
                check_back(base + 1u);
                check_back(base - 1u);
                check_back(base | (p >> 1)); /* an odd significand: ties go up */
                check_back((base | (p >> 1)) + 1u);
                check_back((base | (p >> 1)) - 1u);
                checked += 6u;
            }
        }
    }
    check_back(0u);
    check_back(UINT64_MAX);
    check_back((uint64_t)INT64_MAX);
    check_back((uint64_t)INT64_MIN);
    uint64_t s = UINT64_C(0x9E3779B97F4A7C15);
    for (unsigned k = 0u; k < 2000000u; k++) {
        const uint64_t r = next_random(&s);
        check_back(r >> (k % 64u));
        checked++;
    }
    assert_true(same(f2l_from_i64(0), 0.0f));
    assert_true(same(f2l_from_i64(INT64_MIN), -9.2233720e18f));
    assert_true(same(f2l_from_u64(UINT64_MAX), 1.8446744e19f));
    assert_true(same(f2l_from_u64(16777217u), 16777216.0f));     /* a tie, to even (down) */
    assert_true(same(f2l_from_u64(16777219u), 16777220.0f));     /* a tie, to even (up) */
    assert_true(same(f2l_from_u64(UINT64_C(0x100000100000001)), 72057602627862528.0f)); /* above the tie */
    print_message("%u conversions back to float checked against the compiler's\n", checked);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matches_c_conversion_wherever_c_defines_it),
        cmocka_unit_test(test_truncates_toward_zero),
        cmocka_unit_test(test_saturates_where_c_is_undefined),
        cmocka_unit_test(test_to_float_matches_c_conversion),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
