/*
 * calib.h - the calibration of the car: the one owner of the heading correction dH (or
 * the mounting yaw, which is the same angle when the filter estimates it), the odometer
 * scale error mu, their provenance and their storage in NVM (calstore.h). The dead
 * reckoning and the filter take the values from here (calib_apply_dr, fusion_start); a
 * new estimate (a one-point calibration, the filter's) becomes the calibration here and
 * nowhere else. Limits: DR_DH_MAX_RAD and DR_MU_MAX (dr.h).
 *
 * NVM policy: a one-point calibration is stored at once; the filter's estimates are
 * adopted when converged and stored only at a standstill, only when they moved by more
 * than APP_CAL_CHANGED_SIGMAS, at most every APP_CAL_SAVE_MIN_S (a sector erase stalls
 * the ECU and wears the flash, docs/porting.md); StoreCalibration at most every
 * APP_STORE_MIN_S.
 */
#ifndef NAVECU_CALIB_H
#define NAVECU_CALIB_H

#include <stdint.h>

#include "calstore.h"
#include "dr.h"
#include "ekf.h"
#include "hal.h"
#include "sins.h"

/* What survives a navigation reset: the car's calibration and the NVM. */
typedef struct {
    calstore_t store;
    nav_real_t dh_rad;  /* heading correction / mounting yaw in use (seed 000 eq 9) */
    nav_real_t mu;      /* odometer scale error in use (seed 000 eq 10) */
    nav_real_t base_m;  /* the one-point calibration's base length (its quality) */
    uint8_t status;     /* NAV_Calibration CalStatus */
    uint8_t source;     /* CalSource */
    uint8_t count;      /* one-point calibrations since boot */
    uint8_t stored;     /* the values in use are in NVM */
    uint8_t nvm_error;  /* the last NVM operation failed (HealthFlags NVM_ERROR) */
} calib_t;

/* What restarts with navigation: this trip's storage policy. */
typedef struct {
    nav_real_t stored_mu, stored_dh_rad; /* the values last written to NVM */
    uint64_t last_save_sample;  /* sample of the last NVM save (0: none since the reset) */
    uint8_t filter_stored;      /* the filter's calibration was stored this trip */
    uint64_t odo_dist_dmm;      /* this trip's odometer distance at speed, 0.1 mm (integers:
                                   a float32 sum of an hour's 5-cm steps would round each) */
    uint64_t odo_moving_us;     /* and its time, us: their ratio is the trip's mean speed */
    uint8_t at_gnss;            /* calibrate at the next accepted GNSS fix */
} calib_trip_t;

/* Power-on state: nothing calibrated, no NVM slot known yet. */
void calib_init(calib_t *c);

/* Boot: the stored calibration (a corrupt store leaves the defaults with
 * CalStatus NvmCorrupt; a read error sets nvm_error). */
void calib_boot(calib_t *c, hal_t *hal);

/* Write the values in use to NVM at sample n (nvm_error on a failure). */
void calib_store(calib_t *c, calib_trip_t *t, hal_t *hal, uint64_t n);

/* StoreCalibration: refused (returns -1) when nothing is calibrated or within
 * APP_STORE_MIN_S of the last save; else stores and returns 0. */
int calib_store_command(calib_t *c, calib_trip_t *t, hal_t *hal, uint64_t n,
                        uint32_t imu_rate_hz);

/* EraseCalibration: the store and the values in use, also the dead reckoning's (dr may be
 * NULL when not navigating). An NVM failure leaves everything as it was (nvm_error). */
void calib_erase(calib_t *c, hal_t *hal, dr_t *dr);

/* One-point calibration (seed 000 eqs 7-12) at the true latitude and longitude of point
 * (its height is not used) with CalSource source, when `ready` (navigating on the odometer
 * without the filter): the dead reckoning's estimates composed, the position reset to the
 * point (dr and nav), the result stored, and in *out (if not NULL) dr_calibrate's. Refused
 * with a reason in CalStatus otherwise (returns -1: count it). */
int calib_one_point(calib_t *c, calib_trip_t *t, hal_t *hal, uint64_t n, int ready, dr_t *dr,
                    sins_t *nav, const geo_pos_t *point, uint8_t source, nav_real_t min_base_m,
                    dr_cal_t *out);

/* A calibration asked for when it cannot be done (CalStatus RefusedNotReady). */
void calib_not_ready(calib_t *c);

/* One IMU sample of dt_s with the odometer reading speed_mps (valid: the reading is live):
 * the trip's distance and time at a speed the filter's odometer rows use. */
void calib_trip_odo(calib_trip_t *t, int valid, nav_real_t speed_mps, nav_real_t dt_s);

/* The scale the filter's odometer scale k and speed offset o imply over this trip,
 * k + o / v_mean (v_mean the trip's mean speed at speed, calib_trip_odo), and its sigma
 * from their covariance; 0 before any speed was driven. */
int calib_filter_scale(const calib_trip_t *t, const ekf_t *ekf, nav_real_t *v_mean_mps,
                       nav_real_t *mu, nav_real_t *sigma);

/* The filter's odometer scale and mounting yaw, once converged, are the calibration in use
 * (CalSource Filter), also the dead reckoning's; stored by the policy above. The filter
 * has the odometer's speed offset o besides its scale k (ekf.h, state 22); the dead
 * reckoning and the store have one scale: k + o / v_mean, at the trip's mean speed (what
 * a one-point calibration over this trip would find), its sigma from the filter's
 * covariance of k and o. */
void calib_adopt_filter(calib_t *c, calib_trip_t *t, hal_t *hal, uint64_t n,
                        uint32_t imu_rate_hz, const ekf_t *ekf, dr_t *dr, int standing);

/* Start a dead reckoning at pos with the calibration in use (dr_init). */
int calib_start_dr(const calib_t *c, dr_t *dr, const geo_pos_t *pos);

/* The calibration in use's errors, 1 sigma, for the dead reckoning's accuracy (dr_acc.h):
 * the odometer scale's and the mounting's part of dH. None: the filter's priors
 * (ec's k and mount_rad: ekf_default_config); a one-point calibration: its point's and base's
 * position errors over its base length (seed 000 eqs 9-10 to first order, both points
 * known to APP_KNOWN_POS_SIGMA_M, or to gnss_sigma_axis_m per axis when GNSS gave them: the
 * caller's, a fix's per-axis sigma as the filter takes it, fusion_fix_sigma_axis_m); the
 * filter's: the bound it was adopted within (APP_CAL_ADOPT_SIGMA, a root sum square of the
 * two: each at most that). */
void calib_sigmas(const calib_t *c, const ekf_config_t *ec, nav_real_t gnss_sigma_axis_m,
                  nav_real_t *mu_sigma, nav_real_t *mount_sigma_rad);

#endif /* NAVECU_CALIB_H */
