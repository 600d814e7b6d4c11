/*
 * ekf_meas.c - the measurements of the filter (ekf.h, docs/kalman.md): for each,
 * a row builder (ekf_rows_*: rows h and innovations z, also called by the tests that check
 * each row against a numerical derivative, tests/test_ekf_rows.c) and the update that
 * gates and applies them.
 */
#include "dr.h"
#include "ekf.h"

#include <stddef.h>

#define MAX_ROWS 3

static void zero_row(nav_real_t h[EKF_N])
{
    for (int i = 0; i < EKF_N; i++) {
        h[i] = NAV_C(0.0);
    }
}

/* z^2 / (h P h^T + r) for one row, with the current P */
static nav_real_t nis(const ekf_t *k, const nav_real_t h[EKF_N], nav_real_t z, nav_real_t r)
{
    nav_real_t s = r;
    for (int i = 0; i < EKF_N; i++) {
        nav_real_t acc = NAV_C(0.0);
        for (int j = 0; j < EKF_N; j++) {
            acc += k->P[i][j] * h[j];
        }
        s += h[i] * acc;
    }
    return z * z / s;
}

/* gate the rows as one measurement (with the variances r), then apply them in sequence
 * with the variances r times r_scale (> 0) */
static int apply_rows_scaled(ekf_t *k, nav_real_t H[][EKF_N], const nav_real_t *z,
                             const nav_real_t *r, int n, nav_real_t gate_sigma,
                             nav_real_t r_scale)
{
    if (!(r_scale > NAV_C(0.0)) || !nav_isfinite(r_scale)) {
        return -1;
    }
    for (int m = 0; m < n; m++) {
        if (!nav_isfinite(z[m]) || !(r[m] > NAV_C(0.0))) {
            return -1;
        }
        if (gate_sigma > NAV_C(0.0) && nis(k, H[m], z[m], r[m]) > gate_sigma * gate_sigma) {
            k->n_gated++;
            return 0;
        }
    }
    int applied = 0;
    for (int m = 0; m < n; m++) {
        if (ekf_update(k, H[m], z[m], r[m] * r_scale, NAV_C(0.0)) == 1) {
            applied++;
        }
    }
    return applied;
}

/* out of line (noinline): the link inlined it at its six calls, 24-32 bytes more of the
 * ECU's flash */
__attribute__((noinline)) static int apply_rows(ekf_t *k, nav_real_t H[][EKF_N],
                                                const nav_real_t *z, const nav_real_t *r,
                                                int n, nav_real_t gate_sigma)
{
    return apply_rows_scaled(k, H, z, r, n, gate_sigma, NAV_C(1.0));
}

void ekf_rows_gnss_position(const sins_t *s, const geo_pos_t *pos_then, const geo_pos_t *meas,
                            const nav_real_t lever_b_m[3], nav_real_t h[EKF_GNSS_POS_ROWS][EKF_N],
                            nav_real_t z_enu_m[EKF_GNSS_POS_ROWS])
{
    mat3_t C;
    quat_to_dcm(s->q_bn, &C);
    nav_real_t l_n[3];
    mat3_mul_vec(&C, lever_b_m, l_n);
    nav_real_t e, n;
    dr_local_m(meas, pos_then, &e, &n); /* navigator minus measurement, metres */
    const nav_real_t u = (nav_real_t)(pos_then->h - meas->h) / (nav_real_t)GEO_LSB_PER_MM *
                         NAV_C(0.001);
    z_enu_m[0] = e + l_n[0];
    z_enu_m[1] = n + l_n[1];
    z_enu_m[2] = u + l_n[2];
    for (int m = 0; m < 3; m++) {
        zero_row(h[m]);
        h[m][EKF_DR + m] = NAV_C(1.0);
    }
    /* d(C l) = [(C l) x] psi */
    h[0][EKF_PSI + 1] = -l_n[2];
    h[0][EKF_PSI + 2] = l_n[1];
    h[1][EKF_PSI + 0] = l_n[2];
    h[1][EKF_PSI + 2] = -l_n[0];
    h[2][EKF_PSI + 0] = -l_n[1];
    h[2][EKF_PSI + 1] = l_n[0];
}

int ekf_gnss_position(ekf_t *k, const sins_t *s, const geo_pos_t *pos_then,
                      const geo_pos_t *meas, const nav_real_t lever_b[3], nav_real_t sigma_h_m,
                      nav_real_t sigma_hw_m, nav_real_t sigma_v_m, nav_real_t gate_sigma,
                      nav_real_t r_scale_v, int use_height, int use_bias)
{
    nav_real_t H[MAX_ROWS][EKF_N], z[3];
    ekf_rows_gnss_position(s, pos_then, meas, lever_b, H, z);
    /* the fix less its estimated correlated error: z = dr + db - white */
    for (int m = 0; use_bias && m < 2; m++) {
        z[m] += k->gnss_bias_m[m];
        H[m][EKF_GB + m] = NAV_C(1.0);
    }
    if (!(sigma_hw_m > NAV_C(0.0)) || !(sigma_h_m > NAV_C(0.0))) {
        return -1;
    }
    const nav_real_t r[3] = {sigma_h_m * sigma_h_m, sigma_h_m * sigma_h_m,
                             sigma_v_m * sigma_v_m};
    /* horizontal and vertical gated apart: a height offset (datum, a receiver without
     * heights) must not lock out the horizontal fix; the horizontal gated against the
     * declared accuracy (a receiver's error jumps when its satellites change), applied
     * with the white part */
    const nav_real_t w = sigma_hw_m / sigma_h_m;
    const int nh = apply_rows_scaled(k, H, z, r, 2, gate_sigma, w * w);
    if (nh < 0 || !use_height) {
        return nh;
    }
    const int nv = apply_rows_scaled(k, &H[2], &z[2], &r[2], 1, gate_sigma, r_scale_v);
    return nv < 0 ? nv : nh + nv;
}

void ekf_rows_gnss_velocity(const nav_real_t v_then_mps[3], const nav_real_t meas_mps[3],
                            nav_real_t h[EKF_GNSS_VEL_ROWS][EKF_N],
                            nav_real_t z_enu_mps[EKF_GNSS_VEL_ROWS])
{
    for (int m = 0; m < 3; m++) {
        zero_row(h[m]);
        h[m][EKF_DV + m] = NAV_C(1.0);
        z_enu_mps[m] = v_then_mps[m] - meas_mps[m];
    }
}

int ekf_gnss_velocity(ekf_t *k, const nav_real_t v_then_mps[3], const nav_real_t meas_mps[3],
                      nav_real_t sigma_h_mps, nav_real_t sigma_v_mps, nav_real_t gate_sigma)
{
    nav_real_t H[MAX_ROWS][EKF_N];
    nav_real_t z[3], r[3];
    ekf_rows_gnss_velocity(v_then_mps, meas_mps, H, z);
    for (int m = 0; m < 3; m++) {
        r[m] = m < 2 ? sigma_h_mps * sigma_h_mps : sigma_v_mps * sigma_v_mps;
    }
    return apply_rows(k, H, z, r, 3, gate_sigma);
}

int ekf_gnss_velocity_horizontal(ekf_t *k, const nav_real_t v_then_mps[3],
                                 const nav_real_t meas_mps[3], nav_real_t sigma_h_mps,
                                 nav_real_t gate_sigma)
{
    nav_real_t H[MAX_ROWS][EKF_N];
    nav_real_t z[3];
    ekf_rows_gnss_velocity(v_then_mps, meas_mps, H, z);
    const nav_real_t r[2] = {sigma_h_mps * sigma_h_mps, sigma_h_mps * sigma_h_mps};
    return apply_rows(k, H, z, r, 2, gate_sigma);
}

void ekf_rows_odometer(const ekf_t *k, const sins_t *s, const nav_real_t w_b_rps[3],
                       const nav_real_t lever_b_m[3], nav_real_t speed_mps,
                       nav_real_t h[EKF_ODO_ROWS][EKF_N], nav_real_t z_car_mps[EKF_ODO_ROWS])
{
    mat3_t C;
    quat_to_dcm(s->q_bn, &C);
    nav_real_t v_b[3], wxl[3];
    mat3t_mul_vec(&C, s->v_n_mps, v_b); /* IMU velocity, IMU axes */
    vec3_cross(w_b_rps, lever_b_m, wxl);
    for (int i = 0; i < 3; i++) {
        v_b[i] += wxl[i];               /* the reference point's (the rotation is known:
                                           its error, from the gyro bias, is neglected) */
    }
    /* d(v_b) = C^T dv - C^T [v_n x] psi: rows of M = C^T and N = -C^T [v_n x] */
    const nav_real_t *v = s->v_n_mps;
    nav_real_t N[3][3];
    for (int i = 0; i < 3; i++) {
        /* row i of C^T is column i of C; times [v x] */
        const nav_real_t c0 = C.m[0][i], c1 = C.m[1][i], c2 = C.m[2][i];
        N[i][0] = -(c1 * v[2] - c2 * v[1]);
        N[i][1] = -(c2 * v[0] - c0 * v[2]);
        N[i][2] = -(c0 * v[1] - c1 * v[0]);
    }
    const nav_real_t my = k->mount_yaw_rad, mp = k->mount_pitch_rad;
    const nav_real_t scale = NAV_C(1.0) + k->k;
    /* the offset acts in the direction of travel (a reversing car's reading is negative) */
    const nav_real_t dir = speed_mps < NAV_C(0.0) ? NAV_C(-1.0) : NAV_C(1.0);
    /* car frame: lateral v_b,x + my v_b,y = 0; vertical v_b,z + mp v_b,y = 0;
     * forward (1 + k) v_b,y + dir ob = speed read */
    const int axis[EKF_ODO_ROWS] = {0, 2, 1}; /* lateral x, vertical z, forward y */
    for (int m = 0; m < 3; m++) {
        const int i = axis[m];
        const nav_real_t g = m == EKF_ODO_FORWARD ? scale : NAV_C(1.0);
        zero_row(h[m]);
        for (int j = 0; j < 3; j++) {
            h[m][EKF_DV + j] = g * C.m[j][i];
            h[m][EKF_PSI + j] = g * N[i][j];
        }
    }
    h[EKF_ODO_LATERAL][EKF_MY] = v_b[1];
    h[EKF_ODO_VERTICAL][EKF_MP] = v_b[1];
    h[EKF_ODO_FORWARD][EKF_K] = v_b[1];
    h[EKF_ODO_FORWARD][EKF_OB] = dir;
    z_car_mps[EKF_ODO_LATERAL] = v_b[0] + my * v_b[1];
    z_car_mps[EKF_ODO_VERTICAL] = v_b[2] + mp * v_b[1];
    z_car_mps[EKF_ODO_FORWARD] = scale * v_b[1] + dir * k->odo_offset_mps - speed_mps;
}

int ekf_odometer(ekf_t *k, const sins_t *s, const nav_real_t w_b_rps[3],
                 const nav_real_t lever_b_m[3], nav_real_t speed_mps, nav_real_t sigma_fwd_mps,
                 nav_real_t sigma_nhc_mps, nav_real_t sigma_vert_mps, nav_real_t gate_sigma)
{
    nav_real_t H[MAX_ROWS][EKF_N], z[3], r[3];
    ekf_rows_odometer(k, s, w_b_rps, lever_b_m, speed_mps, H, z);
    r[EKF_ODO_LATERAL] = sigma_nhc_mps * sigma_nhc_mps;
    r[EKF_ODO_VERTICAL] = sigma_vert_mps * sigma_vert_mps;
    r[EKF_ODO_FORWARD] = sigma_fwd_mps * sigma_fwd_mps;
    return apply_rows(k, H, z, r, 3, gate_sigma);
}

void ekf_rows_zero_velocity(const sins_t *s, nav_real_t h[EKF_ZUPT_ROWS][EKF_N],
                            nav_real_t z_enu_mps[EKF_ZUPT_ROWS])
{
    for (int m = 0; m < 3; m++) {
        zero_row(h[m]);
        h[m][EKF_DV + m] = NAV_C(1.0);
        z_enu_mps[m] = s->v_n_mps[m];
    }
}

int ekf_zero_velocity(ekf_t *k, const sins_t *s, nav_real_t sigma_mps, nav_real_t gate_sigma)
{
    nav_real_t H[MAX_ROWS][EKF_N], z[3], r[3];
    ekf_rows_zero_velocity(s, H, z);
    for (int m = 0; m < 3; m++) {
        r[m] = sigma_mps * sigma_mps;
    }
    const int used = apply_rows(k, H, z, r, 2, gate_sigma);
    /* the vertical apart: a vertical velocity the filter got wrong (a braking dive taken as
     * a climb) must not cost the standstill its horizontal zero */
    return used > 0 ? used + apply_rows(k, &H[2], &z[2], &r[2], 1, gate_sigma) : used;
}

void ekf_rows_zero_rate(nav_real_t residual_rate_z_rps, nav_real_t h[EKF_ZARU_ROWS][EKF_N],
                        nav_real_t z_rps[EKF_ZARU_ROWS])
{
    zero_row(h[0]);
    h[0][EKF_BG + 2] = NAV_C(1.0);
    h[0][EKF_GZ] = NAV_C(1.0);
    z_rps[0] = residual_rate_z_rps;
}

int ekf_zero_rate(ekf_t *k, nav_real_t residual_rate_z_rps, nav_real_t sigma_rps)
{
    nav_real_t H[MAX_ROWS][EKF_N], z[1];
    ekf_rows_zero_rate(residual_rate_z_rps, H, z);
    const nav_real_t r[1] = {sigma_rps * sigma_rps};
    return apply_rows(k, H, z, r, 1, NAV_C(0.0));
}

/* ------------------------------------------------------- raw GNSS (issue #20) ---- */

/* (u x a) for the rows' psi entries, negated: -(u x a) */
static void neg_cross(const nav_real_t u[3], const nav_real_t a[3], nav_real_t out[3])
{
    out[0] = -(u[1] * a[2] - u[2] * a[1]);
    out[1] = -(u[2] * a[0] - u[0] * a[2]);
    out[2] = -(u[0] * a[1] - u[1] * a[0]);
}

int ekf_antenna(const sins_t *s, const geo_pos_t *pos_then, const nav_real_t lever_b_m[3],
                ekf_antenna_t *a)
{
    mat3_t C;
    quat_to_dcm(s->q_bn, &C);
    mat3_mul_vec(&C, lever_b_m, a->l_n);
    const nav_real_t lat = geo_lat_rad(pos_then);
    const nav_real_t hgt = geo_h_m(pos_then);
    nav_real_t R_M, R_N;
    earth_radii(nav_sin(lat), &R_M, &R_N);
    geo_pos_t ant = *pos_then;
    if (geo_pos_add(&ant, a->l_n[1] / (R_M + hgt), a->l_n[0] / ((R_N + hgt) * nav_cos(lat)),
                    a->l_n[2]) != NAV_OK) {
        return NAV_EINVAL;
    }
    geo_to_ecef_dmm(&ant, a->ecef_dmm);
    /* the navigator's ENU axes, those of the error state dr and of its velocity */
    const nav_real_t lon = geo_lon_rad(pos_then);
    a->sin_lat = nav_sin(lat);
    a->cos_lat = nav_cos(lat);
    a->sin_lon = nav_sin(lon);
    a->cos_lon = nav_cos(lon);
    return NAV_OK;
}

/* a in ECEF axes to the antenna's local east, north, up axes */
static void ecef_to_enu(const ekf_antenna_t *an, const nav_real_t a[3], nav_real_t out[3])
{
    const nav_real_t sl = an->sin_lat, cl = an->cos_lat, so = an->sin_lon, co = an->cos_lon;
    out[0] = -so * a[0] + co * a[1];
    out[1] = -sl * co * a[0] - sl * so * a[1] + cl * a[2];
    out[2] = cl * co * a[0] + cl * so * a[1] + sl * a[2];
}

int ekf_sat_geometry(const ekf_antenna_t *a, const int32_t sat_pos_lsb[3],
                     const int16_t sat_vel_lsb[3], ekf_sat_t *sat)
{
    if (gnss_geom_sat(a->ecef_dmm, sat_pos_lsb, sat_vel_lsb, &sat->g) != NAV_OK) {
        return NAV_EINVAL;
    }
    ecef_to_enu(a, sat->g.los_ecef, sat->los_enu);
    ecef_to_enu(a, sat->g.sat_vel_mps, sat->sat_vel_enu_mps);
    return NAV_OK;
}

void ekf_rows_pseudorange(const ekf_t *k, const ekf_antenna_t *a, const ekf_sat_t *sat,
                          uint32_t pr_lsb, int use_bias, nav_real_t h[EKF_N], nav_real_t *z_m)
{
    zero_row(h);
    const nav_real_t *u = sat->los_enu;
    nav_real_t hp[3];
    neg_cross(u, a->l_n, hp);
    for (int i = 0; i < 3; i++) {
        h[EKF_DR + i] = -u[i];
        h[EKF_PSI + i] = hp[i];
    }
    h[EKF_CB] = NAV_C(1.0);
    *z_m = -gnss_geom_pr_residual_m(pr_lsb, &sat->g, k->clock_dmm);
    if (use_bias != 0) {
        /* the correlated part of the range errors as the receiver's horizontal position
         * error b: the range is short by u . b */
        h[EKF_GB] = -u[0];
        h[EKF_GB + 1] = -u[1];
        *z_m -= u[0] * k->gnss_bias_m[0] + u[1] * k->gnss_bias_m[1];
    }
}

void ekf_rows_range_rate(const ekf_t *k, const sins_t *s, const nav_real_t v_then_mps[3],
                         const nav_real_t w_b_rps[3], const nav_real_t lever_b_m[3],
                         const ekf_sat_t *sat, nav_real_t rr_mps, nav_real_t h[EKF_N],
                         nav_real_t *z_mps)
{
    mat3_t C;
    quat_to_dcm(s->q_bn, &C);
    nav_real_t wl_b[3], wl_n[3];
    vec3_cross(w_b_rps, lever_b_m, wl_b);
    mat3_mul_vec(&C, wl_b, wl_n);
    const nav_real_t *u = sat->los_enu;
    nav_real_t rate = k->clock_drift_mps - rr_mps;
    for (int i = 0; i < 3; i++) {
        rate += u[i] * (sat->sat_vel_enu_mps[i] - (v_then_mps[i] + wl_n[i]));
    }
    zero_row(h);
    nav_real_t hp[3], u_b[3], hb[3];
    neg_cross(u, wl_n, hp);
    mat3t_mul_vec(&C, u, u_b);
    vec3_cross(u_b, lever_b_m, hb);
    for (int i = 0; i < 3; i++) {
        h[EKF_DV + i] = -u[i];
        h[EKF_PSI + i] = hp[i];
        h[EKF_BG + i] = hb[i];
    }
    h[EKF_GZ] = hb[2];
    h[EKF_SG] = hb[2] * w_b_rps[2]; /* the z rate's scale error, as its bias (ekf.h) */
    h[EKF_CD] = NAV_C(1.0);
    *z_mps = rate;
}
