/*
 * test_sins.c - the strapdown mechanization against physics, with exact sensor data.
 * Built twice: as the float32 firmware variant and as the double reference variant;
 * tolerances differ by variant and each is justified where it is set.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "motions.h"
#include "nav_run.h"
#include "sins.h"
#include "test_util.h"

#if defined(NAV_REAL_DOUBLE)
#define NAV_RUN nav_run_f64
#define VARIANT "f64"
#else
#define NAV_RUN nav_run_f32
#define VARIANT "f32"
#endif

#define DEG (3.14159265358979323846 / 180.0)

static run_spec_t still_spec(const still_t *still, double duration_s, double rate_hz)
{
    return run_spec_default(kin_still, still, duration_s, rate_hz);
}

/*
 * GIVEN a vehicle standing still for 1 h at 45 deg N, exact increments at 100 Hz
 * WHEN the core navigates from the exact initial state
 * THEN the horizontal position stays within 0.05 m (double) / 1 m (float32) of the start.
 * The vertical channel is damped to the true height: undamped it diverges with time
 * constant sqrt(R/2g) = 570 s from any rounding (test_vertical_channel_diverges) and its
 * vertical velocity couples into east through Coriolis - physics, not a defect.
 */
static void test_stationary_1h(void **state)
{
    (void)state;
    const still_t still = {2.0 * DEG, -1.0 * DEG, 30.0 * DEG};
    run_spec_t spec = still_spec(&still, 3600.0, 100.0);
    run_result_t r;
    NAV_RUN(&spec, &r);
    assert_int_equal(r.rc, 0);
#if defined(NAV_REAL_DOUBLE)
    /* issue #2 asks < 0.05 m; double rounding (1e-16) leaves nothing measurable, so any
     * inconsistency of mechanization and Earth model shows well above 1 mm */
    const double tol_m = 0.001;
#else
    /* issue #2 asks < 1 m; the float32 attitude alone is rounded by up to 3e-8 rad, which
     * the Schuler loop turns into up to 2 R 3e-8 = 0.38 m (docs/numeric-design.md) */
    const double tol_m = 0.5;
#endif
    print_message("[" VARIANT "] stationary 1 h: max horizontal drift %.4f m, final %.4f m, "
                  "attitude %.3g rad\n",
                  r.max_horiz_err_m, r.final_horiz_err_m, r.final_att_err_rad);
    assert_true(r.max_horiz_err_m < tol_m);
}


/* Peaks of a per-second series above half its maximum, refined by a parabola through
 * the three samples around each. Returns the number found (at most max_peaks). */
static int find_peaks(const double *y, size_t n, double *t_peak, int max_peaks)
{
    double ymax = 0.0;
    for (size_t i = 0; i < n; i++) {
        ymax = y[i] > ymax ? y[i] : ymax;
    }
    int found = 0;
    for (size_t i = 1; i + 1 < n && found < max_peaks; i++) {
        if (y[i] > 0.5 * ymax && y[i] > y[i - 1] && y[i] >= y[i + 1]) {
            const double den = y[i - 1] - 2.0 * y[i] + y[i + 1]; /* < 0 at a strict peak */
            t_peak[found++] = (double)i + 0.5 * (y[i - 1] - y[i + 1]) / den;
        }
    }
    return found;
}

/*
 * GIVEN perfect sensors and a 1e-4 rad initial tilt (about north), still at 45 deg N
 * WHEN the core navigates for 4 h
 * THEN the horizontal error oscillates as R*tilt*(1 - cos(w_s t)): its peaks are one Schuler
 * period 2*pi*sqrt(R/g) apart (84.4 min here), measured within 1 %, and the peak is 2*R*tilt
 * within 5 % (Earth-rate coupling shifts both by < 0.2 %).
 */
static void test_schuler_period(void **state)
{
    (void)state;
    static double herr[4 * 3600 + 1];
    const still_t still = {0.0, 0.0, 0.0};
    run_spec_t spec = still_spec(&still, 4.0 * 3600.0, 10.0);
    spec.init_tilt_err_rad[1] = 1e-4;
    spec.horiz_err_m = herr;
    spec.horiz_err_len = sizeof herr / sizeof herr[0];
    run_result_t r;
    NAV_RUN(&spec, &r);
    assert_int_equal(r.rc, 0);

    const double lat = spec.lat0_rad, h = spec.h0_m;
    double rm, rn;
    truth_radii(lat, &rm, &rn);
    const double R = sqrt(rm * rn) + h;
    const double g = truth_gravity(lat, h);
    const double T_expect_s = 2.0 * 3.14159265358979323846 * sqrt(R / g);

    double t_peak[3];
    const int n = find_peaks(herr, spec.horiz_err_len, t_peak, 3);
    assert_int_equal(n, 3);
    const double T_meas_s = 0.5 * (t_peak[2] - t_peak[0]);
    print_message("[" VARIANT "] Schuler period: measured %.1f s (%.2f min), expected %.1f s "
                  "(%.2f min); peak error %.1f m, expected %.1f m\n",
                  T_meas_s, T_meas_s / 60.0, T_expect_s, T_expect_s / 60.0,
                  herr[(size_t)t_peak[0]], 2.0 * R * 1e-4);
    assert_near(T_meas_s, T_expect_s, 0.01 * T_expect_s);
    assert_near(herr[(size_t)t_peak[0]], 2.0 * R * 1e-4, 0.05 * 2.0 * R * 1e-4);
}

/*
 * GIVEN a stationary vehicle, undamped vertical channel, 100 m initial height error (large
 *       enough that float32 rounding of gravity, a 6e-7 m/s^2 bias, adds < 0.1 %)
 * WHEN the core navigates for 1000 s
 * THEN the height error grows as cosh(w_v t) with w_v^2 = -dg/dh = 2g/R (1 + f + m - ...),
 * TR8350.2 eq. 4-3: the free-inertial vertical instability, w_v measured within 2 %.
 */
static void test_vertical_channel_diverges(void **state)
{
    (void)state;
    const still_t still = {0.0, 0.0, 0.0};
    run_spec_t spec = still_spec(&still, 1000.0, 10.0);
    spec.vdamp = 0;
    spec.init_h_err_m = 100.0;
    run_result_t r;
    NAV_RUN(&spec, &r);
    assert_int_equal(r.rc, 0);
    const double dh = r.final_h_m - r.truth_h_m;
    /* -dg/dh from the height derivative of the normal gravity series, numerically */
    const double w_v2 = truth_gravity(spec.lat0_rad, spec.h0_m) - truth_gravity(spec.lat0_rad, spec.h0_m + 1.0);
    const double w_v_expect = sqrt(w_v2);
    const double w_v_meas = acosh(dh / 100.0) / 1000.0;
    print_message("[" VARIANT "] vertical channel: height error 100 m -> %.3f m in 1000 s; "
                  "w_v %.4e /s, expected %.4e /s\n", dh, w_v_meas, w_v_expect);
    assert_near(w_v_meas, w_v_expect, 0.02 * w_v_expect);
}

/* the same motion with and without the two-sample coning/sculling corrections */
static void run_with_and_without(run_spec_t *spec, run_result_t *with, run_result_t *without)
{
    spec->coning_sculling = 1;
    NAV_RUN(spec, with);
    spec->coning_sculling = 0;
    NAV_RUN(spec, without);
    assert_int_equal(with->rc, 0);
    assert_int_equal(without->rc, 0);
}

/*
 * GIVEN a classical coning motion (half-angle 1 deg, 2 Hz) sampled at 100 Hz, 60 s
 * WHEN the core integrates it with and without the two-sample coning correction
 * THEN the final attitude error with the correction is at least 10x smaller.
 */
static void test_coning_compensation(void **state)
{
    (void)state;
    cone_t cone = {1.0 * DEG, 2.0 * 2.0 * 3.14159265358979323846, {0}};
    truth_q_from_euler(0.0, 0.0, 30.0 * DEG, cone.q0);
    run_spec_t spec = still_spec(NULL, 60.0, 100.0);
    spec.kin = kin_cone;
    spec.ctx = &cone;
    run_result_t with, without;
    run_with_and_without(&spec, &with, &without);
    print_message("[" VARIANT "] coning 60 s: attitude error %.3g rad without correction, "
                  "%.3g rad with (ratio %.0f)\n", without.final_att_err_rad,
                  with.final_att_err_rad, without.final_att_err_rad / with.final_att_err_rad);
    assert_true(without.final_att_err_rad > 10.0 * with.final_att_err_rad);
}


static void init_still(sins_t *s)
{
    const sins_config_t cfg = sins_default_config();
    const geo_pos_t pos = {45LL * 10000000LL * GEO_LSB_PER_DEG_E7, 0, 0};
    const nav_real_t v[3] = {(nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)0.0};
    const nav_real_t q[4] = {(nav_real_t)1.0, (nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)0.0};
    assert_int_equal(sins_init(s, &cfg, &pos, v, q), NAV_OK);
}

/* the navigation state proper (not the bookkeeping of coning history) */
static void assert_same_state(const sins_t *a, const sins_t *b)
{
    assert_memory_equal(&a->pos, &b->pos, sizeof a->pos);
    assert_memory_equal(a->q_bn, b->q_bn, sizeof a->q_bn);
    assert_memory_equal(a->v_n_mps, b->v_n_mps, sizeof a->v_n_mps);
    assert_int_equal(a->n_steps, b->n_steps);
}

/*
 * GIVEN a navigator at rest
 * WHEN it is fed malformed increments (non-finite values, dt <= 0 or above max_dt_s, more
 *      than half a turn in one sample) or increments that would leave the valid region
 * THEN each is rejected with its documented code and the navigation state is unchanged.
 */
static void test_rejects_bad_input(void **state)
{
    (void)state;
    sins_t s, before;
    init_still(&s);
    imu_inc_t good = {{(nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)0.0},
                      {(nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)0.098},
                      (nav_real_t)0.01};
    assert_int_equal(sins_step(&s, &good), NAV_OK);
    before = s;

    imu_inc_t bad = good;
    bad.dt_s = (nav_real_t)0.0;
    assert_int_equal(sins_step(&s, &bad), NAV_EINVAL);
    bad.dt_s = (nav_real_t)-0.01;
    assert_int_equal(sins_step(&s, &bad), NAV_EINVAL);
    bad.dt_s = (nav_real_t)0.5; /* > max_dt_s 0.2: a gap in the data, not one sample */
    assert_int_equal(sins_step(&s, &bad), NAV_EINVAL);
    bad.dt_s = (nav_real_t)NAN;
    assert_int_equal(sins_step(&s, &bad), NAV_EINVAL);
    bad = good;
    bad.dtheta_b_rad[1] = (nav_real_t)NAN;
    assert_int_equal(sins_step(&s, &bad), NAV_EINVAL);
    bad = good;
    bad.dv_b_mps[0] = (nav_real_t)INFINITY;
    assert_int_equal(sins_step(&s, &bad), NAV_EINVAL);
    bad = good;
    bad.dtheta_b_rad[2] = (nav_real_t)3.5; /* more than pi in one sample */
    assert_int_equal(sins_step(&s, &bad), NAV_EINVAL);
    bad = good;
    bad.dv_b_mps[1] = (nav_real_t)2000.0; /* would exceed 1000 m/s */
    assert_int_equal(sins_step(&s, &bad), NAV_ERANGE);
    assert_same_state(&s, &before);
    assert_int_equal(s.have_prev, 0); /* coning history is not trusted across a gap */

    /* and init refuses what it cannot navigate from */
    sins_t t;
    const sins_config_t cfg = sins_default_config();
    const geo_pos_t pole = {895LL * 1000000LL * GEO_LSB_PER_DEG_E7, 0, 0};
    const geo_pos_t ok = {0, 0, 0};
    const nav_real_t v0[3] = {(nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)0.0};
    const nav_real_t vnan[3] = {(nav_real_t)NAN, (nav_real_t)0.0, (nav_real_t)0.0};
    const nav_real_t q1[4] = {(nav_real_t)1.0, (nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)0.0};
    const nav_real_t q0[4] = {(nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)0.0};
    assert_int_equal(sins_init(&t, &cfg, &pole, v0, q1), NAV_EINVAL);
    assert_int_equal(sins_init(&t, &cfg, &ok, vnan, q1), NAV_EINVAL);
    assert_int_equal(sins_init(&t, &cfg, &ok, v0, q0), NAV_EINVAL);
    const geo_pos_t deep = {0, 0, -2000000LL * GEO_LSB_PER_MM}; /* 2 km below the ellipsoid */
    assert_int_equal(sins_init(&t, &cfg, &deep, v0, q1), NAV_EINVAL);
    sins_config_t bad_cfg = cfg;
    bad_cfg.max_dt_s = (nav_real_t)0.0;
    assert_int_equal(sins_init(&t, &bad_cfg, &ok, v0, q1), NAV_EINVAL);
    bad_cfg = cfg;
    bad_cfg.vdamp_tau_s = (nav_real_t)1e-3; /* a loop faster than the samples is unstable */
    assert_int_equal(sins_init(&t, &bad_cfg, &ok, v0, q1), NAV_EINVAL);
    bad_cfg.vdamp_tau_s = (nav_real_t)NAN;
    assert_int_equal(sins_init(&t, &bad_cfg, &ok, v0, q1), NAV_EINVAL);

    /* climbing out of the valid height range is refused, not overflowed */
    const geo_pos_t high = {0, 0, GEO_H_MAX_LSB - 1000LL * GEO_LSB_PER_MM}; /* 1 m below */
    const nav_real_t up[3] = {(nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)900.0};
    assert_int_equal(sins_init(&t, &cfg, &high, up, q1), NAV_OK);
    const sins_t t0 = t;
    assert_int_equal(sins_step(&t, &good), NAV_ERANGE);
    assert_same_state(&t, &t0);
}

/*
 * GIVEN a stationary vehicle, 10 m initial height error, vertical damping (tau = 100 s)
 *       toward the true height
 * WHEN the core navigates for 200 s
 * THEN the loop is critically damped with both poles at -1/tau:
 *      dh'' + (2/tau) dh' + dh/tau^2 = 0 with dh(0) = h0 and dh'(0) = dv(0) - k1 h0 =
 *      -2 h0/tau (the velocity is exact, the height feedback acts at once), so
 *      dh(t) = h0 (1 - t/tau) exp(-t/tau) = -1.353 m at t = 2 tau (2 % for the discrete
 *      loop). A wrong k1 or a k2 without the 2g/R term misses this by far more.
 */
static void test_vertical_damping_response(void **state)
{
    (void)state;
    const still_t still = {0.0, 0.0, 0.0};
    run_spec_t spec = still_spec(&still, 200.0, 10.0);
    spec.init_h_err_m = 10.0;
    run_result_t r;
    NAV_RUN(&spec, &r);
    assert_int_equal(r.rc, 0);
    const double expect = 10.0 * (1.0 - 2.0) * exp(-2.0);
    print_message("[" VARIANT "] vertical damping: 10 m -> %.3f m after 2 tau, expected %.3f m\n",
                  r.final_h_m - r.truth_h_m, expect);
    assert_near(r.final_h_m - r.truth_h_m, expect, 0.02 * fabs(expect));
}

/*
 * GIVEN a classical sculling motion (yaw +-2 deg at 2 Hz with +-2 m/s^2 along north in
 *       phase) sampled at 100 Hz, 60 s
 * WHEN the core integrates it with and without the two-sample sculling correction
 *      (coning is nil for a rotation about one fixed axis, so the switch isolates sculling)
 * THEN the horizontal error with the correction is at least 10x smaller.
 */
static void test_sculling_compensation(void **state)
{
    (void)state;
    const scull_t scull = {2.0, 2.0 * 2.0 * 3.14159265358979323846, 2.0 * DEG};
    run_spec_t spec = run_spec_default(kin_scull, &scull, 60.0, 100.0);
    run_result_t with, without;
    run_with_and_without(&spec, &with, &without);
    print_message("[" VARIANT "] sculling 60 s: max horizontal error %.3g m without correction, "
                  "%.3g m with (ratio %.0f)\n", without.max_horiz_err_m, with.max_horiz_err_m,
                  without.max_horiz_err_m / with.max_horiz_err_m);
    assert_true(without.max_horiz_err_m > 10.0 * with.max_horiz_err_m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stationary_1h),
        cmocka_unit_test(test_schuler_period),
        cmocka_unit_test(test_vertical_channel_diverges),
        cmocka_unit_test(test_vertical_damping_response),
        cmocka_unit_test(test_coning_compensation),
        cmocka_unit_test(test_sculling_compensation),
        cmocka_unit_test(test_rejects_bad_input),
    };
    return cmocka_run_group_tests_name("sins_" VARIANT, tests, NULL, NULL);
}
