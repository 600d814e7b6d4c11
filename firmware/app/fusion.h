/*
 * fusion.h - the Kalman filter's schedule and supervision (docs/kalman.md): when it
 * starts (the first GNSS fix while navigating), the IMU samples with its bias estimates
 * removed, the prediction every 1/APP_EKF_PRED_HZ with the odometer or standstill
 * updates and their noise, the GNSS update at the fix's time of validity (gnss_time.h)
 * with the antenna lever arm, its gate and the reopening of a filter that keeps refusing
 * fixes, and the supervision that stops a diverged filter (docs/reliability.md).
 *
 * It takes decoded inputs in SI units (no codec types) and reports what the application
 * must do next through fusion_action_t; rejections go to the app_diag_t it is given.
 *
 * Divergence: the filter's state, covariance or the navigator it corrects is no longer
 * finite, a variance went negative (ekf_health repairs the covariance and counts it), or
 * GNSS fixes stay beyond the innovation gate through APP_FILTER_REOPEN_LIMIT covariance
 * reopens in a row while the odometer is refused too or the GNSS course disagrees with
 * the filter's heading (every source then says the filter is wrong; GNSS refused alone is
 * a receiver fault, e.g. a frozen fix, which the gate is there to keep out). A diverged
 * filter is stopped: with GNSS, navigation re-acquires from the next GNSS epoch (as after
 * a long IMU gap) and the filter restarts at the epoch after; without GNSS it goes on as
 * the land navigation system; if the navigator itself is not finite, navigation restarts
 * from the initial state. Counted in health.filter_resets.
 */
#ifndef NAVECU_FUSION_H
#define NAVECU_FUSION_H

#include <stdint.h>

#include "app_config.h"
#include "app_health.h"
#include "dr.h"
#include "ekf.h"
#include "gnss_epoch.h"
#include "gnss_raw.h"
#include "gnss_time.h"
#include "landnav.h"
#include "odo.h"
#include "raw_bias.h"
#include "sins.h"

/* What the tightly coupled updates did (issue #20), kept over navigation restarts
 * (app_keep_t); saturating. */
typedef struct {
    uint32_t epochs_used;   /* raw epochs fused */
    uint32_t pr_used;       /* pseudorange updates applied */
    uint32_t rr_used;       /* range-rate updates applied */
    uint32_t excluded;      /* measurements excluded by the consistency check among the
                               epoch's satellites (fault exclusion: fusion.c) */
    uint32_t gated;         /* measurements refused by the filter's innovation gate */
    uint32_t clock_starts;  /* the clock estimated afresh: the first epoch of a filter, a
                               gap of over 60 s, a reopened filter, a clock jump (these
                               counted in clock_jumps too) */
    uint32_t clock_jumps;   /* receiver clock resets (flagged in GNSS_RawEpoch, or found:
                               every satellite off by the same beyond the clock's sigma) */
    uint32_t corrected;     /* pseudorange updates with their satellite's learnt bias
                               removed (raw_bias.h; gnss_input = both) */
} fusion_raw_counts_t;

typedef struct {
    ekf_t ekf;
    uint8_t on;                 /* the filter runs */
    uint32_t pred_n;            /* samples accumulated for the next prediction */
    nav_real_t pred_t_s;
    nav_real_t f_sum_n[3];      /* sum of velocity increments in ENU over the interval */
    nav_real_t w_sum_rad[3];    /* sum of compensated angle increments over the interval */
    uint32_t odo_frames_used;   /* odo.n_frames at the last odometer update */
    nav_real_t v_prev_pred_mps[2]; /* horizontal velocity at the last prediction */
    uint64_t start_sample;      /* sample at which the filter started */
    app_stamp_t fix;            /* the last GNSS fix the filter took */
    uint8_t vel_gated_run;      /* GNSS velocities refused in a row (diverged: the
                                   witness without wheel speeds) */
    app_stamp_t odo_used;       /* the last odometer or standstill update the filter took */
    uint8_t gated_run;          /* consecutive fixes refused by the gate */
    uint8_t reopen_run;         /* covariance reopens since the last fix taken */
    uint8_t locked_out;         /* fixes refused for APP_FILTER_LOCKOUT_S (gate_run) */
    uint64_t refused_since;     /* sample of the first fix refused in the current run */
    uint64_t gate_prev_sample;  /* sample of the previous fix gate_run saw */
    uint64_t prev_fix_sample;   /* sample of the previous fix offered (fix interval) */
    nav_real_t gnss_sc_prev_m;  /* the correlated part of the previous fix's accuracy */
    uint64_t gnss_bias_sample;  /* sample of the last step of the correlated error state */
    nav_real_t gnss_ep_typ_s;   /* the receiver's usual fix interval (0: none yet) */
    uint32_t nonfinite_seen, negative_seen; /* ekf counters at the last check */
    uint8_t state_lost;         /* the filter's state was found not finite at a feedback */
    nav_real_t course_rad, speed_mps; /* of the latest GNSS epoch with a velocity */
    /* the next start's heading and tilt sigmas (rad) when the start knows them (the
     * in-motion alignment, align.h); 0: the filter's defaults. Used once. */
    nav_real_t init_heading_sigma_rad, init_tilt_sigma_rad;
    nav_real_t w_b_last_rps[3]; /* the mean body rate of the last prediction interval */
    /* raw GNSS (issue #20) */
    uint8_t clock_valid;        /* the filter's clock states hold an estimate */
    uint32_t raw_tow_ms;        /* TimeOfWeek of the last raw epoch fused */
    uint8_t raw_have_tow;       /* one was, within APP_RAW_CLOCK_KEEP_S of the IMU's time */
    uint64_t raw_sample;        /* the IMU sample count at it */
    uint32_t raw_reopens;       /* ekf.n_reopened the clock was estimated with */
    /* the epoch's satellites' geometry (fusion.c raw_geometry), in the epoch's order: formed
     * once per epoch; here, not on the stack (64 bytes each) */
    ekf_sat_t raw_geo[GNSS_RAW_MAX_SATS];
    uint8_t raw_geo_ok[GNSS_RAW_MAX_SATS];
    nav_real_t raw_corr_m[GNSS_RAW_MAX_SATS]; /* the epoch's satellites' learnt biases */
    uint8_t raw_corr_on[GNSS_RAW_MAX_SATS];   /* 1: learnt (raw_bias_of) */
    raw_bias_t raw_bias;        /* each satellite's, learnt while fixes come (raw_bias.h) */
} fusion_t;

/* What the caller does after a fusion step. */
typedef enum {
    FUSION_GO_ON = 0,       /* nothing */
    FUSION_REACQUIRE,       /* the filter was reset: re-acquire from the next GNSS epoch */
    FUSION_RESTART,         /* the navigator is not finite: restart navigation */
} fusion_action_t;

/* What a step needs besides the filter: the navigator, the dead reckoning, the odometer,
 * the configuration, where to report, and the state of the other sources. */
typedef struct {
    sins_t *nav;
    dr_t *dr;
    odo_t *odo;
    landnav_t *land;            /* its heading hold is released: the filter holds it */
    const app_config_t *cfg;
    const app_diag_t *diag;
    app_stamp_t *filter_reset;  /* stamped at a reset (FILTER_RESET flag) */
    const app_stamp_t *gnss;    /* the latest usable GNSS epoch */
    gnss_time_t *time;          /* the receiver's clock and latency, the velocity history
                                   (app_keep_t: the receiver outlives a navigation reset) */
    fusion_raw_counts_t *raw;   /* the tightly coupled updates' counters */
} fusion_ctx_t;

/* The estimates the filter starts from: what standstill and calibration already know. */
typedef struct {
    nav_real_t gyro_bias_z_rps;
    nav_real_t odo_scale;
    uint8_t have_mount_yaw;     /* the calibration in use is the filter's */
    nav_real_t mount_yaw_rad;
    nav_real_t mount_sigma_rad[2]; /* pitch, yaw: the mounting in use's 1-sigma, if known
                                      only that well (the automatic estimate); 0: none */
} fusion_prior_t;

/* One IMU sample with the filter on (SI increments, compensated here). *yaw_rate gets the
 * compensated body z rate (rad/s). */
fusion_action_t fusion_imu_step(fusion_t *fu, const fusion_ctx_t *c, imu_inc_t *inc,
                                nav_real_t *yaw_rate_rps);

/* A usable GNSS epoch while navigating: starts the filter (from the fix) if it is off,
 * then the position and velocity updates. *adopt is set when the calibration may adopt
 * the filter's estimates now (calib_adopt_filter). */
fusion_action_t fusion_gnss(fusion_t *fu, const fusion_ctx_t *c, const fusion_prior_t *prior,
                            const gnss_fix_t *fix, int *adopt);

/* Remember the latest GNSS course and speed (any epoch with a velocity). */
/* One closed raw epoch (gnss_raw.h: the assembly g with its complete satellites in
 * closed->complete; TimeOfWeek tow_ms; clock_reset as flagged in GNSS_RawEpoch) for the
 * tightly coupled updates (docs/kalman.md, "Tightly coupled GNSS"), with cfg->gnss_input
 * raw, or both while the receiver gives no fixes. The filter starts from a fix: before
 * that the epoch is not used. */
fusion_action_t fusion_raw(fusion_t *fu, const fusion_ctx_t *c, const gnss_raw_asm_t *g,
                           const gnss_raw_close_t *closed, uint32_t tow_ms, int clock_reset,
                           int *adopt);

void fusion_note_course(fusion_t *fu, nav_real_t speed_mps, nav_real_t course_rad);

/* Stop the filter (re-acquisition, a reset): it restarts at a later fix. */
void fusion_stop(fusion_t *fu);

/* The number of IMU samples per prediction. */
uint32_t fusion_pred_div(uint32_t imu_rate_hz);

/* The horizontal accuracy the navigator reports (NAV_Status HorizAccuracy), m: the
 * filter's sqrt(P_EE + P_NN) with, while the receiver's correlated error is the filter's
 * state, twice the recent fixes' correlated variance per axis added (ekf_gnss_sc_m;
 * docs/kalman.md, correlated GNSS errors). */
nav_real_t fusion_sigma_h_m(const fusion_t *fu, const app_config_t *cfg);

/* The vertical accuracy the navigator reports (NAV_Height VertAccuracy), m: the filter's
 * height sigma with, while the receiver's correlated error is the filter's state, the
 * recent fixes' correlated vertical variance added (ekf_gnss_scv_m). */
nav_real_t fusion_sigma_v_m(const fusion_t *fu, const app_config_t *cfg);

/* The receiver's error correlation time (s): gnss_corr_s plus the time the wheels have
 * read zero (odo zero_for_s), that at most APP_GNSS_STAND_CORR_MAX_S: a standing antenna
 * sits in its multipath (fusion.c; docs/kalman.md, a standing receiver). */
nav_real_t fusion_rx_corr_s(const app_config_t *cfg, const odo_t *odo);

/* A fix's horizontal sigma per axis (m) from its HorizAccuracy (the radial 1-sigma),
 * clamped to APP_GNSS_SIGMA_FLOOR_M..APP_GNSS_SIGMA_MAX_M: the filter's, and a GNSS
 * calibration point's */
nav_real_t fusion_fix_sigma_axis_m(nav_real_t hacc_m);

#endif /* NAVECU_FUSION_H */
