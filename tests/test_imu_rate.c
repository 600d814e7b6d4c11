/*
 * test_imu_rate.c - imu_rate.h: the configured IMU rate against the samples counted
 * between GNSS epochs by their TimeOfWeek. Mismatches found at the third epoch (the first
 * with two intervals) for 400 Hz data configured as 100 Hz and the reverse; never for a
 * correct rate through lost samples, missing, late and repeated epochs, receiver clock
 * jumps (forward, back, with a late epoch after), the week's end, 50 ppm of drift and IMU
 * silences; the exact boundaries of an interval's 5 % + 2 samples and of a run's
 * allowance; the end of a mismatch; the measured rate.
 *
 * An epoch "on time" after k samples of rate R: TimeOfWeek advanced by k / R exactly.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app_tuning.h"
#include "imu_rate.h"

static imu_rate_t r;
static uint32_t tow; /* ms */

static int setup(void **state)
{
    (void)state;
    imu_rate_init(&r);
    tow = 100000u;
    return 0;
}

/* n samples received, none lost */
static void samples(uint32_t n)
{
    for (uint32_t k = 0u; k < n; k++) {
        imu_rate_sample(&r, 0u, 0u);
    }
}

/* an epoch dt_ms after the last, against the configured rate cfg_hz */
static imu_rate_change_t epoch(uint32_t dt_ms, uint32_t cfg_hz)
{
    tow = (tow + dt_ms) % 604800000u;
    return imu_rate_epoch(&r, cfg_hz, tow);
}

/* data at data_hz, GNSS at gnss_hz, configured cfg_hz: the epoch (1-based) at which the
 * mismatch is found, 0 if not within max_epochs */
static int epochs_to_detect(uint32_t data_hz, uint32_t gnss_hz, uint32_t cfg_hz, int max_epochs)
{
    imu_rate_init(&r);
    samples(37u); /* before the first epoch: not counted */
    if (epoch(0u, cfg_hz) != IMU_RATE_SAME) {
        return -1;
    }
    for (int e = 2; e <= max_epochs; e++) {
        samples(data_hz / gnss_hz);
        if (epoch(1000u / gnss_hz, cfg_hz) == IMU_RATE_MISMATCH) {
            return e;
        }
    }
    return 0;
}

/* GIVEN 400 Hz data configured as 100 Hz, and 100 Hz data configured as 400 Hz
 * THEN the mismatch is found at the third epoch with 1, 2 and 5 Hz GNSS (and 10 Hz for
 *      400 on 100); 100 on 400 at 10 Hz GNSS takes five epochs (0.4 s: 0.3 s of missing
 *      samples must exceed 5 % + 2 samples + the 0.25 s latency allowance); never at the
 *      second (one interval is no run); and correct rates are never flagged. */
static void test_detection_latency(void **state)
{
    (void)state;
    const uint32_t gnss[4] = {1u, 2u, 5u, 10u};
    for (int i = 0; i < 4; i++) {
        assert_int_equal(epochs_to_detect(400u, gnss[i], 100u, 50), 3);
        assert_int_equal(epochs_to_detect(100u, gnss[i], 400u, 50), gnss[i] == 10u ? 5 : 3);
        assert_int_equal(epochs_to_detect(100u, gnss[i], 100u, 200), 0);
        assert_int_equal(epochs_to_detect(400u, gnss[i], 400u, 200), 0);
        assert_int_equal(epochs_to_detect(10u, gnss[i], 10u, 200), 0);
    }
    /* the rates next to each other in use, at 1 Hz GNSS: 125 Hz on 100, 100 on 125, 200 on
     * 250 (20 % apart: 2 x 20 % of a second is beyond 5 % + 2 samples + 0.25 s) */
    assert_int_equal(epochs_to_detect(125u, 1u, 100u, 50), 3);
    assert_int_equal(epochs_to_detect(100u, 1u, 125u, 50), 3);
    assert_int_equal(epochs_to_detect(200u, 1u, 250u, 50), 3);
    /* the Kingston drive's 10 Hz IMU configured as the default 100 Hz */
    assert_int_equal(epochs_to_detect(10u, 1u, 100u, 50), 3);
}

/* The measured rate: the run's samples over its TimeOfWeek span, 0.01 Hz, while the
 * mismatch lasts (0 from the accessor without one). */
static void test_measured_rate(void **state)
{
    (void)state;
    assert_int_equal(epochs_to_detect(400u, 1u, 100u, 10), 3);
    assert_true(imu_rate_mismatch(&r));
    assert_int_equal(imu_rate_measured_chz(&r), 40000u);
    assert_int_equal(epochs_to_detect(100u, 5u, 400u, 10), 3);
    assert_int_equal(imu_rate_measured_chz(&r), 10000u);
    imu_rate_init(&r);
    assert_int_equal(imu_rate_measured_chz(&r), 0u);
}

/* One interval's boundary: 100 Hz, 1 s: 100 samples +- (5 % + 2) = 93..107 are on-rate;
 * two intervals of 108 (fast) agree, but 216 is within 200 + 10 + 2 + 25: no mismatch. */
static void test_interval_boundary(void **state)
{
    (void)state;
    (void)epoch(0u, 100u);
    samples(107u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.run_n, 0u);
    samples(93u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.run_n, 0u);
    samples(108u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.run_n, 1u);
    assert_int_equal(r.run_dir, 1);
    samples(92u); /* off-rate the other way: a new run */
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.run_n, 1u);
    assert_int_equal(r.run_dir, -1);
    samples(108u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(108u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.run_n, 2u);
    assert_false(imu_rate_mismatch(&r));
}

/* A run's boundary: 100 Hz, two 1 s intervals: allowance 2 x 100 x 5 % + 2 + 100 x 0.25 s
 * = 37 samples; a run of 2 x 118 + 1 = 237 (rates 118 and 119 agree) is 37 off: no
 * mismatch; 238 is 38 off: found. Slow side alike: 163 no, 162 yes. */
static void test_run_boundary(void **state)
{
    (void)state;
    (void)epoch(0u, 100u);
    samples(118u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(119u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.run_n, 2u);
    assert_false(imu_rate_mismatch(&r));
    setup(NULL);
    (void)epoch(0u, 100u);
    samples(119u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(119u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_MISMATCH);
    setup(NULL);
    (void)epoch(0u, 100u);
    samples(82u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(81u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_false(imu_rate_mismatch(&r));
    setup(NULL);
    (void)epoch(0u, 100u);
    samples(81u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(81u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_MISMATCH);
}

/* Off-rate intervals whose rates disagree form no run: 150 then 130 samples per second
 * (20 apart: more than 5 % + 2 samples a side) each restart it; 150 then 146 agree. */
static void test_run_needs_one_rate(void **state)
{
    (void)state;
    (void)epoch(0u, 100u);
    samples(150u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(130u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.run_n, 1u);
    samples(150u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.run_n, 1u);
    samples(146u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_MISMATCH);
}

/* Lost samples counted by the IMU counter are samples: 400 Hz with 3 of every 20 lost
 * (15 %, and one gap of 14) is on rate; the same counted without them would be slow. */
static void test_lost_samples_counted(void **state)
{
    (void)state;
    (void)epoch(0u, 400u);
    for (int e = 0; e < 100; e++) {
        for (int k = 0; k < 20; k++) {
            if (k % 20 == 0) {
                imu_rate_sample(&r, 3u, 0u); /* this one after 3 lost */
            } else if (k % 20 < 17) {
                imu_rate_sample(&r, 0u, 0u);
            }
        }
        /* 20 per 50 ms: 17 received + 3 lost */
        assert_int_equal(epoch(50u, 400u), IMU_RATE_SAME);
        assert_false(imu_rate_mismatch(&r));
        if (e == 50) {
            imu_rate_sample(&r, 14u, 0u); /* after 14 lost: the counter's longest gap */
            samples(5u);
            assert_int_equal(epoch(50u, 400u), IMU_RATE_SAME);
            assert_int_equal(r.ok_n, 52u);
        }
    }
}

/* Missing epochs: intervals of 1, 3 and 7 s at the right rate are on-rate; at the wrong
 * rate they are one run (the rate agrees whatever the interval). */
static void test_missing_epochs(void **state)
{
    (void)state;
    (void)epoch(0u, 100u);
    const uint32_t gaps_s[5] = {1u, 3u, 1u, 7u, 1u};
    for (int i = 0; i < 5; i++) {
        samples(100u * gaps_s[i]);
        assert_int_equal(epoch(1000u * gaps_s[i], 100u), IMU_RATE_SAME);
        assert_int_equal(r.run_n, 0u);
    }
    setup(NULL);
    (void)epoch(0u, 100u);
    samples(400u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(1200u);
    assert_int_equal(epoch(3000u, 100u), IMU_RATE_MISMATCH);
}

/* Late epochs: one epoch 0.6 s late at 1 Hz (the fault drives' spike), one 0.9 s late
 * (just before the next), never a mismatch (a long interval, then a short one); a latency
 * growing by 0.1 s per epoch for two epochs (0.2 s) is within the allowance (0.25 s + 5 %
 * + 2 samples = 0.37 s over two intervals). A steady growth of 0.2 s per epoch over two
 * (0.4 s) looks like a rate 20 % off: found (the limit of what two intervals can tell). */
static void test_late_epochs(void **state)
{
    (void)state;
    (void)epoch(0u, 100u);
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(160u); /* received 0.6 s late */
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(40u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(190u); /* 0.9 s late */
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(10u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_false(imu_rate_mismatch(&r));
    samples(110u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(110u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(80u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_false(imu_rate_mismatch(&r));
    samples(120u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(120u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_MISMATCH);
}

/* Receiver clock jumps: TimeOfWeek +10 s for good (one slow interval), -10 s for good (a
 * step back: the measurement restarts), +10 s followed by an epoch 0.2 s early (two slow
 * intervals, but at rates 9 and 80 Hz that do not agree), +0.5 s then -0.5 s (a wrong
 * TimeOfWeek on one epoch): never a mismatch. */
static void test_clock_jumps(void **state)
{
    (void)state;
    (void)epoch(0u, 100u);
    samples(100u);
    assert_int_equal(epoch(11000u, 100u), IMU_RATE_SAME);
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(100u);
    assert_int_equal(epoch(604800000u - 9000u, 100u), IMU_RATE_SAME); /* -10 s: back */
    assert_int_equal(r.run_n, 0u);
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(100u);
    assert_int_equal(epoch(11000u, 100u), IMU_RATE_SAME);
    samples(80u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(120u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(100u);
    assert_int_equal(epoch(1500u, 100u), IMU_RATE_SAME);
    samples(100u);
    assert_int_equal(epoch(500u, 100u), IMU_RATE_SAME);
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_false(imu_rate_mismatch(&r));
}

/* The week's end: TimeOfWeek 604799.5 s -> 0.5 s is a 1 s interval. An interval of
 * 600 s is measured, one of 600.001 s restarts the measurement. */
static void test_week_end_and_longest_interval(void **state)
{
    (void)state;
    tow = 604798500u;
    (void)epoch(0u, 100u);
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(tow, 604799500u);
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(tow, 500u);
    assert_int_equal(r.ok_n, 2u);
    samples(60000u);
    assert_int_equal(epoch(APP_IMU_RATE_MAX_MS, 100u), IMU_RATE_SAME);
    assert_int_equal(r.ok_n, 3u);
    samples(60001u);
    assert_int_equal(epoch(APP_IMU_RATE_MAX_MS + 1u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.ok_n, 0u); /* not measured */
    assert_int_equal(r.count, 0u);
}

/* Drift: the IMU's clock 50 ppm fast (and 1000 ppm, twenty times more) against the
 * receiver's, for 2 h at 1 Hz: 100.005 (100.1) samples per second, never off-rate. */
static void test_clock_drift(void **state)
{
    (void)state;
    const uint32_t ppm[2] = {50u, 1000u};
    for (int i = 0; i < 2; i++) {
        setup(NULL);
        (void)epoch(0u, 100u);
        uint64_t due = 0u, sent = 0u;
        for (uint32_t s = 1u; s <= 7200u; s++) {
            due = (uint64_t)s * 100u * (1000000u + ppm[i]) / 1000000u;
            samples((uint32_t)(due - sent));
            sent = due;
            assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
            assert_int_equal(r.run_n, 0u);
        }
    }
}

/* A repeated TimeOfWeek (a frozen receiver) is ignored: the interval goes on to the next
 * fresh epoch, 3 s of samples over 3 s. */
static void test_repeated_time_of_week(void **state)
{
    (void)state;
    (void)epoch(0u, 100u);
    for (int k = 0; k < 3; k++) {
        samples(100u);
        assert_int_equal(epoch(0u, 100u), IMU_RATE_SAME);
    }
    assert_int_equal(r.count, 300u);
    assert_int_equal(epoch(3000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.ok_n, 1u);
}

/* IMU silences: an interval without a sample restarts the measurement (the silence is
 * IMU_STALE's). A silence of 1 s, 0.45 s before an epoch and 0.55 s after it (100
 * samples lost, the counter sees 100 mod 15 = 10 of them) makes two slow intervals of 55
 * samples, one rate, 0.9 s short together: a mismatch if it were measured; it is not,
 * since a sample came after a gap seen only in receive time among samples in time. */
static void test_imu_silence(void **state)
{
    (void)state;
    (void)epoch(0u, 100u);
    samples(50u); /* then silent */
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME); /* no sample: restart */
    assert_int_equal(r.run_n, 0u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.ok_n, 1u);
    samples(55u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.run_n, 1u);
    imu_rate_sample(&r, 10u, 1u);
    samples(44u);
    assert_int_equal(r.count, 55u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(r.run_n, 0u); /* not measured */
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_false(imu_rate_mismatch(&r));
}

/* 10 Hz data configured as 100 Hz: every sample arrives ten configured periods after the
 * last, so the stream sees a gap before each (time_gap): that is the data's rate, not a
 * gap among samples in time, and it is measured: 10 Hz, found at the third epoch. */
static void test_every_sample_after_a_time_gap(void **state)
{
    (void)state;
    (void)epoch(0u, 100u);
    for (int e = 2; e <= 3; e++) {
        for (int k = 0; k < 10; k++) {
            imu_rate_sample(&r, 0u, 1u);
        }
        assert_int_equal(epoch(1000u, 100u), e == 3 ? IMU_RATE_MISMATCH : IMU_RATE_SAME);
    }
    assert_int_equal(imu_rate_measured_chz(&r), 1000u);
}

/* The end of a mismatch: two on-rate intervals in a row. One on-rate interval between
 * off-rate ones does not end it; a measurement restart does not end it either. */
static void test_mismatch_ends(void **state)
{
    (void)state;
    assert_int_equal(epochs_to_detect(400u, 1u, 100u, 10), 3);
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(400u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME); /* no sample: restart */
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    assert_true(imu_rate_mismatch(&r));
    samples(100u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_MATCH);
    assert_false(imu_rate_mismatch(&r));
    assert_int_equal(imu_rate_measured_chz(&r), 0u);
    assert_int_equal(r.measured_chz, 40000u); /* the last rate measured, for a summary */
    /* and it is found again */
    samples(400u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_SAME);
    samples(400u);
    assert_int_equal(epoch(1000u, 100u), IMU_RATE_MISMATCH);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_detection_latency, setup),
        cmocka_unit_test_setup(test_measured_rate, setup),
        cmocka_unit_test_setup(test_interval_boundary, setup),
        cmocka_unit_test_setup(test_run_boundary, setup),
        cmocka_unit_test_setup(test_run_needs_one_rate, setup),
        cmocka_unit_test_setup(test_lost_samples_counted, setup),
        cmocka_unit_test_setup(test_missing_epochs, setup),
        cmocka_unit_test_setup(test_late_epochs, setup),
        cmocka_unit_test_setup(test_clock_jumps, setup),
        cmocka_unit_test_setup(test_week_end_and_longest_interval, setup),
        cmocka_unit_test_setup(test_clock_drift, setup),
        cmocka_unit_test_setup(test_repeated_time_of_week, setup),
        cmocka_unit_test_setup(test_imu_silence, setup),
        cmocka_unit_test_setup(test_every_sample_after_a_time_gap, setup),
        cmocka_unit_test_setup(test_mismatch_ends, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
