/*
 * test_commands.c - commands.h: what CMD_KnownPosition, CMD_Control and
 * CMD_InitialAttitude do to the application's state, and when one is refused (counted in
 * cmd_rejected). The commands come decoded, as app_rx gives them.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "commands.h"
#include "app_fixture.h"
#include "fake_hal.h"
#include "navecu_can.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define RM_45 6367381.8 /* WGS-84 meridian radius at 45 deg */

static hal_t hal;
static app_t app;

static int setup(void **state)
{
    (void)state;
    assert_int_equal(fx_fresh_app(&app, &hal), NAV_OK);
    return 0;
}

static void known(int32_t lat_e7, int32_t lon_e7)
{
    rx_input_t in;
    memset(&in, 0, sizeof in);
    in.kind = RX_KNOWN_POSITION;
    in.u.position.lat_e7 = lat_e7;
    in.u.position.lon_e7 = lon_e7;
    commands_handle(&app, &hal, &in);
}

static rx_input_t control(rx_command_t command)
{
    rx_input_t in;
    memset(&in, 0, sizeof in);
    in.kind = RX_COMMAND;
    in.u.command.command = command;
    in.u.command.heading_in_range = 1u;
    in.u.command.height_in_range = 1u;
    return in;
}

static void command(rx_command_t c)
{
    const rx_input_t in = control(c);
    commands_handle(&app, &hal, &in);
}

/* SetInitialPosition at height h_cm, heading (rad) if valid */
static void set_initial(int heading_valid, float heading_rad, int32_t h_cm)
{
    rx_input_t in = control(RX_CMD_SET_INITIAL_POSITION);
    in.u.command.heading_valid = heading_valid ? 1u : 0u;
    in.u.command.heading_rad = heading_rad;
    in.u.command.h_cm = h_cm;
    commands_handle(&app, &hal, &in);
}

static void attitude(float roll, float pitch)
{
    rx_input_t in;
    memset(&in, 0, sizeof in);
    in.kind = RX_INITIAL_ATTITUDE;
    in.u.attitude.roll_rad = roll;
    in.u.attitude.pitch_rad = pitch;
    commands_handle(&app, &hal, &in);
}

static uint32_t refused(void)
{
    return app_health(&app)->cmd_rejected;
}

/* GIVEN a known position and SetInitialPosition with heading 30 deg at 123.45 m THEN
 * levelling starts from exactly there. */
static void test_set_initial_position(void **state)
{
    (void)state;
    known(451234567, 98765432);
    assert_int_equal(app.run.align.known_valid, 1);
    set_initial(1, (float)(30.0 * DEG), 12345);
    assert_int_equal(refused(), 0u);
    assert_int_equal(app_mode(&app), APP_MODE_LEVELLING);
    const geo_pos_t p = align_pos_of(451234567, 98765432, 12345);
    assert_true(app.run.align.pos.lat == p.lat && app.run.align.pos.lon == p.lon &&
                app.run.align.pos.h == p.h);
    assert_int_equal(app.run.align.h_cm, 12345);
    assert_near(app.run.align.heading_rad, 30.0 * DEG, 1e-7);
    assert_int_equal(app.run.align.level_n, 0u);
}

/* Without a heading: the position is taken, the car waits for a heading (NO_HEADING). */
static void test_set_initial_position_without_heading(void **state)
{
    (void)state;
    known(450000000, 100000000);
    set_initial(0, 0.0f, 0);
    assert_int_equal(refused(), 0u);
    assert_int_equal(app_mode(&app), APP_MODE_WAIT_INIT);
    assert_int_equal(app.run.align.pos_valid, 1);
    assert_int_equal(app.run.align.heading_valid, 0);
}

/* Refused: no known position; a valid heading out of range; a height out of range. A
 * heading out of range that is not valid is not looked at. */
static void test_set_initial_position_refused(void **state)
{
    (void)state;
    set_initial(1, 0.0f, 0);
    assert_int_equal(refused(), 1u);
    assert_int_equal(app.run.events.reject.seen, 1); /* REJECTED */
    assert_int_equal(app_mode(&app), APP_MODE_WAIT_INIT);
    assert_int_equal(app.run.align.pos_valid, 0);
    known(450000000, 100000000);
    rx_input_t in = control(RX_CMD_SET_INITIAL_POSITION);
    in.u.command.heading_valid = 1u;
    in.u.command.heading_in_range = 0u;
    commands_handle(&app, &hal, &in);
    assert_int_equal(refused(), 2u);
    in = control(RX_CMD_SET_INITIAL_POSITION);
    in.u.command.height_in_range = 0u;
    commands_handle(&app, &hal, &in);
    assert_int_equal(refused(), 3u);
    assert_int_equal(app.run.align.pos_valid, 0);
    in = control(RX_CMD_SET_INITIAL_POSITION);
    in.u.command.heading_in_range = 0u;
    commands_handle(&app, &hal, &in);
    assert_int_equal(refused(), 3u);
    assert_int_equal(app.run.align.pos_valid, 1);
}

/* SetInitialPosition and Reset restart navigation: app_run_t anew, app_keep_t kept (the
 * time base, the health counters, the calibration). The known position belongs to the run:
 * after a reset it must be given again. */
static void test_reset_keeps_the_ecu_state(void **state)
{
    (void)state;
    app.keep.n_samples = 500u;
    app.keep.health.bad_crc = 3u;
    app.keep.cal.mu = 0.01f;
    app.run.imu.n_pending = 1u;
    known(450000000, 100000000);
    set_initial(1, 0.0f, 0);
    assert_int_equal(app.run.imu.n_pending, 0);
    assert_int_equal(app.run.align.known_valid, 0);
    app.run.mode = APP_MODE_NAVIGATING;
    command(RX_CMD_RESET);
    assert_int_equal(app_mode(&app), APP_MODE_WAIT_INIT);
    assert_int_equal(app.run.align.pos_valid, 0);
    assert_int_equal(app_samples(&app), 500u);
    assert_int_equal(app.keep.health.bad_crc, 3u);
    assert_near(app.keep.cal.mu, 0.01f, 0.0);
    set_initial(1, 0.0f, 0);
    assert_int_equal(refused(), 1u);
}

/* CMD_InitialAttitude ends levelling at once with its roll and pitch; outside levelling it
 * is refused. */
static void test_initial_attitude(void **state)
{
    (void)state;
    attitude(0.1f, -0.05f);
    assert_int_equal(refused(), 1u);
    known(450000000, 100000000);
    set_initial(1, (float)(60.0 * DEG), 10000);
    attitude(0.1f, -0.05f);
    assert_int_equal(refused(), 1u);
    assert_int_equal(app_mode(&app), APP_MODE_NAVIGATING);
    nav_real_t r, p, h;
    sins_euler(&app.run.nav, &r, &p, &h);
    assert_near(r, 0.1, 1e-6);
    assert_near(p, -0.05, 1e-6);
    assert_near(h, 60.0 * DEG, 1e-6);
    assert_int_equal(app.run.land.output_dr, 0);
    attitude(0.1f, -0.05f);
    assert_int_equal(refused(), 2u);
}

/* A start the core refuses (the calibration in use beyond what the dead reckoning takes):
 * mode Fault, counted in bad_value. */
static void test_start_refused_is_fault(void **state)
{
    (void)state;
    known(450000000, 100000000);
    set_initial(1, 0.0f, 0);
    app.keep.cal.mu = 0.3f;
    commands_start_navigation(&app, 0.0f, 0.0f);
    assert_int_equal(app_mode(&app), APP_MODE_FAULT);
    assert_int_equal(app_health(&app)->bad_value, 1u);
}

/* StoreCalibration and EraseCalibration (destructive, any node on the bus could send
 * them) moved to UDS RoutineControl 0x0203 / 0x0201: on CMD_Control each is refused and
 * counted, with a calibration in use or not, and the store and the values in use stay. */
static void test_store_and_erase_refused(void **state)
{
    (void)state;
    app.keep.n_samples = 100u;
    command(RX_CMD_STORE_CALIBRATION);
    assert_int_equal(refused(), 1u);
    app.keep.cal.source = NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_KNOWN_POSITION_CHOICE;
    app.keep.cal.mu = 0.015f;
    command(RX_CMD_STORE_CALIBRATION);
    assert_int_equal(refused(), 2u);
    calstore_t cs;
    cal_record_t rec;
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_EMPTY);
    calib_store(&app.keep.cal, &app.run.cal, &hal, 100u);
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_OK);
    command(RX_CMD_ERASE_CALIBRATION);
    assert_int_equal(refused(), 3u);
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_OK);
    assert_near(rec.odo_scale_err, 0.015f, 0.0);
    assert_near(app.keep.cal.mu, 0.015f, 0.0);
    assert_int_equal(app.keep.cal.source,
                     NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_KNOWN_POSITION_CHOICE);
}

/* navigating at 45 N 10 E heading north, on the odometer without the filter */
static void navigate_on_odometer(void)
{
    known(450000000, 100000000);
    set_initial(1, 0.0f, 0);
    attitude(0.0f, 0.0f);
    assert_int_equal(app_mode(&app), APP_MODE_NAVIGATING);
    app.run.land.output_dr = 1u;
}

/* CalibrateHere: without a known position, or not navigating on the odometer (waiting for
 * init, or with the filter running), refused as RefusedNotReady, and the point is used up.
 * GIVEN 3000 m dead-reckoned north and the true point right there THEN a one-point
 * calibration of dH 0, mu 0 (CalStatus OnePoint, source KnownPosition). */
static void test_calibrate_here(void **state)
{
    (void)state;
    command(RX_CMD_CALIBRATE_HERE);
    assert_int_equal(refused(), 1u);
    assert_int_equal(app.keep.cal.status,
                     NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE);
    known(450000000, 100000000);
    command(RX_CMD_CALIBRATE_HERE); /* waiting for init */
    assert_int_equal(refused(), 2u);
    assert_int_equal(app.run.align.known_valid, 0);
    command(RX_CMD_CALIBRATE_HERE); /* the point was used */
    assert_int_equal(refused(), 3u);

    app.keep.cal.status = 0u;
    navigate_on_odometer();
    for (int k = 0; k < 300; k++) {
        assert_int_equal(dr_step(&app.run.dr, 10.0f, 0.0f, 0.0f), NAV_OK);
    }
    const int32_t lat_e7 = (int32_t)lround((45.0 + 3000.0 / RM_45 / DEG) * 1e7);
    app.run.fusion.on = 1u;
    known(lat_e7, 100000000);
    command(RX_CMD_CALIBRATE_HERE);
    assert_int_equal(refused(), 4u);
    assert_int_equal(app.keep.cal.status,
                     NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE);
    app.run.fusion.on = 0u;
    known(lat_e7, 100000000);
    command(RX_CMD_CALIBRATE_HERE);
    assert_int_equal(refused(), 4u);
    assert_int_equal(app.keep.cal.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_ONE_POINT_CHOICE);
    assert_int_equal(app.keep.cal.source,
                     NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_KNOWN_POSITION_CHOICE);
    assert_int_equal(app.keep.cal.count, 1);
    assert_near(app.keep.cal.dh_rad, 0.0, 2e-5);
    assert_near(app.keep.cal.mu, 0.0, 2e-5);
    assert_near(app.keep.cal.base_m, 3000.0, 0.05);
}

/* CalibrateAtGnss: only while navigating; it marks the next accepted fix. */
static void test_calibrate_at_gnss(void **state)
{
    (void)state;
    command(RX_CMD_CALIBRATE_AT_GNSS);
    assert_int_equal(refused(), 1u);
    assert_int_equal(app.run.cal.at_gnss, 0);
    assert_int_equal(app.keep.cal.status,
                     NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE);
    navigate_on_odometer();
    command(RX_CMD_CALIBRATE_AT_GNSS);
    assert_int_equal(refused(), 1u);
    assert_int_equal(app.run.cal.at_gnss, 1);
}

/* Command None does nothing; a value the protocol does not define is refused. */
static void test_none_and_unknown(void **state)
{
    (void)state;
    known(450000000, 100000000);
    set_initial(1, 0.0f, 0);
    command(RX_CMD_NONE);
    assert_int_equal(refused(), 0u);
    assert_int_equal(app_mode(&app), APP_MODE_LEVELLING);
    command(RX_CMD_UNKNOWN);
    assert_int_equal(refused(), 1u);
    assert_int_equal(app_mode(&app), APP_MODE_LEVELLING);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_set_initial_position, setup),
        cmocka_unit_test_setup(test_set_initial_position_without_heading, setup),
        cmocka_unit_test_setup(test_set_initial_position_refused, setup),
        cmocka_unit_test_setup(test_reset_keeps_the_ecu_state, setup),
        cmocka_unit_test_setup(test_initial_attitude, setup),
        cmocka_unit_test_setup(test_start_refused_is_fault, setup),
        cmocka_unit_test_setup(test_store_and_erase_refused, setup),
        cmocka_unit_test_setup(test_calibrate_here, setup),
        cmocka_unit_test_setup(test_calibrate_at_gnss, setup),
        cmocka_unit_test_setup(test_none_and_unknown, setup),
    };
    return cmocka_run_group_tests_name("commands", tests, NULL, NULL);
}
