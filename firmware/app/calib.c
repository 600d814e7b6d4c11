/* calib.c - the car's calibration and its NVM policy; see calib.h. */
#include "calib.h"

#include <string.h>

#include "app_tuning.h"
#include "navecu_can.h"
#include "nvstore.h"

void calib_init(calib_t *c)
{
    memset(c, 0, sizeof *c);
    c->store.slot = -1;
}

void calib_boot(calib_t *c, hal_t *hal)
{
    cal_record_t rec;
    const int rc = calstore_load(hal, &c->store, &rec);
    if (rc == CALSTORE_OK && rec.source != (uint8_t)CAL_SRC_NONE) {
        c->dh_rad = (nav_real_t)rec.dh_rad;
        c->mu = (nav_real_t)rec.odo_scale_err;
        c->base_m = (nav_real_t)rec.base_m;
        c->source = rec.source;
        c->status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_FROM_NVM_CHOICE;
        c->stored = 1u;
    } else if (rc == CALSTORE_CORRUPT) {
        c->status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NVM_CORRUPT_CHOICE;
        c->nvm_error = 1u;
    } else if (rc < 0) {
        c->nvm_error = 1u;
    }
}

void calib_store(calib_t *c, calib_trip_t *t, hal_t *hal, uint64_t n)
{
    cal_record_t rec;
    rec.dh_rad = (float)c->dh_rad;
    rec.odo_scale_err = (float)c->mu;
    rec.base_m = (float)c->base_m;
    rec.source = c->source;
    t->last_save_sample = n;
    if (calstore_save(hal, &c->store, &rec) == 0) {
        c->stored = 1u;
        t->stored_mu = c->mu;
        t->stored_dh_rad = c->dh_rad;
        c->nvm_error = 0u;
    } else {
        c->stored = 0u;
        c->nvm_error = 1u;
    }
}

int calib_store_command(calib_t *c, calib_trip_t *t, hal_t *hal, uint64_t n,
                        uint32_t imu_rate_hz)
{
    if (c->source == NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_NONE_CHOICE ||
        (t->last_save_sample != 0u &&
         n - t->last_save_sample < (uint64_t)APP_STORE_MIN_S * imu_rate_hz)) {
        return -1; /* nothing calibrated to store, or asked again too soon (flash wear) */
    }
    calib_store(c, t, hal, n);
    return 0;
}

void calib_erase(calib_t *c, hal_t *hal, dr_t *dr)
{
    /* the stored parameters stay (nvstore.h) */
    if (nvstore_erase_calibration(hal, &c->store) != 0) {
        c->nvm_error = 1u;
        return;
    }
    c->nvm_error = 0u;
    c->dh_rad = NAV_C(0.0);
    c->mu = NAV_C(0.0);
    c->base_m = NAV_C(0.0);
    c->source = NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_NONE_CHOICE;
    c->status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NONE_CHOICE;
    c->stored = 0u;
    if (dr != NULL) {
        (void)dr_set_compensation(dr, c->dh_rad, c->mu);
    }
}

void calib_not_ready(calib_t *c)
{
    c->status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE;
}

int calib_one_point(calib_t *c, calib_trip_t *t, hal_t *hal, uint64_t n, int ready, dr_t *dr,
                    sins_t *nav, const geo_pos_t *point, uint8_t source, nav_real_t min_base_m,
                    dr_cal_t *out)
{
    /* with the filter running, GNSS calibrates the odometer and the mounting: the
     * one-point calibration is for GNSS-denied driving */
    if (!ready) {
        calib_not_ready(c);
        return -1;
    }
    geo_pos_t p = dr->pos;
    p.lat = point->lat;
    p.lon = point->lon;
    dr_cal_t res;
    const int rc = dr_calibrate(dr, &p, min_base_m, &res);
    if (rc != NAV_OK) {
        c->status = rc == NAV_ERANGE
                        ? NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_TOO_CLOSE_CHOICE
                        : NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE;
        return -1;
    }
    c->dh_rad = dr->dh_rad;
    c->mu = dr->mu;
    c->base_m = res.base_m;
    c->source = source;
    c->status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_ONE_POINT_CHOICE;
    if (c->count < UINT8_MAX) {
        c->count++;
    }
    (void)sins_set_position(nav, &dr->pos);
    calib_store(c, t, hal, n);
    if (out != NULL) {
        *out = res;
    }
    return 0;
}

void calib_trip_odo(calib_trip_t *t, int valid, nav_real_t speed_mps, nav_real_t dt_s)
{
    const nav_real_t v = nav_fabs(speed_mps);
    if (valid && v > APP_ODO_MIN_SPEED_MPS && dt_s > NAV_C(0.0) && dt_s < NAV_C(1.0) &&
        v < NAV_C(1000.0)) {
        const nav_real_t d_dmm = v * dt_s * NAV_C(1e4) + NAV_C(0.5);
        const nav_real_t t_us = dt_s * NAV_C(1e6) + NAV_C(0.5);
        t->odo_dist_dmm += (uint64_t)d_dmm;
        t->odo_moving_us += (uint64_t)t_us;
    }
}

int calib_filter_scale(const calib_trip_t *t, const ekf_t *ekf, nav_real_t *v_mean_mps,
                       nav_real_t *mu, nav_real_t *sigma)
{
    if (t->odo_moving_us == 0u || t->odo_dist_dmm == 0u) {
        return 0; /* no speed driven yet: no mean speed for the offset */
    }
    /* k + o / v_mean; its variance a' P a with a = (1, 1 / v_mean) over (k, o);
     * 1 / v_mean = (us / 0.1 mm) x 1e-2 s/m */
    const nav_real_t inv_v =
        (nav_real_t)t->odo_moving_us / (nav_real_t)t->odo_dist_dmm * NAV_C(1e-2);
    *v_mean_mps = NAV_C(1.0) / inv_v;
    *mu = ekf->k + ekf->odo_offset_mps * inv_v;
    const nav_real_t var_mu = ekf->P[EKF_K][EKF_K] +
                              NAV_C(2.0) * inv_v * ekf->P[EKF_K][EKF_OB] +
                              inv_v * inv_v * ekf->P[EKF_OB][EKF_OB];
    *sigma = nav_sqrt(var_mu > NAV_C(0.0) ? var_mu : NAV_C(0.0));
    return 1;
}

void calib_adopt_filter(calib_t *c, calib_trip_t *t, hal_t *hal, uint64_t n,
                        uint32_t imu_rate_hz, const ekf_t *ekf, dr_t *dr, int standing)
{
    nav_real_t v_mean, mu, sk;
    if (!calib_filter_scale(t, ekf, &v_mean, &mu, &sk)) {
        return;
    }
    const nav_real_t sy = ekf_state_sigma(ekf, EKF_MY);
    if (sk * sk + sy * sy > APP_CAL_ADOPT_SIGMA * APP_CAL_ADOPT_SIGMA ||
        dr_set_compensation(dr, ekf->mount_yaw_rad, mu) != NAV_OK) {
        return; /* not converged, or outside what the store accepts */
    }
    c->mu = mu;
    c->dh_rad = ekf->mount_yaw_rad;
    c->source = NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_FILTER_CHOICE;
    const int changed = !t->filter_stored ||
                        nav_fabs(c->mu - t->stored_mu) > APP_CAL_CHANGED_SIGMAS * sk ||
                        nav_fabs(c->dh_rad - t->stored_dh_rad) > APP_CAL_CHANGED_SIGMAS * sy;
    if (changed) {
        c->stored = 0u;
    }
    const uint64_t min_gap = (uint64_t)APP_CAL_SAVE_MIN_S * imu_rate_hz;
    if (changed && standing && (!t->filter_stored || n - t->last_save_sample >= min_gap)) {
        t->filter_stored = 1u;
        c->base_m = NAV_C(0.0);
        if (c->count < UINT8_MAX) {
            c->count++; /* a calibration adopted: CalCount, CalSource Filter */
        }
        calib_store(c, t, hal, n);
    }
}

int calib_start_dr(const calib_t *c, dr_t *dr, const geo_pos_t *pos)
{
    return dr_init(dr, pos, c->dh_rad, c->mu);
}

void calib_sigmas(const calib_t *c, const ekf_config_t *ec, nav_real_t gnss_sigma_axis_m,
                  nav_real_t *mu_sigma, nav_real_t *mount_sigma_rad)
{
    *mu_sigma = ec->k;
    *mount_sigma_rad = ec->mount_rad;
    if (c->source == CAL_SRC_FILTER) {
        /* adopted within a root sum square: each part at most that (a review: split
         * evenly, the scale's sigma was understated by up to 29 %) */
        *mu_sigma = APP_CAL_ADOPT_SIGMA;
        *mount_sigma_rad = APP_CAL_ADOPT_SIGMA;
    } else if ((c->source == CAL_SRC_KNOWN_POSITION || c->source == CAL_SRC_GNSS) &&
               c->base_m > NAV_C(0.0)) {
        const nav_real_t s_pt =
            c->source == CAL_SRC_GNSS ? gnss_sigma_axis_m : APP_KNOWN_POS_SIGMA_M;
        *mu_sigma = NAV_C(1.4142135) * s_pt / c->base_m;
        *mount_sigma_rad = *mu_sigma;
    } else {
        /* nothing calibrated: the priors */
    }
}
