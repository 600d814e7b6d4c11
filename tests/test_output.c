/*
 * test_output.c - output.h: the NAV_* frames from the application's state. HealthFlags
 * bits for their conditions and cleared after their hold time (1 s, 10 s, NO_GNSS after
 * 2 s, at 100 Hz), NAV_Status's page rotation 1..6 and counter saturation, the output
 * mode, heading 359.996 deg sent as 0, accuracy signals saturating one below "unknown",
 * the rounding of the fixed-point position, the output rates on the IMU time base.
 * Frames are read back with the generated codec.
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
#include "app_fixture.h"
#include "fake_hal.h"
#include "navecu_protocol.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

static hal_t hal;
static app_t app;

static int setup(void **state)
{
    (void)state;
    assert_int_equal(fx_fresh_app(&app, &hal), NAV_OK);
    return 0;
}

static uint16_t flags_now(void)
{
    output_status(&app, &hal);
    return cf_last_status_page0(&hal).health_flags;
}

/* navigating at 45 N 10 E, 100 m, level, heading deg, without the filter */
static void navigate(double heading_deg)
{
    const geo_pos_t p = {450000000LL * GEO_LSB_PER_DEG_E7, 100000000LL * GEO_LSB_PER_DEG_E7,
                         100000LL * GEO_LSB_PER_MM};
    nav_real_t q[4];
    quat_from_euler(0.0f, 0.0f, (nav_real_t)(heading_deg * DEG), q);
    const sins_config_t cfg = sins_default_config();
    const nav_real_t v0[3] = {0.0f, 0.0f, 0.0f};
    assert_int_equal(sins_init(&app.run.nav, &cfg, &p, v0, q), NAV_OK);
    assert_int_equal(dr_init(&app.run.dr, &p, 0.0f, 0.0f), NAV_OK);
    app.run.mode = APP_MODE_NAVIGATING;
}

/* the filter "running" with position sigmas sh (each horizontal axis) and sv */
static void filter_on(float sh, float sv)
{
    app.run.fusion.on = 1u;
    app.run.fusion.ekf.P[EKF_DR][EKF_DR] = sh * sh;
    app.run.fusion.ekf.P[EKF_DR + 1][EKF_DR + 1] = sh * sh;
    app.run.fusion.ekf.P[EKF_DR + 2][EKF_DR + 2] = sv * sv;
}

static void emit_now(void)
{
    hal.tx_n = 0u;
    output_due(&app, &hal); /* at a sample where every output is due (n = 0 mod 100) */
}

/* ---- HealthFlags ---- */

/* Fresh, nothing received: only NO_GNSS. */
static void test_flags_at_power_on(void **state)
{
    (void)state;
    assert_int_equal(flags_now(), NAVECU_HEALTH_NO_GNSS);
}

/* GIVEN an event stamped at sample 1000 THEN its flag is set through sample 1000 + hold
 * and clear one sample later, nothing else raised (a usable GNSS epoch keeps NO_GNSS out). */
static void check_hold(app_stamp_t *s, uint16_t bit, uint64_t hold)
{
    setup(NULL);
    app.run.align.heading_valid = 1u; /* not the GNSS-only start's NO_HEADING */
    app_stamp(s, 1000u);
    const uint64_t at[3] = {1000u, 1000u + hold, 1000u + hold + 1u};
    for (int i = 0; i < 3; i++) {
        app.keep.n_samples = at[i];
        app_stamp(&app.keep.gnss, at[i]);
        const uint16_t got = flags_now();
        const uint16_t want = i < 2 ? bit : 0u;
        if (got != want) {
            fail_msg("flag 0x%04x at +%llu: 0x%04x, expected 0x%04x", bit,
                     (unsigned long long)(at[i] - 1000u), got, want);
        }
    }
}

static void test_flags_held_for_their_time(void **state)
{
    (void)state;
    check_hold(&app.run.events.reject, NAVECU_HEALTH_REJECTED, 100u);
    check_hold(&app.run.events.gap, NAVECU_HEALTH_IMU_GAP, 100u);
    check_hold(&app.run.events.saturated, NAVECU_HEALTH_IMU_SATURATED, 100u);
    check_hold(&app.run.events.odo_reject, NAVECU_HEALTH_ODO_REJECTED, 100u);
    check_hold(&app.keep.filter_reset, NAVECU_HEALTH_FILTER_RESET, 1000u);
    check_hold(&app.run.events.stuck, NAVECU_HEALTH_IMU_SUSPECT, 1000u);
}

/* NO_GNSS: set until an epoch, clear for 2 s (200 samples) after it, set again after. */
static void test_flag_no_gnss(void **state)
{
    (void)state;
    app.run.align.heading_valid = 1u; /* not the GNSS-only start's NO_HEADING */
    app_stamp(&app.keep.gnss, 1000u);
    app.keep.n_samples = 1200u;
    assert_int_equal(flags_now(), 0u);
    app.keep.n_samples = 1201u;
    assert_int_equal(flags_now(), NAVECU_HEALTH_NO_GNSS);
}

/* A Reset (or SetInitialPosition) restarts navigation, not the receiver: the epoch of 0.1 s
 * ago still counts (the independent client found NO_GNSS 10 ms after each, with epochs
 * arriving at 5 Hz: the stamp lived in the state a reset clears). */
static void test_no_gnss_survives_reset(void **state)
{
    (void)state;
    app_stamp(&app.keep.gnss, 1000u);
    app.keep.n_samples = 1010u;
    app_reset(&app);
    app.run.align.heading_valid = 1u; /* not the GNSS-only start's NO_HEADING */
    assert_int_equal(flags_now() & NAVECU_HEALTH_NO_GNSS, 0u);
}

/* IMU_STALE: more than 0.5 s of HAL time since the last sample (not at 0.5 s). */
static void test_flag_imu_stale(void **state)
{
    (void)state;
    app.keep.imu.have_sample = 1u;
    app.keep.imu.last_t_us = 1000u;
    hal.t_us = 501000u;
    assert_int_equal(flags_now() & NAVECU_HEALTH_IMU_STALE, 0u);
    hal.t_us = 501001u;
    assert_int_equal(flags_now() & NAVECU_HEALTH_IMU_STALE, NAVECU_HEALTH_IMU_STALE);
    /* no sample ever: stale from 0.5 s after power-on (the first heartbeat's time) */
    app.keep.imu.have_sample = 0u;
    app.keep.tx.boot_us = 2000u;
    assert_int_equal(flags_now() & NAVECU_HEALTH_IMU_STALE, 0u);
    hal.t_us = 502001u;
    assert_int_equal(flags_now() & NAVECU_HEALTH_IMU_STALE, NAVECU_HEALTH_IMU_STALE);
}

/* The flags of a state: IMU_FAULT, NVM_ERROR, NO_HEADING (a position without heading,
 * before navigating; or GNSS only, waiting with no initial state), REACQUIRE. */
static void test_state_flags(void **state)
{
    (void)state;
    app_stamp(&app.keep.gnss, 0u);
    assert_int_equal(flags_now(), NAVECU_HEALTH_NO_HEADING); /* GNSS only, no heading */
    app.run.align.heading_valid = 1u;
    app.keep.imu.fault = 1u;
    assert_int_equal(flags_now(), NAVECU_HEALTH_IMU_FAULT);
    app.keep.imu.fault = 0u;
    app.keep.cal.nvm_error = 1u;
    assert_int_equal(flags_now(), NAVECU_HEALTH_NVM_ERROR);
    app.keep.cal.nvm_error = 0u;
    app.run.align.heading_valid = 0u;
    app.run.align.pos_valid = 1u;
    assert_int_equal(flags_now(), NAVECU_HEALTH_NO_HEADING);
    app.run.align.heading_valid = 1u;
    assert_int_equal(flags_now(), 0u);
    app.run.align.heading_valid = 0u;
    app.run.mode = APP_MODE_NAVIGATING;
    assert_int_equal(flags_now(), 0u);
    app.run.align.reacquire = 1u;
    assert_int_equal(flags_now(), NAVECU_HEALTH_REACQUIRE);
}

/* The board's faults (hal_faults): WATCHDOG_OFF in every NAV_Status while the watchdog is not
 * running; BUS_OFF in the first NAV_Status after a bus-off, then clear; each confirms its
 * DTC (C1108-47 confirmed at once; U0001-88 pending at once, confirmed by a second
 * operation cycle, test_dtc's rule). */
static void test_board_fault_flags(void **state)
{
    (void)state;
    app_stamp(&app.keep.gnss, 0u);
    app.run.align.heading_valid = 1u;
    assert_int_equal(flags_now(), 0u);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_WATCHDOG_OFF) & DTC_TF, 0u);
    hal.faults = HAL_FAULT_WATCHDOG;
    assert_int_equal(flags_now(), NAVECU_HEALTH_WATCHDOG_OFF);
    assert_int_equal(flags_now(), NAVECU_HEALTH_WATCHDOG_OFF); /* a state: held */
    assert_true((dtc_status(&app.keep.dtc, DTC_WATCHDOG_OFF) & (DTC_TF | DTC_CDTC)) ==
                (DTC_TF | DTC_CDTC));
    hal.faults = HAL_FAULT_BUS_OFF; /* an event: the fake clears it when read */
    assert_int_equal(flags_now(), NAVECU_HEALTH_BUS_OFF);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_BUS_OFF) & (DTC_TF | DTC_PDTC | DTC_CDTC),
                     DTC_TF | DTC_PDTC); /* one bus-off: pending, not confirmed */
    assert_int_equal(flags_now(), 0u);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_BUS_OFF) & (DTC_TF | DTC_PDTC | DTC_CDTC),
                     DTC_PDTC); /* passed again, still pending */
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_WATCHDOG_OFF) & DTC_TF, 0u);
}

/* NAV_Status every 100 ms of the HAL clock for s seconds, each saying NO_GNSS */
static void statuses_without_gnss(int s)
{
    for (int k = 0; k < 10 * s; k++) {
        hal.t_us += 100000u;
        assert_int_equal(flags_now() & NAVECU_HEALTH_NO_GNSS, NAVECU_HEALTH_NO_GNSS);
    }
}

/* The DTCs tested only while the car moves (dtc.toml while_moving: U1102-87 NO_GNSS,
 * debounced over 60 s) before navigation, where the odometer's standstill is not updated:
 * GIVEN an ECU waiting for GNSS (WaitInit, NO_GNSS) WHEN its wheels read zero for 70 s
 * THEN U1102-87 is not tested (a review found a car parked at power-on confirming it after
 * 60 s); WHEN they read a speed, or none at all (the odometer not valid), for 61 s THEN
 * it is tested and fails. Navigating, the odometer's standstill decides. */
static void test_waits_untested_while_parked_before_navigation(void **state)
{
    (void)state;
    assert_int_equal(app.run.mode, APP_MODE_WAIT_INIT);
    app.keep.odo.valid = 1u;
    app.keep.odo.zero = 1u;
    app.keep.odo.standing = 0u; /* as before navigation: nothing updates it */
    statuses_without_gnss(70);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_NO_GNSS) & (DTC_TF | DTC_TFTOC), 0u);
    app.keep.odo.zero = 0u; /* the wheels turn */
    statuses_without_gnss(61);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_NO_GNSS) & DTC_TF, DTC_TF);

    setup(NULL);
    app.keep.odo.valid = 0u; /* no wheel speeds: no standstill to see, every second tested */
    app.keep.odo.zero = 1u;
    statuses_without_gnss(61);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_NO_GNSS) & DTC_TF, DTC_TF);

    /* navigating, the standstill is the odometer's (zero wheels and no turn for 0.5 s,
     * odo_tick): zero wheels without it are tested, with it untested */
    setup(NULL);
    navigate(0.0);
    app.keep.odo.valid = 1u;
    app.keep.odo.zero = 1u;
    app.keep.odo.standing = 1u;
    statuses_without_gnss(70);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_NO_GNSS) & (DTC_TF | DTC_TFTOC), 0u);
    app.keep.odo.standing = 0u; /* turning on the spot, or not yet 0.5 s */
    statuses_without_gnss(61);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_NO_GNSS) & DTC_TF, DTC_TF);
}

/* Before the first IMU sample (output_dtc_tests: an ECU whose IMU never speaks) the board's
 * faults are tested too: a watchdog that did not start confirms C1108-47, a bus-off makes
 * U0001-88 pending (a review found neither tested there). */
static void test_board_faults_tested_without_imu(void **state)
{
    (void)state;
    hal.faults = HAL_FAULT_WATCHDOG | HAL_FAULT_BUS_OFF;
    output_dtc_tests(&app, &hal);
    assert_true((dtc_status(&app.keep.dtc, DTC_WATCHDOG_OFF) & (DTC_TF | DTC_CDTC)) ==
                (DTC_TF | DTC_CDTC));
    assert_true((dtc_status(&app.keep.dtc, DTC_BUS_OFF) & (DTC_TF | DTC_PDTC)) ==
                (DTC_TF | DTC_PDTC));
    output_dtc_tests(&app, &hal);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_BUS_OFF) & DTC_TF, 0u); /* event gone */
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_WATCHDOG_OFF) & DTC_TF, DTC_TF);
}

/* IMU_RATE_MISMATCH while the rate check says so, with the measured rate in page 0's
 * ImuRateMeasured (2 Hz steps, rounded; saturated at 510 Hz); 0 without a mismatch, even
 * with a rate measured before. */
static void test_imu_rate_mismatch_flag(void **state)
{
    (void)state;
    app.run.align.heading_valid = 1u; /* not the GNSS-only start's NO_HEADING */
    app_stamp(&app.keep.gnss, 0u);
    app.keep.rate.measured_chz = 40000u;
    assert_int_equal(flags_now(), 0u);
    assert_int_equal(cf_last_status_page0(&hal).imu_rate_measured, 0u);
    app.keep.rate.mismatch = 1u;
    assert_int_equal(flags_now(), NAVECU_HEALTH_IMU_RATE_MISMATCH);
    assert_int_equal(cf_last_status_page0(&hal).imu_rate_measured, 200u);
    app.keep.rate.measured_chz = 12345u; /* 123.45 Hz: 62 x 2 Hz */
    (void)flags_now();
    assert_int_equal(cf_last_status_page0(&hal).imu_rate_measured, 62u);
    app.keep.rate.measured_chz = 200000u; /* 2 kHz */
    (void)flags_now();
    assert_int_equal(cf_last_status_page0(&hal).imu_rate_measured, 255u);
}

/* ---- NAV_Status pages ---- */

static uint8_t page_of(const hal_can_frame_t *f)
{
    return (uint8_t)(f->data[0] & 0x0Fu);
}

/* Each NAV_Status is page 0 and one counter page, 1..6 in rotation; every frame E2E-valid
 * with one alive counter stepping through 0..14. */
static void test_page_rotation(void **state)
{
    (void)state;
    for (int k = 0; k < 13; k++) {
        output_status(&app, &hal);
    }
    assert_int_equal(hal.tx_n, 26u);
    for (uint32_t i = 0u; i < hal.tx_n; i++) {
        const hal_can_frame_t *f = &hal.tx[i];
        assert_int_equal(f->id, NAVECU_CAN_NAV_STATUS_FRAME_ID);
        assert_true(e2e_crc_ok(f->id, f->data));
        struct navecu_can_nav_status_t st;
        memset(&st, 0, sizeof st);
        navecu_can_nav_status_unpack(&st, f->data, 8u);
        assert_int_equal(st.nav_counter, i % 15u);
        const uint8_t want = i % 2u == 0u ? 0u : (uint8_t)((i / 2u) % 6u + 1u);
        assert_int_equal(page_of(f), want);
    }
}

/* the counter page p of the next rotation */
static struct navecu_can_nav_status_t counter_page(uint8_t p)
{
    struct navecu_can_nav_status_t st;
    memset(&st, 0, sizeof st);
    for (int k = 0; k < 6; k++) {
        hal.tx_n = 0u;
        output_status(&app, &hal);
        if (page_of(&hal.tx[1]) == p) {
            navecu_can_nav_status_unpack(&st, hal.tx[1].data, 8u);
            return st;
        }
    }
    fail_msg("page %u not sent", p);
    return st;
}

/* Counters on their pages, saturating at the signal's width (16 or 8 bits); the foreign
 * frames wrap (a rate of other nodes' traffic, not a fault). */
static void test_counter_pages(void **state)
{
    (void)state;
    app_health_t *h = &app.keep.health;
    h->foreign = 70000u;
    h->bad_dlc = 7u;
    h->bad_crc = 300u;
    h->bad_counter = 65535u;
    h->imu_pair_broken = 2u;
    h->imu_lost = 255u;
    h->bad_value = 3u;
    h->gnss_rejected = 4u;
    hal.rx_lost = 9u; /* the HAL's lost frames (hal_can_rx_lost) are CntRxLost */
    h->cmd_rejected = 5u;
    h->nav_rejected = 6u;
    h->time_jumps = 256u;
    h->filter_resets = 8u;
    h->tasks_late = 9u;
    h->nonfinite_out = 10u;
    h->imu_saturated = 11u;
    h->odo_rejected = 12u;
    h->imu_stuck = 13u;
    struct navecu_can_nav_status_t st = counter_page(1u);
    assert_int_equal(st.cnt_foreign, 70000u - 65536u); /* foreign traffic wraps */
    assert_int_equal(st.cnt_bad_dlc, 7u);
    assert_int_equal(st.cnt_bad_crc, 255u);
    st = counter_page(2u);
    assert_int_equal(st.cnt_bad_counter, 65535u);
    assert_int_equal(st.cnt_imu_pair_broken, 2u);
    assert_int_equal(st.cnt_imu_lost, 255u);
    st = counter_page(3u);
    assert_int_equal(st.cnt_bad_value, 3u);
    assert_int_equal(st.cnt_gnss_rejected, 4u);
    assert_int_equal(st.cnt_rx_lost, 9u);
    st = counter_page(4u);
    assert_int_equal(st.cnt_cmd_rejected, 5u);
    assert_int_equal(st.cnt_core_rejected, 6u);
    assert_int_equal(st.cnt_time_jumps, 255u);
    st = counter_page(5u);
    assert_int_equal(st.cnt_filter_resets, 8u);
    assert_int_equal(st.cnt_tasks_late, 9u);
    assert_int_equal(st.cnt_non_finite, 10u);
    st = counter_page(6u);
    assert_int_equal(st.cnt_imu_saturated, 11u);
    assert_int_equal(st.cnt_odo_rejected, 12u);
    assert_int_equal(st.cnt_imu_stuck, 13u);
}

/* ---- the output mode ---- */

static uint8_t mode_now(void)
{
    output_status(&app, &hal);
    return cf_last_status_page0(&hal).mode;
}

static void test_output_mode(void **state)
{
    (void)state;
    assert_int_equal(mode_now(), NAVECU_CAN_NAV_STATUS_MODE_WAIT_INIT_CHOICE);
    app.run.mode = APP_MODE_LEVELLING;
    assert_int_equal(mode_now(), NAVECU_CAN_NAV_STATUS_MODE_LEVELLING_CHOICE);
    app.run.mode = APP_MODE_FAULT;
    assert_int_equal(mode_now(), NAVECU_CAN_NAV_STATUS_MODE_FAULT_CHOICE);
    app.run.mode = APP_MODE_NAVIGATING;
    assert_int_equal(mode_now(), NAVECU_CAN_NAV_STATUS_MODE_INERTIAL_CHOICE);
    app.run.land.output_dr = 1u;
    assert_int_equal(mode_now(), NAVECU_CAN_NAV_STATUS_MODE_DEAD_RECKONING_CHOICE);
    /* the filter: GnssIns while its last fix is at most 2 s (200 samples) old */
    filter_on(1.0f, 1.0f);
    app_stamp(&app.run.fusion.fix, 1000u);
    app.keep.n_samples = 1200u;
    assert_int_equal(mode_now(), NAVECU_CAN_NAV_STATUS_MODE_GNSS_INS_CHOICE);
    app.keep.n_samples = 1201u;
    assert_int_equal(mode_now(), NAVECU_CAN_NAV_STATUS_MODE_INERTIAL_CHOICE);
    app.keep.odo.valid = 1u; /* with the filter the odometer, not landnav, says DR */
    assert_int_equal(mode_now(), NAVECU_CAN_NAV_STATUS_MODE_DEAD_RECKONING_CHOICE);
}

/* ---- accuracies ---- */

/* HorizAccuracy (0.01 m, 65535 unknown): unknown without the filter; sqrt(1.5^2 + 1.5^2)
 * = 2.1213 m -> 212; 707 m saturates at 65534. VertAccuracy (0.1 m, 255 unknown): 2.34 m
 * -> 23; 30 m -> 254. */
static void test_accuracy_saturates_below_unknown(void **state)
{
    (void)state;
    navigate(0.0);
    emit_now();
    struct navecu_can_nav_height_t h;
    navecu_can_nav_height_unpack(&h, cf_last_tx(&hal, NAVECU_CAN_NAV_HEIGHT_FRAME_ID)->data, 8u);
    assert_int_equal(h.vert_accuracy, 255u);
    assert_int_equal(cf_last_status_page0(&hal).horiz_accuracy, 65535u);
    filter_on(1.5f, 2.34f);
    emit_now();
    navecu_can_nav_height_unpack(&h, cf_last_tx(&hal, NAVECU_CAN_NAV_HEIGHT_FRAME_ID)->data, 8u);
    assert_int_equal(h.vert_accuracy, 23u);
    assert_int_equal(cf_last_status_page0(&hal).horiz_accuracy, 212u);
    filter_on(500.0f, 30.0f);
    emit_now();
    navecu_can_nav_height_unpack(&h, cf_last_tx(&hal, NAVECU_CAN_NAV_HEIGHT_FRAME_ID)->data, 8u);
    assert_int_equal(h.vert_accuracy, 254u);
    assert_int_equal(cf_last_status_page0(&hal).horiz_accuracy, 65534u);
}

/* ---- the navigation frames ---- */

static uint16_t heading_raw(void)
{
    struct navecu_can_nav_attitude_t at;
    navecu_can_nav_attitude_unpack(&at, cf_last_tx(&hal, NAVECU_CAN_NAV_ATTITUDE_FRAME_ID)->data,
                                   8u);
    return at.heading;
}

/* 359.996 deg rounds to 360.00, beyond the signal's 359.99: sent as 0 (north); 359.994 is
 * 35999; a heading less the calibration's dH below 0 wraps: 2.8648 - 5.7296 deg = 357.135. */
static void test_heading_wrap(void **state)
{
    (void)state;
    navigate(359.996);
    emit_now();
    assert_int_equal(heading_raw(), 0u);
    navigate(359.994);
    emit_now();
    assert_int_equal(heading_raw(), 35999u);
    navigate(0.05 / DEG);
    app.run.dr.dh_rad = 0.1f;
    emit_now();
    assert_int_equal(heading_raw(), 35714u); /* 357.1352 deg */
}

/* NAV_Position rounds the fixed point half away from zero to 1e-7 deg; NAV_Height is in
 * cm with TimeOfValidity = IMU time in ms modulo 2^16; velocity clamps at the signal. */
static void test_position_height_velocity(void **state)
{
    (void)state;
    navigate(0.0);
    app.run.nav.pos.lat = 450000000LL * GEO_LSB_PER_DEG_E7 + GEO_LSB_PER_DEG_E7 / 2;
    app.run.nav.pos.lon = -(100LL * GEO_LSB_PER_DEG_E7 + GEO_LSB_PER_DEG_E7 / 2);
    app.run.nav.pos.h = 1234567LL * GEO_LSB_PER_MM; /* 1234.567 m */
    app.run.nav.v_n_mps[0] = 400.0f;
    app.run.nav.v_n_mps[1] = -1.234f;
    app.keep.n_samples = 65600u; /* 656 000 ms */
    output_due(&app, &hal);
    struct navecu_can_nav_position_t p;
    navecu_can_nav_position_unpack(&p, cf_last_tx(&hal, NAVECU_CAN_NAV_POSITION_FRAME_ID)->data, 8u);
    assert_int_equal(p.latitude, 450000001);
    assert_int_equal(p.longitude, -101);
    struct navecu_can_nav_height_t h;
    navecu_can_nav_height_unpack(&h, cf_last_tx(&hal, NAVECU_CAN_NAV_HEIGHT_FRAME_ID)->data, 8u);
    assert_int_equal(h.height, 123457); /* 1234.567 m -> 123456.7 cm -> 123457 */
    assert_int_equal(h.time_of_validity, 656000u % 65536u);
    struct navecu_can_nav_velocity_t v;
    navecu_can_nav_velocity_unpack(&v, cf_last_tx(&hal, NAVECU_CAN_NAV_VELOCITY_FRAME_ID)->data, 8u);
    assert_int_equal(v.vel_east, 32767);
    assert_int_equal(v.vel_north, -123);
}

/* Over 100 samples (1 s at 100 Hz) navigating: 50 of each navigation frame and of
 * NAV_Time, 10 NAV_Status pairs and NAV_Accuracy, 1 NAV_Calibration, and one more status
 * pair and NAV_Accuracy at the first sample for the change of Mode (WaitInit to
 * navigating); no dynamics frame, as no IMU sample came (dynamics_take has nothing to
 * average); not navigating: only status (again one more pair for the change), accuracy
 * and calibration. */
static void test_output_rates(void **state)
{
    (void)state;
    navigate(10.0);
    for (uint64_t n = 1u; n <= 100u; n++) {
        app.keep.n_samples = n;
        output_due(&app, &hal);
    }
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_POSITION_FRAME_ID), 50u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_HEIGHT_FRAME_ID), 50u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_VELOCITY_FRAME_ID), 50u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_ATTITUDE_FRAME_ID), 50u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_STATUS_FRAME_ID), 22u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_CALIBRATION_FRAME_ID), 1u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_TIME_FRAME_ID), 50u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_ACCURACY_FRAME_ID), 11u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_RATES_FRAME_ID), 0u);
    assert_int_equal(app.keep.tx.frames_sent, 284u);
    hal.tx_n = 0u;
    app.run.mode = APP_MODE_LEVELLING;
    for (uint64_t n = 101u; n <= 200u; n++) {
        app.keep.n_samples = n;
        output_due(&app, &hal);
    }
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_POSITION_FRAME_ID), 0u);
    assert_int_equal(hal.tx_n, 34u);
}

/* the Mode of NAV_Status page 0 frame k of the transmit log, or -1 if k is another frame */
static int status_mode_at(uint32_t k)
{
    const hal_can_frame_t *f = &hal.tx[k];
    struct navecu_can_nav_status_t st;
    if (f->id != NAVECU_CAN_NAV_STATUS_FRAME_ID) {
        return -1;
    }
    navecu_can_nav_status_unpack(&st, f->data, 8u);
    return st.status_page == NAVECU_NAV_STATUS_PAGE_STATE ? (int)st.mode : -1;
}

/*
 * GIVEN the application going from WaitInit to navigating at a sample between two
 *       NAV_Status cycles, and later out of navigation (a reset)
 * WHEN the outputs of those samples go out
 * THEN a receiver reading the frames in order never has a NAV_Position after a status
 *      that says WaitInit (issue #17: the first 100 ms of every start did), and learns of
 *      the end of navigation at once, not at the next cycle.
 */
static void test_status_on_mode_change(void **state)
{
    (void)state;
    hal.tx_n = 0u;
    app.keep.n_samples = 10u; /* a status cycle in WaitInit */
    output_due(&app, &hal);
    assert_int_equal(status_mode_at(0u), NAVECU_CAN_NAV_STATUS_MODE_WAIT_INIT_CHOICE);
    navigate(10.0);
    int last_mode = -1;
    for (uint64_t n = 12u; n <= 30u; n += 2u) { /* navigation sets at even samples */
        app.keep.n_samples = n;
        output_due(&app, &hal);
    }
    app.run.mode = APP_MODE_WAIT_INIT;
    app.keep.n_samples = 33u; /* between cycles */
    const uint32_t before_reset = hal.tx_n;
    output_due(&app, &hal);
    uint32_t positions = 0u;
    for (uint32_t k = 0u; k < hal.tx_n; k++) {
        const int m = status_mode_at(k);
        if (m >= 0) {
            last_mode = m;
        }
        if (hal.tx[k].id == NAVECU_CAN_NAV_POSITION_FRAME_ID) {
            positions++;
            assert_true(last_mode == NAVECU_CAN_NAV_STATUS_MODE_INERTIAL_CHOICE ||
                        last_mode == NAVECU_CAN_NAV_STATUS_MODE_DEAD_RECKONING_CHOICE);
        }
    }
    assert_int_equal(positions, 10u);
    /* the reset's sample: its status says WaitInit although no cycle is due */
    assert_int_equal(status_mode_at(before_reset), NAVECU_CAN_NAV_STATUS_MODE_WAIT_INIT_CHOICE);
    assert_int_equal(last_mode, NAVECU_CAN_NAV_STATUS_MODE_WAIT_INIT_CHOICE);
}

/* A navigator that is not finite is never on the bus: counted instead. */
static void test_nonfinite_not_sent(void **state)
{
    (void)state;
    navigate(0.0);
    app.run.nav.v_n_mps[1] = NAN;
    emit_now();
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_POSITION_FRAME_ID), 0u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_ATTITUDE_FRAME_ID), 0u);
    assert_int_equal(app.keep.health.nonfinite_out, 1u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_STATUS_FRAME_ID), 2u);
}

/* NAV_Calibration: dH in 0.001 deg, mu in 1e-5, the flags and the calibration's source. */
static void test_calibration_frame(void **state)
{
    (void)state;
    app.keep.cal.dh_rad = (nav_real_t)(0.5 * DEG);
    app.keep.cal.mu = -0.0125f;
    app.keep.cal.source = NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_FILTER_CHOICE;
    app.keep.cal.status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_FROM_NVM_CHOICE;
    app.keep.cal.stored = 1u;
    app.keep.cal.count = 3u;
    emit_now();
    const hal_can_frame_t *f = cf_last_tx(&hal, NAVECU_CAN_NAV_CALIBRATION_FRAME_ID);
    assert_non_null(f);
    assert_true(e2e_crc_ok(f->id, f->data));
    struct navecu_can_nav_calibration_t m;
    navecu_can_nav_calibration_unpack(&m, f->data, 8u);
    assert_int_equal(m.heading_correction, 500);
    assert_int_equal(m.odo_scale_error, -1250);
    assert_int_equal(m.cal_valid, 1u);
    assert_int_equal(m.cal_stored, 1u);
    assert_int_equal(m.cal_status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_FROM_NVM_CHOICE);
    assert_int_equal(m.cal_source, NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_FILTER_CHOICE);
    assert_int_equal(m.cal_count, 3u);
    app.keep.cal.source = NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_NONE_CHOICE;
    emit_now();
    navecu_can_nav_calibration_unpack(&m, cf_last_tx(&hal, NAVECU_CAN_NAV_CALIBRATION_FRAME_ID)->data,
                                      8u);
    assert_int_equal(m.cal_valid, 0u);
}

/* A full transmit queue: the frame is counted as a send error, not as sent. */
static void test_send_error_counted(void **state)
{
    (void)state;
    hal.tx_n = FAKE_TX_MAX;
    output_status(&app, &hal);
    assert_int_equal(app.keep.tx.send_errors, 2u);
    assert_int_equal(app.keep.tx.frames_sent, 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_flags_at_power_on, setup),
        cmocka_unit_test_setup(test_flags_held_for_their_time, setup),
        cmocka_unit_test_setup(test_flag_no_gnss, setup),
        cmocka_unit_test_setup(test_no_gnss_survives_reset, setup),
        cmocka_unit_test_setup(test_flag_imu_stale, setup),
        cmocka_unit_test_setup(test_state_flags, setup),
        cmocka_unit_test_setup(test_board_fault_flags, setup),
        cmocka_unit_test_setup(test_board_faults_tested_without_imu, setup),
        cmocka_unit_test_setup(test_waits_untested_while_parked_before_navigation, setup),
        cmocka_unit_test_setup(test_imu_rate_mismatch_flag, setup),
        cmocka_unit_test_setup(test_page_rotation, setup),
        cmocka_unit_test_setup(test_counter_pages, setup),
        cmocka_unit_test_setup(test_output_mode, setup),
        cmocka_unit_test_setup(test_accuracy_saturates_below_unknown, setup),
        cmocka_unit_test_setup(test_heading_wrap, setup),
        cmocka_unit_test_setup(test_position_height_velocity, setup),
        cmocka_unit_test_setup(test_output_rates, setup),
        cmocka_unit_test_setup(test_status_on_mode_change, setup),
        cmocka_unit_test_setup(test_nonfinite_not_sent, setup),
        cmocka_unit_test_setup(test_calibration_frame, setup),
        cmocka_unit_test_setup(test_send_error_counted, setup),
    };
    return cmocka_run_group_tests_name("output", tests, NULL, NULL);
}
