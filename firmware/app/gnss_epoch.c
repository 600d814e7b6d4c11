/* gnss_epoch.c - GNSS epoch assembly; see gnss_epoch.h. */
#include "gnss_epoch.h"

#include "app_tuning.h"

void gnss_epoch_position(gnss_asm_t *g, int32_t lat_e7, int32_t lon_e7)
{
    g->lat_e7 = lat_e7;
    g->lon_e7 = lon_e7;
    g->pos_pending = 1u;
}

void gnss_epoch_position_refused(gnss_asm_t *g)
{
    g->pos_pending = 0u;
    g->pos_refused = 1u;
}

int gnss_epoch_velocity(gnss_asm_t *g, uint8_t epoch, const nav_real_t v_enu_mps[3],
                        nav_real_t sacc_mps)
{
    if (g->vel_pending && g->vel_epoch == epoch) {
        return 1; /* this epoch's velocity again: a repeated frame, the first one stays */
    }
    g->vel_epoch = epoch;
    for (int i = 0; i < 3; i++) {
        g->v_enu_mps[i] = v_enu_mps[i];
    }
    g->sacc_mps = sacc_mps;
    g->vel_pending = 1u;
    return 0;
}

void gnss_epoch_height(gnss_asm_t *g, uint8_t epoch, int32_t h_cm)
{
    g->h_cm = h_cm;
    g->h_epoch = epoch;
    g->h_pending = 1u;
}

void gnss_epoch_week(gnss_asm_t *g, uint8_t epoch, uint16_t gps_week)
{
    g->gps_week = gps_week;
    g->week_epoch = epoch;
    g->week_pending = 1u;
}

gnss_close_t gnss_epoch_close(gnss_asm_t *g, const rx_input_t *status, gnss_fix_t *fix)
{
    gnss_close_t r = {0u, 0u, 0u, 0u, 0u, 0u, 0u};
    const int have_pos = g->pos_pending;
    int have_vel = g->vel_pending;
    int have_h = g->h_pending;
    const int pos_refused = g->pos_refused;
    const int have_week = g->week_pending;
    g->pos_pending = g->vel_pending = g->h_pending = g->week_pending = 0u;
    g->pos_refused = 0u;
    if (!status->u.status.defined) {
        r.undefined = 1u;
        return r;
    }
    if (status->u.status.repeat) {
        r.repeat = 1u; /* the previous fix again: nothing of it is new */
        return r;
    }
    const uint8_t epoch = status->u.status.epoch;
    if ((have_vel && g->vel_epoch != epoch) || (have_h && g->h_epoch != epoch) ||
        (have_week && g->week_epoch != epoch)) {
        r.mismatch = 1u; /* frames of another epoch: drop them (a GNSS_Time too) */
        have_vel = have_vel && g->vel_epoch == epoch;
        have_h = have_h && g->h_epoch == epoch;
    }
    fix->has_week = (uint8_t)(have_week && g->week_epoch == epoch ? 1u : 0u);
    fix->gps_week = g->gps_week;
    fix->has_vel = have_vel ? 1u : 0u;
    fix->has_h = have_h ? 1u : 0u;
    fix->speed_mps = NAV_C(-1.0);
    fix->course_rad = NAV_C(0.0);
    fix->sacc_mps = NAV_C(0.0); /* no velocity: no speed accuracy either */
    for (int i = 0; i < 3; i++) {
        fix->v_enu_mps[i] = NAV_C(0.0);
    }
    if (have_vel) {
        const nav_real_t ve = g->v_enu_mps[0];
        const nav_real_t vn = g->v_enu_mps[1];
        for (int i = 0; i < 3; i++) {
            fix->v_enu_mps[i] = g->v_enu_mps[i];
        }
        fix->speed_mps = nav_sqrt(ve * ve + vn * vn);
        fix->course_rad = nav_atan2(ve, vn);
        if (fix->course_rad < NAV_C(0.0)) {
            fix->course_rad += NAV_C(2.0) * NAV_PI;
        }
        fix->sacc_mps = g->sacc_mps;
        r.has_course = 1u;
    }
    if (!status->u.status.fix_3d || status->u.status.n_sats < APP_GNSS_MIN_SATS) {
        r.no_fix = 1u; /* the receiver says so: not an error */
        return r;
    }
    if (!have_pos) {
        r.no_position = (uint8_t)(pos_refused ? 0u : 1u); /* a refused position was counted already */
        return r;
    }
    fix->pos.lat = (int64_t)g->lat_e7 * GEO_LSB_PER_DEG_E7;
    fix->pos.lon = (int64_t)g->lon_e7 * GEO_LSB_PER_DEG_E7;
    fix->pos.h = (int64_t)g->h_cm * 10 * GEO_LSB_PER_MM;
    fix->h_cm = g->h_cm;
    fix->hacc_m = status->u.status.hacc_m;
    fix->vacc_m = status->u.status.vacc_m;
    fix->tow_ms = status->u.status.tow_ms;
    r.usable = 1u;
    return r;
}
