/*
 * options.h - navecu's command line: parsed into the application's configuration and the
 * host's run settings (usage text: host_sim/main.c --help).
 */
#ifndef NAVECU_HOST_OPTIONS_H
#define NAVECU_HOST_OPTIONS_H

#include <stddef.h>
#include <stdint.h>

#include "app.h"

typedef struct {
    const char *in_path;   /* --can-log */
    const char *out_path;  /* --out */
    const char *nvm_path;  /* --nvm */
    const char *iface;     /* --iface */
    const char *live_if;   /* --can */
    int nav_rate_given;    /* --nav-rate-hz was given */
    int dyn_rate_given;    /* --dyn-rate-hz was given */
    int stall_poll;        /* --test-stall-poll-s given: stop calling app_poll ... */
    uint64_t stall_poll_us; /* ... this long after the first frame */
    int report_filter;     /* --report-filter-at-s given: print the filter's figures ... */
    uint64_t report_filter_ms; /* ... once this much IMU time has passed (host_filter_report) */
    int help;              /* --help or -h: nothing else was parsed */
    app_config_t cfg;      /* the defaults (or the base) with the options applied */
} host_options_t;

/*
 * Parse argv[1..argc) into *o (argv's strings are referenced, not copied). Returns 0 (check
 * o->help), or 2 on a usage error, described in err[0..err_len) (NUL-terminated; err may
 * be NULL). Every numeric value is range-checked; the result still goes through
 * app_init, which refuses what the application cannot run with.
 */
int host_options_parse(int argc, char **argv, host_options_t *o, char *err, size_t err_len);

/* host_options_parse with the options applied over *base instead of the defaults (NULL:
 * the defaults): the command line as the top configuration layer, over the NVM's
 * (app_start; docs/configuration.md). */
int host_options_parse_over(int argc, char **argv, const app_config_t *base, host_options_t *o,
                            char *err, size_t err_len);

#endif /* NAVECU_HOST_OPTIONS_H */
