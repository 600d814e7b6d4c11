/*
 * test_imu_stream.c - imu_stream.h: the IMU pair, its counter (jumps held until
 * successors confirm them, corrupt counters), gaps seen by counter and by receive time,
 * the interpolated bridge, saturation at the configured range, stuck axes. Frames are the
 * real encoding (tests/support/can_frames.h); the stream is fed their decoded raw values.
 *
 * IMU at 100 Hz (10 000 us a sample), the default ranges 5.235988 rad/s and 78.4532 m/s^2:
 * saturation at 99.9 % of the range per sample is
 *   gyro  5.235988 * 0.01 * 0.999 / 2^-21 = 109696.8 -> 109696 LSB,
 *   accel 78.4532  * 0.01 * 0.999 / 2^-12 =   3210.2 ->   3210 LSB.
 * A moving car: a gyro axis spanning more than 1 deg/s * 0.01 s / 2^-21 = 366.0 LSB.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "can_frames.h"
#include "e2e.h"
#include "imu_stream.h"

#define RATE_HZ 100u
#define PERIOD_US 10000u
#define GYRO_RANGE_RPS 5.235988f
#define ACCEL_RANGE_MPS2 78.4532f

static imu_stream_t s;
static imu_link_t l;
static imu_sample_t out;

static int setup(void **state)
{
    (void)state;
    memset(&s, 0, sizeof s);
    imu_link_init(&l, RATE_HZ, GYRO_RANGE_RPS, ACCEL_RANGE_MPS2, NAVECU_CAN_IMU_ACCEL_FRAME_ID);
    memset(&out, 0, sizeof out);
    return 0;
}

/* one pair through the stream: IMU_Rate, then IMU_Accel at t_us */
static imu_verdict_t pair(uint8_t counter, const int32_t w[3], const int32_t v[3], uint64_t t_us)
{
    hal_can_frame_t fr, fa;
    cf_imu_pair(w, v, counter, 0u, t_us, &fr, &fa);
    (void)imu_stream_rate(&s, counter, w, fr.data);
    return imu_stream_accel(&s, &l, counter, 0u, v, fa.data, t_us, &out);
}

static const int32_t W0[3] = {10, -20, 30};
static const int32_t V0[3] = {-1, 2, 401};

/* the k-th sample of a simple stream: counter k mod 15 at k periods */
static imu_verdict_t nth(uint32_t k)
{
    return pair((uint8_t)(k % 15u), W0, V0, (uint64_t)k * PERIOD_US);
}

/* ---- the pair ---- */

static void test_pair_gives_a_sample(void **state)
{
    (void)state;
    const int32_t w[3] = {1000, -2000, 3};
    const int32_t v[3] = {-40, 50, 401};
    assert_int_equal(pair(0u, w, v, 0u), IMU_SAMPLE);
    for (int i = 0; i < 3; i++) {
        assert_int_equal(out.raw[i], w[i]);
        assert_int_equal(out.raw[i + 3], v[i]);
        assert_int_equal(out.prev_raw[i], w[i]); /* the first sample: no gap to start from */
        assert_int_equal(out.prev_raw[i + 3], v[i]);
    }
    assert_int_equal(out.lost, 0u);
    assert_int_equal(out.saturated, 0);
    assert_int_equal(out.stuck, 0);
    assert_int_equal(l.have_sample, 1);
    assert_int_equal(l.last_t_us, 0u);
    /* the next sample starts from this one */
    assert_int_equal(pair(1u, W0, V0, PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.prev_raw[0], 1000);
    assert_int_equal(out.prev_raw[5], 401);
}

/* IMU_Accel without its IMU_Rate, with another counter than it, and a third IMU_Rate
 * while two wait: broken pairs. */
static void test_broken_pair(void **state)
{
    (void)state;
    hal_can_frame_t fr, fa;
    cf_imu_pair(W0, V0, 0u, 0u, 0u, &fr, &fa);
    assert_int_equal(imu_stream_accel(&s, &l, 0u, 0u, V0, fa.data, 0u, &out), IMU_REJ_PAIR);
    assert_int_equal(imu_stream_rate(&s, 0u, W0, fr.data), 0);
    assert_int_equal(imu_stream_rate(&s, 0u, W0, fr.data), 0); /* two may wait */
    assert_int_equal(imu_stream_rate(&s, 0u, W0, fr.data), 1); /* the oldest had no accel */
    hal_can_frame_t fr1, fa1;
    cf_imu_pair(W0, V0, 1u, 0u, 0u, &fr1, &fa1);
    assert_int_equal(imu_stream_accel(&s, &l, 1u, 0u, V0, fa1.data, 0u, &out), IMU_REJ_PAIR);
    /* an IMU_Accel of no waiting IMU_Rate (its IMU_Rate lost, or a foreign frame) leaves
     * the waiting ones alone: the real IMU_Accel of counter 0 still completes its sample */
    assert_int_equal(imu_stream_accel(&s, &l, 0u, 0u, V0, fa.data, 0u, &out), IMU_SAMPLE);
}

/* GIVEN another node's 8-byte frame on IMU_Rate's identifier between the two halves of
 * a sample WHEN the real IMU_Accel comes THEN it pairs with the real IMU_Rate (its counter
 * and pair CRC); the foreign one after it waits on until the next real pair drops it (a
 * broken pair); a foreign one before the real IMU_Rate is dropped at once. */
static void test_foreign_rate_between_halves(void **state)
{
    (void)state;
    hal_can_frame_t fr, fa;
    cf_imu_pair(W0, V0, 0u, 0u, 0u, &fr, &fa);
    const uint8_t junk[8] = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x08};
    const int32_t junk_raw[3] = {5, 6, 7};
    assert_int_equal(imu_stream_rate(&s, 0u, W0, fr.data), 0);
    assert_int_equal(imu_stream_rate(&s, 0u, junk_raw, junk), 0);
    assert_int_equal(imu_stream_accel(&s, &l, 0u, 0u, V0, fa.data, 0u, &out), IMU_SAMPLE);
    assert_int_equal(out.raw[0], W0[0]);
    assert_int_equal(out.dropped, 0u);
    assert_int_equal(s.n_pending, 1u); /* the foreign one */
    hal_can_frame_t fr2, fa2;
    cf_imu_pair(W0, V0, 1u, 0u, 0u, &fr2, &fa2);
    assert_int_equal(imu_stream_rate(&s, 1u, W0, fr2.data), 0);
    assert_int_equal(imu_stream_accel(&s, &l, 1u, 0u, V0, fa2.data, PERIOD_US, &out), IMU_SAMPLE);
    assert_int_equal(out.dropped, 1u);
    assert_int_equal(out.lost, 0u);
    cf_imu_pair(W0, V0, 2u, 0u, 0u, &fr, &fa);
    assert_int_equal(imu_stream_rate(&s, 2u, junk_raw, junk), 0);
    assert_int_equal(imu_stream_rate(&s, 2u, W0, fr.data), 0);
    assert_int_equal(imu_stream_accel(&s, &l, 2u, 0u, V0, fa.data, 2u * PERIOD_US, &out), IMU_SAMPLE);
    assert_int_equal(out.raw[2], W0[2]);
    assert_int_equal(out.dropped, 1u);
}

/* GIVEN two samples whose frames come reordered (Rate k, Rate k+1, Accel k, Accel k+1)
 * THEN both pair: the newer IMU_Rate waits on while the older pairs. */
static void test_reordered_pairs(void **state)
{
    (void)state;
    hal_can_frame_t r0, a0, r1, a1;
    const int32_t W1[3] = {W0[0] + 3, W0[1], W0[2]};
    cf_imu_pair(W0, V0, 0u, 0u, 0u, &r0, &a0);
    cf_imu_pair(W1, V0, 1u, 0u, 0u, &r1, &a1);
    (void)imu_stream_rate(&s, 0u, W0, r0.data);
    (void)imu_stream_rate(&s, 1u, W1, r1.data);
    assert_int_equal(imu_stream_accel(&s, &l, 0u, 0u, V0, a0.data, 0u, &out), IMU_SAMPLE);
    assert_int_equal(out.raw[0], W0[0]);
    assert_int_equal(out.dropped, 0u);
    assert_int_equal(imu_stream_accel(&s, &l, 1u, 0u, V0, a1.data, PERIOD_US, &out), IMU_SAMPLE);
    assert_int_equal(out.raw[0], W1[0]);
    assert_int_equal(out.lost, 0u);
}

/* GIVEN an 8-byte frame with a wrong pair CRC on IMU_Accel's identifier between the two
 * halves WHEN the real IMU_Accel follows THEN the first is refused (bad CRC) and the real
 * pair still makes the sample. */
static void test_foreign_accel_between_halves(void **state)
{
    (void)state;
    hal_can_frame_t fr, fa;
    cf_imu_pair(W0, V0, 0u, 0u, 0u, &fr, &fa);
    uint8_t junk[8];
    memcpy(junk, fa.data, 8u);
    junk[7] ^= 0x5Au;
    (void)imu_stream_rate(&s, 0u, W0, fr.data);
    assert_int_equal(imu_stream_accel(&s, &l, 0u, 0u, V0, junk, 0u, &out), IMU_REJ_CRC);
    /* and one with another counter (another node's frame, its own counter) */
    assert_int_equal(imu_stream_accel(&s, &l, 9u, 0u, V0, junk, 0u, &out), IMU_REJ_PAIR);
    assert_int_equal(imu_stream_accel(&s, &l, 0u, 0u, V0, fa.data, 0u, &out), IMU_SAMPLE);
    assert_int_equal(out.dropped, 0u);
    assert_int_equal(out.raw[3], V0[0]);
}

/* The pair CRC covers IMU_Rate too: one bit of IMU_Rate's payload changed -> bad CRC. */
static void test_bad_pair_crc(void **state)
{
    (void)state;
    hal_can_frame_t fr, fa;
    cf_imu_pair(W0, V0, 0u, 0u, 0u, &fr, &fa);
    fr.data[2] ^= 0x04u;
    (void)imu_stream_rate(&s, 0u, W0, fr.data);
    assert_int_equal(imu_stream_accel(&s, &l, 0u, 0u, V0, fa.data, 0u, &out), IMU_REJ_CRC);
    cf_imu_pair(W0, V0, 0u, 0u, 0u, &fr, &fa);
    fa.data[7] ^= 0x01u;
    (void)imu_stream_rate(&s, 0u, W0, fr.data);
    assert_int_equal(imu_stream_accel(&s, &l, 0u, 0u, V0, fa.data, 0u, &out), IMU_REJ_CRC);
    assert_int_equal(l.have_sample, 0);
}

/* The fault bit of the sample taken is the link's. */
static void test_fault_bit(void **state)
{
    (void)state;
    hal_can_frame_t fr, fa;
    cf_imu_pair(W0, V0, 0u, 1u, 0u, &fr, &fa);
    (void)imu_stream_rate(&s, 0u, W0, fr.data);
    assert_int_equal(imu_stream_accel(&s, &l, 0u, 1u, V0, fa.data, 0u, &out), IMU_SAMPLE);
    assert_int_equal(l.fault, 1);
    assert_int_equal(nth(1u), IMU_SAMPLE);
    assert_int_equal(l.fault, 0);
}

/* ---- the counter ---- */

/* Steps 1 and 2: taken at once (one sample lost with 2); a repeated counter refused. */
static void test_counter_steps_1_and_2(void **state)
{
    (void)state;
    assert_int_equal(pair(0u, W0, V0, 0u), IMU_SAMPLE);
    assert_int_equal(pair(1u, W0, V0, PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.lost, 0u);
    assert_int_equal(pair(1u, W0, V0, PERIOD_US), IMU_REJ_COUNTER);
    assert_int_equal(pair(3u, W0, V0, 3u * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.lost, 1u);
    assert_int_equal(out.time_gap, 0);
    assert_int_equal(pair(7u, W0, V0, 7u * PERIOD_US), IMU_SAMPLE); /* step 4 = MAX_DELTA */
    assert_int_equal(out.lost, 3u);
}

/* GIVEN counter 0 WHEN counter 5 comes (a step beyond APP_IMU_MAX_DELTA) THEN it is held,
 * and 6 after it too (APP_IMU_JUMP_HELD = 2 samples following one another); WHEN 7
 * follows them THEN the jump was real: taken, with 6 samples lost (1..4 and the held 5
 * and 6). A successor may skip lost ones: 0, 5, 7 (6 lost), 9 is taken with 8 lost. */
static void test_counter_step_5_held_until_confirmed(void **state)
{
    (void)state;
    assert_int_equal(pair(0u, W0, V0, 0u), IMU_SAMPLE);
    assert_int_equal(pair(5u, W0, V0, 5u * PERIOD_US), IMU_REJ_COUNTER);
    assert_int_equal(l.counter.last, 0);
    assert_int_equal(pair(6u, W0, V0, 6u * PERIOD_US), IMU_REJ_COUNTER);
    assert_int_equal(l.counter.last, 0);
    assert_int_equal(pair(7u, W0, V0, 7u * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.lost, 6u);
    assert_int_equal(l.counter.last, 7);
    assert_int_equal(pair(14u, W0, V0, 14u * PERIOD_US), IMU_REJ_COUNTER);
    assert_int_equal(pair(1u, W0, V0, 16u * PERIOD_US), IMU_REJ_COUNTER);
    assert_int_equal(pair(3u, W0, V0, 18u * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.lost, 10u);
}

/* GIVEN counter 0 WHEN two wrong counters follow one another (9, 10: a sender's fault),
 * then 3 (they were samples 1 and 2) THEN they were not a gap: both dropped, 3 taken with
 * 2 lost. (With one held sample, 10 had confirmed 9: 9 samples of time added, then
 * the good samples, 6 behind, a second jump: a whole counter cycle for good.) */
static void test_two_wrong_counters_in_a_row(void **state)
{
    (void)state;
    assert_int_equal(pair(0u, W0, V0, 0u), IMU_SAMPLE);
    assert_int_equal(pair(9u, W0, V0, PERIOD_US), IMU_REJ_COUNTER);
    assert_int_equal(pair(10u, W0, V0, 2u * PERIOD_US), IMU_REJ_COUNTER);
    assert_int_equal(l.counter.last, 0);
    assert_int_equal(pair(3u, W0, V0, 3u * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.lost, 2u);
    assert_int_equal(pair(4u, W0, V0, 4u * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.lost, 0u);
}

/* GIVEN counter 0 WHEN a corrupt counter 9 comes, then 1 (the good one's successor)
 * THEN 9 was a wrong counter: dropped alone, 1 taken with nothing lost, and the stream
 * goes on from 1 (a late 9 is old data, not a jump). */
static void test_corrupt_counter(void **state)
{
    (void)state;
    assert_int_equal(pair(0u, W0, V0, 0u), IMU_SAMPLE);
    assert_int_equal(pair(9u, W0, V0, PERIOD_US), IMU_REJ_COUNTER);
    assert_int_equal(pair(1u, W0, V0, 2u * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.lost, 0u);
    assert_int_equal(l.counter.last, 1);
    assert_int_equal(pair(2u, W0, V0, 3u * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.lost, 0u);
    /* 1..4 behind the counter: old data, dropped, and it does not move the counter */
    assert_int_equal(pair(0u, W0, V0, 4u * PERIOD_US), IMU_REJ_COUNTER);
    assert_int_equal(l.counter.last, 2);
}

/* ---- gaps by receive time ---- */

/* GIVEN a sample WHEN the next has the next counter but arrives 16 periods later THEN 15
 * samples (a whole counter cycle) were lost that the counter could not see; 31 periods:
 * 30; 8 periods (within the 7-period slack) is only a late sample. lost_by_time is the
 * part of lost only receive time showed (the IMU rate check counts without it). */
static void test_gap_by_receive_time(void **state)
{
    (void)state;
    uint64_t t = 1000000u;
    assert_int_equal(pair(0u, W0, V0, t), IMU_SAMPLE);
    t += 16u * PERIOD_US;
    assert_int_equal(pair(1u, W0, V0, t), IMU_SAMPLE);
    assert_int_equal(out.lost, 15u);
    assert_int_equal(out.lost_by_time, 15u);
    assert_int_equal(out.time_gap, 1);
    t += 31u * PERIOD_US;
    assert_int_equal(pair(2u, W0, V0, t), IMU_SAMPLE);
    assert_int_equal(out.lost, 30u);
    assert_int_equal(out.lost_by_time, 30u);
    t += 8u * PERIOD_US;
    assert_int_equal(pair(3u, W0, V0, t), IMU_SAMPLE);
    assert_int_equal(out.lost, 0u);
    assert_int_equal(out.lost_by_time, 0u);
    assert_int_equal(out.time_gap, 0);
    /* a counter step of 3 over 3 + 7 periods: still the counter's 2 lost only */
    t += 10u * PERIOD_US;
    assert_int_equal(pair(6u, W0, V0, t), IMU_SAMPLE);
    assert_int_equal(out.lost, 2u);
    assert_int_equal(out.lost_by_time, 0u);
    assert_int_equal(out.time_gap, 0);
    /* a step of 3 and 19 periods: the counter's 2 and a whole cycle by time */
    t += 19u * PERIOD_US;
    assert_int_equal(pair(9u, W0, V0, t), IMU_SAMPLE);
    assert_int_equal(out.lost, 17u);
    assert_int_equal(out.lost_by_time, 15u);
    assert_int_equal(out.time_gap, 1);
    /* a receive time going backwards adds nothing */
    assert_int_equal(pair(10u, W0, V0, t - 100u * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.lost, 0u);
}

/* ---- the bridge ---- */

/* GIVEN a sample 0 then counter 3 (2 lost) THEN the bridge is the straight line between
 * them at 1/3 and 2/3, rounded to nearest: from 0 to 10: 3.33 -> 3, 6.67 -> 7; to -10:
 * -3, -7; to 100000: 33333, 66667. */
static void test_bridge_interpolation(void **state)
{
    (void)state;
    const int32_t w0[3] = {0, 0, 0};
    const int32_t v0[3] = {0, 0, 0};
    const int32_t w1[3] = {10, -10, 100000};
    const int32_t v1[3] = {-100000, 2, 1};
    assert_int_equal(pair(0u, w0, v0, 0u), IMU_SAMPLE);
    assert_int_equal(pair(3u, w1, v1, 3u * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.lost, 2u);
    int32_t w[3], v[3];
    imu_stream_bridge(&out, 0u, w, v);
    assert_int_equal(w[0], 3);
    assert_int_equal(w[1], -3);
    assert_int_equal(w[2], 33333);
    assert_int_equal(v[0], -33333);
    assert_int_equal(v[1], 1);  /* 0.67 */
    assert_int_equal(v[2], 0);  /* 0.33 */
    imu_stream_bridge(&out, 1u, w, v);
    assert_int_equal(w[0], 7);
    assert_int_equal(w[1], -7);
    assert_int_equal(w[2], 66667);
    assert_int_equal(v[0], -66667);
    assert_int_equal(v[1], 1);  /* 1.33 */
    assert_int_equal(v[2], 1);  /* 0.67 */
}

/* Halves of the step round away from zero (one lost sample between 0 and +-1: +-0.5 ->
 * +-1), and the line spans the whole int32 range without overflow. */
static void test_bridge_halves_and_extremes(void **state)
{
    (void)state;
    imu_sample_t smp;
    memset(&smp, 0, sizeof smp);
    smp.lost = 1u;
    smp.raw[0] = 1;
    smp.raw[1] = -1;
    smp.raw[2] = 3;
    smp.prev_raw[2] = 0;
    smp.prev_raw[3] = INT32_MIN;
    smp.raw[3] = INT32_MAX;
    smp.prev_raw[4] = INT32_MAX;
    smp.raw[4] = INT32_MIN;
    int32_t w[3], v[3];
    imu_stream_bridge(&smp, 0u, w, v);
    assert_int_equal(w[0], 1);
    assert_int_equal(w[1], -1);
    assert_int_equal(w[2], 2);  /* 1.5 -> 2 */
    /* ties of the result (-0.5 both): the step (+-(2^32 - 1) / 2) is rounded away from
     * zero, so either neighbour comes out, each nearest */
    assert_int_equal(v[0], 0);  /* -2^31 + 2^31 */
    assert_int_equal(v[1], -1); /* 2^31 - 1 - 2^31 */
    assert_int_equal(v[2], 0);
}

/* ---- plausibility ---- */

/* GIVEN samples taken, then the stream's state cleared (a navigation reset: app_reset
 * clears run.imu, the link's counter goes on) WHEN the next sample comes after a gap
 * THEN the gap is seen and bridged from that sample itself (prev_raw = raw), not from
 * zeros (a bridge from 0 to the sample would step the increments, gravity's included). */
static void test_bridge_after_a_reset_starts_at_the_sample(void **state)
{
    (void)state;
    assert_int_equal(nth(0u), IMU_SAMPLE);
    assert_int_equal(nth(1u), IMU_SAMPLE);
    for (int i = 0; i < 3; i++) {
        assert_int_equal(out.prev_raw[i], W0[i]);
        assert_int_equal(out.prev_raw[i + 3], V0[i]);
    }
    memset(&s, 0, sizeof s);
    assert_int_equal(nth(3u), IMU_SAMPLE);
    assert_int_equal(out.lost, 1u);
    for (int i = 0; i < 3; i++) {
        assert_int_equal(out.prev_raw[i], W0[i]);
        assert_int_equal(out.prev_raw[i + 3], V0[i]);
    }
}

/* GIVEN a stream after a navigation reset (its state cleared, the link's kept)
 * WHEN the first sample has axes at 0, the cleared state's value
 * THEN none counts as a repeat (its stuck count stays 0); the next, equal, does (1). */
static void test_first_sample_after_a_reset_repeats_nothing(void **state)
{
    (void)state;
    assert_int_equal(nth(0u), IMU_SAMPLE);
    memset(&s, 0, sizeof s);
    const int32_t w[3] = {0, 5, 0};
    const int32_t v[3] = {0, 0, 401};
    assert_int_equal(pair(1u, w, v, PERIOD_US), IMU_SAMPLE);
    for (int i = 0; i < 6; i++) {
        assert_int_equal(s.plaus.same_n[i], 0u);
    }
    assert_int_equal(pair(2u, w, v, 2u * PERIOD_US), IMU_SAMPLE);
    for (int i = 0; i < 6; i++) {
        assert_int_equal(s.plaus.same_n[i], 1u);
    }
}

/* GIVEN the ranges above THEN a gyro axis at +-109696 LSB or an accelerometer axis at
 * +-3210 LSB is saturated (its bit in saturated: raw[i], bit i), one LSB less is not. */
static void test_saturation_at_configured_range(void **state)
{
    (void)state;
    assert_int_equal(l.sat_raw[0], 109696);
    assert_int_equal(l.sat_raw[1], 3210);
    int32_t w[3] = {109695, -109695, 0};
    int32_t v[3] = {3209, -3209, 0};
    uint32_t k = 0u;
    assert_int_equal(pair((uint8_t)k, w, v, k * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.saturated, 0);
    const int axis_w[3] = {0, 1, 2};
    for (int i = 0; i < 3; i++) {
        int32_t ws[3] = {0, 0, 0};
        ws[axis_w[i]] = i == 1 ? -109696 : 109696;
        k++;
        assert_int_equal(pair((uint8_t)(k % 15u), ws, v, k * PERIOD_US), IMU_SAMPLE);
        assert_int_equal(out.saturated, 1u << axis_w[i]);
    }
    for (int i = 0; i < 3; i++) {
        int32_t vs[3] = {0, 0, 0};
        vs[i] = i == 2 ? -3210 : 3210;
        k++;
        assert_int_equal(pair((uint8_t)(k % 15u), w, vs, k * PERIOD_US), IMU_SAMPLE);
        assert_int_equal(out.saturated, 8u << i);
        int32_t ws[3] = {0, -109696, 0};
        k++;
        assert_int_equal(pair((uint8_t)(k % 15u), ws, vs, k * PERIOD_US), IMU_SAMPLE);
        assert_int_equal(out.saturated, 2u | (8u << i));
    }
    k++;
    assert_int_equal(pair((uint8_t)(k % 15u), w, v, k * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.saturated, 0);
}

/* sample k of a car turning (gyro z alternating 0 / 2000 LSB, more than 366), every other
 * axis moving its last bit, and gyro x at x_raw */
static void turning(uint32_t k, int32_t x_raw, int32_t w[3], int32_t v[3])
{
    const int32_t b = (int32_t)(k % 2u);
    w[0] = x_raw;
    w[1] = 5 + b;
    w[2] = 2000 * b;
    v[0] = b;
    v[1] = -b;
    v[2] = 401 + b;
}

/* GIVEN gyro x repeating 1234 while the car turns THEN from the sample where it has
 * repeated for 2 s (200 repeats: sample 201) the sample is stuck, counted once
 * (stuck_new 1) however long it lasts; WHEN x moves once and repeats again for 2 s THEN
 * a new episode is counted. */
static void test_stuck_axis_while_another_moves(void **state)
{
    (void)state;
    uint32_t counted = 0u;
    uint32_t first_stuck = 0u;
    int32_t w[3], v[3];
    for (uint32_t k = 1u; k <= 400u; k++) {
        turning(k, 1234, w, v);
        assert_int_equal(pair((uint8_t)(k % 15u), w, v, k * PERIOD_US), IMU_SAMPLE);
        counted += out.stuck_new;
        if (out.stuck && first_stuck == 0u) {
            first_stuck = k;
        }
        if (k > 201u) {
            assert_int_equal(out.stuck, 1);
        }
    }
    assert_int_equal(first_stuck, 201u);
    assert_int_equal(counted, 1u);
    turning(401u, 1235, w, v); /* it moved: the episode is over */
    assert_int_equal(pair((uint8_t)(401u % 15u), w, v, 401u * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.stuck, 0);
    for (uint32_t k = 402u; k <= 700u; k++) {
        turning(k, 1235, w, v);
        assert_int_equal(pair((uint8_t)(k % 15u), w, v, k * PERIOD_US), IMU_SAMPLE);
        counted += out.stuck_new;
    }
    assert_int_equal(counted, 2u);
}

/* GIVEN a car standing still, a quiet sensor (gyro x repeating, the others moving by
 * their last bit only: a second difference of 2 LSB, below APP_IMU_NOISE_MIN_LSB) THEN
 * after 5 s no axis is stuck: a quiet sensor may repeat. */
static void test_not_stuck_while_still(void **state)
{
    (void)state;
    for (uint32_t k = 1u; k <= 500u; k++) {
        const int32_t b = (int32_t)(k % 2u);
        const int32_t w[3] = {1234, 5 + b, 300 + b};
        const int32_t v[3] = {b, 20 + b, 401};
        assert_int_equal(pair((uint8_t)(k % 15u), w, v, k * PERIOD_US), IMU_SAMPLE);
        assert_int_equal(out.stuck, 0);
        assert_int_equal(out.stuck_new, 0);
    }
}

/* the raw increment of a smooth signal (LSB per sample, real), quantized with its
 * remainder carried, as an ideal simulation sends it */
static int32_t carried(double value, double *carry)
{
    const double x = value + *carry;
    const int32_t q = (int32_t)lround(x);
    *carry = x - q;
    return q;
}

/*
 * Ideal, noiseless data (issue #17: IMU_STUCK counted 2-8 times on every clean drive).
 * GIVEN a car braking in a straight line on a flat road for 4 s (deceleration rising to
 * 3 m/s^2: the forward accelerometer spans far more than 0.5 m/s^2), then turning for 4 s
 * (yaw rate rising to 20 deg/s, the centripetal acceleration with it), every gyro axis but
 * the yaw exactly 0 and the lateral accelerometer exactly 0 while braking, each signal
 * quantized with its remainder carried
 * THEN no axis is stuck: values repeating on ideal data are the motion's, not a fault.
 */
static void test_not_stuck_on_ideal_data(void **state)
{
    (void)state;
    const double dt = 1.0 / RATE_HZ;
    const double v_lsb = 1.0 / 4096.0, w_lsb = 1.0 / 2097152.0;
    double c[6] = {0};
    uint32_t stuck = 0u;
    for (uint32_t k = 1u; k <= 800u; k++) {
        const double t = k * dt;
        double a_fwd = 0.0, a_lat = 0.0, yaw = 0.0;
        if (t < 4.0) {
            a_fwd = -3.0 * (t / 4.0);
        } else {
            yaw = 20.0 * 3.14159265358979 / 180.0 * ((t - 4.0) / 4.0);
            a_lat = -yaw * 10.0; /* at 10 m/s */
        }
        const int32_t w[3] = {carried(0.0, &c[0]), carried(0.0, &c[1]),
                              carried(yaw * dt / w_lsb, &c[2])};
        const int32_t v[3] = {carried(a_lat * dt / v_lsb, &c[3]),
                              carried(a_fwd * dt / v_lsb, &c[4]),
                              carried(9.80665 * dt / v_lsb, &c[5])};
        assert_int_equal(pair((uint8_t)(k % 15u), w, v, k * PERIOD_US), IMU_SAMPLE);
        stuck += out.stuck;
    }
    assert_int_equal(stuck, 0u);
}

/*
 * GIVEN a car standing, a noisy gyro (y and z: uniform noise of +-20 LSB, sigma 11.5 LSB,
 * a mean |second difference| near 22 LSB, above APP_IMU_NOISE_MIN_LSB 4) whose x axis
 * repeats 1234
 * THEN x is stuck from its 200th repeat (sample 201), counted once; the accelerometer
 * (quiet, repeating) is not.
 */
static void test_stuck_axis_of_a_noisy_sensor(void **state)
{
    (void)state;
    uint32_t rng = 12345u;
    uint32_t counted = 0u, first = 0u;
    for (uint32_t k = 1u; k <= 400u; k++) {
        int32_t n[2];
        for (int i = 0; i < 2; i++) {
            rng = rng * 1103515245u + 12345u;
            n[i] = (int32_t)((rng >> 16) % 41u) - 20;
        }
        const int32_t w[3] = {1234, 50 + n[0], -70 + n[1]};
        const int32_t v[3] = {0, 0, 401};
        assert_int_equal(pair((uint8_t)(k % 15u), w, v, k * PERIOD_US), IMU_SAMPLE);
        counted += out.stuck_new;
        if (out.stuck && first == 0u) {
            first = k;
        }
    }
    assert_int_equal(first, 201u);
    assert_int_equal(counted, 1u);
}

/*
 * GIVEN a car standing, the accelerometer's x and z noisy (uniform +-20 LSB) and its y
 * axis (raw[4]) repeating 77
 * THEN y is stuck from sample 201 (stuck: its bit, IMU_AXES_ACCEL's middle one)
 * AND WHEN x and z go quiet (repeating too) from sample 301 THEN y stays stuck, counted
 *     once: found while its sensor showed the noise, the episode lasts while the value
 *     repeats (the filter takes its samples as unknown motion, app.c); x and z, repeating
 *     while nothing shows the noise, are not stuck
 * AND WHEN y moves THEN nothing is stuck.
 */
static void test_stuck_axis_stays_stuck_while_it_repeats(void **state)
{
    (void)state;
    uint32_t rng = 777u;
    uint32_t counted = 0u;
    const int32_t w[3] = {0, 0, 0};
    for (uint32_t k = 1u; k <= 600u; k++) {
        int32_t n[2] = {3, -4};
        if (k <= 300u) {
            for (int i = 0; i < 2; i++) {
                rng = rng * 1103515245u + 12345u;
                n[i] = (int32_t)((rng >> 16) % 41u) - 20;
            }
        }
        const int32_t v[3] = {n[0], 77, 401 + n[1]};
        assert_int_equal(pair((uint8_t)(k % 15u), w, v, k * PERIOD_US), IMU_SAMPLE);
        counted += out.stuck_new;
        assert_int_equal(out.stuck, k >= 201u ? 0x10 : 0);
    }
    assert_int_equal(out.stuck & IMU_AXES_ACCEL, 0x10);
    assert_int_equal(counted, 1u);
    const int32_t v[3] = {3, 78, 397};
    assert_int_equal(pair((uint8_t)(601u % 15u), w, v, 601u * PERIOD_US), IMU_SAMPLE);
    assert_int_equal(out.stuck, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_pair_gives_a_sample, setup),
        cmocka_unit_test_setup(test_broken_pair, setup),
        cmocka_unit_test_setup(test_foreign_rate_between_halves, setup),
        cmocka_unit_test_setup(test_foreign_accel_between_halves, setup),
        cmocka_unit_test_setup(test_reordered_pairs, setup),
        cmocka_unit_test_setup(test_bad_pair_crc, setup),
        cmocka_unit_test_setup(test_fault_bit, setup),
        cmocka_unit_test_setup(test_counter_steps_1_and_2, setup),
        cmocka_unit_test_setup(test_counter_step_5_held_until_confirmed, setup),
        cmocka_unit_test_setup(test_two_wrong_counters_in_a_row, setup),
        cmocka_unit_test_setup(test_corrupt_counter, setup),
        cmocka_unit_test_setup(test_gap_by_receive_time, setup),
        cmocka_unit_test_setup(test_bridge_interpolation, setup),
        cmocka_unit_test_setup(test_bridge_halves_and_extremes, setup),
        cmocka_unit_test_setup(test_saturation_at_configured_range, setup),
        cmocka_unit_test_setup(test_bridge_after_a_reset_starts_at_the_sample, setup),
        cmocka_unit_test_setup(test_first_sample_after_a_reset_repeats_nothing, setup),
        cmocka_unit_test_setup(test_stuck_axis_while_another_moves, setup),
        cmocka_unit_test_setup(test_stuck_axis_stays_stuck_while_it_repeats, setup),
        cmocka_unit_test_setup(test_not_stuck_while_still, setup),
        cmocka_unit_test_setup(test_not_stuck_on_ideal_data, setup),
        cmocka_unit_test_setup(test_stuck_axis_of_a_noisy_sensor, setup),
    };
    return cmocka_run_group_tests_name("imu_stream", tests, NULL, NULL);
}
