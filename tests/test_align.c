/*
 * test_align.c - align.h: the initial state, levelling with parabolic weights, the start
 * of navigation, GNSS-only initialisation and re-acquisition.
 *
 * Levelling (align.h): the specific force of a vehicle at rest in body axes is
 * g (-cos(p) sin(r), sin(p), cos(p) cos(r)), so roll = atan2(-f_x, f_z) and
 * pitch = atan2(f_y, sqrt(f_x^2 + f_z^2)) whatever g and the scale.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "align.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

/* the identity mounting: the IMU square in the vehicle */
static const mounting_t no_mount;

static align_t al;
static sins_t nav;
static dr_t dr;
static calib_t cal;

static int setup(void **state)
{
    (void)state;
    memset(&al, 0, sizeof al);
    memset(&nav, 0, sizeof nav);
    memset(&dr, 0, sizeof dr);
    calib_init(&cal);
    return 0;
}

static double lat_deg_of(const geo_pos_t *p)
{
    return (double)p->lat / 16777216.0 * 1e-7;
}

/* ---- levelling ---- */

/* GIVEN a constant specific force (-300, 500, 400) LSB per sample over a window THEN roll
 * = atan2(300, 400) = atan(3/4) and pitch = atan2(500, 500) = 45 deg, within float
 * rounding (the weights, however large, cancel in the ratios). */
static void test_level_exact_attitude(void **state)
{
    (void)state;
    const int32_t v[3] = {-300, 500, 400};
    const uint32_t n = 3000u; /* 30 s at 100 Hz */
    align_level_restart(&al);
    for (uint32_t k = 1u; k < n; k++) {
        assert_int_equal(align_level_sample(&al, v, n), 0);
    }
    assert_int_equal(align_level_sample(&al, v, n), 1); /* the window is complete */
    nav_real_t roll, pitch;
    align_level_attitude(&al, &no_mount, &roll, &pitch);
    assert_near(roll, 0.6435011087932844, 1e-6);
    assert_near(pitch, PI / 4.0, 1e-6);
}

/* GIVEN a car at roll 10 deg, pitch -5 deg, its specific force g dt = 0.0980665 m/s per
 * 10 ms sample quantised to the 2^-12 m/s LSB THEN levelling finds the tilt within the
 * quantisation (0.5 LSB of 402: 0.07 deg), and the exact attitude of the rounded vector
 * within float rounding. */
static void test_level_tilted_vehicle(void **state)
{
    (void)state;
    const double r = 10.0 * DEG, p = -5.0 * DEG, gdt = 9.80665 * 0.01 * 4096.0;
    const int32_t v[3] = {(int32_t)lround(-gdt * cos(p) * sin(r)), (int32_t)lround(gdt * sin(p)),
                          (int32_t)lround(gdt * cos(p) * cos(r))};
    align_level_restart(&al);
    for (uint32_t k = 0u; k < 3000u; k++) {
        (void)align_level_sample(&al, v, 3000u);
    }
    nav_real_t roll, pitch;
    align_level_attitude(&al, &no_mount, &roll, &pitch);
    assert_near(roll, atan2(-(double)v[0], (double)v[2]), 1e-6);
    assert_near(pitch, atan2((double)v[1], hypot((double)v[0], (double)v[2])), 1e-6);
    assert_near(roll, r, 0.07 * DEG);
    assert_near(pitch, p, 0.07 * DEG);
}

/* The weights are k (N - k): over N = 4 samples 3, 4, 3, 0. GIVEN x = 1, 2, 3, 4 and z = 100
 * THEN the weighted x is 3 + 8 + 9 + 0 = 20 against z 1000: roll = atan2(-20, 1000) (a
 * plain mean would give atan2(-2.5, 100)); the last sample has no weight at all. */
static void test_level_parabolic_weights(void **state)
{
    (void)state;
    align_level_restart(&al);
    for (int32_t k = 1; k <= 4; k++) {
        const int32_t v[3] = {k, 0, 100};
        (void)align_level_sample(&al, v, 4u);
    }
    nav_real_t roll, pitch;
    align_level_attitude(&al, &no_mount, &roll, &pitch);
    assert_near(roll, atan2(-20.0, 1000.0), 1e-7);
    assert_near(pitch, 0.0, 0.0);
    /* a restart forgets everything: the same window without the x ramp is level */
    align_level_restart(&al);
    assert_int_equal(al.level_n, 0u);
    for (int32_t k = 1; k <= 4; k++) {
        const int32_t v[3] = {k == 4 ? 100000 : 0, 0, 100};
        (void)align_level_sample(&al, v, 4u);
    }
    align_level_attitude(&al, &no_mount, &roll, &pitch);
    assert_near(roll, 0.0, 0.0);
}

/* ---- initial state and start ---- */

static void test_initial_state(void **state)
{
    (void)state;
    assert_int_equal(align_ready(&al), 0);
    const geo_pos_t p = align_pos_of(451234567, -98765432, 999);
    assert_true(p.lat == 451234567LL * 16777216LL);
    assert_true(p.lon == -98765432LL * 16777216LL);
    assert_true(p.h == 9990LL * 16777216LL); /* 9.99 m */
    align_set_initial(&al, &p, 12345, 0, 1.0f);
    assert_int_equal(al.pos_valid, 1);
    assert_true(al.pos.h == 123450LL * 16777216LL); /* the height is h_cm's */
    assert_int_equal(al.h_cm, 12345);
    assert_int_equal(align_ready(&al), 0); /* no heading yet */
    align_set_initial(&al, &p, 12345, 1, 1.0f);
    assert_int_equal(align_ready(&al), 1);
    assert_near(al.heading_rad, 1.0, 0.0);
}

/* GIVEN the initial state (45 N, 10 E, 100 m, heading 30 deg) and a calibration in use
 * WHEN navigation starts at roll 2 deg, pitch -1 deg THEN the navigator is at rest at
 * that position and attitude, its height held at 100 m, the dead reckoning starts there
 * with the calibration's dH and mu. */
static void test_start(void **state)
{
    (void)state;
    const geo_pos_t p = align_pos_of(450000000, 100000000, 0);
    align_set_initial(&al, &p, 10000, 1, (nav_real_t)(30.0 * DEG));
    cal.dh_rad = 0.01f;
    cal.mu = 0.02f;
    assert_int_equal(align_start(&al, (nav_real_t)(2.0 * DEG), (nav_real_t)(-1.0 * DEG), &nav,
                                 &dr, &cal),
                     NAV_OK);
    nav_real_t roll, pitch, heading;
    sins_euler(&nav, &roll, &pitch, &heading);
    assert_near(roll, 2.0 * DEG, 1e-6);
    assert_near(pitch, -1.0 * DEG, 1e-6);
    assert_near(heading, 30.0 * DEG, 1e-6);
    for (int i = 0; i < 3; i++) {
        assert_near(nav.v_n_mps[i], 0.0, 0.0);
    }
    assert_true(nav.pos.lat == al.pos.lat && nav.pos.lon == al.pos.lon && nav.pos.h == al.pos.h);
    assert_int_equal(nav.h_ref_valid, 1);
    assert_near(nav.h_ref_m, 100.0, 1e-5);
    assert_true(dr.pos.lat == al.pos.lat && dr.pos.lon == al.pos.lon);
    assert_near(dr.dh_rad, 0.01f, 0.0);
    assert_near(dr.mu, 0.02f, 0.0);
    /* a calibration beyond what the dead reckoning takes (|mu| > 0.2) is refused */
    cal.mu = 0.3f;
    assert_int_not_equal(align_start(&al, 0.0f, 0.0f, &nav, &dr, &cal), NAV_OK);
}

/* ---- GNSS-only initialisation ---- */

static gnss_fix_t fix_at(float speed, float course, int has_h)
{
    gnss_fix_t f;
    memset(&f, 0, sizeof f);
    f.pos = align_pos_of(450000000, 100000000, 0);
    f.h_cm = 25000;
    f.has_h = has_h ? 1u : 0u;
    f.has_vel = speed >= 0.0f ? 1u : 0u;
    f.speed_mps = speed;
    f.course_rad = course;
    f.v_enu_mps[0] = speed >= 0.0f ? speed * sinf(course) : 0.0f;
    f.v_enu_mps[1] = speed >= 0.0f ? speed * cosf(course) : 0.0f;
    return f;
}

/* GIVEN driving at 6 m/s on course 1.0 rad THEN the course is kept but nothing starts;
 * WHEN the gyro turns 1.7 deg and the receiver says stopped (0.2 m/s) while the wheels
 * still turn THEN nothing yet; WHEN the wheels stand too THEN the initial state is the
 * fix's position and height with the course as heading; WHEN instead the gyro turned
 * 2.9 deg THEN the course is no heading and nothing starts. */
static void test_gnss_init_course_then_stop(void **state)
{
    (void)state;
    gnss_fix_t f = fix_at(6.0f, 1.0f, 1);
    assert_int_equal(align_gnss(&al, &f, 0), 0);
    assert_int_equal(al.course_valid, 1);
    imu_inc_t inc;
    memset(&inc, 0, sizeof inc);
    inc.dt_s = 0.01f;
    inc.dtheta_b_rad[2] = 0.0003f; /* the gyro: 0.03 rad (1.7 deg) over 100 samples */
    for (int k = 0; k < 100; k++) {
        align_motion_sample(&al, &inc);
    }
    f = fix_at(0.2f, 3.0f, 1); /* a standing car's course is noise: not taken */
    assert_int_equal(align_gnss(&al, &f, 1), 0); /* the wheels still turn: not yet */
    assert_int_equal(al.pos_valid, 0);
    assert_int_equal(align_gnss(&al, &f, 0), 1);
    assert_int_equal(align_ready(&al), 1);
    assert_near(al.heading_rad, 1.0, 0.0);
    assert_int_equal(al.h_cm, 25000);
    assert_true(al.pos.lat == f.pos.lat && al.pos.lon == f.pos.lon);
    assert_near(lat_deg_of(&al.pos), 45.0, 1e-9);

    /* a course, then a turn of 0.05 rad (2.9 deg) below 5 m/s before the stop: the course
     * is no longer the heading (a review found a start 90 deg off after a slow corner) */
    memset(&al, 0, sizeof al);
    f = fix_at(6.0f, 1.0f, 1);
    assert_int_equal(align_gnss(&al, &f, 0), 0);
    inc.dtheta_b_rad[2] = 0.0005f;
    for (int k = 0; k < 100; k++) {
        align_motion_sample(&al, &inc);
    }
    f = fix_at(0.2f, 3.0f, 1);
    assert_int_equal(align_gnss(&al, &f, 0), 0);
    assert_int_equal(al.pos_valid, 0);
}

/* Below 5 m/s the course is no heading; a stop without a course, without a height or
 * without a velocity starts nothing; between 0.3 and 5 m/s the car is not standing. */
static void test_gnss_init_needs_course_and_stop(void **state)
{
    (void)state;
    gnss_fix_t f = fix_at(4.9f, 1.0f, 1);
    assert_int_equal(align_gnss(&al, &f, 0), 0);
    assert_int_equal(al.course_valid, 0);
    f = fix_at(0.0f, 0.0f, 1);
    assert_int_equal(align_gnss(&al, &f, 0), 0);
    f = fix_at(5.0f, 2.0f, 1);
    assert_int_equal(align_gnss(&al, &f, 0), 0);
    assert_int_equal(al.course_valid, 1);
    f = fix_at(1.0f, 2.0f, 1);
    assert_int_equal(align_gnss(&al, &f, 0), 0);
    f = fix_at(0.1f, 2.0f, 0);
    assert_int_equal(align_gnss(&al, &f, 0), 0);
    f = fix_at(-1.0f, 0.0f, 1); /* no velocity: speed -1 */
    assert_int_equal(align_gnss(&al, &f, 0), 0);
    assert_int_equal(al.pos_valid, 0);
}

/* ---- re-acquisition ---- */

/* driving (the course a heading) or standing, with velocity and height; standing only
 * when the car has not moved since the re-acquisition began (a review: a car that braked
 * and turned 90 deg in a gap re-acquired at its stop with the heading before, 90 deg off,
 * claiming 5 deg) */
static void test_reacquire_ready(void **state)
{
    (void)state;
    align_reacquire_begin(&al, &nav, 0.0f, 0);
    gnss_fix_t f = fix_at(10.0f, 0.0f, 1);
    assert_int_equal(align_reacquire_ready(&al, &f), 1);
    f = fix_at(0.3f, 0.0f, 1);
    assert_int_equal(align_reacquire_ready(&al, &f), 1);
    f = fix_at(2.0f, 0.0f, 1);
    assert_int_equal(align_reacquire_ready(&al, &f), 0); /* a course that is not a heading */
    f = fix_at(10.0f, 0.0f, 0);
    assert_int_equal(align_reacquire_ready(&al, &f), 0); /* no height */
    f = fix_at(10.0f, 0.0f, 1);
    f.has_vel = 0u;
    assert_int_equal(align_reacquire_ready(&al, &f), 0);
    align_reacquire_begin(&al, &nav, 0.0f, 1); /* moving when the gap came */
    f = fix_at(0.3f, 0.0f, 1);
    assert_int_equal(align_reacquire_ready(&al, &f), 0);
    f = fix_at(10.0f, 0.0f, 1);
    assert_int_equal(align_reacquire_ready(&al, &f), 1);
}

/* GIVEN a navigator at roll 2, pitch -1, heading 60 deg and a mounting yaw of 0.05 rad
 * WHEN re-acquiring from a fix driving at 10 m/s on course 2.0 rad THEN roll and pitch are
 * kept, the heading is the course plus the mounting (2.05 rad), position, velocity and
 * height reference are the fix's; WHEN instead standing THEN the heading before is kept;
 * WHEN reversing THEN the heading is the course's opposite. */
static void test_reacquire(void **state)
{
    (void)state;
    const geo_pos_t p = align_pos_of(440000000, 90000000, 0);
    align_set_initial(&al, &p, 0, 1, (nav_real_t)(60.0 * DEG));
    assert_int_equal(align_start(&al, (nav_real_t)(2.0 * DEG), (nav_real_t)(-1.0 * DEG), &nav,
                                 &dr, &cal),
                     NAV_OK);
    align_reacquire_begin(&al, &nav, 0.05f, 1);
    assert_int_equal(al.reacquire, 1);
    gnss_fix_t f = fix_at(10.0f, 2.0f, 1);
    assert_int_equal(align_reacquire(&al, &f, &nav, &dr, &cal, 0), NAV_OK);
    assert_int_equal(al.reacquire, 0);
    nav_real_t roll, pitch, heading;
    sins_euler(&nav, &roll, &pitch, &heading);
    assert_near(roll, 2.0 * DEG, 1e-6);
    assert_near(pitch, -1.0 * DEG, 1e-6);
    assert_near(heading, 2.05, 1e-6);
    assert_near(nav.v_n_mps[0], 10.0 * sin(2.0), 1e-5);
    assert_near(nav.v_n_mps[1], 10.0 * cos(2.0), 1e-5);
    assert_true(nav.pos.lat == f.pos.lat && nav.pos.lon == f.pos.lon);
    assert_true(dr.pos.lat == f.pos.lat && dr.pos.lon == f.pos.lon);
    assert_near(nav.h_ref_m, 250.0, 1e-4);

    align_reacquire_begin(&al, &nav, 0.05f, 0);
    f = fix_at(0.1f, 5.0f, 1);
    assert_int_equal(align_reacquire(&al, &f, &nav, &dr, &cal, 0), NAV_OK);
    sins_euler(&nav, &roll, &pitch, &heading);
    assert_near(heading, 2.05, 1e-6); /* the heading before, not the standing course */

    /* reversing (the wheels say so) at 6 m/s on course 2.0 rad: the car points the other
     * way, 2.0 + pi + 0.05 (a review: it took the course, 180 deg off, claiming 2-3 deg) */
    align_reacquire_begin(&al, &nav, 0.05f, 1);
    f = fix_at(6.0f, 2.0f, 1);
    assert_int_equal(align_reacquire(&al, &f, &nav, &dr, &cal, 1), NAV_OK);
    sins_euler(&nav, &roll, &pitch, &heading);
    assert_near(remainder((double)heading - (2.05 + M_PI), 2.0 * M_PI), 0.0, 1e-5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_level_exact_attitude, setup),
        cmocka_unit_test_setup(test_level_tilted_vehicle, setup),
        cmocka_unit_test_setup(test_level_parabolic_weights, setup),
        cmocka_unit_test_setup(test_initial_state, setup),
        cmocka_unit_test_setup(test_start, setup),
        cmocka_unit_test_setup(test_gnss_init_course_then_stop, setup),
        cmocka_unit_test_setup(test_gnss_init_needs_course_and_stop, setup),
        cmocka_unit_test_setup(test_reacquire_ready, setup),
        cmocka_unit_test_setup(test_reacquire, setup),
    };
    return cmocka_run_group_tests_name("align", tests, NULL, NULL);
}
