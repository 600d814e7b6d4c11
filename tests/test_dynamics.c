/*
 * test_dynamics.c - the outputs' motion (firmware/app/dynamics.c): rates and accelerations
 * from the IMU increments of an output interval, against motions whose answer is known in
 * closed form: a car at rest (the gyro reads the Earth's rotation, the accelerometer the
 * normal gravity: no acceleration, no attitude rate), a car tilted and turning with given
 * roll, pitch and heading rates (the forward Euler kinematics of docs/frames.md give the
 * body rates it reads; the module must invert them), an acceleration along the car's axis
 * seen through a mounting yaw.
 *
 * Tolerances: float32 rounding of sums of 10 samples and of trigonometry, a few ulp of the
 * quantities (1e-6 rad/s on rates of 0.1 rad/s, 1e-5 m/s^2 on 9.8 m/s^2 sums).
 */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <string.h>

#include <cmocka.h>

#include "dynamics.h"

#define RATE_TOL_RPS 1e-6
#define ACCEL_TOL_MPS2 2e-5
#define N_SAMPLES 10
#define DT_S 0.01

/* a navigator at 45 deg N, 100 m, with attitude (roll, pitch, heading) */
static sins_t nav_at(double roll, double pitch, double heading)
{
    sins_t s;
    nav_real_t q[4];
    quat_from_euler((nav_real_t)roll, (nav_real_t)pitch, (nav_real_t)heading, q);
    const geo_pos_t pos = {450000000LL * GEO_LSB_PER_DEG_E7, 0, 100000LL * GEO_LSB_PER_MM};
    const nav_real_t v0[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    const sins_config_t cfg = sins_default_config();
    assert_int_equal(sins_init(&s, &cfg, &pos, v0, q), NAV_OK);
    return s;
}

/* the specific force a body at rest reads: C_bn^T (0, 0, g) */
static void rest_force_b(const sins_t *s, double f_b[3])
{
    mat3_t C;
    quat_to_dcm(s->q_bn, &C);
    const double g = (double)earth_gravity(nav_sin(geo_lat_rad(&s->pos)), geo_h_m(&s->pos));
    for (int i = 0; i < 3; i++) {
        f_b[i] = (double)C.m[2][i] * g;
    }
}

/* N_SAMPLES samples of constant body rate w_b (rad/s) and specific force f_b (m/s^2) */
static void feed(dynamics_t *d, const sins_t *s, const double w_b[3], const double f_b[3])
{
    for (int k = 0; k < N_SAMPLES; k++) {
        imu_inc_t inc;
        for (int i = 0; i < 3; i++) {
            inc.dtheta_b_rad[i] = (nav_real_t)(w_b[i] * DT_S);
            inc.dv_b_mps[i] = (nav_real_t)(f_b[i] * DT_S);
        }
        inc.dt_s = (nav_real_t)DT_S;
        dynamics_sample(d, s, &inc);
    }
}

/* one output interval of body rate w_b with the specific force of rest, no mounting */
static dynamics_out_t interval_at_rest_force(const sins_t *s, const double w_b[3])
{
    double f_b[3];
    rest_force_b(s, f_b);
    dynamics_t d;
    memset(&d, 0, sizeof d);
    feed(&d, s, w_b, f_b);
    dynamics_out_t o;
    assert_int_equal(dynamics_take(&d, s, NAV_C(0.0), NAV_C(0.0), &o), 0);
    return o;
}

static void test_at_rest_no_motion(void **state)
{
    (void)state;
    const sins_t s = nav_at(0.05, -0.03, 1.0);
    nav_real_t w_ie[3];
    sins_earth_rate_b(&s, w_ie);
    const double w_b[3] = {(double)w_ie[0], (double)w_ie[1], (double)w_ie[2]};
    const dynamics_out_t o = interval_at_rest_force(&s, w_b);
    for (int i = 0; i < 3; i++) {
        assert_true(fabs((double)o.att_rate_rps[i]) < RATE_TOL_RPS);
        assert_true(fabs((double)o.accel_n_mps2[i]) < ACCEL_TOL_MPS2);
        assert_true(fabs((double)o.accel_v_mps2[i]) < ACCEL_TOL_MPS2);
        /* the vehicle-frame rate is what a perfect gyro reads: Earth's rotation */
        assert_true(fabs((double)o.rate_v_rps[i] - w_b[i]) < RATE_TOL_RPS);
    }
}

/* docs/frames.md, C_bn = Rz(-H) Rx(p) Ry(r): w_nb_b = (cr p' + sr cp H', r' - sp H',
 * sr p' - cr cp H') */
static void test_euler_rates_inverted(void **state)
{
    (void)state;
    const double r = 0.08, p = -0.12, H = 2.0;
    const double rd = 0.02, pd = -0.015, Hd = 0.1; /* roll, pitch, heading rates */
    const sins_t s = nav_at(r, p, H);
    nav_real_t w_ie[3];
    sins_earth_rate_b(&s, w_ie);
    const double w_b[3] = {cos(r) * pd + sin(r) * cos(p) * Hd + (double)w_ie[0],
                           rd - sin(p) * Hd + (double)w_ie[1],
                           sin(r) * pd - cos(r) * cos(p) * Hd + (double)w_ie[2]};
    const dynamics_out_t o = interval_at_rest_force(&s, w_b);
    assert_true(fabs((double)o.att_rate_rps[0] - rd) < RATE_TOL_RPS);
    assert_true(fabs((double)o.att_rate_rps[1] - pd) < RATE_TOL_RPS);
    assert_true(fabs((double)o.att_rate_rps[2] - Hd) < RATE_TOL_RPS);
}

/* A car accelerating at 2 m/s^2 along its forward axis, heading north and level, the IMU
 * turned by a mounting yaw: its forward axis clockwise of the car's (dynamics.h). The IMU
 * reads the acceleration on its x axis as -sin(yaw) a; in the vehicle frame it is forward
 * again, and in ENU it points north. */
static void test_forward_accel_through_mounting(void **state)
{
    (void)state;
    const double yaw = 0.02, a = 2.0;
    const sins_t s = nav_at(0.0, 0.0, yaw); /* the IMU's forward axis points at +yaw */
    nav_real_t w_ie[3];
    sins_earth_rate_b(&s, w_ie);
    const double w_b[3] = {(double)w_ie[0], (double)w_ie[1], (double)w_ie[2]};
    double f_b[3];
    rest_force_b(&s, f_b);
    f_b[0] -= a * sin(yaw); /* the car's forward (north) in the IMU's axes */
    f_b[1] += a * cos(yaw);
    dynamics_t d;
    memset(&d, 0, sizeof d);
    feed(&d, &s, w_b, f_b);
    dynamics_out_t o;
    assert_int_equal(dynamics_take(&d, &s, (nav_real_t)yaw, NAV_C(0.0), &o), 0);
    assert_true(fabs((double)o.accel_v_mps2[0]) < ACCEL_TOL_MPS2);
    assert_true(fabs((double)o.accel_v_mps2[1] - a) < ACCEL_TOL_MPS2);
    assert_true(fabs((double)o.accel_v_mps2[2]) < ACCEL_TOL_MPS2);
    assert_true(fabs((double)o.accel_n_mps2[0]) < ACCEL_TOL_MPS2);
    assert_true(fabs((double)o.accel_n_mps2[1] - a) < ACCEL_TOL_MPS2);
}

static void test_interval_restarts_and_empty_refused(void **state)
{
    (void)state;
    const sins_t s = nav_at(0.0, 0.0, 0.0);
    dynamics_t d;
    memset(&d, 0, sizeof d);
    dynamics_out_t o;
    memset(&o, 0x5A, sizeof o);
    const dynamics_out_t before = o;
    assert_int_equal(dynamics_take(&d, &s, NAV_C(0.0), NAV_C(0.0), &o), -1);
    assert_memory_equal(&o, &before, sizeof o);
    const double w_b[3] = {0.0, 0.0, 0.3};
    double f_b[3];
    rest_force_b(&s, f_b);
    feed(&d, &s, w_b, f_b);
    assert_int_equal(dynamics_take(&d, &s, NAV_C(0.0), NAV_C(0.0), &o), 0);
    assert_true(fabs((double)o.rate_v_rps[2] - 0.3) < RATE_TOL_RPS);
    /* the next interval starts empty: nothing came since */
    assert_int_equal(dynamics_take(&d, &s, NAV_C(0.0), NAV_C(0.0), &o), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_at_rest_no_motion),
        cmocka_unit_test(test_euler_rates_inverted),
        cmocka_unit_test(test_forward_accel_through_mounting),
        cmocka_unit_test(test_interval_restarts_and_empty_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
