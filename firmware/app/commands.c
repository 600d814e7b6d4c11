/* commands.c - what the operator's commands do; see commands.h. */
#include "commands.h"

#include "app_tuning.h"
#include "navecu_can.h"

static void refuse(app_t *a, cmd_refusal_t why)
{
    const app_diag_t d = app_diag_of(a);
    a->keep.cmd_refusal = (uint8_t)why;
    app_diag_reject(&d, &a->keep.health.cmd_rejected);
}

int commands_car_moving(const app_t *a)
{
    const odo_t *o = &a->keep.odo;
    const uint64_t fresh = (uint64_t)APP_NO_GNSS_S * a->cfg.imu_rate_hz;
    return ((o->valid && !o->zero) ||
            (app_stamp_within(&a->keep.gnss, a->keep.n_samples, fresh) &&
             a->run.fusion.speed_mps > APP_CMD_MOVING_GNSS_MPS))
               ? 1
               : 0;
}

void commands_motion_seen(app_t *a)
{
    align_t *al = &a->run.align;
    if (al->known_valid) {
        al->known_moved = 1u;
    }
    if (a->run.mode == APP_MODE_LEVELLING) {
        /* the commanded point is where the car was: never applied after it moved; a
         * levelling the GNSS-only start began is stopped alike, but no command was
         * refused (the in-motion alignment takes over) */
        const uint8_t commanded = al->commanded;
        const uint8_t kv = al->known_valid, km = al->known_moved;
        const int32_t klat = al->known_lat_e7, klon = al->known_lon_e7;
        app_reset(a);
        a->run.align.known_valid = kv;
        a->run.align.known_moved = km;
        a->run.align.known_lat_e7 = klat;
        a->run.align.known_lon_e7 = klon;
        if (commanded != 0u) {
            refuse(a, CMD_REFUSAL_STALE_POSITION);
        }
    }
}

void commands_start_navigation(app_t *a, nav_real_t roll_rad, nav_real_t pitch_rad)
{
    if (a->keep.mount_state == (uint8_t)APP_MOUNT_ESTIMATING) {
        a->run.mount_held = 1u; /* no navigation before the mounting is known (app.c) */
        a->run.mode = APP_MODE_FAULT;
        return;
    }
    if (align_start(&a->run.align, roll_rad, pitch_rad, &a->run.nav, &a->run.dr,
                    &a->keep.cal) != NAV_OK) {
        const app_diag_t d = app_diag_of(a);
        app_diag_reject(&d, &a->keep.health.bad_value);
        a->run.mode = APP_MODE_FAULT;
        return;
    }
    landnav_restart(&a->run.land);
    if (a->run.align.commanded != 0u) {
        /* the dead reckoning's accuracy from the commanded point and heading (the filter's
         * prior for a commanded heading, with the mounting's part of dH), the calibration
         * in use and the z gyro as far as it is known (dr_acc.h); a start from GNSS has
         * the filter at once, and the accuracy is its */
        const ekf_config_t ec = ekf_default_config();
        nav_real_t s_mu, s_mount;
        /* a stored GNSS point's sigma is not kept: the configured receiver accuracy's,
         * as the filter would take such a fix */
        calib_sigmas(&a->keep.cal, &ec, fusion_fix_sigma_axis_m(a->cfg.gnss_hacc_m), &s_mu,
                     &s_mount);
        const zbias_prior_t zp = app_zbias_prior(&a->cfg);
        const nav_real_t dt = NAV_C(1.0) / (nav_real_t)a->cfg.imu_rate_hz;
        /* the bias walked on since it was last learnt (the filter's drives do not teach
         * the standstill estimate) */
        const uint64_t since_n = a->keep.n_samples - a->keep.zbias_sample;
        const nav_real_t since_s = a->keep.zbias.n > 0u ? (nav_real_t)since_n * dt : NAV_C(0.0);
        dr_acc_start(&a->run.land.acc, APP_KNOWN_POS_SIGMA_M, s_mu,
                     nav_sqrt(ec.heading_rad * ec.heading_rad + s_mount * s_mount),
                     zbias_sigma_rps(&a->keep.zbias, &zp, dt, since_s), a->cfg.gyro_scale);
    }
    a->run.mode = APP_MODE_NAVIGATING;
}

void commands_calibrate_at(app_t *a, hal_t *hal, const geo_pos_t *point, uint8_t source,
                           nav_real_t point_sigma_m)
{
    const int ready = a->run.mode == APP_MODE_NAVIGATING && a->run.land.output_dr &&
                      !a->run.fusion.on;
    dr_cal_t res;
    if (calib_one_point(&a->keep.cal, &a->run.cal, hal, a->keep.n_samples, ready, &a->run.dr,
                        &a->run.nav, point, source, a->cfg.cal_min_base_m, &res) != 0) {
        refuse(a, CMD_REFUSAL_NOT_NOW);
        return;
    }
    dr_acc_calibrated(&a->run.land.acc, point_sigma_m, res.t_e_m, res.t_n_m);
}

static void set_initial_position(app_t *a, const rx_input_t *in)
{
    const align_t *al = &a->run.align;
    if (!al->known_valid) {
        refuse(a, CMD_REFUSAL_NO_KNOWN_POSITION);
        return;
    }
    if (!in->u.command.height_in_range ||
        (in->u.command.heading_valid && !in->u.command.heading_in_range)) {
        refuse(a, CMD_REFUSAL_OUT_OF_RANGE);
        return;
    }
    if (commands_car_moving(a)) {
        refuse(a, CMD_REFUSAL_MOVING); /* docs/can.md: at standstill */
        return;
    }
    if (al->known_moved) {
        refuse(a, CMD_REFUSAL_STALE_POSITION); /* where the car was, not where it is */
        return;
    }
    const geo_pos_t pos = align_pos_of(al->known_lat_e7, al->known_lon_e7, in->u.command.h_cm);
    app_reset(a);
    align_set_initial(&a->run.align, &pos, in->u.command.h_cm, in->u.command.heading_valid,
                      in->u.command.heading_rad);
    a->run.align.commanded = 1u;
    if (align_ready(&a->run.align)) {
        a->run.mode = APP_MODE_LEVELLING;
        align_level_restart(&a->run.align);
    }
}

static void control(app_t *a, hal_t *hal, const rx_input_t *in)
{
    align_t *al = &a->run.align;
    switch (in->u.command.command) {
    case RX_CMD_NONE:
        break;
    case RX_CMD_RESET:
        app_reset(a);
        break;
    case RX_CMD_SET_INITIAL_POSITION:
        set_initial_position(a, in);
        break;
    case RX_CMD_STORE_CALIBRATION:
    case RX_CMD_ERASE_CALIBRATION:
        /* destructive: any node on the bus could send them, so they moved to UDS
         * RoutineControl 0x0203 / 0x0201 (extended session, SecurityAccess): refused and
         * counted here (cmd_rejected) */
        refuse(a, CMD_REFUSAL_MOVED_TO_UDS);
        break;
    case RX_CMD_CALIBRATE_HERE: /* the last CMD_KnownPosition is where the car is */
        if (!al->known_valid) {
            calib_not_ready(&a->keep.cal);
            refuse(a, CMD_REFUSAL_NO_KNOWN_POSITION);
            break;
        }
        al->known_valid = 0u; /* a point is used once: the next needs its own */
        const geo_pos_t point = align_pos_of(al->known_lat_e7, al->known_lon_e7, 0);
        commands_calibrate_at(a, hal, &point,
                              NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_KNOWN_POSITION_CHOICE,
                              APP_KNOWN_POS_SIGMA_M);
        break;
    case RX_CMD_CALIBRATE_AT_GNSS: /* at the next accepted fix */
        if (a->run.mode != APP_MODE_NAVIGATING) {
            calib_not_ready(&a->keep.cal);
            refuse(a, CMD_REFUSAL_NOT_NOW);
            break;
        }
        a->run.cal.at_gnss = 1u;
        break;
    default:
        refuse(a, CMD_REFUSAL_UNDEFINED);
        break;
    }
}

void commands_handle(app_t *a, hal_t *hal, const rx_input_t *in)
{
    if (in->kind == RX_KNOWN_POSITION) {
        a->run.align.known_lat_e7 = in->u.position.lat_e7;
        a->run.align.known_lon_e7 = in->u.position.lon_e7;
        a->run.align.known_valid = 1u;
        a->run.align.known_moved = commands_car_moving(a) ? 1u : 0u;
    } else if (in->kind == RX_INITIAL_ATTITUDE) {
        /* roll and pitch from another source end levelling at once (a perfect start) */
        if (a->run.mode != APP_MODE_LEVELLING) {
            refuse(a, CMD_REFUSAL_NOT_NOW); /* only between SetInitialPosition and navigating */
            return;
        }
        commands_start_navigation(a, in->u.attitude.roll_rad, in->u.attitude.pitch_rad);
    } else {
        control(a, hal, in);
    }
}
