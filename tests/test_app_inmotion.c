/*
 * test_app_inmotion.c - the in-motion alignment in the application (issue #17;
 * firmware/app/align.h align_motion_*, app.c) against the in-memory HAL, through real
 * frames: IMU pairs (100 Hz, remainder carried), WheelSpeeds (50 Hz) and GNSS epochs
 * (10 Hz, sigma_v 0.2 m/s) of a level car on a straight at constant speed, course 30 deg:
 *  - power-on while driving at 15 m/s, no command: navigating within 2 s (the window
 *    is 1 s between two epochs), the heading within 0.5 deg of the course, roll and pitch
 *    within 0.2 deg of level, the position within 3 m, NAV_Position sent;
 *  - a Reset at 15 m/s: navigating again within 2 s, the same figures;
 *  - SetInitialPosition with HeadingValid 0 at rest: NO_HEADING, waiting; after drive-off
 *    it navigates from the GNSS course within 2 s of reaching 15 m/s, NO_HEADING cleared;
 *  - GNSS only, at rest: NO_HEADING set while the heading is unknown (docs/kalman.md);
 *  - reversing at 6 m/s (the wheels negative): the heading is the course + 180 deg.
 * Before the in-motion alignment each of these waited (WaitInit) for a stop.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app.h"
#include "can_frames.h"
#include "commands.h"
#include "e2e.h"
#include "fake_hal.h"
#include "navecu_can.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define RATE_HZ 100
#define R_EARTH_M 6378137.0

static hal_t hal;
static app_t app;
static double carry_v[3], speed, nose_rad, north_m, east_m;
static uint8_t imu_counter, wheel_counter, cmd_counter, gnss_epoch;
static uint32_t k_sample, n_position;
static uint32_t gnss_late_samples;
static int first_nav_time_known; /* -1: no NAV_Time yet; else whether the first was known */ /* the fixes' time of validity this many samples back */
static struct navecu_can_nav_status_t last_status; /* the last page 0 */
static uint32_t n_levelling_moving; /* NAV_Status page 0 saying Levelling while moving */
static int wheels_read_zero; /* the wheel-speed source lags: it still says 0 */
static uint32_t wheel_every; /* samples between WheelSpeeds frames (2: 50 Hz) */
static float gnss_hacc_m; /* the fixes' HorizAccuracy */
static int imu_drop; /* the IMU's frames are lost (a gap) */

static const double LAT0_DEG = 45.0, LON0_DEG = 10.0, H0_M = 100.0;

static void feed(const hal_can_frame_t *f)
{
    app_handle_frame(&app, &hal, f);
}

static void drain(void)
{
    for (uint32_t i = 0u; i < hal.tx_n; i++) {
        if (hal.tx[i].id == app.cfg.can_ids[NAVECU_MSG_NAV_POSITION]) {
            n_position++;
        } else if (hal.tx[i].id == app.cfg.can_ids[NAVECU_MSG_NAV_TIME] &&
                   first_nav_time_known < 0) {
            struct navecu_can_nav_time_t m;
            assert_int_equal(navecu_can_nav_time_unpack(&m, hal.tx[i].data, 8u), 0);
            first_nav_time_known = m.time_of_week != NAVECU_NAV_TIME_TIME_OF_WEEK_RAW_MAX;
        } else if (hal.tx[i].id == app.cfg.can_ids[NAVECU_MSG_NAV_STATUS]) {
            struct navecu_can_nav_status_t m;
            assert_int_equal(navecu_can_nav_status_unpack(&m, hal.tx[i].data, 8u), 0);
            if (m.status_page == 0u) {
                last_status = m;
                if (m.mode == NAVECU_CAN_NAV_STATUS_MODE_LEVELLING_CHOICE && fabs(speed) > 0.1) {
                    n_levelling_moving++;
                }
            }
        }
    }
    hal.tx_n = 0u;
}

static int setup(void **state)
{
    (void)state;
    fake_hal_reset(&hal);
    app_config_t cfg = app_default_config();
    cfg.level_s = 2u;
    cfg.gnss_latency_s = 0.0f; /* the fixes here are valid when they arrive (but one test) */
    gnss_late_samples = 0u;
    first_nav_time_known = -1;
    assert_int_equal(app_init(&app, &cfg), NAV_OK);
    memset(carry_v, 0, sizeof carry_v);
    speed = 0.0;
    nose_rad = 30.0 * DEG;
    north_m = east_m = 0.0;
    imu_counter = wheel_counter = cmd_counter = gnss_epoch = 0u;
    k_sample = n_position = n_levelling_moving = 0u;
    wheels_read_zero = 0;
    wheel_every = 2u;
    gnss_hacc_m = 1.0f;
    imu_drop = 0;
    memset(&last_status, 0, sizeof last_status);
    hal.t_us = 1000000u;
    return 0;
}

static double lat_deg(void)
{
    return LAT0_DEG + north_m / R_EARTH_M / DEG;
}

static double lon_deg(void)
{
    return LON0_DEG + east_m / (R_EARTH_M * cos(LAT0_DEG * DEG)) / DEG;
}

static void send_gnss(void)
{
    const double vn = speed * cos(nose_rad), ve = speed * sin(nose_rad);
    /* where the car was gnss_late_samples ago (at constant speed and heading) */
    const double back_m = speed * (double)gnss_late_samples / RATE_HZ;
    const double lat = lat_deg() - back_m * cos(nose_rad) / R_EARTH_M / DEG;
    const double lon = lon_deg() - back_m * sin(nose_rad) / (R_EARTH_M * cos(LAT0_DEG * DEG)) / DEG;
    hal_can_frame_t f = cf_gnss_position((int32_t)lround(lat * 1e7), (int32_t)lround(lon * 1e7),
                                         hal.t_us);
    feed(&f);
    struct navecu_can_gnss_velocity_t gv;
    memset(&gv, 0, sizeof gv);
    gv.vel_north = (int16_t)lround(vn * 100.0);
    gv.vel_east = (int16_t)lround(ve * 100.0);
    gv.gnss_epoch = gnss_epoch;
    gv.speed_accuracy = navecu_can_gnss_velocity_speed_accuracy_encode(0.2f);
    f = cf_gnss_velocity(&gv, hal.t_us);
    feed(&f);
    f = cf_gnss_height((int32_t)lround(H0_M * 100.0), gnss_epoch, hal.t_us);
    feed(&f);
    struct navecu_can_gnss_status_t gs;
    memset(&gs, 0, sizeof gs);
    gs.fix_type = 3u;
    gs.num_satellites = 9u;
    gs.horiz_accuracy = navecu_can_gnss_status_horiz_accuracy_encode(gnss_hacc_m);
    gs.vert_accuracy = navecu_can_gnss_status_vert_accuracy_encode(1.5f);
    gs.gnss_epoch = gnss_epoch;
    gs.time_of_week = 100000u + (k_sample - gnss_late_samples) * (1000u / RATE_HZ);
    f = cf_gnss_status(&gs, hal.t_us);
    feed(&f);
    gnss_epoch = (uint8_t)((gnss_epoch + 1u) % 15u);
}

/* one sample of the car accelerating at a (m/s^2) along its nose (speed signed:
 * negative reversing), level, no turn; wheels every 2nd sample, GNSS every 10th */
static void sample(double a, double v_max)
{
    const double v0 = speed;
    speed = v0 + a / RATE_HZ;
    if ((a > 0.0 && speed > v_max) || (a < 0.0 && speed < v_max)) {
        speed = v_max;
    }
    const double a_eff = (speed - v0) * RATE_HZ;
    const double ds = 0.5 * (v0 + speed) / RATE_HZ;
    north_m += ds * cos(nose_rad);
    east_m += ds * sin(nose_rad);
    const double fv[3] = {0.0, a_eff, 9.80665};
    int32_t w[3] = {0, 0, 0}, v[3];
    for (int i = 0; i < 3; i++) {
        const double lsb = fv[i] / RATE_HZ * 4096.0 + carry_v[i];
        v[i] = (int32_t)lround(lsb);
        carry_v[i] = lsb - v[i];
    }
    hal.t_us += 1000000u / RATE_HZ;
    k_sample++;
    hal_can_frame_t fr, fa;
    cf_imu_pair(w, v, imu_counter, 0u, hal.t_us, &fr, &fa);
    imu_counter = e2e_counter_next(imu_counter);
    if (!imu_drop) {
        feed(&fr);
        feed(&fa);
    }
    if (k_sample % wheel_every == 0u) {
        const int16_t raw = wheels_read_zero ? (int16_t)0 : (int16_t)lround(speed / 0.02);
        const int16_t four[4] = {raw, raw, raw, raw};
        const hal_can_frame_t fw = cf_wheels(four, wheel_counter, hal.t_us);
        wheel_counter = e2e_counter_next(wheel_counter);
        feed(&fw);
    }
    if (k_sample % 10u == 0u) {
        send_gnss();
    }
    app_poll(&app, &hal);
    drain();
}

static void drive(double seconds, double v)
{
    for (int k = 0; k < (int)(seconds * RATE_HZ); k++) {
        sample(0.0, v);
    }
}

/* the samples until navigating (at most max_s), or -1 */
static double drive_until_navigating(double max_s, double v)
{
    for (int k = 0; k < (int)(max_s * RATE_HZ); k++) {
        sample(0.0, v);
        if (app_mode(&app) == APP_MODE_NAVIGATING) {
            return (double)(k + 1) / RATE_HZ;
        }
    }
    return -1.0;
}

static double wrap(double x)
{
    return remainder(x, 2.0 * PI);
}

static void send_control(uint8_t command, uint8_t heading_valid)
{
    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = command;
    c.heading_valid = heading_valid;
    c.heading = 3000u;
    c.height = navecu_can_cmd_control_height_encode((float)H0_M);
    c.cmd_counter = cmd_counter;
    cmd_counter = e2e_counter_next(cmd_counter);
    const hal_can_frame_t f = cf_control(&c, hal.t_us);
    feed(&f);
}

static uint16_t health_flags(void)
{
    return last_status.health_flags;
}

/* the navigator against the truth: heading (of the nose), roll, pitch, position */
static void assert_navigator(double heading_tol_deg)
{
    nav_real_t roll, pitch, heading;
    sins_euler(&app.run.nav, &roll, &pitch, &heading);
    assert_true(fabs(wrap((double)heading - nose_rad)) < heading_tol_deg * DEG);
    assert_true(fabs((double)roll) < 0.2 * DEG);
    assert_true(fabs((double)pitch) < 0.2 * DEG);
    const double dn = ((double)geo_lat_rad(&app.run.nav.pos) / DEG - lat_deg()) * DEG * R_EARTH_M;
    const double de = ((double)geo_lon_rad(&app.run.nav.pos) / DEG - lon_deg()) * DEG * R_EARTH_M *
                      cos(LAT0_DEG * DEG);
    assert_true(hypot(dn, de) < 3.0);
}

static void test_power_on_while_driving(void **state)
{
    (void)state;
    speed = 15.0;
    const double t = drive_until_navigating(10.0, 15.0);
    assert_true(t > 0.0 && t <= 2.0);
    drive(5.0, 15.0);
    assert_int_equal(app_mode(&app), APP_MODE_NAVIGATING);
    assert_true(n_position > 0u);
    assert_navigator(0.5);
    assert_false(health_flags() & NAVECU_HEALTH_NO_HEADING);
}

/* the navigator's horizontal distance from the truth now (m) */
static double position_error_m(void)
{
    const double dn = ((double)geo_lat_rad(&app.run.nav.pos) / DEG - lat_deg()) * DEG * R_EARTH_M;
    const double de = ((double)geo_lon_rad(&app.run.nav.pos) / DEG - lon_deg()) * DEG * R_EARTH_M *
                      cos(LAT0_DEG * DEG);
    return hypot(dn, de);
}

/* GIVEN fixes valid 100 ms before they arrive (the latency configured as such) at 15 m/s
 * WHEN the in-motion alignment starts navigation from one
 * THEN the navigator starts as close to the car as with fixes on time, not 1.5 m behind,
 *      where the car was when the fix was valid (the independent client's finding: speed x latency behind until the
 *      filter's first update) */
static void test_inmotion_start_carries_the_fix_to_now(void **state)
{
    (void)state;
    speed = 15.0;
    assert_true(drive_until_navigating(10.0, 15.0) > 0.0);
    const double on_time_m = position_error_m(); /* the start's own error, fixes on time */
    setup(NULL);
    app.cfg.gnss_latency_s = 0.1f;
    gnss_late_samples = 10u;
    speed = 15.0;
    assert_true(drive_until_navigating(10.0, 15.0) > 0.0);
    const double late_m = position_error_m();
    print_message("in-motion start at 15 m/s: %.3f m from the truth with fixes on time, "
                  "%.3f m with fixes 100 ms late\n", on_time_m, late_m);
    assert_true(fabs(late_m - on_time_m) < 0.05); /* 1.5 m more before: 15 m/s x 0.1 s */
}

/* the in-motion start's heading sigma (rad) at 15 m/s, printed with what the fixes say */
static double start_heading_sigma_rad(const char *what)
{
    speed = 15.0;
    assert_true(drive_until_navigating(10.0, 15.0) > 0.0);
    const double sigma = (double)app.run.align.mot_heading_sigma_rad;
    print_message("in-motion start at 15 m/s, %s: heading sigma %.3f deg\n", what, sigma / DEG);
    return sigma;
}

/* GIVEN a receiver configured as reporting no accuracy (gnss_accuracy = declared, its
 *       declared speed accuracy 1.0 m/s), whose fixes say 0.2 m/s
 * WHEN the in-motion alignment starts navigation at 15 m/s
 * THEN the start's heading sigma is the declared speed sigma over the speed (1/15 rad),
 *      as the filter takes that fix, not the frames' 0.2/15 (before, the alignment read the
 *      frames' field whatever the configuration said) */
static void test_inmotion_start_takes_the_declared_accuracy(void **state)
{
    (void)state;
    app.cfg.gnss_accuracy = GNSS_ACC_DECLARED;
    app.cfg.gnss_sacc_mps = 1.0f;
    const double sigma = start_heading_sigma_rad("declared 1.0 m/s");
    assert_true(fabs(sigma - 1.0 / 15.0) < 1e-4); /* float32 of 0.0667 rad */
}

/* GIVEN fixes whose HorizAccuracy says 30 m (a poor geometry: the receiver's first fixes
 *       after its own outage) while their SpeedAccuracy still says 0.2 m/s
 * WHEN the in-motion alignment starts navigation at 15 m/s
 * THEN the speed sigma taken is the one the geometry implies, 0.03/s x 30 m = 0.9 m/s
 *      (of the radial figure: conservative per axis by sqrt(2)), and the start's heading
 *      sigma that over 15 m/s (before: 0.2/15, the velocity of a 30 m
 *      fix trusted to 0.2 m/s; on the Kingston drive such fixes are 1 m/s off) */
static void test_poor_fix_velocity_is_not_trusted_beyond_its_geometry(void **state)
{
    (void)state;
    gnss_hacc_m = 30.0f;
    const double sigma = start_heading_sigma_rad("HorizAccuracy 30 m, SpeedAccuracy 0.2 m/s");
    assert_true(fabs(sigma - 0.03 * 30.0 / 15.0) < 1e-4);
}

/* GIVEN gnss_accuracy declared with 10 m, the fixes saying 1 m
 * WHEN the filter starts (the epoch after the in-motion alignment)
 * THEN its horizontal sigma is the declared 10 m's (7.1 m per axis), not the 1 m's: the
 *      declared figures are the fix's for every user (app.c) */
static void test_filter_takes_the_declared_accuracy(void **state)
{
    (void)state;
    app.cfg.gnss_accuracy = GNSS_ACC_DECLARED;
    app.cfg.gnss_hacc_m = 10.0f;
    speed = 15.0;
    assert_true(drive_until_navigating(10.0, 15.0) > 0.0);
    while (!app.run.fusion.on) {
        sample(0.0, 15.0);
    }
    const double s_e = (double)ekf_state_sigma(&app.run.fusion.ekf, EKF_DR);
    print_message("filter start, declared 10 m, fixes 1 m: east sigma %.2f m\n", s_e);
    assert_true(s_e > 5.0 && s_e < 7.2);
}

static void test_reset_at_speed(void **state)
{
    (void)state;
    speed = 15.0;
    assert_true(drive_until_navigating(10.0, 15.0) > 0.0);
    drive(0.1, 15.0);
    /* the GNSS time from the first output set (the receiver's clock is known from the
     * epochs before the start; the independent client found 0.1-0.2 s of 'unknown'
     * TimeOfWeek after every start) */
    assert_int_equal(first_nav_time_known, 1);
    drive(2.9, 15.0);
    send_control(1u, 0u); /* Reset */
    first_nav_time_known = -1;
    assert_int_equal(app_mode(&app), APP_MODE_WAIT_INIT);
    const double t = drive_until_navigating(10.0, 15.0);
    assert_true(t > 0.0 && t <= 2.0);
    drive(0.1, 15.0);
    assert_int_equal(first_nav_time_known, 1); /* the Reset kept the receiver's clock */
    drive(4.9, 15.0);
    assert_navigator(0.5);
}

static void test_set_initial_position_without_heading(void **state)
{
    (void)state;
    drive(1.0, 0.0);
    const hal_can_frame_t f = cf_known_position((int32_t)lround(LAT0_DEG * 1e7),
                                                (int32_t)lround(LON0_DEG * 1e7), hal.t_us);
    feed(&f);
    send_control(2u, 0u); /* SetInitialPosition, HeadingValid 0 */
    drive(3.0, 0.0);
    assert_int_equal(app_mode(&app), APP_MODE_WAIT_INIT);
    assert_true(health_flags() & NAVECU_HEALTH_NO_HEADING);
    /* drive off: 1.5 m/s^2 to 15 m/s (10 s) */
    int k = 0;
    while (speed < 15.0 && k < 20 * RATE_HZ) {
        sample(1.5, 15.0);
        k++;
    }
    const double t = app_mode(&app) == APP_MODE_NAVIGATING ? 0.0 : drive_until_navigating(10.0, 15.0);
    assert_true(t >= 0.0 && t <= 2.0);
    drive(5.0, 15.0);
    assert_navigator(0.5);
    assert_false(health_flags() & NAVECU_HEALTH_NO_HEADING);
}

static void test_gnss_only_at_rest_says_no_heading(void **state)
{
    (void)state;
    drive(3.0, 0.0);
    assert_int_equal(app_mode(&app), APP_MODE_WAIT_INIT);
    assert_true(health_flags() & NAVECU_HEALTH_NO_HEADING);
}

static void test_reversing_heading_is_the_course_reversed(void **state)
{
    (void)state;
    speed = -6.0;
    const double t = drive_until_navigating(10.0, -6.0);
    assert_true(t > 0.0 && t <= 2.0);
    drive(3.0, -6.0);
    assert_navigator(2.0); /* course sigma 0.2 / 6: about 2 deg */
}

static void send_known_position(void)
{
    const hal_can_frame_t f = cf_known_position((int32_t)lround(lat_deg() * 1e7),
                                                (int32_t)lround(lon_deg() * 1e7), hal.t_us);
    feed(&f);
}

/* the case: a Reset at 15 m/s, then CMD_KnownPosition + SetInitialPosition:
 * refused (Moving, counted), never Levelling while driving, the in-motion alignment
 * navigates within 2 s of the reset */
static void test_set_initial_position_while_driving_refused(void **state)
{
    (void)state;
    speed = 15.0;
    assert_true(drive_until_navigating(10.0, 15.0) > 0.0);
    drive(2.0, 15.0);
    send_control(1u, 0u); /* Reset */
    send_known_position();
    const uint32_t before = app.keep.health.cmd_rejected;
    send_control(2u, 1u); /* SetInitialPosition with a heading */
    assert_int_equal(app.keep.health.cmd_rejected, before + 1u);
    assert_int_equal(app.keep.cmd_refusal, CMD_REFUSAL_MOVING);
    assert_int_equal(app_mode(&app), APP_MODE_WAIT_INIT);
    const double t = drive_until_navigating(10.0, 15.0);
    assert_true(t > 0.0 && t <= 2.0);
    drive(5.0, 15.0);
    assert_navigator(0.5);
    assert_int_equal(n_levelling_moving, 0u);
}

/* a CMD_KnownPosition the car has driven away from: SetInitialPosition at the next stop
 * is refused (StalePosition), nothing starts from the old point */
static void test_stale_known_position_refused(void **state)
{
    (void)state;
    drive(1.0, 0.0);
    send_known_position();
    for (int k = 0; k < 2 * RATE_HZ; k++) {
        sample(1.0, 2.0);
    }
    for (int k = 0; k < 3 * RATE_HZ; k++) {
        sample(-1.0, 0.0);
    }
    drive(1.0, 0.0);
    assert_true(fabs(speed) < 1e-9);
    const uint32_t before = app.keep.health.cmd_rejected;
    send_control(2u, 1u);
    assert_int_equal(app.keep.health.cmd_rejected, before + 1u);
    assert_int_equal(app.keep.cmd_refusal, CMD_REFUSAL_STALE_POSITION);
    assert_int_equal(app_mode(&app), APP_MODE_WAIT_INIT);
    assert_false(app.run.align.pos_valid);
}

/* SetInitialPosition at rest, then the car drives off before levelling ends: the point is
 * dropped (StalePosition, counted), the status leaves Levelling, and the in-motion
 * alignment starts once at speed */
static void test_drive_off_during_levelling_drops_the_point(void **state)
{
    (void)state;
    drive(1.0, 0.0);
    send_known_position();
    send_control(2u, 1u);
    assert_int_equal(app_mode(&app), APP_MODE_LEVELLING);
    drive(0.5, 0.0);
    const uint32_t before = app.keep.health.cmd_rejected;
    sample(1.5, 15.0);
    sample(1.5, 15.0);
    sample(1.5, 15.0);
    assert_int_equal(app_mode(&app), APP_MODE_WAIT_INIT);
    assert_int_equal(app.keep.health.cmd_rejected, before + 1u);
    assert_int_equal(app.keep.cmd_refusal, CMD_REFUSAL_STALE_POSITION);
    while (speed < 15.0) {
        sample(1.5, 15.0);
    }
    const double t = app_mode(&app) == APP_MODE_NAVIGATING ? 0.0 : drive_until_navigating(10.0, 15.0);
    assert_true(t >= 0.0 && t <= 2.0);
    drive(5.0, 15.0);
    assert_navigator(0.5);
    assert_int_equal(n_levelling_moving, 0u);
}

/* GIVEN the GNSS-only start: a course seen briefly above 5 m/s (too short a window for the
 *       in-motion alignment), then the car stops and the firmware levels on its own
 *       (level_s 2 s here)
 * WHEN the car drives off during that levelling
 * THEN the levelling stops (WaitInit, never Levelling while driving), but no command is
 *      counted refused: none was sent (before, CntCmdRejected +1 and REJECTED for a
 *      StalePosition nobody commanded) */
static void test_drive_off_during_gnss_only_levelling_refuses_nothing(void **state)
{
    (void)state;
    drive(1.0, 0.0);
    while (speed < 6.0) {
        sample(3.0, 6.0);
    }
    while (speed > 0.0) {
        sample(-3.0, 0.0);
    }
    drive(1.0, 0.0); /* half the levelling (level_s 2 here) */
    assert_int_equal(app_mode(&app), APP_MODE_LEVELLING);
    const uint32_t before = app.keep.health.cmd_rejected;
    for (int k = 0; k < RATE_HZ; k++) {
        sample(1.5, 15.0);
    }
    assert_int_equal(app_mode(&app), APP_MODE_WAIT_INIT);
    assert_int_equal(app.keep.health.cmd_rejected, before);
    assert_int_equal(n_levelling_moving, 0u);
}

/* GIVEN navigation with a 1 Hz wheel-speed source (an OBD-II speed), the car stopped for
 *       3 s (zero wheels: a standstill)
 * WHEN it drives off at 1.5 m/s^2 while the wheel speeds still read 0 for 1 s (the
 *      source's reading is up to a second old)
 * THEN the filter does not hold it at zero velocity: after that second the navigator's
 *      speed is within 0.03 m/s of the true 1.5 m/s (exact IMU data here: the IMU's
 *      acceleration integrated; before, zero-velocity updates took the first tenths of a
 *      second until their gate refused them: 1.419 m/s) */
static void test_drive_off_with_lagging_zero_wheels(void **state)
{
    (void)state;
    wheel_every = RATE_HZ;
    speed = 15.0;
    assert_true(drive_until_navigating(10.0, 15.0) > 0.0);
    drive(20.0, 15.0);
    while (speed > 0.0) {
        sample(-3.0, 0.0);
    }
    drive(3.0, 0.0);
    wheels_read_zero = 1;
    for (int k = 0; k < RATE_HZ; k++) {
        sample(1.5, 15.0);
    }
    const double v_nav = hypot((double)app.run.nav.v_n_mps[0], (double)app.run.nav.v_n_mps[1]);
    print_message("drive-off, wheels reading 0: navigator %.3f m/s, true %.3f m/s\n", v_nav, speed);
    assert_true(fabs(v_nav - speed) < 0.03);
}

/* GIVEN power-on while accelerating at 1 m/s^2 from 10 m/s, no command
 * WHEN 0.5 s of IMU samples are lost inside the in-motion alignment's first window
 *      (beyond the 200 ms that are bridged)
 * THEN the window starts again after the gap: the start's roll and pitch are within
 *      0.2 deg of level (the window summed the samples it had and the GNSS speed change
 *      over the whole interval: 1 m/s^2 x 0.5 s missing is 3 deg of pitch) */
static void test_imu_gap_in_the_alignment_window(void **state)
{
    (void)state;
    speed = 10.0;
    drive(0.05, 10.0); /* the first epoch at 0.1 s opens the window */
    for (int k = 0; k < 10; k++) {
        sample(1.0, 30.0);
    }
    imu_drop = 1;
    for (int k = 0; k < 50; k++) {
        sample(1.0, 30.0);
    }
    imu_drop = 0;
    int n = 0;
    while (app_mode(&app) != APP_MODE_NAVIGATING && n++ < 10 * RATE_HZ) {
        sample(1.0, 30.0);
    }
    assert_int_equal(app_mode(&app), APP_MODE_NAVIGATING);
    nav_real_t roll, pitch, heading;
    sins_euler(&app.run.nav, &roll, &pitch, &heading);
    print_message("in-motion start after a 0.5 s IMU gap: roll %.3f deg, pitch %.3f deg\n",
                  (double)roll / DEG, (double)pitch / DEG);
    assert_true(fabs((double)roll) < 0.2 * DEG);
    assert_true(fabs((double)pitch) < 0.2 * DEG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_power_on_while_driving, setup),
        cmocka_unit_test_setup(test_inmotion_start_carries_the_fix_to_now, setup),
        cmocka_unit_test_setup(test_inmotion_start_takes_the_declared_accuracy, setup),
        cmocka_unit_test_setup(test_poor_fix_velocity_is_not_trusted_beyond_its_geometry, setup),
        cmocka_unit_test_setup(test_filter_takes_the_declared_accuracy, setup),
        cmocka_unit_test_setup(test_reset_at_speed, setup),
        cmocka_unit_test_setup(test_set_initial_position_without_heading, setup),
        cmocka_unit_test_setup(test_gnss_only_at_rest_says_no_heading, setup),
        cmocka_unit_test_setup(test_reversing_heading_is_the_course_reversed, setup),
        cmocka_unit_test_setup(test_set_initial_position_while_driving_refused, setup),
        cmocka_unit_test_setup(test_stale_known_position_refused, setup),
        cmocka_unit_test_setup(test_drive_off_during_levelling_drops_the_point, setup),
        cmocka_unit_test_setup(test_drive_off_during_gnss_only_levelling_refuses_nothing, setup),
        cmocka_unit_test_setup(test_drive_off_with_lagging_zero_wheels, setup),
        cmocka_unit_test_setup(test_imu_gap_in_the_alignment_window, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
