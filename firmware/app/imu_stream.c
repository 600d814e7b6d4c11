/* imu_stream.c - IMU pairing, counter, gaps and plausibility; see imu_stream.h. */
#include "imu_stream.h"

#include <string.h>

#include "app_tuning.h"

void imu_link_init(imu_link_t *l, uint32_t rate_hz, nav_real_t gyro_range_rps,
                   nav_real_t accel_range_mps2, uint32_t accel_id)
{
    memset(l, 0, sizeof *l);
    l->rate_hz = rate_hz;
    l->accel_id = accel_id;
    /* at most 100 rad/s and 2000 m/s^2 (app_config_valid) over 0.1 s: within int32 */
    const nav_real_t dt = NAV_C(1.0) / (nav_real_t)rate_hz;
    const nav_real_t w_lim = gyro_range_rps * dt * APP_IMU_SAT_FRACTION / app_rx_angle_lsb_rad();
    const nav_real_t v_lim = accel_range_mps2 * dt * APP_IMU_SAT_FRACTION / app_rx_vel_lsb_mps();
    l->sat_raw[0] = (int32_t)w_lim;
    l->sat_raw[1] = (int32_t)v_lim;
    const nav_real_t w_car = APP_STUCK_RATE_RPS * dt / app_rx_angle_lsb_rad();
    const nav_real_t v_car = APP_STUCK_ACCEL_MPS2 * dt / app_rx_vel_lsb_mps();
    l->stuck_raw[0] = w_car < w_lim ? (int32_t)w_car : l->sat_raw[0];
    l->stuck_raw[1] = v_car < v_lim ? (int32_t)v_car : l->sat_raw[1];
    l->noise_lsb[0] = APP_IMU_NOISE_MIN_LSB;
    l->noise_lsb[1] = APP_IMU_NOISE_MIN_LSB;
}

void imu_link_noise(imu_link_t *l, nav_real_t gyro_arw_rad_rts)
{
    const nav_real_t sigma_lsb = gyro_arw_rad_rts * nav_sqrt(NAV_C(1.0) / (nav_real_t)l->rate_hz) /
                                 app_rx_angle_lsb_rad();
    /* at most 0.03 rad/sqrt(s) (the parameter's range) at 1 Hz: 6e4 LSB, within uint32 */
    if (sigma_lsb > (nav_real_t)APP_IMU_NOISE_MIN_LSB) {
        l->noise_lsb[0] = (uint32_t)sigma_lsb;
    }
}

void imu_link_stamped(imu_link_t *l, int stamped)
{
    l->stamped = stamped ? 1u : 0u;
}

void imu_stream_time(imu_stream_t *s, const imu_link_t *l, uint8_t counter, uint32_t t_us)
{
    if (l->stamped == 0u) {
        return;
    }
    s->time_valid = 1u;
    s->time_counter = counter;
    s->time_us = t_us;
}

/* The stamped interval of a sample whose counter stepped by step and the whole counter
 * cycles the stamps show beyond the counter, or refuse: no stamp of its counter, a stamp
 * not after the previous one (back: only that restarts the stamps' time base when it
 * lasts), an interval outside the band. */
typedef struct {
    int refuse;
    int back;
    uint32_t dt_us;
    uint64_t cycles;  /* lost samples seen only in the stamps (whole counter cycles) */
} stamp_check_t;

static stamp_check_t check_stamp(const imu_stream_t *s, const imu_link_t *l, uint8_t counter,
                                 int step)
{
    stamp_check_t r = {0, 0, 0u, 0u};
    if (!s->time_valid || s->time_counter != counter) {
        r.refuse = 1; /* the sample's own stamp is missing (or another sample's) */
        return r;
    }
    if (!l->have_stamp) {
        return r; /* the first stamp: no interval yet */
    }
    const uint32_t d = s->time_us - l->stamp_us; /* modulo 2^32: the clock wraps */
    if (d == 0u || d >= 0x80000000u) {
        r.refuse = 1; /* the stamp is not after the previous one */
        r.back = 1;
        return r;
    }
    const uint64_t period_us = 1000000u / l->rate_hz;
    uint64_t n = (uint64_t)step;
    /* like receive time on the grid, but exact: beyond half a counter cycle more than the
     * counter's step, the stamps count whole lost cycles of 15 */
    const uint64_t by_stamp = ((uint64_t)d + period_us / 2u) / period_us;
    if (by_stamp > n + APP_IMU_GAP_SLACK_PERIODS) {
        r.cycles = (by_stamp - n + APP_IMU_GAP_SLACK_PERIODS) / 15u * 15u;
        n += r.cycles;
    }
    /* each of the n samples within [0.5, 1.5] nominal periods */
    const uint64_t dd = (uint64_t)d * APP_IMU_TIME_BAND_DIV;
    if (dd < n * period_us || dd > n * period_us * APP_IMU_TIME_BAND_MUL) {
        r.refuse = 1;
        return r;
    }
    r.dt_us = d;
    return r;
}

int imu_stream_rate(imu_stream_t *s, uint8_t counter, const int32_t raw[3],
                    const uint8_t data[8])
{
    int broken = 0;
    if (s->n_pending == IMU_PENDING_MAX) {
        s->pending[0] = s->pending[1]; /* the oldest got no IMU_Accel */
        s->n_pending--;
        broken = 1;
    }
    imu_half_t *h = &s->pending[s->n_pending++];
    h->counter = counter;
    memcpy(h->data, data, 8u);
    h->raw[0] = raw[0];
    h->raw[1] = raw[1];
    h->raw[2] = raw[2];
    return broken;
}

/* ---- plausibility (docs/reliability.md) ----
 * Saturation: a rate or specific force at the configured range of the IMU (the sensor
 * clips there, so what it reports is not the motion). A stuck axis: its raw increment
 * repeats exactly for APP_IMU_STUCK_S or longer while another axis of the same sensor
 * shows the sensor's noise (app_tuning.h): a working axis of a sensor that noisy cannot
 * repeat its value that long (at a noise sigma of 4 LSB a value repeats the previous one
 * with probability 0.07, 20 times in a row at 10 Hz below 1e-22). An axis that repeats
 * on ideal, noiseless data (a rate exactly 0 on a flat road, a lateral acceleration
 * exactly 0 in a straight line) is not stuck: the other axes show no noise either. Counted
 * once per episode, flagged while it lasts (a stuck axis: while its value repeats, even
 * when the noise shown stops, as it may with the motion). The samples are still used,
 * since neither says what the true value was; the filter takes either as a sample of
 * unknown motion (app.c, sample_noise). */
static void plausibility(imu_plaus_t *p, const imu_link_t *l, const int32_t raw[6],
                         imu_sample_t *out)
{
    uint8_t saturated = 0u;
    for (int i = 0; i < 6; i++) {
        const int32_t lim = l->sat_raw[i < 3 ? 0 : 1];
        if (raw[i] >= lim || raw[i] <= -lim) {
            saturated |= (uint8_t)(1u << i);
        }
    }
    out->saturated = saturated;
    const uint32_t n_stuck = APP_IMU_STUCK_S * l->rate_hz;
    /* blocks of half the window: the last block and the one before lie within the last
     * n_stuck samples, i.e. within the time the stuck axis has been repeating */
    if (p->blk_n == 0u || p->blk_n >= n_stuck / 2u) {
        for (int i = 0; i < 6; i++) {
            p->prev_jit[i] = p->blk_jit[i];
            p->blk_jit[i] = 0u;
        }
        p->prev_n = p->blk_n;
        p->blk_n = 0u;
    }
    p->blk_n++;
    for (int i = 0; i < 6; i++) {
        if (p->hist >= 2u) {
            const int64_t e = (int64_t)raw[i] - 2 * (int64_t)p->last_raw[i] + (int64_t)p->last2_raw[i];
            const int64_t m = e < 0 ? -e : e;
            /* capped at 2^21 (a 20-bit value's most): a block of up to 1000 samples
             * stays within uint32 */
            p->blk_jit[i] += (uint32_t)(m < (int64_t)2097152 ? m : (int64_t)2097152);
        }
        p->last2_raw[i] = p->last_raw[i];
        /* the stream's own last sample (hist): after a navigation reset cleared it, the
         * first sample repeats nothing */
        p->same_n[i] = (p->hist > 0u && raw[i] == p->last_raw[i])
                           ? (p->same_n[i] < UINT32_MAX ? p->same_n[i] + 1u : UINT32_MAX)
                           : 0u;
        p->last_raw[i] = raw[i];
    }
    p->hist = (uint8_t)(p->hist < 2u ? p->hist + 1u : 2u);
    int repeating = 0;
    for (int i = 0; i < 6; i++) {
        repeating |= p->same_n[i] >= n_stuck;
        if (p->same_n[i] < n_stuck) {
            p->stuck_seen &= (uint8_t)~(1u << i); /* it moved: a new episode may come */
        }
    }
    if (!repeating) {
        return; /* the usual case: nothing more to look at */
    }
    /* the sensors (gyro, accelerometer) with an axis showing the noise */
    const uint64_t n_jit = (uint64_t)p->blk_n + p->prev_n;
    int noisy[2] = {0, 0};
    for (int j = 0; j < 6; j++) {
        const uint64_t sum = (uint64_t)p->blk_jit[j] + p->prev_jit[j];
        if (p->same_n[j] < n_stuck && sum >= (uint64_t)l->noise_lsb[j / 3] * n_jit) {
            noisy[j / 3] = 1;
        }
    }
    for (int i = 0; i < 6; i++) {
        const uint8_t bit = (uint8_t)(1u << i);
        if (p->same_n[i] >= n_stuck && noisy[i / 3] && (p->stuck_seen & bit) == 0u) {
            p->stuck_seen |= bit; /* counted once per episode */
            out->stuck_new++;
        }
    }
    /* found stuck while its sensor showed the noise, an axis stays stuck until it moves
     * (stuck_seen is cleared above; the noise shown may come and go with the motion) */
    out->stuck = p->stuck_seen;
}

imu_verdict_t imu_stream_accel(imu_stream_t *s, imu_link_t *l, uint8_t counter, uint8_t fault,
                               const int32_t raw[3], const uint8_t data[8], uint64_t t_us,
                               imu_sample_t *out)
{
    /* the waiting IMU_Rate of this counter whose pair CRC (one E2E data element in two
     * frames: it covers IMU_Rate too) matches, the newest first */
    int match = -1;
    int same_counter = 0;
    for (int k = (int)s->n_pending - 1; k >= 0 && match < 0; k--) {
        if (s->pending[k].counter == counter) {
            same_counter = 1;
            if (data[7] == e2e_pair_crc(l->accel_id, s->pending[k].data, data)) {
                match = k;
            }
        }
    }
    if (!same_counter) {
        /* an IMU_Accel of no waiting IMU_Rate (its IMU_Rate lost, or a foreign frame on
         * the identifier): refused; the waiting ones stay for their own IMU_Accel */
        return IMU_REJ_PAIR;
    }
    if (match < 0) {
        return IMU_REJ_CRC; /* this IMU_Accel is not theirs: they wait for the real one */
    }
    /* the older ones got no IMU_Accel; a newer one waits on (frames reordered on the bus) */
    const imu_half_t rate = s->pending[match];
    const uint8_t dropped = (uint8_t)match;
    uint8_t kept = 0u;
    for (uint8_t k = (uint8_t)(match + 1); k < s->n_pending; k++) {
        s->pending[kept++] = s->pending[k];
    }
    s->n_pending = kept;
    e2e_counter_t probe = l->counter;
    const int step = e2e_counter_step(&probe, counter);
    if (step <= 0) {
        return IMU_REJ_COUNTER; /* repeated sample or invalid counter */
    }
    /* a sample held for a counter jump is followed by one of its next few successors
     * (1..APP_IMU_MAX_DELTA after it, as lost frames may take the very next) */
    const int after_held = ((int)counter - (int)s->resync_counter + 15) % 15;
    const int follows = s->resync_valid != 0u && after_held >= 1 &&
                        after_held <= APP_IMU_MAX_DELTA;
    if (!follows && step >= 15 - APP_IMU_MAX_DELTA) {
        /* 1..4 behind the counter held: old data (or the counter held was itself a
         * corrupt one ahead of time): dropped until the counter catches up, so a wrong
         * counter never moves time ahead for good. */
        return IMU_REJ_COUNTER;
    }
    if ((follows && s->resync_valid < APP_IMU_JUMP_HELD) ||
        (!follows && step > APP_IMU_MAX_DELTA)) {
        /* E2E "wrong sequence": a corrupted counter, or a real gap of APP_IMU_MAX_DELTA
         * samples or more. The next samples decide: if APP_IMU_JUMP_HELD samples follow
         * one another from this one (held as well), the gap was real and is bridged at the
         * next (the held ones counted among the lost); if one follows the last good one,
         * these counters were wrong and only their samples are lost. Counter-only, so the
         * same at any replay speed. */
        s->resync_valid = (uint8_t)(follows ? s->resync_valid + 1u : 1u);
        s->resync_counter = counter;
        return IMU_REJ_COUNTER;
    }
    stamp_check_t st = {0, 0, 0u, 0u};
    uint8_t time_reset = 0u;
    if (l->stamped) {
        st = check_stamp(s, l, counter, step);
        const int own = s->time_valid && s->time_counter == counter;
        s->time_valid = 0u; /* a stamp serves its own sample or none: never a later one */
        if (st.refuse) {
            if (!own || !st.back || l->stamp_refused + 1u < APP_IMU_TIME_RESYNC) {
                l->stamp_refused = (uint8_t)(l->stamp_refused < UINT8_MAX ? l->stamp_refused + 1u
                                                                          : UINT8_MAX);
                return IMU_REJ_TIME; /* bridged, like a lost sample, by the next one */
            }
            /* refused APP_IMU_TIME_RESYNC times in a row, this one with a stamp of its own
             * behind the last one taken: the IMU's clock jumped back; its stamps are the
             * time base again from this sample on. (Intervals outside the band never
             * restart it: a clock that runs at another rate is the rate check's.) */
            time_reset = 1u;
            st.dt_us = 0u;
            st.cycles = 0u;
        }
        l->stamp_refused = 0u;
        l->stamp_us = s->time_us;
        l->have_stamp = 1u;
    }
    s->resync_valid = 0u;
    l->counter = probe;
    l->fault = fault ? 1u : 0u;
    memset(out, 0, sizeof *out);
    out->dropped = dropped;
    /* The 4-bit counter cannot see a gap of 15 samples or more. The receive time can:
     * when more than half a counter cycle beyond the counter's step has elapsed, add the
     * whole cycles it missed. (Time is used only here, for gaps; a replay at any speed
     * that keeps samples less than 7 periods apart gives the same result.) */
    out->lost = (uint64_t)step - 1u;
    out->dt_us = st.dt_us;
    out->time_reset = time_reset;
    if (l->stamped) {
        /* the stamps, not receive time, show the gaps the counter cannot see */
        if (st.cycles > 0u) {
            out->lost_by_time = st.cycles;
            out->lost += st.cycles;
            out->time_gap = 1u;
        }
    } else if (l->have_sample && t_us > l->last_t_us) {
        const uint64_t period_us = 1000000u / l->rate_hz;
        const uint64_t by_time = (t_us - l->last_t_us + period_us / 2u) / period_us;
        if (by_time > (uint64_t)step + APP_IMU_GAP_SLACK_PERIODS) {
            out->lost_by_time = (by_time - (uint64_t)step + APP_IMU_GAP_SLACK_PERIODS) / 15u * 15u;
            out->lost += out->lost_by_time;
            out->time_gap = 1u;
        }
    } else {
        /* the grid's first sample, or receive time not advancing: no gap to see */
    }
    for (int i = 0; i < 3; i++) {
        out->raw[i] = rate.raw[i];
        out->raw[i + 3] = raw[i];
    }
    for (int i = 0; i < 6; i++) {
        /* the last sample this stream took: none since a navigation reset cleared it
         * (app_reset; the link's counter goes on, so a gap across the reset is still
         * bridged, flat from this sample) */
        out->prev_raw[i] = s->plaus.hist > 0u ? s->plaus.last_raw[i] : out->raw[i];
    }
    plausibility(&s->plaus, l, out->raw, out);
    l->have_sample = 1u;
    l->last_t_us = t_us;
    return IMU_SAMPLE;
}

/* from + (to - from) * num / den, rounded to nearest (0 < num < den) */
static int32_t interpolate_raw(int32_t from, int32_t to, uint64_t num, uint64_t den)
{
    const int64_t d = (int64_t)to - (int64_t)from;
    const int64_t scaled = d * (int64_t)num;
    const int64_t half = (int64_t)den / 2;
    const int64_t q = scaled >= 0 ? (scaled + half) / (int64_t)den : -((-scaled + half) / (int64_t)den);
    return (int32_t)((int64_t)from + q);
}

void imu_stream_bridge(const imu_sample_t *smp, uint64_t k, int32_t w_raw[3], int32_t v_raw[3])
{
    for (int i = 0; i < 6; i++) {
        int32_t *out = i < 3 ? &w_raw[i] : &v_raw[i - 3];
        *out = interpolate_raw(smp->prev_raw[i], smp->raw[i], k + 1u, smp->lost + 1u);
    }
}

/* out of line (noinline): the link inlined it, two 64-bit divisions, at its three calls
 * (app.c's on_imu_accel): 64 bytes of the ECU's flash */
__attribute__((noinline)) uint32_t imu_stream_dt_us(const imu_sample_t *smp, uint64_t k)
{
    const uint64_t n = smp->lost + 1u;
    const uint64_t dt = smp->dt_us;
    return (uint32_t)(dt * (k + 1u) / n - dt * k / n);
}
