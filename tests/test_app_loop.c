/*
 * test_app_loop.c - app_loop.h: one pass of the main loop against the in-memory HAL's
 * receive queue (whose clock follows the frames): at most max_frames frames, app_poll
 * after each, once more on a silent bus, the watchdog kicked only when app_tasks_ok, and
 * no watchdog decision at the end of a finite input or on a receive error.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app_loop.h"
#include "can_frames.h"
#include "app_fixture.h"
#include "e2e.h"
#include "fake_hal.h"

static hal_t hal;
static app_t app;

static int setup(void **state)
{
    (void)state;
    assert_int_equal(fx_fresh_app(&app, &hal), NAV_OK);
    return 0;
}

/* n frames of a foreign identifier (counted foreign, nothing sent), byte 0 = index,
 * the k-th received at t0 + k * dt */
static void queue_foreign(uint32_t n, uint64_t t0_us, uint64_t dt_us)
{
    for (uint32_t k = 0u; k < n; k++) {
        const uint8_t d[8] = {(uint8_t)k, 0, 0, 0, 0, 0, 0, 0};
        const hal_can_frame_t f = cf_frame(0x555u, d, t0_us + k * dt_us);
        assert_int_equal(fake_hal_rx_push(&hal, &f), 0);
    }
}

static app_pass_t pass(uint32_t max_frames, uint8_t poll)
{
    const app_pass_cfg_t cfg = {max_frames, poll};
    return app_pass(&app, &hal, &cfg);
}

/* GIVEN 10 frames waiting WHEN passes of at most 4 run THEN 4, 4 and 2 are handled, each
 * pass kicks the watchdog (a flooded bus cannot starve it), and the last pass ends on an
 * empty queue (HAL_EAGAIN: go on). */
static void test_at_most_max_frames(void **state)
{
    (void)state;
    hal.rx_empty_rc = HAL_EAGAIN;
    queue_foreign(10u, 1000u, 1000u);
    app_pass_t p = pass(4u, 1u);
    assert_int_equal(p.frames, 4u);
    assert_int_equal(p.rx_status, 0);
    assert_int_equal(p.last.data[0], 3);
    assert_int_equal(fake_hal_rx_left(&hal), 6u);
    assert_int_equal(app_health(&app)->foreign, 4u);
    assert_int_equal(p.kicked, 1);
    assert_int_equal(hal.kicks, 1u);
    p = pass(4u, 1u);
    assert_int_equal(p.frames, 4u);
    assert_int_equal(p.last.data[0], 7);
    p = pass(4u, 1u);
    assert_int_equal(p.frames, 2u);
    assert_int_equal(p.rx_status, HAL_EAGAIN);
    assert_int_equal(app_pass_go_on(&p), 1);
    assert_int_equal(p.last.data[0], 9);
    assert_int_equal(app_health(&app)->foreign, 10u);
    assert_int_equal(hal.kicks, 3u);
}

/* GIVEN an IMU silent since t = 0 (NAV_Status due from app_poll every 100 ms) WHEN three
 * frames arrive 100 ms apart from 1 s THEN app_poll ran after each: three NAV_Status pairs
 * (6 frames; one poll per pass would give 2); with poll withheld none. */
static void test_poll_after_each_frame(void **state)
{
    (void)state;
    app.keep.imu.have_sample = 1u;
    app.keep.imu.last_t_us = 0u;
    queue_foreign(3u, 1000000u, 100000u);
    app_pass_t p = pass(10u, 1u);
    assert_int_equal(p.frames, 3u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_STATUS_FRAME_ID), 6u);
    assert_int_equal(app.keep.last_poll_us, 1200000u);

    setup(NULL);
    app.keep.imu.have_sample = 1u;
    queue_foreign(3u, 1000000u, 100000u);
    p = pass(10u, 0u);
    assert_int_equal(p.frames, 3u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_STATUS_FRAME_ID), 0u);
    assert_int_equal(app.keep.have_poll, 0);
}

/* The NAV_Heartbeat frames sent so far, decoded, each E2E-checked (CRC; the counter one
 * up from the previous one's), with their HAL send times; returns how many. */
static uint32_t heartbeats(struct navecu_can_nav_heartbeat_t *hb, uint64_t *t_us, uint32_t max)
{
    uint32_t n = 0u;
    for (uint32_t i = 0u; i < hal.tx_n && n < max; i++) {
        const hal_can_frame_t *f = &hal.tx[i];
        if (f->id != NAVECU_CAN_NAV_HEARTBEAT_FRAME_ID) {
            continue;
        }
        assert_int_equal(f->dlc, 8u);
        assert_true(e2e_crc_ok(f->id, f->data));
        assert_int_equal(navecu_can_nav_heartbeat_unpack(&hb[n], f->data, 8u), 0);
        if (n > 0u) {
            assert_int_equal(hb[n].nav_counter, e2e_counter_next(hb[n - 1u].nav_counter));
        }
        t_us[n] = f->t_us;
        n++;
    }
    return n;
}

/* Powered on with no input at all (issue #17: nothing at all was sent, so a live ECU
 * without sensors looked dead). GIVEN a fresh ECU on a silent bus WHEN the main loop
 * passes every 10 ms for 3 s of HAL time THEN NAV_Heartbeat goes out at 1 Hz from the
 * first pass (10 ms, 1.01 s, 2.01 s: uptime 0, 1, 2 s), counter 0, 1, 2, saying no IMU,
 * no GNSS, no wheels, Mode WaitInit, and no other frame is sent (the data-driven outputs
 * wait for data). THEN WHEN IMU samples come at 100 Hz for 1.1 s more, the heartbeat's "no
 * IMU" clears (at 4.01 s; GNSS and wheels still missing), at the same 1 Hz. */
static void test_heartbeat_from_boot(void **state)
{
    (void)state;
    hal.rx_empty_rc = HAL_EAGAIN;
    for (uint64_t k = 1u; k <= 300u; k++) {
        hal.t_us = k * 10000u;
        (void)pass(10u, 1u);
    }
    struct navecu_can_nav_heartbeat_t hb[8];
    uint64_t t[8];
    assert_int_equal(heartbeats(hb, t, 8u), 3u);
    assert_int_equal(hal.tx_n, 3u); /* nothing but the heartbeat */
    for (uint32_t i = 0u; i < 3u; i++) {
        assert_int_equal(t[i], 10000u + i * 1000000u);
        assert_int_equal(hb[i].uptime, i);
        assert_int_equal(hb[i].nav_counter, i);
        assert_int_equal(hb[i].mode, NAVECU_CAN_NAV_HEARTBEAT_MODE_WAIT_INIT_CHOICE);
        assert_int_equal(hb[i].imu_missing, 1u);
        assert_int_equal(hb[i].gnss_missing, 1u);
        assert_int_equal(hb[i].wheels_missing, 1u);
    }

    uint8_t counter = 0u;
    for (uint64_t k = 301u; k <= 410u; k++) {
        const int32_t w[3] = {0, 0, 0};
        const int32_t v[3] = {0, 0, 402}; /* standing: g x 10 ms in 2^-12 m/s */
        hal_can_frame_t fr, fa;
        cf_imu_pair(w, v, counter, 0u, k * 10000u, &fr, &fa);
        counter = e2e_counter_next(counter);
        hal.rx_head = hal.rx_n = 0u; /* the queue is drained each pass: reuse it */
        assert_int_equal(fake_hal_rx_push(&hal, &fr), 0);
        assert_int_equal(fake_hal_rx_push(&hal, &fa), 0);
        (void)pass(10u, 1u);
    }
    assert_int_equal(app_samples(&app), 110u);
    assert_int_equal(heartbeats(hb, t, 8u), 5u);
    /* 3.01 s: sent at the poll after the first IMU_Rate, before its sample was complete */
    assert_int_equal(t[3], 3010000u);
    assert_int_equal(hb[3].uptime, 3u);
    assert_int_equal(t[4], 4010000u);
    assert_int_equal(hb[4].uptime, 4u);
    assert_int_equal(hb[4].imu_missing, 0u);
    assert_int_equal(hb[4].gnss_missing, 1u);
    assert_int_equal(hb[4].wheels_missing, 1u);
    assert_int_equal(hb[4].mode, NAVECU_CAN_NAV_HEARTBEAT_MODE_WAIT_INIT_CHOICE);
}

/* The wheel speeds stop before navigation (docs/can.md: WheelsMissing is the odometer's
 * timeout, 1.5 s of IMU time, in every mode). GIVEN an ECU waiting for GNSS (WaitInit),
 * IMU samples at 100 Hz for 4 s and WheelSpeeds at 50 Hz (standing) for the first second
 * only WHEN the heartbeat goes out at 1.01, 2.01, 3.01 and 4.01 s THEN it says wheels
 * present while the last reading is younger than 1.5 s (1.01 and 2.01 s: 0.01 and 1.01 s
 * old) and missing after (3.01, 4.01 s). (Until 2026-12-06 the odometer aged only while
 * navigating, and a wheel speed once read stayed valid for good before it.) */
static void test_wheels_missing_before_navigation(void **state)
{
    (void)state;
    hal.rx_empty_rc = HAL_EAGAIN;
    uint8_t counter = 0u;
    uint8_t wheel_counter = 0u;
    for (uint64_t k = 1u; k <= 401u; k++) {
        const int32_t w[3] = {0, 0, 0};
        const int32_t v[3] = {0, 0, 402};
        hal_can_frame_t fr, fa;
        cf_imu_pair(w, v, counter, 0u, k * 10000u, &fr, &fa);
        counter = e2e_counter_next(counter);
        hal.rx_head = hal.rx_n = 0u;
        assert_int_equal(fake_hal_rx_push(&hal, &fr), 0);
        assert_int_equal(fake_hal_rx_push(&hal, &fa), 0);
        if (k <= 100u && k % 2u == 0u) {
            const int16_t still[4] = {0, 0, 0, 0};
            const hal_can_frame_t fw = cf_wheels(still, wheel_counter, k * 10000u);
            wheel_counter = e2e_counter_next(wheel_counter);
            assert_int_equal(fake_hal_rx_push(&hal, &fw), 0);
        }
        (void)pass(10u, 1u);
    }
    assert_int_equal(app_samples(&app), 401u);
    struct navecu_can_nav_heartbeat_t hb[8];
    uint64_t t[8];
    assert_int_equal(heartbeats(hb, t, 8u), 5u);
    const uint8_t missing[5] = {1u, 0u, 0u, 1u, 1u}; /* at 0.01 s none read yet */
    for (uint32_t i = 0u; i < 5u; i++) {
        assert_int_equal(t[i], 10000u + i * 1000000u);
        assert_int_equal(hb[i].mode, NAVECU_CAN_NAV_HEARTBEAT_MODE_WAIT_INIT_CHOICE);
        assert_int_equal(hb[i].wheels_missing, missing[i]);
    }
}

/* A silent bus (HAL_EAGAIN at once): app_poll once, then the kick. */
static void test_silent_bus_polls_once(void **state)
{
    (void)state;
    hal.rx_empty_rc = HAL_EAGAIN;
    hal.t_us = 5000000u;
    app.keep.imu.have_sample = 1u;
    const app_pass_t p = pass(10u, 1u);
    assert_int_equal(p.frames, 0u);
    assert_int_equal(p.rx_status, HAL_EAGAIN);
    assert_int_equal(app.keep.have_poll, 1);
    assert_int_equal(app.keep.last_poll_us, 5000000u);
    assert_int_equal(cf_tx_count(&hal, NAVECU_CAN_NAV_STATUS_FRAME_ID), 2u); /* the heartbeat */
    assert_int_equal(p.kicked, 1);
    assert_int_equal(hal.kicks, 1u);
}

/* The kick follows app_tasks_ok: never polled (poll withheld) -> no kick, counted late;
 * polled at 0 then 300 ms without a poll (3 status periods) -> kick, 1 us more -> none. */
static void test_kick_only_when_tasks_ok(void **state)
{
    (void)state;
    hal.rx_empty_rc = HAL_EAGAIN;
    app_pass_t p = pass(10u, 0u);
    assert_int_equal(p.kicked, 0);
    assert_int_equal(hal.kicks, 0u);
    assert_int_equal(app_health(&app)->tasks_late, 1u);
    p = pass(10u, 1u);
    assert_int_equal(p.kicked, 1);
    hal.t_us = 300000u;
    p = pass(10u, 0u);
    assert_int_equal(p.kicked, 1);
    hal.t_us = 300001u;
    p = pass(10u, 0u);
    assert_int_equal(p.kicked, 0);
    assert_int_equal(hal.kicks, 2u);
    assert_int_equal(app_health(&app)->tasks_late, 2u);
}

/* GIVEN the filter running WHEN 31 samples (3 prediction periods of 10, and one) went by
 * without its prediction THEN no kick; 30 is still in time. */
static void test_no_kick_when_prediction_late(void **state)
{
    (void)state;
    hal.rx_empty_rc = HAL_EAGAIN;
    app.run.mode = APP_MODE_NAVIGATING;
    app.run.fusion.on = 1u;
    app.run.fusion.pred_n = 30u;
    assert_int_equal(pass(10u, 1u).kicked, 1);
    app.run.fusion.pred_n = 31u;
    assert_int_equal(pass(10u, 1u).kicked, 0);
    app.run.fusion.on = 0u; /* the land navigation system has no prediction to wait for */
    assert_int_equal(pass(10u, 1u).kicked, 1);
}

/* At the end of a finite input (HAL_ENODATA) or on a receive error the pass returns at
 * once: no kick, no extra poll; the frames before it were handled and polled. */
static void test_end_of_input_no_kick(void **state)
{
    (void)state;
    app_pass_t p = pass(10u, 1u); /* the queue is empty: HAL_ENODATA */
    assert_int_equal(p.rx_status, HAL_ENODATA);
    assert_int_equal(app_pass_go_on(&p), 0);
    assert_int_equal(p.kicked, 0);
    assert_int_equal(hal.kicks, 0u);
    assert_int_equal(app.keep.have_poll, 0);
    assert_int_equal(app_health(&app)->tasks_late, 0u); /* no watchdog decision at all */
    queue_foreign(2u, 1000u, 1000u);
    p = pass(10u, 1u);
    assert_int_equal(p.frames, 2u);
    assert_int_equal(p.rx_status, HAL_ENODATA);
    assert_int_equal(p.kicked, 0);
    assert_int_equal(app.keep.have_poll, 1);
    hal.rx_empty_rc = HAL_EIO;
    p = pass(10u, 1u);
    assert_int_equal(p.rx_status, HAL_EIO);
    assert_int_equal(app_pass_go_on(&p), 0);
    assert_int_equal(p.kicked, 0);
    assert_int_equal(hal.kicks, 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_at_most_max_frames, setup),
        cmocka_unit_test_setup(test_poll_after_each_frame, setup),
        cmocka_unit_test_setup(test_silent_bus_polls_once, setup),
        cmocka_unit_test_setup(test_kick_only_when_tasks_ok, setup),
        cmocka_unit_test_setup(test_no_kick_when_prediction_late, setup),
        cmocka_unit_test_setup(test_end_of_input_no_kick, setup),
        cmocka_unit_test_setup(test_heartbeat_from_boot, setup),
        cmocka_unit_test_setup(test_wheels_missing_before_navigation, setup),
    };
    return cmocka_run_group_tests_name("app_loop", tests, NULL, NULL);
}
