/* mount_est.c - the automatic coarse mounting estimate; see mount_est.h. */
#include "mount_est.h"

#include <string.h>

/* a window's regressor weight on the lateral and forward columns when nothing excites
 * them: (0.01 m/s^2)^2 per window, so that the columns shrink to zero instead of the
 * normal equations going singular (at rest, or driving straight at constant speed) */
#define MOUNT_EST_RIDGE_M2PS4 NAV_C(1e-4)

int mount_est_init(mount_est_t *e, const mount_est_config_t *cfg)
{
    if (!nav_isfinite(cfg->sigma_rad) || !nav_isfinite(cfg->excite_m2ps3) ||
        cfg->sigma_rad <= NAV_C(0.0) || cfg->excite_m2ps3 < NAV_C(0.0)) {
        return NAV_EINVAL;
    }
    (void)memset(e, 0, sizeof *e);
    e->cfg = *cfg;
    e->res.sigma_rp_rad = NAV_PI;
    e->res.sigma_yaw_rad = NAV_PI;
    return NAV_OK;
}

static void window_clear(mount_est_t *e)
{
    for (int i = 0; i < 3; i++) {
        e->win_dv[i] = NAV_C(0.0);
        e->win_dth[i] = NAV_C(0.0);
    }
    e->win_t_s = NAV_C(0.0);
}

static void drop(mount_est_t *e)
{
    window_clear(e);
    e->have_start = 0u;
}

static int inc_finite(const imu_inc_t *inc)
{
    int ok = 1;
    if (!nav_isfinite(inc->dt_s) || !(inc->dt_s > NAV_C(0.0)) || !(inc->dt_s < NAV_C(1.0))) {
        ok = 0;
    }
    for (int i = 0; i < 3; i++) {
        if (!nav_isfinite(inc->dtheta_b_rad[i]) || !nav_isfinite(inc->dv_b_mps[i])) {
            ok = 0;
        }
    }
    return ok;
}

static void accumulate(mount_est_t *e, const nav_real_t f[3], const nav_real_t m[3])
{
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            nav_acc_add(&e->s_mm[r][c], &e->s_mm_lo[r][c], m[r] * m[c]);
            nav_acc_add(&e->s_fm[r][c], &e->s_fm_lo[r][c], f[r] * m[c]);
        }
        nav_acc_add(&e->s_f[r], &e->s_f_lo[r], f[r]);
    }
    nav_acc_add(&e->s_ff, &e->s_ff_lo, vec3_dot(f, f));
    e->n_windows++;
}

/* the window's mean specific force and rate, its model; 1 if accumulated */
static int close_window(mount_est_t *e, nav_real_t speed_mps)
{
    const nav_real_t t = e->win_t_s;
    nav_real_t f[3], w[3], up[3];
    for (int i = 0; i < 3; i++) {
        f[i] = e->win_dv[i] / t;
        w[i] = e->win_dth[i] / t;
        up[i] = e->s_f[i] + f[i];
    }
    const nav_real_t v0 = e->v_start_mps;
    e->v_start_mps = speed_mps;
    window_clear(e);
    if (vec3_norm(f) > MOUNT_EST_MAX_F_MPS2) {
        e->n_refused++;
        return 0;
    }
    const nav_real_t nu = vec3_norm(up);
    const nav_real_t wz = nu > NAV_C(0.0) ? vec3_dot(w, up) / nu : NAV_C(0.0);
    const nav_real_t a_fwd = (speed_mps - v0) / t;
    const nav_real_t a_lat = -NAV_C(0.5) * (speed_mps + v0) * wz;
    const nav_real_t m[3] = {a_lat, a_fwd, MOUNT_EST_G_MPS2};
    accumulate(e, f, m);
    nav_acc_add(&e->excite, &e->excite_lo, (a_fwd * a_fwd + a_lat * a_lat) * t);
    return 1;
}

int mount_est_sample(mount_est_t *e, const imu_inc_t *inc, nav_real_t speed_mps, int speed_valid)
{
    if (!inc_finite(inc) || (speed_valid && !nav_isfinite(speed_mps))) {
        e->n_refused++;
        drop(e);
        return NAV_EINVAL;
    }
    if (!speed_valid) {
        drop(e); /* no model without the speed */
        return 0;
    }
    if (!e->have_start) {
        e->v_start_mps = speed_mps; /* the window starts after this sample */
        e->have_start = 1u;
        return 0;
    }
    for (int i = 0; i < 3; i++) {
        e->win_dv[i] += inc->dv_b_mps[i];
        e->win_dth[i] += inc->dtheta_b_rad[i];
    }
    e->win_t_s += inc->dt_s;
    if (e->win_t_s + NAV_C(0.5) * inc->dt_s < MOUNT_EST_WINDOW_S) {
        return 0;
    }
    return close_window(e, speed_mps);
}

/* inv = the inverse of the symmetric A by its adjugate; 0 if not positive definite */
static int inverse3(const mat3_t *Am, mat3_t *im)
{
    const nav_real_t(*A)[3] = Am->m;
    nav_real_t(*inv)[3] = im->m;
    const nav_real_t c00 = A[1][1] * A[2][2] - A[1][2] * A[2][1];
    const nav_real_t c01 = A[1][2] * A[2][0] - A[1][0] * A[2][2];
    const nav_real_t c02 = A[1][0] * A[2][1] - A[1][1] * A[2][0];
    const nav_real_t det = A[0][0] * c00 + A[0][1] * c01 + A[0][2] * c02;
    if (!(det > NAV_C(0.0)) || !nav_isfinite(det)) {
        return 0;
    }
    inv[0][0] = c00 / det;
    inv[0][1] = (A[0][2] * A[2][1] - A[0][1] * A[2][2]) / det;
    inv[0][2] = (A[0][1] * A[1][2] - A[0][2] * A[1][1]) / det;
    inv[1][0] = c01 / det;
    inv[1][1] = (A[0][0] * A[2][2] - A[0][2] * A[2][0]) / det;
    inv[1][2] = (A[0][2] * A[1][0] - A[0][0] * A[1][2]) / det;
    inv[2][0] = c02 / det;
    inv[2][1] = (A[0][1] * A[2][0] - A[0][0] * A[2][1]) / det;
    inv[2][2] = (A[0][0] * A[1][1] - A[0][1] * A[1][0]) / det;
    return 1;
}

static nav_real_t wrap_pi(nav_real_t a)
{
    return a > NAV_PI ? a - NAV_C(2.0) * NAV_PI : a;
}

/* the residual sum |f - X m|^2 = S_ff - 2 tr(X^T S_fm) + tr(X S_mm X^T), at least 0 */
static nav_real_t residual_sum(const mount_est_t *e, const mat3_t *Xm)
{
    const nav_real_t(*X)[3] = Xm->m;
    nav_real_t r = e->s_ff;
    nav_real_t lo = e->s_ff_lo;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            nav_real_t xs = NAV_C(0.0); /* (X S_mm)_ij */
            for (int k = 0; k < 3; k++) {
                xs += X[i][k] * e->s_mm[k][j];
            }
            nav_acc_add(&r, &lo, X[i][j] * (xs - NAV_C(2.0) * e->s_fm[i][j]));
        }
    }
    r += lo;
    return r > NAV_C(0.0) ? r : NAV_C(0.0);
}

void mount_est_solve(mount_est_t *e)
{
    mount_est_result_t *res = &e->res;
    res->valid = 0u;
    res->converged = 0u;
    res->n_windows = e->n_windows;
    res->excite_m2ps3 = e->excite;
    res->sigma_rp_rad = NAV_PI;
    res->sigma_yaw_rad = NAV_PI;
    if (e->n_windows < MOUNT_EST_MIN_WINDOWS) {
        return;
    }
    mat3_t Am, im, Xm;
    (void)memset(&Am, 0, sizeof Am);
    (void)memset(&im, 0, sizeof im);
    (void)memset(&Xm, 0, sizeof Xm);
    nav_real_t(*A)[3] = Am.m;
    nav_real_t(*inv)[3] = im.m;
    nav_real_t(*X)[3] = Xm.m;
    const nav_real_t ridge = MOUNT_EST_RIDGE_M2PS4 * (nav_real_t)e->n_windows;
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            A[r][c] = e->s_mm[r][c] + e->s_mm_lo[r][c];
        }
    }
    A[0][0] += ridge;
    A[1][1] += ridge;
    if (!inverse3(&Am, &im)) {
        return;
    }
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            X[r][c] = e->s_fm[r][0] * inv[0][c] + e->s_fm[r][1] * inv[1][c] +
                      e->s_fm[r][2] * inv[2][c];
        }
    }
    const nav_real_t s2 =
        residual_sum(e, &Xm) / (NAV_C(3.0) * ((nav_real_t)e->n_windows - NAV_C(3.0)));
    /* the up axis: the column of g */
    nav_real_t z[3] = {X[0][2], X[1][2], X[2][2]};
    const nav_real_t nz = vec3_norm(z);
    if (!(nz > NAV_C(0.5)) || !nav_isfinite(nz)) {
        return; /* not a vehicle on the ground */
    }
    for (int i = 0; i < 3; i++) {
        z[i] /= nz;
    }
    res->sigma_rp_rad = nav_sqrt(s2 * inv[2][2]) / nz;
    res->rpy_rad[0] = nav_atan2(-z[0], z[2]);
    res->rpy_rad[1] = nav_asin(nav_clamp(z[1], NAV_C(-1.0), NAV_C(1.0)));
    res->rpy_rad[2] = NAV_C(0.0);
    res->valid = 1u;
    /* the forward axis: its column, and up x the lateral column, by their weights */
    const nav_real_t x1[3] = {X[0][0], X[1][0], X[2][0]};
    nav_real_t y0[3];
    vec3_cross(z, x1, y0);
    const nav_real_t w_fwd = NAV_C(1.0) / inv[1][1];
    const nav_real_t w_lat = NAV_C(1.0) / inv[0][0];
    nav_real_t y[3];
    for (int i = 0; i < 3; i++) {
        y[i] = (w_fwd * X[i][1] + w_lat * y0[i]) / (w_fwd + w_lat);
    }
    const nav_real_t yz = vec3_dot(y, z);
    for (int i = 0; i < 3; i++) {
        y[i] -= yz * z[i];
    }
    const nav_real_t ny = vec3_norm(y);
    if (!(ny > NAV_C(0.5))) {
        return; /* yaw not observed yet: sigma_yaw stays pi */
    }
    for (int i = 0; i < 3; i++) {
        y[i] /= ny;
    }
    nav_real_t x[3];
    vec3_cross(y, z, x);
    mat3_t C_vi; /* rows: the vehicle's axes in the IMU's */
    for (int i = 0; i < 3; i++) {
        C_vi.m[0][i] = x[i];
        C_vi.m[1][i] = y[i];
        C_vi.m[2][i] = z[i];
    }
    nav_real_t roll, pitch, yaw;
    dcm_to_euler(&C_vi, &roll, &pitch, &yaw);
    res->rpy_rad[0] = roll;
    res->rpy_rad[1] = pitch;
    res->rpy_rad[2] = wrap_pi(yaw);
    /* the yaw's sigma: the forward and lateral columns' combined */
    const nav_real_t info = (w_fwd + w_lat) / (s2 > NAV_C(0.0) ? s2 : NAV_C(1e-30));
    res->sigma_yaw_rad = NAV_C(1.0) / (nav_sqrt(info) * ny);
    res->converged = (res->sigma_rp_rad < e->cfg.sigma_rad && res->sigma_yaw_rad < e->cfg.sigma_rad &&
                      e->excite >= e->cfg.excite_m2ps3)
                         ? 1u
                         : 0u;
}
