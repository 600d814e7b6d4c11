/*
 * gnss_time.h - when a GNSS fix was valid, on the IMU time base. A fix arrives
 * gnss_latency_s (configured) after its time of validity, more when the receiver is late;
 * lateness is seen in TimeOfWeek: the offset (IMU time - TimeOfWeek) of each epoch is
 * compared with its running minimum (which may creep by 50 ppm of elapsed time, clock
 * drift), the excess added to the latency. A receiver clock jump (week rollover, reset)
 * moves the offset for good: counted, and the minimum restarts from it.
 * The navigator's velocity history (entries at most 10 ms apart) gives its position and
 * velocity at that time. Decisions come from the data (sample count, TimeOfWeek), never
 * from arrival times.
 * The latency itself (on-time epochs) is estimated from the data: the IMU and receiver
 * clocks' offset is unknown, so it is the one that best fits the receiver's velocities to
 * the navigator's history (gnss_time_learn); gnss_latency_s is used until the data has
 * decided (on a first acceleration, docs/kalman.md).
 */
#ifndef NAVECU_GNSS_TIME_H
#define NAVECU_GNSS_TIME_H

#include <stdint.h>

#include "app_tuning.h"
#include "nav_types.h"

typedef struct {
    nav_real_t vhist[APP_VHIST][3]; /* navigator velocity, ENU m/s, oldest overwritten */
    uint32_t vhist_n;               /* entries written */
    int64_t off_min_us;             /* min over epochs of (IMU time - TimeOfWeek) */
    uint8_t off_valid;
    uint8_t late_run;               /* consecutive epochs more than 0.5 s late */
    int64_t prev_t_us;              /* IMU time of the previous epoch (drift allowance) */
    uint8_t lowered;                /* an epoch set the minimum since the last IMU sample
                                       (gnss_time_imu_next) */
    uint8_t min_suspect;            /* it arrived in an IMU gap: the next epoch's offset
                                       is the minimum instead */
    uint16_t gps_week;              /* GPS week of the latest epoch that had one */
    uint8_t have_week;
    nav_real_t lat_cost[APP_GNSS_LAT_BINS]; /* faded misfit per latency candidate */
    uint8_t lat_learnt;             /* the data decided: lat_bin is in use */
    uint8_t lat_bin;                /* the latency in use, APP_GNSS_LAT_STEP_S units */
} gnss_time_t;

/* How far back a fix's time of validity lies. */
typedef struct {
    nav_real_t back;    /* history entries back from the latest (fractional) */
    nav_real_t entry_s; /* time between entries */
    nav_real_t late_s;  /* lateness beyond the on-time epochs' offset */
    uint8_t jumped;     /* the receiver's clock jumped: count time_jumps */
    uint8_t in_history; /* the velocity history reaches that far */
    uint8_t before_history; /* not in_history only because the history is younger: the
                             * epoch is valid before navigation (re)started, not late */
} gnss_when_t;

/* The IMU sample after an epoch arrived: gap 1 when samples were lost before it (or the
 * IMU's clock jumped). An epoch's arrival is the IMU time of the last sample before it, so
 * one that arrived in a gap looked early by up to the gap: the minimum it set (as an
 * earlier epoch, the first, or a clock jump; one or several in the gap) is replaced by the
 * next epoch's offset (lost samples before an epoch otherwise shifted NAV_Time and the
 * time of validity of every later epoch by the gap, until the 50 ppm creep undid it). */
void gnss_time_imu_next(gnss_time_t *g, int gap);

/* Record the navigator's velocity after IMU sample n (every entry_s). */
void gnss_time_record(gnss_time_t *g, uint64_t n_samples, uint32_t imu_rate_hz,
                      const nav_real_t v_n_mps[3]);

/* The time of validity of an epoch with TimeOfWeek tow_ms, received at IMU time imu_t_us
 * (app_time_us: the last sample's); imu_rate_hz sets the history's entry spacing. */
gnss_when_t gnss_time_align(gnss_time_t *g, uint64_t imu_t_us, uint32_t imu_rate_hz,
                            uint32_t tow_ms, nav_real_t latency_s);

/* gnss_time_align's answer for an epoch without learning from it (nothing in g changes):
 * an epoch that align would find late (beyond APP_GNSS_LATE_US) or a first one is not
 * in_history. For a second use of an epoch already aligned (fusion.c, raw_learn). */
gnss_when_t gnss_time_peek(const gnss_time_t *g, uint64_t imu_t_us, uint32_t imu_rate_hz,
                           uint32_t tow_ms, nav_real_t latency_s);

/* Set w's reach back for a latency latency_s (w from gnss_time_align). */
void gnss_time_reach(const gnss_time_t *g, gnss_when_t *w, nav_real_t latency_s);

/* Learn the latency from an epoch's velocity (ENU m/s, horizontal used; sigma_mps its
 * speed sigma) and w (gnss_time_align's); latency_cfg_s: the parameter, the first in use.
 * Only on-time epochs with the whole candidate range in the history count. Returns 1 when
 * the latency in use changed (w's reach is then that of the new latency). */
int gnss_time_learn(gnss_time_t *g, gnss_when_t *w, const nav_real_t v_enu_mps[3],
                    nav_real_t sigma_mps, nav_real_t latency_cfg_s);

/* The latency in use: the learnt one, else latency_cfg_s. */
nav_real_t gnss_time_latency(const gnss_time_t *g, nav_real_t latency_cfg_s);

/* a_ms - b_ms for two GPS times of week (ms), across the week's end: the difference
 * within half a week of zero */
int64_t gnss_tow_diff_ms(uint32_t a_ms, uint32_t b_ms);

/* The navigator's displacement (ENU, m) from then to now: the integral of the velocity
 * history over w.back entries (w.in_history must hold). */
void gnss_time_displacement(const gnss_time_t *g, const gnss_when_t *w, nav_real_t d_n_m[3]);

/* The navigator's velocity then (the nearest entry). */
const nav_real_t *gnss_time_velocity_then(const gnss_time_t *g, const gnss_when_t *w);

/* The GPS week of a usable epoch (GNSS_Time). */
void gnss_time_week(gnss_time_t *g, uint16_t gps_week);

/* The GNSS time of IMU time imu_t_us (app_time_us): the IMU time less the offset to the receiver's clock
 * (its running minimum, an on-time epoch) plus the latency (the epoch's time of validity
 * is that long before its arrival): time of week in microseconds, and the week (65535
 * unknown). 0, or -1 before the first epoch. */
int gnss_time_at(const gnss_time_t *g, uint64_t imu_t_us, nav_real_t latency_s,
                 uint64_t *tow_us, uint16_t *gps_week);

/* Forget the history (a new navigator: its velocities before are not this one's). */
void gnss_time_forget(gnss_time_t *g);

#endif /* NAVECU_GNSS_TIME_H */
