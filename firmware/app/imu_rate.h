/*
 * imu_rate.h - the configured IMU rate checked against the data. Between two usable GNSS
 * epochs the IMU samples are counted as the data tells them (each sample received plus
 * the samples its alive counter says were lost before it) and compared with the
 * configured rate times the epochs' TimeOfWeek interval. Data only, never arrival times:
 * the same count and the same decision from a log file, a vcan bus or the ECU.
 *
 * Why: a wrong rate scales the time of every strapdown step (gravity, Earth rate,
 * position = velocity x time): a 400 Hz IMU configured as 100 Hz drifts by kilometres
 * with no other symptom. No legitimate cause moves the count by 5 %: two crystals of
 * 50 ppm differ by 1e-4, and the IMU rates in use (50, 100, 125, 200, 250, 400 Hz)
 * differ from their neighbours by 20 % at least.
 *
 * An interval is ON-RATE when its count is within 5 % + 2 samples of rate x interval
 * (the 2 samples: each epoch's arrival is known to one IMU sample, plus one of latency
 * jitter), else OFF-RATE, fast or slow. A MISMATCH needs APP_IMU_RATE_RUN (2) off-rate
 * intervals in a row that agree with each other on the rate (within 5 % + 2 samples a
 * side) and are together off by more than 5 % + 2 samples + what a steady change of the
 * receiver's latency of APP_IMU_RATE_LATE_MS (0.25 s) could explain. So:
 *   - a late epoch (any lateness) makes one interval long and the next short: no run;
 *   - a receiver clock jump, and an epoch with the wrong TimeOfWeek, move one interval
 *     (or two in opposite directions, at rates that do not agree): no run;
 *   - missing epochs make a longer interval, measured as well as a short one;
 *   - lost samples are in the count when the counter sees them (up to 14 in a row);
 *     an interval with a gap it cannot see (found only in receive time, imu_stream.h:
 *     time_gap) among samples that came in time is not measured; every sample after such
 *     a gap is the data's rate (samples spaced far beyond the configured period), not a
 *     gap, and is measured;
 *   - 50 ppm of drift is 1/500 of the 5 %.
 * The mismatch ends with APP_IMU_RATE_RUN on-rate intervals in a row.
 * Not measured, the measurement restarting at the epoch: an interval without an IMU
 * sample (the IMU silent: IMU_STALE's business), one with a gap the counter cannot see,
 * one of more than APP_IMU_RATE_MAX_MS or going back in TimeOfWeek (a clock jump, modulo
 * the week). An epoch with the TimeOfWeek of the one before (a frozen receiver) is
 * ignored: the interval goes on.
 *
 * Detection latency: at 1..10 Hz GNSS, a 400 Hz IMU configured as 100 Hz (or 100 Hz
 * configured as 400 Hz at 1..5 Hz GNSS) is flagged at the third usable epoch, the first
 * with two intervals (tests/test_imu_rate.c, tests/python/test_imu_rate.py).
 */
#ifndef NAVECU_IMU_RATE_H
#define NAVECU_IMU_RATE_H

#include <stdint.h>

typedef struct {
    /* since the last epoch (the anchor) */
    uint64_t count;      /* samples: received and lost as the counter counts them */
    uint32_t received;   /* samples received */
    uint32_t gaps;       /* of them, after a gap the counter could not see */
    uint32_t tow_ms;     /* the anchor's TimeOfWeek */
    uint64_t stamp_us;   /* imu_time = stamped: the samples' IMU_Time intervals since the
                            anchor, the stamps' own time of the count */
    uint8_t stamped;     /* stamped: the interval is stamp_us, not the TimeOfWeek's */
    uint8_t stamp_gap;   /* a sample refused for its stamp since the anchor: its time is not
                            in stamp_us, the interval is the TimeOfWeek's */
    uint8_t anchored;
    /* the run of off-rate intervals that agree on the rate */
    int8_t run_dir;      /* +1 more samples than configured, -1 fewer */
    uint8_t run_n;       /* intervals in it (saturates) */
    uint64_t run_count;  /* their samples */
    uint64_t run_ms;     /* their TimeOfWeek span */
    uint8_t ok_n;        /* on-rate intervals in a row (saturates) */
    uint8_t mismatch;    /* the data disagree with the configured rate */
    uint32_t measured_chz; /* the rate of the last run found off, 0.01 Hz */
} imu_rate_t;

typedef enum {
    IMU_RATE_SAME = 0,   /* no change */
    IMU_RATE_MISMATCH,   /* the mismatch was found at this epoch */
    IMU_RATE_MATCH,      /* it ended at this epoch */
} imu_rate_change_t;

/* Boot: nothing counted, no mismatch. */
void imu_rate_init(imu_rate_t *r);

/* One IMU sample taken, after counter_lost samples the counter says were lost (the
 * stream's lost less what only receive time showed); time_gap: a gap the counter could
 * not see came before it (imu_sample_t.time_gap). */
void imu_rate_sample(imu_rate_t *r, uint64_t counter_lost, uint8_t time_gap);

/* imu_time = stamped: a sample taken with dt_us of IMU_Time interval (0: none, the first
 * stamp or a restart of the stamps' clock; the measurement restarts at the next epoch).
 * The check then compares the stamps' rate with the configured rate: the samples
 * counted over the stamps' time of those samples (exact, no epoch-arrival quantisation;
 * the TimeOfWeek interval only delimits it), under the same rules as on the grid. Stamps
 * that claim the configured rate for samples coming at another are refused one by one
 * (APP_IMU_TIME_BAND_*) beyond 50 %. */
void imu_rate_stamp(imu_rate_t *r, uint32_t dt_us);

/* Stamped: a sample refused for its stamp (imu_stream.h, IMU_REJ_TIME): it is data, so it
 * is counted, and the interval it falls in is measured by TimeOfWeek as on the grid (a
 * 400 Hz IMU configured as 100 Hz has its stamps refused, 2.5 ms against 5..15 ms, and is
 * still found off-rate). */
void imu_rate_refused(imu_rate_t *r);

/* A usable GNSS epoch of TimeOfWeek tow_ms (0 .. one week), against the configured rate
 * (Hz, > 0). */
imu_rate_change_t imu_rate_epoch(imu_rate_t *r, uint32_t rate_hz, uint32_t tow_ms);

/* 1 while the data disagree with the configured rate. */
static inline int imu_rate_mismatch(const imu_rate_t *r) { return r->mismatch != 0u; }

/* With a mismatch, the rate measured (0.01 Hz); 0 without. */
static inline uint32_t imu_rate_measured_chz(const imu_rate_t *r)
{
    return r->mismatch != 0u ? r->measured_chz : 0u;
}

#endif /* NAVECU_IMU_RATE_H */
