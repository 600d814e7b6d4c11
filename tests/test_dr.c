/*
 * test_dr.c - odometer, dead reckoning and one-point calibration (seed 000 eqs 1-4, 7-12).
 * Built for both numeric variants.
 *
 * Hand-computed case: a true displacement t = (3000, 4000) m (east, north; |t| = 5 km)
 * with mu = 0.01 and dH = 0.002 rad gives, by eqs 5-6, dE = mu t_E + t_N dH = 30 + 8 = 38 m
 * and dN = mu t_N - t_E dH = 40 - 6 = 34 m; eqs 9-10 must return exactly (0.002, 0.01).
 *
 * Drive tests: a polyline of legs (heading, length) is dead-reckoned twice through
 * dr_step: once true, once with an odometer reading (1 + mu) x the distance and a heading
 * offset by dH (seed 000's error model). Calibrating at the end of the erroneous run must
 * find (dH, mu); the same drive rotated by any angle, or mirrored east-west, must give the
 * same estimates (they may not depend on where north is). Float32 tolerance: positions are
 * fixed point; the local metres of eqs 7-8 are float32 (ulp 0.5 mm at 5 km, i.e. 1e-7
 * relative), and a few hundred steps of sin/cos rounding add a random walk of order
 * sqrt(n) x 1e-7 x step: 2e-5 rad and 2e-5 in mu bound both with a margin of ten. The
 * flat local frame of eqs 7-8 adds order (D/R)^2 = 1.6e-6 at 8 km in both variants.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "dr.h"
#include "dr_acc.h"
#include "odo.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

#if defined(NAV_REAL_DOUBLE)
/* the flat local frame of eqs 7-8 (dr_local_m) differs from the curvilinear integration
 * by order (D/R)^2 = (8 km / 6371 km)^2 = 1.6e-6 */
#define TOL_EST 2e-6
#define TOL_POS_M 0.02
#else
#define TOL_EST 2e-5
#define TOL_POS_M 0.05
#endif

/* second-order terms dropped by eqs 9-10 for |dH| ~ 3e-3 rad, |mu| ~ 1e-2: mu dH + dH^2 */
#define TOL_LINEAR 6e-5

static geo_pos_t start_pos(void)
{
    const geo_pos_t p = {450000000LL * GEO_LSB_PER_DEG_E7, 100000000LL * GEO_LSB_PER_DEG_E7,
                         100000LL * GEO_LSB_PER_MM}; /* 45 N, 10 E, 100 m */
    return p;
}

/* ---------------------------------------------------------------- eqs 9-10 ---- */

static void test_linear_hand_case(void **state)
{
    (void)state;
    nav_real_t dh, mu;
    assert_int_equal(onepoint_linear(NAV_C(3000.0), NAV_C(4000.0), NAV_C(38.0), NAV_C(34.0),
                                     &dh, &mu), NAV_OK);
    assert_near(dh, 0.002, 1e-7);
    assert_near(mu, 0.01, 1e-7);
    assert_int_equal(onepoint_linear(NAV_C(0.0), NAV_C(0.0), NAV_C(1.0), NAV_C(1.0), &dh, &mu),
                     NAV_EINVAL);
}

/* d = (1 + mu) R(dH) t, R turning a bearing clockwise by dH */
static void make_d(double te, double tn, double dh, double mu, nav_real_t *de, nav_real_t *dn)
{
    *de = (nav_real_t)((1.0 + mu) * (te * cos(dh) + tn * sin(dh)));
    *dn = (nav_real_t)((1.0 + mu) * (-te * sin(dh) + tn * cos(dh)));
}

static void test_exact_every_bearing(void **state)
{
    (void)state;
    const double dh_true = -0.177 * DEG, mu_true = 0.012;
    for (int b = 0; b < 360; b += 15) {
        const double te = 5000.0 * sin(b * DEG), tn = 5000.0 * cos(b * DEG);
        nav_real_t de, dn, dh, mu, dhl, mul;
        make_d(te, tn, dh_true, mu_true, &de, &dn);
        assert_int_equal(onepoint_exact(de, dn, (nav_real_t)te, (nav_real_t)tn, &dh, &mu),
                         NAV_OK);
        assert_near(dh, dh_true, 1e-6);
        assert_near(mu, mu_true, 1e-6);
        /* eqs 9-10 agree to second order */
        assert_int_equal(onepoint_linear((nav_real_t)te, (nav_real_t)tn,
                                         de - (nav_real_t)te, dn - (nav_real_t)tn, &dhl, &mul),
                         NAV_OK);
        assert_near(dhl, dh_true, TOL_LINEAR);
        assert_near(mul, mu_true, TOL_LINEAR);
    }
    nav_real_t dh, mu;
    assert_int_equal(onepoint_exact(NAV_C(0.0), NAV_C(0.0), NAV_C(1.0), NAV_C(0.0), &dh, &mu),
                     NAV_EINVAL);
}

/* ------------------------------------------------------------ drive tests ---- */

typedef struct {
    double heading_deg, length_m;
} leg_t;

static const leg_t DRIVE[] = {{30, 800}, {120, 600}, {75, 1500}, {10, 900}, {350, 700},
                              {60, 1200}, {95, 500}, {170, 300}, {80, 1000}};
#define N_LEGS (sizeof DRIVE / sizeof DRIVE[0])
#define STEP_M 10.0

/* Drive the legs (heading rotated by rot and optionally mirrored) through two dead
 * reckoners, the second with the seed-000 errors; returns both. */
static void drive(dr_t *truth, dr_t *dr, double rot_deg, int mirror, double dh, double mu,
                  int n_legs)
{
    for (int i = 0; i < n_legs; i++) {
        double hd = DRIVE[i].heading_deg;
        hd = (mirror ? -hd : hd) + rot_deg;
        const int n = (int)(DRIVE[i].length_m / STEP_M);
        for (int k = 0; k < n; k++) {
            assert_int_equal(dr_step(truth, (nav_real_t)STEP_M, (nav_real_t)(hd * DEG),
                                     NAV_C(0.0)), NAV_OK);
            assert_int_equal(dr_step(dr, (nav_real_t)(STEP_M * (1.0 + mu)),
                                     (nav_real_t)(hd * DEG + dh), NAV_C(0.0)), NAV_OK);
        }
    }
}

static void calibrated_drive(double rot_deg, int mirror, nav_real_t *dh, nav_real_t *mu)
{
    const geo_pos_t p0 = start_pos();
    dr_t truth, dr;
    assert_int_equal(dr_init(&truth, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    assert_int_equal(dr_init(&dr, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    drive(&truth, &dr, rot_deg, mirror, -0.177 * DEG, 0.012, (int)N_LEGS);
    dr_cal_t cal;
    assert_int_equal(dr_calibrate(&dr, &truth.pos, NAV_C(2000.0), &cal), NAV_OK);
    *dh = dr.dh_rad;
    *mu = dr.mu;
    /* reset to the true point (eqs 7-12: "the position error is reset") */
    assert_true(dr.pos.lat == truth.pos.lat && dr.pos.lon == truth.pos.lon);
}

static void test_calibration_finds_the_errors(void **state)
{
    (void)state;
    nav_real_t dh, mu;
    calibrated_drive(0.0, 0, &dh, &mu);
    assert_near(dh, -0.177 * DEG, TOL_EST);
    assert_near(mu, 0.012, TOL_EST);
}

static void test_rotated_and_mirrored(void **state)
{
    (void)state;
    nav_real_t dh0, mu0;
    calibrated_drive(0.0, 0, &dh0, &mu0);
    for (int rot = 30; rot < 360; rot += 47) {
        for (int mirror = 0; mirror < 2; mirror++) {
            nav_real_t dh, mu;
            calibrated_drive((double)rot, mirror, &dh, &mu);
            assert_near(dh, dh0, TOL_EST);
            assert_near(mu, mu0, TOL_EST);
        }
    }
    nav_real_t dh, mu;
    calibrated_drive(0.0, 1, &dh, &mu);
    assert_near(dh, dh0, TOL_EST);
}

/* After a calibration the compensated increments (eqs 11-12) follow the truth. */
static void test_compensation_after_calibration(void **state)
{
    (void)state;
    const double dh_t = 0.5 * DEG, mu_t = -0.03;
    const geo_pos_t p0 = start_pos();
    dr_t truth, dr;
    assert_int_equal(dr_init(&truth, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    assert_int_equal(dr_init(&dr, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    drive(&truth, &dr, 0.0, 0, dh_t, mu_t, (int)N_LEGS);
    assert_int_equal(dr_calibrate(&dr, &truth.pos, NAV_C(2000.0), NULL), NAV_OK);
    drive(&truth, &dr, 200.0, 0, dh_t, mu_t, (int)N_LEGS); /* 7.5 km more */
    nav_real_t e, n;
    dr_local_m(&truth.pos, &dr.pos, &e, &n);
    assert_near(e, 0.0, TOL_POS_M);
    assert_near(n, 0.0, TOL_POS_M);
    /* uncompensated, the same errors leave ~0.5 deg x 7.5 km + 3 % x 7.5 km: >100 m */
}

/* A second calibration composes with the first: a heading error that changed between
 * them is found as a residual, and the totals are the current errors. */
static void test_recalibration(void **state)
{
    (void)state;
    const geo_pos_t p0 = start_pos();
    dr_t truth, dr;
    assert_int_equal(dr_init(&truth, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    assert_int_equal(dr_init(&dr, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    drive(&truth, &dr, 0.0, 0, 0.2 * DEG, 0.012, (int)N_LEGS);
    dr_cal_t c1, c2;
    assert_int_equal(dr_calibrate(&dr, &truth.pos, NAV_C(2000.0), &c1), NAV_OK);
    drive(&truth, &dr, 90.0, 0, 0.3 * DEG, 0.015, (int)N_LEGS);
    assert_int_equal(dr_calibrate(&dr, &truth.pos, NAV_C(2000.0), &c2), NAV_OK);
    assert_near(c2.dh_rad, 0.1 * DEG, TOL_EST);
    assert_near(c2.mu, 1.015 / 1.012 - 1.0, TOL_EST);
    assert_near(dr.dh_rad, 0.3 * DEG, TOL_EST);
    assert_near(dr.mu, 0.015, TOL_EST);
}

/* Degenerate points: too close to the base, back at the base (a loop), no motion. */
static void test_degenerate_points(void **state)
{
    (void)state;
    const geo_pos_t p0 = start_pos();
    dr_t truth, dr;
    assert_int_equal(dr_init(&truth, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    assert_int_equal(dr_init(&dr, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    /* no motion at all: t = 0 */
    assert_int_equal(dr_calibrate(&dr, &p0, NAV_C(0.0), NULL), NAV_EINVAL);
    drive(&truth, &dr, 0.0, 0, 0.01, 0.01, 1); /* 800 m */
    const dr_t before = dr;
    assert_int_equal(dr_calibrate(&dr, &truth.pos, NAV_C(2000.0), NULL), NAV_ERANGE);
    assert_true(dr.pos.lat == before.pos.lat && dr.pos.lon == before.pos.lon);
    assert_near(dr.dh_rad, 0.0, 0.0);
    /* a closed loop: 4 legs back to the start, 2 km driven, base distance ~0 */
    dr_t t2, d2;
    assert_int_equal(dr_init(&t2, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    assert_int_equal(dr_init(&d2, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    for (int leg = 0; leg < 4; leg++) {
        for (int k = 0; k < 50; k++) {
            assert_int_equal(dr_step(&t2, NAV_C(10.0), (nav_real_t)(leg * 90 * DEG), NAV_C(0.0)),
                             NAV_OK);
            assert_int_equal(dr_step(&d2, NAV_C(10.1), (nav_real_t)(leg * 90 * DEG + 0.01),
                                     NAV_C(0.0)), NAV_OK);
        }
    }
    assert_int_equal(dr_calibrate(&d2, &t2.pos, NAV_C(2000.0), NULL), NAV_ERANGE);
    /* bad inputs */
    assert_int_equal(dr_step(&d2, (nav_real_t)NAN, NAV_C(0.0), NAV_C(0.0)), NAV_EINVAL);
    assert_int_equal(dr_step(&d2, NAV_C(500.0), NAV_C(0.0), NAV_C(0.0)), NAV_EINVAL);
    assert_int_equal(dr_init(&d2, &p0, NAV_C(1.0), NAV_C(0.0)), NAV_EINVAL);
}

/* On a 5 % slope the horizontal distance is ds cos(p) and the climb ds sin(p). */
static void test_slope(void **state)
{
    (void)state;
    const geo_pos_t p0 = start_pos();
    dr_t dr;
    assert_int_equal(dr_init(&dr, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    const double p = atan(0.05);
    for (int k = 0; k < 100; k++) {
        assert_int_equal(dr_step(&dr, NAV_C(10.0), NAV_C(0.0), (nav_real_t)p), NAV_OK);
    }
    nav_real_t e, n;
    dr_local_m(&p0, &dr.pos, &e, &n);
    assert_near(n, 1000.0 * cos(p), 100 * TOL_POS_M);
    assert_near(e, 0.0, TOL_POS_M);
    assert_near((double)(dr.pos.h - p0.h) / (double)GEO_LSB_PER_MM / 1000.0, 1000.0 * sin(p),
                100 * TOL_POS_M);
}

/* ------------------------------------------------------------- odometer ---- */

static void test_odo_axles(void **state)
{
    (void)state;
    odo_t o;
    odo_config_t c = odo_default_config();
    assert_int_equal(odo_init(&o, &c), NAV_OK);
    /* a left turn at 10 m/s, yaw rate 0.2 rad/s: rear wheels 10 -+ 0.2 x 0.8 */
    const nav_real_t r = NAV_C(0.2);
    const nav_real_t rear_l = NAV_C(10.0) - r * NAV_C(0.8), rear_r = NAV_C(10.0) + r * NAV_C(0.8);
    const nav_real_t lat = r * NAV_C(2.7);
    const nav_real_t fl = nav_sqrt(rear_l * rear_l + lat * lat);
    const nav_real_t fr = nav_sqrt(rear_r * rear_r + lat * lat);
    const nav_real_t w[4] = {fl, fr, rear_l, rear_r};
    assert_int_equal(odo_wheels(&o, w, r), NAV_OK);
    assert_near(o.speed_mps, 10.0, 1e-5);
    c.axle = ODO_AXLE_FRONT;
    assert_int_equal(odo_init(&o, &c), NAV_OK);
    assert_int_equal(odo_wheels(&o, w, r), NAV_OK);
    /* the front mean is 10.0146; the steering correction brings it to within the
     * second-order difference of the two wheels' circles (< 1 mm/s here) */
    assert_near(o.speed_mps, 10.0, 2e-3);
    /* reverse */
    const nav_real_t back[4] = {NAV_C(-2.0), NAV_C(-2.0), NAV_C(-2.0), NAV_C(-2.0)};
    assert_int_equal(odo_wheels(&o, back, NAV_C(0.0)), NAV_OK);
    assert_near(o.speed_mps, -2.0, 1e-5);
}

static void test_odo_refusals_and_timeout(void **state)
{
    (void)state;
    odo_t o;
    const odo_config_t c = odo_default_config();
    assert_int_equal(odo_init(&o, &c), NAV_OK);
    const nav_real_t ok[4] = {NAV_C(5.0), NAV_C(5.0), NAV_C(5.0), NAV_C(5.0)};
    assert_int_equal(odo_wheels(&o, ok, NAV_C(0.0)), NAV_OK);
    const nav_real_t locked[4] = {NAV_C(5.0), NAV_C(5.0), NAV_C(0.0), NAV_C(5.0)};
    assert_int_equal(odo_wheels(&o, locked, NAV_C(0.0)), NAV_EINVAL);
    const nav_real_t nan_w[4] = {NAV_C(5.0), (nav_real_t)NAN, NAV_C(5.0), NAV_C(5.0)};
    assert_int_equal(odo_wheels(&o, nan_w, NAV_C(0.0)), NAV_EINVAL);
    assert_int_equal(o.n_frames, 1u); /* the refused ones not taken */
    assert_near(o.speed_mps, 5.0, 0.0); /* the last good speed stands */
    for (int k = 0; k < 149; k++) {
        odo_tick(&o, NAV_C(0.01), NAV_C(0.0));
    }
    assert_true(o.valid);
    odo_tick(&o, NAV_C(0.02), NAV_C(0.0));
    assert_false(o.valid); /* older than 1.5 s */
}

/* an odometer of the default configuration whose one frame read every wheel at zero, then
 * n ticks of 10 ms without a turn */
static void odo_zero_for(odo_t *o, int n)
{
    const odo_config_t c = odo_default_config();
    assert_int_equal(odo_init(o, &c), NAV_OK);
    const nav_real_t zero[4] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    assert_int_equal(odo_wheels(o, zero, NAV_C(0.0)), NAV_OK);
    for (int k = 0; k < n; k++) {
        odo_tick(o, NAV_C(0.01), NAV_C(0.0));
    }
}

static void test_odo_standstill(void **state)
{
    (void)state;
    odo_t o;
    odo_zero_for(&o, 49);
    assert_false(o.standing);
    odo_tick(&o, NAV_C(0.01), NAV_C(0.0));
    odo_tick(&o, NAV_C(0.01), NAV_C(0.0));
    assert_true(o.standing); /* 0.5 s of zero speed, to one sample (float32 sum of 0.01) */
    odo_tick(&o, NAV_C(0.01), NAV_C(0.05)); /* the body turns: not standing */
    assert_false(o.standing);
    const nav_real_t creep[4] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.02), NAV_C(0.0)};
    assert_int_equal(odo_wheels(&o, creep, NAV_C(0.0)), NAV_OK);
    for (int k = 0; k < 100; k++) {
        odo_tick(&o, NAV_C(0.01), NAV_C(0.0));
    }
    assert_false(o.standing); /* one wheel moves: not standing */
}

/* odo_age (outside navigation): the timeout as odo_tick's, and with the reading the
 * standstill it had (a car whose wheels stop reporting is not known to stand: a review
 * found a stale standstill keeping the DTCs tested only while moving untested). */
static void test_odo_age_ends_the_standstill_with_the_reading(void **state)
{
    (void)state;
    odo_t o;
    odo_zero_for(&o, 60);
    assert_true(o.standing);
    for (int k = 0; k < 89; k++) {
        odo_age(&o, NAV_C(0.01));
    }
    assert_true(o.valid); /* 1.49 s old */
    assert_true(o.standing);
    odo_age(&o, NAV_C(0.02));
    assert_false(o.valid); /* older than 1.5 s */
    assert_false(o.standing);
    assert_near(o.still_for_s, 0.0, 0.0);
}

/* ------------------------------------------------ the dead reckoning's accuracy ----
 * dr_acc.h propagates a covariance of linear errors. With a single error source of size
 * x given as its sigma (the others 0), the covariance is rank one, J x^2 J', and its
 * sqrt(P_EE + P_NN) is |J x|: the position error that source makes. So each source, put
 * into a real dead reckoning (dr_step) over DRIVE, must leave an error of that size: the
 * check of the model's signs and couplings against the navigator itself. Errors small
 * (second-order terms x^2 D below 1 cm); the steps are 10 m at 10 m/s (1 s).
 */
enum { SRC_MU, SRC_PSI, SRC_BIAS, SRC_SCALE };

static double leg_heading_rad(int i)
{
    return DRIVE[i].heading_deg * DEG;
}

static double acc_vs_drive(int src, double x, double *err_m, double *pen_err, double *pen_acc)
{
    const geo_pos_t p0 = start_pos();
    dr_t truth, dr;
    assert_int_equal(dr_init(&truth, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    assert_int_equal(dr_init(&dr, &p0, NAV_C(0.0), NAV_C(0.0)), NAV_OK);
    dr_acc_t a;
    const nav_real_t xs = (nav_real_t)x, z = NAV_C(0.0);
    dr_acc_start(&a, z, src == SRC_MU ? xs : z, src == SRC_PSI ? xs : z,
                 src == SRC_BIAS ? xs : z, src == SRC_SCALE ? xs : z);
    const double dt = 1.0;
    double t = 0.0, turned = 0.0;
    for (int i = 0; i < (int)N_LEGS; i++) {
        const int n = (int)(DRIVE[i].length_m / STEP_M);
        for (int k = 0; k < n; k++) {
            const double hd = leg_heading_rad(i);
            double err_h = 0.0; /* the heading error of this step, by source */
            if (src == SRC_PSI) {
                err_h = x;
            } else if (src == SRC_BIAS) {
                err_h = x * t;
            } else if (src == SRC_SCALE) {
                err_h = x * turned;
            }
            const double ds = STEP_M * (src == SRC_MU ? 1.0 + x : 1.0);
            assert_int_equal(dr_step(&truth, (nav_real_t)STEP_M, (nav_real_t)hd, z), NAV_OK);
            assert_int_equal(dr_step(&dr, (nav_real_t)ds, (nav_real_t)(hd + err_h), z), NAV_OK);
            /* the turn to the next step's heading, made after this step's move */
            double next = hd;
            if (k == n - 1 && i + 1 < (int)N_LEGS) {
                next = leg_heading_rad(i + 1);
            }
            double dth = next - hd;
            dth -= 2.0 * PI * floor(dth / (2.0 * PI) + 0.5);
            dr_acc_move(&a, dr.step_e_m, dr.step_n_m, (nav_real_t)dth, (nav_real_t)dt, z, z);
            t += dt;
            turned += dth;
        }
    }
    nav_real_t e, nn;
    dr_local_m(&truth.pos, &dr.pos, &e, &nn);
    *err_m = sqrt((double)e * (double)e + (double)nn * (double)nn);
    *pen_err = (double)e * (double)nn;
    *pen_acc = (double)a.P[DR_ACC_E][DR_ACC_N];
    return (double)dr_acc_sigma_h_m(&a);
}

/* GIVEN one error at a time in the dead reckoning over DRIVE's 7.5 km: scale 1e-3,
 * heading 1e-3 rad, z gyro bias 1e-6 rad/s (0.2 deg/h; 0.043 deg over its 750 s),
 * z gyro scale factor 1e-3 THEN the accuracy of that source alone is the error it made,
 * to 1 % (second-order terms and the flat local frame), and P_EN its east times its north
 * error */
static void test_acc_single_errors_are_the_drive_error(void **state)
{
    (void)state;
    const int srcs[] = {SRC_MU, SRC_PSI, SRC_BIAS, SRC_SCALE};
    const double xs[] = {1e-3, 1e-3, 1e-6, 1e-3};
    for (int i = 0; i < 4; i++) {
        double err, pen_err, pen_acc;
        const double sig = acc_vs_drive(srcs[i], xs[i], &err, &pen_err, &pen_acc);
        assert_true(err > 0.5); /* a real error: metres */
        assert_near(sig, err, 0.01 * err);
        /* and its direction: the east-north covariance is the product of the two errors
         * (a sign wrong in eqs 5-6 turns it) */
        assert_near(pen_acc, pen_err, 0.02 * err * err);
    }
}

/* dr_acc_move's in-place row and column operations are F P F' for F = I + G (dr_acc.h's
 * G: eqs 5-6 and the heading's drift), on a full covariance with every entry set: against
 * the product written out in double, to float32's rounding */
static void test_acc_move_is_f_p_ft(void **state)
{
    (void)state;
    dr_acc_t a;
    dr_acc_start(&a, NAV_C(1.0), NAV_C(0.0), NAV_C(0.0), NAV_C(0.0), NAV_C(0.0));
    double P[DR_ACC_NX][DR_ACC_NX];
    for (int i = 0; i < DR_ACC_NX; i++) { /* A A' + I: symmetric, positive, all entries */
        for (int j = 0; j < DR_ACC_NX; j++) {
            double sum = i == j ? 1.0 : 0.0;
            for (int k = 0; k < DR_ACC_NX; k++) {
                sum += sin(1.0 + i * 7.0 + k) * sin(1.0 + j * 7.0 + k);
            }
            P[i][j] = sum;
            a.P[i][j] = (nav_real_t)sum;
        }
    }
    const double de = 0.7, dn = -1.3, dth = 0.05, dt = 0.1;
    double G[DR_ACC_NX][DR_ACC_NX] = {{0.0}};
    G[DR_ACC_E][DR_ACC_MU] = de;
    G[DR_ACC_E][DR_ACC_PSI] = dn;
    G[DR_ACC_N][DR_ACC_MU] = dn;
    G[DR_ACC_N][DR_ACC_PSI] = -de;
    G[DR_ACC_PSI][DR_ACC_B] = dt;
    G[DR_ACC_PSI][DR_ACC_S] = dth;
    double F[DR_ACC_NX][DR_ACC_NX], FP[DR_ACC_NX][DR_ACC_NX];
    for (int i = 0; i < DR_ACC_NX; i++) {
        for (int j = 0; j < DR_ACC_NX; j++) {
            F[i][j] = (i == j ? 1.0 : 0.0) + G[i][j];
        }
    }
    for (int i = 0; i < DR_ACC_NX; i++) {
        for (int j = 0; j < DR_ACC_NX; j++) {
            FP[i][j] = 0.0;
            for (int k = 0; k < DR_ACC_NX; k++) {
                FP[i][j] += F[i][k] * P[k][j];
            }
        }
    }
    dr_acc_move(&a, (nav_real_t)de, (nav_real_t)dn, (nav_real_t)dth, (nav_real_t)dt, NAV_C(0.0),
                NAV_C(0.0));
    for (int i = 0; i < DR_ACC_NX; i++) {
        for (int j = 0; j < DR_ACC_NX; j++) {
            double want = 0.0;
            for (int k = 0; k < DR_ACC_NX; k++) {
                want += FP[i][k] * F[j][k];
            }
            assert_near(a.P[i][j], want, 1e-5 * (1.0 + fabs(want)));
        }
    }
}

/* The standstill's bias estimate (gain K, sample variance R) and a calibration reset what
 * dr_acc.h says: b's error (1 - K) e_b - K noise; the point's sigma and the calibration's
 * geometry with the leg's drift; a non-finite step ends the model, and a calibration then
 * leaves it unknown. */
static void test_acc_hold_and_calibration(void **state)
{
    (void)state;
    dr_acc_t a;
    dr_acc_start(&a, NAV_C(2.0), NAV_C(0.01), NAV_C(0.05), NAV_C(1e-4), NAV_C(0.0));
    assert_near(dr_acc_sigma_h_m(&a), sqrt(8.0), 1e-5);
    /* 100 s east at 10 m/s: the bias turns the heading, the heading moves the position */
    for (int k = 0; k < 100; k++) {
        dr_acc_move(&a, NAV_C(10.0), NAV_C(0.0), NAV_C(0.0), NAV_C(1.0), NAV_C(0.0), NAV_C(0.0));
    }
    const double pbb = 1e-8, pnb = (double)a.P[DR_ACC_N][DR_ACC_B];
    assert_true(pnb < 0.0); /* north error -psi dE, psi grown by +b: negative */
    const double K = 0.25, R = 4e-8, q = 1e-12;
    dr_acc_hold(&a, NAV_C(1.0), (nav_real_t)sqrt(q), (nav_real_t)K, (nav_real_t)R);
    assert_near(a.P[DR_ACC_B][DR_ACC_B], (1 - K) * (1 - K) * pbb + K * K * R + q, 1e-14);
    assert_near(a.P[DR_ACC_N][DR_ACC_B], (1 - K) * pnb, 1e-6 * fabs(pnb));
    assert_near(a.P[DR_ACC_B][DR_ACC_N], a.P[DR_ACC_N][DR_ACC_B], 0.0);
    /* the heading's drift over the leg: its variance less the start's 0.05^2 */
    const double drift = (double)a.P[DR_ACC_PSI][DR_ACC_PSI] - 0.0025;
    assert_true(drift > 1e-5);
    const double var_b = (double)a.P[DR_ACC_B][DR_ACC_B];
    dr_acc_calibrated(&a, NAV_C(3.0), NAV_C(600.0), NAV_C(800.0)); /* |t| 1000 m */
    assert_near(a.P[DR_ACC_E][DR_ACC_E], 9.0, 1e-5);
    assert_near(a.P[DR_ACC_N][DR_ACC_N], 9.0, 1e-5);
    const double geo = (9.0 + 4.0) / 1e6; /* (point^2 + base^2) / base length^2 */
    assert_near(a.P[DR_ACC_MU][DR_ACC_MU], geo, 1e-6 * geo);
    assert_near(a.P[DR_ACC_PSI][DR_ACC_PSI], geo + drift, 1e-4 * (geo + drift));
    /* the point's error in both estimates: 9 t / |t|^2 */
    assert_near(a.P[DR_ACC_E][DR_ACC_MU], 9.0 * 600.0 / 1e6, 1e-9);
    assert_near(a.P[DR_ACC_N][DR_ACC_PSI], -9.0 * 600.0 / 1e6, 1e-9);
    assert_near(a.P[DR_ACC_E][DR_ACC_PSI], 9.0 * 800.0 / 1e6, 1e-9);
    assert_near(a.P[DR_ACC_B][DR_ACC_B], var_b, 0.0);
    assert_near(a.P[DR_ACC_N][DR_ACC_B], 0.0, 0.0);
    assert_near(a.base_var_m2, 9.0, 1e-5);
    /* the next calibration's geometry uses this point's 3 m as its base's */
    dr_acc_calibrated(&a, NAV_C(1.0), NAV_C(0.0), NAV_C(1000.0));
    assert_near(a.P[DR_ACC_MU][DR_ACC_MU], (1.0 + 9.0) / 1e6, 1e-11);
    dr_acc_move(&a, NAV_C(NAN), NAV_C(0.0), NAV_C(0.0), NAV_C(1.0), NAV_C(0.0), NAV_C(0.0));
    assert_int_equal(a.valid, 0);
    assert_near(dr_acc_sigma_h_m(&a), -1.0, 0.0);
    dr_acc_calibrated(&a, NAV_C(1.0), NAV_C(0.0), NAV_C(1000.0));
    assert_int_equal(a.valid, 0); /* its leg was not the model's */
    assert_near(dr_acc_sigma_h_m(&a), -1.0, 0.0);
}

/* GIVEN an exact base and a point known to 1 m per axis, 1 km east of it, nothing else
 * uncertain WHEN the car drives on 1 km east THEN each position error is twice the
 * point's: the point's error e went into the calibration too (mu's error e_E / 1000, psi's
 * -e_N / 1000), and 1 km on they add e again (variance 4 per axis, not 1 + 1 = 2) */
static void test_acc_calibration_error_carries_on(void **state)
{
    (void)state;
    dr_acc_t a;
    dr_acc_start(&a, NAV_C(0.0), NAV_C(0.0), NAV_C(0.0), NAV_C(0.0), NAV_C(0.0));
    dr_acc_calibrated(&a, NAV_C(1.0), NAV_C(1000.0), NAV_C(0.0));
    for (int k = 0; k < 100; k++) {
        dr_acc_move(&a, NAV_C(10.0), NAV_C(0.0), NAV_C(0.0), NAV_C(1.0), NAV_C(0.0), NAV_C(0.0));
    }
    assert_near(a.P[DR_ACC_E][DR_ACC_E], 4.0, 1e-4);
    assert_near(a.P[DR_ACC_N][DR_ACC_N], 4.0, 1e-4);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_linear_hand_case),
        cmocka_unit_test(test_exact_every_bearing),
        cmocka_unit_test(test_calibration_finds_the_errors),
        cmocka_unit_test(test_rotated_and_mirrored),
        cmocka_unit_test(test_compensation_after_calibration),
        cmocka_unit_test(test_recalibration),
        cmocka_unit_test(test_degenerate_points),
        cmocka_unit_test(test_slope),
        cmocka_unit_test(test_odo_axles),
        cmocka_unit_test(test_odo_refusals_and_timeout),
        cmocka_unit_test(test_odo_standstill),
        cmocka_unit_test(test_odo_age_ends_the_standstill_with_the_reading),
        cmocka_unit_test(test_acc_single_errors_are_the_drive_error),
        cmocka_unit_test(test_acc_move_is_f_p_ft),
        cmocka_unit_test(test_acc_hold_and_calibration),
        cmocka_unit_test(test_acc_calibration_error_carries_on),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
