/*
 * study_numerics.c - not a test: prints how the float32 core fares on the stationary hour
 * and the closed drive, for docs/numeric-design.md. `make numerics` builds it twice, with
 * and without compensated accumulation (NAV_ACC_PLAIN), and runs both.
 */
#include <stdio.h>

#include "motions.h"
#include "nav_run.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)


int main(void)
{
    const still_t still = {2.0 * DEG, -1.0 * DEG, 30.0 * DEG};
    run_spec_t spec = run_spec_default(kin_still, &still, 3600.0, 10.0);
    const double rates[] = {10.0, 100.0, 400.0};
    printf("stationary 1 h at 45 deg N, exact increments, vertical damped:\n");
    printf("  rate_hz  f32_max_horiz_m  f64_max_horiz_m  f32_att_err_rad\n");
    for (int i = 0; i < 3; i++) {
        run_result_t r32, r64;
        spec.rate_hz = rates[i];
        nav_run_f32(&spec, &r32);
        nav_run_f64(&spec, &r64);
        printf("  %7.0f  %15.4f  %15.4f  %15.3g%s\n", rates[i], r32.max_horiz_err_m,
               r64.max_horiz_err_m, r32.final_att_err_rad, r32.rc ? "  (rejected a step)" : "");
    }

    const circle_t circle = {10.0, 120.0, 6000.0 / (2.0 * PI * 5.0), 20.0 * DEG};
    spec.kin = kin_circle;
    spec.ctx = &circle;
    spec.duration_s = 600.0;
    printf("closed stop-and-go circle drive, 600 s, 6000 m, exact increments:\n");
    printf("  rate_hz  f32_max_horiz_m  f64_max_horiz_m  f32_vs_f64_end_m  f32_att_err_rad\n");
    for (int i = 0; i < 3; i++) {
        run_result_t r32, r64;
        spec.rate_hz = rates[i];
        nav_run_f32(&spec, &r32);
        nav_run_f64(&spec, &r64);
        const double d = truth_horiz_dist_m(r32.final_lat_rad, r32.final_lon_rad,
                                            r64.final_lat_rad, r64.final_lon_rad, spec.h0_m);
        printf("  %7.0f  %15.4f  %15.4f  %16.4f  %15.3g\n", rates[i], r32.max_horiz_err_m,
               r64.max_horiz_err_m, d, r32.final_att_err_rad);
    }
    return 0;
}
