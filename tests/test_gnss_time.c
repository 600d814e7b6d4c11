/*
 * test_gnss_time.c - gnss_time.h: the time of validity of a GNSS fix on the IMU time base.
 * The offset (IMU time - TimeOfWeek) against its running minimum, late epochs, receiver
 * clock jumps (three late epochs in a row, earlier by more than 1 s, later by more than
 * 10 s), the 50 ppm creep of the minimum, the reach of the velocity history, and the
 * displacement integral over it.
 *
 * IMU at 100 Hz: one history entry per sample (0.01 s), latency 0.1 s = 10 entries back.
 * An epoch of a receiver on time: sample n, TimeOfWeek = n * 10 ms + 100 s (offset -100 s).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "gnss_time.h"
#include "test_util.h"

#define RATE_HZ 100u
#define LATENCY_S 0.1f

static gnss_time_t g;

static int setup(void **state)
{
    (void)state;
    memset(&g, 0, sizeof g);
    return 0;
}

/* n history entries of a constant velocity */
static void record_constant(uint32_t n, float e, float north, float up)
{
    const nav_real_t v[3] = {e, north, up};
    for (uint32_t k = 1u; k <= n; k++) {
        gnss_time_record(&g, k, RATE_HZ, v);
    }
}

/* an epoch received after sample n, late_ms later than on time */
static gnss_when_t epoch(uint64_t n, int32_t late_ms)
{
    const int64_t tow = (int64_t)n * 10 + 100000 - late_ms;
    return gnss_time_align(&g, (uint64_t)(n) * 1000000u / (RATE_HZ), RATE_HZ, (uint32_t)tow, LATENCY_S);
}

/* GIVEN a first epoch THEN it sets the minimum: back = latency (10 entries); WHEN the next
 * is 0.3 s late THEN back = (0.1 + 0.3) / 0.01 = 40 entries (less the creep of 10 us over
 * 0.2 s: 39.999); WHEN the one after is on time again THEN 10. */
static void test_offset_minimum(void **state)
{
    (void)state;
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    gnss_when_t w = epoch(1000u, 0);
    assert_int_equal(w.jumped, 0);
    assert_near(w.entry_s, 0.01, 1e-9);
    assert_near(w.back, 10.0, 1e-4);
    assert_int_equal(w.in_history, 1);
    w = epoch(1020u, 300);
    assert_int_equal(w.jumped, 0);
    assert_near(w.back, 39.999, 1e-3);
    w = epoch(1040u, 0);
    assert_near(w.back, 10.0, 1e-4);
    /* an earlier epoch (0.1 s) lowers the minimum: it is the latency's reference now */
    w = epoch(1060u, -100);
    assert_int_equal(w.jumped, 0);
    assert_near(w.back, 10.0, 1e-4);
    w = epoch(1080u, 0); /* the old offset is now 0.1 s late */
    assert_near(w.back, 20.0, 2e-3);
}

/* A single epoch 0.6 s late: not a jump, its lateness is added (back 70: beyond the
 * history's 64 entries, so not in history). */
static void test_late_epoch(void **state)
{
    (void)state;
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    (void)epoch(1000u, 0);
    const gnss_when_t w = epoch(1020u, 600);
    assert_int_equal(w.jumped, 0);
    assert_near(w.back, 69.999, 1e-3);
    assert_int_equal(w.in_history, 0);
}

/* GIVEN three epochs in a row later than the minimum by more than 0.5 s THEN the third is
 * a clock jump: the minimum restarts from it (back 10 again); two late, one on time, two
 * late is no jump. */
static void test_three_late_epochs_are_a_jump(void **state)
{
    (void)state;
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    (void)epoch(1000u, 0);
    assert_int_equal(epoch(1020u, 600).jumped, 0);
    assert_int_equal(epoch(1040u, 600).jumped, 0);
    const gnss_when_t w = epoch(1060u, 600);
    assert_int_equal(w.jumped, 1);
    assert_near(w.back, 10.0, 1e-4);
    assert_near(epoch(1080u, 600).back, 10.0, 1e-3); /* the new offset is on time */

    memset(&g, 0, sizeof g);
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    (void)epoch(1000u, 0);
    assert_int_equal(epoch(1020u, 600).jumped, 0);
    assert_int_equal(epoch(1040u, 600).jumped, 0);
    assert_int_equal(epoch(1060u, 0).jumped, 0);
    assert_int_equal(epoch(1080u, 600).jumped, 0);
    assert_int_equal(epoch(1100u, 600).jumped, 0);
}

/* Earlier by more than 1 s: a jump at once; by 0.9 s: a new minimum, not a jump. Later by
 * more than 10 s: a jump at once. */
static void test_early_and_very_late_jumps(void **state)
{
    (void)state;
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    (void)epoch(1000u, 0);
    gnss_when_t w = epoch(1020u, -900);
    assert_int_equal(w.jumped, 0);
    assert_near(w.back, 10.0, 1e-4);
    w = epoch(1040u, -2000); /* 1.1 s earlier than the minimum now (-0.9 s) */
    assert_int_equal(w.jumped, 1);
    assert_near(w.back, 10.0, 1e-4);
    w = epoch(1060u, 10100 - 2000); /* 10.1 s later than it */
    assert_int_equal(w.jumped, 1);
    assert_near(w.back, 10.0, 1e-4);
}

/* The minimum creeps by 50 ppm of IMU time: over 1000 s, 50 ms. GIVEN an epoch at 10 s
 * WHEN the next at 1010 s is 50 ms later THEN that is drift, not lateness (back 10);
 * 60 ms later: 10 ms late (back 11). */
static void test_50_ppm_creep(void **state)
{
    (void)state;
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    (void)epoch(1000u, 0);
    gnss_time_t saved = g;
    assert_near(epoch(101000u, 50).back, 10.0, 1e-3);
    g = saved;
    assert_near(epoch(101000u, 60).back, 11.0, 1e-3);
}

/* in_history: the history must hold the entry before the one back reaches (m + 1 entries
 * with m = floor(back)) and stay within its 64 entries; before_history: only the first
 * fails (the epoch is valid before the navigation's history starts: the independent
 * client's finding that a correct epoch at each navigation start counted as rejected). */
static void test_history_reach(void **state)
{
    (void)state;
    record_constant(11u, 0.0f, 0.0f, 0.0f);
    gnss_when_t young = epoch(1000u, 0);
    assert_int_equal(young.in_history, 0); /* back 10: 11 < 11 fails */
    /* valid before the history began (navigation started 0.11 s ago): not a late fix */
    assert_int_equal(young.before_history, 1);
    memset(&g, 0, sizeof g);
    record_constant(12u, 0.0f, 0.0f, 0.0f);
    assert_int_equal(epoch(1000u, 0).in_history, 1);
    memset(&g, 0, sizeof g);
    record_constant(200u, 0.0f, 0.0f, 0.0f);
    assert_int_equal(gnss_time_align(&g, (uint64_t)(1000u) * 1000000u / (RATE_HZ), RATE_HZ, 5000u, 0.625f).in_history, 1); /* 62.5 */
    memset(&g, 0, sizeof g);
    record_constant(200u, 0.0f, 0.0f, 0.0f);
    const gnss_when_t late =
        gnss_time_align(&g, (uint64_t)(1000u) * 1000000u / (RATE_HZ), RATE_HZ, 5000u, 0.635f);
    assert_int_equal(late.in_history, 0); /* 63.5: beyond the 64 entries */
    assert_int_equal(late.before_history, 0); /* too late for any history: a refusal */
    /* forgotten: nothing in history */
    gnss_time_forget(&g);
    assert_int_equal(epoch(1020u, 0).in_history, 0);
}

/* At most 100 entries a second: 200 Hz records every second sample, 400 Hz every fourth,
 * 150 Hz every second (2/150 s an entry). */
static void test_history_decimation(void **state)
{
    (void)state;
    const nav_real_t v[3] = {0.0f, 0.0f, 0.0f};
    for (uint64_t n = 1u; n <= 20u; n++) {
        gnss_time_record(&g, n, 200u, v);
    }
    assert_int_equal(g.vhist_n, 10u);
    memset(&g, 0, sizeof g);
    for (uint64_t n = 1u; n <= 20u; n++) {
        gnss_time_record(&g, n, 400u, v);
    }
    assert_int_equal(g.vhist_n, 5u);
    assert_near(gnss_time_align(&g, (uint64_t)(4000u) * 1000000u / (400u), 400u, 5000u, 0.1f).entry_s, 0.01, 1e-9);
    assert_near(gnss_time_align(&g, (uint64_t)(3000u) * 1000000u / (150u), 150u, 15000u, 0.1f).entry_s, 2.0 / 150.0, 1e-9);
}

/* GIVEN a constant velocity (10, -5, 0.5) m/s WHEN the fix is 0.105 s old (10.5 entries)
 * THEN the displacement since is v * 0.105 s = (1.05, -0.525, 0.0525) m. */
static void test_displacement_of_constant_velocity(void **state)
{
    (void)state;
    record_constant(30u, 10.0f, -5.0f, 0.5f);
    const gnss_when_t w = gnss_time_align(&g, (uint64_t)(1000u) * 1000000u / (RATE_HZ), RATE_HZ, 5000u, 0.105f);
    assert_int_equal(w.in_history, 1);
    nav_real_t d[3];
    gnss_time_displacement(&g, &w, d);
    assert_near(d[0], 1.05, 1e-5);
    assert_near(d[1], -0.525, 1e-5);
    assert_near(d[2], 0.0525, 1e-6);
}

/* GIVEN entries whose east velocity is their index (0..19 m/s) WHEN 2.5 entries back
 * THEN the displacement is 0.01 (19 + 18) + 0.5 * 0.01 * 17 = 0.455 m (latest first, the
 * fraction on the oldest), and the velocity then is the nearest entry's: 2.6 back -> 16,
 * 2.4 back -> 17. */
static void test_displacement_and_velocity_then(void **state)
{
    (void)state;
    for (uint32_t k = 0u; k < 20u; k++) {
        const nav_real_t v[3] = {(nav_real_t)k, 0.0f, 0.0f};
        gnss_time_record(&g, k, RATE_HZ, v);
    }
    gnss_when_t w = gnss_time_align(&g, (uint64_t)(1000u) * 1000000u / (RATE_HZ), RATE_HZ, 5000u, 0.025f);
    nav_real_t d[3];
    gnss_time_displacement(&g, &w, d);
    assert_near(d[0], 0.455, 1e-5);
    assert_near(d[1], 0.0, 0.0);
    w = gnss_time_align(&g, (uint64_t)(1000u) * 1000000u / (RATE_HZ), RATE_HZ, 5000u, 0.026f);
    assert_near(gnss_time_velocity_then(&g, &w)[0], 16.0, 0.0);
    w = gnss_time_align(&g, (uint64_t)(1000u) * 1000000u / (RATE_HZ), RATE_HZ, 5000u, 0.024f);
    assert_near(gnss_time_velocity_then(&g, &w)[0], 17.0, 0.0);
}

/* A drive accelerating at 2 m/s^2 east from sample 1, the receiver's epochs (5 Hz) true
 * latency_s before their arrival: the velocity history is the navigator's, exact. Returns
 * the latency in use after `epochs` epochs, learnt with the parameter at cfg_s. */
static float learn_ramp(float latency_s, float cfg_s, uint32_t epochs, float accel_mps2)
{
    const float dt = 1.0f / (float)RATE_HZ;
    uint64_t n = 0u;
    for (uint32_t e = 0u; e < epochs; e++) {
        for (uint32_t k = 0u; k < RATE_HZ / 5u; k++) {
            n++;
            const nav_real_t v[3] = {accel_mps2 * dt * (float)n, 0.0f, 0.0f};
            gnss_time_record(&g, n, RATE_HZ, v);
        }
        /* the fix's time of validity is latency_s before the arrival */
        const float t_valid_s = dt * (float)n - latency_s;
        const int64_t tow_ms = 100000 + (int64_t)(t_valid_s * 1000.0f + (t_valid_s >= 0.0f ? 0.5f : -0.5f));
        gnss_when_t w = gnss_time_align(&g, n * 1000000u / RATE_HZ, RATE_HZ, (uint32_t)tow_ms,
                                         gnss_time_latency(&g, cfg_s));
        const nav_real_t vg[3] = {accel_mps2 * t_valid_s, 0.0f, 0.0f};
        (void)gnss_time_learn(&g, &w, vg, 0.05f, cfg_s);
    }
    return gnss_time_latency(&g, cfg_s);
}

/* GIVEN fixes on time (latency 0) or 0.3 s late, the parameter saying 0.1 s WHEN the car
 * accelerates THEN the latency in use is the true one within the 10 ms grid after 10
 * epochs (2 s); the parameter's own 0.1 s is kept when it is right. Before the fix the
 * parameter was always used (0.1 s: a 0.1 or 0.2 s error, 2 m/s^2 x that in velocity). */
static void test_latency_learnt_from_acceleration(void **state)
{
    (void)state;
    assert_near(learn_ramp(0.0f, 0.1f, 10u, 2.0f), 0.0, 0.0051);
    memset(&g, 0, sizeof g);
    assert_near(learn_ramp(0.3f, 0.1f, 10u, 2.0f), 0.3, 0.0051);
    memset(&g, 0, sizeof g);
    assert_near(learn_ramp(0.1f, 0.1f, 50u, 2.0f), 0.1f, 0.0);
    assert_int_equal(g.lat_learnt, 0); /* never contradicted: the parameter stays */
}

/* GIVEN a constant velocity (no information on the latency) THEN the parameter stays. */
static void test_latency_not_learnt_without_dynamics(void **state)
{
    (void)state;
    assert_near(learn_ramp(0.0f, 0.1f, 100u, 0.0f), 0.1f, 0.0);
    assert_int_equal(g.lat_learnt, 0);
}

/* GIVEN a learnt latency WHEN the receiver's clock jumps THEN it is forgotten. */
static void test_latency_forgotten_at_time_jump(void **state)
{
    (void)state;
    assert_near(learn_ramp(0.0f, 0.1f, 10u, 2.0f), 0.0, 0.0051);
    gnss_when_t w = gnss_time_align(&g, 1000000000u, RATE_HZ, 10u, 0.0f); /* 1000 s later, TOW back */
    assert_int_equal(w.jumped, 1);
    assert_near(gnss_time_latency(&g, 0.1f), 0.1f, 0.0);
}

/* GIVEN epochs on time and a learnt latency WHEN the time of week passes the week's end
 * (604 799.8 and .9 s, then 0.0 and 0.1 s, 0.1 s of IMU time apart) THEN no epoch is a
 * jump, each is on time and the latency stays learnt; before, the offset stepped by a
 * week at 0.0 s: counted as a receiver clock jump, the latency forgotten. */
static void test_week_rollover_is_no_jump(void **state)
{
    (void)state;
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    const uint64_t t0_us = 1000000000u;
    const uint32_t tow0_ms = APP_WEEK_MS - 200u;
    assert_int_equal(gnss_time_align(&g, t0_us, RATE_HZ, tow0_ms, 0.0f).jumped, 0);
    g.lat_learnt = 1u; /* as if learnt: a jump would clear it */
    for (uint32_t k = 1u; k <= 3u; k++) {
        const uint32_t tow_ms = (tow0_ms + 100u * k) % APP_WEEK_MS;
        const gnss_when_t w = gnss_time_align(&g, t0_us + 100000u * k, RATE_HZ, tow_ms, 0.0f);
        assert_int_equal(w.jumped, 0);
        assert_near(w.late_s, 0.0, 1e-4);
    }
    assert_int_equal(g.lat_learnt, 1);
    const gnss_when_t p = gnss_time_peek(&g, t0_us + 400000u, RATE_HZ, 200u, 0.0f);
    assert_near(p.late_s, 0.0, 1e-4);
}

/* GIVEN week 2000 and an epoch 0.2 s before its end WHEN the next epochs are of week 2001
 * (TimeOfWeek from 0) THEN NAV_Time's time is that week's: week 2001, 0.1 s after an epoch
 * at 0.0 s; before the minimum followed the week, it said week 2002 (a review's finding). */
static void test_week_rollover_keeps_the_weeks_time(void **state)
{
    (void)state;
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    const uint64_t t0_us = 1000000000u;
    gnss_time_week(&g, 2000u);
    (void)gnss_time_align(&g, t0_us, RATE_HZ, APP_WEEK_MS - 200u, 0.0f);
    uint64_t tow_us;
    uint16_t week;
    assert_int_equal(gnss_time_at(&g, t0_us + 100000u, 0.0f, &tow_us, &week), 0);
    assert_int_equal(week, 2000u);
    assert_int_equal(tow_us, (uint64_t)(APP_WEEK_MS - 100u) * 1000u);
    gnss_time_week(&g, 2001u);
    assert_int_equal(gnss_time_align(&g, t0_us + 200000u, RATE_HZ, 0u, 0.0f).jumped, 0);
    assert_int_equal(gnss_time_at(&g, t0_us + 300000u, 0.0f, &tow_us, &week), 0);
    assert_int_equal(week, 2001u);
    assert_int_equal(tow_us, 100000u);
}

/* GIVEN epochs on time WHEN one arrives while 3 IMU samples are lost (the last sample
 * before it 30 ms old: it looks 30 ms early and lowers the minimum) and the next sample
 * reveals the gap THEN the minimum is the one before it: the next on-time epoch is on time
 * (back 10), not 30 ms late (back 13); WHEN an early epoch is followed by a sample without
 * a gap THEN its minimum stays (a receiver that was early). */
static void test_epoch_in_an_imu_gap_sets_no_minimum(void **state)
{
    (void)state;
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    (void)epoch(1000u, 0);
    gnss_time_imu_next(&g, 0);
    (void)epoch(1097u, -30); /* received after sample 1100; the last processed is 1097 */
    gnss_time_imu_next(&g, 1); /* sample 1101 reveals 1098..1100 lost */
    gnss_when_t w = epoch(1200u, 0);
    gnss_time_imu_next(&g, 0);
    assert_near(w.back, 10.0, 1e-2);
    (void)epoch(1300u, -30); /* a receiver 30 ms early, no gap */
    gnss_time_imu_next(&g, 0);
    gnss_time_imu_next(&g, 1); /* a later gap does not undo it */
    w = epoch(1400u, -30);
    assert_near(w.back, 10.0, 1e-2);
}

/* Two epochs (a 10 Hz receiver) in one IMU gap: both looked early (the second by more);
 * the next epoch after the gap sets the minimum (a review: the first version restored only
 * the last epoch's, the first's lowered one, and left every later epoch 30 ms late). */
static void test_two_epochs_in_one_imu_gap(void **state)
{
    (void)state;
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    (void)epoch(1000u, 0);
    gnss_time_imu_next(&g, 0);
    (void)epoch(1097u, -30);  /* arrived after sample 1100, the last processed 1097 */
    (void)epoch(1097u, -130); /* arrived after sample 1110 */
    gnss_time_imu_next(&g, 1); /* sample 1116 reveals the loss */
    gnss_when_t w = epoch(1200u, 0);
    gnss_time_imu_next(&g, 0);
    assert_near(w.back, 10.0, 1e-2);
    w = epoch(1300u, 0);
    assert_near(w.back, 10.0, 1e-2);
}

/* A clock jump (1.5 s earlier) whose epoch came in an IMU gap: counted once, the next
 * epochs on the new clock on time; a first epoch in a gap keeps NAV_Time (a review: the
 * first version counted the jump twice and lost NAV_Time until the next epoch). */
static void test_jump_or_first_epoch_in_an_imu_gap(void **state)
{
    (void)state;
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    (void)epoch(1000u, 0);
    gnss_time_imu_next(&g, 0);
    gnss_when_t w = epoch(1100u, -1500);
    int jumps = w.jumped;
    gnss_time_imu_next(&g, 1);
    w = epoch(1110u, -1500);
    jumps += w.jumped;
    gnss_time_imu_next(&g, 0);
    w = epoch(1120u, -1500);
    jumps += w.jumped;
    assert_int_equal(jumps, 1);
    assert_near(w.back, 10.0, 1e-2);

    memset(&g, 0, sizeof g);
    record_constant(64u, 0.0f, 0.0f, 0.0f);
    (void)epoch(1097u, -30);
    gnss_time_imu_next(&g, 1);
    uint64_t tow_us;
    uint16_t week;
    assert_int_equal(gnss_time_at(&g, 1101u * 10000u, 0.1f, &tow_us, &week), 0);
    w = epoch(1200u, 0);
    assert_near(w.back, 10.0, 1e-2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_offset_minimum, setup),
        cmocka_unit_test_setup(test_late_epoch, setup),
        cmocka_unit_test_setup(test_three_late_epochs_are_a_jump, setup),
        cmocka_unit_test_setup(test_early_and_very_late_jumps, setup),
        cmocka_unit_test_setup(test_50_ppm_creep, setup),
        cmocka_unit_test_setup(test_history_reach, setup),
        cmocka_unit_test_setup(test_history_decimation, setup),
        cmocka_unit_test_setup(test_displacement_of_constant_velocity, setup),
        cmocka_unit_test_setup(test_displacement_and_velocity_then, setup),
        cmocka_unit_test_setup(test_latency_learnt_from_acceleration, setup),
        cmocka_unit_test_setup(test_latency_not_learnt_without_dynamics, setup),
        cmocka_unit_test_setup(test_latency_forgotten_at_time_jump, setup),
        cmocka_unit_test_setup(test_week_rollover_is_no_jump, setup),
        cmocka_unit_test_setup(test_week_rollover_keeps_the_weeks_time, setup),
        cmocka_unit_test_setup(test_epoch_in_an_imu_gap_sets_no_minimum, setup),
        cmocka_unit_test_setup(test_two_epochs_in_one_imu_gap, setup),
        cmocka_unit_test_setup(test_jump_or_first_epoch_in_an_imu_gap, setup),
    };
    return cmocka_run_group_tests_name("gnss_time", tests, NULL, NULL);
}
