/*
 * ekf.c - the 26-state error-state Kalman filter (ekf.h, docs/kalman.md).
 */
#include "ekf.h"

#include "dr.h"

#include <stddef.h>
#include <string.h>

#define DEG_RAD NAV_C(0.017453292519943295)

/* metres to the clock's 0.1 mm units, rounded; held within +-1e8 m (a clock error beyond
 * any receiver's, and far inside int64) so that no float-to-integer conversion overflows */
static int64_t nav_round_dmm(nav_real_t m)
{
    if (!nav_isfinite(m)) {
        return 0;
    }
    const nav_real_t lim = NAV_C(1.0e8);
    const nav_real_t c = m > lim ? lim : (m < -lim ? -lim : m);
    const nav_real_t d = c * (nav_real_t)GNSS_GEOM_DMM_PER_M;
    return (int64_t)(d >= NAV_C(0.0) ? d + NAV_C(0.5) : d - NAV_C(0.5));
}

ekf_config_t ekf_default_config(void)
{
    ekf_config_t c;
    c.pos_m = NAV_C(5.0);
    c.vel_mps = NAV_C(0.5);
    c.tilt_rad = NAV_C(0.5) * DEG_RAD;
    c.heading_rad = NAV_C(5.0) * DEG_RAD;
    c.bg_rps = NAV_C(0.015) * DEG_RAD / NAV_C(3600.0);
    c.ba_mps2 = NAV_C(1e-3);
    c.k = NAV_C(0.02);
    c.mount_rad = NAV_C(1.0) * DEG_RAD;
    c.gnss_bias_m = NAV_C(1.0);
    /* a receiver clock unknown to 1 ms (a receiver's clock steps, IS-GPS-200's 1 ms
     * ambiguity) and 1 ppm in frequency (a TCXO's tolerance) */
    c.clk_bias_m = NAV_C(3.0e5);
    c.clk_drift_mps = NAV_C(300.0);
    /* half of a 1 km/h step: the mean error of a truncated whole-km/h speed (OBD-II); the
     * application sets half its source's step (the parameter odo_step_mps) */
    c.odo_offset_mps = NAV_C(0.14);
    c.arw_rad_rts = NAV_C(8.73e-7);   /* 0.003 deg/sqrt(h) */
    c.vrw_mps_rts = NAV_C(1e-4);
    c.bg_rw_rps_rts = NAV_C(1e-9);
    c.ba_rw_mps2_rts = NAV_C(1e-6);
    c.k_rw_rts = NAV_C(1e-6);
    c.mount_rw_rad_rts = NAV_C(1e-7);
    c.odo_offset_rw_mps_rts = NAV_C(1e-5); /* 0.6 mm/s in an hour: a property of the signal */
    /* a MEMS gyro's sensitivity tolerance, 1 % (automotive parts' data sheets: 1-2 %, after
     * a factory trim well under 1 %), drifting with temperature by 0.05 % in an hour */
    c.gyro_scale = NAV_C(0.01);
    c.gyro_scale_rw_rts = NAV_C(8.3e-6);
    /* the in-run wander of a 0.005 deg/h Allan floor over 300 s (navigation grade; the
     * application sets its IMU's: fusion.c) */
    c.gz_sigma_rps = NAV_C(0.005) / EKF_GM_ADEV_PEAK * DEG_RAD / NAV_C(3600.0);
    c.gz_tau_s = NAV_C(300.0);
    /* the forward accelerometer's in-run wander: a 0.01 mg Allan floor over 300 s (the
     * navigation grade's; the application sets its IMU's: fusion.c) */
    c.af_sigma_mps2 = NAV_C(1e-4) / EKF_GM_ADEV_PEAK;
    c.af_tau_s = NAV_C(300.0);
    /* a TCXO (Brown & Hwang, 4th ed., table 9.2: h0 = 2e-19 s, h-2 = 2e-20 1/s):
     * c^2 h0 / 2 = 9.0e-3 m^2/s, 2 pi^2 c^2 h-2 = 3.5e-2 m^2/s^3 */
    c.clk_b_psd_m2ps = NAV_C(9.0e-3);
    c.clk_d_psd_m2ps3 = NAV_C(3.5e-2);
    c.var_floor = NAV_C(1e-18);
    return c;
}

/* out of line (noinline): inlined into ekf_init it measured 72 bytes more of the ECU's flash */
__attribute__((noinline)) static int cfg_ok(const ekf_config_t *c)
{
    const nav_real_t v[] = {c->pos_m, c->vel_mps, c->tilt_rad, c->heading_rad, c->bg_rps,
                            c->ba_mps2, c->k, c->mount_rad, c->arw_rad_rts, c->vrw_mps_rts,
                            c->bg_rw_rps_rts, c->ba_rw_mps2_rts, c->k_rw_rts,
                            c->mount_rw_rad_rts, c->var_floor, c->gnss_bias_m,
                            c->clk_bias_m, c->clk_drift_mps, c->clk_b_psd_m2ps,
                            c->clk_d_psd_m2ps3, c->odo_offset_mps, c->odo_offset_rw_mps_rts,
                            c->gyro_scale, c->gyro_scale_rw_rts, c->gz_sigma_rps,
                            c->gz_tau_s, c->af_sigma_mps2, c->af_tau_s};
    for (size_t i = 0u; i < sizeof v / sizeof v[0]; i++) {
        if (!(v[i] > NAV_C(0.0)) || !nav_isfinite(v[i])) {
            return 0;
        }
    }
    return 1;
}

static void reset_cov(ekf_t *k, nav_real_t heading_sigma_rad)
{
    const ekf_config_t *c = &k->cfg;
    for (int i = 0; i < EKF_N; i++) {
        for (int j = 0; j < EKF_N; j++) {
            k->P[i][j] = NAV_C(0.0);
        }
    }
    const nav_real_t sd[EKF_N] = {c->pos_m,    c->pos_m,    c->pos_m,    c->vel_mps,
                                  c->vel_mps,  c->vel_mps,  c->tilt_rad, c->tilt_rad,
                                  heading_sigma_rad, c->bg_rps, c->bg_rps, c->bg_rps,
                                  c->ba_mps2,  c->ba_mps2,  c->ba_mps2,  c->k,
                                  c->mount_rad, c->mount_rad, c->gnss_bias_m, c->gnss_bias_m,
                                  c->clk_bias_m, c->clk_drift_mps, c->odo_offset_mps,
                                  c->gyro_scale, c->gz_sigma_rps, c->af_sigma_mps2};
    for (int i = 0; i < EKF_N; i++) {
        k->P[i][i] = sd[i] * sd[i];
    }
}

int ekf_init(ekf_t *k, const ekf_config_t *cfg, nav_real_t heading_sigma_rad)
{
    if (k == NULL || cfg == NULL || !cfg_ok(cfg)) {
        return NAV_EINVAL;
    }
    /* every estimate, counter and flag 0, the error state too (P: reset_cov); one clear
     * of the whole, not a store per field (176 bytes less in the ECU image: make
     * VEHICLE=toyota_rav4_2017 target-budget) */
    (void)memset(k, 0, sizeof *k);
    k->cfg = *cfg;
    reset_cov(k, heading_sigma_rad > NAV_C(0.0) ? heading_sigma_rad : cfg->heading_rad);
    return NAV_OK;
}

/* multiply row and column i of P by a (the diagonal by a^2) */
static void scale_state(ekf_t *k, int i, nav_real_t a)
{
    for (int j = 0; j < EKF_N; j++) {
        k->P[i][j] *= a;
        k->P[j][i] *= a;
    }
}

/* ------------------------------------------------------------- prediction ---- */

typedef struct {
    uint8_t r, c;
    nav_real_t v;
} f_entry_t;

/* all 52 used (ekf.h): add_entry drops an entry beyond them, which the new state's own
 * propagation test then finds (test_ekf: test_accel_in_run_bias_is_gauss_markov for the last) */
#define F_MAX 52

static int add_entry(f_entry_t *f, int n, int r, int c, nav_real_t v)
{
    if (n < F_MAX) {
        f[n].r = (uint8_t)r;
        f[n].c = (uint8_t)c;
        f[n].v = v;
        n++;
    }
    return n;
}

/* the non-zero entries of skew(w) = [w x] at (r0, c0), scaled by sign */
static int add_skew(f_entry_t *f, int n, int r0, int c0, const nav_real_t w[3], nav_real_t sign)
{
    n = add_entry(f, n, r0 + 0, c0 + 1, -sign * w[2]);
    n = add_entry(f, n, r0 + 0, c0 + 2, sign * w[1]);
    n = add_entry(f, n, r0 + 1, c0 + 0, sign * w[2]);
    n = add_entry(f, n, r0 + 1, c0 + 2, -sign * w[0]);
    n = add_entry(f, n, r0 + 2, c0 + 0, -sign * w[1]);
    n = add_entry(f, n, r0 + 2, c0 + 1, sign * w[0]);
    return n;
}

static int add_mat(f_entry_t *f, int n, int r0, int c0, const mat3_t *M, nav_real_t sign)
{
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            n = add_entry(f, n, r0 + i, c0 + j, sign * M->m[i][j]);
        }
    }
    return n;
}

/* A first-order Gauss-Markov state i of sigma and tau over dt_s (ekf.h, states 24 and 25):
 * its driving noise, 2 sigma^2 dt / tau, and its estimate's mean decaying as the state */
static void gm_noise(ekf_t *k, int i, nav_real_t *estimate, nav_real_t sigma, nav_real_t tau,
                     nav_real_t dt_s)
{
    k->P[i][i] += NAV_C(2.0) * sigma * sigma * dt_s / tau;
    *estimate -= *estimate * dt_s / tau;
}

void ekf_predict(ekf_t *k, const sins_t *s, const nav_real_t f_n_mps2[3],
                 nav_real_t w_bz_rps, nav_real_t dt_s)
{
    mat3_t C;
    quat_to_dcm(s->q_bn, &C);
    const nav_real_t lat = geo_lat_rad(&s->pos);
    const nav_real_t h = geo_h_m(&s->pos);
    earth_t e;
    earth_eval(lat, h, &e);
    nav_real_t w_en[3];
    earth_transport_rate(&e, h, s->v_n_mps, w_en);
    nav_real_t w_in[3], w_c[3];
    for (int i = 0; i < 3; i++) {
        w_in[i] = e.w_ie_n_rps[i] + w_en[i];
        w_c[i] = NAV_C(2.0) * e.w_ie_n_rps[i] + w_en[i];
    }
    f_entry_t F[F_MAX];
    int n = 0;
    for (int i = 0; i < 3; i++) {
        n = add_entry(F, n, EKF_DR + i, EKF_DV + i, NAV_C(1.0));
    }
    n = add_skew(F, n, EKF_DV, EKF_PSI, f_n_mps2, NAV_C(1.0));  /* [f_n x] psi */
    n = add_mat(F, n, EKF_DV, EKF_BA, &C, NAV_C(1.0));          /* C_bn ba */
    n = add_skew(F, n, EKF_DV, EKF_DV, w_c, NAV_C(-1.0));       /* -(2 w_ie + w_en) x dv */
    n = add_entry(F, n, EKF_DV + 2, EKF_DR + 2,
                  NAV_C(2.0) * e.g_mps2 / nav_sqrt(e.R_M_m * e.R_N_m)); /* gravity vs height */
    n = add_skew(F, n, EKF_PSI, EKF_PSI, w_in, NAV_C(-1.0));    /* -w_in x psi */
    n = add_mat(F, n, EKF_PSI, EKF_BG, &C, NAV_C(-1.0));        /* -C_bn bg */
    for (int i = 0; i < 3; i++) {                                /* -C_bn e_z w_z sg */
        n = add_entry(F, n, EKF_PSI + i, EKF_SG, -C.m[i][2] * w_bz_rps);
    }
    n = add_entry(F, n, EKF_CB, EKF_CD, NAV_C(1.0));             /* clock bias <- drift */
    for (int i = 0; i < 3; i++) {                                /* -C_bn e_z gz */
        n = add_entry(F, n, EKF_PSI + i, EKF_GZ, -C.m[i][2]);
    }
    n = add_entry(F, n, EKF_GZ, EKF_GZ, -NAV_C(1.0) / k->cfg.gz_tau_s); /* decay */
    for (int i = 0; i < 3; i++) {                                /* C_bn e_y af */
        n = add_entry(F, n, EKF_DV + i, EKF_AF, C.m[i][1]);
    }
    n = add_entry(F, n, EKF_AF, EKF_AF, -NAV_C(1.0) / k->cfg.af_tau_s); /* decay */

    /* P <- (I + F dt) P (I + F dt)^T = P + dt (FP + (FP)^T) + dt^2 F (FP)^T */
    nav_real_t (*fp)[EKF_N] = k->fp;
    for (int i = 0; i < EKF_N; i++) {
        for (int j = 0; j < EKF_N; j++) {
            fp[i][j] = NAV_C(0.0);
        }
    }
    for (int q = 0; q < n; q++) {
        for (int j = 0; j < EKF_N; j++) {
            fp[F[q].r][j] += F[q].v * k->P[F[q].c][j];
        }
    }
    for (int i = 0; i < EKF_N; i++) {
        for (int j = 0; j < EKF_N; j++) {
            k->P[i][j] += dt_s * (fp[i][j] + fp[j][i]);
        }
    }
    const nav_real_t dt2 = dt_s * dt_s;
    for (int q = 0; q < n; q++) {
        for (int j = 0; j < EKF_N; j++) {
            k->P[F[q].r][j] += dt2 * F[q].v * fp[j][F[q].c];
        }
    }
    const ekf_config_t *c = &k->cfg;
    for (int i = 0; i < 3; i++) {
        k->P[EKF_DV + i][EKF_DV + i] += c->vrw_mps_rts * c->vrw_mps_rts * dt_s + k->q_inc[1];
        k->P[EKF_PSI + i][EKF_PSI + i] += c->arw_rad_rts * c->arw_rad_rts * dt_s + k->q_inc[0];
    }
    /* accelerometers x and z: a random walk; y: the turn-on bias, constant, and its in-run
     * part the Gauss-Markov state 25 (ekf.h) */
    k->P[EKF_BA][EKF_BA] += c->ba_rw_mps2_rts * c->ba_rw_mps2_rts * dt_s;
    k->P[EKF_BA + 2][EKF_BA + 2] += c->ba_rw_mps2_rts * c->ba_rw_mps2_rts * dt_s;
    /* x and y: a random walk; z: the turn-on bias, constant, and its in-run part the
     * Gauss-Markov state 24 (ekf.h) */
    for (int i = 0; i < 2; i++) {
        k->P[EKF_BG + i][EKF_BG + i] += c->bg_rw_rps_rts * c->bg_rw_rps_rts * dt_s;
    }
    k->q_inc[0] = NAV_C(0.0); /* spent */
    k->q_inc[1] = NAV_C(0.0);
    k->P[EKF_K][EKF_K] += c->k_rw_rts * c->k_rw_rts * dt_s;
    k->P[EKF_OB][EKF_OB] += c->odo_offset_rw_mps_rts * c->odo_offset_rw_mps_rts * dt_s;
    k->P[EKF_SG][EKF_SG] += c->gyro_scale_rw_rts * c->gyro_scale_rw_rts * dt_s;
    gm_noise(k, EKF_GZ, &k->gz_rps, c->gz_sigma_rps, c->gz_tau_s, dt_s);
    gm_noise(k, EKF_AF, &k->af_mps2, c->af_sigma_mps2, c->af_tau_s, dt_s);
    k->P[EKF_MP][EKF_MP] += c->mount_rw_rad_rts * c->mount_rw_rad_rts * dt_s;
    k->P[EKF_MY][EKF_MY] += c->mount_rw_rad_rts * c->mount_rw_rad_rts * dt_s;
    /* the two-state clock's discrete noise (Brown & Hwang sec. 9.3): the drift's white
     * noise integrated into the bias; Phi = I + F dt is exact for this block */
    const nav_real_t qd = c->clk_d_psd_m2ps3;
    k->P[EKF_CB][EKF_CB] += c->clk_b_psd_m2ps * dt_s + qd * dt2 * dt_s / NAV_C(3.0);
    k->P[EKF_CB][EKF_CD] += qd * dt2 / NAV_C(2.0);
    k->P[EKF_CD][EKF_CB] += qd * dt2 / NAV_C(2.0);
    k->P[EKF_CD][EKF_CD] += qd * dt_s;
    /* never more uncertain than a clock nobody measured (ekf_config_t): bounded without
     * raw measurements */
    const nav_real_t cap[2] = {c->clk_bias_m * c->clk_bias_m, c->clk_drift_mps * c->clk_drift_mps};
    for (int a = 0; a < 2; a++) {
        const int i = EKF_CB + a;
        if (k->P[i][i] > cap[a]) {
            scale_state(k, i, nav_sqrt(cap[a] / k->P[i][i]));
            k->P[i][i] = cap[a];
        }
    }
    (void)ekf_health(k);
}

/* ----------------------------------------------------------------- update ---- */

int ekf_update(ekf_t *k, const nav_real_t h[EKF_N], nav_real_t z, nav_real_t r,
               nav_real_t gate_sigma)
{
    if (!nav_isfinite(z) || !(r > NAV_C(0.0)) || !nav_isfinite(r)) {
        return -1;
    }
    nav_real_t u[EKF_N];
    nav_real_t hx = NAV_C(0.0);
    for (int i = 0; i < EKF_N; i++) {
        nav_real_t acc = NAV_C(0.0);
        for (int j = 0; j < EKF_N; j++) {
            acc += k->P[i][j] * h[j];
        }
        u[i] = acc;
        hx += h[i] * k->x[i];
    }
    nav_real_t S = r;
    for (int i = 0; i < EKF_N; i++) {
        S += h[i] * u[i];
    }
    if (!(S > NAV_C(0.0)) || !nav_isfinite(S)) {
        return -1;
    }
    const nav_real_t innov = z - hx;
    if (gate_sigma > NAV_C(0.0) && innov * innov > gate_sigma * gate_sigma * S) {
        k->n_gated++;
        return 0;
    }
    nav_real_t K[EKF_N];
    for (int i = 0; i < EKF_N; i++) {
        K[i] = u[i] / S;
    }
    if (k->hold_heading) {
        K[EKF_PSI + 2] = NAV_C(0.0);
        K[EKF_BG + 2] = NAV_C(0.0);
        K[EKF_MY] = NAV_C(0.0);
        K[EKF_SG] = NAV_C(0.0);
        K[EKF_GZ] = NAV_C(0.0);
    }
    for (int i = 0; i < EKF_N; i++) {
        k->x[i] += K[i] * innov;
    }
    /* Joseph form (I - K h) P (I - K h)^T + K r K^T, expanded for a scalar measurement:
     * P - K u^T - u K^T + S K K^T, evaluated term by term and kept symmetric (it holds for
     * any gain, the held states' zeros included) */
    for (int i = 0; i < EKF_N; i++) {
        for (int j = i; j < EKF_N; j++) {
            const nav_real_t v = k->P[i][j] - K[i] * u[j] - u[i] * K[j] + S * K[i] * K[j];
            k->P[i][j] = v;
            k->P[j][i] = v;
        }
    }
    k->n_updates++;
    return 1;
}

uint32_t ekf_health(ekf_t *k)
{
    uint32_t fixes = 0u;
    int finite = 1;
    for (int i = 0; i < EKF_N && finite; i++) {
        for (int j = 0; j < EKF_N; j++) {
            if (!nav_isfinite(k->P[i][j])) {
                finite = 0;
                break;
            }
        }
    }
    if (!finite) {
        reset_cov(k, k->cfg.heading_rad);
        for (int i = 0; i < EKF_N; i++) {
            k->x[i] = NAV_C(0.0);
        }
        fixes++;
        k->n_nonfinite++;
    }
    for (int i = 0; i < EKF_N; i++) {
        if (k->P[i][i] < NAV_C(0.0)) {
            k->n_negative_var++; /* not rounding below the floor: the filter has diverged */
        }
        if (!(k->P[i][i] >= k->cfg.var_floor)) {
            k->P[i][i] = k->cfg.var_floor;
            fixes++;
        }
        for (int j = i + 1; j < EKF_N; j++) {
            const nav_real_t m = NAV_C(0.5) * (k->P[i][j] + k->P[j][i]);
            /* a correlation beyond 1 is impossible in a valid covariance: clip it */
            const nav_real_t lim = nav_sqrt(k->P[i][i] * k->P[j][j]);
            nav_real_t v = m;
            if (m > lim) {
                v = lim;
                fixes++;
            } else if (m < -lim) {
                v = -lim;
                fixes++;
            }
            k->P[i][j] = v;
            k->P[j][i] = v;
        }
    }
    k->n_health_fixes += fixes;
    return fixes;
}

/* --------------------------------------------------------------- feedback ---- */

int ekf_feedback(ekf_t *k, sins_t *s)
{
    const nav_real_t *x = k->x;
    for (int i = 0; i < EKF_N; i++) {
        if (!nav_isfinite(x[i])) {
            for (int j = 0; j < EKF_N; j++) {
                k->x[j] = NAV_C(0.0);
            }
            return NAV_EINVAL;
        }
    }
    const nav_real_t lat = geo_lat_rad(&s->pos);
    const nav_real_t h = geo_h_m(&s->pos);
    nav_real_t R_M, R_N;
    earth_radii(nav_sin(lat), &R_M, &R_N);
    int rc = geo_pos_add(&s->pos, -x[EKF_DR + 1] / (R_M + h),
                         -x[EKF_DR + 0] / ((R_N + h) * nav_cos(lat)), -x[EKF_DR + 2]);
    nav_real_t v[3];
    for (int i = 0; i < 3; i++) {
        v[i] = s->v_n_mps[i] - x[EKF_DV + i];
    }
    if (rc == NAV_OK) {
        rc = sins_set_velocity(s, v);
    }
    /* C_true = (I + [psi x]) C_computed: q <- q(psi) (x) q */
    nav_real_t dq[4];
    if (rc == NAV_OK && rotvec_to_dquat(&x[EKF_PSI], dq) == NAV_OK) {
        nav_real_t qpsi[4] = {NAV_C(1.0) + dq[0], dq[1], dq[2], dq[3]};
        nav_real_t q[4];
        quat_mul(qpsi, s->q_bn, q);
        const nav_real_t nq = nav_sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        for (int i = 0; i < 4; i++) {
            s->q_bn[i] = q[i] / nq;
            s->q_bn_lo[i] = NAV_C(0.0);
        }
    }
    /* residual sensor errors are absorbed into the estimates; k and the mounting states
     * are estimate minus truth */
    for (int i = 0; i < 3; i++) {
        k->bg_rps[i] += x[EKF_BG + i];
        k->ba_mps2[i] += x[EKF_BA + i];
    }
    k->k -= x[EKF_K];
    k->odo_offset_mps -= x[EKF_OB];
    k->gyro_scale_z += x[EKF_SG];
    k->gz_rps += x[EKF_GZ];
    k->af_mps2 += x[EKF_AF];
    k->mount_pitch_rad -= x[EKF_MP];
    k->mount_yaw_rad -= x[EKF_MY];
    k->gnss_bias_m[0] -= x[EKF_GB];
    k->gnss_bias_m[1] -= x[EKF_GB + 1];
    k->clock_dmm -= nav_round_dmm(x[EKF_CB]);
    k->clock_drift_mps -= x[EKF_CD];
    for (int i = 0; i < EKF_N; i++) {
        k->x[i] = NAV_C(0.0);
    }
    return rc;
}

void ekf_reopen(ekf_t *k, nav_real_t pos_sigma_m, nav_real_t vel_sigma_mps)
{
    for (int i = EKF_DR; i < EKF_DV + 3; i++) {
        for (int j = 0; j < EKF_N; j++) {
            k->P[i][j] = NAV_C(0.0);
            k->P[j][i] = NAV_C(0.0);
        }
        const nav_real_t sd = i < EKF_DV ? pos_sigma_m : vel_sigma_mps;
        k->P[i][i] = sd * sd;
    }
    k->n_reopened++;
}

/* exp(-x) for x >= 0: 1 / (1 + y + y^2/2 + y^3/6 + y^4/24) for y = x / 2^m <= 0.5,
 * squared m times (relative error below 2^m y^5 / 120: 3e-6 at x = 0.25, a fix interval
 * of a quarter of the correlation time; 1e-3 at x = 10); 0 from x = 40 (below 5e-18) */
static nav_real_t exp_neg(nav_real_t x_in)
{
    if (!(x_in < NAV_C(40.0))) {
        return NAV_C(0.0);
    }
    nav_real_t x = x_in;
    int m = 0;
    while (x > NAV_C(0.5) && m < 7) {
        x *= NAV_C(0.5);
        m++;
    }
    nav_real_t e = NAV_C(1.0) /
                   (NAV_C(1.0) +
                    x * (NAV_C(1.0) +
                         x * (NAV_C(0.5) + x * (NAV_C(1.0) / NAV_C(6.0) + x * (NAV_C(1.0) / NAV_C(24.0))))));
    for (int i = 0; i < m; i++) {
        e *= e;
    }
    return e;
}

/* a correlated part's variance as a weight's denominator: at least 1 mm^2. Out of line
 * (noinline): inlined at its calls it took 16-32 bytes more of the ECU's flash. */
__attribute__((noinline)) static nav_real_t sc_var(nav_real_t s2)
{
    return s2 > NAV_C(1e-6) ? s2 : NAV_C(1e-6);
}

/* The vertical sums (ekf_gnss_scv_m) decayed by phi (0 at a start) and a fix's correlated
 * vertical part taken in (none: sigma_cv_m 0); forgotten after 14 correlation times
 * without a height, before the sums reach float32's denormals, where their ratio wanders */
static void scv_take(ekf_t *k, nav_real_t phi, nav_real_t sigma_cv_m)
{
    const nav_real_t has_v = sigma_cv_m > NAV_C(0.0) ? NAV_C(1.0) : NAV_C(0.0);
    k->gnss_scv_count = k->gnss_scv_count * phi + has_v;
    k->gnss_scv_info = k->gnss_scv_info * phi + has_v / sc_var(sigma_cv_m * sigma_cv_m);
    if (k->gnss_scv_count < NAV_C(1e-6)) {
        k->gnss_scv_count = NAV_C(0.0); /* the claim then P_UU's alone */
        k->gnss_scv_info = NAV_C(0.0);
    }
}

void ekf_gnss_bias_step(ekf_t *k, nav_real_t dt_s, nav_real_t tau_s, nav_real_t sigma_c_m,
                        nav_real_t prev_sigma_c_m, nav_real_t sigma_cv_m)
{
    const nav_real_t phi =
        tau_s > NAV_C(0.0) && dt_s >= NAV_C(0.0) ? exp_neg(dt_s / tau_s) : NAV_C(0.0);
    const nav_real_t s2 = sigma_c_m * sigma_c_m;
    const nav_real_t grown = sigma_c_m > prev_sigma_c_m
                                 ? s2 - prev_sigma_c_m * prev_sigma_c_m
                                 : NAV_C(0.0);
    /* a declared accuracy that improved: the error is the fraction sigma_c / prev of the
     * one estimated, the estimate with it (the receiver regained its satellites: the
     * degraded fixes' error is gone, not held with the better fixes' certainty) */
    const nav_real_t shrink = sigma_c_m < prev_sigma_c_m && prev_sigma_c_m > NAV_C(0.0)
                                  ? sigma_c_m / prev_sigma_c_m
                                  : NAV_C(1.0);
    k->gnss_sc_count = k->gnss_sc_count * phi + NAV_C(1.0);
    k->gnss_sc_info = k->gnss_sc_info * phi + NAV_C(1.0) / sc_var(s2);
    scv_take(k, phi, sigma_cv_m);
    for (int a = 0; a < 2; a++) {
        const int i = EKF_GB + a;
        k->gnss_bias_m[a] *= phi * shrink;
        scale_state(k, i, phi * shrink);
        k->P[i][i] += s2 * (NAV_C(1.0) - phi * phi) + grown;
        if (k->P[i][i] > s2) {
            /* P_ii scaled to s2 with its row and column by sqrt(s2 / P_ii): the
             * correlations stay */
            const nav_real_t a_s = nav_sqrt(s2 / k->P[i][i]);
            scale_state(k, i, a_s);
            k->P[i][i] = s2;
        }
        if (!(k->P[i][i] >= k->cfg.var_floor)) {
            k->P[i][i] = k->cfg.var_floor;
        }
    }
}

void ekf_gnss_bias_start(ekf_t *k, nav_real_t sigma_c_m, nav_real_t sigma_cv_m)
{
    const nav_real_t s2 = sigma_c_m * sigma_c_m;
    k->gnss_sc_count = NAV_C(1.0);
    k->gnss_sc_info = NAV_C(1.0) / sc_var(s2);
    scv_take(k, NAV_C(0.0), sigma_cv_m);
    for (int a = 0; a < 2; a++) {
        const int i = EKF_GB + a;
        for (int j = 0; j < EKF_N; j++) {
            k->P[i][j] = NAV_C(0.0);
            k->P[j][i] = NAV_C(0.0);
        }
        k->gnss_bias_m[a] = NAV_C(0.0);
        k->P[i][i] = s2 > k->cfg.var_floor ? s2 : k->cfg.var_floor;
        /* the position is the fix's, true + b + white, and db = 0 - b: dr = -db + white,
         * cov(dr, db) = -var(db), at most var(dr) in size */
        const nav_real_t c = s2 < k->P[EKF_DR + a][EKF_DR + a] ? s2 : k->P[EKF_DR + a][EKF_DR + a];
        k->P[EKF_DR + a][i] = -c;
        k->P[i][EKF_DR + a] = -c;
    }
}

/* sqrt(count / info) of an information-weighted sigma, 0 without any */
static nav_real_t weighted_sigma(nav_real_t count, nav_real_t info)
{
    return info > NAV_C(0.0) ? nav_sqrt(count / info) : NAV_C(0.0);
}

nav_real_t ekf_gnss_sc_m(const ekf_t *k)
{
    return weighted_sigma(k->gnss_sc_count, k->gnss_sc_info);
}

nav_real_t ekf_gnss_scv_m(const ekf_t *k)
{
    return weighted_sigma(k->gnss_scv_count, k->gnss_scv_info);
}

void ekf_clock_start(ekf_t *k, nav_real_t shift_m, nav_real_t drift_shift_mps,
                     nav_real_t sigma_b_m, nav_real_t sigma_d_mps)
{
    const nav_real_t sd[2] = {sigma_b_m, sigma_d_mps};
    for (int a = 0; a < 2; a++) {
        const int i = EKF_CB + a;
        for (int j = 0; j < EKF_N; j++) {
            k->P[i][j] = NAV_C(0.0);
            k->P[j][i] = NAV_C(0.0);
        }
        const nav_real_t v = sd[a] * sd[a];
        k->P[i][i] = v > k->cfg.var_floor ? v : k->cfg.var_floor;
        k->x[i] = NAV_C(0.0);
    }
    k->clock_dmm -= nav_round_dmm(shift_m);
    k->clock_drift_mps -= drift_shift_mps;
}

void ekf_clock_advance(ekf_t *k, nav_real_t dt_s)
{
    k->clock_dmm += nav_round_dmm(k->clock_drift_mps * dt_s);
}

nav_real_t ekf_sigma_h_m(const ekf_t *k)
{
    return nav_sqrt(k->P[EKF_DR][EKF_DR] + k->P[EKF_DR + 1][EKF_DR + 1]);
}

nav_real_t ekf_state_sigma(const ekf_t *k, int i)
{
    return nav_sqrt(k->P[i][i]);
}

nav_real_t ekf_state_cov(const ekf_t *k, int i, int j)
{
    return k->P[i][j];
}

static int finite_n(const nav_real_t *v, int n)
{
    for (int i = 0; i < n; i++) {
        if (!nav_isfinite(v[i])) {
            return 0;
        }
    }
    return 1;
}

int ekf_state_ok(const ekf_t *k)
{
    const nav_real_t scalars[8] = {k->k, k->mount_yaw_rad, k->mount_pitch_rad,
                                   k->clock_drift_mps, k->odo_offset_mps, k->gyro_scale_z,
                                   k->gz_rps, k->af_mps2};
    if (!finite_n(k->x, EKF_N) || !finite_n(k->bg_rps, 3) || !finite_n(k->ba_mps2, 3) ||
        !finite_n(scalars, 8) || !finite_n(k->gnss_bias_m, 2)) {
        return 0;
    }
    for (int i = 0; i < EKF_N; i++) {
        if (!(k->P[i][i] >= NAV_C(0.0)) || !nav_isfinite(k->P[i][i])) {
            return 0;
        }
    }
    return 1;
}

int ekf_set_gyro_bias(ekf_t *k, int axis, nav_real_t b_rps)
{
    if (axis < 0 || axis > 2 || !(nav_fabs(b_rps) < NAV_C(1.0))) {
        return NAV_EINVAL;
    }
    k->bg_rps[axis] = b_rps;
    return NAV_OK;
}

int ekf_set_odo_scale(ekf_t *k, nav_real_t odo_scale)
{
    if (!(nav_fabs(odo_scale) <= DR_MU_MAX)) {
        return NAV_EINVAL;
    }
    k->k = odo_scale;
    return NAV_OK;
}

int ekf_set_mount_yaw(ekf_t *k, nav_real_t yaw_rad)
{
    if (!(nav_fabs(yaw_rad) <= DR_DH_MAX_RAD)) {
        return NAV_EINVAL;
    }
    k->mount_yaw_rad = yaw_rad;
    return NAV_OK;
}

void ekf_add_increment_noise(ekf_t *k, nav_real_t var_angle_rad2, nav_real_t var_vel_m2ps2)
{
    k->q_inc[0] += var_angle_rad2;
    k->q_inc[1] += var_vel_m2ps2;
}

int ekf_widen_mount(ekf_t *k, nav_real_t pitch_sigma_rad, nav_real_t yaw_sigma_rad)
{
    if (!(pitch_sigma_rad >= NAV_C(0.0)) || !nav_isfinite(pitch_sigma_rad) ||
        !(yaw_sigma_rad >= NAV_C(0.0)) || !nav_isfinite(yaw_sigma_rad)) {
        return NAV_EINVAL;
    }
    const nav_real_t v_mp = pitch_sigma_rad * pitch_sigma_rad;
    const nav_real_t v_my = yaw_sigma_rad * yaw_sigma_rad;
    if (v_mp > k->P[EKF_MP][EKF_MP]) {
        k->P[EKF_MP][EKF_MP] = v_mp;
    }
    if (v_my > k->P[EKF_MY][EKF_MY]) {
        k->P[EKF_MY][EKF_MY] = v_my;
    }
    return NAV_OK;
}
