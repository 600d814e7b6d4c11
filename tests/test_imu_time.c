/*
 * test_imu_time.c - the IMU's own sample time (IMU_Time, imu_time = stamped; docs/can.md,
 * IMU samples): each sample integrated over its stamped interval, without resampling, and
 * every stamp that cannot be right refused, counted and bridged (imu_stream.h).
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
#include "imu_rate.h"
#include "motions.h"
#include "navecu_can.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define LAT0_DEG 45.0
#define LON0_DEG 10.0
#define H0_M 100.0
#define RATE_HZ 100
#define PERIOD_US 10000u

static hal_t hal;
static app_t app;
static uint8_t cmd_counter, att_counter;

static void feed(const hal_can_frame_t *f)
{
    app_handle_frame(&app, &hal, f);
}

static void fresh(imu_time_t mode)
{
    fake_hal_reset(&hal);
    app_config_t cfg = app_default_config();
    cfg.imu_time = mode;
    assert_int_equal(app_init(&app, &cfg), NAV_OK);
    cmd_counter = 0u;
    att_counter = 0u;
}

static hal_can_frame_t imu_time_frame(uint8_t counter, uint32_t t_us)
{
    struct navecu_can_imu_time_t m;
    memset(&m, 0, sizeof m);
    m.sample_time = t_us;
    m.imu_counter = counter;
    uint8_t d[8];
    navecu_can_imu_time_pack(d, &m, sizeof d);
    e2e_protect(NAVECU_CAN_IMU_TIME_FRAME_ID, d);
    return cf_frame(NAVECU_CAN_IMU_TIME_FRAME_ID, d, hal.t_us);
}

/* IMU_Time (unless stamp_counter < 0) then the IMU pair of counter */
static void send_sample(const int32_t w[3], const int32_t v[3], uint8_t counter,
                        int stamp_counter, uint32_t stamp_us)
{
    if (stamp_counter >= 0) {
        const hal_can_frame_t ft = imu_time_frame((uint8_t)stamp_counter, stamp_us);
        feed(&ft);
    }
    hal_can_frame_t fr, fa;
    cf_imu_pair(w, v, counter, 0u, hal.t_us, &fr, &fa);
    feed(&fr);
    feed(&fa);
}

/* ---- a tilted vehicle standing still, its exact increments over each true interval ---- */

typedef struct {
    truth_gen_t gen;
    double carry_w[3], carry_v[3];
    uint8_t counter;
    uint32_t stamp_us;
    uint32_t lcg;
} src_t;

static src_t src;
static const still_t STILL = {2.0 * DEG, -1.0 * DEG, 30.0 * DEG};

static void src_init(uint32_t stamp0_us)
{
    memset(&src, 0, sizeof src);
    truth_init(&src.gen, kin_still, &STILL, LAT0_DEG * DEG, LON0_DEG * DEG, H0_M);
    src.stamp_us = stamp0_us;
    src.lcg = 12345u;
}

/* the increments of the next dt_us, quantised with the remainder carried */
static void src_next(uint32_t dt_us, int32_t w[3], int32_t v[3])
{
    double dth[3], dv[3];
    truth_step(&src.gen, (double)dt_us * 1e-6, dth, dv);
    for (int i = 0; i < 3; i++) {
        const double wl = dth[i] * 2097152.0 + src.carry_w[i];
        const double vl = dv[i] * 4096.0 + src.carry_v[i];
        w[i] = (int32_t)lround(wl);
        v[i] = (int32_t)lround(vl);
        src.carry_w[i] = wl - w[i];
        src.carry_v[i] = vl - v[i];
    }
}

/* the jittered interval: 10.4 ms (a 96.15 Hz IMU configured as 100 Hz, within the rate
 * check's 5 %) +- 1.5 ms, uniform, deterministic */
static uint32_t jittered_dt_us(void)
{
    src.lcg = src.lcg * 1664525u + 1013904223u;
    return 10400u - 1500u + (src.lcg >> 8) % 3001u;
}

/* one sample of dt_us, stamped (its IMU_Time sent before the pair) */
static void src_sample(uint32_t dt_us)
{
    int32_t w[3], v[3];
    src_next(dt_us, w, v);
    src.stamp_us += dt_us; /* wraps modulo 2^32 as the IMU's clock does */
    hal.t_us += dt_us;
    send_sample(w, v, src.counter, src.counter, src.stamp_us);
    src.counter = e2e_counter_next(src.counter);
}

/* SetInitialPosition and the true roll and pitch: navigating at once, no levelling */
static void start_navigating(void)
{
    hal_can_frame_t f = cf_known_position((int32_t)lround(LAT0_DEG * 1e7),
                                          (int32_t)lround(LON0_DEG * 1e7), hal.t_us);
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
    f = cf_initial_attitude((int32_t)lround(STILL.roll * 4194304.0),
                            (int32_t)lround(STILL.pitch * 4194304.0), att_counter, hal.t_us);
    att_counter = e2e_counter_next(att_counter);
    feed(&f);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
}

static double lat0_rad, lon0_rad, h0_m; /* the navigator's start */

static void note_start(void)
{
    lat0_rad = (double)geo_lat_rad(&app.run.nav.pos);
    lon0_rad = (double)geo_lon_rad(&app.run.nav.pos);
    h0_m = (double)geo_h_m(&app.run.nav.pos);
}

/* the navigator's horizontal and vertical distance from its start, m */
static void nav_error_m(double *horiz, double *vert)
{
    const double lat = (double)geo_lat_rad(&app.run.nav.pos);
    const double lon = (double)geo_lon_rad(&app.run.nav.pos);
    const double dn = (lat - lat0_rad) * 6367000.0;
    const double de = (lon - lon0_rad) * 6367000.0 * cos(lat0_rad);
    *horiz = sqrt(dn * dn + de * de);
    *vert = fabs((double)geo_h_m(&app.run.nav.pos) - h0_m);
}

static uint32_t first_dt_us;

/* 30 s of the jittered stream, navigating from the start; the sum of the true intervals */
static uint64_t run_jittered(imu_time_t mode, double *horiz, double *vert)
{
    fresh(mode);
    src_init(123456u);
    start_navigating();
    note_start();
    uint64_t true_us = 0u;
    for (int k = 0; k < 30 * RATE_HZ; k++) {
        /* the first stamp has no interval yet: the nominal period, here also the true one */
        const uint32_t dt = k == 0 ? PERIOD_US : jittered_dt_us();
        if (k == 0) {
            first_dt_us = dt;
        }
        src_sample(dt);
        true_us += dt;
    }
    nav_error_m(horiz, vert);
    return true_us;
}

/*
 * GIVEN a tilted IMU standing still, sampled at 96.15 Hz mean with +-1.5 ms of jitter per
 *       sample (a 100 Hz configuration), each sample's exact increments over its own
 *       interval and its IMU_Time stamp
 * WHEN navigated for 30 s, stamped
 * THEN the IMU time is the stamps' (the first sample counts the nominal 10 ms, as it has
 *      no interval yet: the stream's first interval is 10 ms), nothing is refused, and the
 *      navigator stays where the analytic solution (standing still) has it: within 2 cm
 *      horizontally and vertically, as the grid's still-vehicle tests hold (test_app.c;
 *      measured 0.0000 m and 0.0004 m);
 * AND the same stream on the grid (every sample taken for 10 ms) is measurably wrong: its
 *      velocity increments, 4 % longer than 10 ms, read as 4 % more gravity, 0.39 m/s^2
 *      up, 0.5 * 0.39 * 30^2 = 176 m in 30 s undamped (measured 140 m): more than 1 m.
 */
static void test_stamped_dt_exact_on_jittered_stream(void **state)
{
    (void)state;
    double h_st, v_st, h_grid, v_grid;
    const uint64_t true_us = run_jittered(IMU_TIME_STAMPED, &h_st, &v_st);
    assert_int_equal(app_samples(&app), 30u * RATE_HZ);
    assert_int_equal(app_time_us(&app), true_us - first_dt_us + PERIOD_US);
    assert_int_equal(app.keep.health.bad_value, 0u);
    assert_int_equal(app.keep.health.imu_timing, 0u);
    assert_int_equal(app.keep.health.nav_rejected, 0u);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
    print_message("[imu_time] stamped, 30 s jittered: horizontal %.4f m, vertical %.4f m\n",
                  h_st, v_st);
    assert_true(h_st < 0.02);
    assert_true(v_st < 0.02);

    (void)run_jittered(IMU_TIME_GRID, &h_grid, &v_grid);
    print_message("[imu_time] grid, same stream: horizontal %.4f m, vertical %.4f m\n", h_grid,
                  v_grid);
    assert_true(v_grid > 1.0);
}

/* n still samples of the nominal period, stamped */
static void run_nominal(int n)
{
    for (int k = 0; k < n; k++) {
        src_sample(PERIOD_US);
    }
}

/* one still sample of dt_us whose IMU_Time says stamp_us and carries stamp_counter */
static void odd_sample(uint32_t dt_us, int stamp_counter, uint32_t stamp_us)
{
    int32_t w[3], v[3];
    src_next(dt_us, w, v);
    src.stamp_us += dt_us;
    hal.t_us += dt_us;
    send_sample(w, v, src.counter, stamp_counter, stamp_us);
    src.counter = e2e_counter_next(src.counter);
}

/*
 * GIVEN a stamped stream navigating
 * WHEN a sample's stamp goes back 5 ms before the previous sample's (and one repeats it)
 * THEN each is refused, counted in bad_value and imu_timing, flagged REJECTED, and the
 *      next good sample bridges it as a lost one: the IMU time advances by the stamps
 *      exactly, the sample count as the counter says.
 */
static void test_backward_stamp_refused(void **state)
{
    (void)state;
    fresh(IMU_TIME_STAMPED);
    src_init(1000000u);
    start_navigating();
    run_nominal(10);
    const uint64_t n0 = app_samples(&app), t0 = app_time_us(&app);
    const uint32_t last = src.stamp_us;
    odd_sample(PERIOD_US, src.counter, last - 5000u); /* back */
    assert_int_equal(app.keep.health.imu_timing, 1u);
    assert_int_equal(app.keep.health.bad_value, 1u);
    assert_int_equal(app_samples(&app), n0);
    odd_sample(PERIOD_US, src.counter, last); /* the same stamp again: not after it */
    assert_int_equal(app.keep.health.imu_timing, 2u);
    run_nominal(1);
    assert_int_equal(app.keep.health.imu_timing, 2u);
    assert_int_equal(app.keep.health.imu_lost, 2u); /* the two refused, bridged */
    assert_int_equal(app_samples(&app), n0 + 3u);
    assert_int_equal(app_time_us(&app), t0 + 3u * PERIOD_US);
    assert_true(app.run.events.reject.seen); /* REJECTED */
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);
}

/*
 * GIVEN a stamped stream navigating
 * WHEN a sample's interval is 2.2 periods with the counter stepping by one (outside the
 *      0.5..1.5 band), or 0.3 periods
 * THEN it is refused and counted;
 * WHEN 17 samples are lost (the counter steps by 3, 18 mod 15) and the stamps show 18
 *      periods
 * THEN the stamps count the whole counter cycle the counter cannot see: 17 lost, bridged
 *      (170 ms, within the 200 ms bridge), the IMU time exact;
 * WHEN the IMU's clock jumps back for good
 * THEN the third refusal in a row restarts the stamps' time base (a time jump, counted)
 *      and navigation re-acquires, as after a gap too long to bridge.
 */
static void test_gap_and_band(void **state)
{
    (void)state;
    fresh(IMU_TIME_STAMPED);
    src_init(5000000u);
    start_navigating();
    run_nominal(10);
    uint64_t n0 = app_samples(&app), t0 = app_time_us(&app);
    odd_sample(PERIOD_US, src.counter, src.stamp_us + 22000u); /* 2.2 periods after */
    assert_int_equal(app.keep.health.imu_timing, 1u);
    assert_int_equal(app_samples(&app), n0);
    run_nominal(1);
    assert_int_equal(app_samples(&app), n0 + 2u);
    assert_int_equal(app_time_us(&app), t0 + 2u * PERIOD_US);
    n0 = app_samples(&app);
    t0 = app_time_us(&app);
    odd_sample(3000u, src.counter, src.stamp_us + 3000u); /* 0.3 periods */
    assert_int_equal(app.keep.health.imu_timing, 2u);
    run_nominal(1);
    assert_int_equal(app_time_us(&app), t0 + 13000u);
    assert_int_equal(app_samples(&app), n0 + 2u); /* one refused, bridged: 6.5 ms each */

    /* 17 samples lost: the counter sees 2 of them */
    const uint64_t lost0 = app.keep.health.imu_lost;
    n0 = app_samples(&app);
    t0 = app_time_us(&app);
    for (int k = 0; k < 17; k++) {
        int32_t w[3], v[3];
        src_next(PERIOD_US, w, v);
        src.stamp_us += PERIOD_US;
        hal.t_us += PERIOD_US;
        src.counter = e2e_counter_next(src.counter);
    }
    run_nominal(1);
    assert_int_equal(app.keep.health.imu_lost - lost0, 17u);
    assert_int_equal(app_samples(&app), n0 + 18u);
    assert_int_equal(app_time_us(&app), t0 + 18u * PERIOD_US);
    assert_int_equal(app.run.mode, APP_MODE_NAVIGATING);

    /* the clock jumps back 1 s for good */
    const uint32_t jumps0 = app.keep.health.time_jumps;
    src.stamp_us -= 1000000u;
    run_nominal(2);
    assert_int_equal(app.keep.health.imu_timing, 4u);
    assert_int_equal(app.keep.health.time_jumps, jumps0);
    run_nominal(1);
    assert_int_equal(app.keep.health.imu_timing, 4u); /* the third: taken, a restart */
    assert_int_equal(app.keep.health.time_jumps, jumps0 + 1u);
    assert_int_equal(app.run.mode, APP_MODE_FAULT);
    assert_true(app.run.align.reacquire);
    t0 = app_time_us(&app);
    run_nominal(5);
    assert_int_equal(app_time_us(&app), t0 + 5u * PERIOD_US); /* the new time base */
    assert_int_equal(app.keep.health.imu_timing, 4u);
}

/*
 * GIVEN a stamped stream whose u32 microsecond clock is 50 ms before its wrap
 * WHEN it runs 10 s, across the wrap, jittered
 * THEN every interval is taken exactly (modulo 2^32): the IMU time is the true one and
 *      nothing is refused.
 */
static void test_wrap_of_the_u32_clock(void **state)
{
    (void)state;
    fresh(IMU_TIME_STAMPED);
    src_init(UINT32_MAX - 50000u);
    start_navigating();
    uint64_t true_us = 0u;
    for (int k = 0; k < 10 * RATE_HZ; k++) {
        const uint32_t dt = jittered_dt_us();
        src_sample(dt);
        true_us += k == 0 ? PERIOD_US : dt;
    }
    assert_true(src.stamp_us < 20000000u); /* it wrapped */
    assert_int_equal(app_time_us(&app), true_us);
    assert_int_equal(app.keep.health.imu_timing, 0u);
    assert_int_equal(app.keep.health.bad_value, 0u);
    assert_int_equal(app.keep.health.time_jumps, 0u);
}

/*
 * GIVEN a stamped stream
 * WHEN a sample comes with the IMU_Time of another counter, or with none
 * THEN it is refused (its time unknown), counted, and bridged by the next sample;
 * AND on the grid, IMU_Time frames (even nonsense ones) change nothing.
 */
static void test_stamp_of_another_counter(void **state)
{
    (void)state;
    fresh(IMU_TIME_STAMPED);
    src_init(0u);
    start_navigating();
    run_nominal(5);
    const uint64_t n0 = app_samples(&app), t0 = app_time_us(&app);
    odd_sample(PERIOD_US, e2e_counter_next(src.counter), src.stamp_us + PERIOD_US);
    assert_int_equal(app.keep.health.imu_timing, 1u);
    odd_sample(PERIOD_US, -1, 0u);
    assert_int_equal(app.keep.health.imu_timing, 2u);
    assert_int_equal(app_samples(&app), n0);
    run_nominal(1);
    assert_int_equal(app_samples(&app), n0 + 3u);
    assert_int_equal(app_time_us(&app), t0 + 3u * PERIOD_US);

    /* the grid: IMU_Time ignored */
    fresh(IMU_TIME_GRID);
    src_init(0u);
    start_navigating();
    for (int k = 0; k < 20; k++) {
        odd_sample(PERIOD_US, (k * 7) % 15, (uint32_t)k * 977u);
    }
    assert_int_equal(app_samples(&app), 20u);
    assert_int_equal(app_time_us(&app), 20u * PERIOD_US);
    assert_int_equal(app.keep.health.imu_timing, 0u);
    assert_int_equal(app.keep.health.bad_value, 0u);
}

/*
 * The rate check, stamped: it compares the samples counted with the stamps' time of them.
 * GIVEN stamps 8 ms apart (125 Hz) with 100 Hz configured (within the stamps' band) and
 *       GNSS epochs every second
 * THEN the mismatch is found at the third epoch (two intervals), measured 125.00 Hz;
 * GIVEN 10 ms stamps against epochs whose TimeOfWeek says 1.3 s and 0.7 s (late epochs)
 * THEN the stamps' rate is on-rate.
 */
static void test_rate_check_uses_the_stamps(void **state)
{
    (void)state;
    imu_rate_t r;
    imu_rate_init(&r);
    uint32_t tow = 100000u;
    assert_int_equal(imu_rate_epoch(&r, 100u, tow), IMU_RATE_SAME);
    for (int e = 1; e <= 2; e++) {
        for (int k = 0; k < 125; k++) {
            imu_rate_sample(&r, 0u, 0u);
            imu_rate_stamp(&r, 8000u);
        }
        tow += 1000u;
        assert_int_equal(imu_rate_epoch(&r, 100u, tow), e == 2 ? IMU_RATE_MISMATCH : IMU_RATE_SAME);
    }
    assert_int_equal(imu_rate_measured_chz(&r), 12500u);

    imu_rate_init(&r);
    tow = 100000u;
    (void)imu_rate_epoch(&r, 100u, tow);
    const uint32_t tow_step[4] = {1300u, 700u, 1300u, 700u};
    for (int e = 0; e < 4; e++) {
        for (int k = 0; k < 100; k++) {
            imu_rate_sample(&r, 0u, 0u);
            imu_rate_stamp(&r, 10000u);
        }
        tow += tow_step[e];
        assert_int_equal(imu_rate_epoch(&r, 100u, tow), IMU_RATE_SAME);
    }
    assert_false(imu_rate_mismatch(&r));
}

/*
 * GIVEN a 400 Hz IMU (stamps 2.5 ms apart) configured as 100 Hz, stamped
 * THEN the samples are refused for their interval (a quarter period, below the band) or,
 *      their counter then running ahead, for the counter, counted; one whose refused
 *      predecessors bring its interval into the band is taken, the refused ones bridged,
 *      so the IMU time stays the stamps' (never ahead of the IMU's clock), and the stamps'
 *      time base is never restarted (no time jump: a clock at another rate is the rate
 *      check's; measured 233 + 50 refused of 300, 49 samples taken with the bridged);
 * AND the rate check, counting the refused samples over the epochs' TimeOfWeek, finds
 *      400 Hz at the third epoch, as on the grid.
 */
static void test_wrong_rate_is_the_rate_checks(void **state)
{
    (void)state;
    fresh(IMU_TIME_STAMPED);
    src_init(0u);
    start_navigating();
    for (int k = 0; k < 300; k++) {
        src_sample(2500u);
    }
    print_message("[imu_time] 400 Hz stamps at 100 Hz: %u refused for the stamp, %u for the "
                  "counter, %llu samples taken\n", app.keep.health.imu_timing,
                  app.keep.health.bad_counter, (unsigned long long)app_samples(&app));
    assert_int_equal(app.keep.health.time_jumps, 0u);
    assert_true(app.keep.health.imu_timing + app.keep.health.bad_counter > 250u);
    assert_true(app_time_us(&app) <= PERIOD_US + 299u * 2500u);

    imu_rate_t r;
    imu_rate_init(&r);
    uint32_t tow = 200000u;
    (void)imu_rate_epoch(&r, 100u, tow);
    for (int e = 1; e <= 2; e++) {
        for (int k = 0; k < 400; k++) {
            imu_rate_refused(&r);
        }
        tow += 1000u;
        assert_int_equal(imu_rate_epoch(&r, 100u, tow), e == 2 ? IMU_RATE_MISMATCH : IMU_RATE_SAME);
    }
    assert_int_equal(imu_rate_measured_chz(&r), 40000u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stamped_dt_exact_on_jittered_stream),
        cmocka_unit_test(test_backward_stamp_refused),
        cmocka_unit_test(test_gap_and_band),
        cmocka_unit_test(test_wrap_of_the_u32_clock),
        cmocka_unit_test(test_stamp_of_another_counter),
        cmocka_unit_test(test_rate_check_uses_the_stamps),
        cmocka_unit_test(test_wrong_rate_is_the_rate_checks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
