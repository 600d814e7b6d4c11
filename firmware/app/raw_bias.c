/* raw_bias.c - each satellite's pseudorange bias; see raw_bias.h. */
#include "raw_bias.h"

#include "app_tuning.h"
#include "gnss_time.h"

/* ms since the entry was learnt (a free entry: the largest) */
static int64_t age_ms(const raw_bias_sat_t *s, uint32_t tow_ms)
{
    return s->sv_id == 0u ? INT64_MAX : gnss_tow_diff_ms(tow_ms, s->tow_ms);
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

void raw_bias_learn(raw_bias_t *b, uint8_t system, uint8_t sv_id, uint32_t tow_ms,
                    nav_real_t resid_m, nav_real_t step_s)
{
    if (sv_id == 0u || !nav_isfinite(resid_m) || !(step_s > NAV_C(0.0))) {
        return;
    }
    const int k = index_of(b, system, sv_id);
    raw_bias_sat_t *s = k >= 0 ? &b->sat[k] : &b->sat[0];
    if (k < 0) {
        for (uint32_t i = 1u; i < GNSS_RAW_MAX_SATS; i++) {
            if (age_ms(&b->sat[i], tow_ms) > age_ms(s, tow_ms)) {
                s = &b->sat[i];
            }
        }
        s->system = system;
        s->sv_id = sv_id;
        s->learnt_s = NAV_C(0.0);
    } else if (age_ms(s, tow_ms) > (int64_t)APP_RAW_BIAS_KEEP_MS ||
               age_ms(s, tow_ms) < 0) {
        s->learnt_s = NAV_C(0.0); /* forgotten, or a time from before it: learnt afresh */
    } else {
        /* learnt on */
    }
    const nav_real_t step = step_s < APP_RAW_BIAS_TAU_S ? step_s : APP_RAW_BIAS_TAU_S;
    s->learnt_s = s->learnt_s + step < APP_RAW_BIAS_TAU_S ? s->learnt_s + step
                                                          : APP_RAW_BIAS_TAU_S;
    s->bias_m = s->learnt_s > step ? s->bias_m + (resid_m - s->bias_m) * (step / s->learnt_s)
                                   : resid_m;
    s->tow_ms = tow_ms;
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
