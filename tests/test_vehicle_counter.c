/* test_vehicle_counter.c - a car message's rolling counter (firmware/vehicle/vehicle_counter.c):
 * the step modulo the car's modulus, a repeat, a value the sender never counts through, and
 * one state per message kind. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "vehicle_counter.h"

static vehicle_counters_t fresh(void)
{
    vehicle_counters_t c;
    memset(&c, 0, sizeof c);
    return c;
}

/* Honda's 2-bit COUNTER, modulo 4: the first value taken (step 1), then +1 steps through
 * the wrap, a repeat refused without moving the state, lost frames taken with their step */
static void test_two_bits_modulo_four(void **state)
{
    (void)state;
    vehicle_counters_t c = fresh();
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_GEAR, 2u, 4u), 1); /* any first */
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_GEAR, 3u, 4u), 1);
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_GEAR, 0u, 4u), 1); /* 3 -> 0 */
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_GEAR, 0u, 4u), 0); /* repeat */
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_GEAR, 0u, 4u), 0); /* and again */
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_GEAR, 1u, 4u), 1); /* not moved */
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_GEAR, 0u, 4u), 3); /* 2 lost */
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_GEAR, 4u, 4u), -1); /* not 2 bits */
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_GEAR, 1u, 4u), 1); /* not moved */
}

/* Subaru's 4-bit COUNTER, modulo 16: 15 -> 0 is the next frame; with a modulus of 15 (a
 * counter that never sends 15, as navecu's own E2E counters), 15 is refused and 14 -> 0 is
 * the next frame */
static void test_four_bits_and_a_modulus_below_the_bits(void **state)
{
    (void)state;
    vehicle_counters_t c = fresh();
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_WHEELS, 15u, 16u), 1);
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_WHEELS, 0u, 16u), 1);
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_WHEELS, 15u, 16u), 15); /* 14 lost */
    vehicle_counters_t d = fresh();
    assert_int_equal(vehicle_counter_step(&d, VEHICLE_MSG_WHEELS, 15u, 15u), -1);
    assert_int_equal(vehicle_counter_step(&d, VEHICLE_MSG_WHEELS, 14u, 15u), 1); /* still first */
    assert_int_equal(vehicle_counter_step(&d, VEHICLE_MSG_WHEELS, 0u, 15u), 1);
    assert_int_equal(vehicle_counter_step(&d, VEHICLE_MSG_WHEELS, 14u, 15u), 14);
}

/* every (last, counter) pair of an 8-bit counter, modulo 256: step = (counter - last) mod 256 */
static void test_eight_bits_every_pair(void **state)
{
    (void)state;
    for (unsigned last = 0u; last < 256u; last++) {
        for (unsigned next = 0u; next < 256u; next++) {
            vehicle_counters_t c = fresh();
            assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_YAW_RATE, (uint8_t)last, 256u), 1);
            assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_YAW_RATE, (uint8_t)next, 256u),
                             (int)((next + 256u - last) % 256u));
        }
    }
}

/* each message kind has its own sequence: a gear frame's counter is no repeat of the wheel
 * speeds' */
static void test_one_sequence_per_kind(void **state)
{
    (void)state;
    vehicle_counters_t c = fresh();
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_WHEELS, 5u, 16u), 1);
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_GEAR, 5u, 16u), 1);
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_YAW_RATE, 5u, 16u), 1);
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_WHEELS, 5u, 16u), 0);
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_GEAR, 6u, 16u), 1);
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_WHEELS, 6u, 16u), 1);
}

/* what no generated call passes: kind NONE (or beyond), a modulus below 2 or above 256 */
static void test_bad_arguments(void **state)
{
    (void)state;
    vehicle_counters_t c = fresh();
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_NONE, 0u, 4u), -1);
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_N, 0u, 4u), -1);
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_WHEELS, 0u, 1u), -1);
    assert_int_equal(vehicle_counter_step(&c, VEHICLE_MSG_WHEELS, 0u, 257u), -1);
    for (unsigned k = 0u; k < (unsigned)VEHICLE_MSG_N - 1u; k++) {
        assert_int_equal(c.last[k], 0); /* nothing accepted */
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_two_bits_modulo_four),
        cmocka_unit_test(test_four_bits_and_a_modulus_below_the_bits),
        cmocka_unit_test(test_eight_bits_every_pair),
        cmocka_unit_test(test_one_sequence_per_kind),
        cmocka_unit_test(test_bad_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
