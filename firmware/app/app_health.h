/*
 * app_health.h - what the application counts and flags: the rejection counters reported
 * in NAV_Status pages 1..6, the time stamps behind the HealthFlags that hold for a while
 * after their event, and the one function every room of the application reports a
 * rejection through (app_diag_reject), so that each refused input is counted once, and
 * flagged REJECTED for a second.
 *
 * Time is the IMU sample count (the application's time base), never arrival time.
 */
#ifndef NAVECU_APP_HEALTH_H
#define NAVECU_APP_HEALTH_H

#include <stdint.h>

/* Counters of everything the application refused; saturating at UINT32_MAX. */
typedef struct {
    uint32_t foreign;          /* frames navecu does not read: other nodes' traffic, not
                                  refused (no REJECTED flag); wraps modulo 2^32 */
    uint32_t bad_dlc;          /* frames of a known message with DLC != 8 */
    uint32_t bad_crc;          /* E2E CRC mismatch */
    uint32_t bad_counter;      /* alive counter repeated or invalid (15): frame dropped */
    uint32_t imu_pair_broken;  /* IMU_Rate without its IMU_Accel or the reverse */
    uint32_t imu_lost;         /* IMU samples missing (counter steps > 1), bridged */
    uint32_t bad_value;        /* out-of-range or implausible physical value */
    uint32_t gnss_rejected;    /* GNSS epochs refused (impossible position, bad fix) */
    uint32_t rx_lost;          /* received frames the HAL lost (hal_can_rx_lost): overruns,
                                  a replayed log's malformed lines */
    uint32_t cmd_rejected;     /* commands refused (missing known position, bad state) */
    uint32_t nav_rejected;     /* IMU samples the strapdown core refused */
    uint32_t time_jumps;       /* receive time going backwards; IMU gaps seen only in time;
                                  GNSS receiver clock jumps */
    uint32_t filter_resets;    /* Kalman filter found diverged and reset (fusion.h) */
    uint32_t tasks_late;       /* app_tasks_ok found a task late: watchdog kick withheld */
    uint32_t nonfinite_out;    /* output values that were not finite: not sent */
    uint32_t imu_saturated;    /* IMU samples with an axis at its configured range */
    uint32_t imu_stuck;        /* IMU axes found stuck (a raw value repeated for 2 s while
                                  another axis moved) */
    uint32_t imu_timing;       /* of bad_value: IMU samples refused for their IMU_Time stamp
                                  (imu_time = stamped: missing, not after the previous one,
                                  an interval outside the band; imu_stream.h) */
    uint32_t odo_rejected;     /* odometer updates refused by the filter's gate (wheel
                                  lock, spin, slip) */
    uint32_t imu_rate_mismatch; /* IMU rate mismatches found: the samples counted between
                                  GNSS epochs disagreed with the configured rate (imu_rate.h) */
} app_health_t;

/* The sample count of the latest event of a kind, and whether there was one. */
typedef struct {
    uint64_t sample;
    uint8_t seen;
} app_stamp_t;

/* The events behind the HealthFlags that restart with navigation (app.h, app_run_t). */
typedef struct {
    app_stamp_t reject;     /* any input refused: REJECTED */
    app_stamp_t gap;        /* IMU samples lost and bridged: IMU_GAP */
    app_stamp_t stuck;      /* an IMU axis stuck while the car moves: IMU_SUSPECT */
    app_stamp_t saturated;  /* an IMU axis at its range: IMU_SATURATED */
    app_stamp_t odo_reject; /* wheel speeds refused by the filter: ODO_REJECTED */
} app_events_t;

/* Where a room reports to: the counters, the events, and the time now. */
typedef struct {
    app_health_t *health;
    app_events_t *events;
    uint64_t n_samples; /* the IMU sample count now */
    uint64_t t_us;      /* the IMU time now, us (app_time_us) */
} app_diag_t;

/* *c += 1, saturating at UINT32_MAX */
void app_count(uint32_t *c);

/* *c += n, saturating at UINT32_MAX */
void app_count_n(uint32_t *c, uint64_t n);

/* Record an event at sample n. */
void app_stamp(app_stamp_t *s, uint64_t n);

/* 1 if the event happened at most window samples before n. */
int app_stamp_within(const app_stamp_t *s, uint64_t n, uint64_t window);

/* Count a refused input in *counter (a field of d->health) and stamp REJECTED. */
void app_diag_reject(const app_diag_t *d, uint32_t *counter);

#endif /* NAVECU_APP_HEALTH_H */
