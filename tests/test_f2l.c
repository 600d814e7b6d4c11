/*
 * test_f2l.c - the double-free float to 64-bit integer conversions of the Cortex-M4F
 * images (hal/cortex_m4f/f2l.c) against the host compiler's own conversions (x86-64
 * cvttss2si, exact by IEEE 754) wherever C defines the result, and their saturation
 * where it does not.
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matches_c_conversion_wherever_c_defines_it),
        cmocka_unit_test(test_truncates_toward_zero),
        cmocka_unit_test(test_saturates_where_c_is_undefined),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
