/*
 * test_app_health.c - app_health.h: saturating counters, event stamps and their windows
 * on the IMU sample count, and the one way a rejection is reported (counted once, stamped
 * for REJECTED).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app_health.h"

static void test_count_saturates(void **state)
{
    (void)state;
    uint32_t c = 0u;
    app_count(&c);
    app_count(&c);
    assert_int_equal(c, 2u);
    c = UINT32_MAX - 1u;
    app_count(&c);
    assert_int_equal(c, UINT32_MAX);
    app_count(&c);
    assert_int_equal(c, UINT32_MAX); /* not wrapped to 0 */
}

static void test_count_n_saturates(void **state)
{
    (void)state;
    uint32_t c = 5u;
    app_count_n(&c, 7u);
    assert_int_equal(c, 12u);
    app_count_n(&c, 0u);
    assert_int_equal(c, 12u);
    c = UINT32_MAX - 3u;
    app_count_n(&c, 3u);
    assert_int_equal(c, UINT32_MAX);
    c = UINT32_MAX - 3u;
    app_count_n(&c, 4u);
    assert_int_equal(c, UINT32_MAX);
    c = 1u;
    app_count_n(&c, 1ull << 40); /* a 64-bit count beyond 32 bits */
    assert_int_equal(c, UINT32_MAX);
    c = 0u;
    app_count_n(&c, (uint64_t)UINT32_MAX + 1u);
    assert_int_equal(c, UINT32_MAX);
}

/* GIVEN an event at sample 100 THEN it is within a window of w samples up to sample
 * 100 + w and not after; an event never seen is within no window. */
static void test_stamp_windows(void **state)
{
    (void)state;
    app_stamp_t s;
    memset(&s, 0, sizeof s);
    assert_int_equal(app_stamp_within(&s, 0u, UINT64_MAX), 0);
    app_stamp(&s, 100u);
    assert_int_equal(s.seen, 1);
    assert_int_equal(app_stamp_within(&s, 100u, 0u), 1);
    assert_int_equal(app_stamp_within(&s, 101u, 0u), 0);
    assert_int_equal(app_stamp_within(&s, 150u, 50u), 1);
    assert_int_equal(app_stamp_within(&s, 151u, 50u), 0);
    /* a later stamp moves the window */
    app_stamp(&s, 200u);
    assert_int_equal(app_stamp_within(&s, 250u, 50u), 1);
    /* a stamp of a sample still to come (a time base that restarted below it) is not
     * "within": the unsigned difference is huge */
    assert_int_equal(app_stamp_within(&s, 199u, 1000u), 0);
}

/* A rejection: its counter + 1, nothing else counted, REJECTED stamped now. */
static void test_diag_reject(void **state)
{
    (void)state;
    app_health_t h;
    app_events_t ev;
    memset(&h, 0, sizeof h);
    memset(&ev, 0, sizeof ev);
    const app_diag_t d = {&h, &ev, 4242u, 0u};
    app_diag_reject(&d, &h.bad_crc);
    app_diag_reject(&d, &h.bad_crc);
    app_diag_reject(&d, &h.gnss_rejected);
    assert_int_equal(h.bad_crc, 2u);
    assert_int_equal(h.gnss_rejected, 1u);
    app_health_t expect;
    memset(&expect, 0, sizeof expect);
    expect.bad_crc = 2u;
    expect.gnss_rejected = 1u;
    assert_memory_equal(&h, &expect, sizeof h);
    assert_int_equal(ev.reject.seen, 1);
    assert_int_equal(ev.reject.sample, 4242u);
    assert_int_equal(ev.gap.seen, 0);
    assert_int_equal(ev.odo_reject.seen, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_count_saturates),
        cmocka_unit_test(test_count_n_saturates),
        cmocka_unit_test(test_stamp_windows),
        cmocka_unit_test(test_diag_reject),
    };
    return cmocka_run_group_tests_name("app_health", tests, NULL, NULL);
}
