/*
 * dr.c - dead reckoning and one-point calibration (dr.h; seed 000 eqs 1-4, 7-12).
 */
#include "dr.h"

#include <stddef.h>

/* radians per fixed-point angle LSB: pi / 180 / 1e7 / 2^24 */
#define RAD_PER_LSB NAV_C(3.14159265358979323846 / (1.8e9 * (double)GEO_LSB_PER_DEG_E7))

static int comp_ok(nav_real_t dh_rad, nav_real_t mu)
{
    return nav_isfinite(dh_rad) && nav_isfinite(mu) && nav_fabs(dh_rad) <= DR_DH_MAX_RAD &&
           nav_fabs(mu) <= DR_MU_MAX;
}

int dr_init(dr_t *d, const geo_pos_t *pos, nav_real_t dh_rad, nav_real_t mu)
{
    if (d == NULL || pos == NULL || !comp_ok(dh_rad, mu)) {
        return NAV_EINVAL;
    }
    d->pos = *pos;
    d->base = *pos;
    d->dh_rad = dh_rad;
    d->mu = mu;
    d->step_e_m = NAV_C(0.0);
    d->step_n_m = NAV_C(0.0);
    return NAV_OK;
}

int dr_step(dr_t *d, nav_real_t ds_m, nav_real_t heading_rad, nav_real_t pitch_rad)
{
    if (!nav_isfinite(ds_m) || !nav_isfinite(heading_rad) || !nav_isfinite(pitch_rad) ||
        nav_fabs(ds_m) > NAV_C(100.0)) {
        return NAV_EINVAL;
    }
    const nav_real_t ds_c = ds_m / (NAV_C(1.0) + d->mu);       /* eqs 11-12, exact form */
    const nav_real_t h_c = heading_rad - d->dh_rad;
    const nav_real_t ds_h = ds_c * nav_cos(pitch_rad);
    const nav_real_t de = ds_h * nav_sin(h_c);                  /* eq 3 */
    const nav_real_t dn = ds_h * nav_cos(h_c);                  /* eq 4 */
    const nav_real_t lat = geo_lat_rad(&d->pos);
    const nav_real_t h = geo_h_m(&d->pos);
    nav_real_t R_M, R_N;
    earth_radii(nav_sin(lat), &R_M, &R_N);
    const int rc = geo_pos_add(&d->pos, dn / (R_M + h),                      /* eq 1 */
                               de / ((R_N + h) * nav_cos(lat)),              /* eq 2 */
                               ds_c * nav_sin(pitch_rad));
    if (rc != NAV_OK) {
        return rc;
    }
    d->step_e_m = de;
    d->step_n_m = dn;
    return NAV_OK;
}

int dr_set_compensation(dr_t *d, nav_real_t dh_rad, nav_real_t mu)
{
    if (!comp_ok(dh_rad, mu)) {
        return NAV_EINVAL;
    }
    d->dh_rad = dh_rad;
    d->mu = mu;
    return NAV_OK;
}

void dr_set_position(dr_t *d, const geo_pos_t *pos)
{
    d->pos = *pos;
}

void dr_local_m(const geo_pos_t *ref, const geo_pos_t *p, nav_real_t *e_m, nav_real_t *n_m)
{
    const int64_t dlat = p->lat - ref->lat;
    int64_t dlon = p->lon - ref->lon;
    if (dlon > GEO_LSB_180DEG) {
        dlon -= 2 * GEO_LSB_180DEG;
    } else if (dlon < -GEO_LSB_180DEG) {
        dlon += 2 * GEO_LSB_180DEG;
    }
    const nav_real_t dlat_rad = (nav_real_t)dlat * RAD_PER_LSB;
    const nav_real_t dlon_rad = (nav_real_t)dlon * RAD_PER_LSB;
    const nav_real_t lat_ref = geo_lat_rad(ref);
    const nav_real_t h = geo_h_m(ref);
    nav_real_t R_M, R_N;
    earth_radii(nav_sin(lat_ref), &R_M, &R_N);
    *n_m = dlat_rad * (R_M + h);
    *e_m = dlon_rad * (R_N + h) * nav_cos(lat_ref + NAV_C(0.5) * dlat_rad);
}

int onepoint_exact(nav_real_t d_e_m, nav_real_t d_n_m, nav_real_t t_e_m, nav_real_t t_n_m,
                   nav_real_t *dh_rad, nav_real_t *mu)
{
    const nav_real_t t2 = t_e_m * t_e_m + t_n_m * t_n_m;
    const nav_real_t d2 = d_e_m * d_e_m + d_n_m * d_n_m;
    if (!(t2 > NAV_C(0.0)) || !(d2 > NAV_C(0.0)) || !nav_isfinite(t2) || !nav_isfinite(d2)) {
        return NAV_EINVAL;
    }
    /* bearing of d minus bearing of t (bearings clockwise from north, as headings) */
    *dh_rad = nav_atan2(d_e_m * t_n_m - d_n_m * t_e_m, d_e_m * t_e_m + d_n_m * t_n_m);
    *mu = nav_sqrt(d2 / t2) - NAV_C(1.0);
    return NAV_OK;
}

int onepoint_linear(nav_real_t t_e_m, nav_real_t t_n_m, nav_real_t err_e_m, nav_real_t err_n_m,
                    nav_real_t *dh_rad, nav_real_t *mu)
{
    const nav_real_t t2 = t_e_m * t_e_m + t_n_m * t_n_m;
    if (!(t2 > NAV_C(0.0)) || !nav_isfinite(t2)) {
        return NAV_EINVAL;
    }
    *dh_rad = (err_e_m * t_n_m - err_n_m * t_e_m) / t2;  /* eq 9 */
    *mu = (err_e_m * t_e_m + err_n_m * t_n_m) / t2;      /* eq 10 */
    return NAV_OK;
}

int dr_calibrate(dr_t *d, const geo_pos_t *true_pos, nav_real_t min_base_m, dr_cal_t *out)
{
    nav_real_t t_e, t_n, d_e, d_n;
    dr_local_m(&d->base, true_pos, &t_e, &t_n);  /* eqs 7-8: true displacement */
    dr_local_m(&d->base, &d->pos, &d_e, &d_n);   /* dead-reckoned displacement */
    const nav_real_t base_m = nav_sqrt(t_e * t_e + t_n * t_n);
    if (!nav_isfinite(base_m) || !nav_isfinite(min_base_m)) {
        return NAV_EINVAL;
    }
    if (base_m < min_base_m) {
        return NAV_ERANGE;
    }
    nav_real_t dh, mu;
    if (onepoint_exact(d_e, d_n, t_e, t_n, &dh, &mu) != NAV_OK) {
        return NAV_EINVAL;
    }
    /* compose with the compensation in use: the residuals were measured on compensated
     * increments */
    const nav_real_t dh_new = d->dh_rad + dh;
    const nav_real_t mu_new = (NAV_C(1.0) + d->mu) * (NAV_C(1.0) + mu) - NAV_C(1.0);
    if (!comp_ok(dh_new, mu_new)) {
        return NAV_EINVAL;
    }
    if (out != NULL) {
        out->dh_rad = dh;
        out->mu = mu;
        out->base_m = base_m;
        out->err_e_m = d_e - t_e;
        out->err_n_m = d_n - t_n;
        out->t_e_m = t_e;
        out->t_n_m = t_n;
    }
    d->dh_rad = dh_new;
    d->mu = mu_new;
    d->pos.lat = true_pos->lat;
    d->pos.lon = true_pos->lon;
    d->base = d->pos;
    return NAV_OK;
}
