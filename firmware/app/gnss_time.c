/* gnss_time.c - GNSS time of validity on the IMU time base; see gnss_time.h. */
#include "gnss_time.h"

static void gnss_time_unlearn(gnss_time_t *g);

/* the last latency candidate */
static const uint32_t lat_last = APP_GNSS_LAT_BINS - 1u;

/* IMU samples per history entry: at most APP_VHIST_MAX_HZ entries per second */
static uint32_t vhist_div(uint32_t imu_rate_hz)
{
    return (imu_rate_hz + APP_VHIST_MAX_HZ - 1u) / APP_VHIST_MAX_HZ;
}

void gnss_time_record(gnss_time_t *g, uint64_t n_samples, uint32_t imu_rate_hz,
                      const nav_real_t v_n_mps[3])
{
    if (n_samples % vhist_div(imu_rate_hz) != 0u) {
        return;
    }
    for (int i = 0; i < 3; i++) {
        g->vhist[g->vhist_n % APP_VHIST][i] = v_n_mps[i];
    }
    g->vhist_n++;
}

/* w's lateness (late_us beyond the on-time epochs' offset; none if below), entry spacing
 * and reach back. Out of line (noinline): GCC inlined it at both its calls, 16 bytes more
 * of the ECU's flash (docs/target.md); it runs per GNSS epoch, not per IMU sample. */
__attribute__((noinline)) static void when_late(const gnss_time_t *g, gnss_when_t *w, int64_t late_us,
                      uint32_t imu_rate_hz, nav_real_t latency_s)
{
    w->late_s = late_us > 0 ? (nav_real_t)late_us * NAV_C(1e-6) : NAV_C(0.0);
    w->entry_s = (nav_real_t)vhist_div(imu_rate_hz) / (nav_real_t)imu_rate_hz;
    gnss_time_reach(g, w, latency_s);
}

/* the epoch's offset: IMU time less the receiver's time of week, us */
static int64_t offset_us(uint64_t imu_t_us, uint32_t tow_ms)
{
    return (int64_t)imu_t_us - (int64_t)tow_ms * 1000;
}

/* The time of week restarts at 0 every week: an offset a week (more than half of one)
 * away from the minimum is the same clock, not a jump (it was counted as one, and the
 * learnt latency forgotten). The week that the minimum is of: +-1 week to reach off.
 * Out of line (noinline), as when_late: 56 bytes of the ECU's flash inlined at its two
 * calls, per GNSS epoch. */
__attribute__((noinline)) static int64_t week_step_us(const gnss_time_t *g, int64_t off)
{
    const int64_t week_us = (int64_t)APP_WEEK_MS * 1000;
    if (g->off_valid && off - g->off_min_us > week_us / 2) {
        return week_us;
    }
    if (g->off_valid && off - g->off_min_us < -week_us / 2) {
        return -week_us;
    }
    return 0;
}

gnss_when_t gnss_time_align(gnss_time_t *g, uint64_t imu_t_us, uint32_t imu_rate_hz,
                            uint32_t tow_ms, nav_real_t latency_s)
{
    gnss_when_t w;
    const int64_t t_imu_us = (int64_t)imu_t_us;
    const int64_t off = offset_us(imu_t_us, tow_ms);
    /* a new week: the minimum moves to it, so that it stays the latest epoch's (NAV_Time
     * takes the week from the fixes: gnss_time_at) */
    g->off_min_us += week_step_us(g, off);
    if (g->min_suspect != 0u) {
        g->min_suspect = 0u; /* the one set in an IMU gap: this epoch's instead */
        g->off_min_us = off;
        g->lowered = 1u;
    }
    /* A step earlier by more than 1 s, later by more than 10 s, or later by more than
     * 0.5 s three epochs in a row is a time jump; a late epoch moves the offset once. */
    const int64_t excess = off - g->off_min_us;
    g->late_run = (uint8_t)(g->off_valid && excess > APP_GNSS_LATE_US
                                ? (g->late_run < 255u ? g->late_run + 1u : 255u)
                                : 0u);
    const int jumped = g->off_valid && (excess < -APP_GNSS_JUMP_EARLY_US ||
                                        excess > APP_GNSS_JUMP_LATE_US ||
                                        g->late_run >= APP_GNSS_LATE_RUN);
    w.jumped = jumped ? 1u : 0u;
    if (jumped) {
        g->late_run = 0u;
    }
    if (!g->off_valid || off < g->off_min_us || jumped) {
        g->lowered = 1u;
        g->off_min_us = off; /* first epoch, an earlier one, or a time jump */
        g->off_valid = 1u;
    } else {
        /* the minimum may creep up by 50 ppm of the IMU time elapsed (clock drift) */
        g->off_min_us += (t_imu_us - g->prev_t_us) / APP_GNSS_DRIFT_DIV;
        if (off < g->off_min_us) {
            g->off_min_us = off;
        }
    }
    g->prev_t_us = t_imu_us;
    if (jumped) {
        gnss_time_unlearn(g); /* a receiver reset: its latency may be another */
    }
    when_late(g, &w, off - g->off_min_us, imu_rate_hz, latency_s); /* off >= off_min_us */
    return w;
}

void gnss_time_imu_next(gnss_time_t *g, int gap)
{
    if (g->lowered != 0u && gap != 0) {
        g->min_suspect = 1u;
    }
    g->lowered = 0u;
}

gnss_when_t gnss_time_peek(const gnss_time_t *g, uint64_t imu_t_us, uint32_t imu_rate_hz,
                           uint32_t tow_ms, nav_real_t latency_s)
{
    gnss_when_t w;
    const int64_t off = offset_us(imu_t_us, tow_ms);
    const int64_t late = off - (g->off_min_us + week_step_us(g, off));
    w.jumped = 0u;
    when_late(g, &w, late, imu_rate_hz, latency_s);
    if (g->off_valid == 0u || late > APP_GNSS_LATE_US) {
        w.in_history = 0u;
        w.before_history = 0u;
    }
    return w;
}

/* does the history reach back entries back (one more for the interpolation)? */
static int reaches(const gnss_time_t *g, nav_real_t back)
{
    const uint32_t m = (uint32_t)back;
    return m + 1u < APP_VHIST && m + 1u < g->vhist_n;
}

void gnss_time_reach(const gnss_time_t *g, gnss_when_t *w, nav_real_t latency_s)
{
    w->back = (latency_s + w->late_s) / w->entry_s;
    w->in_history = reaches(g, w->back) ? 1u : 0u;
    const uint32_t m = (uint32_t)w->back;
    w->before_history = !w->in_history && m + 1u < APP_VHIST ? 1u : 0u;
}

/* Forget the latency learnt (a receiver reset). */
static void gnss_time_unlearn(gnss_time_t *g)
{
    for (uint32_t k = 0u; k < APP_GNSS_LAT_BINS; k++) {
        g->lat_cost[k] = NAV_C(0.0);
    }
    g->lat_learnt = 0u;
    g->lat_bin = 0u;
}

/* the candidate nearest a latency (the parameter's), within the range */
static uint32_t bin_of(nav_real_t latency_s)
{
    const nav_real_t k = latency_s / APP_GNSS_LAT_STEP_S + NAV_C(0.5);
    if (!(k > NAV_C(0.0))) {
        return 0u;
    }
    return k < (nav_real_t)lat_last ? (uint32_t)k : lat_last;
}

int gnss_time_learn(gnss_time_t *g, gnss_when_t *w, const nav_real_t v_enu_mps[3],
                    nav_real_t sigma_mps, nav_real_t latency_cfg_s)
{
    const nav_real_t far_s = APP_GNSS_LAT_STEP_S * (nav_real_t)lat_last;
    /* on time (late by less than a history entry), every candidate in the history */
    if (!(w->late_s < w->entry_s) || !reaches(g, far_s / w->entry_s) || !(sigma_mps > NAV_C(0.0))) {
        return 0;
    }
    const nav_real_t inv_var = NAV_C(1.0) / (sigma_mps * sigma_mps);
    uint32_t best = 0u;
    for (uint32_t k = 0u; k < APP_GNSS_LAT_BINS; k++) {
        /* the navigator's velocity tau_k before the arrival, interpolated in the history */
        const nav_real_t back = APP_GNSS_LAT_STEP_S * (nav_real_t)k / w->entry_s;
        const uint32_t m = (uint32_t)back;
        const nav_real_t f = back - (nav_real_t)m;
        const nav_real_t *a = g->vhist[(g->vhist_n - 1u - m) % APP_VHIST];
        const nav_real_t *b = g->vhist[(g->vhist_n - 2u - m) % APP_VHIST];
        nav_real_t e2 = NAV_C(0.0);
        for (int i = 0; i < 2; i++) {
            const nav_real_t e = v_enu_mps[i] - (a[i] + f * (b[i] - a[i]));
            e2 += e * e;
        }
        e2 *= inv_var;
        g->lat_cost[k] = APP_GNSS_LAT_FADE * g->lat_cost[k] +
                         (e2 < APP_GNSS_LAT_TERM_MAX ? e2 : APP_GNSS_LAT_TERM_MAX);
        if (g->lat_cost[k] < g->lat_cost[best]) {
            best = k;
        }
    }
    const uint32_t used = g->lat_learnt ? (uint32_t)g->lat_bin : bin_of(latency_cfg_s);
    if (best == used || !(g->lat_cost[used] - g->lat_cost[best] > APP_GNSS_LAT_EVIDENCE)) {
        return 0;
    }
    g->lat_bin = (uint8_t)best;
    g->lat_learnt = 1u;
    gnss_time_reach(g, w, gnss_time_latency(g, latency_cfg_s));
    return 1;
}

/* Out of line (noinline), as gnss_tow_diff_ms: GCC inlined it at its six calls (the GNSS
 * updates, NAV_Time); one copy is 128 bytes less of the ECU's flash (docs/target.md) */
__attribute__((noinline)) nav_real_t gnss_time_latency(const gnss_time_t *g,
                                                       nav_real_t latency_cfg_s)
{
    return g->lat_learnt ? APP_GNSS_LAT_STEP_S * (nav_real_t)g->lat_bin : latency_cfg_s;
}

void gnss_time_displacement(const gnss_time_t *g, const gnss_when_t *w, nav_real_t d_n_m[3])
{
    /* position then = now - integral of v over tau (latest samples first) */
    const uint32_t m = (uint32_t)w->back;
    d_n_m[0] = d_n_m[1] = d_n_m[2] = NAV_C(0.0);
    for (uint32_t j = 0u; j <= m; j++) {
        const nav_real_t wt = j < m ? w->entry_s : (w->back - (nav_real_t)m) * w->entry_s;
        const nav_real_t *v = g->vhist[(g->vhist_n - 1u - j) % APP_VHIST];
        for (int i = 0; i < 3; i++) {
            d_n_m[i] += wt * v[i];
        }
    }
}

/* out of line (noinline), as when_late: inlined at its two calls (fusion.c's GNSS and raw
 * epochs), 24 bytes more of the ECU's flash */
__attribute__((noinline)) const nav_real_t *gnss_time_velocity_then(const gnss_time_t *g,
                                                                    const gnss_when_t *w)
{
    return g->vhist[(g->vhist_n - 1u - (uint32_t)(w->back + NAV_C(0.5))) % APP_VHIST];
}

void gnss_time_forget(gnss_time_t *g)
{
    g->vhist_n = 0u;
}

void gnss_time_week(gnss_time_t *g, uint16_t gps_week)
{
    g->gps_week = gps_week;
    g->have_week = 1u;
}

#define US_PER_WEEK ((int64_t)APP_WEEK_MS * INT64_C(1000))

__attribute__((noinline)) int64_t gnss_tow_diff_ms(uint32_t a_ms, uint32_t b_ms)
{
    const int64_t week = (int64_t)APP_WEEK_MS;
    const int64_t half = week / 2;
    int64_t d = (int64_t)a_ms - (int64_t)b_ms;
    if (d < -half) {
        d += week;
    } else if (d > half) {
        d -= week;
    } else {
        /* within half a week */
    }
    return d;
}

int gnss_time_at(const gnss_time_t *g, uint64_t imu_t_us, nav_real_t latency_s,
                 uint64_t *tow_us, uint16_t *gps_week)
{
    if (!g->off_valid) {
        return -1;
    }
    const int64_t t_imu_us = (int64_t)imu_t_us;
    const int64_t latency_us = (int64_t)(latency_s * NAV_C(1e6) + NAV_C(0.5));
    int64_t tow = t_imu_us - g->off_min_us + latency_us;
    int32_t week = g->have_week ? (int32_t)g->gps_week : -1;
    if (tow >= US_PER_WEEK) { /* the week ended since the last epoch */
        tow -= US_PER_WEEK;
        week = week >= 0 ? week + 1 : week;
    } else if (tow < 0) {
        tow += US_PER_WEEK;
        week = week > 0 ? week - 1 : week;
    }
    *tow_us = tow >= 0 && tow < US_PER_WEEK ? (uint64_t)tow : 0u;
    *gps_week = week >= 0 && week < 65535 ? (uint16_t)week : 65535u;
    return 0;
}
