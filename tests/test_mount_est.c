/*
 * test_mount_est.c - the automatic mounting estimate (firmware/app/mount_est.c) on
 * synthetic drives: the vehicle's specific force and rate of a drive (accelerations,
 * braking, turns, stops) turned into the IMU's axes by a known mounting, at 100 Hz, with
 * the exact odometer speed.
 *  - noiseless: the installs of the issue (turned 90 deg, upside down, pitched 30 deg) and
 *    a general one recovered; tolerance 0.05 deg: the model's only approximation is the
 *    window's mean speed times its mean yaw rate for the centripetal term (a 0.5-s window
 *    of a turn whose rate changes by at most 0.03 rad/s: below 1e-3 rad) and float32;
 *  - at rest: roll and pitch from gravity, yaw not observed (sigma pi, never converged);
 *  - driving straight at a constant speed: yaw not observed either;
 *  - white accelerometer noise: the error within 4 sigma on every axis, sigma falling
 *    with time (as 1/sqrt(N)), converged at 1 deg, not at 0.001 deg;
 *  - a non-finite sample or speed refused and counted, the estimate unchanged.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "mount_est.h"
#include "mounting.h"

#define DEG (3.14159265358979323846 / 180.0)
#define DT 0.01
#define NEAR(x, y, tol) assert_true(fabs((double)(x) - (double)(y)) <= (double)(tol))

typedef struct {
    mounting_t mount; /* the true mounting */
    double t, v;
    uint32_t rng;
    double noise_mps2; /* white accelerometer noise per sample, 1 sigma */
    int straight;      /* constant speed, no turns */
} drive_t;

static double uniform(drive_t *d)
{
    d->rng = d->rng * 1664525u + 1013904223u;
    return ((double)(d->rng >> 8) + 0.5) / 16777216.0;
}

static double gauss(drive_t *d)
{
    double s = 0.0;
    for (int i = 0; i < 12; i++) {
        s += uniform(d);
    }
    return s - 6.0;
}

static void drive_init(drive_t *d, double r_deg, double p_deg, double y_deg)
{
    memset(d, 0, sizeof *d);
    const nav_real_t rpy[3] = {(nav_real_t)(r_deg * DEG), (nav_real_t)(p_deg * DEG),
                               (nav_real_t)(y_deg * DEG)};
    mounting_init(&d->mount, rpy);
    d->rng = 12345u;
}

/* a 60-s cycle: 5 s standing, 10 s at +1.5 m/s^2, 35 s of turns, 10 s at -1.5 m/s^2 */
static void profile(const drive_t *d, double *a, double *w)
{
    const double c = fmod(d->t, 60.0);
    *a = 0.0;
    *w = 0.0;
    if (d->straight) {
        return;
    }
    if (c >= 5.0 && c < 15.0) {
        *a = 1.5;
    } else if (c >= 15.0 && c < 50.0) {
        *w = 0.25 * sin(2.0 * 3.14159265358979 * (c - 15.0) / 17.5);
        *a = 0.5 * sin(2.0 * 3.14159265358979 * (c - 15.0) / 7.0);
    } else if (c >= 50.0) {
        *a = -1.5;
    }
}

/* the next sample in the IMU's axes and the odometer speed after it */
static void drive_step(drive_t *d, imu_inc_t *inc, double *speed)
{
    double a, w;
    profile(d, &a, &w);
    const double v0 = d->straight ? 15.0 : d->v;
    const double v1 = d->straight ? 15.0 : (v0 + a * DT > 0.0 ? v0 + a * DT : 0.0);
    const double a_eff = (v1 - v0) / DT;
    const double vm = 0.5 * (v0 + v1);
    const double fv[3] = {-vm * w, a_eff, 9.80665};
    const double wv[3] = {0.0, 0.0, w};
    for (int i = 0; i < 3; i++) {
        double f = 0.0, r = 0.0;
        for (int k = 0; k < 3; k++) { /* C_iv = C_vi^T */
            f += (double)d->mount.C_vi.m[k][i] * fv[k];
            r += (double)d->mount.C_vi.m[k][i] * wv[k];
        }
        inc->dv_b_mps[i] = (nav_real_t)((f + d->noise_mps2 * gauss(d)) * DT);
        inc->dtheta_b_rad[i] = (nav_real_t)(r * DT);
    }
    inc->dt_s = (nav_real_t)DT;
    d->v = v1;
    d->t += DT;
    *speed = v1;
}

static void run(mount_est_t *e, drive_t *d, double seconds)
{
    const long n = lround(seconds / DT);
    for (long k = 0; k < n; k++) {
        imu_inc_t inc;
        double v;
        drive_step(d, &inc, &v);
        assert_true(mount_est_sample(e, &inc, (nav_real_t)v, 1) >= 0);
    }
    mount_est_solve(e);
}

static mount_est_t make_est(double sigma_deg, double excite)
{
    mount_est_t e;
    const mount_est_config_t cfg = {(nav_real_t)(sigma_deg * DEG), (nav_real_t)excite};
    assert_int_equal(mount_est_init(&e, &cfg), NAV_OK);
    return e;
}

/* the angle (rad) of the rotation between the estimate and the truth */
static double angle_err(const mount_est_t *e, const drive_t *d)
{
    mounting_t m;
    mounting_init(&m, e->res.rpy_rad);
    double tr = 0.0;
    for (int i = 0; i < 3; i++) {
        for (int k = 0; k < 3; k++) {
            tr += (double)m.C_vi.m[i][k] * (double)d->mount.C_vi.m[i][k];
        }
    }
    const double c = 0.5 * (tr - 1.0);
    return acos(c > 1.0 ? 1.0 : c);
}

/* the up axis' error (rad): roll and pitch together */
static double up_err(const mount_est_t *e, const drive_t *d)
{
    mounting_t m;
    mounting_init(&m, e->res.rpy_rad);
    double c = 0.0;
    for (int k = 0; k < 3; k++) {
        c += (double)m.C_vi.m[2][k] * (double)d->mount.C_vi.m[2][k];
    }
    return acos(c > 1.0 ? 1.0 : c);
}

static void check_install(double r, double p, double y)
{
    drive_t d;
    drive_init(&d, r, p, y);
    mount_est_t e = make_est(1.0, 50.0);
    run(&e, &d, 180.0);
    assert_true(e.res.valid);
    assert_true(e.res.converged);
    const double err = angle_err(&e, &d);
    if (err > 0.05 * DEG) {
        fail_msg("mount (%g, %g, %g): estimate (%g, %g, %g) deg, %g deg off", r, p, y,
                 (double)e.res.rpy_rad[0] / DEG, (double)e.res.rpy_rad[1] / DEG,
                 (double)e.res.rpy_rad[2] / DEG, err / DEG);
    }
    assert_int_equal(e.n_refused, 0);
}

static void test_installs(void **state)
{
    (void)state;
    check_install(0.0, 0.0, 0.0);
    check_install(0.0, 0.0, 90.0);
    check_install(180.0, 0.0, 0.0);
    check_install(0.0, 30.0, 0.0);
    check_install(0.0, 0.0, -90.0);
    check_install(25.0, -40.0, 135.0);
    check_install(180.0, 0.0, 180.0);
}

/* the angles come out in mounting.h's convention, as configured */
static void test_angles_as_configured(void **state)
{
    (void)state;
    drive_t d;
    drive_init(&d, 0.0, 0.0, 90.0);
    mount_est_t e = make_est(1.0, 50.0);
    run(&e, &d, 180.0);
    NEAR(e.res.rpy_rad[2], 90.0 * DEG, 0.05 * DEG);
    NEAR(e.res.rpy_rad[1], 0.0, 0.05 * DEG);
    drive_init(&d, 0.0, 30.0, 0.0);
    e = make_est(1.0, 50.0);
    run(&e, &d, 180.0);
    NEAR(e.res.rpy_rad[1], 30.0 * DEG, 0.05 * DEG);
    NEAR(e.res.rpy_rad[2], 0.0, 0.05 * DEG);
}

static void test_at_rest(void **state)
{
    (void)state;
    const double rp[2][2] = {{180.0, 0.0}, {10.0, -20.0}};
    for (int i = 0; i < 2; i++) {
        drive_t d;
        drive_init(&d, rp[i][0], rp[i][1], 0.0);
        d.t = 0.0;
        mount_est_t e = make_est(1.0, 0.0);
        /* standing only: the first 5 s of the cycle, repeated */
        for (int rep = 0; rep < 10; rep++) {
            d.t = 0.0;
            d.v = 0.0;
            run(&e, &d, 4.9);
        }
        assert_true(e.res.valid);
        assert_false(e.res.converged);
        NEAR(e.res.sigma_yaw_rad, 3.14159265358979, 1e-6);
        /* roll 180 may come out as -180: the same install */
        NEAR(remainder((double)e.res.rpy_rad[0] - rp[i][0] * DEG, 2.0 * 3.14159265358979), 0.0,
             0.01 * DEG);
        NEAR(e.res.rpy_rad[1], rp[i][1] * DEG, 0.01 * DEG);
    }
}

static void test_straight_not_observed(void **state)
{
    (void)state;
    drive_t d;
    drive_init(&d, 0.0, 0.0, 45.0);
    d.straight = 1;
    mount_est_t e = make_est(1.0, 0.0);
    run(&e, &d, 120.0);
    assert_true(e.res.valid);
    assert_false(e.res.converged);
    assert_true(up_err(&e, &d) < 0.01 * DEG);
    assert_true((double)e.res.excite_m2ps3 < 1e-6);
}

static void test_noise_sigma(void **state)
{
    (void)state;
    drive_t d;
    drive_init(&d, 180.0, 0.0, 90.0);
    d.noise_mps2 = 0.5;
    mount_est_t e = make_est(1.0, 50.0);
    run(&e, &d, 60.0);
    const double s_rp_60 = (double)e.res.sigma_rp_rad;
    const double s_y_60 = (double)e.res.sigma_yaw_rad;
    run(&e, &d, 180.0);
    const double s_rp_240 = (double)e.res.sigma_rp_rad;
    const double s_y_240 = (double)e.res.sigma_yaw_rad;
    /* four times the windows: half the sigma (within 20 %, the noise of the residuals) */
    assert_true(s_rp_240 < 0.6 * s_rp_60 && s_rp_240 > 0.4 * s_rp_60);
    assert_true(s_y_240 < 0.6 * s_y_60 && s_y_240 > 0.4 * s_y_60);
    /* the residual variance: 0.5 m/s^2 per 100-Hz sample is 0.5 / sqrt(50) per window */
    const double s_rp_expect = 0.5 / sqrt(50.0) / (9.80665 * sqrt(480.0));
    assert_true(s_rp_240 < 1.2 * s_rp_expect && s_rp_240 > 0.8 * s_rp_expect);
    assert_true(up_err(&e, &d) < 4.0 * s_rp_240 * sqrt(2.0)); /* two axes */
    const double yaw_err = fabs(remainder((double)e.res.rpy_rad[2] - 90.0 * DEG, 2.0 * 3.14159265358979));
    assert_true(yaw_err < 4.0 * s_y_240);
    assert_true(e.res.converged);
    /* a demand the data cannot meet: not converged */
    mount_est_t tight = make_est(0.001, 50.0);
    drive_init(&d, 180.0, 0.0, 90.0);
    d.noise_mps2 = 0.5;
    run(&tight, &d, 240.0);
    assert_true(tight.res.valid);
    assert_false(tight.res.converged);
}

static void test_refuses_nan(void **state)
{
    (void)state;
    drive_t d;
    drive_init(&d, 0.0, 30.0, 0.0);
    mount_est_t e = make_est(1.0, 50.0);
    run(&e, &d, 120.0);
    const mount_est_result_t before = e.res;
    const uint32_t n = e.n_windows;
    imu_inc_t inc;
    double v;
    drive_step(&d, &inc, &v);
    inc.dv_b_mps[1] = (nav_real_t)NAN;
    assert_int_equal(mount_est_sample(&e, &inc, (nav_real_t)v, 1), NAV_EINVAL);
    drive_step(&d, &inc, &v);
    inc.dtheta_b_rad[2] = (nav_real_t)INFINITY;
    assert_int_equal(mount_est_sample(&e, &inc, (nav_real_t)v, 1), NAV_EINVAL);
    drive_step(&d, &inc, &v);
    assert_int_equal(mount_est_sample(&e, &inc, (nav_real_t)NAN, 1), NAV_EINVAL);
    drive_step(&d, &inc, &v);
    inc.dt_s = (nav_real_t)0.0;
    assert_int_equal(mount_est_sample(&e, &inc, (nav_real_t)v, 1), NAV_EINVAL);
    assert_int_equal(e.n_refused, 4);
    assert_int_equal(e.n_windows, n);
    mount_est_solve(&e);
    assert_memory_equal(&e.res, &before, sizeof before);
    /* a NaN speed flagged invalid is no speed, not a refusal */
    drive_step(&d, &inc, &v);
    assert_int_equal(mount_est_sample(&e, &inc, (nav_real_t)NAN, 0), 0);
    assert_int_equal(e.n_refused, 4);
    /* a window of an impossible specific force (a crash, a stuck sensor at full scale) */
    for (int k = 0; k < 60; k++) {
        drive_step(&d, &inc, &v);
        inc.dv_b_mps[0] = (nav_real_t)(100.0 * DT);
        (void)mount_est_sample(&e, &inc, (nav_real_t)v, 1);
    }
    assert_int_equal(e.n_refused, 5);
    assert_int_equal(e.n_windows, n);
    /* configurations */
    mount_est_t bad;
    const mount_est_config_t c1 = {(nav_real_t)NAN, 1.0f};
    const mount_est_config_t c2 = {0.0f, 1.0f};
    const mount_est_config_t c3 = {0.01f, -1.0f};
    assert_int_equal(mount_est_init(&bad, &c1), NAV_EINVAL);
    assert_int_equal(mount_est_init(&bad, &c2), NAV_EINVAL);
    assert_int_equal(mount_est_init(&bad, &c3), NAV_EINVAL);
}

static void test_excitation_gate(void **state)
{
    (void)state;
    drive_t d;
    drive_init(&d, 0.0, 0.0, 90.0);
    mount_est_t e = make_est(1.0, 1e6);
    run(&e, &d, 120.0);
    assert_true(e.res.valid);
    assert_true((double)e.res.sigma_yaw_rad < 1.0 * DEG);
    assert_false(e.res.converged); /* sigma small, excitation short of the demand */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_installs),
        cmocka_unit_test(test_angles_as_configured),
        cmocka_unit_test(test_at_rest),
        cmocka_unit_test(test_straight_not_observed),
        cmocka_unit_test(test_noise_sigma),
        cmocka_unit_test(test_refuses_nan),
        cmocka_unit_test(test_excitation_gate),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
