/* landnav.c - standstill and dead reckoning without the filter; see landnav.h. */
#include "landnav.h"

#include "app_tuning.h"
#include "earth.h"

/* the prior's weight in samples of the standstill average: n0 = ARW^2 / (dt sigma_b^2) */
static nav_real_t zbias_n0(const zbias_prior_t *prior, nav_real_t dt_s)
{
    const nav_real_t arw = prior->gyro_arw_rad_rts;
    const nav_real_t sb = prior->gyro_bias_rps;
    return arw * arw / (dt_s * sb * sb);
}

static void standstill_step(landnav_t *ln, zbias_t *zb, const zbias_prior_t *prior,
                            sins_t *nav, nav_real_t raw_rate_z_rad, nav_real_t dt)
{
    static const nav_real_t zero_v[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    nav_real_t roll, pitch, heading;
    sins_euler(nav, &roll, &pitch, &heading);
    if (!ln->holding) {
        ln->holding = 1u;
        ln->hold_heading_rad = heading;
    }
    nav_real_t dh = ln->hold_heading_rad - heading;
    if (dh > NAV_PI) {
        dh -= NAV_C(2.0) * NAV_PI;
    } else if (dh < -NAV_PI) {
        dh += NAV_C(2.0) * NAV_PI;
    }
    (void)sins_turn_heading(nav, dh);
    (void)sins_set_velocity(nav, zero_v);
    if (ln->yaw_car != 0u) {
        return; /* a stuck yaw gyro says nothing of its bias */
    }
    nav_real_t w_ie_b[3];
    sins_earth_rate_b(nav, w_ie_b);
    nav_acc_add(&zb->sum_rps, &zb->sum_lo_rps, raw_rate_z_rad / dt - w_ie_b[2]);
    if (zb->n < UINT32_MAX) {
        zb->n++;
    }
    const nav_real_t arw = prior->gyro_arw_rad_rts;
    const nav_real_t n0 = zbias_n0(prior, dt);
    zb->bias_rps = (zb->sum_rps + zb->sum_lo_rps) / ((nav_real_t)zb->n + n0);
    /* the estimate moved by 1 / (n + n0) of this sample's difference from it (dr_acc.h) */
    dr_acc_hold(&ln->acc, dt, prior->gyro_bias_rw_rps_rts,
                NAV_C(1.0) / ((nav_real_t)zb->n + n0), arw * arw / dt);
}

nav_real_t zbias_sigma_rps(const zbias_t *zb, const zbias_prior_t *prior, nav_real_t dt_s,
                           nav_real_t elapsed_s)
{
    /* sb^2 n0 / (n + n0): the prior's weight n0 against n samples of variance ARW^2 / dt */
    const nav_real_t sb = prior->gyro_bias_rps;
    const nav_real_t n0 = zbias_n0(prior, dt_s);
    const nav_real_t rw = prior->gyro_bias_rw_rps_rts;
    const nav_real_t var = sb * sb * n0 / ((nav_real_t)zb->n + n0) + rw * rw * elapsed_s;
    return nav_sqrt(var < sb * sb ? var : sb * sb);
}

/* returns 1 if the dead reckoning refused the step */
static int odometer_step(landnav_t *ln, const zbias_prior_t *prior, sins_t *nav, dr_t *dr,
                         const odo_t *odo, nav_real_t dtheta_z_rad, nav_real_t dt)
{
    nav_real_t roll, pitch, heading;
    sins_euler(nav, &roll, &pitch, &heading);
    const nav_real_t ds = odo->speed_mps * dt;
    if (dr_step(dr, ds, heading, pitch) != NAV_OK) {
        return 1;
    }
    dr_acc_move(&ln->acc, dr->step_e_m, dr->step_n_m, dtheta_z_rad, dt,
                prior->gyro_arw_rad_rts, prior->gyro_bias_rw_rps_rts);
    const nav_real_t v = odo->speed_mps / (NAV_C(1.0) + dr->mu) * nav_cos(pitch);
    const nav_real_t hc = heading - dr->dh_rad;
    const nav_real_t v_n[3] = {v * nav_sin(hc), v * nav_cos(hc), nav->v_n_mps[2]};
    (void)sins_set_velocity(nav, v_n);
    (void)sins_set_position(nav, &dr->pos);
    sins_set_height_ref(nav, geo_h_m(&dr->pos));
    return 0;
}

nav_real_t landnav_car_yaw(const sins_t *nav, const imu_inc_t *inc)
{
    mat3_t C;
    quat_to_dcm(nav->q_bn, &C);
    nav_real_t v_fwd = NAV_C(0.0);
    for (int i = 0; i < 3; i++) {
        v_fwd += C.m[i][1] * nav->v_n_mps[i];
    }
    nav_real_t w_ie_b[3];
    sins_earth_rate_b(nav, w_ie_b);
    nav_real_t dtheta = w_ie_b[2] * inc->dt_s;
    if (nav_fabs(v_fwd) > APP_STUCK_YAW_MIN_MPS) {
        dtheta -= (inc->dv_b_mps[0] - NAV_C(STD_GRAVITY_MPS2) * C.m[2][0] * inc->dt_s) / v_fwd;
    }
    return dtheta;
}

int landnav_step(landnav_t *ln, zbias_t *zb, const zbias_prior_t *prior, sins_t *nav, dr_t *dr,
                 odo_t *odo, imu_inc_t *inc, nav_real_t *yaw_rate_rps)
{
    int refused = 0;
    const nav_real_t raw_z = inc->dtheta_b_rad[2];
    if (ln->yaw_car != 0u) {
        inc->dtheta_b_rad[2] = landnav_car_yaw(nav, inc);
    } else {
        inc->dtheta_b_rad[2] -= zb->bias_rps * inc->dt_s;
    }
    *yaw_rate_rps = inc->dtheta_b_rad[2] / inc->dt_s;
    if (sins_step(nav, inc) != NAV_OK) {
        /* as fusion_imu_step: the sample's time passes for the wheel speeds, and nothing
         * else takes its refused increments (not the standstill's bias, not the dead
         * reckoning's heading) */
        odo_age(odo, inc->dt_s);
        return 1;
    }
    odo_tick(odo, inc->dt_s, *yaw_rate_rps);
    if (odo->standing) {
        standstill_step(ln, zb, prior, nav, raw_z, inc->dt_s);
        ln->output_dr = 1u;
    } else {
        ln->holding = 0u;
        if (odo->valid) {
            refused += odometer_step(ln, prior, nav, dr, odo, inc->dtheta_b_rad[2], inc->dt_s);
            ln->output_dr = 1u;
        } else {
            /* no odometer: the free SINS carries on, dead reckoning follows it; once it
             * carried the car (its own speed above APP_ODO_MIN_SPEED_MPS: not the first
             * samples at rest before the first wheel frame) the dead reckoning's error
             * model no longer holds */
            dr_set_position(dr, &nav->pos);
            ln->output_dr = 0u;
            const nav_real_t *v = nav->v_n_mps;
            if (v[0] * v[0] + v[1] * v[1] > APP_ODO_MIN_SPEED_MPS * APP_ODO_MIN_SPEED_MPS) {
                ln->acc.valid = 0u;
            }
        }
    }
    return refused;
}

void landnav_restart(landnav_t *ln)
{
    ln->output_dr = 0u;
    ln->holding = 0u;
    ln->acc.valid = 0u;
}

void landnav_release_hold(landnav_t *ln)
{
    ln->holding = 0u;
}
