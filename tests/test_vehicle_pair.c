/* test_vehicle_pair.c - the four wheel speeds of a car that sends them in two messages, one
 * per axle (firmware/vehicle/vehicle_pair.c): one sample per pair, on the second half to
 * arrive, in FL, FR, RL, RR order whichever axle comes first; a repeated half replaces the
 * held one; no sample while one axle's message is missing. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "vehicle_pair.h"

static vehicle_pair_t fresh(void)
{
    vehicle_pair_t p;
    memset(&p, 0, sizeof p);
    return p;
}

static void assert_wheels(const nav_real_t w[4], nav_real_t fl, nav_real_t fr, nav_real_t rl,
                          nav_real_t rr)
{
    /* copies of the halves' values, not computed: the same bits */
    const nav_real_t expect[4] = {fl, fr, rl, rr};
    assert_memory_equal(w, expect, sizeof expect);
}

/* front then rear, rear then front: one sample on the second, the wheels in their places */
static void test_one_sample_per_pair_in_wheel_order(void **state)
{
    (void)state;
    vehicle_pair_t p = fresh();
    nav_real_t w[4] = {NAV_C(-9.0), NAV_C(-9.0), NAV_C(-9.0), NAV_C(-9.0)};
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_FRONT, NAV_C(1.0), NAV_C(2.0), w), 0);
    assert_wheels(w, NAV_C(-9.0), NAV_C(-9.0), NAV_C(-9.0), NAV_C(-9.0)); /* untouched */
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_REAR, NAV_C(3.0), NAV_C(4.0), w), 1);
    assert_wheels(w, NAV_C(1.0), NAV_C(2.0), NAV_C(3.0), NAV_C(4.0));
    /* nothing held after a sample: the rear first this time */
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_REAR, NAV_C(7.0), NAV_C(8.0), w), 0);
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_FRONT, NAV_C(5.0), NAV_C(6.0), w), 1);
    assert_wheels(w, NAV_C(5.0), NAV_C(6.0), NAV_C(7.0), NAV_C(8.0));
}

/* a half that comes again before the other axle's replaces the held one: the sample has the
 * newest of each axle, and there is one sample, not two */
static void test_a_repeated_half_replaces_the_held_one(void **state)
{
    (void)state;
    vehicle_pair_t p = fresh();
    nav_real_t w[4] = {NAV_C(0.0)};
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_FRONT, NAV_C(1.0), NAV_C(2.0), w), 0);
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_FRONT, NAV_C(1.5), NAV_C(2.5), w), 0);
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_FRONT, NAV_C(1.7), NAV_C(2.7), w), 0);
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_REAR, NAV_C(3.0), NAV_C(4.0), w), 1);
    assert_wheels(w, NAV_C(1.7), NAV_C(2.7), NAV_C(3.0), NAV_C(4.0));
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_REAR, NAV_C(3.1), NAV_C(4.1), w), 0);
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_REAR, NAV_C(3.2), NAV_C(4.2), w), 0);
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_FRONT, NAV_C(1.8), NAV_C(2.8), w), 1);
    assert_wheels(w, NAV_C(1.8), NAV_C(2.8), NAV_C(3.2), NAV_C(4.2));
}

/* one axle's message stopped: however many of the other's come, no sample (the odometer's
 * timeout then says the wheels are missing); the first of the stopped axle's again makes
 * one with the latest of the other */
static void test_a_stopped_axle_gives_no_sample(void **state)
{
    (void)state;
    vehicle_pair_t p = fresh();
    nav_real_t w[4] = {NAV_C(0.0)};
    for (int i = 0; i < 1000; i++) {
        const nav_real_t v = (nav_real_t)i;
        assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_REAR, v, v + NAV_C(0.5), w), 0);
    }
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_FRONT, NAV_C(1.0), NAV_C(2.0), w), 1);
    assert_wheels(w, NAV_C(1.0), NAV_C(2.0), NAV_C(999.0), NAV_C(999.5));
}

/* a cleared state (vehicle_reset: held = 0) holds nothing: the next half is held, whichever
 * axle was held before */
static void test_cleared_holds_nothing(void **state)
{
    (void)state;
    vehicle_pair_t p = fresh();
    nav_real_t w[4] = {NAV_C(0.0)};
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_FRONT, NAV_C(1.0), NAV_C(2.0), w), 0);
    p.held = 0u;
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_REAR, NAV_C(3.0), NAV_C(4.0), w), 0);
    assert_int_equal(vehicle_pair_half(&p, VEHICLE_AXLE_FRONT, NAV_C(5.0), NAV_C(6.0), w), 1);
    assert_wheels(w, NAV_C(5.0), NAV_C(6.0), NAV_C(3.0), NAV_C(4.0));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_one_sample_per_pair_in_wheel_order),
        cmocka_unit_test(test_a_repeated_half_replaces_the_held_one),
        cmocka_unit_test(test_a_stopped_axle_gives_no_sample),
        cmocka_unit_test(test_cleared_holds_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
