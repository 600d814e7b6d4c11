/*
 * fuzz_cmdline.c - libFuzzer harness: navecu's command line (host_sim/options.c).
 *
 * Input: the arguments, separated by NUL bytes (at most CMDLINE_MAX_ARGS of them; argv[0] is
 * "navecu"). host_options_parse gets them as they are: any bytes, no terminating NUL
 * needed at the end of the input (the harness copies and terminates).
 *
 * Invariants: the parser never crashes or reads past an argument (ASan); it returns 0 or
 * 2; on 2 it describes the error (a non-empty, NUL-terminated message within its
 * buffer); on 0 without --help, either a log run (input and output given) or a live run
 * (an interface of 1..15 characters), never both, and app_init accepts the configuration
 * (the parser's ranges are inside the application's).
 */
#include <stdint.h>
#include <string.h>

#include "app.h"
#include "fuzz_fail.h"
#include "options.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define CMDLINE_MAX_ARGS 32u
#define CMDLINE_MAX_INPUT 4096u

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char buf[CMDLINE_MAX_INPUT + 1u];
    static char prog[] = "navecu";
    static app_t cmd_app;
    char *argv[CMDLINE_MAX_ARGS + 2u];
    if (size > CMDLINE_MAX_INPUT) {
        size = CMDLINE_MAX_INPUT;
    }
    memcpy(buf, data, size);
    buf[size] = '\0';
    int argc = 0;
    argv[argc++] = prog;
    size_t start = 0u;
    for (size_t i = 0u; i <= size && argc < (int)CMDLINE_MAX_ARGS + 1; i++) {
        if (i == size || buf[i] == '\0') {
            argv[argc++] = &buf[start];
            start = i + 1u;
        }
    }
    argv[argc] = NULL;

    host_options_t o;
    char err[96];
    memset(err, 'x', sizeof err);
    const int rc = host_options_parse(argc, argv, &o, err, sizeof err);
    if (rc != 0 && rc != 2) {
        fuzz_fail("host_options_parse returned %d", rc);
    }
    if (rc == 2) {
        if (memchr(err, '\0', sizeof err) == NULL || err[0] == '\0') {
            fuzz_fail("a usage error without a message");
        }
        return 0;
    }
    if (o.help) {
        return 0;
    }
    const int log_run = o.in_path != NULL && o.out_path != NULL;
    const int live_run = o.live_if != NULL;
    if (log_run == live_run) {
        fuzz_fail("accepted: log run %d, live run %d (exactly one expected)", log_run, live_run);
    }
    if (live_run && (strlen(o.live_if) == 0u || strlen(o.live_if) > 15u)) {
        fuzz_fail("accepted an interface name of %zu characters", strlen(o.live_if));
    }
    if (app_init(&cmd_app, &o.cfg) != 0) {
        fuzz_fail("the command line was accepted but app_init refuses its configuration");
    }
    return 0;
}
