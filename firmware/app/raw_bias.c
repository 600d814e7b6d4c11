/* raw_bias.c - each satellite's pseudorange bias; see raw_bias.h. */
#include "raw_bias.h"

#include "app_tuning.h"
#include "gnss_time.h"

/* ms since the entry was learnt; a free entry, or one learnt "after" tow_ms by more than
 * APP_RAW_BIAS_KEEP_MS (a receiver's time gone back: a reset, another drive), the largest */
static int64_t age_ms(const raw_bias_sat_t *s, uint32_t tow_ms)
{
    const int64_t age = s->sv_id == 0u ? INT64_MAX : gnss_tow_diff_ms(tow_ms, s->tow_ms);
    return age < -(int64_t)APP_RAW_BIAS_KEEP_MS ? INT64_MAX : age;
}

/* the satellite's entry, -1: none */
static int index_of(const raw_bias_t *b, uint8_t system, uint8_t sv_id)
{
    for (int i = 0; i < (int)GNSS_RAW_MAX_SATS; i++) {
        const raw_bias_sat_t *s = &b->sat[i];
        if (s->sv_id != 0u && s->sv_id == sv_id && s->system == system) {
            return i;
        }
    }
    return -1;
}

/* the entry for a new satellite: the one learnt longest ago, never one learnt at tow_ms
 * (a satellite of this epoch); -1 when every entry is */
static int entry_for_new(const raw_bias_t *b, uint32_t tow_ms)
{
    int k = -1;
    int64_t oldest = 0;
    for (int i = 0; i < (int)GNSS_RAW_MAX_SATS; i++) {
        const int64_t age = age_ms(&b->sat[i], tow_ms);
        if (age > oldest) {
            oldest = age;
            k = i;
        }
    }
    return k;
}

/* one satellite's residual (raw_bias_learn); k its entry, -1: none yet */
static void learn_one(raw_bias_t *b, int k_in, uint8_t system, uint8_t sv_id,
                      nav_real_t resid_m, uint32_t tow_ms, nav_real_t step_s)
{
    int k = k_in;
    const int64_t age = k >= 0 ? age_ms(&b->sat[k], tow_ms) : INT64_MAX;
    if (k >= 0 && age <= 0) {
        return; /* this epoch again, or one before the last learnt: nothing new */
    }
    nav_real_t step = step_s;
    if (k < 0 || age > (int64_t)APP_RAW_BIAS_KEEP_MS) {
        k = k >= 0 ? k : entry_for_new(b, tow_ms);
        if (k < 0) {
            return; /* the table holds this epoch's satellites only */
        }
        b->sat[k].system = system;
        b->sat[k].sv_id = sv_id;
        b->sat[k].learnt_s = NAV_C(0.0);
    } else {
        /* the receiver's time since it was learnt, at most APP_RAW_BIAS_STEP_MAX_S */
        const nav_real_t since_s = (nav_real_t)age * NAV_C(0.001);
        step = since_s < APP_RAW_BIAS_STEP_MAX_S ? since_s : APP_RAW_BIAS_STEP_MAX_S;
    }
    raw_bias_sat_t *s = &b->sat[k];
    s->learnt_s = s->learnt_s + step < APP_RAW_BIAS_TAU_S ? s->learnt_s + step
                                                          : APP_RAW_BIAS_TAU_S;
    s->bias_m = s->learnt_s > step ? s->bias_m + (resid_m - s->bias_m) * (step / s->learnt_s)
                                   : resid_m;
    s->tow_ms = tow_ms;
}

void raw_bias_learn(raw_bias_t *b, const gnss_raw_sat_t *sat, const uint8_t *slot,
                    const nav_real_t *resid_m, const uint8_t *ok, int n, uint32_t tow_ms,
                    nav_real_t step_s)
{
    if (!(step_s > NAV_C(0.0)) || !(step_s <= APP_RAW_BIAS_TAU_S)) {
        return;
    }
    /* the satellites with an entry first: a new one then takes no entry of this epoch's */
    for (int pass = 0; pass < 2; pass++) {
        for (int i = 0; i < n && i < (int)GNSS_RAW_MAX_SATS; i++) {
            const gnss_raw_sat_t *m = &sat[slot[i] % GNSS_RAW_MAX_SATS];
            const int k = index_of(b, m->system, m->sv_id);
            const uint8_t known = k >= 0 ? 1u : 0u;
            const uint8_t wanted = pass == 0 ? 1u : 0u;
            if (ok[i] != 0u && m->sv_id != 0u && nav_isfinite(resid_m[i]) && known == wanted) {
                learn_one(b, k, m->system, m->sv_id, resid_m[i], tow_ms, step_s);
            }
        }
    }
}

void raw_bias_forget(raw_bias_t *b)
{
    for (int i = 0; i < (int)GNSS_RAW_MAX_SATS; i++) {
        b->sat[i].sv_id = 0u; /* free */
    }
}

int raw_bias_of(const raw_bias_t *b, uint8_t system, uint8_t sv_id, uint32_t tow_ms,
                nav_real_t *bias_m)
{
    *bias_m = NAV_C(0.0);
    const int k = index_of(b, system, sv_id);
    if (k < 0 || b->sat[k].learnt_s < APP_RAW_BIAS_MIN_S) {
        return 0;
    }
    const int64_t age = age_ms(&b->sat[k], tow_ms);
    if (age < 0 || age > (int64_t)APP_RAW_BIAS_KEEP_MS) {
        return 0;
    }
    *bias_m = b->sat[k].bias_m;
    return 1;
}
