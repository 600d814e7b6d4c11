/*
 * odo.c - odometer speed of the reference point and standstill (odo.h).
 */
#include "odo.h"

#include <stddef.h>

odo_config_t odo_default_config(void)
{
    odo_config_t c;
    c.axle = ODO_AXLE_REAR;
    c.wheelbase_m = NAV_C(2.7);
    c.track_m = NAV_C(1.6);
    c.still_speed_mps = NAV_C(0.01);
    c.still_time_s = NAV_C(0.5);
    c.still_rate_rps = NAV_C(0.00873); /* 0.5 deg/s */
    c.timeout_s = NAV_C(1.5);
    c.max_speed_mps = NAV_C(90.0);
    c.max_wheel_spread = NAV_C(0.3);
    return c;
}

static int cfg_ok(const odo_config_t *c)
{
    return (c->axle == ODO_AXLE_REAR || c->axle == ODO_AXLE_FRONT) &&
           c->wheelbase_m > NAV_C(0.5) && c->wheelbase_m < NAV_C(10.0) &&
           c->track_m > NAV_C(0.5) && c->track_m < NAV_C(5.0) &&
           c->still_speed_mps > NAV_C(0.0) && c->still_speed_mps < NAV_C(1.0) &&
           c->still_time_s >= NAV_C(0.0) && c->still_time_s < NAV_C(60.0) &&
           c->still_rate_rps > NAV_C(0.0) && c->timeout_s > NAV_C(0.0) &&
           c->timeout_s <= NAV_C(10.0) && c->max_speed_mps > NAV_C(1.0) &&
           c->max_wheel_spread > NAV_C(0.0);
}

int odo_init(odo_t *o, const odo_config_t *cfg)
{
    if (o == NULL || cfg == NULL || !cfg_ok(cfg)) {
        return NAV_EINVAL;
    }
    o->cfg = *cfg;
    o->speed_mps = NAV_C(0.0);
    o->age_s = NAV_C(0.0);
    o->period_s = NAV_C(0.0);
    o->still_for_s = NAV_C(0.0);
    o->zero_for_s = NAV_C(0.0);
    o->valid = 0u;
    o->standing = 0u;
    o->zero = 0u;
    o->n_frames = 0u;
    return NAV_OK;
}

/* Mean of one axle's two speeds if they agree with each other (the turn's own difference,
 * yaw rate x track, allowed for), else NAV_EINVAL. */
static int axle_mean(const odo_config_t *c, nav_real_t left, nav_real_t right,
                     nav_real_t yaw_rate_rps, nav_real_t *mean)
{
    const nav_real_t m = NAV_C(0.5) * (left + right);
    const nav_real_t allowed = c->max_wheel_spread * nav_fabs(m) +
                               nav_fabs(yaw_rate_rps) * c->track_m + NAV_C(0.1);
    if (nav_fabs(left - right) > allowed) {
        return NAV_EINVAL;
    }
    *mean = m;
    return NAV_OK;
}

int odo_wheels(odo_t *o, const nav_real_t wheel_mps[4], nav_real_t yaw_rate_rps)
{
    int all_zero = 1;
    for (int i = 0; i < 4; i++) {
        if (!nav_isfinite(wheel_mps[i]) || nav_fabs(wheel_mps[i]) > o->cfg.max_speed_mps) {
            return NAV_EINVAL;
        }
        if (nav_fabs(wheel_mps[i]) >= o->cfg.still_speed_mps) {
            all_zero = 0;
        }
    }
    if (!nav_isfinite(yaw_rate_rps)) {
        return NAV_EINVAL;
    }
    nav_real_t v;
    if (o->cfg.axle == ODO_AXLE_REAR) {
        if (axle_mean(&o->cfg, wheel_mps[2], wheel_mps[3], yaw_rate_rps, &v) != NAV_OK) {
            return NAV_EINVAL;
        }
    } else {
        nav_real_t vf;
        if (axle_mean(&o->cfg, wheel_mps[0], wheel_mps[1], yaw_rate_rps, &vf) != NAV_OK) {
            return NAV_EINVAL;
        }
        /* the steered wheels run on a circle of larger radius: remove the lateral part */
        const nav_real_t lat = yaw_rate_rps * o->cfg.wheelbase_m;
        const nav_real_t lon2 = vf * vf - lat * lat;
        const nav_real_t lon = lon2 > NAV_C(0.0) ? nav_sqrt(lon2) : NAV_C(0.0);
        v = vf < NAV_C(0.0) ? -lon : lon;
    }
    if (o->valid) {
        /* the source's rate, for the measurement noise of a slow (1 Hz OBD-II) source */
        o->period_s = o->period_s > NAV_C(0.0)
                          ? o->period_s + NAV_C(0.1) * (o->age_s - o->period_s)
                          : o->age_s;
    }
    o->speed_mps = all_zero ? NAV_C(0.0) : v;
    o->zero = all_zero ? 1u : 0u;
    o->age_s = NAV_C(0.0);
    o->valid = 1u;
    if (!all_zero) {
        o->still_for_s = NAV_C(0.0);
        o->zero_for_s = NAV_C(0.0);
        o->standing = 0u;
    }
    o->n_frames++;
    return NAV_OK;
}

void odo_age(odo_t *o, nav_real_t dt_s)
{
    o->age_s += dt_s;
    if (o->age_s > o->cfg.timeout_s) {
        o->valid = 0u;
        /* no wheel speeds, no standstill (as odo_tick: "still" needs a valid reading) */
        o->standing = 0u;
        o->still_for_s = NAV_C(0.0);
        o->zero_for_s = NAV_C(0.0);
    }
}

void odo_tick(odo_t *o, nav_real_t dt_s, nav_real_t yaw_rate_rps)
{
    odo_age(o, dt_s);
    const int still = o->valid && o->zero &&
                      nav_fabs(yaw_rate_rps) < o->cfg.still_rate_rps;
    if (still) {
        o->still_for_s += dt_s;
    } else {
        o->still_for_s = NAV_C(0.0);
    }
    /* a yaw rate above still_rate_rps for a sample (noise) ends "still", not the stop */
    if (o->valid && o->zero) {
        o->zero_for_s = o->zero_for_s < ODO_ZERO_FOR_MAX_S ? o->zero_for_s + dt_s
                                                           : ODO_ZERO_FOR_MAX_S;
    } else {
        o->zero_for_s = NAV_C(0.0);
    }
    o->standing = (still && o->still_for_s >= o->cfg.still_time_s) ? 1u : 0u;
}
