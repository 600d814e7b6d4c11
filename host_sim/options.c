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

#include "params_cli.h"

/* err = a + b + c, truncated to err_len - 1 characters */
static void say(char *err, size_t err_len, const char *a, const char *b, const char *c)
{
    if (err != NULL && err_len > 0u) {
        (void)snprintf(err, err_len, "%s%s%s", a, b, c);
    }
}

/* parse a finite decimal; 0 on success */
static int parse_double(const char *s, double *out)
{
    char *end = NULL;
    errno = 0;
    const double v = strtod(s, &end);
    if (errno != 0 || end == s || *end != '\0' || !isfinite(v)) {
        return -1;
    }
    *out = v;
    return 0;
}

static int in_range(const params_cli_t *c, double x)
{
    const int lo = app_params[c->id].min_exclusive ? x > c->min : x >= c->min;
    return lo && x <= c->max;
}

/* the index of name among values ("a|b|c"), or -1 */
static int enum_index(const char *values, const char *name)
{
    const size_t n = strlen(name);
    int k = 0;
    for (const char *p = values; *p != '\0'; k++) {
        const char *bar = strchr(p, '|');
        const size_t len = bar != NULL ? (size_t)(bar - p) : strlen(p);
        if (len == n && strncmp(p, name, n) == 0) {
            return k;
        }
        p += len + (bar != NULL ? 1u : 0u);
    }
    return -1;
}

/* The value of a table parameter's option (its unit; a vec3 "X,Y,Z") into cfg; 0 on
 * success, -1 when it is malformed or out of range. */
static int parse_param(const params_cli_t *c, const char *v, app_config_t *cfg)
{
    const app_param_t *p = &app_params[c->id];
    nav_real_t si[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    if (p->type == APP_PARAM_ENUM) {
        const int k = enum_index(c->values, v);
        if (k < 0) {
            return -1;
        }
        si[0] = (nav_real_t)k;
    } else if (p->type == APP_PARAM_VEC3) {
        double x[3] = {0.0, 0.0, 0.0};
        char tail = 0;
        if (sscanf(v, "%lf,%lf,%lf%c", &x[0], &x[1], &x[2], &tail) != 3) {
            return -1;
        }
        for (int i = 0; i < 3; i++) {
            if (!isfinite(x[i]) || !in_range(c, x[i])) {
                return -1;
            }
            si[i] = (nav_real_t)(x[i] * c->to_si);
        }
    } else {
        double x = 0.0;
        if (parse_double(v, &x) != 0 || !in_range(c, x) ||
            (p->type == APP_PARAM_U16 && floor(x) < x)) {
            return -1;
        }
        si[0] = (nav_real_t)(x * c->to_si);
    }
    return app_param_set(cfg, c->id, si);
}

/* The configuration against app_config_check's rules (the application's own, so the
 * parser accepts nothing app_init refuses): 0, or 2 with the broken rule said. */
static int config_check(const app_config_t *cfg, char *err, size_t err_len)
{
    static const char *const said[] = {
        [APP_CONFIG_RANGE] = "a parameter is out of its range",
        [APP_CONFIG_UDS_ON_NAV] = "a UDS ID is one of navecu's CAN IDs",
        [APP_CONFIG_CAN_IDS] = "navecu's CAN IDs must be 11-bit and distinct",
        [APP_CONFIG_UDS_SAME] = "the UDS request and response IDs must differ",
        [APP_CONFIG_RATES] = "output rates cannot exceed the IMU rate",
    };
    const app_config_rule_t rule = app_config_check(cfg);
    if (rule == APP_CONFIG_OK) {
        return 0;
    }
    say(err, err_len, said[rule], "", "");
    for (size_t i = 0u; rule == APP_CONFIG_UDS_ON_NAV && i < (size_t)NAVECU_MSG_N; i++) {
        if (cfg->can_ids[i] == cfg->uds_request_id || cfg->can_ids[i] == cfg->uds_response_id) {
            if (err != NULL && err_len > 0u) {
                (void)snprintf(err, err_len,
                               "a UDS ID is one of navecu's CAN IDs: 0x%03X is both; move the "
                               "UDS IDs (--uds-request-id, --uds-response-id) or that message "
                               "(the vehicle profile's can_ids)",
                               (unsigned)cfg->can_ids[i]);
            }
            break;
        }
    }
    return 2;
}

static const params_cli_t *param_option(const char *name)
{
    for (size_t k = 0u; k < (size_t)PARAMS_CLI_N; k++) {
        if (strcmp(params_cli[k].option, name) == 0) {
            return &params_cli[k];
        }
    }
    return NULL;
}

int host_options_parse(int argc, char **argv, host_options_t *o, char *err, size_t err_len)
{
    return host_options_parse_over(argc, argv, NULL, o, err, err_len);
}

int host_options_parse_over(int argc, char **argv, const app_config_t *base, host_options_t *o,
                            char *err, size_t err_len)
{
    memset(o, 0, sizeof *o);
    o->cfg = base != NULL ? *base : app_default_config();
    if (err != NULL && err_len > 0u) {
        err[0] = '\0';
    }
    /* --imu-preset first, wherever it is: the other options override its figures */
    for (int i = 1; i + 1 < argc; i += 2) {
        if (strcmp(argv[i], "--imu-preset") == 0) {
            int found = 0;
            for (int k = 0; k < (int)APP_PRESET_N; k++) {
                if (strcmp(argv[i + 1], app_preset_names[k]) == 0) {
                    found = app_config_preset(&o->cfg, (app_preset_id_t)k) == 0;
                }
            }
            if (!found) {
                say(err, err_len, "unknown --imu-preset '", argv[i + 1], "'");
                return 2;
            }
        }
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
        } else if (strcmp(a, "--imu-preset") == 0) {
            /* applied above */
        } else if (strcmp(a, "--test-stall-poll-s") == 0) {
            double x = 0.0;
            bad = parse_double(v, &x) != 0 || x < 0.0 || x > 1e6;
            o->stall_poll_us = bad ? 0u : (uint64_t)(x * 1e6); /* no conversion out of range */
            o->stall_poll = 1;
        } else if (strcmp(a, "--report-filter-at-s") == 0) {
            double x = 0.0;
            bad = parse_double(v, &x) != 0 || x < 0.0 || x > 1e6;
            o->report_filter_ms = bad ? 0u : (uint64_t)(x * 1e3); /* no conversion out of range */
            o->report_filter = 1;
        } else if (param_option(a) != NULL) {
            bad = parse_param(param_option(a), v, &o->cfg) != 0;
            o->nav_rate_given |= strcmp(a, "--nav-rate-hz") == 0;
            o->dyn_rate_given |= strcmp(a, "--dyn-rate-hz") == 0;
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
    return config_check(&o->cfg, err, err_len);
}
