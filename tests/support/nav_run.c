/* nav_run.c - see nav_run.h. Built once per numeric variant. */
#include "nav_run.h"

#include <math.h>

#include "sins.h"

#if defined(NAV_REAL_DOUBLE)
#define NAV_RUN nav_run_f64
#else
#define NAV_RUN nav_run_f32
#endif

#define RAD_PER_LSB (3.14159265358979323846 / (1800000000.0 * (double)GEO_LSB_PER_DEG_E7))

static int64_t rad_to_lsb(double rad)
{
    return (int64_t)llround(rad / RAD_PER_LSB);
}

/* value to feed, carrying what the rounding to nav_real_t dropped into the next sample */
static nav_real_t with_carry(double exact, double *carry)
{
    const double want = exact + *carry;
    const nav_real_t fed = (nav_real_t)want;
    *carry = want - (double)fed;
    return fed;
}

void NAV_RUN(const run_spec_t *spec, run_result_t *res)
{
    truth_gen_t g;
    truth_init(&g, spec->kin, spec->ctx, spec->lat0_rad, spec->lon0_rad, spec->h0_m);
    kin_t k;
    spec->kin(spec->ctx, 0.0, &k);

    /* initial attitude: truth rotated by the requested error, q = q(err) (x) q_true */
    double dq[4], q0[4];
    const double *e = spec->init_tilt_err_rad;
    const double ang = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    const double s = ang > 0.0 ? sin(0.5 * ang) / ang : 0.5;
    dq[0] = cos(0.5 * ang);
    dq[1] = s * e[0];
    dq[2] = s * e[1];
    dq[3] = s * e[2];
    q0[0] = dq[0] * k.q_bn[0] - dq[1] * k.q_bn[1] - dq[2] * k.q_bn[2] - dq[3] * k.q_bn[3];
    q0[1] = dq[0] * k.q_bn[1] + dq[1] * k.q_bn[0] + dq[2] * k.q_bn[3] - dq[3] * k.q_bn[2];
    q0[2] = dq[0] * k.q_bn[2] - dq[1] * k.q_bn[3] + dq[2] * k.q_bn[0] + dq[3] * k.q_bn[1];
    q0[3] = dq[0] * k.q_bn[3] + dq[1] * k.q_bn[2] - dq[2] * k.q_bn[1] + dq[3] * k.q_bn[0];

    sins_config_t cfg = sins_default_config();
    cfg.coning_sculling = (uint8_t)(spec->coning_sculling != 0);
    const geo_pos_t pos0 = {rad_to_lsb(spec->lat0_rad), rad_to_lsb(spec->lon0_rad),
                            (int64_t)llround((spec->h0_m + spec->init_h_err_m) * 1000.0 * (double)GEO_LSB_PER_MM)};
    const nav_real_t v0[3] = {(nav_real_t)k.v_n_mps[0], (nav_real_t)k.v_n_mps[1],
                              (nav_real_t)k.v_n_mps[2]};
    const nav_real_t q0r[4] = {(nav_real_t)q0[0], (nav_real_t)q0[1], (nav_real_t)q0[2],
                               (nav_real_t)q0[3]};
    sins_t nav;
    res->rc = sins_init(&nav, &cfg, &pos0, v0, q0r);
    res->max_horiz_err_m = 0.0;
    res->max_att_err_rad = 0.0;
    res->final_att_err_rad = 0.0;

    if (!(spec->rate_hz >= 1.0) || !(spec->duration_s >= 0.0)) {
        res->rc = -22; /* the runner samples the error once per second */
        return;
    }
    const double dt = 1.0 / spec->rate_hz;
    const long n_steps = lround(spec->duration_s * spec->rate_hz);
    const long per_second = lround(spec->rate_hz);
    double carry_th[3] = {0.0, 0.0, 0.0}, carry_v[3] = {0.0, 0.0, 0.0};
    double lat = spec->lat0_rad, lon = spec->lon0_rad;
    for (long n = 1; n <= n_steps && res->rc == 0; n++) {
        double dth[3], dv[3];
        truth_step(&g, dt, dth, dv);
        if (spec->vdamp) {
            sins_set_height_ref(&nav, (nav_real_t)g.h_m);
        }
        imu_inc_t inc;
        for (int i = 0; i < 3; i++) {
            inc.dtheta_b_rad[i] = with_carry(dth[i], &carry_th[i]);
            inc.dv_b_mps[i] = with_carry(dv[i], &carry_v[i]);
        }
        inc.dt_s = (nav_real_t)dt;
        res->rc = sins_step(&nav, &inc);
        lat = (double)nav.pos.lat * RAD_PER_LSB;
        lon = (double)nav.pos.lon * RAD_PER_LSB;
        const double herr = truth_horiz_dist_m(g.lat_rad, g.lon_rad, lat, lon, g.h_m);
        if (herr > res->max_horiz_err_m) {
            res->max_horiz_err_m = herr;
        }
        spec->kin(spec->ctx, g.t_s, &k);
        const double qn[4] = {(double)nav.q_bn[0], (double)nav.q_bn[1], (double)nav.q_bn[2],
                              (double)nav.q_bn[3]};
        res->final_att_err_rad = truth_att_err_rad(k.q_bn, qn);
        if (res->final_att_err_rad > res->max_att_err_rad) {
            res->max_att_err_rad = res->final_att_err_rad;
        }
        if (spec->horiz_err_m != NULL && n % per_second == 0 &&
            (size_t)(n / per_second) < spec->horiz_err_len) {
            spec->horiz_err_m[n / per_second] = herr;
        }
    }
    res->final_lat_rad = lat;
    res->final_lon_rad = lon;
    res->final_h_m = (double)nav.pos.h / (1000.0 * (double)GEO_LSB_PER_MM);
    res->truth_lat_rad = g.lat_rad;
    res->truth_lon_rad = g.lon_rad;
    res->truth_h_m = g.h_m;
    res->final_horiz_err_m = truth_horiz_dist_m(g.lat_rad, g.lon_rad, lat, lon, g.h_m);
}
