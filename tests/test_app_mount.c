/*
 * test_app_mount.c - the automatic mounting in the application (imu_mount_source
 * automatic; firmware/app/app.c, mount_est.c) against the in-memory HAL, with IMU and
 * WheelSpeeds frames of a car that stands, then accelerates and brakes, the IMU upside
 * down and turned 90 deg (roll 180, yaw 90):
 *  - the start is held: levelling ends in mode Fault, no NAV_Position, NAV_Calibration
 *    pages 1 and 2 say Estimating; app_adopt_mounting refuses (-1, nothing changed);
 *  - the estimate converges on the accelerations (excitation 5 m^2/s^3): MountState
 *    Estimated, the mounting in use is the estimate, within 0.2 deg of the truth
 *    (quantisation of the frames: 2^-12 m/s per sample, carried; wheel speeds in 0.02 m/s
 *    steps, whose error over a 0.5-s window is below 0.04 m/s^2 of 1 m/s^2: 2 deg at
 *    worst on one window, averaged over tens), and the start waits for GNSS while driving;
 *  - app_adopt_mounting copies it into the parameters, the source becomes fixed;
 *  - in fixed mode (the default) no page 1 or 2 is ever sent.
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
#include "e2e.h"
#include "fake_hal.h"
#include "navecu_can.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define RATE_HZ 100

static hal_t hal;
static app_t app;
static mounting_t truth_mount;
static double carry_v[3], speed;
static uint8_t imu_counter, wheel_counter, cmd_counter;
static uint32_t n_position, n_cal_page[3];
static struct navecu_can_nav_calibration_t last_page[3];

static void feed(const hal_can_frame_t *f)
{
    app_handle_frame(&app, &hal, f);
}

/* the frames sent since the last call: counted and the buffer emptied */
static void drain(void)
{
    for (uint32_t i = 0u; i < hal.tx_n; i++) {
        const hal_can_frame_t *f = &hal.tx[i];
        if (f->id == app.cfg.can_ids[NAVECU_MSG_NAV_POSITION]) {
            n_position++;
        } else if (f->id == app.cfg.can_ids[NAVECU_MSG_NAV_CALIBRATION]) {
            struct navecu_can_nav_calibration_t m;
            assert_int_equal(navecu_can_nav_calibration_unpack(&m, f->data, 8u), 0);
            assert_true(m.cal_page <= 2u);
            n_cal_page[m.cal_page]++;
            last_page[m.cal_page] = m;
        }
    }
    hal.tx_n = 0u;
}

static void start(mount_source_t source)
{
    fake_hal_reset(&hal);
    app_config_t cfg = app_default_config();
    cfg.imu_mount_source = source;
    cfg.mount_est_sigma_rad = (nav_real_t)(1.0 * DEG);
    cfg.mount_est_excite_m2ps3 = 5.0f;
    cfg.level_s = 2u;
    assert_int_equal(app_init(&app, &cfg), NAV_OK);
    const nav_real_t rpy[3] = {(nav_real_t)(180.0 * DEG), 0.0f, (nav_real_t)(90.0 * DEG)};
    mounting_init(&truth_mount, rpy);
    memset(carry_v, 0, sizeof carry_v);
    speed = 0.0;
    imu_counter = wheel_counter = cmd_counter = 0u;
    n_position = 0u;
    memset(n_cal_page, 0, sizeof n_cal_page);
    hal.t_us = 1000000u;
}

static void init_commands(void)
{
    hal_can_frame_t f = cf_known_position(450000000, 100000000, hal.t_us);
    feed(&f);
    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = 2u; /* SetInitialPosition */
    c.heading_valid = 1u;
    c.heading = 3000u;
    c.height = 1000;
    c.cmd_counter = cmd_counter;
    cmd_counter = e2e_counter_next(cmd_counter);
    f = cf_control(&c, hal.t_us);
    feed(&f);
}

/* one 100-Hz sample of the car accelerating at a (m/s^2, forward, no turn), the IMU's
 * specific force in its own axes; wheel speeds every second sample */
static void sample(double a)
{
    const double v0 = speed;
    speed = v0 + a / RATE_HZ;
    if (speed < 0.0) {
        speed = 0.0;
    }
    const double a_eff = (speed - v0) * RATE_HZ;
    const double fv[3] = {0.0, a_eff, 9.80665};
    int32_t w[3] = {0, 0, 0}, v[3];
    for (int i = 0; i < 3; i++) {
        double f = 0.0;
        for (int k = 0; k < 3; k++) {
            f += (double)truth_mount.C_vi.m[k][i] * fv[k]; /* C_iv = C_vi^T */
        }
        const double lsb = f / RATE_HZ * 4096.0 + carry_v[i];
        v[i] = (int32_t)lround(lsb);
        carry_v[i] = lsb - v[i];
    }
    hal.t_us += 1000000u / RATE_HZ;
    hal_can_frame_t fr, fa;
    cf_imu_pair(w, v, imu_counter, 0u, hal.t_us, &fr, &fa);
    imu_counter = e2e_counter_next(imu_counter);
    feed(&fr);
    feed(&fa);
    if (imu_counter % 2u == 0u) {
        const int16_t raw = (int16_t)lround(speed / 0.02);
        const int16_t four[4] = {raw, raw, raw, raw};
        const hal_can_frame_t fw = cf_wheels(four, wheel_counter, hal.t_us);
        wheel_counter = e2e_counter_next(wheel_counter);
        feed(&fw);
    }
    app_poll(&app, &hal);
    drain();
}

static void stand(int n)
{
    for (int k = 0; k < n; k++) {
        sample(0.0);
    }
}

/* accelerate 4 s at 1 m/s^2, brake 4 s: one cycle 0 -> 4 m/s -> 0 */
static void cycle(void)
{
    for (int k = 0; k < 4 * RATE_HZ; k++) {
        sample(1.0);
    }
    for (int k = 0; k < 4 * RATE_HZ; k++) {
        sample(-1.0);
    }
}

static double wrap(double x)
{
    return remainder(x, 2.0 * PI);
}

static void test_start_held_then_estimated(void **state)
{
    (void)state;
    start(MOUNT_SOURCE_AUTOMATIC);
    assert_int_equal(app.keep.mount_state, APP_MOUNT_ESTIMATING);
    init_commands();
    stand(5 * RATE_HZ); /* levelling 2 s, the estimate's first 8 windows 4 s */
    /* levelling done, the start held for the mounting */
    assert_int_equal(app_mode(&app), APP_MODE_FAULT);
    assert_int_equal(app.run.mount_held, 1u);
    assert_int_equal(n_position, 0u);
    assert_true(n_cal_page[1] >= 2u && n_cal_page[2] >= 2u);
    assert_int_equal(last_page[2].mount_state, NAVECU_CAN_NAV_CALIBRATION_MOUNT_STATE_ESTIMATING_CHOICE);
    const app_config_t before = app.cfg;
    assert_int_equal(app_adopt_mounting(&app), -1);
    assert_memory_equal(&app.cfg, &before, sizeof before);
    /* roll and pitch known at rest already, the yaw not */
    const mount_est_result_t *r = app_mount_estimate(&app);
    assert_true(r->valid);
    assert_false(r->converged);
    assert_true(fabs(wrap((double)r->rpy_rad[0] - PI)) < 0.05 * DEG);
    int cycles = 0;
    while (app.keep.mount_state == APP_MOUNT_ESTIMATING && cycles < 10) {
        cycle();
        cycles++;
    }
    assert_int_equal(app.keep.mount_state, APP_MOUNT_ESTIMATED);
    assert_true(cycles <= 2); /* 5 m^2/s^3: 5 s of 1 m/s^2 */
    /* the sigmas at convergence go with the mounting in use, for the filter's start */
    for (int i = 0; i < 2; i++) {
        assert_true(app.keep.mount_sigma_rad[i] > 0.0f);
        assert_true(app.keep.mount_sigma_rad[i] <= app.cfg.mount_est_sigma_rad);
    }
    assert_true(fabs(wrap((double)r->rpy_rad[0] - PI)) < 0.2 * DEG);
    assert_true(fabs((double)r->rpy_rad[1]) < 0.2 * DEG);
    assert_true(fabs(wrap((double)r->rpy_rad[2] - 90.0 * DEG)) < 0.2 * DEG);
    /* the mounting in use: the estimate's rotation, the true one within 0.2 deg */
    assert_int_equal(app.keep.mount.rotate, 1u);
    for (int i = 0; i < 3; i++) {
        for (int k = 0; k < 3; k++) {
            assert_true(fabs((double)app.keep.mount.C_vi.m[i][k] -
                             (double)truth_mount.C_vi.m[i][k]) < 0.2 * DEG);
        }
    }
    /* the start waits for GNSS while driving: none here */
    assert_int_equal(app.run.mount_held, 0u);
    assert_int_equal(app.run.mount_start, 1u);
    assert_int_equal(app.run.align.reacquire, 1u);
    assert_int_equal(app_mode(&app), APP_MODE_FAULT);
    assert_int_equal(n_position, 0u);
    stand(RATE_HZ + 1);
    assert_int_equal(last_page[2].mount_state, NAVECU_CAN_NAV_CALIBRATION_MOUNT_STATE_ESTIMATED_CHOICE);
    assert_true(fabs((double)navecu_can_nav_calibration_mount_yaw_decode(last_page[1].mount_yaw) - 90.0) < 0.2);
    assert_true(fabs(fabs((double)navecu_can_nav_calibration_mount_roll_decode(last_page[1].mount_roll)) - 180.0) < 0.2);
    /* adopted: the parameters take it, the source becomes fixed */
    assert_int_equal(app_adopt_mounting(&app), 0);
    assert_int_equal(app.cfg.imu_mount_source, MOUNT_SOURCE_FIXED);
    for (int i = 0; i < 3; i++) {
        assert_true(app.cfg.imu_mount_rad[i] > r->rpy_rad[i] - 1e-6f &&
                    app.cfg.imu_mount_rad[i] < r->rpy_rad[i] + 1e-6f);
    }
    assert_true(app_config_valid(&app.cfg));
}

static void test_fixed_sends_no_mount_pages(void **state)
{
    (void)state;
    start(MOUNT_SOURCE_FIXED);
    assert_int_equal(app.keep.mount_state, APP_MOUNT_FIXED);
    init_commands();
    stand(3 * RATE_HZ);
    assert_int_equal(app_mode(&app), APP_MODE_NAVIGATING);
    assert_true(n_cal_page[0] >= 2u);
    assert_int_equal(n_cal_page[1], 0u);
    assert_int_equal(n_cal_page[2], 0u);
    assert_int_equal(app_adopt_mounting(&app), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_start_held_then_estimated),
        cmocka_unit_test(test_fixed_sends_no_mount_pages),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
