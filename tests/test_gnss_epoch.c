/*
 * test_gnss_epoch.c - gnss_epoch.h: GNSS_Position, _Velocity and _Height collected until
 * the GNSS_Status that closes the epoch; matching and mismatching epoch numbers, a fix
 * without its position, no fix, too few satellites, speed and course from the ENU
 * velocity, the position in the core's fixed point (2^24 LSB per 1e-7 deg and per mm).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "gnss_epoch.h"
#include "test_util.h"

#define PI 3.14159265358979323846

static gnss_asm_t g;
static gnss_fix_t fix;

static int setup(void **state)
{
    (void)state;
    memset(&g, 0, sizeof g);
    memset(&fix, 0, sizeof fix);
    return 0;
}

/* a GNSS_Status as app_rx decodes it: 3D fix with 9 satellites unless told otherwise */
static rx_input_t status(uint8_t epoch, uint8_t fix_3d, uint8_t n_sats)
{
    rx_input_t in;
    memset(&in, 0, sizeof in);
    in.kind = RX_GNSS_STATUS;
    in.u.status.epoch = epoch;
    in.u.status.defined = 1u;
    in.u.status.fix_3d = fix_3d;
    in.u.status.n_sats = n_sats;
    in.u.status.hacc_m = 2.5f;
    in.u.status.vacc_m = 3.5f;
    in.u.status.tow_ms = 345600123u;
    return in;
}

static void velocity(uint8_t epoch, float east, float north, float up)
{
    const nav_real_t v[3] = {east, north, up};
    (void)gnss_epoch_velocity(&g, epoch, v, 0.3f);
}

/* GIVEN position, velocity and height of epoch 3 and the status of epoch 3 THEN one usable
 * fix: the position exact in fixed point, the height of the epoch, the velocity, the
 * receiver's accuracies and TimeOfWeek. */
static void test_matching_epoch(void **state)
{
    (void)state;
    gnss_epoch_position(&g, 451234567, -1234567);
    velocity(3u, 1.0f, 2.0f, -0.5f);
    gnss_epoch_height(&g, 3u, 12345);
    const rx_input_t st = status(3u, 1u, 9u);
    const gnss_close_t r = gnss_epoch_close(&g, &st, &fix);
    assert_int_equal(r.usable, 1);
    assert_int_equal(r.has_course, 1);
    assert_int_equal(r.mismatch, 0);
    assert_int_equal(r.no_fix, 0);
    assert_int_equal(r.no_position, 0);
    assert_int_equal(r.undefined, 0);
    assert_true(fix.pos.lat == 451234567LL * 16777216LL);
    assert_true(fix.pos.lon == -1234567LL * 16777216LL);
    assert_true(fix.pos.h == 123450LL * 16777216LL); /* 123.45 m = 123450 mm */
    assert_int_equal(fix.h_cm, 12345);
    assert_int_equal(fix.has_vel, 1);
    assert_int_equal(fix.has_h, 1);
    assert_near(fix.v_enu_mps[0], 1.0, 0.0);
    assert_near(fix.v_enu_mps[1], 2.0, 0.0);
    assert_near(fix.v_enu_mps[2], -0.5, 0.0);
    assert_near(fix.sacc_mps, 0.3f, 0.0);
    assert_near(fix.hacc_m, 2.5, 0.0);
    assert_near(fix.vacc_m, 3.5, 0.0);
    assert_int_equal(fix.tow_ms, 345600123u);
}

/* GIVEN the velocity of epoch 2 and the height of epoch 3, closed by epoch 3 THEN the
 * velocity of the other epoch is dropped (mismatch: counted), the rest is a usable fix
 * without velocity: speed -1, course 0. */
static void test_mismatching_epoch(void **state)
{
    (void)state;
    gnss_epoch_position(&g, 450000000, 100000000);
    velocity(2u, 10.0f, 0.0f, 0.0f);
    gnss_epoch_height(&g, 3u, 10000);
    const rx_input_t st = status(3u, 1u, 9u);
    const gnss_close_t r = gnss_epoch_close(&g, &st, &fix);
    assert_int_equal(r.mismatch, 1);
    assert_int_equal(r.usable, 1);
    assert_int_equal(r.has_course, 0);
    assert_int_equal(fix.has_vel, 0);
    assert_int_equal(fix.has_h, 1);
    assert_near(fix.speed_mps, -1.0, 0.0);
    assert_near(fix.course_rad, 0.0, 0.0);
    /* a height of another epoch likewise */
    gnss_epoch_position(&g, 450000000, 100000000);
    velocity(4u, 10.0f, 0.0f, 0.0f);
    gnss_epoch_height(&g, 5u, 10000);
    const rx_input_t st4 = status(4u, 1u, 9u);
    const gnss_close_t r4 = gnss_epoch_close(&g, &st4, &fix);
    assert_int_equal(r4.mismatch, 1);
    assert_int_equal(fix.has_vel, 1);
    assert_int_equal(fix.has_h, 0);
    assert_int_equal(r4.usable, 1);
    /* a GNSS_Time of another epoch likewise: dropped and counted (it was dropped alone) */
    gnss_epoch_position(&g, 450000000, 100000000);
    gnss_epoch_week(&g, 5u, 2012u);
    const rx_input_t st6 = status(6u, 1u, 9u);
    const gnss_close_t r6 = gnss_epoch_close(&g, &st6, &fix);
    assert_int_equal(r6.mismatch, 1);
    assert_int_equal(fix.has_week, 0);
    assert_int_equal(r6.usable, 1);
}

/* GIVEN velocity and height but no GNSS_Position, with a 3D fix THEN no_position (a
 * receiver fault, counted); with the position refused by app_rx it was counted already. */
static void test_fix_without_position(void **state)
{
    (void)state;
    velocity(1u, 0.0f, 0.0f, 0.0f);
    gnss_epoch_height(&g, 1u, 0);
    const rx_input_t st = status(1u, 1u, 9u);
    gnss_close_t r = gnss_epoch_close(&g, &st, &fix);
    assert_int_equal(r.no_position, 1);
    assert_int_equal(r.usable, 0);
    assert_int_equal(r.has_course, 1); /* the velocity is still a course */
    gnss_epoch_position(&g, 450000000, 100000000);
    gnss_epoch_position_refused(&g);
    r = gnss_epoch_close(&g, &st, &fix);
    assert_int_equal(r.no_position, 0);
    assert_int_equal(r.usable, 0);
    /* the refusal was this epoch's: the next one without position is counted again */
    r = gnss_epoch_close(&g, &st, &fix);
    assert_int_equal(r.no_position, 1);
}

/* No 3D fix, or 3 satellites: no_fix (not an error), not usable; 4 satellites: usable. */
static void test_no_fix_and_too_few_satellites(void **state)
{
    (void)state;
    const rx_input_t no3d = status(1u, 0u, 9u);
    gnss_epoch_position(&g, 450000000, 100000000);
    gnss_close_t r = gnss_epoch_close(&g, &no3d, &fix);
    assert_int_equal(r.no_fix, 1);
    assert_int_equal(r.usable, 0);
    assert_int_equal(r.no_position, 0);
    const rx_input_t three = status(2u, 1u, 3u);
    gnss_epoch_position(&g, 450000000, 100000000);
    r = gnss_epoch_close(&g, &three, &fix);
    assert_int_equal(r.no_fix, 1);
    assert_int_equal(r.usable, 0);
    const rx_input_t four = status(3u, 1u, 4u);
    gnss_epoch_position(&g, 450000000, 100000000);
    r = gnss_epoch_close(&g, &four, &fix);
    assert_int_equal(r.no_fix, 0);
    assert_int_equal(r.usable, 1);
}

/* A status whose epoch or fix type the protocol does not define: undefined, and the frames
 * in assembly are consumed (the next status finds no position). */
static void test_undefined_status_consumes(void **state)
{
    (void)state;
    gnss_epoch_position(&g, 450000000, 100000000);
    velocity(1u, 3.0f, 4.0f, 0.0f);
    rx_input_t st = status(1u, 1u, 9u);
    st.u.status.defined = 0u;
    gnss_close_t r = gnss_epoch_close(&g, &st, &fix);
    assert_int_equal(r.undefined, 1);
    assert_int_equal(r.usable, 0);
    assert_int_equal(r.has_course, 0);
    st.u.status.defined = 1u;
    r = gnss_epoch_close(&g, &st, &fix);
    assert_int_equal(r.no_position, 1);
    assert_int_equal(r.has_course, 0);
}

/* Speed and course from ENU velocity: east 10 m/s -> 90 deg, 10 m/s; south -> 180 deg;
 * west -> 270 deg (course in [0, 2 pi)); east 3 north 4 -> 5 m/s at atan(3/4) = 36.87 deg;
 * the vertical velocity is not speed. */
static void test_course_and_speed(void **state)
{
    (void)state;
    const struct {
        float e, n, u;
        double speed, course_rad;
    } cases[] = {
        {10.0f, 0.0f, 0.0f, 10.0, PI / 2.0},
        {0.0f, -10.0f, 0.0f, 10.0, PI},
        {-10.0f, 0.0f, 5.0f, 10.0, 1.5 * PI},
        {3.0f, 4.0f, -2.0f, 5.0, 0.6435011087932844},
        {-1.0f, 1.0f, 0.0f, 1.4142135623730951, 1.75 * PI},
        {0.0f, 7.0f, 0.0f, 7.0, 0.0},
    };
    for (size_t i = 0u; i < sizeof cases / sizeof cases[0]; i++) {
        gnss_epoch_position(&g, 450000000, 100000000);
        velocity(5u, cases[i].e, cases[i].n, cases[i].u);
        const rx_input_t st = status(5u, 1u, 9u);
        const gnss_close_t r = gnss_epoch_close(&g, &st, &fix);
        assert_int_equal(r.has_course, 1);
        assert_near(fix.speed_mps, cases[i].speed, 2e-6);
        assert_near(fix.course_rad, cases[i].course_rad, 2e-6);
        assert_true(fix.course_rad >= 0.0f && fix.course_rad < 2.0f * (float)PI);
    }
}

/* The position's height is the latest GNSS_Height received, also in an epoch without one
 * (has_h says whether it is this epoch's). */
static void test_height_kept_across_epochs(void **state)
{
    (void)state;
    gnss_epoch_position(&g, 450000000, 100000000);
    gnss_epoch_height(&g, 1u, -5000);
    rx_input_t st = status(1u, 1u, 9u);
    (void)gnss_epoch_close(&g, &st, &fix);
    gnss_epoch_position(&g, 450000001, 100000000);
    st = status(2u, 1u, 9u);
    const gnss_close_t r = gnss_epoch_close(&g, &st, &fix);
    assert_int_equal(r.usable, 1);
    assert_int_equal(fix.has_h, 0);
    assert_int_equal(fix.h_cm, -5000);
    assert_true(fix.pos.h == -50000LL * 16777216LL);
}

/* A status app_rx marked a repeat (the previous fix's TimeOfWeek): nothing usable, no
 * course, and the frames in assembly are consumed. */
static void test_repeat_consumes(void **state)
{
    (void)state;
    gnss_epoch_position(&g, 451234567, -1234567);
    velocity(3u, 1.0f, 2.0f, -0.5f);
    rx_input_t st = status(3u, 1u, 9u);
    st.u.status.repeat = 1u;
    gnss_close_t r = gnss_epoch_close(&g, &st, &fix);
    assert_int_equal(r.repeat, 1);
    assert_int_equal(r.usable, 0);
    assert_int_equal(r.has_course, 0);
    st.u.status.repeat = 0u;
    r = gnss_epoch_close(&g, &st, &fix);
    assert_int_equal(r.no_position, 1);
    assert_int_equal(r.has_course, 0);
}

/* A second GNSS_Velocity of the same number within one epoch is a repeated frame: 1, and
 * the first one stays; after the status closes the epoch the same number is a new epoch's
 * (the counter comes round over an outage). */
static void test_velocity_repeat_within_epoch(void **state)
{
    (void)state;
    const nav_real_t v1[3] = {1.0f, 0.0f, 0.0f}, v2[3] = {5.0f, 0.0f, 0.0f};
    gnss_epoch_position(&g, 451234567, -1234567);
    assert_int_equal(gnss_epoch_velocity(&g, 3u, v1, 0.3f), 0);
    assert_int_equal(gnss_epoch_velocity(&g, 3u, v2, 0.3f), 1);
    const rx_input_t st = status(3u, 1u, 9u);
    gnss_close_t r = gnss_epoch_close(&g, &st, &fix);
    assert_int_equal(r.usable, 1);
    assert_near(fix.v_enu_mps[0], 1.0, 0.0);
    gnss_epoch_position(&g, 451234567, -1234567);
    assert_int_equal(gnss_epoch_velocity(&g, 3u, v2, 0.3f), 0);
    r = gnss_epoch_close(&g, &st, &fix);
    assert_near(fix.v_enu_mps[0], 5.0, 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_matching_epoch, setup),
        cmocka_unit_test_setup(test_mismatching_epoch, setup),
        cmocka_unit_test_setup(test_fix_without_position, setup),
        cmocka_unit_test_setup(test_no_fix_and_too_few_satellites, setup),
        cmocka_unit_test_setup(test_undefined_status_consumes, setup),
        cmocka_unit_test_setup(test_course_and_speed, setup),
        cmocka_unit_test_setup(test_height_kept_across_epochs, setup),
        cmocka_unit_test_setup(test_repeat_consumes, setup),
        cmocka_unit_test_setup(test_velocity_repeat_within_epoch, setup),
    };
    return cmocka_run_group_tests_name("gnss_epoch", tests, NULL, NULL);
}
