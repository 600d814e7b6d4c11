/*
 * raw_bias.h - each satellite's pseudorange bias, learnt while the receiver gives fixes
 * (issue #20, gnss_input = both; docs/kalman.md "Tightly coupled GNSS").
 *
 * A receiver's ranges carry biases of a metre or two that last tens of minutes: the
 * broadcast orbit's and clock's residuals and the satellite's group delay, the atmosphere's
 * residuals after the receiver's models (the Kingston receiver's: +-1.3 m per satellite
 * for the hour; the simulator's: 1 m per satellite over 1 h, the atmosphere's over 30 min).
 * With all satellites in view they average out in the fix; with the one to three satellites
 * of an urban canyon each pulls the position along its line of sight. While fixes come,
 * the filter's position follows them, and each satellite's residual against it, less the
 * epoch's median (the receiver's clock and what all satellites share), is that satellite's
 * bias plus its multipath and noise: averaged over APP_RAW_BIAS_TAU_S of driving (the
 * multipath of a moving car decorrelates in tens of seconds; parked, it is a constant of
 * the spot and is not learnt), it is removed from the satellite's range when the raw
 * measurements are fused. Learnt and used per satellite (system and PRN); a bias not
 * learnt for APP_RAW_BIAS_KEEP_MS is forgotten (the slow errors have moved on).
 *
 * Fixed size: GNSS_RAW_MAX_SATS satellites; a new one takes the place of the one learnt
 * longest ago. All zero is the empty table (the navigation's state is cleared at its start).
 */
#ifndef NAVECU_RAW_BIAS_H
#define NAVECU_RAW_BIAS_H

#include <stdint.h>

#include "gnss_raw.h"
#include "nav_types.h"

typedef struct {
    uint8_t system, sv_id; /* sv_id 0: the entry is free */
    uint32_t tow_ms;       /* the epoch it was last learnt at (GPS time of week) */
    nav_real_t learnt_s;   /* how long it was learnt, up to APP_RAW_BIAS_TAU_S */
    nav_real_t bias_m;     /* measured minus computed range, less the epoch's median */
} raw_bias_sat_t;

typedef struct {
    raw_bias_sat_t sat[GNSS_RAW_MAX_SATS];
} raw_bias_t;

/* One epoch's residuals at tow_ms: of satellite sat[slot[i]], resid_m[i] (measured minus
 * computed range, less the epoch's median, m) where ok[i] is set, i < n; each learnt: the
 * running mean over the first APP_RAW_BIAS_TAU_S of learning, then an exponential average
 * of that time constant. Each epoch counts for the receiver's time since the satellite was
 * last learnt, at most APP_RAW_BIAS_STEP_MAX_S (after a gap, one epoch is one sample of the
 * multipath), and a new satellite's first for step_s (the receiver's usual fix interval).
 * Not learnt: a residual that is not finite, satellite
 * number 0, all of them for a step_s not in (0, APP_RAW_BIAS_TAU_S], an epoch not after
 * the satellite's last one (a repeat, one out of order); a satellite not learnt for
 * APP_RAW_BIAS_KEEP_MS is learnt afresh. The satellites already in the table are learnt
 * first; a new one takes the entry learnt longest ago, never one of this epoch's (none
 * when all are). */
void raw_bias_learn(raw_bias_t *b, const gnss_raw_sat_t *sat, const uint8_t *slot,
                    const nav_real_t *resid_m, const uint8_t *ok, int n, uint32_t tow_ms,
                    nav_real_t step_s);

/* Every satellite forgotten (the table empty). */
void raw_bias_forget(raw_bias_t *b);

/* The bias to remove from the satellite's range at tow_ms into *bias_m: 1; 0 (and
 * *bias_m = 0) when it was learnt for less than APP_RAW_BIAS_MIN_S, or not within
 * APP_RAW_BIAS_KEEP_MS before tow_ms. */
int raw_bias_of(const raw_bias_t *b, uint8_t system, uint8_t sv_id, uint32_t tow_ms,
                nav_real_t *bias_m);

#endif /* NAVECU_RAW_BIAS_H */
