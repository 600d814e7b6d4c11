/*
 * options.c - navecu's command line (contract in options.h). No I/O here: errors are
 * described in a caller's buffer, so the parser runs under a fuzzer
 * (tests/fuzz/fuzz_options.c) as well as in main.
 */
#include "options.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* err = a + b + c, truncated to err_len - 1 characters */
static void say(char *err, size_t err_len, const char *a, const char *b, const char *c)
{
    if (err != NULL && err_len > 0u) {
        (void)snprintf(err, err_len, "%s%s%s", a, b, c);
    }
}

/* parse an unsigned decimal in [lo, hi]; 0 on success */
static int parse_u16(const char *s, unsigned lo, unsigned hi, uint16_t *out)
{
    char *end = NULL;
    errno = 0;
    const unsigned long v = strtoul(s, &end, 10);
    if (errno != 0 || end == s || *end != '\0' || v < lo || v > hi) {
        return -1;
    }
    *out = (uint16_t)v;
    return 0;
}

/* parse a finite decimal in [lo, hi]; 0 on success */
static int parse_real(const char *s, double lo, double hi, double *out)
{
    char *end = NULL;
    errno = 0;
    const double v = strtod(s, &end);
    if (errno != 0 || end == s || *end != '\0' || !(v >= lo && v <= hi)) {
        return -1;
    }
    *out = v;
    return 0;
}

#define RAD_PER_DEG (3.14159265358979323846 / 180.0)

/* parse "X,Y,Z" metres, each within 10 m; 0 on success */
static int parse_lever(const char *s, nav_real_t out[3])
{
    double x = 0.0, y = 0.0, z = 0.0;
    char tail = 0;
    if (sscanf(s, "%lf,%lf,%lf%c", &x, &y, &z, &tail) != 3 || !(fabs(x) <= 10.0) ||
        !(fabs(y) <= 10.0) || !(fabs(z) <= 10.0)) {
        return -1;
    }
    out[0] = (nav_real_t)x;
    out[1] = (nav_real_t)y;
    out[2] = (nav_real_t)z;
    return 0;
}

int host_options_parse(int argc, char **argv, host_options_t *o, char *err, size_t err_len)
{
    memset(o, 0, sizeof *o);
    o->cfg = app_default_config();
    if (err != NULL && err_len > 0u) {
        err[0] = '\0';
    }
    for (int i = 1; i < argc; i += 2) { /* an option and its value */
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        int bad = 0;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            o->help = 1;
            return 0;
        } else if (v == NULL) {
            bad = 1;
        } else if (strcmp(a, "--can-log") == 0) {
            o->in_path = v;
        } else if (strcmp(a, "--can") == 0) {
            o->live_if = v;
            bad = strlen(v) == 0 || strlen(v) > 15;
        } else if (strcmp(a, "--out") == 0) {
            o->out_path = v;
        } else if (strcmp(a, "--nvm") == 0) {
            o->nvm_path = v;
        } else if (strcmp(a, "--iface") == 0) {
            o->iface = v;
            bad = strlen(v) == 0 || strlen(v) > 15;
        } else if (strcmp(a, "--imu-rate-hz") == 0) {
            bad = parse_u16(v, 10, 400, &o->cfg.imu_rate_hz);
        } else if (strcmp(a, "--nav-rate-hz") == 0) {
            bad = parse_u16(v, 1, 400, &o->cfg.nav_rate_hz);
            o->nav_rate_given = 1;
        } else if (strcmp(a, "--dyn-rate-hz") == 0) {
            bad = parse_u16(v, 0, 400, &o->cfg.dyn_rate_hz);
            o->dyn_rate_given = 1;
        } else if (strcmp(a, "--status-rate-hz") == 0) {
            bad = parse_u16(v, 1, 400, &o->cfg.status_rate_hz);
        } else if (strcmp(a, "--level-s") == 0) {
            bad = parse_u16(v, 1, 600, &o->cfg.level_s);
        } else if (strcmp(a, "--odo-axle") == 0) {
            bad = strcmp(v, "rear") != 0 && strcmp(v, "front") != 0;
            o->cfg.odo_axle = strcmp(v, "front") == 0 ? ODO_AXLE_FRONT : ODO_AXLE_REAR;
        } else if (strcmp(a, "--cal-min-base-m") == 0) {
            double x = 0.0;
            bad = parse_real(v, 0.0, 1e5, &x);
            o->cfg.cal_min_base_m = (nav_real_t)x;
        } else if (strcmp(a, "--gyro-arw-dpsh") == 0) {
            double x = 0.0;
            bad = parse_real(v, 1e-6, 100.0, &x);
            o->cfg.gyro_arw_rad_rts = (nav_real_t)(x * RAD_PER_DEG / 60.0);
        } else if (strcmp(a, "--accel-bias-mg") == 0) {
            double x = 0.0;
            bad = parse_real(v, 1e-4, 1000.0, &x);
            o->cfg.accel_bias_mps2 = (nav_real_t)(x * 9.80665e-3);
        } else if (strcmp(a, "--gyro-instability-dph") == 0) {
            double x = 0.0;
            bad = parse_real(v, 1e-6, 1e4, &x);
            o->cfg.gyro_bias_rw_rps_rts = (nav_real_t)(x * RAD_PER_DEG / 3600.0 * sqrt(2.0 / 300.0));
        } else if (strcmp(a, "--accel-instability-mg") == 0) {
            double x = 0.0;
            bad = parse_real(v, 1e-5, 1000.0, &x);
            o->cfg.accel_bias_rw_mps2_rts = (nav_real_t)(x * 9.80665e-3 * sqrt(2.0 / 300.0));
        } else if (strcmp(a, "--gnss-corr-s") == 0) {
            double x = 0.0;
            bad = parse_real(v, 0.0, 600.0, &x);
            o->cfg.gnss_corr_s = (nav_real_t)x;
        } else if (strcmp(a, "--gnss-latency-ms") == 0) {
            double x = 0.0;
            bad = parse_real(v, 0.0, 500.0, &x);
            o->cfg.gnss_latency_s = (nav_real_t)(x * 1e-3);
        } else if (strcmp(a, "--gnss-lever-m") == 0) {
            bad = parse_lever(v, o->cfg.gnss_lever_b_m);
        } else if (strcmp(a, "--odo-lever-m") == 0) {
            bad = parse_lever(v, o->cfg.odo_lever_b_m);
        } else if (strcmp(a, "--gyro-range-dps") == 0) {
            double x = 0.0;
            bad = parse_real(v, 1.0, 5000.0, &x);
            o->cfg.gyro_range_rps = (nav_real_t)(x * RAD_PER_DEG);
        } else if (strcmp(a, "--accel-range-mps2") == 0) {
            double x = 0.0;
            bad = parse_real(v, 1.0, 2000.0, &x);
            o->cfg.accel_range_mps2 = (nav_real_t)x;
        } else if (strcmp(a, "--test-stall-poll-s") == 0) {
            double x = 0.0;
            bad = parse_real(v, 0.0, 1e6, &x);
            o->stall_poll_us = (uint64_t)(x * 1e6);
            o->stall_poll = 1;
        } else if (strcmp(a, "--gyro-bias-dph") == 0) {
            double x = 0.0;
            bad = parse_real(v, 1e-6, 1e4, &x);
            o->cfg.gyro_bias_rps = (nav_real_t)(x * RAD_PER_DEG / 3600.0);
        } else {
            say(err, err_len, "unknown option '", a, "'");
            return 2;
        }
        if (bad) {
            say(err, err_len, "bad or missing value for ", a, "");
            return 2;
        }
    }
    if ((o->in_path == NULL) == (o->live_if == NULL) ||
        (o->in_path != NULL && o->out_path == NULL)) {
        say(err, err_len, "give either --can-log IN --out OUT, or --can IFACE (see --help)", "",
            "");
        return 2;
    }
    if (!o->nav_rate_given && o->cfg.nav_rate_hz > o->cfg.imu_rate_hz) {
        o->cfg.nav_rate_hz = o->cfg.imu_rate_hz;
    }
    if (!o->dyn_rate_given && o->cfg.dyn_rate_hz > o->cfg.imu_rate_hz) {
        o->cfg.dyn_rate_hz = o->cfg.imu_rate_hz;
    }
    if (o->cfg.nav_rate_hz > o->cfg.imu_rate_hz || o->cfg.status_rate_hz > o->cfg.imu_rate_hz ||
        o->cfg.dyn_rate_hz > o->cfg.imu_rate_hz) {
        say(err, err_len, "output rates cannot exceed the IMU rate", "", "");
        return 2;
    }
    return 0;
}
