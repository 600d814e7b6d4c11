/*
 * test_gnss_raw.c - raw GNSS epochs (issue #20): each satellite's five frames, encoded as a
 * receiver encodes them (the generated codec, the E2E CRC), decoded by app_rx and assembled
 * by gnss_raw.h until GNSS_RawEpoch closes the epoch: values exact in the protocol's units,
 * any frame order, a missing frame, a repeated frame, an epoch that never closed, a close
 * of another epoch, a repeated epoch, a slot beyond NumMeas, a bad CRC, an invalid epoch
 * number, an elevation out of range; and through the application, what is counted where.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app.h"
#include "app_fixture.h"
#include "can_frames.h"
#include "e2e.h"
#include "fake_hal.h"
#include "app_tuning.h"
#include "gnss_raw.h"
#include "navecu_can.h"
#include "raw_bias.h"

static gnss_raw_asm_t g;
static rx_state_t rx;
static uint32_t ids[NAVECU_MSG_N] = NAVECU_MSG_STOCK_IDS;

static int setup(void **state)
{
    (void)state;
    gnss_raw_init(&g);
    memset(&rx, 0, sizeof rx);
    return 0;
}

/* satellite k of a test epoch: a GPS-like position (2.6e7 m, so the 32-bit signal's high
 * bits are used), a velocity, a pseudorange and rate, its identity */
typedef struct {
    int32_t pos[3];
    int16_t vel[3];
    uint32_t pr;
    int32_t rr;
    uint8_t sv, elev, pr_sigma, rr_sigma, cn0;
} sat_t;

static sat_t sat_k(int k)
{
    sat_t s;
    s.pos[0] = 1300000000 + 12345 * k; /* 26,000 km at 0.02 m */
    s.pos[1] = -700000000 - 777 * k;
    s.pos[2] = 450000000 + k;
    s.vel[0] = (int16_t)(-12000 + k);  /* -1500 m/s at 0.125 */
    s.vel[1] = (int16_t)(20000 - k);
    s.vel[2] = (int16_t)(3 * k);
    s.pr = 1100000000u + (uint32_t)k * 1000u; /* 22,000 km at 0.02 m */
    s.rr = -300000 + 1000 * k;                 /* -3000 m/s at 0.01 */
    s.sv = (uint8_t)(5 + k);
    s.elev = (uint8_t)(10 + 7 * k);
    s.pr_sigma = 30u;
    s.rr_sigma = 8u;
    s.cn0 = 42u;
    return s;
}

static hal_can_frame_t protect(uint32_t id, uint8_t d[8])
{
    e2e_protect(id, d);
    return cf_frame(id, d, 1000u);
}

/* frame `part` (0 X, 1 Y, 2 Z, 3 range, 4 rate) of satellite s in slot/epoch */
static hal_can_frame_t sat_frame(const sat_t *s, int part, uint8_t slot, uint8_t epoch)
{
    uint8_t d[8];
    if (part == 0) {
        struct navecu_can_gnss_raw_sat_x_t m = {s->pos[0], s->vel[0], slot, epoch, 0u};
        navecu_can_gnss_raw_sat_x_pack(d, &m, 8u);
        return protect(NAVECU_CAN_GNSS_RAW_SAT_X_FRAME_ID, d);
    }
    if (part == 1) {
        struct navecu_can_gnss_raw_sat_y_t m = {s->pos[1], s->vel[1], slot, epoch, 0u};
        navecu_can_gnss_raw_sat_y_pack(d, &m, 8u);
        return protect(NAVECU_CAN_GNSS_RAW_SAT_Y_FRAME_ID, d);
    }
    if (part == 2) {
        struct navecu_can_gnss_raw_sat_z_t m = {s->pos[2], s->vel[2], slot, epoch, 0u};
        navecu_can_gnss_raw_sat_z_pack(d, &m, 8u);
        return protect(NAVECU_CAN_GNSS_RAW_SAT_Z_FRAME_ID, d);
    }
    if (part == 3) {
        struct navecu_can_gnss_raw_range_t m;
        memset(&m, 0, sizeof m);
        m.pseudorange = s->pr;
        m.gnss_system = 0u;
        m.sv_id = s->sv;
        m.elevation = s->elev;
        m.pseudorange_valid = 1u;
        m.raw_slot = slot;
        m.gnss_epoch = epoch;
        navecu_can_gnss_raw_range_pack(d, &m, 8u);
        return protect(NAVECU_CAN_GNSS_RAW_RANGE_FRAME_ID, d);
    }
    struct navecu_can_gnss_raw_rate_t m;
    memset(&m, 0, sizeof m);
    m.range_rate = s->rr;
    m.pseudorange_sigma = s->pr_sigma;
    m.range_rate_sigma = s->rr_sigma;
    m.cn0 = s->cn0;
    m.range_rate_valid = 1u;
    m.raw_slot = slot;
    m.gnss_epoch = epoch;
    navecu_can_gnss_raw_rate_pack(d, &m, 8u);
    return protect(NAVECU_CAN_GNSS_RAW_RATE_FRAME_ID, d);
}

static hal_can_frame_t epoch_frame(uint8_t epoch, uint8_t n_meas, uint32_t tow_ms)
{
    uint8_t d[8];
    struct navecu_can_gnss_raw_epoch_t m;
    memset(&m, 0, sizeof m);
    m.time_of_week = tow_ms;
    m.num_meas = n_meas;
    m.gnss_epoch = epoch;
    navecu_can_gnss_raw_epoch_pack(d, &m, 8u);
    return protect(NAVECU_CAN_GNSS_RAW_EPOCH_FRAME_ID, d);
}

static gnss_raw_frame_t feed(const hal_can_frame_t *f)
{
    rx_input_t in;
    assert_int_equal(app_rx_decode(&rx, ids, f, &in), RX_OK);
    assert_int_equal(in.kind, RX_GNSS_RAW_SAT);
    return gnss_raw_frame(&g, &in);
}

static gnss_raw_close_t close_with(const hal_can_frame_t *f)
{
    rx_input_t in;
    assert_int_equal(app_rx_decode(&rx, ids, f, &in), RX_OK);
    assert_int_equal(in.kind, RX_GNSS_RAW_EPOCH);
    return gnss_raw_close(&g, &in);
}

static void feed_sat(int k, uint8_t slot, uint8_t epoch)
{
    const sat_t s = sat_k(k);
    for (int p = 0; p < 5; p++) {
        const hal_can_frame_t f = sat_frame(&s, p, slot, epoch);
        assert_int_equal(feed(&f), GNSS_RAW_TAKEN);
    }
}

static void assert_sat(uint8_t slot, int k)
{
    const sat_t s = sat_k(k);
    const gnss_raw_sat_t *r = &g.sat[slot];
    for (int i = 0; i < 3; i++) {
        assert_int_equal(r->pos_lsb[i], s.pos[i]);
        assert_int_equal(r->vel_lsb[i], s.vel[i]);
    }
    assert_int_equal(r->pr_lsb, s.pr);
    assert_int_equal(r->rr_lsb, s.rr);
    assert_int_equal(r->sv_id, s.sv);
    assert_int_equal(r->elevation_deg, s.elev);
    assert_int_equal(r->pr_sigma_lsb, s.pr_sigma);
    assert_int_equal(r->rr_sigma_lsb, s.rr_sigma);
    assert_int_equal(r->cn0_dbhz, s.cn0);
    assert_int_equal(r->pr_valid, 1u);
    assert_int_equal(r->rr_valid, 1u);
}

/* GIVEN three satellites' frames of epoch 4 WHEN GNSS_RawEpoch 4 with NumMeas 3 closes it
 * THEN three complete satellites, every value exact in the protocol's integer units (the
 * 32-bit position and the 31-bit pseudorange through the codec without float). */
static void test_three_satellites(void **state)
{
    (void)state;
    for (int k = 0; k < 3; k++) {
        feed_sat(k, (uint8_t)k, 4u);
    }
    const hal_can_frame_t e = epoch_frame(4u, 3u, 345600000u);
    const gnss_raw_close_t c = close_with(&e);
    assert_int_equal(c.usable, 1u);
    assert_int_equal(c.n_sats, 3u);
    assert_int_equal(c.complete, 0x7u);
    assert_int_equal(c.incomplete + c.extra + c.mismatch + c.repeat, 0u);
    for (int k = 0; k < 3; k++) {
        assert_sat((uint8_t)k, k);
    }
}

/* The five frames of two satellites interleaved in reverse order: the same result. */
static void test_any_order(void **state)
{
    (void)state;
    const sat_t s0 = sat_k(0), s1 = sat_k(1);
    for (int p = 4; p >= 0; p--) {
        const hal_can_frame_t f1 = sat_frame(&s1, p, 1u, 9u);
        const hal_can_frame_t f0 = sat_frame(&s0, p, 0u, 9u);
        assert_int_equal(feed(&f1), GNSS_RAW_TAKEN);
        assert_int_equal(feed(&f0), GNSS_RAW_TAKEN);
    }
    const hal_can_frame_t e = epoch_frame(9u, 2u, 1000u);
    const gnss_raw_close_t c = close_with(&e);
    assert_int_equal(c.n_sats, 2u);
    assert_sat(0u, 0);
    assert_sat(1u, 1);
}

/* Slot 1 lacks its GNSS_RawRate: it is dropped and counted, slots 0 and 2 are used. */
static void test_missing_frame(void **state)
{
    (void)state;
    feed_sat(0, 0u, 2u);
    const sat_t s1 = sat_k(1);
    for (int p = 0; p < 4; p++) {
        const hal_can_frame_t f = sat_frame(&s1, p, 1u, 2u);
        assert_int_equal(feed(&f), GNSS_RAW_TAKEN);
    }
    feed_sat(2, 2u, 2u);
    const hal_can_frame_t e = epoch_frame(2u, 3u, 2000u);
    const gnss_raw_close_t c = close_with(&e);
    assert_int_equal(c.usable, 1u);
    assert_int_equal(c.n_sats, 2u);
    assert_int_equal(c.incomplete, 1u);
    assert_int_equal(c.complete, 0x5u);
}

/* Satellite 1 sent in slots 1 and 3 (the same System and SvId), satellite 0 in slot 0 and
 * 2 in slot 2: slots 1 and 3 are both dropped and counted (which is right cannot be told;
 * fused twice it weighed double and outvoted the others in the fault exclusion: a review's
 * finding), slots 0 and 2 used. */
static void test_duplicate_satellite(void **state)
{
    (void)state;
    feed_sat(0, 0u, 3u);
    feed_sat(1, 1u, 3u);
    feed_sat(2, 2u, 3u);
    feed_sat(1, 3u, 3u);
    const hal_can_frame_t e = epoch_frame(3u, 4u, 4000u);
    const gnss_raw_close_t c = close_with(&e);
    assert_int_equal(c.usable, 1u);
    assert_int_equal(c.n_sats, 2u);
    assert_int_equal(c.duplicate, 2u);
    assert_int_equal(c.complete, 0x5u);
    assert_sat(0u, 0);
    assert_sat(2u, 2);
}

/* A second GNSS_RawRange of slot 0 in the same epoch is a repeat: dropped, the first
 * value stays. */
static void test_repeated_frame(void **state)
{
    (void)state;
    feed_sat(0, 0u, 1u);
    sat_t other = sat_k(0);
    other.pr += 500u;
    const hal_can_frame_t f = sat_frame(&other, 3, 0u, 1u);
    assert_int_equal(feed(&f), GNSS_RAW_REPEAT);
    const hal_can_frame_t e = epoch_frame(1u, 1u, 3000u);
    const gnss_raw_close_t c = close_with(&e);
    assert_int_equal(c.n_sats, 1u);
    assert_sat(0u, 0);
}

/* Epoch 5 never closes (its GNSS_RawEpoch lost): the first frame of epoch 6 drops it; epoch
 * 6 then closes with its own satellites only. A close of another number drops them all. */
static void test_unclosed_and_mismatched_epochs(void **state)
{
    (void)state;
    feed_sat(0, 0u, 5u);
    feed_sat(1, 1u, 5u);
    const sat_t s2 = sat_k(2);
    const hal_can_frame_t f = sat_frame(&s2, 0, 0u, 6u);
    assert_int_equal(feed(&f), GNSS_RAW_DROPPED);
    for (int p = 1; p < 5; p++) {
        const hal_can_frame_t fp = sat_frame(&s2, p, 0u, 6u);
        assert_int_equal(feed(&fp), GNSS_RAW_TAKEN);
    }
    const hal_can_frame_t e6 = epoch_frame(6u, 1u, 4000u);
    gnss_raw_close_t c = close_with(&e6);
    assert_int_equal(c.n_sats, 1u);
    assert_int_equal(c.incomplete, 0u);
    assert_sat(0u, 2);

    feed_sat(0, 0u, 7u);
    const hal_can_frame_t e8 = epoch_frame(8u, 1u, 5000u);
    c = close_with(&e8);
    assert_int_equal(c.mismatch, 1u);
    assert_int_equal(c.usable, 0u);
    assert_int_equal(c.n_sats, 0u);
}

/* The same TimeOfWeek twice: the second epoch is a repeat, dropped whole. A slot at or
 * beyond NumMeas is dropped and counted; NumMeas 0 closes an empty epoch, not usable. */
static void test_repeat_extra_and_empty(void **state)
{
    (void)state;
    feed_sat(0, 0u, 3u);
    const hal_can_frame_t e = epoch_frame(3u, 1u, 6000u);
    assert_int_equal(close_with(&e).n_sats, 1u);
    feed_sat(0, 0u, 4u);
    const hal_can_frame_t e4 = epoch_frame(4u, 1u, 6000u);
    gnss_raw_close_t c = close_with(&e4);
    assert_int_equal(c.repeat, 1u);
    assert_int_equal(c.usable, 0u);

    feed_sat(0, 0u, 5u);
    feed_sat(1, 3u, 5u);
    const hal_can_frame_t e5 = epoch_frame(5u, 1u, 7000u);
    c = close_with(&e5);
    assert_int_equal(c.n_sats, 1u);
    assert_int_equal(c.extra, 1u);

    const hal_can_frame_t e6 = epoch_frame(6u, 0u, 8000u);
    c = close_with(&e6);
    assert_int_equal(c.usable, 0u);
    assert_int_equal(c.n_sats + c.incomplete + c.extra + c.mismatch, 0u);
}

/* Frame checks in app_rx: a wrong CRC, the invalid epoch number 15, an elevation above 90
 * deg, a NumMeas above 16. */
static void test_frame_checks(void **state)
{
    (void)state;
    const sat_t s = sat_k(0);
    rx_input_t in;
    hal_can_frame_t f = sat_frame(&s, 0, 0u, 1u);
    f.data[2] ^= 0x10u;
    assert_int_equal(app_rx_decode(&rx, ids, &f, &in), RX_BAD_CRC);
    f = sat_frame(&s, 4, 0u, 15u);
    assert_int_equal(app_rx_decode(&rx, ids, &f, &in), RX_BAD_COUNTER);
    sat_t high = s;
    high.elev = 91u;
    f = sat_frame(&high, 3, 0u, 1u);
    assert_int_equal(app_rx_decode(&rx, ids, &f, &in), RX_BAD_VALUE);
    f = epoch_frame(1u, 17u, 1000u);
    assert_int_equal(app_rx_decode(&rx, ids, &f, &in), RX_BAD_VALUE);
    f = epoch_frame(15u, 1u, 1000u);
    assert_int_equal(app_rx_decode(&rx, ids, &f, &in), RX_BAD_COUNTER);
}

/* Through the application: a good epoch counted in raw_epochs/raw_sats; an incomplete
 * one in CntGnssRejected (once); a repeated frame in CntBadCounter; nothing else; an epoch
 * with a satellite in two slots in CntGnssRejected (once), its other satellite used. */
static void test_counted_by_the_application(void **state)
{
    (void)state;
    static app_t app;
    hal_t hal;
    assert_int_equal(fx_fresh_app(&app, &hal), 0);
    const app_health_t h0 = app.keep.health;
    for (int k = 0; k < 2; k++) {
        const sat_t s = sat_k(k);
        for (int p = 0; p < 5; p++) {
            const hal_can_frame_t f = sat_frame(&s, p, (uint8_t)k, 0u);
            app_handle_frame(&app, &hal, &f);
        }
    }
    hal_can_frame_t e = epoch_frame(0u, 2u, 1000u);
    app_handle_frame(&app, &hal, &e);
    assert_int_equal(app.keep.raw_epochs, 1u);
    assert_int_equal(app.keep.raw_sats, 2u);
    assert_memory_equal(&app.keep.health, &h0, sizeof h0);

    const sat_t s = sat_k(0);
    for (int p = 0; p < 4; p++) { /* no GNSS_RawRate */
        const hal_can_frame_t f = sat_frame(&s, p, 0u, 1u);
        app_handle_frame(&app, &hal, &f);
    }
    const hal_can_frame_t again = sat_frame(&s, 0, 0u, 1u);
    app_handle_frame(&app, &hal, &again);
    e = epoch_frame(1u, 1u, 2000u);
    app_handle_frame(&app, &hal, &e);
    assert_int_equal(app.keep.raw_epochs, 1u);
    assert_int_equal(app.keep.health.gnss_rejected, h0.gnss_rejected + 1u);
    assert_int_equal(app.keep.health.bad_counter, h0.bad_counter + 1u);

    /* satellite 0 in slots 0 and 2, satellite 1 in slot 1: one satellite used, the epoch
     * counted once in CntGnssRejected */
    const int sat_of_slot[3] = {0, 1, 0};
    for (int k = 0; k < 3; k++) {
        const sat_t d = sat_k(sat_of_slot[k]);
        for (int p = 0; p < 5; p++) {
            const hal_can_frame_t f = sat_frame(&d, p, (uint8_t)k, 2u);
            app_handle_frame(&app, &hal, &f);
        }
    }
    e = epoch_frame(2u, 3u, 3000u);
    app_handle_frame(&app, &hal, &e);
    assert_int_equal(app.keep.raw_epochs, 2u);
    assert_int_equal(app.keep.raw_sats, 3u);
    assert_int_equal(app.keep.health.gnss_rejected, h0.gnss_rejected + 2u);
}

/* ---- each satellite's learnt range bias (raw_bias.h) ---- */

/* an epoch's satellites for raw_bias_learn: satellite i in slot i, all usable */
static gnss_raw_sat_t bsat[GNSS_RAW_MAX_SATS];
static const uint8_t bslot[GNSS_RAW_MAX_SATS] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13,
                                                  14, 15};
static const uint8_t bok[GNSS_RAW_MAX_SATS] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};

/* learn one satellite's residual at tow_ms (an epoch of one) */
static void learn1(raw_bias_t *b, uint8_t system, uint8_t sv, uint32_t tow_ms, nav_real_t r,
                   nav_real_t step_s)
{
    bsat[0].system = system;
    bsat[0].sv_id = sv;
    raw_bias_learn(b, bsat, bslot, &r, bok, 1, tow_ms, step_s);
}

/* A satellite 1.5 m long with +-0.5 m of alternating noise, learnt at 1 s epochs: after the
 * running mean of the first APP_RAW_BIAS_TAU_S and as long again of the exponential average,
 * within the noise's remainder (the average of 300 alternating values: 0; the exponential
 * average leaves at most 0.5 x 1 / 300 of the last one) of 1.5 m; not usable before
 * APP_RAW_BIAS_MIN_S of learning, usable from it on; another satellite (or system) has none */
static void test_bias_learnt_as_the_average(void **state)
{
    (void)state;
    raw_bias_t b;
    memset(&b, 0, sizeof b);
    const uint32_t t0 = 100000u;
    nav_real_t got = NAV_C(9.0);
    const int min_epochs = (int)APP_RAW_BIAS_MIN_S;
    for (int k = 0; k < 2 * (int)APP_RAW_BIAS_TAU_S; k++) {
        const nav_real_t noise = (k % 2) == 0 ? NAV_C(0.5) : NAV_C(-0.5);
        learn1(&b, 0u, 7u, t0 + 1000u * (uint32_t)k, NAV_C(1.5) + noise, NAV_C(1.0));
        const int usable = raw_bias_of(&b, 0u, 7u, t0 + 1000u * (uint32_t)k, &got);
        assert_int_equal(usable, k + 1 >= min_epochs ? 1 : 0);
        if (!usable) {
            assert_float_equal(got, 0.0, 0.0);
        }
    }
    assert_float_equal(got, 1.5, 0.01);
    assert_int_equal(raw_bias_of(&b, 0u, 8u, t0, &got), 0);
    assert_int_equal(raw_bias_of(&b, 1u, 7u, t0, &got), 0);
}

/* Each epoch counts for the receiver's time since the satellite's last one, whatever the
 * fix interval: raw epochs every 2 s with fixes at 5 Hz (step_s 0.2 s: the simulator's
 * receiver) usable after 30 of them, not 60 (nor 300 counted as fix intervals, as a
 * version did); the same epoch again, or one before it (out of order), learns nothing */
static void test_bias_learnt_over_the_receivers_time(void **state)
{
    (void)state;
    raw_bias_t b;
    memset(&b, 0, sizeof b);
    const uint32_t t0 = 100000u;
    nav_real_t got;
    for (uint32_t k = 0u; k < 30u; k++) {
        learn1(&b, 0u, 9u, t0 + 2000u * k, NAV_C(2.0), NAV_C(0.2));
    }
    /* learnt 0.2 s (the first epoch) + 29 x 2 s = 58.2 s */
    assert_int_equal(raw_bias_of(&b, 0u, 9u, t0 + 58000u, &got), 0);
    learn1(&b, 0u, 9u, t0 + 58000u, NAV_C(50.0), NAV_C(0.2)); /* a repeat */
    learn1(&b, 0u, 9u, t0 + 57500u, NAV_C(50.0), NAV_C(0.2)); /* out of order */
    assert_int_equal(raw_bias_of(&b, 0u, 9u, t0 + 58000u, &got), 0);
    learn1(&b, 0u, 9u, t0 + 60000u, NAV_C(2.0), NAV_C(0.2));
    assert_int_equal(raw_bias_of(&b, 0u, 9u, t0 + 60000u, &got), 1);
    assert_float_equal(got, 2.0, 1e-5);
}

/* Not learnt for APP_RAW_BIAS_KEEP_MS: forgotten, and learnt afresh (the old value gone);
 * a time before the last learnt one (a replay) is not used either; across the week's end
 * the age is the time between (gnss_tow_diff_ms) */
static void test_bias_forgotten_and_across_the_week(void **state)
{
    (void)state;
    raw_bias_t b;
    memset(&b, 0, sizeof b);
    const uint32_t week = APP_WEEK_MS;
    const uint32_t t0 = week - 30000u; /* 30 s before the week's end */
    for (uint32_t k = 0u; k < 60u; k++) {
        learn1(&b, 0u, 3u, t0 + 1000u * k < week ? t0 + 1000u * k : t0 + 1000u * k - week,
               NAV_C(-2.0), NAV_C(1.0));
    }
    const uint32_t last = 29000u; /* t0 + 59 s, in the next week */
    nav_real_t got;
    assert_int_equal(raw_bias_of(&b, 0u, 3u, last, &got), 1);
    assert_float_equal(got, -2.0, 1e-5);
    assert_int_equal(raw_bias_of(&b, 0u, 3u, last + APP_RAW_BIAS_KEEP_MS, &got), 1);
    assert_int_equal(raw_bias_of(&b, 0u, 3u, last + APP_RAW_BIAS_KEEP_MS + 1u, &got), 0);
    assert_float_equal(got, 0.0, 0.0);
    assert_int_equal(raw_bias_of(&b, 0u, 3u, last - 1000u, &got), 0);
    /* learnt afresh after the gap: the first value is the bias, not usable for a minute */
    const uint32_t t1 = last + APP_RAW_BIAS_KEEP_MS + 1000u;
    learn1(&b, 0u, 3u, t1, NAV_C(4.0), NAV_C(1.0));
    assert_int_equal(raw_bias_of(&b, 0u, 3u, t1, &got), 0);
    for (uint32_t k = 1u; k < 60u; k++) {
        learn1(&b, 0u, 3u, t1 + 1000u * k, NAV_C(4.0), NAV_C(1.0));
    }
    assert_int_equal(raw_bias_of(&b, 0u, 3u, t1 + 59000u, &got), 1);
    assert_float_equal(got, 4.0, 1e-5);
}

/* A residual that is not finite, satellite number 0 or no time step is not learnt; the
 * table full, a new satellite takes the place of the one learnt longest ago, the others
 * stay */
static void test_bias_table_and_refusals(void **state)
{
    (void)state;
    raw_bias_t b;
    memset(&b, 0, sizeof b);
    const uint32_t t0 = 5000000u;
    nav_real_t got;
    for (uint32_t k = 0u; k < 80u; k++) {
        for (uint8_t sv = 1u; sv <= (uint8_t)GNSS_RAW_MAX_SATS; sv++) {
            /* satellite sv learnt until epoch 80 - sv (65 epochs at least): satellite 16 the
             * longest ago */
            if (k + sv <= 80u) {
                learn1(&b, 0u, sv, t0 + 1000u * k, (nav_real_t)sv, NAV_C(1.0));
            }
        }
        learn1(&b, 0u, 1u, t0 + 1000u * k + 500u, (nav_real_t)NAN, NAV_C(1.0));
        learn1(&b, 0u, 0u, t0 + 1000u * k + 500u, NAV_C(9.0), NAV_C(1.0));
        learn1(&b, 0u, 2u, t0 + 1000u * k + 500u, NAV_C(99.0), NAV_C(0.0));
    }
    const uint32_t t = t0 + 80000u;
    assert_int_equal(raw_bias_of(&b, 0u, 1u, t, &got), 1);
    assert_float_equal(got, 1.0, 1e-6);
    assert_int_equal(raw_bias_of(&b, 0u, 2u, t, &got), 1);
    assert_float_equal(got, 2.0, 1e-6);
    assert_int_equal(raw_bias_of(&b, 0u, 0u, t, &got), 0);
    learn1(&b, 0u, 17u, t, NAV_C(17.0), NAV_C(1.0));
    assert_int_equal(raw_bias_of(&b, 0u, 16u, t, &got), 0); /* replaced */
    for (uint8_t sv = 1u; sv < 16u; sv++) {
        assert_int_equal(raw_bias_of(&b, 0u, sv, t, &got), 1);
        assert_float_equal(got, (double)sv, 1e-6);
    }
}

/* The table full of the last epoch's 16 satellites, all learnt at the same time: the next
 * epoch brings a new satellite first and 15 of the 16. The new one takes the entry of the
 * satellite that left, whatever the order of the epoch; the 15 keep what they learnt (the
 * review of 7fb48b2 found each evicting the next down the table) */
static void test_bias_new_satellite_takes_the_one_that_left(void **state)
{
    (void)state;
    raw_bias_t b;
    memset(&b, 0, sizeof b);
    const uint32_t t0 = 200000u;
    nav_real_t r[GNSS_RAW_MAX_SATS];
    for (uint32_t k = 0u; k < 100u; k++) {
        for (int i = 0; i < (int)GNSS_RAW_MAX_SATS; i++) {
            bsat[i].system = 0u;
            bsat[i].sv_id = (uint8_t)(i + 1);
            r[i] = (nav_real_t)(i + 1);
        }
        raw_bias_learn(&b, bsat, bslot, r, bok, (int)GNSS_RAW_MAX_SATS, t0 + 1000u * k,
                       NAV_C(1.0));
    }
    /* the next epoch: satellite 20 first, then 1..15 (16 has set) */
    bsat[0].sv_id = 20u;
    r[0] = NAV_C(-3.0);
    for (int i = 1; i < (int)GNSS_RAW_MAX_SATS; i++) {
        bsat[i].sv_id = (uint8_t)i;
        r[i] = (nav_real_t)i;
    }
    const uint32_t t = t0 + 100000u;
    raw_bias_learn(&b, bsat, bslot, r, bok, (int)GNSS_RAW_MAX_SATS, t, NAV_C(1.0));
    nav_real_t got;
    for (uint8_t sv = 1u; sv < 16u; sv++) {
        assert_int_equal(raw_bias_of(&b, 0u, sv, t, &got), 1);
        assert_float_equal(got, (double)sv, 1e-5);
    }
    assert_int_equal(raw_bias_of(&b, 0u, 16u, t, &got), 0);
    assert_int_equal(raw_bias_of(&b, 0u, 20u, t, &got), 0); /* learnt, not for a minute */
    /* a 17th satellite of the same epoch finds no entry that is not this epoch's */
    learn1(&b, 0u, 21u, t, NAV_C(5.0), NAV_C(1.0));
    for (uint8_t sv = 1u; sv < 16u; sv++) {
        assert_int_equal(raw_bias_of(&b, 0u, sv, t, &got), 1);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_three_satellites, setup),
        cmocka_unit_test_setup(test_any_order, setup),
        cmocka_unit_test_setup(test_missing_frame, setup),
        cmocka_unit_test_setup(test_repeated_frame, setup),
        cmocka_unit_test_setup(test_duplicate_satellite, setup),
        cmocka_unit_test_setup(test_unclosed_and_mismatched_epochs, setup),
        cmocka_unit_test_setup(test_repeat_extra_and_empty, setup),
        cmocka_unit_test_setup(test_frame_checks, setup),
        cmocka_unit_test_setup(test_counted_by_the_application, setup),
        cmocka_unit_test(test_bias_learnt_as_the_average),
        cmocka_unit_test(test_bias_learnt_over_the_receivers_time),
        cmocka_unit_test(test_bias_forgotten_and_across_the_week),
        cmocka_unit_test(test_bias_table_and_refusals),
        cmocka_unit_test(test_bias_new_satellite_takes_the_one_that_left),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
