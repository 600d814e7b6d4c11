/* app_health.c - counters and event stamps; see app_health.h. */
#include "app_health.h"

void app_count(uint32_t *c)
{
    if (*c < UINT32_MAX) {
        (*c)++;
    }
}

/* out of line (noinline): inlined at its seven calls it took 8 bytes more */
__attribute__((noinline)) void app_count_n(uint32_t *c, uint64_t n)
{
    *c = n > UINT32_MAX - *c ? UINT32_MAX : *c + (uint32_t)n;
}

/* app_stamp and app_stamp_within out of line (noinline): the link inlined them at their
 * calls across the application, 96 bytes more of the ECU's flash (docs/target.md). At an
 * event, a status or a GNSS epoch; per IMU sample only output_mode's one call. */
__attribute__((noinline)) void app_stamp(app_stamp_t *s, uint64_t n)
{
    s->sample = n;
    s->seen = 1u;
}

__attribute__((noinline)) int app_stamp_within(const app_stamp_t *s, uint64_t n,
                                               uint64_t window)
{
    return s->seen && n - s->sample <= window;
}

void app_diag_reject(const app_diag_t *d, uint32_t *counter)
{
    app_count(counter);
    app_stamp(&d->events->reject, d->n_samples);
}
