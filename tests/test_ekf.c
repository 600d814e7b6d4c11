/*
 * test_ekf.c - the error-state filter against the strapdown core it models.
 * Built for both numeric variants.
 *
 * 1. Propagation: the error model F (ekf.h) is checked against the navigator itself. Two
 *    SINS run the same exact IMU data of a stop-and-go circle drive (tests/support): one
 *    clean, one with residual gyro and accelerometer biases and initial position, velocity
 *    and attitude errors. The filter propagates a rank-one covariance P0 = a a^T with a the
 *    initial error vector and no process noise, so P(T) = (Phi a)(Phi a)^T and the
 *    predicted error is P(T)[:, j] / a_j for a state j that stays constant (a bias). It
 *    must match the two SINS's actual difference: to 5 % of each component's size (the
 *    model drops terms of order v/R and second-order products of the errors, which over
 *    60 s of these errors stay below 1 %) plus a small absolute floor.
 * 2. Measurements: each update, applied to a navigator with a known error, must move the
 *    estimate toward the truth: the sign and the geometry of each row (lever arm, odometer
 *    scale, non-holonomic constraints with a mounting yaw, zero velocity, zero rate).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app_tuning.h"
#include "dr.h"
#include "ekf.h"
#include "motions.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define LAT0 (45.0 * DEG)
#define LON0 (10.0 * DEG)
#define H0 100.0

static geo_pos_t geo(double lat, double lon, double h)
{
    const double lsb_per_rad = 1.8e9 * (double)GEO_LSB_PER_DEG_E7 / PI;
    const geo_pos_t p = {(int64_t)llround(lat * lsb_per_rad), (int64_t)llround(lon * lsb_per_rad),
                         (int64_t)llround(h * 1000.0 * (double)GEO_LSB_PER_MM)};
    return p;
}

static void q_of(double roll, double pitch, double heading, nav_real_t q[4])
{
    double qd[4];
    truth_q_from_euler(roll, pitch, heading, qd);
    for (int i = 0; i < 4; i++) {
        q[i] = (nav_real_t)qd[i];
    }
}

/* psi with C_comp = (I - [psi x]) C_true */
static void psi_of(const sins_t *comp, const sins_t *truth, double psi[3])
{
    mat3_t Cc, Ct;
    quat_to_dcm(comp->q_bn, &Cc);
    quat_to_dcm(truth->q_bn, &Ct);
    double M[3][3];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            double acc = 0.0;
            for (int l = 0; l < 3; l++) {
                acc += (double)Cc.m[i][l] * (double)Ct.m[j][l];
            }
            M[i][j] = acc;
        }
    }
    psi[0] = 0.5 * (M[1][2] - M[2][1]);
    psi[1] = 0.5 * (M[2][0] - M[0][2]);
    psi[2] = 0.5 * (M[0][1] - M[1][0]);
}

static ekf_config_t quiet_config(void)
{
    ekf_config_t c = ekf_default_config();
    c.arw_rad_rts = c.vrw_mps_rts = c.bg_rw_rps_rts = c.ba_rw_mps2_rts = NAV_C(1e-15);
    c.k_rw_rts = c.mount_rw_rad_rts = c.gyro_scale_rw_rts = NAV_C(1e-15);
    c.af_sigma_mps2 = NAV_C(1e-15);
    c.var_floor = NAV_C(1e-30);
    return c;
}

static void test_propagation_matches_sins(void **state)
{
    (void)state;
    const circle_t circ = {8.0, 40.0, 150.0, 30.0 * DEG};
    truth_gen_t g;
    truth_init(&g, kin_circle, &circ, LAT0, LON0, H0);
    kin_t k0;
    kin_circle(&circ, 0.0, &k0);
    const sins_config_t scfg = sins_default_config();
    sins_config_t cfg = scfg;
    cfg.vdamp_tau_s = NAV_C(0.0);
    const geo_pos_t p0 = geo(LAT0, LON0, H0);
    nav_real_t q0[4], v0[3];
    for (int i = 0; i < 4; i++) {
        q0[i] = (nav_real_t)k0.q_bn[i];
    }
    for (int i = 0; i < 3; i++) {
        v0[i] = (nav_real_t)k0.v_n_mps[i];
    }
    sins_t truth, comp;
    assert_int_equal(sins_init(&truth, &cfg, &p0, v0, q0), NAV_OK);
    /* initial errors a (computed minus true) */
    const double a_r[3] = {2.0, -1.5, 0.0}, a_v[3] = {0.05, -0.03, 0.0};
    const double a_psi[3] = {4e-4, -3e-4, 2e-3};
    const double a_bg[3] = {2e-6, -3e-6, 5e-6}, a_ba[3] = {2e-3, -1.5e-3, 0.0};
    const double a_sg = 1e-3; /* the z gyro reads 0.1 % high: 0.7 deg over the 12 rad turned */
    double R_M, R_N;
    truth_radii(LAT0, &R_M, &R_N);
    const geo_pos_t pc = geo(LAT0 + a_r[1] / (R_M + H0),
                             LON0 + a_r[0] / ((R_N + H0) * cos(LAT0)), H0 + a_r[2]);
    nav_real_t vc[3];
    for (int i = 0; i < 3; i++) {
        vc[i] = v0[i] + (nav_real_t)a_v[i];
    }
    /* C_comp = (I - [a_psi x]) C_true: q_comp = q(-a_psi) (x) q_true */
    const nav_real_t mpsi[3] = {(nav_real_t)-a_psi[0], (nav_real_t)-a_psi[1],
                                (nav_real_t)-a_psi[2]};
    nav_real_t dq[4], qm[4], qc[4];
    assert_int_equal(rotvec_to_dquat(mpsi, dq), NAV_OK);
    qm[0] = NAV_C(1.0) + dq[0];
    qm[1] = dq[1];
    qm[2] = dq[2];
    qm[3] = dq[3];
    quat_mul(qm, q0, qc);
    assert_int_equal(sins_init(&comp, &cfg, &pc, vc, qc), NAV_OK);

    ekf_t f;
    assert_int_equal(ekf_init(&f, &(ekf_config_t){0}, NAV_C(0.0)), NAV_EINVAL);
    const ekf_config_t qc_cfg = quiet_config();
    assert_int_equal(ekf_init(&f, &qc_cfg, NAV_C(0.0)), NAV_OK);
    double a[EKF_N] = {0};
    for (int i = 0; i < 3; i++) {
        a[EKF_DR + i] = a_r[i];
        a[EKF_DV + i] = a_v[i];
        a[EKF_PSI + i] = a_psi[i];
        a[EKF_BG + i] = a_bg[i];
        a[EKF_BA + i] = a_ba[i];
    }
    a[EKF_SG] = a_sg;
    for (int i = 0; i < EKF_N; i++) {
        for (int j = 0; j < EKF_N; j++) {
            f.P[i][j] = (nav_real_t)(a[i] * a[j]);
        }
    }
    const double dt = 0.01;
    const int n_pred = 10; /* predict at 10 Hz with the mean specific force */
    nav_real_t f_sum[3] = {0};
    nav_real_t wz_sum = NAV_C(0.0); /* the compensated z rate, as the application's mean */
    for (int k = 1; k <= 6000; k++) {
        double dth[3], dvb[3];
        truth_step(&g, dt, dth, dvb);
        imu_inc_t it, ic;
        it.dt_s = ic.dt_s = (nav_real_t)dt;
        for (int i = 0; i < 3; i++) {
            it.dtheta_b_rad[i] = (nav_real_t)dth[i];
            it.dv_b_mps[i] = (nav_real_t)dvb[i];
            ic.dtheta_b_rad[i] = (nav_real_t)(dth[i] * (i == 2 ? 1.0 + a_sg : 1.0) + a_bg[i] * dt);
            ic.dv_b_mps[i] = (nav_real_t)(dvb[i] + a_ba[i] * dt);
        }
        assert_int_equal(sins_step(&truth, &it), NAV_OK);
        assert_int_equal(sins_step(&comp, &ic), NAV_OK);
        mat3_t C;
        quat_to_dcm(comp.q_bn, &C);
        nav_real_t fn[3];
        mat3_mul_vec(&C, it.dv_b_mps, fn);
        for (int i = 0; i < 3; i++) {
            f_sum[i] += fn[i] / (nav_real_t)dt;
        }
        wz_sum += ic.dtheta_b_rad[2];
        if (k % n_pred == 0) {
            for (int i = 0; i < 3; i++) {
                f_sum[i] /= (nav_real_t)n_pred;
            }
            ekf_predict(&f, &comp, f_sum, wz_sum / (nav_real_t)(dt * n_pred),
                        (nav_real_t)(dt * n_pred));
            f_sum[0] = f_sum[1] = f_sum[2] = NAV_C(0.0);
            wz_sum = NAV_C(0.0);
        }
    }
    /* predicted error vector from the column of a constant state */
    double pred[EKF_N];
    for (int i = 0; i < EKF_N; i++) {
        pred[i] = (double)f.P[i][EKF_BG + 2] / a_bg[2];
    }
    /* actual errors */
    nav_real_t e_m, n_m;
    dr_local_m(&truth.pos, &comp.pos, &e_m, &n_m);
    const double act_r[3] = {(double)e_m, (double)n_m,
                             (double)(comp.pos.h - truth.pos.h) / (double)GEO_LSB_PER_MM / 1000.0};
    double act_psi[3];
    psi_of(&comp, &truth, act_psi);
    for (int i = 0; i < 2; i++) { /* horizontal: the vertical channel is unstable, undamped */
        print_message("dr[%d] predicted %.4f m, actual %.4f m\n", i, pred[EKF_DR + i], act_r[i]);
        assert_near(pred[EKF_DR + i], act_r[i], 0.05 * fabs(act_r[i]) + 0.05);
        const double act_v = (double)(comp.v_n_mps[i] - truth.v_n_mps[i]);
        print_message("dv[%d] predicted %.5f m/s, actual %.5f m/s\n", i, pred[EKF_DV + i], act_v);
        assert_near(pred[EKF_DV + i], act_v, 0.05 * fabs(act_v) + 2e-3);
    }
    for (int i = 0; i < 3; i++) {
        print_message("psi[%d] predicted %.3e rad, actual %.3e rad\n", i, pred[EKF_PSI + i],
                      act_psi[i]);
        assert_near(pred[EKF_PSI + i], act_psi[i], 0.05 * fabs(act_psi[i]) + 2e-5);
    }
}

/* ------------------------------------------------------------ measurements ---- */

/* a navigator at 45 N, attitude (roll, pitch, heading), velocity v_n */
static void nav_at(sins_t *s, double roll, double pitch, double heading, const double v[3])
{
    nav_real_t q[4], vn[3];
    q_of(roll, pitch, heading, q);
    for (int i = 0; i < 3; i++) {
        vn[i] = (nav_real_t)v[i];
    }
    const geo_pos_t p = geo(LAT0, LON0, H0);
    const sins_config_t cfg = sins_default_config();
    assert_int_equal(sins_init(s, &cfg, &p, vn, q), NAV_OK);
}

/* every state's 1-sigma 1e-9 (known), for a test that then opens the ones it studies */
static void sd_quiet(double sd[EKF_N])
{
    for (int i = 0; i < EKF_N; i++) {
        sd[i] = 1e-9;
    }
}

static void filter_with(ekf_t *f, const double sd[EKF_N])
{
    const ekf_config_t c = quiet_config();
    assert_int_equal(ekf_init(f, &c, NAV_C(0.0)), NAV_OK);
    for (int i = 0; i < EKF_N; i++) {
        f->P[i][i] = (nav_real_t)(sd[i] * sd[i]);
    }
}

/* GNSS position with a lever arm: the navigator 3 m east, 2 m south, 1 m high of the
 * truth; the antenna 1.5 m above and 1 m ahead of the IMU. One update with a 10 m prior
 * and a 0.1 m fix removes the error to 1 %. */
static void test_gnss_position_update(void **state)
{
    (void)state;
    const double v[3] = {0, 0, 0};
    sins_t s;
    nav_at(&s, 0.0, 0.0, 40.0 * DEG, v);
    const geo_pos_t truth = s.pos;
    assert_int_equal(geo_pos_add(&s.pos, (nav_real_t)(-2.0 / 6367000.0),
                                 (nav_real_t)(3.0 / (6389000.0 * cos(LAT0))), NAV_C(1.0)),
                     NAV_OK);
    const nav_real_t lever[3] = {NAV_C(0.0), NAV_C(1.0), NAV_C(1.5)};
    /* the antenna: 1 m along heading 40 deg, 1.5 m up */
    geo_pos_t ant = truth;
    assert_int_equal(geo_pos_add(&ant, (nav_real_t)(cos(40 * DEG) / 6367380.0),
                                 (nav_real_t)(sin(40 * DEG) / (6388838.0 * cos(LAT0))),
                                 NAV_C(1.5)),
                     NAV_OK);
    ekf_t f;
    double sd[EKF_N];
    sd_quiet(sd);
    sd[0] = sd[1] = sd[2] = 10.0;
    filter_with(&f, sd);
    assert_int_equal(ekf_gnss_position(&f, &s, &s.pos, &ant, lever, NAV_C(0.1), NAV_C(0.1),
                                       NAV_C(0.1), NAV_C(5.0), NAV_C(1.0), 1, 0),
                     3);
    assert_near(f.x[EKF_DR + 0], 3.0, 0.03);
    assert_near(f.x[EKF_DR + 1], -2.0, 0.03);
    assert_near(f.x[EKF_DR + 2], 1.0, 0.03);
    assert_int_equal(ekf_feedback(&f, &s), NAV_OK);
    nav_real_t e, n;
    dr_local_m(&truth, &s.pos, &e, &n);
    assert_near(e, 0.0, 0.05);
    assert_near(n, 0.0, 0.05);
    /* a 100 m jump is gated, nothing changes */
    geo_pos_t far = ant;
    assert_int_equal(geo_pos_add(&far, NAV_C(100.0) / NAV_C(6367380.0), NAV_C(0.0), NAV_C(0.0)),
                     NAV_OK);
    const uint32_t gated = f.n_gated;
    /* the horizontal pair is refused; the height, right, is gated on its own and taken */
    assert_int_equal(ekf_gnss_position(&f, &s, &s.pos, &far, lever, NAV_C(0.1), NAV_C(0.1),
                                       NAV_C(0.1), NAV_C(5.0), NAV_C(1.0), 1, 0),
                     1);
    assert_int_equal(f.n_gated, gated + 1u);
    assert_near(f.x[EKF_DR + 0], 0.0, 0.01);
    assert_near(f.x[EKF_DR + 1], 0.0, 0.01);
}

/* The receiver's correlated error as a state (ekf_gnss_bias_start, ekf_gnss_bias_step):
 * a standing navigator at the truth, a receiver declared 0.3 m white and 2.0 m correlated
 * (correlation time 120 s), 600 fixes at 5 Hz (2 min, one correlation time) all 3 m east
 * of the truth. The offset is split between the navigator's position and the receiver's
 * estimated error gnss_bias_m (the two add up to the 3 m: the fix less its estimated
 * error is where the navigator goes), the position sigma stays near the correlated part
 * (the white model without the state would average 600 fixes to 0.3 / sqrt(600) = 0.01
 * m) and covers the navigator's error within 2 sigma; over a gap of 10 correlation times
 * the state forgets: its estimate decays by exp(-10) and its variance returns to the
 * stationary 2.0^2. */
static void test_gnss_correlated_error_state(void **state)
{
    (void)state;
    const double v[3] = {0, 0, 0};
    sins_t s;
    nav_at(&s, 0.0, 0.0, 40.0 * DEG, v);
    geo_pos_t fix = s.pos;
    assert_int_equal(geo_pos_add(&fix, NAV_C(0.0), (nav_real_t)(3.0 / (6388838.0 * cos(LAT0))),
                                 NAV_C(0.0)),
                     NAV_OK);
    ekf_t f;
    double sd[EKF_N];
    sd_quiet(sd);
    const double sw = 0.3, sc = 2.0, sh = sqrt(sw * sw + sc * sc);
    sd[0] = sd[1] = sd[2] = sh;
    filter_with(&f, sd);
    ekf_gnss_bias_start(&f, (nav_real_t)sc, NAV_C(0.0));
    assert_near(f.P[EKF_GB][EKF_GB], sc * sc, 1e-4);
    assert_near(f.P[EKF_DR][EKF_GB], -sc * sc, 1e-4); /* dr = -db + white */
    const nav_real_t lever[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    for (int i = 0; i < 600; i++) {
        ekf_gnss_bias_step(&f, NAV_C(0.2), NAV_C(120.0), (nav_real_t)sc, (nav_real_t)sc, NAV_C(0.0));
        assert_int_equal(ekf_gnss_position(&f, &s, &s.pos, &fix, lever, (nav_real_t)sh,
                                           (nav_real_t)sw, NAV_C(1.0), NAV_C(5.0), NAV_C(1.0),
                                           0, 1),
                         2);
        assert_int_equal(ekf_feedback(&f, &s), NAV_OK);
    }
    nav_real_t e, n;
    dr_local_m(&fix, &s.pos, &e, &n); /* the navigator against the fix */
    const double east = (double)e + 3.0; /* the navigator against the truth */
    const double sig_e = (double)ekf_state_sigma(&f, EKF_DR);
    /* the offset split between the position and the receiver's error: none of it averaged
     * away as if it were white */
    assert_near((double)f.gnss_bias_m[0] + east, 3.0, 0.02);
    assert_true(sig_e > 0.6 * sc && sig_e < sc);
    assert_true(fabs(east) < 2.0 * sig_e);
    /* a gap of 10 correlation times */
    const double b0 = (double)f.gnss_bias_m[0];
    ekf_gnss_bias_step(&f, NAV_C(1200.0), NAV_C(120.0), (nav_real_t)sc, (nav_real_t)sc, NAV_C(0.0));
    assert_near((double)f.gnss_bias_m[0], b0 * exp(-10.0), fabs(b0) * exp(-10.0) * 2e-3 + 1e-7);
    assert_near(f.P[EKF_GB][EKF_GB], sc * sc, 0.01);
    /* a declared accuracy that grows adds its variance (a new error, the estimate kept);
     * one that shrinks to a third takes the estimate, its variance and its covariances to
     * a third, a ninth and a third (the error of the poorer fixes is gone with them: an
     * estimate of 6 m held with the better fixes' 1 m sigma would put the navigator 6 m
     * off them) */
    const double b1 = (double)f.gnss_bias_m[0];
    ekf_gnss_bias_step(&f, NAV_C(0.0), NAV_C(120.0), NAV_C(3.0), (nav_real_t)sc, NAV_C(0.0));
    assert_near(f.P[EKF_GB][EKF_GB], 9.0, 0.01);
    assert_near((double)f.gnss_bias_m[0], b1, 1e-9);
    f.gnss_bias_m[0] = NAV_C(6.0); /* as estimated from fixes declared that poor */
    const double c_dr = (double)f.P[EKF_DR][EKF_GB];
    const double p_gb = (double)f.P[EKF_GB][EKF_GB];
    ekf_gnss_bias_step(&f, NAV_C(0.0), NAV_C(120.0), NAV_C(1.0), NAV_C(3.0), NAV_C(0.0));
    assert_near((double)f.gnss_bias_m[0], 2.0, 1e-5);
    assert_near((double)f.P[EKF_GB][EKF_GB], p_gb / 9.0, 1e-4);
    assert_near((double)f.P[EKF_DR][EKF_GB], c_dr / 3.0, 1e-5 + fabs(c_dr) * 1e-5);
    assert_true((double)f.P[EKF_GB][EKF_GB] <= 1.0 + 1e-4);
}

/* ekf_state_ok sees a non-finite fed-back estimate, the gyro scale factor's among them (the
 * application divides every z increment by 1 + it) */
static void test_state_ok_sees_the_estimates(void **state)
{
    (void)state;
    ekf_t f;
    const ekf_config_t c = ekf_default_config();
    assert_int_equal(ekf_init(&f, &c, NAV_C(0.0)), NAV_OK);
    assert_true(ekf_state_ok(&f));
    f.gyro_scale_z = (nav_real_t)NAN;
    assert_false(ekf_state_ok(&f));
    f.gyro_scale_z = NAV_C(0.0);
    f.odo_offset_mps = (nav_real_t)INFINITY;
    assert_false(ekf_state_ok(&f));
    f.odo_offset_mps = NAV_C(0.0);
    f.gnss_bias_m[1] = (nav_real_t)NAN; /* subtracted from every fix (ekf_gnss_position) */
    assert_false(ekf_state_ok(&f));
}

/* The recent fixes' correlated sigma (ekf_gnss_sc_m): GIVEN a fresh filter THEN 0; GIVEN a
 * start at sigma_c 2 m and a fix of 4 m at once (dt 0: no decay) THEN the two weigh
 * equally, sqrt(2 / (1/4 + 1/16)) = 2.53 m; a fix of 4 m after 40 correlation times THEN
 * only it counts: 4 m; and with the correlation time between them halfway, phi = e^-1. */
static void test_recent_correlated_sigma(void **state)
{
    (void)state;
    ekf_t f;
    const ekf_config_t c = ekf_default_config();
    assert_int_equal(ekf_init(&f, &c, NAV_C(0.0)), NAV_OK);
    assert_near(ekf_gnss_sc_m(&f), 0.0, 0.0);
    ekf_gnss_bias_start(&f, NAV_C(2.0), NAV_C(0.0));
    assert_near(ekf_gnss_sc_m(&f), 2.0, 1e-6);
    ekf_gnss_bias_step(&f, NAV_C(0.0), NAV_C(20.0), NAV_C(4.0), NAV_C(2.0), NAV_C(0.0));
    assert_near(ekf_gnss_sc_m(&f), sqrt(2.0 / (0.25 + 1.0 / 16.0)), 1e-5);
    ekf_gnss_bias_start(&f, NAV_C(2.0), NAV_C(0.0));
    ekf_gnss_bias_step(&f, NAV_C(800.0), NAV_C(20.0), NAV_C(4.0), NAV_C(2.0), NAV_C(0.0));
    assert_near(ekf_gnss_sc_m(&f), 4.0, 1e-5);
    ekf_gnss_bias_start(&f, NAV_C(2.0), NAV_C(0.0));
    ekf_gnss_bias_step(&f, NAV_C(20.0), NAV_C(20.0), NAV_C(4.0), NAV_C(2.0), NAV_C(0.0));
    /* phi by the filter's exp_neg: within 5.2e-4 of e^-1 at x = 1 (2 y^5 / 120, y = 0.5) */
    const double phi = exp(-1.0);
    const double sc = sqrt((phi + 1.0) / (phi * 0.25 + 1.0 / 16.0));
    assert_near(ekf_gnss_sc_m(&f), sc, 5.2e-4 * sc);
}

/* The vertical's (ekf_gnss_scv_m), counted apart: GIVEN a start without a height (0) THEN
 * 0; a fix with a vertical part of 3 m THEN 3 m; one of 6 m at once THEN the two weigh
 * equally, sqrt(2 / (1/9 + 1/36)) = 3.79 m; then a fix without a height after one
 * correlation time THEN both decay by phi alike and the sigma stays 3.79 m (it is a ratio),
 * while the horizontal count takes the fix; a fix of 6 m after 40 correlation times THEN
 * only it counts; without a height for 14 correlation times THEN forgotten. */
static void test_recent_correlated_vertical_sigma(void **state)
{
    (void)state;
    ekf_t f;
    const ekf_config_t c = ekf_default_config();
    assert_int_equal(ekf_init(&f, &c, NAV_C(0.0)), NAV_OK);
    assert_near(ekf_gnss_scv_m(&f), 0.0, 0.0);
    ekf_gnss_bias_start(&f, NAV_C(2.0), NAV_C(0.0));
    assert_near(ekf_gnss_scv_m(&f), 0.0, 0.0);
    ekf_gnss_bias_step(&f, NAV_C(0.0), NAV_C(20.0), NAV_C(2.0), NAV_C(2.0), NAV_C(3.0));
    assert_near(ekf_gnss_scv_m(&f), 3.0, 1e-5);
    ekf_gnss_bias_step(&f, NAV_C(0.0), NAV_C(20.0), NAV_C(2.0), NAV_C(2.0), NAV_C(6.0));
    const double two = sqrt(2.0 / (1.0 / 9.0 + 1.0 / 36.0));
    assert_near(ekf_gnss_scv_m(&f), two, 1e-5 * two);
    ekf_gnss_bias_step(&f, NAV_C(20.0), NAV_C(20.0), NAV_C(2.0), NAV_C(2.0), NAV_C(0.0));
    assert_near(ekf_gnss_scv_m(&f), two, 1e-5 * two);
    ekf_gnss_bias_step(&f, NAV_C(800.0), NAV_C(20.0), NAV_C(2.0), NAV_C(2.0), NAV_C(6.0));
    assert_near(ekf_gnss_scv_m(&f), 6.0, 1e-4);
    ekf_gnss_bias_start(&f, NAV_C(2.0), NAV_C(1.5));
    assert_near(ekf_gnss_scv_m(&f), 1.5, 1e-6);
    /* 13 correlation times without a height: held; 15: forgotten, 0 (not the wandering
     * ratio of two denormals) */
    ekf_gnss_bias_step(&f, NAV_C(260.0), NAV_C(20.0), NAV_C(2.0), NAV_C(2.0), NAV_C(0.0));
    assert_near(ekf_gnss_scv_m(&f), 1.5, 1e-4);
    ekf_gnss_bias_step(&f, NAV_C(40.0), NAV_C(20.0), NAV_C(2.0), NAV_C(2.0), NAV_C(0.0));
    assert_near(ekf_gnss_scv_m(&f), 0.0, 0.0);
}

/* The heading error shows in the lever arm: an antenna 2 m ahead, the heading 2 deg off,
 * the position exact: the update (attitude prior 5 deg, position prior tiny) finds the
 * heading error from the 7 cm antenna offset. */
static void test_lever_arm_observes_heading(void **state)
{
    (void)state;
    const double v[3] = {0, 0, 0};
    sins_t s;
    nav_at(&s, 0.0, 0.0, 42.0 * DEG, v); /* true heading 40: error +2 deg = +psi_U */
    geo_pos_t ant = s.pos;
    assert_int_equal(geo_pos_add(&ant, (nav_real_t)(2.0 * cos(40 * DEG) / 6367380.0),
                                 (nav_real_t)(2.0 * sin(40 * DEG) / (6388838.0 * cos(LAT0))),
                                 NAV_C(0.0)),
                     NAV_OK);
    ekf_t f;
    double sd[EKF_N];
    sd_quiet(sd);
    sd[EKF_PSI + 2] = 5.0 * DEG;
    filter_with(&f, sd);
    const nav_real_t lever[3] = {NAV_C(0.0), NAV_C(2.0), NAV_C(0.0)};
    assert_true(ekf_gnss_position(&f, &s, &s.pos, &ant, lever, NAV_C(0.001), NAV_C(0.001),
                                  NAV_C(0.001), NAV_C(0.0), NAV_C(1.0), 1, 0) == 3);
    assert_near(f.x[EKF_PSI + 2], 2.0 * DEG, 0.05 * DEG);
}

/* Odometer and non-holonomic constraints. The car drives at 10 m/s along heading 40 deg;
 * the IMU is mounted 1 deg clockwise of the car's axis (its heading reads 41 deg), the
 * odometer reads 2 % long. From priors on k and the mounting yaw only, one update finds
 * both; a navigator velocity error along the car's lateral axis is removed by the NHC. */
static void test_odometer_scale_and_mounting(void **state)
{
    (void)state;
    const double v[3] = {10.0 * sin(40 * DEG), 10.0 * cos(40 * DEG), 0.0};
    sins_t s;
    nav_at(&s, 0.0, 0.0, 41.0 * DEG, v);
    ekf_t f;
    double sd[EKF_N];
    sd_quiet(sd);
    sd[EKF_K] = 0.05;
    sd[EKF_MY] = 3.0 * DEG;
    filter_with(&f, sd);
    const nav_real_t w0[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    assert_int_equal(ekf_odometer(&f, &s, w0, w0, NAV_C(10.2), NAV_C(0.001), NAV_C(0.001),
                                  NAV_C(0.001), NAV_C(0.0)), 3);
    assert_int_equal(ekf_feedback(&f, &s), NAV_OK);
    assert_near(f.k, 0.02, 2e-4);
    assert_near(f.mount_yaw_rad, 1.0 * DEG, 0.02 * DEG);
    /* lateral velocity error: the car's right-hand axis at heading 130 deg */
    const double vl[3] = {v[0] + 0.3 * sin(130 * DEG), v[1] + 0.3 * cos(130 * DEG), 0.0};
    nav_at(&s, 0.0, 0.0, 40.0 * DEG, vl);
    sd_quiet(sd);
    sd[EKF_DV] = sd[EKF_DV + 1] = sd[EKF_DV + 2] = 1.0;
    filter_with(&f, sd);
    assert_int_equal(ekf_odometer(&f, &s, w0, w0, NAV_C(10.0), NAV_C(0.01), NAV_C(0.01),
                                  NAV_C(0.01), NAV_C(0.0)), 3);
    assert_int_equal(ekf_feedback(&f, &s), NAV_OK);
    assert_near(s.v_n_mps[0], v[0], 0.01);
    assert_near(s.v_n_mps[1], v[1], 0.01);
}

/* Standstill: zero velocity removes a velocity error; zero rate finds the z gyro bias. */
/* The odometer's reference point behind the IMU: the IMU 1.5 m ahead of the rear axle, a
 * left turn of 15 m radius at 6 m/s (yaw rate 0.4 rad/s). The IMU slides 0.6 m/s to the
 * left while the rear axle runs straight along the car: with the lever arm the NHC sees
 * no lateral velocity and leaves the mounting yaw alone; without it, the same data would
 * read as a 0.1 rad mounting error. */
static void test_odometer_lever_arm_in_a_turn(void **state)
{
    (void)state;
    const double hd = 40.0 * DEG, r = 0.4, arm = 1.5, speed = 6.0;
    /* IMU velocity, body axes: (-r arm, speed, 0); to ENU with heading hd */
    const double vx = -r * arm, vy = speed;
    const double v[3] = {vx * cos(hd) + vy * sin(hd), -vx * sin(hd) + vy * cos(hd), 0.0};
    const nav_real_t w[3] = {NAV_C(0.0), NAV_C(0.0), (nav_real_t)r};
    const nav_real_t lever[3] = {NAV_C(0.0), (nav_real_t)-arm, NAV_C(0.0)};
    const nav_real_t none[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    double sd[EKF_N];
    sd_quiet(sd);
    sd[EKF_MY] = 3.0 * DEG;
    for (int with_lever = 1; with_lever >= 0; with_lever--) {
        sins_t s;
        nav_at(&s, 0.0, 0.0, hd, v);
        ekf_t f;
        filter_with(&f, sd);
        assert_int_equal(ekf_odometer(&f, &s, w, with_lever ? lever : none, (nav_real_t)speed,
                                      NAV_C(0.01), NAV_C(0.01), NAV_C(0.01), NAV_C(0.0)),
                         3);
        assert_int_equal(ekf_feedback(&f, &s), NAV_OK);
        if (with_lever) {
            assert_near(f.mount_yaw_rad, 0.0, 1e-5);
        } else {
            assert_true(fabs((double)f.mount_yaw_rad) > 0.02);
        }
    }
}

static void test_standstill_updates(void **state)
{
    (void)state;
    const double v[3] = {0.2, -0.1, 0.05};
    sins_t s;
    nav_at(&s, 0.0, 0.0, 0.0, v);
    ekf_t f;
    double sd[EKF_N];
    sd_quiet(sd);
    sd[EKF_DV] = sd[EKF_DV + 1] = sd[EKF_DV + 2] = 1.0;
    sd[EKF_BG + 2] = 1e-4;
    filter_with(&f, sd);
    assert_int_equal(ekf_zero_velocity(&f, &s, NAV_C(0.001), NAV_C(0.0)), 3);
    assert_int_equal(ekf_zero_rate(&f, NAV_C(5e-5), NAV_C(1e-7)), 1);
    assert_int_equal(ekf_feedback(&f, &s), NAV_OK);
    assert_near(s.v_n_mps[0], 0.0, 1e-3);
    assert_near(s.v_n_mps[2], 0.0, 1e-3);
    assert_near(f.bg_rps[2], 5e-5, 1e-7);

    /* a locked wheel says "standing" while the car runs at 8 m/s north with the filter's
     * velocity known to 0.1 m/s: the north row is 80 sigma off, so at a 5-sigma gate the
     * measurement is refused as a whole; the velocity is left alone */
    const double v8[3] = {0.0, 8.0, 0.0};
    nav_at(&s, 0.0, 0.0, 0.0, v8);
    sd[EKF_DV] = sd[EKF_DV + 1] = sd[EKF_DV + 2] = 0.1;
    filter_with(&f, sd);
    assert_int_equal(ekf_zero_velocity(&f, &s, NAV_C(0.02), NAV_C(5.0)), 0);
    assert_int_equal(f.n_gated, 1u);
    assert_int_equal(ekf_feedback(&f, &s), NAV_OK);
    assert_near(s.v_n_mps[1], 8.0, 1e-6);

    /* a standing car whose filter took a braking dive for a climb: up 0.09 m/s, known to
     * 0.01 m/s; the horizontal off by 0.05 m/s, known to 0.1 m/s. The vertical row is
     * 0.09 / sqrt(0.01^2 + 0.012^2) = 5.8 sigma off: refused alone (counted); the
     * horizontal zero is taken (before, the three were refused together, and the stop
     * with them) */
    const double vz[3] = {0.05, 0.0, 0.09};
    nav_at(&s, 0.0, 0.0, 0.0, vz);
    sd[EKF_DV] = sd[EKF_DV + 1] = 0.1;
    sd[EKF_DV + 2] = 0.01;
    filter_with(&f, sd);
    assert_int_equal(ekf_zero_velocity(&f, &s, NAV_C(0.012), NAV_C(5.0)), 2);
    assert_int_equal(f.n_gated, 1u);
    assert_int_equal(ekf_feedback(&f, &s), NAV_OK);
    assert_near(s.v_n_mps[0], 0.0, 2e-3);
    assert_near(s.v_n_mps[2], 0.09, 1e-6);
}

/* every state known to 1e-9 (sd_quiet), uncorrelated, but state i at its steady sigma */
static void filter_known_but(ekf_t *f, const ekf_config_t *c, int i, double sigma)
{
    assert_int_equal(ekf_init(f, c, NAV_C(0.0)), NAV_OK);
    double sd[EKF_N];
    sd_quiet(sd);
    sd[i] = sigma;
    for (int r = 0; r < EKF_N; r++) {
        for (int j = 0; j < EKF_N; j++) {
            f->P[r][j] = NAV_C(0.0);
        }
        f->P[r][r] = (nav_real_t)(sd[r] * sd[r]);
    }
}

/* The z gyro's in-run bias (state 24, ekf.h) is a first-order Gauss-Markov process:
 * GIVEN a level car standing still for 600 s, the in-run state at its steady sigma s
 * (correlation time T = 100 s), every other state known and no other noise, and an
 * estimate of 1e-4 rad/s WHEN the filter predicts at 10 Hz THEN
 * - the state's variance stays s^2 (a random walk of the same driving noise would reach
 *   13 s^2);
 * - the estimate decays as exp(-t / T);
 * - the heading's variance is the integrated process's, the double integral of its
 *   autocorrelation s^2 exp(-|u - v| / T) over [0, t]^2 = 2 s^2 T (t - T (1 - exp(-t / T))):
 *   10 s^2 T^2, where a bias held constant over the same time would give s^2 t^2 = 36 s^2 T^2;
 * - the heading's covariance with the state has the sign of d(psi_U)/dt = -gz (ekf.h: the
 *   residual bias turns the computed heading as bg_z does), -s^2 T (1 - exp(-t / T)).
 * Tolerance 2 %: Phi = I + F dt's error is dt / (2 T) = 5e-4 per correlation time, and the
 * Earth rate's coupling of the heading into the tilts is (w_ie t)^2 / 2 = 1e-3. */
static void test_gyro_in_run_bias_is_gauss_markov(void **state)
{
    (void)state;
    const double v[3] = {0.0, 0.0, 0.0};
    sins_t s;
    nav_at(&s, 0.0, 0.0, 0.0, v);
    ekf_config_t c = quiet_config();
    const double sigma = 1e-5, tau = 100.0, dt = 0.1, t_end = 600.0;
    c.gz_sigma_rps = (nav_real_t)sigma;
    c.gz_tau_s = (nav_real_t)tau;
    ekf_t f;
    filter_known_but(&f, &c, EKF_GZ, sigma);
    f.gz_rps = NAV_C(1e-4);
    const nav_real_t fn[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(9.80665)};
    const int n = (int)(t_end / dt + 0.5);
    for (int k = 0; k < n; k++) {
        ekf_predict(&f, &s, fn, NAV_C(0.0), (nav_real_t)dt);
    }
    const double var_gz = (double)f.P[EKF_GZ][EKF_GZ];
    const double var_h = (double)f.P[EKF_PSI + 2][EKF_PSI + 2];
    const double want_h = 2.0 * sigma * sigma * tau * (t_end - tau * (1.0 - exp(-t_end / tau)));
    print_message("in-run z bias: variance %.4g (steady %.4g), heading variance %.4g (want %.4g), "
                  "estimate %.4g (want %.4g)\n",
                  var_gz, sigma * sigma, var_h, want_h, (double)f.gz_rps, 1e-4 * exp(-t_end / tau));
    assert_near(var_gz, sigma * sigma, 0.02 * sigma * sigma);
    assert_near(var_h, want_h, 0.02 * want_h);
    assert_near((double)f.gz_rps, 1e-4 * exp(-t_end / tau), 0.02 * 1e-4 * exp(-t_end / tau));
    const double want_c = -sigma * sigma * tau * (1.0 - exp(-t_end / tau));
    assert_near((double)f.P[EKF_PSI + 2][EKF_GZ], want_c, 0.02 * fabs(want_c));
}

/* State 25, the forward accelerometer's in-run bias (ekf.h), on a standing car pitched
 * 5 deg nose up and heading 30 deg, over 300 s = 3 T with sigma s = 1e-3 m/s^2 and
 * T = 100 s, the other states known (1e-9) and quiet, the estimate started at 1e-2 m/s^2:
 * - the state's variance stays s^2 (a random walk of the same driving noise would reach
 *   7 s^2);
 * - the estimate decays as exp(-t / T);
 * - the velocity error along the body's forward axis u = C_bn e_y (east, north and up: the
 *   pitch puts 8.7 % of it into the height's rate) is the integrated process,
 *   2 s^2 T (t - T (1 - exp(-t / T))) = 4.1 s^2 T^2 in variance, and its covariance with
 *   the state has the sign of d(dv)/dt = +C_bn e_y af: +s^2 T (1 - exp(-t / T));
 * - nothing of it is across u (the Coriolis term turns 2 w_ie sin(lat) t = 0.03 rad of it).
 * Tolerance 2 %: Phi = I + F dt's error is dt / (2 T) = 5e-4 per correlation time, the
 * Coriolis turn's cos is 0.9996, the vertical channel's instability (2 g / R) t^2 / 2 =
 * 0.14 on the 0.76 % of the variance that is vertical. */
static void test_accel_in_run_bias_is_gauss_markov(void **state)
{
    (void)state;
    const double v[3] = {0.0, 0.0, 0.0};
    sins_t s;
    nav_at(&s, 0.0, 5.0 * DEG, 30.0 * DEG, v);
    ekf_config_t c = quiet_config();
    const double sigma = 1e-3, tau = 100.0, dt = 0.1, t_end = 300.0;
    c.af_sigma_mps2 = (nav_real_t)sigma;
    c.af_tau_s = (nav_real_t)tau;
    ekf_t f;
    filter_known_but(&f, &c, EKF_AF, sigma);
    f.af_mps2 = NAV_C(1e-2);
    mat3_t C;
    quat_to_dcm(s.q_bn, &C);
    const double u[3] = {(double)C.m[0][1], (double)C.m[1][1], (double)C.m[2][1]};
    /* the specific force of a standing car: gravity's reaction, up */
    const nav_real_t fn[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(9.80665)};
    const int n = (int)(t_end / dt + 0.5);
    for (int k = 0; k < n; k++) {
        ekf_predict(&f, &s, fn, NAV_C(0.0), (nav_real_t)dt);
    }
    double var_u = 0.0, cov_u = 0.0, trace_v = 0.0;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            var_u += u[i] * (double)f.P[EKF_DV + i][EKF_DV + j] * u[j];
        }
        cov_u += u[i] * (double)f.P[EKF_DV + i][EKF_AF];
        trace_v += (double)f.P[EKF_DV + i][EKF_DV + i];
    }
    const double var_af = (double)f.P[EKF_AF][EKF_AF];
    const double want_v = 2.0 * sigma * sigma * tau * (t_end - tau * (1.0 - exp(-t_end / tau)));
    const double want_c = sigma * sigma * tau * (1.0 - exp(-t_end / tau));
    const double want_x = 1e-2 * exp(-t_end / tau);
    print_message("in-run forward accelerometer bias: variance %.4g (steady %.4g), forward "
                  "velocity variance %.4g (want %.4g), across %.3g, up share %.4f, covariance "
                  "%.4g (want %.4g), estimate %.4g (want %.4g)\n",
                  var_af, sigma * sigma, var_u, want_v, trace_v - var_u, u[2] * u[2], cov_u,
                  want_c, (double)f.af_mps2, want_x);
    assert_true(u[2] > 0.08); /* the pitch reaches the height's rate */
    assert_near(var_af, sigma * sigma, 0.02 * sigma * sigma);
    assert_near(var_u, want_v, 0.02 * want_v);
    assert_near(trace_v - var_u, 0.0, 0.02 * want_v);
    assert_near(cov_u, want_c, 0.02 * want_c);
    assert_near((double)f.af_mps2, want_x, 0.02 * want_x);
}

/* The in-run states are residuals, as b_g and b_a (ekf.h: what the compensated value still
 * has): the feedback adds each to its estimate, which the application subtracts from the
 * increments (test_fusion's test_in_run_estimates_compensate_the_sensor), and clears it. */
static void test_in_run_feedback_adds_the_residual(void **state)
{
    (void)state;
    const double v[3] = {0.0, 0.0, 0.0};
    sins_t s;
    nav_at(&s, 0.0, 0.0, 0.0, v);
    const ekf_config_t c = quiet_config();
    ekf_t f;
    assert_int_equal(ekf_init(&f, &c, NAV_C(0.0)), NAV_OK);
    f.gz_rps = NAV_C(1e-4);
    f.af_mps2 = NAV_C(0.01);
    f.x[EKF_GZ] = NAV_C(2e-5);
    f.x[EKF_AF] = NAV_C(-0.003);
    assert_int_equal(ekf_feedback(&f, &s), NAV_OK);
    assert_near((double)f.gz_rps, 1.2e-4, 1e-9);
    assert_near((double)f.af_mps2, 0.007, 1e-7);
    assert_near((double)f.x[EKF_GZ], 0.0, 0.0);
    assert_near((double)f.x[EKF_AF], 0.0, 0.0);
}

/* The application's factor from the stored bias instability to the in-run state's sigma
 * (app_tuning.h, a literal so that its float32 value stays the one the outputs were made
 * with) is sqrt(150 s) / EKF_GM_ADEV_PEAK, to its six digits (relative 1e-5). */
static void test_app_gm_factor_is_the_filters(void **state)
{
    (void)state;
    const double want = sqrt(150.0) / (double)EKF_GM_ADEV_PEAK;
    assert_near((double)APP_GYRO_GM_SIGMA_PER_RW, want, 1e-5 * want);
}

/* The heading held (ekf_t.hold_heading: a zero-velocity update at standstill, a GNSS fix
 * below 10 speed sigmas): GIVEN the north velocity error correlated with the heading
 * (correlation 0.5, as a drive-off's acceleration makes it) WHEN a zero-velocity update
 * sees 0.01 m/s north THEN without the hold the heading moves (0.5 x 5 deg / 0.02 m/s x
 * 0.01 m/s ~ 0.6 deg: the drive-off jump), with it the heading, its variance and its
 * covariances' other side stay exactly, the velocity is still corrected, and P stays
 * symmetric. */
static void test_hold_heading(void **state)
{
    (void)state;
    const double v[3] = {0.0, 0.01, 0.0};
    double sd[EKF_N];
    for (int i = 0; i < EKF_N; i++) {
        sd[i] = 1e-6;
    }
    sd[EKF_DV] = sd[EKF_DV + 1] = sd[EKF_DV + 2] = 0.02;
    sd[EKF_PSI + 2] = 5.0 * DEG;
    for (int hold = 0; hold < 2; hold++) {
        sins_t s;
        nav_at(&s, 0.0, 0.0, 0.0, v);
        ekf_t f;
        filter_with(&f, sd);
        const nav_real_t c = (nav_real_t)(0.5 * 0.02 * 5.0 * DEG);
        f.P[EKF_DV + 1][EKF_PSI + 2] = f.P[EKF_PSI + 2][EKF_DV + 1] = c;
        const nav_real_t p_psi = f.P[EKF_PSI + 2][EKF_PSI + 2];
        f.hold_heading = (uint8_t)hold;
        assert_int_equal(ekf_zero_velocity(&f, &s, NAV_C(0.012), NAV_C(0.0)), 3);
        if (hold) {
            assert_near(f.x[EKF_PSI + 2], 0.0, 0.0);
            assert_near(f.P[EKF_PSI + 2][EKF_PSI + 2], p_psi, 0.0);
        } else {
            assert_true(fabs((double)f.x[EKF_PSI + 2]) > 0.3 * DEG);
        }
        assert_true(f.x[EKF_DV + 1] > NAV_C(0.005)); /* the velocity error seen */
        for (int i = 0; i < EKF_N; i++) {
            for (int j = 0; j < EKF_N; j++) {
                assert_near(f.P[i][j], f.P[j][i], 0.0);
            }
        }
    }
}

/* Extra process noise (ekf_add_increment_noise, for bridged IMU samples): GIVEN two
 * filters alike, one given qa rad^2 and qv (m/s)^2 in two calls before a prediction,
 * WHEN both predict THEN the one's P differs from the other's by exactly qa on the three
 * attitude variances and qv on the three velocity variances, nowhere else; AND WHEN both
 * predict again from the same P, the one with no noise pending THEN their P are equal
 * (the noise was spent). */
static void test_increment_noise_once(void **state)
{
    (void)state;
    const double v[3] = {3.0, 4.0, 0.0};
    sins_t s;
    nav_at(&s, 0.02, -0.01, 0.5, v);
    const nav_real_t fn[3] = {NAV_C(0.3), NAV_C(-0.2), NAV_C(9.8)};
    const ekf_config_t c = ekf_default_config();
    ekf_t a, b;
    assert_int_equal(ekf_init(&a, &c, NAV_C(0.0)), NAV_OK);
    assert_int_equal(ekf_init(&b, &c, NAV_C(0.0)), NAV_OK);
    /* large against the entries' float32 rounding (the heading's variance is 7.6e-3 rad^2:
     * the tolerance below is 0.1 % of qa) */
    const double qa = 1e-5, qv = 1e-3;
    ekf_add_increment_noise(&b, (nav_real_t)(0.25 * qa), (nav_real_t)(0.25 * qv));
    ekf_add_increment_noise(&b, (nav_real_t)(0.75 * qa), (nav_real_t)(0.75 * qv));
    ekf_predict(&a, &s, fn, NAV_C(0.01), NAV_C(0.1));
    ekf_predict(&b, &s, fn, NAV_C(0.01), NAV_C(0.1));
    for (int i = 0; i < EKF_N; i++) {
        for (int j = 0; j < EKF_N; j++) {
            double want = 0.0;
            if (i == j && i >= EKF_PSI && i < EKF_PSI + 3) {
                want = qa;
            } else if (i == j && i >= EKF_DV && i < EKF_DV + 3) {
                want = qv;
            }
            const double got = (double)b.P[i][j] - (double)a.P[i][j];
            /* float32 sums: a few ulps of the entry */
            assert_near(got, want, 1e-6 * fabs((double)a.P[i][j]) + 1e-4 * want + 1e-30);
        }
    }
    /* a has nothing pending: b must have nothing left either */
    memcpy(a.P, b.P, sizeof a.P);
    ekf_predict(&a, &s, fn, NAV_C(0.01), NAV_C(0.1));
    ekf_predict(&b, &s, fn, NAV_C(0.01), NAV_C(0.1));
    for (int i = 0; i < EKF_N; i++) {
        for (int j = 0; j < EKF_N; j++) {
            assert_near(b.P[i][j], a.P[i][j], 0.0);
        }
    }
}

/* Covariance health: a NaN is reset and counted; a negative variance is floored. */
static void test_covariance_health(void **state)
{
    (void)state;
    ekf_t f;
    const ekf_config_t c = ekf_default_config();
    assert_int_equal(ekf_init(&f, &c, NAV_C(0.0)), NAV_OK);
    f.P[3][3] = NAV_C(-1.0);
    assert_true(ekf_health(&f) >= 1u);
    assert_true(f.P[3][3] >= c.var_floor);
    f.P[2][5] = (nav_real_t)NAN;
    assert_true(ekf_health(&f) >= 1u);
    assert_near(f.P[0][0], (double)(c.pos_m * c.pos_m), 1e-6);
    const nav_real_t h[EKF_N] = {0};
    assert_int_equal(ekf_update(&f, h, (nav_real_t)NAN, NAV_C(1.0), NAV_C(0.0)), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_propagation_matches_sins),
        cmocka_unit_test(test_gnss_position_update),
        cmocka_unit_test(test_lever_arm_observes_heading),
        cmocka_unit_test(test_gnss_correlated_error_state),
        cmocka_unit_test(test_state_ok_sees_the_estimates),
        cmocka_unit_test(test_increment_noise_once),
        cmocka_unit_test(test_recent_correlated_sigma),
        cmocka_unit_test(test_recent_correlated_vertical_sigma),
        cmocka_unit_test(test_odometer_scale_and_mounting),
        cmocka_unit_test(test_odometer_lever_arm_in_a_turn),
        cmocka_unit_test(test_standstill_updates),
        cmocka_unit_test(test_gyro_in_run_bias_is_gauss_markov),
        cmocka_unit_test(test_accel_in_run_bias_is_gauss_markov),
        cmocka_unit_test(test_in_run_feedback_adds_the_residual),
        cmocka_unit_test(test_app_gm_factor_is_the_filters),
        cmocka_unit_test(test_hold_heading),
        cmocka_unit_test(test_covariance_health),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
