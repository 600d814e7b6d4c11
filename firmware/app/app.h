/*
 * app.h - the navecu application: CAN in, navigation core, CAN out.
 *
 * The application owns the navigator. It decodes and validates every received frame
 * (length, E2E CRC and alive counter, value ranges, plausibility), assembles IMU samples
 * from IMU_Rate + IMU_Accel pairs, feeds the strapdown core, and emits the NAV_* frames.
 *
 * Time base: the IMU sample counter and the configured IMU rate, never the arrival time of
 * frames, so the same input gives the same output frames however fast it arrives. Output
 * frames are produced inside app_handle_frame, right after the IMU sample that is due.
 *
 * Everything rejected is counted in app_health_t and reported in NAV_Status pages 1..3.
 * Includes only the core, the CAN codec and hal/hal.h (docs/architecture.md).
 */
#ifndef NAVECU_APP_H
#define NAVECU_APP_H

#include <stddef.h>
#include <stdint.h>

#include "calstore.h"
#include "dr.h"
#include "e2e.h"
#include "ekf.h"
#include "hal.h"
#include "odo.h"
#include "sins.h"

typedef struct {
    uint16_t imu_rate_hz;    /* IMU sample rate, 10..400 */
    uint16_t nav_rate_hz;    /* NAV_Position/Height/Velocity/Attitude rate, <= imu_rate_hz */
    uint16_t status_rate_hz; /* NAV_Status rate, <= imu_rate_hz */
    uint16_t level_s;        /* accelerometer levelling time before navigation starts */
    odo_axle_t odo_axle;     /* wheels that measure the distance (odo.h) */
    nav_real_t cal_min_base_m;    /* one-point calibration refused closer than this to its base */
    /* the gyro's noise and bias, for the bias estimate at standstill (a scalar Kalman
     * filter of a constant with a zero-mean prior): */
    nav_real_t gyro_arw_rad_rts;  /* angle random walk, rad/sqrt(s) */
    nav_real_t gyro_bias_rps;     /* 1-sigma of the turn-on bias, rad/s */
    nav_real_t accel_bias_mps2;   /* 1-sigma of the accelerometer bias, m/s^2 */
    nav_real_t gyro_bias_rw_rps_rts;    /* in-run gyro bias random walk, rad/s/sqrt(s) */
    nav_real_t accel_bias_rw_mps2_rts;  /* in-run accelerometer bias random walk */
    nav_real_t gnss_latency_s;    /* receiver output latency: fix time of validity to
                                     arrival (more when TimeOfWeek shows a late epoch) */
    nav_real_t gnss_lever_b_m[3]; /* GNSS antenna from the IMU, body axes, m */
    nav_real_t gnss_corr_s;       /* correlation time of the receiver's position errors */
    nav_real_t odo_lever_b_m[3];  /* the odometer's reference point (rear axle middle) from
                                     the IMU, body axes, m */
    nav_real_t gyro_range_rps;    /* the IMU's measurement range: a rate at or beyond it is */
    nav_real_t accel_range_mps2;  /* saturated (counted, flagged) */
} app_config_t;

/* Counters of everything the application refused; saturating at UINT32_MAX. */
typedef struct {
    uint32_t unknown_id;       /* frames with an identifier the protocol does not define */
    uint32_t bad_dlc;          /* frames of a known message with DLC != 8 */
    uint32_t bad_crc;          /* E2E CRC mismatch */
    uint32_t bad_counter;      /* alive counter repeated or invalid (15): frame dropped */
    uint32_t imu_pair_broken;  /* IMU_Rate without its IMU_Accel or the reverse */
    uint32_t imu_lost;         /* IMU samples missing (counter steps > 1), bridged */
    uint32_t bad_value;        /* out-of-range or implausible physical value */
    uint32_t gnss_rejected;    /* GNSS epochs refused (impossible position, bad fix) */
    uint32_t log_line_bad;     /* malformed source frames skipped by the HAL */
    uint32_t cmd_rejected;     /* commands refused (missing known position, bad state) */
    uint32_t nav_rejected;     /* IMU samples the strapdown core refused */
    uint32_t time_jumps;       /* receive time going backwards; IMU gaps seen only in time */
    uint32_t filter_resets;    /* Kalman filter found diverged and reset (app_t supervision) */
    uint32_t tasks_late;       /* app_tasks_ok found a task late: watchdog kick withheld */
    uint32_t nonfinite_out;    /* output values that were not finite: not sent */
    uint32_t imu_saturated;    /* IMU samples with an axis at its configured range */
    uint32_t imu_stuck;        /* IMU axes found stuck (a raw value repeated for 2 s while
                                  another axis moved) */
    uint32_t imu_timing;       /* IMU samples received more than half a period off time */
    uint32_t odo_rejected;     /* odometer updates refused by the filter's gate (wheel
                                  lock, spin, slip) */
} app_health_t;

typedef enum {
    APP_MODE_WAIT_INIT = 0,  /* waiting for an initial position (command or GNSS) */
    APP_MODE_LEVELLING = 1,  /* standing still, averaging the accelerometers */
    APP_MODE_NAVIGATING = 2, /* inertial only: the free SINS is the output */
    APP_MODE_FAULT = 3,
    APP_MODE_DEAD_RECKONING = 4, /* odometer along the SINS heading is the output */
} app_mode_t;

/* HealthFlags bits of NAV_Status page 0 */
#define APP_FLAG_IMU_STALE 0x0001u    /* no IMU sample for more than 0.5 s of bus time */
#define APP_FLAG_IMU_FAULT 0x0002u    /* the IMU reports a fault */
#define APP_FLAG_NO_GNSS 0x0004u      /* no usable GNSS epoch in the last 2 s of IMU time */
#define APP_FLAG_REJECTED 0x0008u     /* some input was rejected in the last second */
#define APP_FLAG_NVM_ERROR 0x0010u    /* the last NVM operation failed */
#define APP_FLAG_NO_HEADING 0x0020u   /* waiting for a heading (command or GNSS course) */
#define APP_FLAG_IMU_GAP 0x0040u      /* IMU samples were lost and bridged in the last second */
#define APP_FLAG_FILTER_RESET 0x0080u /* the Kalman filter diverged and was reset in the last 10 s */
#define APP_FLAG_IMU_SUSPECT 0x0100u  /* an IMU axis was found stuck in the last 10 s */
#define APP_FLAG_IMU_SATURATED 0x0200u /* an IMU axis was at its range in the last second */
#define APP_FLAG_ODO_REJECTED 0x0400u /* the wheel speeds disagreed with the filter in the last second */
#define APP_FLAG_REACQUIRE 0x0800u    /* after a long IMU gap or a filter reset: waiting for
                                         GNSS to re-acquire */

/* IMU gaps up to this many milliseconds are bridged by repeating the next sample; a longer
 * gap stops navigation (output mode Fault, HealthFlags REACQUIRE) until a GNSS epoch gives
 * position, velocity and heading again (app.c, re-acquisition), or, without GNSS, until the
 * next SetInitialPosition. */
#define APP_MAX_BRIDGE_MS 200u

typedef struct {
    app_config_t cfg;
    app_health_t health;
    app_mode_t mode;
    uint16_t flags_sticky; /* flags that persist until cleared by their cause */
    sins_t nav;

    /* E2E receive state per protected input; kept through a reset, so that a replayed
     * old frame is never taken for a first one */
    e2e_counter_t rx_imu, rx_wheel, rx_cmd, rx_gnss_vel, rx_att;
    uint64_t last_rx_t_us;      /* latest receive time seen (time jumps) */
    uint64_t last_status_t_us;  /* receive time of the last NAV_Status (app_poll) */
    uint64_t last_poll_us;      /* HAL time of the last app_poll (task supervision) */
    uint8_t have_poll;
    uint64_t last_gap_sample;   /* sample count at the last IMU gap */
    uint8_t had_gap;
    /* IMU pair assembly */
    uint8_t rate_pending;       /* an IMU_Rate waits for its IMU_Accel */
    uint8_t rate_counter;
    uint8_t rate_data[8];       /* its payload, covered by the pair CRC */
    int32_t rate_raw[3];
    uint8_t have_sample;        /* a sample has been processed (staleness) */
    uint64_t n_samples;         /* IMU samples processed: the time base */
    uint64_t last_imu_t_us;     /* HAL time of the last IMU sample (staleness only) */
    uint64_t last_reject_sample;
    uint8_t rejected_recently;

    /* initial state */
    uint8_t known_pos_valid;
    int32_t known_lat_e7, known_lon_e7;
    uint8_t init_pos_valid, init_heading_valid;
    int32_t init_lat_e7, init_lon_e7;
    int32_t init_h_cm;
    nav_real_t init_heading_rad;
    nav_real_t level_wsum[3];   /* weighted sum of velocity increments (levelling) */
    nav_real_t level_wsum_lo[3];
    uint32_t level_n;           /* samples levelled so far */

    /* GNSS epoch assembly */
    uint8_t gnss_pos_pending, gnss_vel_pending, gnss_h_pending;
    uint8_t gnss_pos_rejected;  /* this epoch's position was refused (count once) */
    uint8_t gnss_vel_epoch, gnss_h_epoch;
    uint8_t course_valid;       /* a GNSS course was seen while moving (GNSS init) */
    nav_real_t course_rad;
    int32_t gnss_lat_e7, gnss_lon_e7, gnss_h_cm;
    int16_t gnss_vel_raw[3];
    uint64_t last_gnss_sample;
    uint8_t have_gnss;

    /* odometer, dead reckoning, standstill (docs/odometry.md) */
    odo_t odo;
    dr_t dr;
    uint8_t output_dr;          /* the dead-reckoned solution is the output (mode 4) */
    uint8_t holding;            /* standstill: heading held at hold_heading_rad */
    nav_real_t hold_heading_rad;
    nav_real_t yaw_rate_rps;    /* body z rate of the last IMU sample */
    nav_real_t gz_sum, gz_sum_lo; /* sum of (gyro z - Earth rate) at standstill, rad/s */
    uint32_t gz_n;              /* samples in gz_sum */
    nav_real_t gyro_bias_z_rps; /* estimate applied to every sample */

    /* Kalman filter (docs/kalman.md): runs from the first GNSS fix while navigating */
    ekf_t ekf;
    uint8_t ekf_on;
    uint8_t ekf_cal_stored;     /* the filter's calibration was stored this trip */
    uint32_t pred_n;            /* samples accumulated for the next prediction */
    nav_real_t pred_t_s;
    nav_real_t f_sum_n[3];      /* sum of velocity increments in ENU over the interval */
    nav_real_t w_sum_rad[3];    /* sum of compensated angle increments over the interval */
    uint32_t odo_frames_used;   /* odo.n_frames at the last odometer update */
    nav_real_t v_prev_pred_mps[2]; /* horizontal velocity at the last prediction */
#define APP_VHIST 64
    nav_real_t vhist[APP_VHIST][3]; /* velocity of the last samples (GNSS latency) */
    uint32_t vhist_n;           /* samples written */
    int64_t gnss_off_min_us;    /* min over epochs of (IMU time - TimeOfWeek) */
    uint8_t gnss_off_valid;
    uint8_t gnss_late_run;      /* consecutive epochs more than 0.5 s late */
    uint16_t gnss_hacc_dm, gnss_vacc_dm; /* this epoch's accuracies, 0.1 m */
    uint8_t gnss_sacc_raw;      /* SpeedAccuracy of the epoch's velocity, 0.1 m/s */
    uint64_t last_fix_sample;   /* sample of the last GNSS fix used by the filter */
    uint8_t have_fix;
    uint8_t gnss_gated_run;     /* consecutive fixes refused by the gate */
    uint64_t gnss_prev_sample;  /* sample of the previous fix offered to the filter */
    int64_t gnss_prev_t_us;     /* IMU time of the previous epoch (clock-drift allowance) */
    uint64_t ekf_start_sample;  /* sample at which the filter started */
    uint8_t gnss_reopen_run;    /* covariance reopens since the last fix taken */
    uint32_t ekf_nonfinite_seen, ekf_negative_seen; /* ekf counters at the last check */
    uint64_t last_filter_reset_sample; /* sample of the last filter reset */
    uint8_t had_filter_reset;
    /* re-acquisition after an IMU gap too long to bridge: the attitude before the gap is
     * kept; position, velocity and (when driving) heading come from the next GNSS epoch */
    uint8_t reacquire;
    uint8_t imu_resync_valid;   /* a sample with a counter jump waits for confirmation */
    uint8_t imu_resync_counter;
    nav_real_t gnss_course_rad, gnss_speed_mps; /* of the latest epoch with a velocity */
    nav_real_t reacq_roll_rad, reacq_pitch_rad, reacq_heading_rad, reacq_mount_rad;
    /* IMU plausibility: an axis whose raw increment repeats exactly (stuck), saturation */
    int32_t imu_last_raw[6];
    uint32_t imu_same_n[6];     /* consecutive samples with the same raw value, per axis */
    int32_t imu_blk_min[6], imu_blk_max[6];   /* raw range of each axis in this block and */
    int32_t imu_prev_min[6], imu_prev_max[6]; /* the previous one (IMU_STUCK_S / 2 each) */
    uint32_t imu_blk_n;
    uint8_t imu_stuck_seen;     /* axes whose current stuck episode was counted (bits) */
    int32_t imu_sat_raw[2];     /* gyro and accelerometer range in raw LSB (0: not yet) */
    uint64_t last_stuck_sample, last_sat_sample, last_odo_reject_sample;
    uint8_t had_stuck, had_sat, had_odo_reject;

    /* calibration (seed 000 eqs 7-12) and its storage */
    calstore_t calstore;
    nav_real_t cal_dh_rad, cal_mu; /* in use (also the DR's) */
    uint8_t cal_status;         /* NAV_Calibration CalStatus */
    uint8_t cal_source;         /* CalSource */
    uint8_t cal_count;          /* one-point calibrations since boot */
    uint8_t cal_stored;         /* the values in use are in NVM */
    uint8_t cal_at_gnss;        /* calibrate at the next accepted GNSS fix */
    nav_real_t stored_mu, stored_dh_rad; /* the values last written to NVM */
    uint64_t last_save_sample;  /* sample of the last NVM save (0: none since boot) */
    nav_real_t cal_base_m;

    /* output */
    uint8_t tx_counter[6];      /* alive counters of the E2E-protected outputs */
    uint8_t status_page;        /* next counter page of NAV_Status (1..3) */
    uint32_t frames_sent;
    uint32_t send_errors;
} app_t;

/* Defaults: IMU 100 Hz, outputs 50 Hz, status 10 Hz, levelling 30 s. */
app_config_t app_default_config(void);

/* Start in APP_MODE_WAIT_INIT. Returns NAV_OK, or NAV_EINVAL for a config out of range. */
int app_init(app_t *app, const app_config_t *cfg);

/* Once after app_init: load the stored calibration from NVM (calstore.h) as the starting
 * values. A corrupt store leaves the defaults (0, 0) with CalStatus NvmCorrupt; an NVM
 * read error also sets the NVM_ERROR flag. */
void app_boot(app_t *app, hal_t *hal);

/* Process one received frame; may send frames through hal. Never fails: whatever is
 * wrong with the frame is counted in app->health. */
void app_handle_frame(app_t *app, hal_t *hal, const hal_can_frame_t *frame);

/* The CAN identifiers the application receives (for receive filters): writes up to max
 * of them to ids and returns how many there are. */
size_t app_rx_ids(uint32_t *ids, size_t max);

/* Call from the main loop (after each frame, or on a timer): while no IMU data arrives,
 * NAV_Status goes on at its rate on the HAL clock with the IMU_STALE flag. */
void app_poll(app_t *app, hal_t *hal);

/*
 * Task supervision: did every task of the application run in time? The main loop calls
 * it once per pass, after app_poll, with the HAL clock, and kicks the watchdog only when
 * it returns 1 (so a stuck loop or task ends in a watchdog reset, not in a silent ECU):
 *  - NAV_Status, which app_poll keeps going even without input, went out within
 *    APP_STATUS_DEADLINE_PERIODS status periods of now (the loop and app_poll run);
 *  - while navigating with the Kalman filter, its prediction ran within
 *    APP_PREDICT_DEADLINE_PERIODS prediction periods of IMU time (the filter task runs;
 *    IMU time stops when the IMU does, so missing input is not a late task).
 * A late task is counted in health.tasks_late. Input faults (a silent IMU, rejected
 * frames) are not task failures: they are flagged in NAV_Status and navigation goes on.
 */
#define APP_STATUS_DEADLINE_PERIODS 3u
#define APP_PREDICT_DEADLINE_PERIODS 3u
int app_tasks_ok(app_t *app, uint64_t now_us);

/*
 * Profiling points: the application calls app_trace(point, 0) before and
 * app_trace(point, 1) after each of these steps. app.c defines app_trace as a weak
 * function that does nothing (a few instructions per call); a board may define its own to
 * time the steps (hal/cortex_m4f/main_qemu.c, make target-bench). It must not touch the
 * application's state, so timing never changes what is computed.
 */
typedef enum {
    APP_TRACE_MECHANIZATION = 0, /* the strapdown step of one IMU sample (filter running) */
    APP_TRACE_PREDICTION,        /* the filter's covariance prediction (10 Hz) */
    APP_TRACE_ODOMETER_UPDATE,   /* the odometer's speed and non-holonomic updates */
    APP_TRACE_GNSS_UPDATE,       /* one GNSS epoch: latency, gates, position and velocity */
    APP_TRACE_N
} app_trace_point_t;
void app_trace(uint32_t point, uint32_t end);

#endif
