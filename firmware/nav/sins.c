/* sins.c - strapdown mechanization; see sins.h for the contract and sources. */
#include "sins.h"

#define MAX_LAT_LSB (890000000LL * GEO_LSB_PER_DEG_E7) /* 89 deg: ENU is singular at a pole */
#define MAX_SPEED_MPS NAV_C(1000.0)

sins_config_t sins_default_config(void)
{
    sins_config_t cfg;
    cfg.coning_sculling = 1u;
    cfg.max_dt_s = NAV_C(0.2);
    cfg.vdamp_tau_s = NAV_C(100.0);
    return cfg;
}

static int finite3(const nav_real_t v[3])
{
    return nav_isfinite(v[0]) && nav_isfinite(v[1]) && nav_isfinite(v[2]);
}

/* the region where the ENU mechanization is valid: |lat| <= 89 deg, height in [-1, 20] km */
static int pos_ok(const geo_pos_t *pos)
{
    return pos->lat <= MAX_LAT_LSB && pos->lat >= -MAX_LAT_LSB && pos->lon <= GEO_LSB_180DEG &&
           pos->lon > -GEO_LSB_180DEG && pos->h <= GEO_H_MAX_LSB && pos->h >= GEO_H_MIN_LSB;
}

int sins_init(sins_t *s, const sins_config_t *cfg, const geo_pos_t *pos,
              const nav_real_t v_n_mps[3], const nav_real_t q_bn[4])
{
    const nav_real_t tau = cfg->vdamp_tau_s;
    if (!(cfg->max_dt_s > NAV_C(0.0)) || !(cfg->max_dt_s <= NAV_C(1.0)) || !(tau >= NAV_C(0.0)) ||
        !nav_isfinite(tau) || (tau > NAV_C(0.0) && tau < NAV_C(10.0) * cfg->max_dt_s)) {
        return NAV_EINVAL;
    }
    if (!pos_ok(pos)) {
        return NAV_EINVAL;
    }
    if (!finite3(v_n_mps) || !(vec3_norm(v_n_mps) <= MAX_SPEED_MPS)) {
        return NAV_EINVAL;
    }
    const nav_real_t qn2 = q_bn[0] * q_bn[0] + q_bn[1] * q_bn[1] + q_bn[2] * q_bn[2] +
                           q_bn[3] * q_bn[3];
    if (!(qn2 >= NAV_C(0.81)) || !(qn2 <= NAV_C(1.21))) {
        return NAV_EINVAL; /* also rejects NaN components */
    }
    const nav_real_t inv_qn = NAV_C(1.0) / nav_sqrt(qn2);

    s->cfg = *cfg;
    s->pos = *pos;
    for (int i = 0; i < 4; i++) {
        s->q_bn[i] = q_bn[i] * inv_qn;
        s->q_bn_lo[i] = NAV_C(0.0);
    }
    for (int i = 0; i < 3; i++) {
        s->v_n_mps[i] = v_n_mps[i];
        s->v_n_lo_mps[i] = NAV_C(0.0);
        s->v_n_prev_mps[i] = v_n_mps[i];
        s->dtheta_prev_b_rad[i] = NAV_C(0.0);
        s->dv_prev_b_mps[i] = NAV_C(0.0);
    }
    s->dt_prev_s = NAV_C(0.0);
    s->h_ref_m = NAV_C(0.0);
    s->have_prev = 0u;
    s->h_ref_valid = 0u;
    s->n_steps = 0u;
    return NAV_OK;
}

void sins_set_height_ref(sins_t *s, nav_real_t h_ref_m)
{
    s->h_ref_valid = (uint8_t)(nav_isfinite(h_ref_m) && s->cfg.vdamp_tau_s > NAV_C(0.0));
    s->h_ref_m = s->h_ref_valid ? h_ref_m : NAV_C(0.0);
}

void sins_clear_height_ref(sins_t *s)
{
    s->h_ref_valid = 0u;
}

int sins_set_position(sins_t *s, const geo_pos_t *pos)
{
    if (!pos_ok(pos)) {
        return NAV_EINVAL;
    }
    s->pos = *pos;
    return NAV_OK;
}

void sins_earth_rate_b(const sins_t *s, nav_real_t w_ie_b_rps[3])
{
    mat3_t C_bn;
    quat_to_dcm(s->q_bn, &C_bn);
    earth_t e;
    earth_eval(geo_lat_rad(&s->pos), geo_h_m(&s->pos), &e);
    mat3t_mul_vec(&C_bn, e.w_ie_n_rps, w_ie_b_rps);
}

int sins_finite(const sins_t *s)
{
    for (int i = 0; i < 4; i++) {
        if (!nav_isfinite(s->q_bn[i]) || (i < 3 && !nav_isfinite(s->v_n_mps[i]))) {
            return 0;
        }
    }
    return 1;
}

void sins_euler(const sins_t *s, nav_real_t *roll_rad, nav_real_t *pitch_rad,
                nav_real_t *heading_rad)
{
    mat3_t C_bn;
    quat_to_dcm(s->q_bn, &C_bn);
    dcm_to_euler(&C_bn, roll_rad, pitch_rad, heading_rad);
}

int sins_set_velocity(sins_t *s, const nav_real_t v_n_mps[3])
{
    for (int i = 0; i < 3; i++) {
        if (!nav_isfinite(v_n_mps[i]) || nav_fabs(v_n_mps[i]) > NAV_C(1000.0)) {
            return NAV_EINVAL;
        }
    }
    for (int i = 0; i < 3; i++) {
        s->v_n_mps[i] = v_n_mps[i];
        s->v_n_lo_mps[i] = NAV_C(0.0);
        s->v_n_prev_mps[i] = v_n_mps[i];
    }
    return NAV_OK;
}

int sins_turn_heading(sins_t *s, nav_real_t dheading_rad)
{
    if (!nav_isfinite(dheading_rad) || nav_fabs(dheading_rad) > NAV_C(3.14159265358979)) {
        return NAV_EINVAL;
    }
    /* a turn of the body by alpha about ENU up (counter-clockwise) is a heading change
     * of -alpha: q_bn <- q_z(alpha) (x) q_bn with alpha = -dheading */
    const nav_real_t half = NAV_C(-0.5) * dheading_rad;
    const nav_real_t qz[4] = {nav_cos(half), NAV_C(0.0), NAV_C(0.0), nav_sin(half)};
    nav_real_t q[4];
    quat_mul(qz, s->q_bn, q);
    for (int i = 0; i < 4; i++) {
        s->q_bn[i] = q[i];
        s->q_bn_lo[i] = NAV_C(0.0);
    }
    return NAV_OK;
}

/* Attitude increment dq_bn such that q(k) = q(k-1) + dq_bn is q(-zeta) (x) q(k-1) (x) q(phi)
 * (Savage's attitude update: the body turned by phi, the ENU frame by zeta, over the
 * interval). Only the difference is formed, so float32 rounding is relative to the small
 * change, not to q itself. */
static int attitude_increment(const nav_real_t q[4], const nav_real_t phi_b_rad[3],
                              const nav_real_t zeta_n_rad[3], nav_real_t dq_bn[4])
{
    const nav_real_t minus_zeta[3] = {-zeta_n_rad[0], -zeta_n_rad[1], -zeta_n_rad[2]};
    nav_real_t a[4], b[4], aq[4], qb[4], aqb[4];
    if (rotvec_to_dquat(minus_zeta, a) != NAV_OK || rotvec_to_dquat(phi_b_rad, b) != NAV_OK) {
        return NAV_EINVAL;
    }
    quat_mul(a, q, aq);
    quat_mul(q, b, qb);
    quat_mul(a, qb, aqb);
    for (int i = 0; i < 4; i++) {
        dq_bn[i] = aq[i] + qb[i] + aqb[i];
    }
    return NAV_OK;
}

int sins_step(sins_t *s, const imu_inc_t *inc)
{
    const nav_real_t dt = inc->dt_s;
    if (!(dt > NAV_C(0.0)) || !(dt <= s->cfg.max_dt_s) || !finite3(inc->dtheta_b_rad) ||
        !finite3(inc->dv_b_mps)) {
        s->have_prev = 0u;
        return NAV_EINVAL;
    }
    const nav_real_t *dth = inc->dtheta_b_rad;
    const nav_real_t *dv = inc->dv_b_mps;
    const nav_real_t zero3[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    /* the two-sample corrections assume equal intervals; after a dropped sample skip them */
    const int same_dt = s->have_prev && nav_fabs(dt - s->dt_prev_s) <= NAV_C(0.01) * dt;
    const int use_prev = same_dt && s->cfg.coning_sculling;
    const nav_real_t *dth_prev = use_prev ? s->dtheta_prev_b_rad : zero3;
    const nav_real_t *dv_prev = use_prev ? s->dv_prev_b_mps : zero3;
    const nav_real_t half = NAV_C(0.5), twelfth = NAV_C(1.0) / NAV_C(12.0);

    /* Earth at the start of the interval; over one sample the position moves too little
     * for radii or gravity to change measurably (< 1e-9 relative at 100 m/s, 10 Hz). */
    const nav_real_t lat = geo_lat_rad(&s->pos);
    const nav_real_t h = geo_h_m(&s->pos);
    earth_t e;
    earth_eval(lat, h, &e);

    /* ---- velocity (seed 001 eqs. 3-5, increment form) ---- */
    nav_real_t v_mid[3], w_en[3], w_in[3];
    const nav_real_t extrap = s->have_prev ? half * dt / s->dt_prev_s : NAV_C(0.0);
    for (int i = 0; i < 3; i++) {
        v_mid[i] = s->v_n_mps[i] + extrap * (s->v_n_mps[i] - s->v_n_prev_mps[i]);
    }
    earth_transport_rate(&e, h, v_mid, w_en);
    for (int i = 0; i < 3; i++) {
        w_in[i] = e.w_ie_n_rps[i] + w_en[i];
    }

    /* velocity increment in b(k-1): rotation and sculling terms */
    nav_real_t t1[3], t2[3], t3[3], dv_fb[3];
    vec3_cross(dth, dv, t1);
    vec3_cross(dth_prev, dv, t2);
    vec3_cross(dv_prev, dth, t3);
    for (int i = 0; i < 3; i++) {
        dv_fb[i] = dv[i] + half * t1[i] + twelfth * (t2[i] + t3[i]);
    }
    mat3_t C_bn;
    nav_real_t dv_fn0[3], zeta[3], dv_fn[3];
    quat_to_dcm(s->q_bn, &C_bn);
    mat3_mul_vec(&C_bn, dv_fb, dv_fn0);
    for (int i = 0; i < 3; i++) {
        zeta[i] = w_in[i] * dt;
    }
    vec3_cross(zeta, dv_fn0, t1); /* the n frame turns by zeta during the interval */
    for (int i = 0; i < 3; i++) {
        dv_fn[i] = dv_fn0[i] - half * t1[i];
    }
    /* Coriolis and transport: (2 w_ie + w_en) x v, at mid-interval */
    nav_real_t w_cor[3], a_cor[3];
    for (int i = 0; i < 3; i++) {
        w_cor[i] = NAV_C(2.0) * e.w_ie_n_rps[i] + w_en[i];
    }
    vec3_cross(w_cor, v_mid, a_cor);
    nav_real_t dv_n[3];
    dv_n[0] = dv_fn[0] - a_cor[0] * dt;
    dv_n[1] = dv_fn[1] - a_cor[1] * dt;
    dv_n[2] = dv_fn[2] + (-e.g_mps2 - a_cor[2]) * dt;

    nav_real_t dh_damp_m = NAV_C(0.0);
    if (s->h_ref_valid) {
        /* dh'' = (2g/R) dh is the free-inertial vertical channel; feeding back -k1 dh into
         * dh/dt and -k2 dh into dv_U/dt gives s^2 + k1 s + k2 - 2g/R = (s + 1/tau)^2. */
        const nav_real_t inv_tau = NAV_C(1.0) / s->cfg.vdamp_tau_s;
        const nav_real_t w_v2 = NAV_C(2.0) * e.g_mps2 / (nav_sqrt(e.R_M_m * e.R_N_m) + h);
        const nav_real_t dh_err_m = h - s->h_ref_m;
        dv_n[2] -= (w_v2 + inv_tau * inv_tau) * dh_err_m * dt;
        dh_damp_m = -NAV_C(2.0) * inv_tau * dh_err_m * dt;
    }

    nav_real_t v_new[3], v_new_lo[3], v_avg[3];
    for (int i = 0; i < 3; i++) {
        v_new[i] = s->v_n_mps[i];
        v_new_lo[i] = s->v_n_lo_mps[i];
        nav_acc_add(&v_new[i], &v_new_lo[i], dv_n[i]);
        v_avg[i] = s->v_n_mps[i] + half * dv_n[i];
    }
    if (!(vec3_norm(v_new) <= MAX_SPEED_MPS)) {
        s->have_prev = 0u;
        return NAV_ERANGE;
    }

    /* ---- position (seed 001 eq. 6), trapezoidal in velocity ---- */
    const nav_real_t dh_m = v_avg[2] * dt + dh_damp_m;
    const nav_real_t h_mid = h + half * dh_m;
    const nav_real_t dlat = v_avg[1] * dt / (e.R_M_m + h_mid);
    const nav_real_t cos_lat_mid = e.cos_lat - e.sin_lat * half * dlat;
    const nav_real_t dlon = v_avg[0] * dt / ((e.R_N_m + h_mid) * cos_lat_mid);
    geo_pos_t pos_new = s->pos;
    if (geo_pos_add(&pos_new, dlat, dlon, dh_m) != NAV_OK || pos_new.lat > MAX_LAT_LSB ||
        pos_new.lat < -MAX_LAT_LSB) {
        s->have_prev = 0u;
        return NAV_ERANGE;
    }

    /* ---- attitude (seed 001 eq. 2) ---- */
    earth_transport_rate(&e, h_mid, v_avg, w_en);
    nav_real_t phi_b[3];
    vec3_cross(dth_prev, dth, t1);
    for (int i = 0; i < 3; i++) {
        zeta[i] = (e.w_ie_n_rps[i] + w_en[i]) * dt;
        phi_b[i] = dth[i] + twelfth * t1[i];
    }
    nav_real_t dq[4];
    if (attitude_increment(s->q_bn, phi_b, zeta, dq) != NAV_OK) {
        s->have_prev = 0u;
        return NAV_EINVAL;
    }
    nav_real_t q[4], q_lo[4];
    for (int i = 0; i < 4; i++) {
        q[i] = s->q_bn[i];
        q_lo[i] = s->q_bn_lo[i];
        nav_acc_add(&q[i], &q_lo[i], dq[i]);
    }
    /* Normalize by a radial increment -q (|q|^2 - 1)/2, also compensated: rescaling q
     * directly would round each component and turn the attitude by up to 3e-8 rad. */
    const nav_real_t n2m1 = (vec3_dot(&q[1], &q[1]) + q[0] * q[0] - NAV_C(1.0)) +
                            NAV_C(2.0) * (q[0] * q_lo[0] + vec3_dot(&q[1], &q_lo[1]));
    const nav_real_t k = -half * n2m1;
    for (int i = 0; i < 4; i++) {
        nav_acc_add(&q[i], &q_lo[i], k * q[i]);
    }

    /* ---- commit ---- */
    s->pos = pos_new;
    for (int i = 0; i < 4; i++) {
        s->q_bn[i] = q[i];
        s->q_bn_lo[i] = q_lo[i];
    }
    for (int i = 0; i < 3; i++) {
        s->v_n_prev_mps[i] = s->v_n_mps[i];
        s->v_n_mps[i] = v_new[i];
        s->v_n_lo_mps[i] = v_new_lo[i];
        s->dtheta_prev_b_rad[i] = dth[i];
        s->dv_prev_b_mps[i] = dv[i];
    }
    s->dt_prev_s = dt;
    s->have_prev = 1u;
    s->n_steps++;
    return NAV_OK;
}
