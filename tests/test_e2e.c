/* test_e2e.c - the E2E CRC and alive counter (firmware/can/e2e.c). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "e2e.h"

/* CRC-8/SAE-J1850 catalogue check value: the CRC of "123456789" is 0x4B. */
static void test_crc_check_value(void **state)
{
    (void)state;
    const uint8_t s[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    assert_int_equal(e2e_crc8_update(0xFFu, s, 9u) ^ 0xFFu, 0x4Bu);
}

static void test_protect_and_check(void **state)
{
    (void)state;
    uint8_t d[8] = {0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0x05, 0x00};
    e2e_protect(0x100u, d);
    assert_true(e2e_crc_ok(0x100u, d));
    /* the identifier is part of the CRC: the same payload under another ID fails */
    assert_false(e2e_crc_ok(0x101u, d));
    /* every single-bit error in bytes 0..7 is detected */
    for (int byte = 0; byte < 8; byte++) {
        for (int bit = 0; bit < 8; bit++) {
            d[byte] ^= (uint8_t)(1u << bit);
            assert_false(e2e_crc_ok(0x100u, d));
            d[byte] ^= (uint8_t)(1u << bit);
        }
    }
}

/* the IMU pair: one CRC over both frames; a bit flipped in either is caught */
static void test_pair_crc(void **state)
{
    (void)state;
    uint8_t first[8] = {1, 2, 3, 4, 5, 6, 7, 0x98};
    uint8_t second[8] = {9, 10, 11, 12, 13, 14, 0x05, 0};
    second[7] = e2e_pair_crc(0x101u, first, second);
    for (int byte = 0; byte < 15; byte++) {
        uint8_t *p = byte < 8 ? &first[byte] : &second[byte - 8];
        for (int bit = 0; bit < 8; bit++) {
            *p ^= (uint8_t)(1u << bit);
            assert_int_not_equal(second[7], e2e_pair_crc(0x101u, first, second));
            *p ^= (uint8_t)(1u << bit);
        }
    }
    assert_int_equal(second[7], e2e_pair_crc(0x101u, first, second));
}

static void test_counter_steps(void **state)
{
    (void)state;
    e2e_counter_t c = {0, 0};
    assert_int_equal(e2e_counter_step(&c, 7u), 1);  /* first: accepted */
    assert_int_equal(e2e_counter_step(&c, 8u), 1);
    assert_int_equal(e2e_counter_step(&c, 8u), 0);  /* repeated */
    assert_int_equal(e2e_counter_step(&c, 11u), 3); /* two lost */
    assert_int_equal(e2e_counter_step(&c, 14u), 3);
    assert_int_equal(e2e_counter_step(&c, 0u), 1);  /* wraps 14 -> 0 */
    assert_int_equal(e2e_counter_step(&c, 15u), -1); /* invalid, state kept */
    assert_int_equal(e2e_counter_step(&c, 1u), 1);
    assert_int_equal(e2e_counter_next(14u), 0);
    assert_int_equal(e2e_counter_next(3u), 4);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc_check_value),
        cmocka_unit_test(test_protect_and_check),
        cmocka_unit_test(test_pair_crc),
        cmocka_unit_test(test_counter_steps),
    };
    return cmocka_run_group_tests_name("e2e", tests, NULL, NULL);
}
