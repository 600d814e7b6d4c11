/*
 * test_vehicle_split.c - wheel speeds split over two messages, through the application's
 * receive path: the 2017 Nissan X-Trail's generated vehicle layer (vehicles/
 * nissan_x_trail_2017.toml, build/vehicle/nissan_x_trail_2017/: WHEEL_SPEEDS_FRONT 0x29A,
 * WHEEL_SPEEDS_REAR 0x285, 0.005 km/h big-endian, GEARBOX 0x41F) under app_rx_decode.
 *
 * GIVEN the car's frames built here byte by byte from the DBC's layout (each 16-bit speed
 * big-endian: FR then FL in the front message, RR then RL in the rear's; the gear in bits
 * 5..3 of byte 0)
 * THEN the first half of a pair is read and held (RX_OK, nothing to act on, counted as a
 * wheel-speed frame read), the second gives one RX_WHEELS of the four wheels in FL, FR,
 * RL, RR order in m/s, signed by the gear; a repeated half replaces the held one; a
 * refused half (its DLC) is not held; app_init forgets a held half with the receive state.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app.h"
#include "app_config.h"
#include "app_rx.h"
#include "vehicle.h"
#include "app_fixture.h"
#include "can_frames.h"
#include "dr.h"
#include "e2e.h"
#include "fake_hal.h"
#include "sins.h"

static rx_state_t rx;
static rx_input_t in;
static uint32_t ids[NAVECU_MSG_N];

static int setup(void **state)
{
    (void)state;
    memset(&rx, 0, sizeof rx);
    memset(&in, 0, sizeof in);
    for (int i = 0; i < (int)NAVECU_MSG_N; i++) {
        ids[i] = vehicle_profile.can_ids[i];
    }
    vehicle_reset(); /* as app_init: the generated layer's state with the receive state */
    return 0;
}

/* an axle's frame: raw speeds (0.005 km/h) of its right and left wheel, in that order */
static hal_can_frame_t axle(uint32_t id, uint16_t right, uint16_t left, uint8_t dlc)
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = dlc;
    f.data[0] = (uint8_t)(right >> 8);
    f.data[1] = (uint8_t)(right & 0xFFu);
    f.data[2] = (uint8_t)(left >> 8);
    f.data[3] = (uint8_t)(left & 0xFFu);
    return f;
}

static hal_can_frame_t front(uint16_t fl, uint16_t fr)
{
    return axle(0x29Au, fr, fl, 8u);
}

static hal_can_frame_t rear(uint16_t rl, uint16_t rr)
{
    return axle(0x285u, rr, rl, 8u);
}

static hal_can_frame_t gear(uint8_t value) /* the DBC's VAL_: 6 L, 4 D, 3 N, 2 R, 1 P */
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = 0x41Fu;
    f.dlc = 2u;
    f.data[0] = (uint8_t)(value << 3);
    return f;
}

static rx_verdict_t decode(hal_can_frame_t f)
{
    in.kind = RX_WHEELS; /* app_rx_decode must say what it is */
    return app_rx_decode(&rx, ids, &f, &in);
}

/* raw 0.005 km/h in m/s, as the generated decode computes it (float32) */
static nav_real_t mps(uint16_t raw)
{
    return ((nav_real_t)raw * NAV_C(0.005) + NAV_C(0.0)) * NAV_C(0.2777777777777778);
}

static void assert_sample(nav_real_t sign, uint16_t fl, uint16_t fr, uint16_t rl, uint16_t rr)
{
    assert_int_equal(in.kind, RX_WHEELS);
    const nav_real_t expect[4] = {sign * mps(fl), sign * mps(fr), sign * mps(rl), sign * mps(rr)};
    assert_memory_equal(in.u.wheels.mps, expect, sizeof expect);
}

static void assert_held(rx_verdict_t v)
{
    assert_int_equal(v, RX_OK);
    assert_int_equal(in.kind, RX_NONE);
}

/* one sample per pair, on its second half, the wheels in their places whichever axle came
 * first; every half counted as a wheel-speed frame read */
static void test_one_sample_per_pair(void **state)
{
    (void)state;
    assert_held(decode(front(2000u, 2010u)));
    assert_int_equal(decode(rear(2020u, 2030u)), RX_OK);
    assert_sample(NAV_C(1.0), 2000u, 2010u, 2020u, 2030u);
    assert_held(decode(rear(3020u, 3030u)));
    assert_int_equal(decode(front(3000u, 3010u)), RX_OK);
    assert_sample(NAV_C(1.0), 3000u, 3010u, 3020u, 3030u);
    assert_int_equal(rx.car_read[VEHICLE_MSG_WHEELS], 4u);
    /* 7,200 raw: 36 km/h, 10 m/s */
    assert_held(decode(front(7200u, 7200u)));
    assert_int_equal(decode(rear(7200u, 7200u)), RX_OK);
    for (int i = 0; i < 4; i++) {
        assert_float_equal(in.u.wheels.mps[i], 10.0, 1e-5);
    }
}

/* reverse gear: the sample's speeds are negative; park: forward again (a car at rest) */
static void test_the_gear_signs_the_sample(void **state)
{
    (void)state;
    assert_int_equal(decode(gear(2u)), RX_OK); /* R */
    assert_held(decode(front(100u, 110u)));
    assert_int_equal(decode(rear(120u, 130u)), RX_OK);
    assert_sample(NAV_C(-1.0), 100u, 110u, 120u, 130u);
    assert_int_equal(decode(gear(1u)), RX_OK); /* P */
    assert_held(decode(rear(0u, 0u)));
    assert_int_equal(decode(front(0u, 0u)), RX_OK);
    assert_sample(NAV_C(1.0), 0u, 0u, 0u, 0u);
    assert_int_equal(decode(gear(5u)), RX_BAD_VALUE); /* a value the DBC does not name */
}

/* a half that comes again before the other axle's replaces the held one: one sample, with
 * the newest of each axle */
static void test_a_repeated_half_replaces(void **state)
{
    (void)state;
    assert_held(decode(front(1000u, 1001u)));
    assert_held(decode(front(1100u, 1101u)));
    assert_int_equal(decode(rear(1200u, 1201u)), RX_OK);
    assert_sample(NAV_C(1.0), 1100u, 1101u, 1200u, 1201u);
    assert_int_equal(rx.car_read[VEHICLE_MSG_WHEELS], 3u); /* read: 3 frames, 1 sample */
}

/* the rear axle's message stopped: the front's keep coming, no sample at all */
static void test_a_stopped_axle_gives_no_sample(void **state)
{
    (void)state;
    for (uint16_t i = 0u; i < 500u; i++) {
        assert_held(decode(front(i, i)));
    }
    assert_int_equal(decode(rear(7u, 8u)), RX_OK);
    assert_sample(NAV_C(1.0), 499u, 499u, 7u, 8u);
}

/* a half refused for its length is not held: the held front stays the one paired, and a
 * refused rear alone leaves nothing held */
static void test_a_refused_half_is_not_held(void **state)
{
    (void)state;
    assert_held(decode(front(400u, 401u)));
    assert_int_equal(decode(axle(0x285u, 9u, 9u, 7u)), RX_BAD_DLC);
    assert_int_equal(decode(axle(0x29Au, 9u, 9u, 6u)), RX_BAD_DLC);
    assert_int_equal(decode(rear(402u, 403u)), RX_OK);
    assert_sample(NAV_C(1.0), 400u, 401u, 402u, 403u);
    assert_int_equal(decode(axle(0x285u, 9u, 9u, 7u)), RX_BAD_DLC);
    assert_held(decode(front(500u, 501u))); /* nothing was held */
}

/* app_init (power-on, ECUReset) forgets a held half with the receive state: the next half
 * is held, not paired with one from before */
static void test_app_init_forgets_the_held_half(void **state)
{
    (void)state;
    static app_t app;
    const app_config_t cfg = app_default_config();
    assert_held(decode(front(600u, 601u)));
    assert_int_equal(app_init(&app, &cfg), NAV_OK);
    hal_can_frame_t f = rear(602u, 603u);
    in.kind = RX_WHEELS;
    assert_int_equal(app_rx_decode(&app.keep.rx, ids, &f, &in), RX_OK);
    assert_int_equal(in.kind, RX_NONE); /* held: the front from before is gone */
    f = front(604u, 605u);
    assert_int_equal(app_rx_decode(&app.keep.rx, ids, &f, &in), RX_OK);
    assert_sample(NAV_C(1.0), 604u, 605u, 602u, 603u);
}

/* a frame to the application */
static void feed(app_t *app, hal_t *hal, hal_can_frame_t f)
{
    app_handle_frame(app, hal, &f);
}

/* navigating on the dead reckoning's path (it ticks the odometer), level at 45 N 10 E, with
 * the gear in D */
static void navigating(app_t *app, hal_t *hal)
{
    assert_int_equal(fx_fresh_app(app, hal), NAV_OK);
    const geo_pos_t p = {450000000LL * GEO_LSB_PER_DEG_E7, 100000000LL * GEO_LSB_PER_DEG_E7,
                         100000LL * GEO_LSB_PER_MM};
    const nav_real_t q[4] = {NAV_C(1.0), NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    const nav_real_t v0[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    const sins_config_t scfg = sins_default_config();
    assert_int_equal(sins_init(&app->run.nav, &scfg, &p, v0, q), NAV_OK);
    assert_int_equal(dr_init(&app->run.dr, &p, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    app->run.mode = APP_MODE_NAVIGATING;
    feed(app, hal, gear(4u)); /* D */
}

/* one IMU sample 10 ms after the last (level, at rest: 1 g up, FRD z down) */
static void imu_sample(app_t *app, hal_t *hal, uint8_t *counter)
{
    const int32_t w[3] = {0, 0, 0};
    const int32_t v[3] = {0, 0, -402}; /* 9.81 m/s^2 x 10 ms in 2^-12 m/s LSB */
    hal_can_frame_t rate, accel;
    hal->t_us += 10000u;
    cf_imu_pair(w, v, *counter, 0u, hal->t_us, &rate, &accel);
    *counter = e2e_counter_next(*counter);
    app_handle_frame(app, hal, &rate);
    app_handle_frame(app, hal, &accel);
}

/* after a silence: the rear half is held (the front from before the silence is gone), and
 * with the next front half it makes one sample */
static void assert_fresh_pairing(app_t *app)
{
    hal_can_frame_t f = rear(3000u, 3000u);
    in.kind = RX_WHEELS;
    assert_int_equal(app_rx_decode(&app->keep.rx, ids, &f, &in), RX_OK);
    assert_int_equal(in.kind, RX_NONE);
    f = front(3002u, 3004u);
    assert_int_equal(app_rx_decode(&app->keep.rx, ids, &f, &in), RX_OK);
    assert_sample(NAV_C(1.0), 3002u, 3004u, 3000u, 3000u);
}

/* The odometer's timeout forgets a held half too: a pair makes the wheel speeds fresh;
 * then a front half arrives alone and both axles go quiet for 1.6 s of IMU time (the
 * timeout 1.5 s, WheelsMissing). The rear half after the silence is held, not paired with
 * the front half from before it: navigating, and before navigation (waiting for GNSS, in
 * mode WaitInit), where the odometer ages as well (until 2026-12-06 it aged only while
 * navigating, and the pair was made). */
static void wheel_timeout_forgets_the_held_half(int navigate)
{
    static app_t app;
    static hal_t hal;
    if (navigate != 0) {
        navigating(&app, &hal);
    } else {
        assert_int_equal(fx_fresh_app(&app, &hal), NAV_OK);
        feed(&app, &hal, gear(4u)); /* D */
    }
    const app_mode_t mode = app.run.mode;
    uint8_t counter = 0u;
    feed(&app, &hal, front(1000u, 1000u));
    feed(&app, &hal, rear(1000u, 1000u));
    for (int k = 0; k < 161; k++) {
        if (k == 1) {
            assert_int_equal(app.keep.odo.valid, 1u); /* the pair's speeds, fresh */
            feed(&app, &hal, front(2000u, 2000u));     /* held: its rear never comes */
        }
        imu_sample(&app, &hal, &counter);
    }
    assert_int_equal(app.run.mode, mode);
    assert_int_equal(app.keep.odo.valid, 0u); /* timed out */
    assert_fresh_pairing(&app);
}

static void test_wheel_timeout_forgets_the_held_half(void **state)
{
    (void)state;
    wheel_timeout_forgets_the_held_half(1);
}

static void test_wheel_timeout_before_navigation_forgets_the_held_half(void **state)
{
    (void)state;
    wheel_timeout_forgets_the_held_half(0);
}

/* A silence of the whole bus stops the IMU too (no odometer timeout then): the IMU gap too
 * long to bridge forgets the held half (a review's case: 2 s of nothing, then the rear half
 * paired with the front from before). */
static void test_bus_silence_forgets_the_held_half(void **state)
{
    (void)state;
    static app_t app;
    static hal_t hal;
    navigating(&app, &hal);
    uint8_t counter = 0u;
    imu_sample(&app, &hal, &counter);
    feed(&app, &hal, front(1000u, 1000u));
    feed(&app, &hal, rear(1000u, 1000u));
    imu_sample(&app, &hal, &counter);
    feed(&app, &hal, front(2000u, 2000u)); /* held, then nothing at all for 2 s */
    hal.t_us += 2000000u;
    for (int k = 0; k < 200; k++) {
        counter = e2e_counter_next(counter); /* the IMU's counter ran on */
    }
    for (int k = 0; k < 5; k++) { /* a jump of the counter is confirmed by its followers */
        imu_sample(&app, &hal, &counter);
    }
    assert_int_not_equal(app.run.mode, APP_MODE_NAVIGATING); /* re-acquiring */
    assert_fresh_pairing(&app);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_one_sample_per_pair, setup),
        cmocka_unit_test_setup(test_the_gear_signs_the_sample, setup),
        cmocka_unit_test_setup(test_a_repeated_half_replaces, setup),
        cmocka_unit_test_setup(test_a_stopped_axle_gives_no_sample, setup),
        cmocka_unit_test_setup(test_a_refused_half_is_not_held, setup),
        cmocka_unit_test_setup(test_app_init_forgets_the_held_half, setup),
        cmocka_unit_test_setup(test_wheel_timeout_forgets_the_held_half, setup),
        cmocka_unit_test_setup(test_wheel_timeout_before_navigation_forgets_the_held_half, setup),
        cmocka_unit_test_setup(test_bus_silence_forgets_the_held_half, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
