/*
 * test_fuzz_regressions.c - every input the libFuzzer harnesses found violating an
 * invariant (tests/fuzz/README.md), replayed through the same harness code and invariant
 * checks, built with gcc like the other tests: a violation fails the test with the
 * harness's message instead of aborting.
 *
 * Inputs: tests/fuzz/crashes/<harness>/<name> (run from the repository root, as make
 * does); every file there is replayed, so a new crash needs only its file. Found so far,
 * and what was done:
 *  - fuzz_codec/heading-correction-max: NAV_Calibration.HeadingCorrection raw 32767 is in
 *    range, but decodes to 32.767002 (float32), which the generated
 *    is_in_phys_range (<= 32.767f) refuses: a rounding edge of cantools' float codec,
 *    now checked to within 1 ulp (codec_check.h);
 *  - fuzz_options/nav-rate-above-imu-rate: app_init accepted nav_rate_hz 50 with
 *    imu_rate_hz 32 (app.h: nav_rate_hz and status_rate_hz <= imu_rate_hz): app_init
 *    refuses it now;
 *  - fuzz_options/pitch-beyond-90: with the Kalman filter running, NAV_Attitude.Pitch was
 *    sent as 90.71 deg, outside the DBC range [-90, 90]: emit_navigation subtracted the
 *    filter's mounting pitch from a SINS pitch of 89.7 deg without limiting the result
 *    (default configuration but for --imu-rate-hz 239): the pitch is limited now;
 *  - fuzz_cmdline/stall-poll-out-of-range: `--test-stall-poll-s 2.4e93` was refused, but
 *    the value was converted to microseconds first (a double far beyond uint64_t cast:
 *    undefined behaviour, UBSan in the CI's fuzz run): the conversion now follows the
 *    range check (host_sim/options.c). Only the ASan+UBSan build of this test can see it;
 *  - fuzz_cmdline/uds-request-id-equals-response-id, uds-response-id-equals-request-id,
 *    uds-request-id-is-a-navecu-id: the parser accepted UDS IDs that collide with each
 *    other or with one of navecu's CAN IDs, which app_init refuses (CI's fuzz run, 42 s):
 *    the parser now says which ID collides, and ends with app_config_valid.
 */
#include <dirent.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "fuzz/fuzz_fail.h"

/* the harnesses themselves, their entry points renamed, and their shared checks */
#include "fuzz/codec_check.c"
#include "fuzz/fuzz_app_common.c"
#define LLVMFuzzerTestOneInput fuzz_codec_one
#include "fuzz/fuzz_codec.c"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_options_one
#include "fuzz/fuzz_options.c"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_cmdline_one
#include "fuzz/fuzz_cmdline.c"
#undef LLVMFuzzerTestOneInput

#define CRASH_DIR "tests/fuzz/crashes"
#define MAX_INPUTS 256

typedef struct {
    char path[512];
    int (*one)(const uint8_t *, size_t);
} input_t;

static input_t inputs[MAX_INPUTS];
static size_t n_inputs;
static const char *current = "";

void fuzz_fail(const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    fail_msg("%s: %s", current, msg);
    abort(); /* not reached: fail_msg leaves the test */
}

static int by_path(const void *a, const void *b)
{
    return strcmp(((const input_t *)a)->path, ((const input_t *)b)->path);
}

/* every file of CRASH_DIR/<harness>/, for the harness's entry point */
static void collect(const char *harness, int (*one)(const uint8_t *, size_t))
{
    char dir[256];
    (void)snprintf(dir, sizeof dir, "%s/%s", CRASH_DIR, harness);
    DIR *d = opendir(dir);
    if (d == NULL) {
        return;
    }
    const struct dirent *e;
    while ((e = readdir(d)) != NULL && n_inputs < MAX_INPUTS) {
        if (e->d_name[0] != '.') {
            input_t *in = &inputs[n_inputs++];
            (void)snprintf(in->path, sizeof in->path, "%s/%s", dir, e->d_name);
            in->one = one;
        }
    }
    (void)closedir(d);
}

/* one input through its harness: the harness's invariants call fuzz_fail */
static void replay(void **state)
{
    static uint8_t buf[1u << 16];
    const input_t *in = *state;
    current = in->path;
    FILE *f = fopen(in->path, "rb");
    assert_non_null(f);
    const size_t len = fread(buf, 1u, sizeof buf, f);
    assert_int_equal(ferror(f), 0);
    (void)fclose(f);
    (void)in->one(buf, len);
}

int main(void)
{
    static struct CMUnitTest tests[MAX_INPUTS];
    collect("fuzz_codec", fuzz_codec_one);
    collect("fuzz_options", fuzz_options_one);
    collect("fuzz_cmdline", fuzz_cmdline_one);
    if (n_inputs == 0u) {
        fprintf(stderr, "test_fuzz_regressions: no inputs under %s (run from the repository "
                        "root)\n", CRASH_DIR);
        return 1;
    }
    qsort(inputs, n_inputs, sizeof inputs[0], by_path);
    for (size_t k = 0u; k < n_inputs; k++) {
        tests[k].name = inputs[k].path;
        tests[k].test_func = replay;
        tests[k].initial_state = &inputs[k];
    }
    return _cmocka_run_group_tests("fuzz regressions", tests, n_inputs, NULL, NULL);
}
