/* imu_rate.c - the configured IMU rate against the data; see imu_rate.h. */
#include "imu_rate.h"

#include <string.h>

#include "app_tuning.h"


void imu_rate_init(imu_rate_t *r)
{
    (void)memset(r, 0, sizeof *r);
}

void imu_rate_sample(imu_rate_t *r, uint64_t counter_lost, uint8_t time_gap)
{
    r->count += 1u + counter_lost;
    if (r->received < UINT32_MAX) {
        r->received++;
        if (time_gap != 0u) {
            r->gaps++;
        }
    }
}

void imu_rate_stamp(imu_rate_t *r, uint32_t dt_us)
{
    r->stamped = 1u;
    if (dt_us == 0u) {
        r->received = 0u; /* no interval known: this one is not measured */
        r->gaps = 0u;
        r->count = 0u;
        r->stamp_us = 0u;
        r->anchored = 0u;
        return;
    }
    r->stamp_us += dt_us;
}

void imu_rate_refused(imu_rate_t *r)
{
    imu_rate_sample(r, 0u, 0u);
    r->stamp_gap = 1u;
}

/* the next interval starts at this epoch. Out of line (noinline): GCC inlined it at each
 * of its 3 calls, 32 bytes more of the ECU's flash (docs/target.md); it runs per GNSS
 * epoch, not per IMU sample. */
__attribute__((noinline)) static void anchor(imu_rate_t *r, uint32_t tow_ms)
{
    r->count = 0u;
    r->stamp_us = 0u;
    r->stamp_gap = 0u;
    r->received = 0u;
    r->gaps = 0u;
    r->tow_ms = tow_ms;
    r->anchored = 1u;
}

/* no measurement: a run, or a run of on-rate intervals, has to start again */
static void restart(imu_rate_t *r, uint32_t tow_ms)
{
    r->run_n = 0u;
    r->run_dir = 0;
    r->ok_n = 0u;
    anchor(r, tow_ms);
}

/* out of line (noinline): inlined at both its calls it took 8 bytes more */
__attribute__((noinline)) static uint8_t inc_sat(uint8_t n)
{
    return n < UINT8_MAX ? (uint8_t)(n + 1u) : n;
}

/* samples x 1000 (sample-ms) off the rate over ms, and what 5 % + the quantisation allow */
static int64_t deviation(int64_t count, int64_t ms, int64_t rate)
{
    return count * 1000 - rate * ms;
}

static int64_t allowance(int64_t ms, int64_t rate)
{
    return rate * ms / APP_IMU_RATE_TOL_DIV + (int64_t)APP_IMU_RATE_QUANT * 1000;
}

static int64_t abs64(int64_t x)
{
    return x < 0 ? -x : x;
}

/* count/ms at the run's rate: within 5 % of it plus the quantisation of both counts */
static int same_rate(const imu_rate_t *r, int64_t count, int64_t ms)
{
    const int64_t rc = (int64_t)r->run_count, rms = (int64_t)r->run_ms;
    const int64_t diff = abs64(count * rms - rc * ms);
    return diff <= rc * ms / APP_IMU_RATE_TOL_DIV + (int64_t)APP_IMU_RATE_QUANT * (rms + ms);
}

imu_rate_change_t imu_rate_epoch(imu_rate_t *r, uint32_t rate_hz, uint32_t tow_ms)
{
    if (!r->anchored) {
        anchor(r, tow_ms);
        return IMU_RATE_SAME;
    }
    /* the TimeOfWeek interval, modulo the week: a step back is close to a week (both
     * below 604,800,000 ms, so the sum stays below 2^32) */
    const int64_t tow_span = (int64_t)(tow_ms >= r->tow_ms ? tow_ms - r->tow_ms
                                                           : tow_ms + APP_WEEK_MS - r->tow_ms);
    if (tow_span == 0) {
        return IMU_RATE_SAME; /* the same epoch again (a frozen receiver): ignored */
    }
    /* stamped: the stamps' time of the samples counted (rounded to ms); a clock going
     * back (modulo the week) is still not measured */
    const uint64_t stamp_ms = (r->stamp_us + 500u) / 1000u;
    const int64_t ms = r->stamped != 0u && r->stamp_gap == 0u &&
                               tow_span <= (int64_t)APP_IMU_RATE_MAX_MS
                           ? (int64_t)stamp_ms
                           : tow_span;
    /* not measured: too long or a step back, no sample, or a gap the counter could not see
     * among samples in time (most samples after such a gap is the data's rate: measured) */
    if (ms == 0 || ms > (int64_t)APP_IMU_RATE_MAX_MS || r->received == 0u ||
        (r->gaps > 0u && r->gaps < r->received - r->gaps)) {
        restart(r, tow_ms);
        return IMU_RATE_SAME;
    }
    const int64_t rate = (int64_t)rate_hz;
    const int64_t count = (int64_t)r->count;
    anchor(r, tow_ms);
    const int64_t dev = deviation(count, ms, rate);
    if (abs64(dev) <= allowance(ms, rate)) {
        r->run_n = 0u;
        r->run_dir = 0;
        r->ok_n = inc_sat(r->ok_n);
        if (r->mismatch && r->ok_n >= APP_IMU_RATE_RUN) {
            r->mismatch = 0u; /* measured_chz keeps the last rate measured */
            return IMU_RATE_MATCH;
        }
        return IMU_RATE_SAME;
    }
    r->ok_n = 0u;
    const int8_t dir = dev > 0 ? (int8_t)1 : (int8_t)-1;
    if (r->run_n > 0u && dir == r->run_dir && same_rate(r, count, ms)) {
        r->run_n = inc_sat(r->run_n);
        r->run_count += (uint64_t)count;
        r->run_ms += (uint64_t)ms;
    } else {
        r->run_dir = dir;
        r->run_n = 1u;
        r->run_count = (uint64_t)count;
        r->run_ms = (uint64_t)ms;
    }
    if (r->run_n < APP_IMU_RATE_RUN) {
        return IMU_RATE_SAME;
    }
    const int64_t rms = (int64_t)r->run_ms;
    const int64_t run_dev = deviation((int64_t)r->run_count, rms, rate);
    if (abs64(run_dev) <= allowance(rms, rate) + rate * APP_IMU_RATE_LATE_MS) {
        return IMU_RATE_SAME; /* a steady change of latency could do that */
    }
    /* the run's rate in 0.01 Hz, rounded */
    const int64_t chz = ((int64_t)r->run_count * 100000 + rms / 2) / rms;
    r->measured_chz = chz < (int64_t)UINT32_MAX ? (uint32_t)chz : UINT32_MAX;
    if (r->mismatch) {
        return IMU_RATE_SAME;
    }
    r->mismatch = 1u;
    return IMU_RATE_MISMATCH;
}
