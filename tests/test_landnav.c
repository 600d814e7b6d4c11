/*
 * test_landnav.c - landnav.h: navigation without the Kalman filter. Standstill: velocity
 * zero, heading held, the z gyro bias estimated as the closed form b = sum(r_k) / (n + n0)
 * with n0 = ARW^2 / (dt sigma_b^2); dead reckoning on the odometer along the SINS heading,
 * which is then the output; the free SINS without an odometer.
 *
 * The car is on the equator, level, heading north: the Earth's rate in body axes is
 * (0, Omega, 0), so the body z gyro's Earth part is zero and what it reads is its bias.
 * The prior ARW 1e-3 rad/sqrt(s), sigma_b 1e-2 rad/s at dt 0.01 s gives n0 = 1 exactly.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "landnav.h"
#include "test_util.h"

#define DT 0.01f
#define OMEGA 7.292115e-5

static landnav_t ln;
static zbias_t zb;
static sins_t nav;
static dr_t dr;
static odo_t odo;
static const zbias_prior_t PRIOR = {1e-3f, 1e-2f, 0.0f};
static geo_pos_t start;
static float g0;

static void start_at(nav_real_t dh_rad, nav_real_t mu)
{
    memset(&ln, 0, sizeof ln);
    memset(&zb, 0, sizeof zb);
    start.lat = start.lon = start.h = 0;
    const sins_config_t cfg = sins_default_config();
    nav_real_t q[4];
    quat_from_euler(0.0f, 0.0f, 0.0f, q);
    const nav_real_t v0[3] = {0.0f, 0.0f, 0.0f};
    assert_int_equal(sins_init(&nav, &cfg, &start, v0, q), NAV_OK);
    assert_int_equal(dr_init(&dr, &start, dh_rad, mu), NAV_OK);
    const odo_config_t ocfg = odo_default_config();
    assert_int_equal(odo_init(&odo, &ocfg), NAV_OK);
    g0 = earth_gravity(0.0f, 0.0f);
}

static int setup(void **state)
{
    (void)state;
    start_at(0.0f, 0.0f);
    return 0;
}

static void wheels(float v)
{
    const nav_real_t w[4] = {v, v, v, v};
    assert_int_equal(odo_wheels(&odo, w, 0.0f), NAV_OK);
}

/* one sample at rest with the z gyro reading rate_z (rad/s) and a horizontal specific
 * force ax (m/s^2) east; returns the compensated yaw rate */
static nav_real_t step(float rate_z, float ax)
{
    imu_inc_t inc;
    inc.dtheta_b_rad[0] = 0.0f;
    inc.dtheta_b_rad[1] = (float)(OMEGA * (double)DT);
    inc.dtheta_b_rad[2] = rate_z * DT;
    inc.dv_b_mps[0] = ax * DT;
    inc.dv_b_mps[1] = 0.0f;
    inc.dv_b_mps[2] = g0 * DT;
    inc.dt_s = DT;
    nav_real_t yaw = 0.0f;
    assert_int_equal(landnav_step(&ln, &zb, &PRIOR, &nav, &dr, &odo, &inc, &yaw), 0);
    return yaw;
}

/* 1 s at 10 m/s (wheel frames at 50 Hz): the dead reckoning's metres east and north */
static void drive_1s_at_10mps(nav_real_t *e, nav_real_t *n)
{
    for (int k = 0; k < 100; k++) {
        if (k % 2 == 0) {
            wheels(10.0f);
        }
        step(0.0f, 0.0f);
    }
    dr_local_m(&start, &dr.pos, e, n);
}

static double heading_of(void)
{
    nav_real_t r, p, h;
    sins_euler(&nav, &r, &p, &h);
    return (double)h;
}

/* GIVEN the car standing (wheels at zero) with its z gyro alternating 1e-4 and 3e-4 rad/s
 * THEN after standstill is declared every sample is in the estimate, which is the closed
 * form sum(r_k) / (n + 1), and each sample's yaw rate is its reading less the estimate
 * before it. */
static void test_standstill_bias_closed_form(void **state)
{
    (void)state;
    double sum = 0.0;
    double bias_before = 0.0;
    for (int k = 0; k < 400; k++) {
        if (k % 10 == 0) {
            wheels(0.0f);
        }
        const float r = (k % 2 == 0) ? 1e-4f : 3e-4f;
        const uint32_t n_before = zb.n;
        const nav_real_t yaw = step(r, 0.0f);
        assert_near(yaw, (double)r - bias_before, 1e-9);
        if (zb.n == n_before + 1u) {
            sum += (double)r;
        } else {
            assert_int_equal(zb.n, n_before); /* before standstill: nothing learnt */
        }
        bias_before = (double)zb.bias_rps;
    }
    /* standstill after 0.5 s of zero wheels: about 350 of the 400 samples */
    assert_true(zb.n >= 340u && zb.n <= 352u);
    assert_int_equal(odo.standing, 1);
    assert_near(zb.bias_rps, sum / ((double)zb.n + 1.0), 1e-9);
    assert_true(fabs((double)zb.bias_rps - sum / (double)zb.n) > 4e-7); /* not a plain mean: 5.7e-7 off */
    assert_int_equal(ln.output_dr, 1); /* standing: the dead reckoning is the output */
}

/* A stuck yaw gyro (ln.yaw_car, set by the application): GIVEN the car standing with a
 * bias learnt (1 s of 2e-4 rad/s) WHEN the gyro is stuck at 0.1 rad/s and the car stands
 * 2 s more THEN the bias and its count stay as they were and the yaw rate is the car's, 0
 * (the Earth's about the body z is 0 at the equator); WHEN it drives north at 10 m/s with
 * a lateral force of -1 m/s^2 THEN the yaw rate is 0.1 rad/s (landnav_car_yaw), the frozen
 * 0.1 of the gyro playing no part (it reads 0.05 there). */
static void test_stuck_yaw_gyro_learns_no_bias(void **state)
{
    (void)state;
    for (int k = 0; k < 100; k++) {
        if (k % 10 == 0) {
            wheels(0.0f);
        }
        step(2e-4f, 0.0f);
    }
    assert_int_equal(odo.standing, 1);
    const uint32_t n0 = zb.n;
    const nav_real_t b0 = zb.bias_rps;
    assert_true(n0 > 0u);
    ln.yaw_car = 1u;
    for (int k = 0; k < 200; k++) {
        if (k % 10 == 0) {
            wheels(0.0f);
        }
        assert_near(step(0.1f, 0.0f), 0.0, 1e-9);
    }
    assert_int_equal(zb.n, n0);
    assert_near(zb.bias_rps, b0, 0.0);
    /* driving */
    const nav_real_t v_north[3] = {0.0f, 10.0f, 0.0f};
    assert_int_equal(sins_set_velocity(&nav, v_north), NAV_OK);
    wheels(10.0f);
    /* the navigator's speed is 10 m/s to 1e-3 over the sample: 1e-4 rad/s */
    assert_near(step(0.05f, -1.0f), 0.1, 2e-4);
}

/* GIVEN standstill with the z gyro reading 1e-3 rad/s and a 0.1 m/s^2 accelerometer error
 * WHEN 10 s pass THEN the heading stays where it was when the car stopped and the velocity
 * at zero; WHEN the same runs without an odometer THEN the free SINS turns by about
 * -1e-3 rad/s x 10 s (counter-clockwise about up: the heading decreases) and drifts. */
static void test_heading_held_at_standstill(void **state)
{
    (void)state;
    wheels(0.0f);
    for (int k = 0; k < 60; k++) {
        step(0.0f, 0.0f);
    }
    assert_int_equal(ln.holding, 1);
    const double held = (double)ln.hold_heading_rad;
    for (int k = 0; k < 1000; k++) {
        if (k % 10 == 0) {
            wheels(0.0f);
        }
        step(1e-3f, 0.1f);
    }
    double dh = heading_of() - held;
    dh -= 2.0 * 3.14159265358979 * floor(dh / (2.0 * 3.14159265358979) + 0.5);
    assert_near(dh, 0.0, 1e-6);
    for (int i = 0; i < 3; i++) {
        assert_near(nav.v_n_mps[i], 0.0, 0.0);
    }

    start_at(0.0f, 0.0f); /* no wheel frames: no odometer */
    for (int k = 0; k < 1000; k++) {
        step(1e-3f, 0.1f);
    }
    dh = heading_of();
    dh -= 2.0 * 3.14159265358979 * floor(dh / (2.0 * 3.14159265358979) + 0.5);
    assert_near(dh, -0.01, 1e-4);
    assert_true(nav.v_n_mps[0] > 0.5f); /* 0.1 m/s^2 east for 10 s: about 1 m/s */
    assert_int_equal(ln.holding, 0);
    assert_int_equal(ln.output_dr, 0);
    assert_int_equal(zb.n, 0u);
}

/* GIVEN wheels at 10.00 m/s, heading north, an odometer reading 2 % long (mu 0.02)
 * WHEN 1 s passes THEN the dead reckoning went 10 / 1.02 = 9.804 m north, it is the output,
 * and the SINS took its position and the odometer's velocity (10 / 1.02 m/s north). */
static void test_dead_reckoning_on_odometer(void **state)
{
    (void)state;
    start_at(0.0f, 0.02f);
    nav_real_t e, n;
    drive_1s_at_10mps(&e, &n);
    assert_near(n, 10.0 / 1.02, 0.01);
    assert_near(e, 0.0, 1e-3);
    assert_int_equal(ln.output_dr, 1);
    assert_true(nav.pos.lat == dr.pos.lat && nav.pos.lon == dr.pos.lon);
    assert_near(nav.v_n_mps[1], 10.0 / 1.02, 1e-4);
    assert_near(nav.v_n_mps[0], 0.0, 1e-4);
}

/* With a heading correction dH = 0.1 rad the SINS heading north is compensated to
 * -0.1 rad: the track goes 0.0998 of the distance west. */
static void test_dead_reckoning_heading_correction(void **state)
{
    (void)state;
    start_at(0.1f, 0.0f);
    nav_real_t e, n;
    drive_1s_at_10mps(&e, &n);
    assert_near(e, -10.0 * sin(0.1), 0.01);
    assert_near(n, 10.0 * cos(0.1), 0.01);
    assert_near(nav.v_n_mps[0], -10.0 * sin(0.1), 1e-4);
}

/* Without an odometer the dead reckoning follows the free SINS. */
static void test_no_odometer_dr_follows_sins(void **state)
{
    (void)state;
    for (int k = 0; k < 100; k++) {
        step(0.0f, 1.0f);
    }
    assert_int_equal(ln.output_dr, 0);
    assert_true(nav.pos.lon != start.lon); /* it moved east */
    assert_true(dr.pos.lat == nav.pos.lat && dr.pos.lon == nav.pos.lon);
}

/* The hold ends when the filter takes over (release) or with a new navigator (restart,
 * which also makes the free SINS the output); the next standstill holds again, at the
 * heading then. */
static void test_release_and_restart(void **state)
{
    (void)state;
    wheels(0.0f);
    for (int k = 0; k < 60; k++) {
        step(0.0f, 0.0f);
    }
    assert_int_equal(ln.holding, 1);
    landnav_release_hold(&ln);
    assert_int_equal(ln.holding, 0);
    assert_int_equal(ln.output_dr, 1);
    (void)sins_turn_heading(&nav, 0.5f);
    step(0.0f, 0.0f);
    assert_int_equal(ln.holding, 1);
    assert_near(ln.hold_heading_rad, 0.5, 1e-5);
    landnav_restart(&ln);
    assert_int_equal(ln.holding, 0);
    assert_int_equal(ln.output_dr, 0);
}

/* A step the strapdown core refuses (an interval longer than its 0.2 s) is counted. GIVEN
 * the wheels reading zero THEN its time passes for them (the odometer's age, IMU time)
 * but does not count as time standing still: its zero rates were refused. GIVEN then a
 * standstill declared (its z bias learnt) WHEN a refused step says 0.5 rad/s THEN the
 * bias learns nothing from it (neither its count nor its value move; before, the
 * refused rate went into the bias, 1e-4 -> 1e-2 rad/s, a review's probe) and the
 * standstill stands. */
static void test_refused_step_counted(void **state)
{
    (void)state;
    wheels(0.0f);
    (void)step(0.0f, 0.0f);
    const double age0_s = (double)odo.age_s;
    const double still0_s = (double)odo.still_for_s;
    imu_inc_t inc;
    memset(&inc, 0, sizeof inc);
    inc.dt_s = 0.5f;
    nav_real_t yaw;
    assert_int_equal(landnav_step(&ln, &zb, &PRIOR, &nav, &dr, &odo, &inc, &yaw), 1);
    assert_near((double)odo.age_s, age0_s + 0.5, 1e-6);
    assert_near((double)odo.still_for_s, still0_s, 1e-9);

    for (int k = 0; k < 100; k++) {
        if (k % 10 == 0) {
            wheels(0.0f);
        }
        (void)step(1e-4f, 0.0f);
    }
    assert_int_equal(odo.standing, 1);
    const uint32_t n0 = zb.n;
    const double bias0_rps = (double)zb.bias_rps;
    assert_true(n0 > 0u);
    inc.dtheta_b_rad[2] = 0.5f * 0.5f;
    assert_int_equal(landnav_step(&ln, &zb, &PRIOR, &nav, &dr, &odo, &inc, &yaw), 1);
    assert_int_equal(zb.n, n0);
    assert_near((double)zb.bias_rps, bias0_rps, 1e-12);
    assert_int_equal(odo.standing, 1);
}

/* GIVEN the dead reckoning's accuracy started at 1 m per axis, scale 0.02, heading 0.05
 * rad WHEN the car drives north for 1 s THEN (seed 000 eqs 5-6) the north error's
 * variance is 1 + (0.02 D)^2 and the east's 1 + (0.05 D)^2, D the distance driven (the
 * gyro's ARW, 1e-3 rad/sqrt(s) over 1 s, adds 3e-5 m^2); GIVEN it restarted with the z
 * bias's prior WHEN the car then stands THEN the accuracy holds and the bias's variance
 * is the estimator's own, sigma_b^2 n0 / (n + n0) (zbias_sigma_rps: the accuracy's model
 * of the estimate is the estimate's) */
static void test_accuracy_of_the_dead_reckoning(void **state)
{
    (void)state;
    dr_acc_start(&ln.acc, 1.0f, 0.02f, 0.05f, 0.0f, 0.0f);
    nav_real_t e, n;
    drive_1s_at_10mps(&e, &n);
    assert_true(n > 9.0f);
    assert_near(ln.acc.P[DR_ACC_N][DR_ACC_N], 1.0 + 0.0004 * (double)n * (double)n, 1e-3);
    assert_near(ln.acc.P[DR_ACC_E][DR_ACC_E], 1.0 + 0.0025 * (double)n * (double)n, 1e-3);
    /* the bias's prior from here, nothing learnt yet (zb.n 0) */
    assert_int_equal(zb.n, 0u);
    dr_acc_start(&ln.acc, 1.0f, 0.02f, 0.05f, PRIOR.gyro_bias_rps, 0.0f);
    const nav_real_t moving = dr_acc_sigma_h_m(&ln.acc);
    for (int k = 0; k < 400; k++) {
        if (k % 10 == 0) {
            wheels(0.0f);
        }
        step(2e-4f, 0.0f);
    }
    assert_true(zb.n > 300u);
    assert_near(dr_acc_sigma_h_m(&ln.acc), moving, 1e-6);
    const double sb = (double)zbias_sigma_rps(&zb, &PRIOR, DT, 0.0f);
    assert_near(sqrt((double)ln.acc.P[DR_ACC_B][DR_ACC_B]), sb, 1e-4 * sb);
    assert_int_equal(ln.acc.valid, 1);
    /* learnt long ago, the bias has walked on (instability 1e-5 rad/s/sqrt(s) over 100 s
     * adds 1e-8), but never beyond its turn-on prior */
    const zbias_prior_t walk = {PRIOR.gyro_arw_rad_rts, PRIOR.gyro_bias_rps, 1e-5f};
    assert_near(zbias_sigma_rps(&zb, &walk, DT, 100.0f), sqrt(sb * sb + 1e-8), 1e-4 * sb);
    assert_near(zbias_sigma_rps(&zb, &walk, DT, 1e9f), PRIOR.gyro_bias_rps, 1e-9);
}

/* Without an odometer the accuracy holds while the free SINS stands (the first samples
 * before the first wheel frame) and ends once it carries the car (above 0.5 m/s) */
static void test_accuracy_ends_with_the_free_sins(void **state)
{
    (void)state;
    dr_acc_start(&ln.acc, 1.0f, 0.02f, 0.05f, 0.0f, 0.0f);
    for (int k = 0; k < 20; k++) {
        step(0.0f, 0.0f);
    }
    assert_int_equal(ln.output_dr, 0);
    assert_int_equal(ln.acc.valid, 1);
    for (int k = 0; k < 100; k++) {
        step(0.0f, 1.0f);
    }
    assert_int_equal(ln.acc.valid, 0);
    assert_near(dr_acc_sigma_h_m(&ln.acc), -1.0, 0.0);
    landnav_restart(&ln);
    assert_int_equal(ln.acc.valid, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_standstill_bias_closed_form, setup),
        cmocka_unit_test_setup(test_stuck_yaw_gyro_learns_no_bias, setup),
        cmocka_unit_test_setup(test_heading_held_at_standstill, setup),
        cmocka_unit_test_setup(test_dead_reckoning_on_odometer, setup),
        cmocka_unit_test_setup(test_dead_reckoning_heading_correction, setup),
        cmocka_unit_test_setup(test_no_odometer_dr_follows_sins, setup),
        cmocka_unit_test_setup(test_release_and_restart, setup),
        cmocka_unit_test_setup(test_refused_step_counted, setup),
        cmocka_unit_test_setup(test_accuracy_of_the_dead_reckoning, setup),
        cmocka_unit_test_setup(test_accuracy_ends_with_the_free_sins, setup),
    };
    return cmocka_run_group_tests_name("landnav", tests, NULL, NULL);
}
