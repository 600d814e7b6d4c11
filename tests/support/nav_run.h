/*
 * nav_run.h - run the navigation core against a truth motion (test support).
 *
 * nav_run.c is compiled twice, as the float32 firmware variant (nav_run_f32) and the
 * double reference variant (nav_run_f64), so one test can run both on the same motion.
 * The float32 runner rounds the exact increments to float carrying the rounding remainder
 * to the next sample, as a real IMU's output stage does, so no information is lost over
 * time; only the per-sample rounding reaches the core.
 */
#ifndef NAVECU_TEST_NAV_RUN_H
#define NAVECU_TEST_NAV_RUN_H

#include <stddef.h>

#include "truth.h"

typedef struct {
    kin_fn kin;
    const void *ctx;
    double lat0_rad, lon0_rad, h0_m;
    double rate_hz;
    double duration_s;
    double init_tilt_err_rad[3]; /* rotation vector (ENU) applied to the true initial attitude */
    double init_h_err_m;         /* added to the true initial height */
    int coning_sculling;         /* passed to sins_config_t */
    int vdamp;                   /* 1: damp the vertical channel to the true height */
    double *horiz_err_m;         /* optional: horizontal error once per second, */
    size_t horiz_err_len;        /* element i at t = i s */
} run_spec_t;

typedef struct {
    int rc;                  /* first non-zero sins_step return, or 0 */
    double max_horiz_err_m;  /* over the run */
    double final_horiz_err_m;
    double final_att_err_rad;
    double max_att_err_rad;  /* over the run */
    double final_lat_rad, final_lon_rad, final_h_m; /* navigation solution at the end */
    double truth_lat_rad, truth_lon_rad, truth_h_m; /* truth at the end */
} run_result_t;

/* The common test site: 45 deg N, 10 deg E, 100 m; coning/sculling on; vertical damped. */
run_spec_t run_spec_default(kin_fn kin, const void *ctx, double duration_s, double rate_hz);

void nav_run_f32(const run_spec_t *spec, run_result_t *res);
void nav_run_f64(const run_spec_t *spec, run_result_t *res);

#endif
