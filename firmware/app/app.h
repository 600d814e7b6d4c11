/*
 * app.h - the navecu application: CAN in, navigation core, CAN out.
 *
 * The application owns the navigator. It is a dispatcher (app.c) over rooms with one
 * concern each (docs/architecture.md draws who calls whom):
 *   app_rx       receive and validate one frame -> decoded input in SI units
 *   imu_stream   IMU pairing, counter, gap bridging, plausibility -> raw samples
 *   imu_rate     the configured IMU rate against the samples counted between GNSS epochs
 *   gnss_epoch   GNSS frames -> one epoch (gnss_fix_t) with its time of validity
 *   gnss_raw     raw GNSS frames -> one raw epoch of satellites (issue #20; fusion_raw fuses it)
 *   align        initial state, levelling, start, re-acquisition
 *   landnav      standstill and dead reckoning without the filter
 *   fusion       the Kalman filter's schedule, updates and supervision (gnss_time: when
 *                a fix was valid)
 *   calib        the car's calibration (dH, mu, mounting) and its NVM policy
 *   mount_est    the automatic estimate of the IMU's mounting (imu_mount_source automatic)
 *   commands     CMD_Control, CMD_KnownPosition, CMD_InitialAttitude
 *   output       NAV_* frames, HealthFlags, the output mode
 *   app_loop     the main loop's pass, the same on every board
 *   app_uds      diagnostics: the UDS server on its ISO-TP channel, the parameters' DIDs
 *   app_dtc      the fault memory: the health conditions as DTCs (dtc.h), their NVM seam
 * with app_config (what an integrator sets), app_tuning.h (the tuning constants) and
 * app_health (counters and flags).
 *
 * Time base: the IMU sample counter and the configured IMU rate (with imu_time = stamped,
 * the IMU's own IMU_Time stamps for the time, app_time_us), never the arrival time of
 * frames, so the same input gives the same output frames however fast it arrives. Output
 * frames are produced inside app_handle_frame, right after the IMU sample that is due.
 * Everything rejected is counted in app_health_t and reported in NAV_Status pages 1..6.
 * Includes only the core, the CAN codec and hal/hal.h (docs/architecture.md).
 */
#ifndef NAVECU_APP_H
#define NAVECU_APP_H

#include <stddef.h>
#include <stdint.h>

#include "align.h"
#include "app_config.h"
#include "app_dtc.h"
#include "app_health.h"
#include "app_rx.h"
#include "app_uds.h"
#include "calib.h"
#include "dr.h"
#include "dynamics.h"
#include "fusion.h"
#include "gnss_epoch.h"
#include "gnss_raw.h"
#include "hal.h"
#include "imu_rate.h"
#include "imu_stream.h"
#include "landnav.h"
#include "mount_est.h"
#include "mounting.h"
#include "nvstore.h"
#include "odo.h"
#include "output.h"
#include "sins.h"

typedef enum {
    APP_MODE_WAIT_INIT = 0,  /* waiting for an initial position (command or GNSS) */
    APP_MODE_LEVELLING = 1,  /* standing still, averaging the accelerometers */
    APP_MODE_NAVIGATING = 2, /* navigating: the output mode says with what (output.h) */
    APP_MODE_FAULT = 3,
} app_mode_t;

/* What survives a navigation reset (CMD_Control Reset, a SetInitialPosition, a filter
 * whose navigator is lost): the ECU's state, not the trip's. */
typedef struct {
    app_health_t health;
    rx_state_t rx;          /* E2E receive state of the single-frame inputs */
    imu_link_t imu;         /* the IMU's counter, staleness and fault bit */
    imu_rate_t rate;        /* the configured IMU rate against the data: a mismatch holds
                               navigation whatever restarts it (imu_rate.h) */
    uint64_t n_samples;     /* IMU samples processed: the time base, runs on */
    uint64_t imu_t_us;      /* imu_time = stamped: the IMU time of the last sample, us, the
                               sum of the samples' stamped intervals (app_time_us) */
    uint64_t last_rx_t_us;  /* latest receive time seen (time jumps) */
    tx_state_t tx;          /* E2E transmit state and what was sent */
    uint64_t last_poll_us;  /* HAL time of the last app_poll (task supervision) */
    uint8_t have_poll;
    app_stamp_t filter_reset; /* the flag outlives the reset it caused */
    app_stamp_t gnss;       /* the latest usable GNSS epoch (NO_GNSS): the receiver's state,
                               so a Reset or SetInitialPosition does not say NO_GNSS */
    gnss_time_t gnss_time;  /* the receiver's clock against the IMU's, its GPS week and
                               latency, from every usable epoch (NAV_Time from the first
                               sample of a start); the navigator's velocity history in it
                               is forgotten at each navigation (re)start */
    calib_t cal;            /* the car's calibration and the NVM */
    zbias_t zbias;          /* the z gyro bias learnt at standstill (the IMU's) */
    uint64_t zbias_sample;  /* n_samples at its last standstill sample */
    odo_t odo;              /* the car's odometer */
    mounting_t mount;       /* the IMU's configured rotation into the vehicle's axes */
    mount_est_t mest;       /* the automatic mounting estimate (imu_mount_source automatic) */
    uint8_t mount_state;    /* app_mount_state_t */
    nav_real_t mount_sigma_rad[2]; /* 1-sigma (roll/pitch, yaw) of the mounting in use when
                                      it is the automatic estimate's, at its convergence;
                                      0 for a configured one */
    dtc_t dtc;              /* the fault memory: a DTC per health condition (app_dtc.h) */
    gnss_raw_asm_t raw;     /* the raw GNSS epoch in assembly (gnss_raw.h; the receiver's
                               state: outlives a navigation reset) */
    uint32_t raw_epochs;    /* raw epochs closed with a complete satellite (saturating) */
    uint32_t raw_sats;      /* their complete satellites (saturating) */
    fusion_raw_counts_t raw_counts; /* what the tightly coupled updates did (fusion.h) */
    uint8_t cmd_refusal;         /* why the last command was refused (cmd_refusal_t; not a
                                    counter, so not in app_health_t, whose fields all are) */
    uint32_t dtc_dirty;          /* DTCs whose stored byte changed, not yet in NVM (bit i) */
    uint32_t dtc_persist_writes; /* NVM record writes of the DTC status bytes (app_dtc.c) */
    uint32_t dtc_persist_failed; /* of them, writes that failed */
} app_keep_t;

/* The mounting's state (NAV_Calibration MountState, DID 0x0260). */
typedef enum {
    APP_MOUNT_FIXED = 0,      /* imu_mount_source fixed: imu_mount_rad */
    APP_MOUNT_ESTIMATING = 1, /* automatic, not converged: navigation held */
    APP_MOUNT_ESTIMATED = 2,  /* automatic, converged: the estimate is the mounting */
} app_mount_state_t;

/* What restarts with navigation: a reset is one assignment of zeros (app_reset). */
typedef struct {
    app_mode_t mode;
    app_events_t events;    /* stamps behind the HealthFlags that hold for a while */
    imu_stream_t imu;       /* the IMU pair in assembly, the plausibility checks */
    gnss_asm_t gnss_asm;    /* the GNSS epoch in assembly */
    align_t align;          /* initial state, levelling, re-acquisition */
    sins_t nav;             /* the strapdown navigator */
    dr_t dr;                /* dead reckoning alongside */
    landnav_t land;         /* standstill, dead reckoning output */
    fusion_t fusion;        /* the Kalman filter */
    calib_trip_t cal;       /* this trip's calibration storage policy */
    dynamics_t dyn;         /* the motion since the last dynamics output */
    nav_real_t yaw_rate_rps;/* body z rate of the last IMU sample */
    uint8_t rate_held;      /* mode Fault for an IMU rate mismatch, from rate_resume */
    app_mode_t rate_resume; /* WaitInit or Levelling: where it goes on when the rate matches */
    uint8_t mount_held;     /* mode Fault: the start waits for the mounting estimate */
    uint8_t mount_start;    /* the estimate converged: start from GNSS, driving */
} app_run_t;

struct app {
    app_config_t cfg;
    nvstore_status_t nvm;   /* what app_start loaded from NVM (UDS DID 0xF1A1) */
    uint8_t started;        /* started by app_start: an ECUReset layers again */
    app_keep_t keep;
    app_run_t run;
    app_uds_t uds;          /* diagnostics: UDS over ISO-TP (app_uds.h), off the navigation
                               path; restarted with the application (ECUReset) */
};

/* Start in APP_MODE_WAIT_INIT. Returns NAV_OK, or NAV_EINVAL for a config out of range. */
int app_init(app_t *app, const app_config_t *cfg);

/* app_init with the table's defaults (app_config_defaults), in app_start's copy of the
 * configuration: a board's first start, without a copy of its own in RAM. NAV_OK (the
 * defaults are valid: test_app). */
int app_init_defaults(app_t *app);

/*
 * The boot of every board, in layers: the table's defaults, the parameters stored in NVM
 * over them (nvstore.h), then the board's own layer app_board_layer over both; app_init
 * with the result, then app_boot. ECUReset (UDS 0x11) runs it again, so what was written
 * over UDS and not saved (RoutineControl 0x0200) is gone after it, as on a real ECU.
 * A refused extension or refused entries raise NAV_Status NVM_ERROR (and DID 0xF1A1 says
 * which and how many), as a corrupt calibration record does.
 * Returns NAV_OK, or NAV_EINVAL when the result is refused (by the layer or app_init).
 */
int app_start(app_t *app, hal_t *hal);

/* The board's configuration layer over the defaults and the NVM (app_start): 0, or
 * nonzero to refuse the configuration. The default (weak, in app.c) changes nothing; the
 * host defines its own, its command-line options (host_sim/main.c). */
int app_board_layer(app_config_t *cfg);

/* Once after app_init: load the stored calibration from NVM (calstore.h) as the starting
 * values. A corrupt store leaves the defaults (0, 0) with CalStatus NvmCorrupt; an NVM
 * read error also sets the NVM_ERROR flag. */
void app_boot(app_t *app, hal_t *hal);

/* 1 when the application may write NVM now: navigation not started, or the car standing
 * (a flash erase stalls the CPU for hundreds of ms on a single-bank flash: never while
 * moving). The UDS routines and the DTC status bytes (app_dtc.c) follow it. */
int app_nvm_write_allowed(const app_t *a);

/* Process one received frame; may send frames through hal. Never fails: whatever is
 * wrong with the frame is counted in app->keep.health. A frame on the UDS request ID goes
 * to the diagnostic channel first (app_uds.h) and to nothing else. */
void app_handle_frame(app_t *app, hal_t *hal, const hal_can_frame_t *frame);

/* Restart navigation (CMD_Control Reset): everything in app_run_t starts again;
 * configuration, health, E2E state, the time base, the calibration, the standstill gyro
 * bias and the odometer are kept (app_keep_t). */
void app_reset(app_t *app);

/* Call from the main loop (after each frame, or on a timer): while no IMU data arrives,
 * NAV_Status goes on at its rate on the HAL clock with the IMU_STALE flag. Diagnostics
 * are served here too (app_uds_poll: ISO-TP timing, S3, a pending ECUReset). */
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
 * The automatic mounting estimate into the parameters: once it has converged (mount_state
 * APP_MOUNT_ESTIMATED) the latest estimate (it goes on refining after convergence) is
 * copied into cfg.imu_mount_rad and imu_mount_source becomes fixed, so that a parameter
 * save (RoutineControl 0x0200) keeps it and the next start uses it without estimating
 * again. The mounting in use does not change before that restart. Returns 0, or -1 when
 * there is no converged estimate (nothing changed). RoutineControl 0x0204 AdoptMounting
 * calls it.
 */
int app_adopt_mounting(app_t *app);

/* The mounting estimate's state and result (DID 0x0260, NAV_Calibration). */
static inline const mount_est_result_t *app_mount_estimate(const app_t *app)
{
    return &app->keep.mest.res;
}

/* Read-only views for the board's summary and the tests. */
static inline app_mode_t app_mode(const app_t *app) { return app->run.mode; }
static inline uint64_t app_samples(const app_t *app) { return app->keep.n_samples; }
/* The IMU time now, us: on the grid the sample count over the configured rate; stamped
 * (imu_time), the sum of the samples' IMU_Time intervals (a sample without one, the first,
 * counts the nominal period). What GNSS epochs are aligned to and NAV_Height's
 * TimeOfValidity and NAV_Time carry. */
static inline uint64_t app_time_us(const app_t *app)
{
    return app->cfg.imu_time == IMU_TIME_STAMPED
               ? app->keep.imu_t_us
               : app->keep.n_samples * 1000000u / app->cfg.imu_rate_hz;
}
static inline const app_health_t *app_health(const app_t *app) { return &app->keep.health; }
/* The HAL time IMU_STALE counts from: the last IMU sample's, or before the first the
 * power-on's (the first NAV_Heartbeat's; app_poll sends that first) */
static inline uint64_t app_imu_since(const app_t *app)
{
    return app->keep.imu.have_sample ? app->keep.imu.last_t_us : app->keep.tx.boot_us;
}
/* The application's counters, events, sample count and time, for a module to count and
 * stamp its rejections with (app_health.h). */
app_diag_t app_diag_of(app_t *a);
static inline const calib_t *app_calibration(const app_t *app) { return &app->keep.cal; }

/* The configured gyro figures the standstill bias estimate and its accuracy use. */
static inline zbias_prior_t app_zbias_prior(const app_config_t *cfg)
{
    const zbias_prior_t p = {cfg->gyro_arw_rad_rts, cfg->gyro_bias_rps,
                             cfg->gyro_bias_rw_rps_rts};
    return p;
}
/* Kalman updates applied so far (a board's trace) */
static inline uint32_t app_filter_updates(const app_t *app) { return app->run.fusion.ekf.n_updates; }
/* the filter, or NULL when it does not run */
static inline const ekf_t *app_filter(const app_t *app)
{
    return app->run.fusion.on ? &app->run.fusion.ekf : NULL;
}

/*
 * Profiling points: the application calls app_trace(point, 0) before and
 * app_trace(point, 1) after each of these steps. app.c defines app_trace as a weak
 * function that does nothing (a few instructions per call); a board may define its own to
 * time the steps (boards/qemu/, make target-bench). It must not touch the application's
 * state, so timing never changes what is computed.
 */
typedef enum {
    APP_TRACE_MECHANIZATION = 0, /* the strapdown step of one IMU sample (filter running) */
    APP_TRACE_PREDICTION,        /* the filter's covariance prediction (10 Hz) */
    APP_TRACE_ODOMETER_UPDATE,   /* the odometer's speed and non-holonomic updates */
    APP_TRACE_GNSS_UPDATE,       /* one GNSS epoch: latency, gates, position and velocity */
    APP_TRACE_FRAME,             /* one received frame: app_handle_frame + app_poll */
    APP_TRACE_N
} app_trace_point_t;
void app_trace(uint32_t point, uint32_t end);

#endif
