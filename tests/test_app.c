/*
 * test_app.c - the application against an in-memory HAL (tests/support/fake_hal.c):
 * initialization by command, navigation from exactly-encoded IMU data, output rates and
 * E2E, determinism, and every kind of bad input counted, never fatal.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app.h"
#include "navecu_protocol.h"
#include "e2e.h"
#include "app_fixture.h"
#include "can_frames.h"
#include "fake_hal.h"
#include "motions.h"
#include "navecu_can.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define LAT0_DEG 45.0
#define LON0_DEG 10.0
#define H0_M 100.0
#define RATE_HZ 100

static hal_t hal;
static app_t app;

/* ---- frame builders (the real encoding: generated codec + E2E, can_frames.h) ---- */

static hal_can_frame_t frame(uint32_t id, const uint8_t d[8])
{
    return cf_frame(id, d, hal.t_us);
}

static void feed(const hal_can_frame_t *f)
{
    app_handle_frame(&app, &hal, f);
}

/* the two frames of one IMU sample, with the pair CRC in IMU_Accel (docs/can.md) */
static void make_imu_pair(const int32_t w[3], const int32_t v[3], uint8_t counter,
                          hal_can_frame_t *rate, hal_can_frame_t *accel)
{
    cf_imu_pair(w, v, counter, 0u, hal.t_us, rate, accel);
}

static void send_imu_pair(const int32_t w[3], const int32_t v[3], uint8_t counter)
{
    hal_can_frame_t fr, fa;
    make_imu_pair(w, v, counter, &fr, &fa);
    feed(&fr);
    feed(&fa);
}

static uint8_t cmd_counter;

static void send_init_commands(double heading_deg)
{
    hal_can_frame_t f = cf_known_position((int32_t)lround(LAT0_DEG * 1e7),
                                          (int32_t)lround(LON0_DEG * 1e7), hal.t_us);
    feed(&f);
    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = 2u;
    c.heading_valid = 1u;
    c.heading = (uint16_t)lround(heading_deg * 100.0);
    c.height = (int32_t)lround(H0_M * 10.0);
    c.cmd_counter = cmd_counter;
    cmd_counter = e2e_counter_next(cmd_counter);
    f = cf_control(&c, hal.t_us);
    feed(&f);
}

/* ---- a vehicle standing still, its exact IMU increments quantised with carry ---- */

typedef struct {
    truth_gen_t gen;
    double carry_w[3], carry_v[3]; /* in LSB */
    uint8_t counter;
} imu_src_t;

static imu_src_t src;
static const still_t STILL = {2.0 * DEG, -1.0 * DEG, 30.0 * DEG};

static void imu_src_init(void)
{
    memset(&src, 0, sizeof src);
    truth_init(&src.gen, kin_still, &STILL, LAT0_DEG * DEG, LON0_DEG * DEG, H0_M);
}

static void imu_src_next(int32_t w[3], int32_t v[3])
{
    double dth[3], dv[3];
    truth_step(&src.gen, 1.0 / RATE_HZ, dth, dv);
    for (int i = 0; i < 3; i++) {
        const double wl = dth[i] * 2097152.0 + src.carry_w[i]; /* LSB 2^-21 rad */
        const double vl = dv[i] * 4096.0 + src.carry_v[i];     /* LSB 2^-12 m/s */
        w[i] = (int32_t)lround(wl);
        v[i] = (int32_t)lround(vl);
        src.carry_w[i] = wl - w[i];
        src.carry_v[i] = vl - v[i];
    }
}

/* run n seconds of stationary IMU data */
static void run_still(int seconds)
{
    for (int k = 0; k < seconds * RATE_HZ; k++) {
        int32_t w[3], v[3];
        imu_src_next(w, v);
        hal.t_us += 1000000u / RATE_HZ;
        send_imu_pair(w, v, src.counter);
        src.counter = e2e_counter_next(src.counter);
    }
}

static int setup(void **state)
{
    (void)state;
    assert_int_equal(fx_fresh_app(&app, &hal), NAV_OK);
    imu_src_init();
    cmd_counter = 0u;
    return 0;
}

static const hal_can_frame_t *last_tx(uint32_t id)
{
    return cf_last_tx(&hal, id);
}

static uint32_t tx_count(uint32_t id)
{
    return cf_tx_count(&hal, id);
}

/*
 * GIVEN a known position and heading by command, then 60 s of a tilted vehicle standing
 *       still (exact increments through the real encoding, remainder carried)
 * WHEN the application levels for 30 s (default) and navigates for 30 s
 * THEN NAV_Position stays within 0.5 m of the start, NAV_Attitude shows the true roll,
 *      pitch and heading within 0.01 deg, and nothing was rejected.
 */
static void test_stationary_navigation(void **state)
{
    (void)state;
    send_init_commands(30.0);
    assert_int_equal(app.run.mode, APP_MODE_LEVELLING);
    run_still(60);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);

    assert_int_equal(hal.tx_dropped, 0); /* the capture holds every frame sent */
    const hal_can_frame_t *p = last_tx(NAVECU_CAN_NAV_POSITION_FRAME_ID);
    assert_non_null(p);
    struct navecu_can_nav_position_t pos;
    navecu_can_nav_position_unpack(&pos, p->data, 8u);
    const double dn_m = (pos.latitude * 1e-7 - LAT0_DEG) * DEG * 6367381.8;
    const double de_m = (pos.longitude * 1e-7 - LON0_DEG) * DEG * 6388838.3 * cos(LAT0_DEG * DEG);
    print_message("stationary, 30 s navigating: NAV_Position %.3f m from the start\n", hypot(dn_m, de_m));
    assert_true(hypot(dn_m, de_m) < 0.5);

    struct navecu_can_nav_attitude_t att;
    navecu_can_nav_attitude_unpack(&att, last_tx(NAVECU_CAN_NAV_ATTITUDE_FRAME_ID)->data, 8u);
    assert_near(att.roll * 0.01, 2.0, 0.01);
    assert_near(att.pitch * 0.01, -1.0, 0.01);
    assert_near(att.heading * 0.01, 30.0, 0.01);

    const app_health_t zero = {0};
    assert_memory_equal(&app.keep.health, &zero, sizeof zero);
}

/* the NavCounter of an E2E-protected output frame, through the generated codec */
static uint8_t nav_counter_of(const hal_can_frame_t *f)
{
    switch (f->id) {
    case NAVECU_CAN_NAV_HEIGHT_FRAME_ID: {
        struct navecu_can_nav_height_t m;
        navecu_can_nav_height_unpack(&m, f->data, 8u);
        return m.nav_counter;
    }
    case NAVECU_CAN_NAV_VELOCITY_FRAME_ID: {
        struct navecu_can_nav_velocity_t m;
        navecu_can_nav_velocity_unpack(&m, f->data, 8u);
        return m.nav_counter;
    }
    case NAVECU_CAN_NAV_ATTITUDE_FRAME_ID: {
        struct navecu_can_nav_attitude_t m;
        navecu_can_nav_attitude_unpack(&m, f->data, 8u);
        return m.nav_counter;
    }
    case NAVECU_CAN_NAV_STATUS_FRAME_ID: {
        struct navecu_can_nav_status_t m;
        memset(&m, 0, sizeof m);
        navecu_can_nav_status_unpack(&m, f->data, 8u);
        return m.nav_counter;
    }
    default: {
        struct navecu_can_nav_calibration_t m;
        navecu_can_nav_calibration_unpack(&m, f->data, 8u);
        return m.nav_counter;
    }
    }
}

/* the start commands, 30 s of levelling at rest, then 10 s of outputs: hal.tx holds those
 * 10 s, none dropped */
static void run_levelled_10_s(void)
{
    send_init_commands(30.0);
    run_still(30); /* levelling */
    hal.tx_n = 0u;
    run_still(10);
    assert_int_equal(hal.tx_dropped, 0);
}

/*
 * GIVEN navigation running at the default rates (IMU 100 Hz)
 * WHEN 10 s pass
 * THEN NAV_Position/Height/Velocity/Attitude come at 50 Hz, NAV_Status at 10 Hz (page 0
 *      plus one counter page), NAV_Calibration at 1 Hz; every protected output has a valid
 *      CRC and its alive counter steps by one.
 */
static void test_output_rates_and_e2e(void **state)
{
    (void)state;
    run_levelled_10_s();
    assert_int_equal(tx_count(NAVECU_CAN_NAV_POSITION_FRAME_ID), 500);
    assert_int_equal(tx_count(NAVECU_CAN_NAV_HEIGHT_FRAME_ID), 500);
    assert_int_equal(tx_count(NAVECU_CAN_NAV_VELOCITY_FRAME_ID), 500);
    assert_int_equal(tx_count(NAVECU_CAN_NAV_ATTITUDE_FRAME_ID), 500);
    assert_int_equal(tx_count(NAVECU_CAN_NAV_STATUS_FRAME_ID), 200);
    assert_int_equal(tx_count(NAVECU_CAN_NAV_CALIBRATION_FRAME_ID), 10);
    e2e_counter_t ctr[0x20];
    memset(ctr, 0, sizeof ctr);
    for (uint32_t i = 0; i < hal.tx_n; i++) {
        const hal_can_frame_t *f = &hal.tx[i];
        assert_int_equal(f->dlc, 8);
        if (f->id == NAVECU_CAN_NAV_POSITION_FRAME_ID) {
            continue; /* 64 bits of coordinates: no E2E (docs/can.md) */
        }
        assert_true(e2e_crc_ok(f->id, f->data));
        if (f->id == NAVECU_CAN_NAV_TIME_FRAME_ID) {
            continue; /* CRC, no alive counter: its TimeOfWeek advances (docs/can.md) */
        }
        assert_int_equal(e2e_counter_step(&ctr[f->id - 0x300u], nav_counter_of(f)), 1);
    }
}

/* Output rates that do not divide the IMU rate (100 Hz): 60 Hz is every 2nd sample, 50 Hz;
 * 30 Hz every 3rd, 33.3 Hz; 7 Hz every 14th, 7.14 Hz (round(IMU rate / rate)). Before, the
 * IMU rate over the rate was truncated: 60 Hz went out at 100 Hz (a review's finding). */
static void test_output_rates_not_dividing(void **state)
{
    (void)state;
    app_config_t cfg = app_default_config();
    cfg.nav_rate_hz = 60u;
    cfg.status_rate_hz = 30u;
    cfg.dyn_rate_hz = 7u;
    assert_int_equal(app_init(&app, &cfg), NAV_OK);
    run_levelled_10_s();
    assert_int_equal(tx_count(NAVECU_CAN_NAV_POSITION_FRAME_ID), 500);
    assert_in_range(tx_count(NAVECU_CAN_NAV_STATUS_FRAME_ID), 666, 668); /* two a period */
    assert_in_range(tx_count(NAVECU_CAN_NAV_RATES_FRAME_ID), 71, 72);
}

/* Same input twice, fresh application: byte-identical output frames. */
static void test_deterministic(void **state)
{
    (void)state;
    static hal_can_frame_t first[FAKE_TX_MAX];
    send_init_commands(30.0);
    run_still(35);
    const uint32_t n1 = hal.tx_n;
    memcpy(first, hal.tx, n1 * sizeof first[0]);
    setup(NULL);
    send_init_commands(30.0);
    run_still(35);
    assert_int_equal(hal.tx_n, n1);
    assert_memory_equal(first, hal.tx, n1 * sizeof first[0]);
}

/*
 * GIVEN a navigating application whose filter has not started (no GNSS yet)
 * WHEN two IMU samples are lost between two whose increments differ by dw and dv (LSB)
 * THEN the filter's next prediction is given 2 |dw|^2 and 2 |dv|^2 (in rad^2 and
 *      (m/s)^2) of process noise on each axis: the two bridged samples, each off by as
 *      much as the increment changed across the gap (app.c sample_noise); a sample that
 *      follows its predecessor adds none (test_ekf: the prediction spends it)
 * AND WHEN eight are bridged THEN (8 |d|)^2 / 4 more (a long gap's errors are correlated)
 * AND WHEN a gyro axis, then an accelerometer axis, is at its range THEN that sensor's
 *      range squared, on its own increments only
 */
static void test_bridged_samples_carry_process_noise(void **state)
{
    (void)state;
    send_init_commands(30.0);
    run_still(32);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    assert_false(app.run.fusion.on);
    const nav_real_t *q = app.run.fusion.ekf.q_inc;
    assert_near(q[0], 0.0, 0.0); /* no gap so far */
    assert_near(q[1], 0.0, 0.0);
    int32_t w[3], v[3];
    imu_src_next(w, v);
    send_imu_pair(w, v, src.counter);
    src.counter = e2e_counter_next(src.counter);
    assert_near(q[0], 0.0, 0.0);
    assert_near(q[1], 0.0, 0.0);
    const int32_t dw[3] = {300, -400, 1200};
    const int32_t dv[3] = {50, 0, -120};
    int32_t w1[3], v1[3];
    for (int i = 0; i < 3; i++) {
        w1[i] = w[i] + dw[i];
        v1[i] = v[i] + dv[i];
    }
    src.counter = e2e_counter_next(e2e_counter_next(src.counter));
    send_imu_pair(w1, v1, src.counter);
    src.counter = e2e_counter_next(src.counter);
    assert_int_equal(app.keep.health.imu_lost, 2);
    const double lsb_a = ldexp(1.0, -21), lsb_v = ldexp(1.0, -12); /* docs/can.md */
    const double want_a = 2.0 * (300.0 * 300.0 + 400.0 * 400.0 + 1200.0 * 1200.0) * lsb_a * lsb_a;
    const double want_v = 2.0 * (50.0 * 50.0 + 120.0 * 120.0) * lsb_v * lsb_v;
    assert_near((double)q[0], want_a, 1e-5 * want_a);
    assert_near((double)q[1], want_v, 1e-5 * want_v);

    /* six lost after the last one: a counter step of 7 is held with the next one until a
     * third follows (docs/can.md), so 8 are bridged at the third; a long gap's errors are
     * correlated: (8 |d|)^2 / 4 = 16 |d|^2 (the same increments back: d = -dw, -dv) */
    for (int i = 0; i < 6; i++) {
        src.counter = e2e_counter_next(src.counter);
    }
    for (int i = 0; i < 3; i++) {
        send_imu_pair(w, v, src.counter);
        src.counter = e2e_counter_next(src.counter);
    }
    assert_int_equal(app.keep.health.imu_lost, 2 + 8);
    const double want_a6 = want_a + 16.0 * want_a / 2.0;
    const double want_v6 = want_v + 16.0 * want_v / 2.0;
    assert_near((double)q[0], want_a6, 1e-5 * want_a6);
    assert_near((double)q[1], want_v6, 1e-5 * want_v6);

    /* a gyro axis at its range: the range's square on the angle, nothing on the velocity;
     * then an accelerometer axis at its range */
    int32_t ws[3] = {w[0], w[1], app.keep.imu.sat_raw[0]};
    send_imu_pair(ws, v, src.counter);
    src.counter = e2e_counter_next(src.counter);
    const double ra = (double)app.keep.imu.sat_raw[0] * lsb_a;
    const double rv = (double)app.keep.imu.sat_raw[1] * lsb_v;
    assert_int_equal(app.keep.health.imu_saturated, 1);
    assert_near((double)q[0], want_a6 + ra * ra, 1e-5 * (want_a6 + ra * ra));
    assert_near((double)q[1], want_v6, 1e-5 * want_v6);
    int32_t vs[3] = {-app.keep.imu.sat_raw[1], v[1], v[2]};
    send_imu_pair(w, vs, src.counter);
    src.counter = e2e_counter_next(src.counter);
    assert_int_equal(app.keep.health.imu_saturated, 2);
    assert_near((double)q[0], want_a6 + ra * ra, 1e-5 * (want_a6 + ra * ra));
    assert_near((double)q[1], want_v6 + rv * rv, 1e-5 * (want_v6 + rv * rv));

    /* two lost before a saturated gyro sample: the two bridged samples lead up to it and
     * are as unknown (3 ra^2), beside the gap's own noise (2 |d|^2) */
    src.counter = e2e_counter_next(e2e_counter_next(src.counter));
    send_imu_pair(ws, v, src.counter);
    src.counter = e2e_counter_next(src.counter);
    assert_int_equal(app.keep.health.imu_lost, 2 + 8 + 2);
    const double dz = (double)(ws[2] - w[2]) * lsb_a;
    const double dvx = (double)(v[0] - vs[0]) * lsb_v;
    const double want_a7 = want_a6 + ra * ra + 3.0 * ra * ra + 2.0 * dz * dz;
    const double want_v7 = want_v6 + rv * rv + 2.0 * dvx * dvx;
    assert_near((double)q[0], want_a7, 1e-5 * want_a7);
    assert_near((double)q[1], want_v7, 1e-5 * want_v7);
}

/*
 * GIVEN a navigating application
 * WHEN every kind of bad input arrives
 * THEN each is counted in its health counter (and reported in NAV_Status), none changes
 *      the navigation, and navigation goes on.
 */
static void test_bad_input_counted(void **state)
{
    (void)state;
    send_init_commands(30.0);
    run_still(32);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    uint8_t d[8] = {0};
    hal_can_frame_t f, fr, fa;
    int32_t w[3], v[3];

    /* unknown standard and extended identifiers */
    f = frame(0x7FFu, d);
    feed(&f);
    f.extended = 1u;
    f.id = 0x18FEF100u;
    feed(&f);
    assert_int_equal(app.keep.health.foreign, 2);

    /* wrong DLC of a known message */
    imu_src_next(w, v);
    make_imu_pair(w, v, src.counter, &fr, &fa);
    f = fr;
    f.dlc = 6u;
    feed(&f);
    assert_int_equal(app.keep.health.bad_dlc, 1);

    /* corrupted IMU_Rate payload: the pair CRC in IMU_Accel catches it */
    f = fr;
    f.data[2] ^= 0x10u;
    feed(&f);
    feed(&fa);
    assert_int_equal(app.keep.health.bad_crc, 1);

    /* a repeated sample (same counter twice) is dropped */
    send_imu_pair(w, v, src.counter);
    const uint64_t n_before = app.keep.n_samples;
    send_imu_pair(w, v, src.counter);
    assert_int_equal(app.keep.health.bad_counter, 1);
    assert_int_equal(app.keep.n_samples, n_before);
    src.counter = e2e_counter_next(src.counter);

    /* two samples lost: bridged, counted, time advances by three samples */
    imu_src_next(w, v);
    imu_src_next(w, v);
    imu_src_next(w, v);
    src.counter = e2e_counter_next(e2e_counter_next(src.counter));
    send_imu_pair(w, v, src.counter);
    src.counter = e2e_counter_next(src.counter);
    assert_int_equal(app.keep.health.imu_lost, 2);
    assert_int_equal(app.keep.n_samples, n_before + 3u);

    /* half pairs: IMU_Rate twice, then IMU_Accel with a foreign counter */
    imu_src_next(w, v);
    make_imu_pair(w, v, src.counter, &fr, &fa);
    feed(&fr);
    feed(&fr);
    assert_int_equal(app.keep.health.imu_pair_broken, 1);
    make_imu_pair(w, v, e2e_counter_next(src.counter), &fr, &fa);
    feed(&fa);
    assert_int_equal(app.keep.health.imu_pair_broken, 2);
    /* the IMU goes on with its next sample: the IMU_Rate frames held for the sample whose
     * IMU_Accel never came are dropped when the next sample pairs (CntImuPairBroken +2),
     * that sample lost and bridged (CntImuLost +1), on the first sample of run_still below */
    src.counter = e2e_counter_next(src.counter);

    /* the invalid alive counter 15 */
    make_imu_pair(w, v, 15u, &fr, &fa);
    feed(&fr);
    assert_int_equal(app.keep.health.bad_counter, 2);

    /* a GNSS fix at an impossible position, a known position off the globe, a GNSS height
     * outside its range */
    struct navecu_can_gnss_position_t gp = {950000000, 0};
    navecu_can_gnss_position_pack(d, &gp, 8u);
    f = frame(NAVECU_CAN_GNSS_POSITION_FRAME_ID, d);
    feed(&f);
    assert_int_equal(app.keep.health.gnss_rejected, 1);
    struct navecu_can_cmd_known_position_t kp = {0, -1800000001};
    navecu_can_cmd_known_position_pack(d, &kp, 8u);
    f = frame(NAVECU_CAN_CMD_KNOWN_POSITION_FRAME_ID, d);
    feed(&f);
    struct navecu_can_gnss_height_t gh = {-200000, 0u}; /* -2000 m */
    navecu_can_gnss_height_pack(d, &gh, 8u);
    f = frame(NAVECU_CAN_GNSS_HEIGHT_FRAME_ID, d);
    feed(&f);
    assert_int_equal(app.keep.health.bad_value, 2);

    /* an unknown command */
    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = 9u;
    c.cmd_counter = cmd_counter;
    navecu_can_cmd_control_pack(d, &c, 8u);
    e2e_protect(NAVECU_CAN_CMD_CONTROL_FRAME_ID, d);
    f = frame(NAVECU_CAN_CMD_CONTROL_FRAME_ID, d);
    feed(&f);
    assert_int_equal(app.keep.health.cmd_rejected, 1);

    /* navigation went on through all of it and reports what it rejected */
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    hal.tx_n = 0u;
    run_still(1);
    struct navecu_can_nav_status_t st;
    int pages_seen = 0;
    for (uint32_t i = 0; i < hal.tx_n; i++) {
        if (hal.tx[i].id != NAVECU_CAN_NAV_STATUS_FRAME_ID) {
            continue;
        }
        memset(&st, 0, sizeof st);
        navecu_can_nav_status_unpack(&st, hal.tx[i].data, 8u);
        if (st.status_page == 0u) {
            assert_int_equal(st.mode, APP_MODE_NAVIGATING);
            assert_true(st.health_flags & NAVECU_HEALTH_REJECTED);
        } else if (st.status_page == 1u) {
            assert_int_equal(st.cnt_foreign, 2);
            assert_int_equal(st.cnt_bad_dlc, 1);
            assert_int_equal(st.cnt_bad_crc, 1);
            pages_seen |= 1;
        } else if (st.status_page == 2u) {
            assert_int_equal(st.cnt_bad_counter, 2);
            assert_int_equal(st.cnt_imu_pair_broken, 4);
            assert_int_equal(st.cnt_imu_lost, 3);
            pages_seen |= 2;
        } else if (st.status_page == 3u) {
            assert_int_equal(st.cnt_bad_value, 2);
            assert_int_equal(st.cnt_gnss_rejected, 1);
            pages_seen |= 4;
        } else if (st.status_page == 4u) {
            assert_int_equal(st.cnt_cmd_rejected, 1);
            assert_int_equal(st.cnt_core_rejected, 0);
            assert_int_equal(st.cnt_time_jumps, 0);
            pages_seen |= 8;
        }
    }
    assert_int_equal(pages_seen, 15);
    const hal_can_frame_t *p = last_tx(NAVECU_CAN_NAV_POSITION_FRAME_ID);
    struct navecu_can_nav_position_t pos;
    navecu_can_nav_position_unpack(&pos, p->data, 8u);
    assert_near(pos.latitude * 1e-7, LAT0_DEG, 1e-5); /* about 1 m */
}

/* SetInitialPosition without a known position is refused; the app keeps waiting. */
static void test_init_needs_known_position(void **state)
{
    (void)state;
    uint8_t d[8];
    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = 2u;
    c.heading_valid = 1u;
    navecu_can_cmd_control_pack(d, &c, 8u);
    e2e_protect(NAVECU_CAN_CMD_CONTROL_FRAME_ID, d);
    hal_can_frame_t f = frame(NAVECU_CAN_CMD_CONTROL_FRAME_ID, d);
    feed(&f);
    assert_int_equal(app.keep.health.cmd_rejected, 1);
    assert_int_equal(app.run.mode, APP_MODE_WAIT_INIT);
    run_still(1);
    assert_null(last_tx(NAVECU_CAN_NAV_POSITION_FRAME_ID)); /* nothing to report yet */
    assert_non_null(last_tx(NAVECU_CAN_NAV_STATUS_FRAME_ID));
}

/* every NAV_Position/Height/Velocity/Attitude frame sent, in order, into out[] */
static uint32_t collect_nav(hal_can_frame_t *out, uint32_t max)
{
    uint32_t n = 0u;
    for (uint32_t i = 0u; i < hal.tx_n && n < max; i++) {
        const uint32_t id = hal.tx[i].id;
        if (id >= NAVECU_CAN_NAV_POSITION_FRAME_ID && id <= NAVECU_CAN_NAV_ATTITUDE_FRAME_ID) {
            out[n] = hal.tx[i];
            out[n].t_us = 0u;
            n++;
        }
    }
    return n;
}

static void feed_junk(int which)
{
    uint8_t d[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    hal_can_frame_t f;
    switch (which % 7) {
    case 0: /* unknown identifier */
        f = frame(0x555u, d);
        break;
    case 1: /* a known message with a short DLC */
        f = frame(NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID, d);
        f.dlc = 3u;
        break;
    case 2: /* a command with a bad CRC */
        f = frame(NAVECU_CAN_CMD_CONTROL_FRAME_ID, d);
        break;
    case 3: { /* a GNSS position off the globe */
        struct navecu_can_gnss_position_t gp = {-950000000, 0};
        navecu_can_gnss_position_pack(d, &gp, 8u);
        f = frame(NAVECU_CAN_GNSS_POSITION_FRAME_ID, d);
        break;
    }
    case 4: { /* a known position off the globe */
        struct navecu_can_cmd_known_position_t kp = {910000000, 0};
        navecu_can_cmd_known_position_pack(d, &kp, 8u);
        f = frame(NAVECU_CAN_CMD_KNOWN_POSITION_FRAME_ID, d);
        break;
    }
    case 5: /* an extended identifier */
        f = frame(0x1234567u, d);
        f.extended = 1u;
        break;
    default: { /* wheel speeds with the invalid counter 15 */
        struct navecu_can_wheel_speeds_t w;
        memset(&w, 0, sizeof w);
        w.wheel_counter = 15u;
        navecu_can_wheel_speeds_pack(d, &w, 8u);
        e2e_protect(NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID, d);
        f = frame(NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID, d);
        break;
    }
    }
    feed(&f);
}

/*
 * GIVEN the same 40 s of IMU data twice, the second time with a rejected frame after
 *       every IMU sample (seven kinds in turn)
 * THEN every rejected frame is counted, and the navigation outputs are bit-identical.
 */
static void test_rejected_frames_change_nothing(void **state)
{
    (void)state;
    static hal_can_frame_t clean[FAKE_TX_MAX], dirty[FAKE_TX_MAX];
    send_init_commands(30.0);
    run_still(40);
    const uint32_t n_clean = collect_nav(clean, FAKE_TX_MAX);
    assert_int_equal(hal.tx_dropped, 0);

    setup(NULL);
    send_init_commands(30.0);
    for (int k = 0; k < 40 * RATE_HZ; k++) {
        int32_t w[3], v[3];
        imu_src_next(w, v);
        hal.t_us += 1000000u / RATE_HZ;
        send_imu_pair(w, v, src.counter);
        src.counter = e2e_counter_next(src.counter);
        feed_junk(k);
    }
    const uint32_t n_dirty = collect_nav(dirty, FAKE_TX_MAX);
    assert_int_equal(hal.tx_dropped, 0);
    const app_health_t *h = &app.keep.health;
    assert_int_equal(h->foreign, 2 * 4000 / 7 + 1);
    assert_int_equal(h->foreign + h->bad_dlc + h->bad_crc + h->gnss_rejected +
                         h->bad_value + h->bad_counter,
                     4000);
    assert_true(n_clean > 1000u);
    assert_int_equal(n_dirty, n_clean);
    assert_memory_equal(clean, dirty, n_clean * sizeof clean[0]);
}

/* A Reset, then an old command frame replayed: its counter is stale, it is dropped. */
static void test_replayed_command_rejected(void **state)
{
    (void)state;
    uint8_t d[8];
    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = 1u; /* Reset */
    c.cmd_counter = cmd_counter;
    cmd_counter = e2e_counter_next(cmd_counter);
    navecu_can_cmd_control_pack(d, &c, 8u);
    e2e_protect(NAVECU_CAN_CMD_CONTROL_FRAME_ID, d);
    const hal_can_frame_t reset = frame(NAVECU_CAN_CMD_CONTROL_FRAME_ID, d);
    feed(&reset);
    send_init_commands(30.0);
    run_still(31);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    feed(&reset); /* the old Reset again */
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    assert_int_equal(app.keep.health.bad_counter, 1);
}

/* skip n IMU samples: the truth moves on, nothing is sent */
/* HealthFlags of the latest NAV_Status page 0 that carries them, after one more status */
static uint16_t health_flags_now(void)
{
    return cf_last_status_page0(&hal).health_flags;
}

static void skip_samples(int n)
{
    for (int k = 0; k < n; k++) {
        int32_t w[3], v[3];
        imu_src_next(w, v);
        hal.t_us += 1000000u / RATE_HZ;
        src.counter = e2e_counter_next(src.counter);
    }
}

/*
 * GIVEN navigation at 100 Hz
 * WHEN 15 samples (150 ms) are lost (the counter's cycle: the counter alone sees nothing)
 * THEN the receive time reveals them: 15 counted lost, bridged, time base right, flagged;
 * AND WHEN 2 s are lost (beyond the 200 ms that are bridged)
 * THEN navigation stops (Fault) instead of going on with an untrustworthy solution.
 */
static void test_imu_gaps(void **state)
{
    (void)state;
    send_init_commands(30.0);
    run_still(31);
    const uint64_t n0 = app.keep.n_samples;
    skip_samples(15);
    run_still(1);
    assert_int_equal(app.keep.health.imu_lost, 15);
    assert_int_equal(app.keep.health.time_jumps, 1);
    assert_int_equal(app.keep.n_samples, n0 + 15u + 100u);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    hal.tx_n = 0u;
    skip_samples(200);
    run_still(1);
    /* 200 lost, and the first two samples after them: the first's counter step (201 mod
     * 15 = 6) is a wrong sequence until the two after it confirm the gap */
    assert_int_equal(app.keep.health.imu_lost, 217);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    assert_int_equal(tx_count(NAVECU_CAN_NAV_POSITION_FRAME_ID), 0);
    struct navecu_can_nav_status_t st;
    memset(&st, 0, sizeof st);
    navecu_can_nav_status_unpack(&st, hal.tx[0].data, 8u);
    assert_int_equal(st.mode, APP_MODE_FAULT);
    assert_true(st.health_flags & NAVECU_HEALTH_IMU_GAP);
    assert_true(st.health_flags & NAVECU_HEALTH_REACQUIRE);
}


/*
 * A sample whose alive counter is wrong but whose CRC is right (a sender fault: E2E
 * "wrong sequence") must not be taken for a gap: a jump of 9 is held, the next sample
 * follows the last good one, so the held one is dropped (CntBadCounter) and one sample
 * bridged; time does not run ahead. A real gap of 9 samples is confirmed by the two
 * samples after it and bridged whole.
 */
static void test_corrupt_imu_counter_is_not_a_gap(void **state)
{
    (void)state;
    send_init_commands(30.0);
    run_still(31);
    const uint64_t n0 = app.keep.n_samples;
    const uint32_t bad0 = app.keep.health.bad_counter;
    int32_t w[3], v[3];
    imu_src_next(w, v);
    hal.t_us += 1000000u / RATE_HZ;
    uint8_t wrong = src.counter;
    for (int k = 0; k < 9; k++) {
        wrong = e2e_counter_next(wrong);
    }
    send_imu_pair(w, v, wrong); /* the right data, a counter 9 ahead */
    src.counter = e2e_counter_next(src.counter);
    run_still(1);
    assert_int_equal(app.keep.health.bad_counter, bad0 + 1u);
    assert_int_equal(app.keep.health.imu_lost, 1u);
    assert_int_equal(app.keep.n_samples, n0 + 1u + 100u); /* time as it was, not 9 ahead */
    /* a real gap of 9 samples */
    skip_samples(9);
    run_still(1);
    assert_int_equal(app.keep.health.bad_counter, bad0 + 3u); /* the two after it, held */
    assert_int_equal(app.keep.health.imu_lost, 1u + 11u);
    assert_int_equal(app.keep.n_samples, n0 + 1u + 100u + 9u + 100u);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    /* a counter corrupted 2 ahead looks like one lost sample and is bridged; the real
     * samples after it are then behind the counter held and dropped until it catches up:
     * time ends where it should, not 2 samples ahead */
    const uint64_t n1 = app.keep.n_samples;
    imu_src_next(w, v);
    hal.t_us += 1000000u / RATE_HZ;
    wrong = e2e_counter_next(e2e_counter_next(src.counter));
    send_imu_pair(w, v, wrong);
    src.counter = e2e_counter_next(src.counter);
    run_still(1);
    assert_int_equal(app.keep.n_samples, n1 + 1u + 100u);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
}

/* an IMU sample of explicit raw increments (counter and timestamp advanced) */
static void feed_raw_sample(const int32_t w[3], const int32_t v[3])
{
    hal.t_us += 1000000u / RATE_HZ;
    send_imu_pair(w, v, src.counter);
    src.counter = e2e_counter_next(src.counter);
}

/*
 * IMU plausibility. Gyro axes whose raw increments repeat for 2 s while the x gyro shows
 * the noise of the configured preset (automotive: 2 deg/sqrt(h), a sigma of 122 LSB per
 * sample at 100 Hz; here uniform noise of +-250 LSB, sigma 144) are stuck: counted once
 * each, flagged (bit 8); a vehicle standing with an ideal IMU is not. A rate at the
 * configured range is saturated: counted per sample and flagged (bit 9) for a second.
 */
static void test_imu_stuck_and_saturated(void **state)
{
    (void)state;
    send_init_commands(30.0);
    run_still(31); /* an ideal IMU standing: every axis repeats, nothing flagged */
    assert_int_equal(app.keep.health.imu_stuck, 0u);
    uint32_t rng = 4711u;
    for (int k = 0; k < 3 * RATE_HZ; k++) {
        /* x gyro: noise of +-250 LSB; the accelerometer noisy in its last bits; y and z
         * gyro frozen */
        rng = rng * 1103515245u + 12345u;
        const int32_t w[3] = {(int32_t)((rng >> 16) % 501u) - 250, 0, 1234};
        const int32_t vk[3] = {k % 2, -(k % 3), 2048 + k % 2};
        feed_raw_sample(w, vk);
    }
    assert_int_equal(app.keep.health.imu_stuck, 2u); /* the z gyro and the frozen y gyro */
    const int32_t v[3] = {0, 1, 2048};
    assert_true(health_flags_now() & NAVECU_HEALTH_IMU_SUSPECT);
    /* a stuck axis's samples say nothing of the motion: each adds a car's yaw rate
     * (APP_STUCK_RATE_RPS: 30 deg/s, 0.005236 rad per sample, under the 300 deg/s range),
     * squared, to the angle's process noise and nothing to the velocity's (app.c
     * sample_noise; the filter is off here: the noise waits in q_inc); the episode itself
     * is test_imu_stream's */
    const nav_real_t *q = app.run.fusion.ekf.q_inc;
    assert_int_equal(app.keep.imu.stuck_raw[0], 10980); /* 0.005236 rad / 2^-21 rad */
    const double ra = (double)app.keep.imu.stuck_raw[0] * ldexp(1.0, -21); /* docs/can.md */
    for (int k = 0; k < 3; k++) {
        const double q0 = (double)q[0];
        const double q1 = (double)q[1];
        const int32_t wq[3] = {5, 0, 1234};
        const int32_t vq[3] = {k % 2, 0, 2048};
        feed_raw_sample(wq, vq);
        assert_near((double)q[0] - q0, ra * ra, 1e-4 * ra * ra);
        assert_near((double)q[1], q1, 0.0);
    }
    /* saturation: 300 deg/s = 5.236 rad/s, 0.05236 rad per sample = 109 805 LSB */
    const uint32_t sat0 = app.keep.health.imu_saturated;
    const int32_t w_sat[3] = {0, 0, 109805};
    feed_raw_sample(w_sat, v);
    assert_int_equal(app.keep.health.imu_saturated, sat0 + 1u);
    const int32_t w_ok[3] = {0, 0, 100000};
    for (int k = 0; k < RATE_HZ / 10; k++) { /* until the next NAV_Status */
        feed_raw_sample(w_ok, v);
    }
    assert_int_equal(app.keep.health.imu_saturated, sat0 + 1u);
    assert_true(health_flags_now() & NAVECU_HEALTH_IMU_SATURATED);
}

/* the angle of the navigator's forward axis from east toward north (rad): a left turn
 * raises it */
static double forward_angle_rad(void)
{
    mat3_t C;
    quat_to_dcm(app.run.nav.q_bn, &C);
    return atan2((double)C.m[1][1], (double)C.m[0][1]);
}

/*
 * GIVEN navigation, the car driving at 10 m/s round a left-hand curve of 100 m radius
 *   (yaw rate 0.1 rad/s, a lateral specific force of -1 m/s^2), rolled 2 deg on a banked
 *   road (gravity's share on x, 0.34 m/s^2, would be 0.034 rad/s of turn), its x gyro
 *   showing its noise
 * WHEN the z gyro freezes at 1234 LSB per sample (0.0588 rad/s)
 * THEN once found stuck (2 s) the navigator turns at the car's own rate, the lateral force
 *   over the forward speed (landnav_car_yaw), not at the frozen one; with the car standing
 *   it does not turn at all (the standstill's bias: test_landnav
 *   test_stuck_yaw_gyro_learns_no_bias)
 */
static void test_stuck_yaw_gyro_takes_the_cars_turn(void **state)
{
    (void)state;
    send_init_commands(30.0);
    run_still(31);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    /* the car rolled 2 deg more (a banked road; about its forward axis): the added share
     * of gravity on the x accelerometer, 0.34 m/s^2, is the navigator's roll's, not a turn */
    mat3_t C;
    quat_to_dcm(app.run.nav.q_bn, &C);
    const double c20_level = (double)C.m[2][0];
    const nav_real_t q_roll[4] = {NAV_C(0.99984770), NAV_C(0.0), NAV_C(0.01745241), NAV_C(0.0)};
    nav_real_t q[4];
    quat_mul(app.run.nav.q_bn, q_roll, q);
    memcpy(app.run.nav.q_bn, q, sizeof q);
    quat_to_dcm(app.run.nav.q_bn, &C);
    const int32_t g_x_lsb =
        (int32_t)lround(9.80665 * ((double)C.m[2][0] - c20_level) * 0.01 * 4096.0);
    assert_true(g_x_lsb >= 13 || g_x_lsb <= -13); /* 0.0349 g over 10 ms: 14.0 LSB */
    for (int i = 0; i < 3; i++) {
        app.run.nav.v_n_mps[i] = NAV_C(10.0) * C.m[i][1];
        app.run.nav.v_n_prev_mps[i] = app.run.nav.v_n_mps[i];
    }
    uint32_t rng = 4711u;
    double a0 = 0.0;
    for (int k = 0; k < 3 * RATE_HZ; k++) {
        if (k == 2 * RATE_HZ + 2) { /* found stuck at 2 s (test_imu_stream) */
            assert_true(app.run.land.yaw_car);
            a0 = forward_angle_rad();
        }
        int32_t w[3], v[3];
        imu_src_next(w, v);
        rng = rng * 1103515245u + 12345u;
        w[0] += (int32_t)((rng >> 16) % 501u) - 250; /* the noise of test_imu_stuck_... */
        w[2] = 1234;
        v[0] += g_x_lsb - 41; /* -1 m/s^2 over 10 ms: 40.96 LSB of 2^-12 m/s */
        feed_raw_sample(w, v);
    }
    const double turned = forward_angle_rad() - a0; /* over the last 98 samples */
    const double expected = 0.98 * 41.0 / 4096.0 / 0.01 / 10.0;
    /* 1.9 % low here: the x gyro's noise tilts the navigator by about 1 mrad (0.01 m/s^2
     * of gravity, 1 %), the roll's share rounded to 14 LSB (0.012 m/s^2, 1.2 %), the
     * velocity 0.08 rad off the forward axis after the 2 s at the frozen rate (0.3 %) */
    assert_near(turned, expected, 0.03 * expected);
    /* standing: no turn at all, whatever the frozen value */
    for (int i = 0; i < 3; i++) {
        app.run.nav.v_n_mps[i] = NAV_C(0.0);
        app.run.nav.v_n_prev_mps[i] = NAV_C(0.0);
    }
    const double a1 = forward_angle_rad();
    for (int k = 0; k < RATE_HZ; k++) {
        int32_t w[3], v[3];
        imu_src_next(w, v);
        w[2] = 1234;
        rng = rng * 1103515245u + 12345u;
        w[0] += (int32_t)((rng >> 16) % 501u) - 250;
        feed_raw_sample(w, v);
    }
    assert_true(app.run.land.yaw_car);
    assert_near(forward_angle_rad() - a1, 0.0, 1e-3); /* 0.0588 rad frozen */
}

/* While the IMU is silent, app_poll keeps NAV_Status going with the stale flag. */
static void test_stale_imu_status(void **state)
{
    (void)state;
    send_init_commands(30.0);
    run_still(31);
    hal.tx_n = 0u;
    for (int k = 0; k < 200; k++) { /* 2 s of silence, polled every 10 ms */
        hal.t_us += 10000u;
        app_poll(&app, &hal);
    }
    const uint32_t n = tx_count(NAVECU_CAN_NAV_STATUS_FRAME_ID);
    assert_in_range(n, 28, 32); /* two frames per 100 ms after 0.5 s of silence */
    struct navecu_can_nav_status_t st;
    memset(&st, 0, sizeof st);
    navecu_can_nav_status_unpack(&st, last_tx(NAVECU_CAN_NAV_STATUS_FRAME_ID)->data, 8u);
    hal_can_frame_t page0 = hal.tx[hal.tx_n - 2u];
    navecu_can_nav_status_unpack(&st, page0.data, 8u);
    assert_int_equal(st.status_page, 0);
    assert_true(st.health_flags & NAVECU_HEALTH_IMU_STALE);
}

/* the four frames of one GNSS epoch: position, velocity (north only) and height carrying
 * vel_epoch, the status closing epoch status_epoch with its accuracies and TimeOfWeek */
typedef struct {
    int32_t lat_e7, lon_e7;
    double speed_north_mps, height_m;
    uint8_t vel_epoch, status_epoch;
    uint16_t hacc_dm, vacc_dm;
    uint8_t sacc_raw;
    uint32_t tow_ms;
} gnss_epoch_t;

static void send_gnss(const gnss_epoch_t *g)
{
    hal_can_frame_t f = cf_gnss_position(g->lat_e7, g->lon_e7, hal.t_us);
    feed(&f);
    struct navecu_can_gnss_velocity_t gv;
    memset(&gv, 0, sizeof gv);
    gv.vel_north = (int16_t)lround(g->speed_north_mps * 100.0);
    gv.gnss_epoch = g->vel_epoch;
    gv.speed_accuracy = g->sacc_raw;
    f = cf_gnss_velocity(&gv, hal.t_us);
    feed(&f);
    f = cf_gnss_height((int32_t)lround(g->height_m * 100.0), g->vel_epoch, hal.t_us);
    feed(&f);
    struct navecu_can_gnss_status_t gs;
    memset(&gs, 0, sizeof gs);
    gs.fix_type = 3u;
    gs.num_satellites = 9u;
    gs.horiz_accuracy = g->hacc_dm;
    gs.vert_accuracy = g->vacc_dm;
    gs.gnss_epoch = g->status_epoch;
    gs.time_of_week = g->tow_ms;
    f = cf_gnss_status(&gs, hal.t_us);
    feed(&f);
}

/* the epochs' TimeOfWeek: 200 ms apart */
static uint32_t epoch_tow_ms;

static void send_gnss_epoch(uint8_t vel_epoch, uint8_t status_epoch, double speed_north)
{
    epoch_tow_ms += 200u;
    const gnss_epoch_t g = {450000000, 100000000, speed_north, 100.0, vel_epoch, status_epoch,
                            0u, 0u, 0u, epoch_tow_ms};
    send_gnss(&g);
}

/* A course seen while waiting, then an IMU gap too long to bridge: the gap's turn is not
 * in the gyro's sum, so the course is no longer the heading for a stop (a review found a
 * GNSS-only start 90 deg off after a turn inside such a gap) */
static void test_gap_while_waiting_forgets_the_course(void **state)
{
    (void)state;
    run_still(1);
    send_gnss_epoch(0u, 0u, 10.0);
    assert_int_equal(app.run.align.course_valid, 1);
    skip_samples(200);
    run_still(1);
    assert_int_equal(app.run.align.course_valid, 0);
    send_gnss_epoch(1u, 1u, 0.0); /* the stop: no GNSS-only start */
    assert_int_equal(app.run.mode, APP_MODE_WAIT_INIT);
}

/*
 * GNSS initialization: a course while driving north at 10 m/s, then a stop gives position,
 * height and heading, and levelling starts. An epoch whose velocity and height carry
 * another number than its status is refused.
 */
static void test_gnss_init_and_epochs(void **state)
{
    (void)state;
    send_gnss_epoch(0u, 0u, 10.0);
    assert_int_equal(app.run.mode, APP_MODE_WAIT_INIT);
    send_gnss_epoch(1u, 2u, 0.0); /* mismatched: velocity and height dropped */
    assert_int_equal(app.keep.health.gnss_rejected, 1);
    assert_int_equal(app.run.mode, APP_MODE_WAIT_INIT);
    send_gnss_epoch(2u, 2u, 0.0); /* repeated velocity counter 2 after 1: fine, step 1 */
    assert_int_equal(app.run.mode, APP_MODE_LEVELLING);
    assert_near(app.run.align.heading_rad, 0.0, 1e-6);
    assert_int_equal(app.run.align.h_cm, 10000);
    epoch_tow_ms -= 200u; /* the same epoch again (its TimeOfWeek): a repeat */
    send_gnss_epoch(2u, 2u, 0.0);
    assert_int_equal(app.keep.health.bad_counter, 1);
}

static uint8_t att_counter;


/*
 * GIVEN levelling after SetInitialPosition, 10 s into its 30 s
 * WHEN 2 s of IMU samples are lost (beyond the 200 ms that are bridged)
 * THEN the levelling starts over (its average would span an unknown interval), it does
 *      not stop in Fault waiting for a command: the gap flagged, navigation 30 s after
 *      the gap and not before.
 */
static void test_imu_gap_restarts_levelling(void **state)
{
    (void)state;
    send_init_commands(30.0);
    run_still(10);
    assert_int_equal(app.run.mode, APP_MODE_LEVELLING);
    skip_samples(200);
    run_still(1);
    assert_true(app.keep.health.imu_lost >= 200u); /* 201: as in test_imu_gaps */
    assert_int_equal(app.run.mode, APP_MODE_LEVELLING);
    assert_true(health_flags_now() & NAVECU_HEALTH_IMU_GAP);
    run_still(28); /* 29 s after the gap: still levelling (20 s would have ended it) */
    assert_int_equal(app.run.mode, APP_MODE_LEVELLING);
    run_still(2);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
}

/*
 * GIVEN navigation of a standing car interrupted by an IMU gap of 2 s (beyond bridging):
 *       mode Fault, HealthFlags REACQUIRE
 * WHEN a GNSS epoch of the car still standing arrives
 * THEN navigation resumes there with the attitude from before the gap (heading 30 deg)
 *      and nothing is refused afterwards;
 * GIVEN another such gap WHEN an epoch at 2 m/s arrives (its course is no heading yet)
 * THEN it waits, and WHEN the car then stands THEN it still waits (it may have turned:
 *      a review found a car re-acquired 90 deg off, claiming 5 deg), until a course at
 *      10 m/s gives the heading.
 */
static void test_reacquire_after_long_gap(void **state)
{
    (void)state;
    send_init_commands(30.0);
    run_still(31);
    skip_samples(200);
    run_still(1);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    assert_true(app.run.align.reacquire);
    send_gnss_epoch(0u, 0u, 0.0); /* still standing: the heading before is kept */
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    assert_false(app.run.align.reacquire);
    run_still(1);
    nav_real_t roll, pitch, heading;
    sins_euler(&app.run.nav, &roll, &pitch, &heading);
    assert_true(fabs((double)heading / DEG - 30.0) < 0.05);
    assert_int_equal(app.keep.health.nav_rejected, 0u);
    assert_false(health_flags_now() & NAVECU_HEALTH_REACQUIRE);

    /* again, and the car moves before it stops (2 m/s: no course to take): the heading
     * before may be gone, so the stop does not re-acquire; the course at 10 m/s does */
    skip_samples(200);
    run_still(1);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    send_gnss_epoch(1u, 1u, 2.0);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    send_gnss_epoch(2u, 2u, 0.0);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    send_gnss_epoch(3u, 3u, 10.0); /* north */
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    sins_euler(&app.run.nav, &roll, &pitch, &heading);
    assert_true(fabs(remainder((double)heading, 2.0 * M_PI)) < 0.05);
}

static void send_initial_attitude(double roll_rad, double pitch_rad)
{
    const hal_can_frame_t f = cf_initial_attitude((int32_t)lround(roll_rad * 4194304.0), /* 2^-22 rad */
                                                  (int32_t)lround(pitch_rad * 4194304.0),
                                                  att_counter, hal.t_us);
    att_counter = e2e_counter_next(att_counter);
    feed(&f);
}

/*
 * GIVEN SetInitialPosition and then the true roll and pitch by CMD_InitialAttitude
 * THEN navigation starts at once (no levelling), holds position over 30 s standing still,
 *      and the same command outside levelling is refused.
 */
static void test_initial_attitude_skips_levelling(void **state)
{
    (void)state;
    att_counter = 0u;
    send_initial_attitude(STILL.roll, STILL.pitch); /* before any position: refused */
    assert_int_equal(app.keep.health.cmd_rejected, 1);
    send_init_commands(30.0);
    send_initial_attitude(STILL.roll, STILL.pitch);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    run_still(30);
    struct navecu_can_nav_position_t pos;
    navecu_can_nav_position_unpack(&pos, last_tx(NAVECU_CAN_NAV_POSITION_FRAME_ID)->data, 8u);
    assert_near(pos.latitude * 1e-7, LAT0_DEG, 2e-7);  /* 2 cm */
    assert_near(pos.longitude * 1e-7, LON0_DEG, 3e-7);
    struct navecu_can_nav_attitude_t att;
    navecu_can_nav_attitude_unpack(&att, last_tx(NAVECU_CAN_NAV_ATTITUDE_FRAME_ID)->data, 8u);
    assert_near(att.roll * 0.01, 2.0, 0.01);
    assert_near(att.pitch * 0.01, -1.0, 0.01);
}

/* ---- odometer, dead reckoning, standstill, calibration (docs/odometry.md) ---- */

static uint8_t wheel_counter;

static void send_wheels(double v_mps)
{
    const int16_t raw = (int16_t)lround(v_mps / 0.02);
    const int16_t four[4] = {raw, raw, raw, raw};
    const hal_can_frame_t f = cf_wheels(four, wheel_counter, hal.t_us);
    wheel_counter = e2e_counter_next(wheel_counter);
    feed(&f);
}

/* n IMU samples of the still source plus a gyro z bias (LSB per sample, exact), with
 * WheelSpeeds at v_mps every second sample (50 Hz); the capture buffer is emptied as it
 * goes, keeping the latest frames */
static void run_wheels(int samples, double v_mps, int32_t gz_bias_lsb)
{
    for (int k = 0; k < samples; k++) {
        int32_t w[3], v[3];
        imu_src_next(w, v);
        w[2] += gz_bias_lsb;
        hal.t_us += 1000000u / RATE_HZ;
        if (hal.tx_n > FAKE_TX_MAX - 64u) {
            hal.tx_n = 0u;
        }
        if (k % 2 == 0) {
            send_wheels(v_mps);
        }
        send_imu_pair(w, v, src.counter);
        src.counter = e2e_counter_next(src.counter);
    }
}

static void start_perfect(void)
{
    wheel_counter = 0u;
    att_counter = 0u;
    send_init_commands(30.0);
    send_initial_attitude(STILL.roll, STILL.pitch);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
}

static void last_position(double *lat_deg, double *lon_deg)
{
    struct navecu_can_nav_position_t pos;
    navecu_can_nav_position_unpack(&pos, last_tx(NAVECU_CAN_NAV_POSITION_FRAME_ID)->data, 8u);
    *lat_deg = pos.latitude * 1e-7;
    *lon_deg = pos.longitude * 1e-7;
}

/* metres east and north of (lat, lon) from the start, flat Earth at 45 N (WGS-84 radii:
 * M = 6367381.8 m, N = 6388838.3 m; 1e-6 relative over a few hundred metres) */
#define RM_45 6367381.8
#define RN_45 6388838.3
static void local_en(double lat_deg, double lon_deg, double *e, double *n)
{
    *n = (lat_deg - LAT0_DEG) * DEG * RM_45;
    *e = (lon_deg - LON0_DEG) * DEG * RN_45 * cos(LAT0_DEG * DEG);
}

static struct navecu_can_nav_calibration_t last_cal(void)
{
    struct navecu_can_nav_calibration_t c;
    navecu_can_nav_calibration_unpack(&c, last_tx(NAVECU_CAN_NAV_CALIBRATION_FRAME_ID)->data, 8u);
    return c;
}

static uint8_t last_mode(void)
{
    for (uint32_t i = hal.tx_n; i > 0u; i--) {
        const hal_can_frame_t *f = &hal.tx[i - 1u];
        if (f->id == NAVECU_CAN_NAV_STATUS_FRAME_ID && (f->data[0] & 0x0Fu) == 0u) {
            struct navecu_can_nav_status_t st;
            navecu_can_nav_status_unpack(&st, f->data, 8u);
            return st.mode;
        }
    }
    return 0xFFu;
}

/*
 * GIVEN a perfect start (heading 30 deg, pitch -1 deg) and wheels at 10.00 m/s for 20 s
 * THEN the output is the dead-reckoned solution (mode 4): 200 m x cos(1 deg) along 30 deg
 *      (seed 000 eqs 1-4; 0.2 m for the first wheel frame's timing and 1e-7 deg output
 *      rounding), the height 200 m x sin(-1 deg) lower, velocity 10 m/s along 30 deg.
 */
static void test_dead_reckoning_output(void **state)
{
    (void)state;
    start_perfect();
    run_wheels(20 * RATE_HZ, 10.0, 0);
    assert_int_equal(last_mode(), NAVECU_CAN_NAV_STATUS_MODE_DEAD_RECKONING_CHOICE);
    double lat, lon, e, n;
    last_position(&lat, &lon);
    local_en(lat, lon, &e, &n);
    const double d = 200.0 * cos(1.0 * DEG);
    assert_near(hypot(e, n), d, 0.2);
    assert_near(atan2(e, n) / DEG, 30.0, 0.01);
    struct navecu_can_nav_height_t h;
    navecu_can_nav_height_unpack(&h, last_tx(NAVECU_CAN_NAV_HEIGHT_FRAME_ID)->data, 8u);
    assert_near(h.height * 0.01, H0_M - 200.0 * sin(1.0 * DEG), 0.05);
    struct navecu_can_nav_velocity_t v;
    navecu_can_nav_velocity_unpack(&v, last_tx(NAVECU_CAN_NAV_VELOCITY_FRAME_ID)->data, 8u);
    assert_near(v.vel_east * 0.01, 10.0 * cos(1.0 * DEG) * sin(30.0 * DEG), 0.011);
    assert_near(v.vel_north * 0.01, 10.0 * cos(1.0 * DEG) * cos(30.0 * DEG), 0.011);
    /* wheels silent for longer than the odometer timeout: inertial only (mode 2) */
    for (int k = 0; k < 2 * RATE_HZ; k++) {
        int32_t w[3], a[3];
        imu_src_next(w, a);
        send_imu_pair(w, a, src.counter);
        src.counter = e2e_counter_next(src.counter);
    }
    assert_int_equal(last_mode(), NAVECU_CAN_NAV_STATUS_MODE_INERTIAL_CHOICE);
}

/*
 * GIVEN a perfect start (heading 30 deg) and the navigator moving along its heading at
 *       -2, -0.1 (within APP_ODO_REVERSE_MPS of standing) and +2 m/s
 * WHEN WheelSpeeds read +2 m/s (magnitudes: an OBD-II speed forwarded, the car reversing)
 * THEN with odo_direction navigator the odometer's speed takes the navigator's sign beyond
 *      APP_ODO_REVERSE_MPS (-2, +2, +2 m/s), with as_read it is the reading (+2 always).
 */
static void test_odo_direction_from_navigator(void **state)
{
    (void)state;
    const double v_nav_mps[3] = {-2.0, -0.1, 2.0};
    for (int mode = 0; mode < 2; mode++) {
        app_config_t cfg = app_default_config();
        cfg.odo_direction = mode ? ODO_DIR_NAVIGATOR : ODO_DIR_AS_READ;
        assert_int_equal(app_init(&app, &cfg), NAV_OK);
        start_perfect();
        for (int i = 0; i < 3; i++) {
            const double v = v_nav_mps[i];
            app.run.nav.v_n_mps[0] = (nav_real_t)(v * sin(30.0 * DEG));
            app.run.nav.v_n_mps[1] = (nav_real_t)(v * cos(30.0 * DEG));
            send_wheels(2.0);
            const double expect = (mode && v < -(double)APP_ODO_REVERSE_MPS) ? -2.0 : 2.0;
            assert_near((double)app.keep.odo.speed_mps, expect, 1e-4);
        }
    }
}

/*
 * GIVEN a gyro z bias of 10 deg/h (exactly 1 LSB of 2^-21 rad per 10 ms sample = 9.83
 *       deg/h) and the wheels at zero for 120 s, the bias prior widened to 100 deg/h
 * THEN the heading is held (0.01 deg; unheld it would drift 0.33 deg), the position holds,
 *      and the bias estimate is 9.83 deg/h x n / (n + n0) with n0 = ARW^2/(dt sigma_b^2)
 *      (default ARW): within 2 % of that.
 */
static void test_standstill_holds_and_estimates_bias(void **state)
{
    (void)state;
    app_config_t cfg = app_default_config();
    cfg.gyro_bias_rps = (nav_real_t)(100.0 * DEG / 3600.0);
    assert_int_equal(app_init(&app, &cfg), NAV_OK);
    start_perfect();
    run_wheels(120 * RATE_HZ, 0.0, 1);
    assert_int_equal(last_mode(), NAVECU_CAN_NAV_STATUS_MODE_DEAD_RECKONING_CHOICE);
    struct navecu_can_nav_attitude_t att;
    navecu_can_nav_attitude_unpack(&att, last_tx(NAVECU_CAN_NAV_ATTITUDE_FRAME_ID)->data, 8u);
    assert_near(att.heading * 0.01, 30.0, 0.01);
    double lat, lon, e, n;
    last_position(&lat, &lon);
    local_en(lat, lon, &e, &n);
    assert_near(hypot(e, n), 0.0, 0.02);
    const double bias_dph = ldexp(1.0, -21) * RATE_HZ / DEG * 3600.0;
    const double arw = (double)cfg.gyro_arw_rad_rts, sb = (double)cfg.gyro_bias_rps;
    const double n0 = arw * arw / (0.01 * sb * sb);
    const double nst = (double)app.keep.zbias.n;
    assert_true(nst > 119.0 * RATE_HZ - 60 && nst <= 120.0 * RATE_HZ); /* 0.5 s to declare */
    assert_near((double)app.keep.zbias.bias_rps / DEG * 3600.0, bias_dph * nst / (nst + n0),
                0.02 * bias_dph);
}

/*
 * GIVEN a noisy gyro configured as such (ARW 2 deg/sqrt(h) at 100 Hz: one sample scatters
 *       by 0.33 deg/s) and the car parked, its yaw rate samples alternating +-1 deg/s
 * WHEN  60 s pass with the wheels at zero
 * THEN  it is a standstill from 0.5 s on (every sample but the first 0.5 s taught the z
 *       bias, and the heading is held): the test is 4 of the sample's sigmas (1.33 deg/s),
 *       not the 0.5 deg/s that every one of these samples exceeds (before, not one was
 *       taken); a body turning at 2 deg/s with zero wheels is still no standstill.
 */
static void test_standstill_with_a_noisy_gyro(void **state)
{
    (void)state;
    app_config_t cfg = app_default_config();
    cfg.gyro_arw_rad_rts = (nav_real_t)(2.0 * DEG / 60.0);
    assert_int_equal(app_init(&app, &cfg), NAV_OK);
    assert_near((double)app.keep.odo.cfg.still_rate_rps,
                4.0 * 2.0 * DEG / 60.0 * sqrt((double)RATE_HZ), 1e-6);
    start_perfect();
    const int32_t one_dps_lsb = (int32_t)lround(DEG / RATE_HZ / ldexp(1.0, -21)); /* 366 */
    for (int k = 0; k < 60 * RATE_HZ; k++) {
        run_wheels(1, 0.0, (k % 2 == 0) ? one_dps_lsb : -one_dps_lsb);
    }
    const double nst = (double)app.keep.zbias.n;
    assert_true(nst > 59.0 * RATE_HZ - 60 && nst <= 60.0 * RATE_HZ);
    struct navecu_can_nav_attitude_t att;
    navecu_can_nav_attitude_unpack(&att, last_tx(NAVECU_CAN_NAV_ATTITUDE_FRAME_ID)->data, 8u);
    assert_near(att.heading * 0.01, 30.0, 0.01);
    const uint32_t n_before = app.keep.zbias.n;
    run_wheels(10 * RATE_HZ, 0.0, 2 * one_dps_lsb);
    assert_int_equal(app.keep.zbias.n, n_before); /* turning: nothing learnt */
}

/* a point at bearing (from the start) of the last output + dbearing, at distance / scale */
static void known_point(double dbearing_deg, double scale, int32_t *lat_e7, int32_t *lon_e7)
{
    double lat, lon, e, n;
    last_position(&lat, &lon);
    local_en(lat, lon, &e, &n);
    const double d = hypot(e, n) / scale, b = atan2(e, n) + dbearing_deg * DEG;
    *lat_e7 = (int32_t)lround((LAT0_DEG + d * cos(b) / RM_45 / DEG) * 1e7);
    *lon_e7 = (int32_t)lround((LON0_DEG + d * sin(b) / (RN_45 * cos(LAT0_DEG * DEG)) / DEG) * 1e7);
}

static void send_known_position(int32_t lat_e7, int32_t lon_e7)
{
    const hal_can_frame_t f = cf_known_position(lat_e7, lon_e7, hal.t_us);
    feed(&f);
}

static void send_command(uint8_t command)
{
    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = command;
    c.cmd_counter = cmd_counter;
    cmd_counter = e2e_counter_next(cmd_counter);
    const hal_can_frame_t f = cf_control(&c, hal.t_us);
    feed(&f);
}

/*
 * GIVEN 30 s of dead reckoning at 10 m/s (300 m) and the minimum base set to 250 m
 * WHEN CalibrateHere at a point whose bearing from the start is 0.5 deg less than the
 *      dead-reckoned one's, at 1/1.02 of its distance (the heading reads 0.5 deg too far
 *      clockwise and the odometer 2 % long: dH = +0.5 deg, mu = 0.02)
 * THEN NAV_Calibration carries dH +0.5 deg (0.005: the point's 1 cm rounding over 300 m)
 *      and mu 0.02 (1e-4), CalStatus OnePoint from KnownPosition, stored; the position is
 *      reset to the point; a reboot loads them from NVM; EraseCalibration clears them,
 *      and after a reboot nothing is loaded. A point closer than the base is refused with
 *      its reason, and CalibrateHere without a new CMD_KnownPosition is refused.
 */
/* the defaults but a one-point calibration's minimum base of base_m; booted, navigating
 * from start_perfect; returns the configuration */
static app_config_t start_with_min_base(nav_real_t base_m)
{
    app_config_t cfg = app_default_config();
    cfg.cal_min_base_m = base_m;
    assert_int_equal(app_init(&app, &cfg), NAV_OK);
    app_boot(&app, &hal);
    start_perfect();
    return cfg;
}

static void test_one_point_calibration_and_nvm(void **state)
{
    (void)state;
    const app_config_t cfg = start_with_min_base(NAV_C(250.0));
    run_wheels(20 * RATE_HZ, 10.0, 0);
    int32_t lat_e7, lon_e7;
    known_point(0.0, 1.0, &lat_e7, &lon_e7);
    send_known_position(lat_e7, lon_e7);
    send_command(NAVECU_CAN_CMD_CONTROL_COMMAND_CALIBRATE_HERE_CHOICE);
    run_wheels(RATE_HZ, 10.0, 0);
    assert_int_equal(last_cal().cal_status,
                     NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_TOO_CLOSE_CHOICE);
    assert_int_equal(last_cal().cal_valid, 0);
    run_wheels(9 * RATE_HZ, 10.0, 0);
    known_point(-0.5, 1.02, &lat_e7, &lon_e7); /* true bearing 0.5 deg less: dH = +0.5 */
    send_known_position(lat_e7, lon_e7);
    send_command(NAVECU_CAN_CMD_CONTROL_COMMAND_CALIBRATE_HERE_CHOICE);
    send_command(NAVECU_CAN_CMD_CONTROL_COMMAND_CALIBRATE_HERE_CHOICE); /* point used */
    assert_int_equal(app.keep.health.cmd_rejected, 2);
    run_wheels(2, 10.0, 0);
    double lat, lon;
    last_position(&lat, &lon);
    /* reset to the point, plus the 0.2 m driven in the two samples since */
    assert_near(lat, lat_e7 * 1e-7, 2.5e-6);
    assert_near(lon, lon_e7 * 1e-7, 2.5e-6);
    run_wheels(RATE_HZ, 10.0, 0);
    struct navecu_can_nav_calibration_t c = last_cal();
    /* CalStatus tells the last request's outcome (the repeated one was refused); the
     * values in use stay those of the calibration */
    assert_int_equal(c.cal_status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE);
    assert_int_equal(c.cal_source, NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_KNOWN_POSITION_CHOICE);
    assert_int_equal(c.cal_valid, 1);
    assert_int_equal(c.cal_stored, 1);
    assert_int_equal(c.cal_count, 1);
    assert_near(c.heading_correction * 0.001, 0.5, 0.005);
    assert_near(c.odo_scale_error * 1e-5, 0.02, 1e-4);
    /* from here on the track runs along 30 - 0.5 deg at 1/1.02 of the wheel distance */
    double lat2, lon2, e1, n1, e2, n2;
    last_position(&lat, &lon);
    local_en(lat, lon, &e1, &n1);
    run_wheels(10 * RATE_HZ, 10.0, 0);
    last_position(&lat2, &lon2);
    local_en(lat2, lon2, &e2, &n2);
    assert_near(atan2(e2 - e1, n2 - n1) / DEG, 29.5, 0.01);
    assert_near(hypot(e2 - e1, n2 - n1), 100.0 * cos(1.0 * DEG) / 1.02, 0.05);

    /* reboot: the stored values come back */
    const nav_real_t dh = app.keep.cal.dh_rad, mu = app.keep.cal.mu;
    assert_int_equal(app_init(&app, &cfg), NAV_OK);
    app_boot(&app, &hal);
    assert_int_equal(app.keep.cal.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_FROM_NVM_CHOICE);
    assert_near(app.keep.cal.dh_rad, dh, 0.0);
    assert_near(app.keep.cal.mu, mu, 0.0);
    /* CMD_Control EraseCalibration is refused (a UDS routine now, test_app_uds) */
    cmd_counter = 0u;
    const uint32_t refused0 = app_health(&app)->cmd_rejected;
    send_command(NAVECU_CAN_CMD_CONTROL_COMMAND_ERASE_CALIBRATION_CHOICE);
    assert_int_equal(app_health(&app)->cmd_rejected, refused0 + 1u);
    assert_near(app.keep.cal.dh_rad, dh, 0.0);
    /* erase (what RoutineControl 0x0201 does), reboot: nothing */
    calib_erase(&app.keep.cal, &hal, NULL);
    assert_near(app.keep.cal.dh_rad, 0.0, 0.0);
    assert_int_equal(app_init(&app, &cfg), NAV_OK);
    app_boot(&app, &hal);
    assert_int_equal(app.keep.cal.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NONE_CHOICE);
    assert_near(app.keep.cal.mu, 0.0, 0.0);
}

/* the last NAV_Status page 0's HorizAccuracy (m; 655.35 "unknown") and NAV_Accuracy's
 * HeadingAccuracy (deg; 40.95 "unknown") */
static double last_horiz_accuracy(void)
{
    for (uint32_t i = hal.tx_n; i > 0u; i--) {
        if (hal.tx[i - 1u].id == NAVECU_CAN_NAV_STATUS_FRAME_ID &&
            (hal.tx[i - 1u].data[0] & 15u) == 0u) {
            struct navecu_can_nav_status_t st;
            memset(&st, 0, sizeof st);
            navecu_can_nav_status_unpack(&st, hal.tx[i - 1u].data, 8u);
            return st.horiz_accuracy * 0.01;
        }
    }
    fail_msg("no NAV_Status page 0");
    return -1.0;
}

static double last_heading_accuracy(void)
{
    struct navecu_can_nav_accuracy_t m;
    navecu_can_nav_accuracy_unpack(&m, last_tx(NAVECU_CAN_NAV_ACCURACY_FRAME_ID)->data, 8u);
    return m.heading_accuracy * 0.01;
}

/*
 * GIVEN a commanded start (the point known to APP_KNOWN_POS_SIGMA_M per axis, the
 *      commanded heading to the filter's prior, the uncalibrated car's scale and mounting
 *      to the filter's priors: ekf_default_config) and no GNSS
 * WHEN the car dead-reckons straight at 10 m/s
 * THEN HorizAccuracy is the dead reckoning's (dr_acc.h, seed 000 eqs 5-6):
 *      sqrt(2 s_p^2 + D^2 (s_k^2 + s_psi^2) + (s_b v t^2 / 2)^2) after D = 100 and 300 m,
 *      and HeadingAccuracy sqrt(s_psi^2 + (s_b t)^2), to 2 % (s_b the z gyro's turn-on
 *      bias prior: nothing learnt at a standstill yet; its noise adds less)
 * WHEN a one-point calibration resets the position to a known point
 * THEN it is that point's, sqrt(2) s_p, and grows again from there with the calibration's
 *      errors over its 300 m base and the bias's drift, to 3 %.
 */
static void test_dead_reckoning_reports_its_accuracy(void **state)
{
    (void)state;
    const app_config_t cfg = start_with_min_base(NAV_C(250.0));
    run_wheels(RATE_HZ / 2, 0.0, 0);
    const double sp = (double)APP_KNOWN_POS_SIGMA_M;
    assert_near(last_horiz_accuracy(), sqrt(2.0) * sp, 0.011);
    const ekf_config_t ec = ekf_default_config();
    const double s_psi = sqrt((double)ec.heading_rad * (double)ec.heading_rad +
                              (double)ec.mount_rad * (double)ec.mount_rad);
    const double s2 = (double)ec.k * (double)ec.k + s_psi * s_psi;
    /* no standstill yet: the z bias is its turn-on prior, turning the heading by sb t
     * and moving the car sideways by sb v t^2 / 2 after t s at v */
    const double sb = (double)cfg.gyro_bias_rps;
    double prev = 0.0;
    for (int leg = 0; leg < 2; leg++) {
        run_wheels((leg == 0 ? 10 : 20) * RATE_HZ, 10.0, 0);
        const double t = leg == 0 ? 10.0 : 30.0;
        double lat, lon, e, n;
        last_position(&lat, &lon);
        local_en(lat, lon, &e, &n);
        const double d2 = e * e + n * n, side = sb * 10.0 * t * t / 2.0;
        const double expect = sqrt(2.0 * sp * sp + d2 * s2 + side * side);
        assert_near(last_horiz_accuracy(), expect, 0.02 * expect);
        assert_true(last_horiz_accuracy() > prev);
        prev = last_horiz_accuracy();
        const double head = sqrt(s_psi * s_psi + sb * t * sb * t) / DEG;
        assert_near(last_heading_accuracy(), head, 0.02 * head);
    }
    int32_t lat_e7, lon_e7;
    known_point(0.0, 1.0, &lat_e7, &lon_e7);
    send_known_position(lat_e7, lon_e7);
    send_command(NAVECU_CAN_CMD_CONTROL_COMMAND_CALIBRATE_HERE_CHOICE);
    assert_int_equal(app.keep.cal.count, 1); /* performed */
    run_wheels(RATE_HZ / 5, 10.0, 0); /* 2 m, two NAV_Status */
    assert_near(last_horiz_accuracy(), sqrt(2.0) * sp, 0.011);
    run_wheels(30 * RATE_HZ, 10.0, 0);
    /* 300 m on along the same line, one base length: per axis the point's error twice (it
     * went into the calibration's scale and heading too: dr_acc.h) and the base's once,
     * 4 s_p^2 + s_p^2; the leg's heading drift, s_b 30 s, over the 300 m; the bias's 30 s
     * more sideways */
    const double drift = sb * 30.0, side = sb * 10.0 * 30.0 * 30.0 / 2.0;
    const double after =
        sqrt(2.0 * 5.0 * sp * sp + 300.0 * 300.0 * drift * drift + side * side);
    assert_near(last_horiz_accuracy(), after, 0.03 * after);
    assert_true(last_horiz_accuracy() < prev);
}

/*
 * GIVEN a stored one-point calibration from GNSS over a 300 m base (its point's sigma is
 *      not stored) and a receiver declared at gnss_hacc_m 0.5 m
 * WHEN navigation starts from a commanded point
 * THEN the dead reckoning's odometer scale sigma is sqrt(2) times the per-axis sigma the
 *      filter would give such a fix, floor included (fusion_fix_sigma_axis_m: 1 m), over
 *      the base, not sqrt(2) x 0.5 / sqrt(2) / 300 (the declared figure unclamped)
 */
static void test_stored_gnss_calibration_takes_the_fix_sigma(void **state)
{
    (void)state;
    app_config_t cfg = app_default_config();
    cfg.gnss_hacc_m = NAV_C(0.5);
    assert_int_equal(app_init(&app, &cfg), NAV_OK);
    app_boot(&app, &hal);
    app.keep.cal.source = CAL_SRC_GNSS;
    app.keep.cal.base_m = NAV_C(300.0);
    start_perfect();
    const double expect = sqrt(2.0) * (double)APP_GNSS_SIGMA_FLOOR_M / 300.0;
    assert_near(fusion_fix_sigma_axis_m(cfg.gnss_hacc_m), APP_GNSS_SIGMA_FLOOR_M, 0.0);
    assert_near(sqrt((double)app.run.land.acc.P[DR_ACC_MU][DR_ACC_MU]), expect, 1e-4 * expect);
}

/* Both NVM slots corrupt at boot: defaults, CalStatus NvmCorrupt, the NVM flag raised. */
static void test_corrupt_nvm_at_boot(void **state)
{
    (void)state;
    memset(hal.nvm, 0x5A, sizeof hal.nvm);
    app_boot(&app, &hal);
    assert_int_equal(app.keep.cal.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NVM_CORRUPT_CHOICE);
    assert_near(app.keep.cal.dh_rad, 0.0, 0.0);
    start_perfect();
    run_wheels(RATE_HZ, 0.0, 0);
    struct navecu_can_nav_status_t st;
    navecu_can_nav_status_unpack(&st, hal.tx[0].data, 8u);
    for (uint32_t i = hal.tx_n; i > 0u; i--) {
        if (hal.tx[i - 1u].id == NAVECU_CAN_NAV_STATUS_FRAME_ID && (hal.tx[i - 1u].data[0] & 15u) == 0u) {
            navecu_can_nav_status_unpack(&st, hal.tx[i - 1u].data, 8u);
            break;
        }
    }
    assert_true(st.health_flags & NAVECU_HEALTH_NVM_ERROR);
    assert_int_equal(last_cal().cal_status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NVM_CORRUPT_CHOICE);
}

/* CalibrateAtGnss waits for the next accepted fix; that fix (the start point here) is too
 * close, and the refusal says so. Before navigating the command is refused at once. */
static void test_calibrate_at_gnss(void **state)
{
    (void)state;
    send_command(NAVECU_CAN_CMD_CONTROL_COMMAND_CALIBRATE_AT_GNSS_CHOICE);
    assert_int_equal(app.keep.health.cmd_rejected, 1);
    start_perfect();
    run_wheels(RATE_HZ, 5.0, 0);
    send_command(NAVECU_CAN_CMD_CONTROL_COMMAND_CALIBRATE_AT_GNSS_CHOICE);
    /* still the first refusal's reason: nothing happens before the fix */
    assert_int_equal(app.keep.cal.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE);
    assert_int_equal(app.run.cal.at_gnss, 1);
    send_gnss_epoch(0u, 0u, 5.0);
    assert_int_equal(app.keep.cal.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_TOO_CLOSE_CHOICE);
    assert_int_equal(app.run.cal.at_gnss, 0);
}

/* ---- the Kalman filter in the application (docs/kalman.md) ---- */

static uint8_t fix_epoch;

/* one GNSS epoch at lat/lon (1e-7 deg), height H0, zero velocity, 2 m accuracy, tow_ms */
static void send_fix(int32_t lat_e7, int32_t lon_e7, uint32_t tow_ms)
{
    const gnss_epoch_t g = {lat_e7, lon_e7, 0.0, H0_M, fix_epoch, fix_epoch, 20u, 30u, 1u, tow_ms};
    send_gnss(&g);
    fix_epoch = e2e_counter_next(fix_epoch);
}

static struct navecu_can_nav_status_t last_status_page0(void)
{
    return cf_last_status_page0(&hal);
}

/*
 * GIVEN a perfect start, the car standing (wheels at zero), GNSS fixes at the true
 *       position at 5 Hz for 20 s
 * THEN the filter runs: NAV_Status mode 5 GnssIns, a finite 1-sigma HorizAccuracy of a
 *      few metres at most (the receiver says 2 m), the position within 0.1 m;
 * WHEN one fix is 100 m off
 * THEN it is refused and counted (CntGnssRejected), and the position does not move;
 * WHEN the fixes stop for 3 s
 * THEN the mode is DeadReckoning (the odometer, standing, still valid).
 */
static void test_filter_with_gnss(void **state)
{
    (void)state;
    start_perfect();
    fix_epoch = 0u;
    const int32_t lat0 = (int32_t)lround(LAT0_DEG * 1e7), lon0 = (int32_t)lround(LON0_DEG * 1e7);
    uint32_t tow = 100000u;
    for (int k = 0; k < 100; k++) {
        run_wheels(RATE_HZ / 5, 0.0, 0);
        tow += 200u;
        send_fix(lat0, lon0, tow);
    }
    assert_true(app.run.fusion.on);
    run_wheels(RATE_HZ / 5, 0.0, 0);
    struct navecu_can_nav_status_t st = last_status_page0();
    assert_int_equal(st.mode, NAVECU_CAN_NAV_STATUS_MODE_GNSS_INS_CHOICE);
    assert_true(st.horiz_accuracy > 0u && st.horiz_accuracy < 300u); /* 0.01 m units */
    double lat, lon, e, n;
    last_position(&lat, &lon);
    local_en(lat, lon, &e, &n);
    assert_near(hypot(e, n), 0.0, 0.1);
    const uint32_t rejected = app.keep.health.gnss_rejected;
    tow += 200u;
    send_fix(lat0 + 9000, lon0, tow); /* 100 m north */
    run_wheels(RATE_HZ / 5, 0.0, 0);
    assert_int_equal(app.keep.health.gnss_rejected, rejected + 1u);
    last_position(&lat, &lon);
    local_en(lat, lon, &e, &n);
    assert_near(hypot(e, n), 0.0, 0.1);
    run_wheels(3 * RATE_HZ, 0.0, 0);
    st = last_status_page0();
    assert_int_equal(st.mode, NAVECU_CAN_NAV_STATUS_MODE_DEAD_RECKONING_CHOICE);
    assert_int_equal(app.run.fusion.ekf.n_health_fixes, 0u);
}


/*
 * Longitude -180 deg, within the DBC's range (issue #17: 89 of 89 fixes there were refused,
 * and the known position too).
 * GIVEN a known position at longitude -180 deg, SetInitialPosition and the attitude
 * WHEN the car stands there with GNSS fixes at -180 deg for 10 s
 * THEN nothing is refused, the filter runs on them, and NAV_Position is on that meridian
 *      (+180 deg, the same one, inside the DBC's [-180, 180]) within 0.1 m.
 */
static void test_longitude_minus_180(void **state)
{
    (void)state;
    wheel_counter = 0u;
    att_counter = 0u;
    fix_epoch = 0u;
    const int32_t lat0 = (int32_t)lround(LAT0_DEG * 1e7), lon0 = -1800000000;
    hal_can_frame_t f = cf_known_position(lat0, lon0, hal.t_us);
    feed(&f);
    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = 2u;
    c.heading_valid = 1u;
    c.heading = 3000u;
    c.height = (int32_t)lround(H0_M * 10.0);
    c.cmd_counter = cmd_counter;
    cmd_counter = e2e_counter_next(cmd_counter);
    f = cf_control(&c, hal.t_us);
    feed(&f);
    send_initial_attitude(STILL.roll, STILL.pitch);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    uint32_t tow = 100000u;
    for (int k = 0; k < 50; k++) {
        run_wheels(RATE_HZ / 5, 0.0, 0);
        tow += 200u;
        send_fix(lat0, lon0, tow);
    }
    run_wheels(RATE_HZ / 5, 0.0, 0);
    assert_int_equal(app.keep.health.gnss_rejected, 0u);
    assert_int_equal(app.keep.health.bad_value, 0u);
    assert_true(app.run.fusion.on);
    struct navecu_can_nav_position_t pos;
    navecu_can_nav_position_unpack(&pos, last_tx(NAVECU_CAN_NAV_POSITION_FRAME_ID)->data, 8u);
    assert_true(navecu_can_nav_position_longitude_is_in_range(pos.longitude));
    /* 1e-7 deg of longitude at 45 deg is 7.9 mm: 0.1 m is 13 LSB */
    const int64_t off = pos.longitude > 0 ? 1800000000LL - pos.longitude
                                          : (int64_t)pos.longitude + 1800000000LL;
    assert_true(off >= -13 && off <= 13);
    assert_true(pos.latitude - lat0 <= 9 && lat0 - pos.latitude <= 9); /* 1e-7 deg: 11 mm */
}

/* the filter running on fixes at the start point, car standing: returns the next tow */
static uint32_t run_filter_on_fixes(int n_fixes, uint32_t tow)
{
    const int32_t lat0 = (int32_t)lround(LAT0_DEG * 1e7), lon0 = (int32_t)lround(LON0_DEG * 1e7);
    for (int k = 0; k < n_fixes; k++) {
        run_wheels(RATE_HZ / 5, 0.0, 0);
        tow += 200u;
        send_fix(lat0, lon0, tow);
    }
    return tow;
}

static int all_nav_outputs_finite(void)
{
    const hal_can_frame_t *fp = last_tx(NAVECU_CAN_NAV_VELOCITY_FRAME_ID);
    const hal_can_frame_t *fa = last_tx(NAVECU_CAN_NAV_ATTITUDE_FRAME_ID);
    if (fp == NULL || fa == NULL) {
        return 0;
    }
    struct navecu_can_nav_velocity_t v;
    struct navecu_can_nav_attitude_t at;
    navecu_can_nav_velocity_unpack(&v, fp->data, 8u);
    navecu_can_nav_attitude_unpack(&at, fa->data, 8u);
    return isfinite(navecu_can_nav_velocity_vel_east_decode(v.vel_east)) &&
           isfinite(navecu_can_nav_attitude_heading_decode(at.heading)) &&
           fabs(navecu_can_nav_velocity_vel_east_decode(v.vel_east)) < 0.5;
}

/*
 * The GnssEpoch counter (0..14) comes round over an outage (issue #17: the first fix after
 * it was dropped as a repeat). A repeat is decided from the data, the TimeOfWeek.
 * GIVEN the filter running on 5 Hz fixes (car standing)
 * WHEN 14 epochs are missed, so that the next epoch carries the counter of the last one
 *      received, with its own TimeOfWeek 3 s later
 * THEN that epoch is taken whole: nothing counted, as many filter updates (position and
 *      velocity) as from any other fix;
 * WHEN then the same epoch comes again (counter and TimeOfWeek)
 * THEN it is a repeat: dropped and counted (CntBadCounter), no filter update.
 */
static void test_gnss_epoch_counter_round_an_outage(void **state)
{
    (void)state;
    start_perfect();
    fix_epoch = 0u;
    const int32_t lat0 = (int32_t)lround(LAT0_DEG * 1e7), lon0 = (int32_t)lround(LON0_DEG * 1e7);
    uint32_t tow = run_filter_on_fixes(50, 100000u);
    assert_true(app.run.fusion.on);
    run_wheels(RATE_HZ / 5, 0.0, 0);
    uint32_t u0 = app.run.fusion.ekf.n_updates;
    tow += 200u;
    send_fix(lat0, lon0, tow);
    const uint32_t per_fix = app.run.fusion.ekf.n_updates - u0;
    assert_true(per_fix >= 4u); /* position and velocity */
    const app_health_t before = app.keep.health;
    for (int k = 0; k < 14; k++) { /* the outage: 14 epochs never sent */
        run_wheels(RATE_HZ / 5, 0.0, 0);
        tow += 200u;
        fix_epoch = e2e_counter_next(fix_epoch);
    }
    run_wheels(RATE_HZ / 5, 0.0, 0);
    tow += 200u;
    u0 = app.run.fusion.ekf.n_updates;
    const uint8_t again = fix_epoch;
    send_fix(lat0, lon0, tow);
    assert_int_equal(app.run.fusion.ekf.n_updates - u0, per_fix);
    assert_int_equal(app.keep.health.bad_counter, before.bad_counter);
    assert_int_equal(app.keep.health.gnss_rejected, before.gnss_rejected);
    /* the same epoch repeated */
    u0 = app.run.fusion.ekf.n_updates;
    fix_epoch = again;
    send_fix(lat0, lon0, tow);
    assert_int_equal(app.run.fusion.ekf.n_updates, u0);
    assert_int_equal(app.keep.health.bad_counter, before.bad_counter + 1u);
}

/*
 * GIVEN the filter running on GNSS fixes (car standing)
 * WHEN its covariance becomes non-finite (a NaN in P, as a numerical blow-up leaves it)
 * THEN at the next prediction it is found diverged and reset: CntFilterResets 1 on
 *      NAV_Status page 5, HealthFlags bit 7 set, no non-finite output ever sent; with
 *      GNSS around, navigation re-acquires (mode Fault, bit 11) at the next fix and the
 *      filter restarts at the one after (mode GnssIns again);
 * WHEN instead the navigator itself becomes non-finite
 * THEN navigation restarts from the initial state (mode WaitInit), counted again.
 */
static void test_diverged_filter_is_reset(void **state)
{
    (void)state;
    start_perfect();
    fix_epoch = 0u;
    uint32_t tow = run_filter_on_fixes(50, 100000u);
    assert_true(app.run.fusion.on);
    assert_int_equal(app.keep.health.filter_resets, 0u);
    app.run.fusion.ekf.P[3][3] = NAN;
    run_wheels(RATE_HZ / 5, 0.0, 0);
    assert_int_equal(app.keep.health.filter_resets, 1u);
    assert_false(app.run.fusion.on);
    assert_int_equal(app.run.mode, APP_MODE_FAULT); /* re-acquiring from GNSS */
    struct navecu_can_nav_status_t st = last_status_page0();
    assert_true((st.health_flags & NAVECU_HEALTH_FILTER_RESET) != 0u);
    assert_true((st.health_flags & NAVECU_HEALTH_REACQUIRE) != 0u);
    assert_true(all_nav_outputs_finite()); /* the last ones sent, from before the reset */
    run_wheels(RATE_HZ, 0.0, 0); /* every page goes round within 1 s */
    int seen_page5 = 0;
    for (uint32_t i = 0u; i < hal.tx_n; i++) {
        const hal_can_frame_t *fr = &hal.tx[i];
        if (fr->id == NAVECU_CAN_NAV_STATUS_FRAME_ID && (fr->data[0] & 0x0Fu) == 5u) {
            struct navecu_can_nav_status_t p5;
            navecu_can_nav_status_unpack(&p5, fr->data, 8u);
            seen_page5 = p5.cnt_filter_resets == 1u;
        }
    }
    assert_true(seen_page5);
    tow += 1200u; /* the receiver's clock went on meanwhile (1.2 s without fixes) */
    tow = run_filter_on_fixes(1, tow);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING); /* re-acquired */
    tow = run_filter_on_fixes(1, tow);
    assert_true(app.run.fusion.on); /* restarted at the fix after */
    run_wheels(RATE_HZ / 5, 0.0, 0);
    st = last_status_page0();
    assert_int_equal(st.mode, NAVECU_CAN_NAV_STATUS_MODE_GNSS_INS_CHOICE);

    app.run.nav.v_n_mps[0] = INFINITY;
    run_wheels(RATE_HZ / 5, 0.0, 0);
    assert_int_equal(app.keep.health.filter_resets, 2u);
    assert_int_equal(app.run.mode, APP_MODE_WAIT_INIT);
    (void)tow;
}

/*
 * GIVEN a running application whose main loop calls app_poll every pass
 * THEN app_tasks_ok says 1 every pass (the watchdog is kicked), across a 10 s silence
 *      of the bus too (missing input is not a late task);
 * WHEN app_poll stops being called (a stuck task) while time goes on
 * THEN app_tasks_ok says 0 once three status periods have passed, and counts it.
 */
static void test_task_supervision(void **state)
{
    (void)state;
    start_perfect();
    for (int k = 0; k < RATE_HZ; k++) {
        run_wheels(1, 0.0, 0);
        app_poll(&app, &hal);
        assert_true(app_tasks_ok(&app, hal.t_us));
    }
    hal.t_us += 10000000u; /* the bus silent for 10 s, then the loop runs again */
    app_poll(&app, &hal);
    assert_true(app_tasks_ok(&app, hal.t_us));
    assert_int_equal(app.keep.health.tasks_late, 0u);
    hal.t_us += 250000u; /* within 3 status periods (300 ms): still fine */
    assert_true(app_tasks_ok(&app, hal.t_us));
    hal.t_us += 100000u;
    assert_false(app_tasks_ok(&app, hal.t_us));
    assert_int_equal(app.keep.health.tasks_late, 1u);
}

/* ---- the IMU rate against the data (imu_rate.h) ----
 * The configured rate is 100 Hz; what the IMU really sends is told by the GNSS epochs'
 * TimeOfWeek: 100 samples per 1000 ms is 100 Hz, 100 samples per 250 ms is a 400 Hz IMU
 * (and per 4000 ms a 25 Hz one). */

/* n epochs at the start point (standing), each after `samples` IMU samples with the wheels
 * at zero, TimeOfWeek on by tow_step_ms; *nav_frames += the NAV_Position frames sent.
 * Returns the next TimeOfWeek. */
static uint32_t run_epochs(int n, int samples, uint32_t tow_step_ms, uint32_t tow,
                           uint32_t *nav_frames)
{
    const int32_t lat0 = (int32_t)lround(LAT0_DEG * 1e7), lon0 = (int32_t)lround(LON0_DEG * 1e7);
    for (int k = 0; k < n; k++) {
        hal.tx_n = 0u;
        run_wheels(samples, 0.0, 0);
        tow += tow_step_ms;
        send_fix(lat0, lon0, tow);
        *nav_frames += tx_count(NAVECU_CAN_NAV_POSITION_FRAME_ID);
    }
    return tow;
}

static uint16_t flags_after_one_status(void)
{
    run_wheels(RATE_HZ / 10, 0.0, 0);
    return health_flags_now();
}

/*
 * GIVEN levelling after SetInitialPosition, and the samples of a 400 Hz IMU (100 per
 *       0.25 s of TimeOfWeek) with the rate configured as 100 Hz
 * THEN the second epoch (one interval) changes nothing, the third finds the mismatch:
 *      mode Fault, HealthFlags IMU_RATE_MISMATCH, NAV_Status ImuRateMeasured 400 Hz,
 *      counted once; for 60 s of such data (levelling would have ended at 30 s) no
 *      NAV_Position is sent, and Reset, SetInitialPosition and CMD_InitialAttitude do not
 *      start navigation;
 * WHEN the data come at 100 Hz again
 * THEN the second interval at the rate ends the mismatch: levelling starts again from the
 *      commanded position, and navigation 30 s later.
 */
static void test_imu_rate_mismatch_holds_levelling(void **state)
{
    (void)state;
    fix_epoch = 0u;
    wheel_counter = 0u;
    att_counter = 0u;
    send_init_commands(30.0);
    assert_int_equal(app.run.mode, APP_MODE_LEVELLING);
    uint32_t nav = 0u;
    uint32_t tow = run_epochs(2, 100, 250u, 100000u, &nav);
    assert_int_equal(app.run.mode, APP_MODE_LEVELLING);
    tow = run_epochs(1, 100, 250u, tow, &nav);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    assert_int_equal(app.keep.health.imu_rate_mismatch, 1u);
    assert_true(flags_after_one_status() & NAVECU_HEALTH_IMU_RATE_MISMATCH);
    struct navecu_can_nav_status_t st = last_status_page0();
    assert_int_equal(st.mode, NAVECU_CAN_NAV_STATUS_MODE_FAULT_CHOICE);
    assert_near(navecu_can_nav_status_imu_rate_measured_decode(st.imu_rate_measured), 400.0, 1e-9);
    tow = run_epochs(240, 100, 250u, tow, &nav); /* 60 s of 400 Hz data */
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    send_command(1u); /* Reset */
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    send_init_commands(30.0);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    const uint32_t refused = app.keep.health.cmd_rejected;
    send_initial_attitude(STILL.roll, STILL.pitch);
    assert_int_equal(app.keep.health.cmd_rejected, refused + 1u);
    tow = run_epochs(40, 100, 250u, tow, &nav);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    assert_int_equal(nav, 0u);
    assert_int_equal(app.keep.health.imu_rate_mismatch, 1u);
    /* the IMU at 100 Hz: the first interval is on rate, the second ends it */
    tow = run_epochs(1, 100, 1000u, tow, &nav);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    tow = run_epochs(1, 100, 1000u, tow, &nav);
    assert_int_equal(app.run.mode, APP_MODE_LEVELLING);
    assert_int_equal(app.run.align.level_n, 0u);
    assert_false(flags_after_one_status() & NAVECU_HEALTH_IMU_RATE_MISMATCH);
    assert_int_equal(last_status_page0().imu_rate_measured, 0u);
    (void)run_epochs(31, 100, 1000u, tow, &nav);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    assert_true(nav > 0u);
}

/*
 * GIVEN the filter navigating on GNSS (standing) with the IMU at its configured 100 Hz
 * WHEN the IMU sends 25 Hz (100 samples per 4 s of TimeOfWeek)
 * THEN the second epoch after the change finds it: navigation stops (mode Fault,
 *      HealthFlags IMU_RATE_MISMATCH and REACQUIRE, no NAV_Position), and the epochs after
 *      do not re-acquire while it lasts;
 * WHEN the IMU is back at 100 Hz
 * THEN at the second epoch at the rate navigation re-acquires from that epoch, as after a
 *      long IMU gap: the attitude from before is kept (heading 30 deg), and the filter
 *      runs again at the next.
 */
static void test_imu_rate_mismatch_reacquires(void **state)
{
    (void)state;
    start_perfect();
    fix_epoch = 0u;
    uint32_t nav = 0u;
    uint32_t tow = run_epochs(20, 100, 1000u, 100000u, &nav);
    assert_true(app.run.fusion.on);
    assert_true(nav > 0u);
    tow = run_epochs(1, 100, 4000u, tow, &nav);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    tow = run_epochs(1, 100, 4000u, tow, &nav);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    assert_true(app.run.align.reacquire);
    assert_false(app.run.fusion.on);
    const uint16_t fl = flags_after_one_status();
    assert_true(fl & NAVECU_HEALTH_IMU_RATE_MISMATCH);
    assert_true(fl & NAVECU_HEALTH_REACQUIRE);
    assert_near(navecu_can_nav_status_imu_rate_measured_decode(last_status_page0().imu_rate_measured),
                26.0, 1e-9); /* 25 Hz in 2 Hz steps, rounded up */
    nav = 0u;
    tow = run_epochs(10, 100, 4000u, tow, &nav);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    tow = run_epochs(1, 100, 1000u, tow, &nav);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    assert_int_equal(nav, 0u);
    tow = run_epochs(1, 100, 1000u, tow, &nav);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    assert_false(app.run.align.reacquire);
    nav_real_t roll, pitch, heading;
    sins_euler(&app.run.nav, &roll, &pitch, &heading);
    assert_true(fabs((double)heading / DEG - 30.0) < 0.05);
    (void)run_epochs(2, 100, 1000u, tow, &nav);
    assert_true(app.run.fusion.on);
    assert_true(nav > 0u);
    const uint16_t after = flags_after_one_status();
    assert_false(after & NAVECU_HEALTH_IMU_RATE_MISMATCH);
    assert_false(after & NAVECU_HEALTH_REACQUIRE);
    assert_int_equal(app.keep.health.imu_rate_mismatch, 1u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_stationary_navigation, setup),
        cmocka_unit_test_setup(test_output_rates_and_e2e, setup),
        cmocka_unit_test_setup(test_output_rates_not_dividing, setup),
        cmocka_unit_test_setup(test_deterministic, setup),
        cmocka_unit_test_setup(test_bad_input_counted, setup),
        cmocka_unit_test_setup(test_bridged_samples_carry_process_noise, setup),
        cmocka_unit_test_setup(test_init_needs_known_position, setup),
        cmocka_unit_test_setup(test_rejected_frames_change_nothing, setup),
        cmocka_unit_test_setup(test_replayed_command_rejected, setup),
        cmocka_unit_test_setup(test_imu_gaps, setup),
        cmocka_unit_test_setup(test_imu_gap_restarts_levelling, setup),
        cmocka_unit_test_setup(test_corrupt_imu_counter_is_not_a_gap, setup),
        cmocka_unit_test_setup(test_imu_stuck_and_saturated, setup),
        cmocka_unit_test_setup(test_stuck_yaw_gyro_takes_the_cars_turn, setup),
        cmocka_unit_test_setup(test_reacquire_after_long_gap, setup),
        cmocka_unit_test_setup(test_gap_while_waiting_forgets_the_course, setup),
        cmocka_unit_test_setup(test_stale_imu_status, setup),
        cmocka_unit_test_setup(test_gnss_init_and_epochs, setup),
        cmocka_unit_test_setup(test_initial_attitude_skips_levelling, setup),
        cmocka_unit_test_setup(test_dead_reckoning_output, setup),
        cmocka_unit_test_setup(test_odo_direction_from_navigator, setup),
        cmocka_unit_test_setup(test_standstill_holds_and_estimates_bias, setup),
        cmocka_unit_test_setup(test_standstill_with_a_noisy_gyro, setup),
        cmocka_unit_test_setup(test_one_point_calibration_and_nvm, setup),
        cmocka_unit_test_setup(test_corrupt_nvm_at_boot, setup),
        cmocka_unit_test_setup(test_diverged_filter_is_reset, setup),
        cmocka_unit_test_setup(test_task_supervision, setup),
        cmocka_unit_test_setup(test_calibrate_at_gnss, setup),
        cmocka_unit_test_setup(test_dead_reckoning_reports_its_accuracy, setup),
        cmocka_unit_test_setup(test_stored_gnss_calibration_takes_the_fix_sigma, setup),
        cmocka_unit_test_setup(test_filter_with_gnss, setup),
        cmocka_unit_test_setup(test_longitude_minus_180, setup),
        cmocka_unit_test_setup(test_gnss_epoch_counter_round_an_outage, setup),
        cmocka_unit_test_setup(test_imu_rate_mismatch_holds_levelling, setup),
        cmocka_unit_test_setup(test_imu_rate_mismatch_reacquires, setup),
    };
    return cmocka_run_group_tests_name("app", tests, NULL, NULL);
}
