/*
 * test_drive.c - a closed drive with exact sensor data, both numeric variants.
 *
 * The motion: 10 min of stop-and-go driving on a circle of radius 191 m at 45 deg N. Speed
 * s(t) = S0 (1 - cos(2 pi t / T)) (stops every T = 120 s, 20 m/s peak); the path curvature
 * is constant, so heading advances by s/R and after 600 s the car has driven 6000 m = five
 * laps and is back at the start. The body rolls out of the turn with lateral acceleration
 * and pitches and rolls on its suspension, so all three gyro and accelerometer axes work
 * (kin_circle, tests/support/motions.c).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "motions.h"
#include "nav_run.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

static const circle_t CIRCLE = {10.0, 120.0, 6000.0 / (2.0 * PI * 5.0), 20.0 * DEG};

static run_spec_t circle_spec(void)
{
    return run_spec_default(kin_circle, &CIRCLE, 600.0, 100.0);
}

/*
 * GIVEN the closed 10-min drive with exact increments at 100 Hz
 * WHEN both variants navigate it from the exact initial state
 * THEN the truth itself closes (< 0.2 m: a path of constant curvature relative to local
 *      north is closed on a plane, not exactly on the ellipsoid; a check of the generator);
 *      the double variant ends within 1 m of the start, the float32 variant within 2 m, and
 *      they agree within 1 m (issue #2's figures);
 *      and, tighter, the error against the truth stays below 2 cm (double) / 5 cm (float32)
 *      all the way: what is left with exact data is the algorithm's O(dt^2) truncation
 *      (0.6 cm here) plus float32 rounding (2 cm). A rectangle-rule position update or a
 *      wrong sculling term shows as 10-15 cm.
 */
static void test_closed_drive(void **state)
{
    (void)state;
    const run_spec_t spec = circle_spec();
    run_result_t r32, r64;
    nav_run_f32(&spec, &r32);
    nav_run_f64(&spec, &r64);
    assert_int_equal(r32.rc, 0);
    assert_int_equal(r64.rc, 0);

    const double h = spec.h0_m;
    const double truth_closure_m = truth_horiz_dist_m(spec.lat0_rad, spec.lon0_rad,
                                                      r64.truth_lat_rad, r64.truth_lon_rad, h);
    const double end64_m = truth_horiz_dist_m(spec.lat0_rad, spec.lon0_rad, r64.final_lat_rad,
                                              r64.final_lon_rad, h);
    const double end32_m = truth_horiz_dist_m(spec.lat0_rad, spec.lon0_rad, r32.final_lat_rad,
                                              r32.final_lon_rad, h);
    const double diff_m = truth_horiz_dist_m(r64.final_lat_rad, r64.final_lon_rad,
                                             r32.final_lat_rad, r32.final_lon_rad, h);
    print_message("closed drive 600 s, 6000 m: truth closes to %.2e m; end-to-start f64 %.4f m, "
                  "f32 %.4f m; f32 vs f64 %.4f m; max error f64 %.4f m, f32 %.4f m; "
                  "final attitude error f64 %.2e rad, f32 %.2e rad\n",
                  truth_closure_m, end64_m, end32_m, diff_m, r64.max_horiz_err_m,
                  r32.max_horiz_err_m, r64.final_att_err_rad, r32.final_att_err_rad);
    assert_true(truth_closure_m < 0.2);
    assert_true(end64_m < 1.0);
    assert_true(end32_m < 2.0);
    assert_true(diff_m < 1.0);
    assert_true(r64.max_horiz_err_m < 0.02);
    assert_true(r32.max_horiz_err_m < 0.05);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closed_drive),
    };
    return cmocka_run_group_tests_name("closed_drive", tests, NULL, NULL);
}
