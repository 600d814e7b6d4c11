/* align.c - initialisation, levelling, start and re-acquisition; see align.h. */
#include "align.h"

#include "app_tuning.h"

void align_set_initial(align_t *al, const geo_pos_t *pos, int32_t h_cm, int heading_valid,
                       nav_real_t heading_rad)
{
    al->pos_valid = 1u;
    al->pos = *pos;
    al->pos.h = (int64_t)h_cm * 10 * GEO_LSB_PER_MM;
    al->h_cm = h_cm;
    al->heading_valid = heading_valid ? 1u : 0u;
    al->heading_rad = heading_rad;
}

int align_ready(const align_t *al)
{
    return al->pos_valid && al->heading_valid;
}

void align_level_restart(align_t *al)
{
    al->level_n = 0u;
    for (int i = 0; i < 3; i++) {
        al->level_wsum[i] = NAV_C(0.0);
        al->level_wsum_lo[i] = NAV_C(0.0);
    }
}

int align_level_sample(align_t *al, const int32_t v_raw[3], uint32_t n_total)
{
    al->level_n++;
    const nav_real_t k = (nav_real_t)al->level_n;
    const nav_real_t w = k * ((nav_real_t)n_total - k);
    for (int i = 0; i < 3; i++) {
        nav_acc_add(&al->level_wsum[i], &al->level_wsum_lo[i], w * (nav_real_t)v_raw[i]);
    }
    return al->level_n >= n_total;
}

void align_level_attitude(const align_t *al, const mounting_t *mount, nav_real_t *roll_rad,
                          nav_real_t *pitch_rad)
{
    nav_real_t f[3];
    mounting_to_vehicle(mount, al->level_wsum, f);
    const nav_real_t fx = f[0];
    const nav_real_t fy = f[1];
    const nav_real_t fz = f[2];
    *roll_rad = nav_atan2(-fx, fz);
    *pitch_rad = nav_atan2(fy, nav_sqrt(fx * fx + fz * fz));
}

geo_pos_t align_pos_of(int32_t lat_e7, int32_t lon_e7, int32_t h_cm)
{
    const geo_pos_t p = {(int64_t)lat_e7 * GEO_LSB_PER_DEG_E7, (int64_t)lon_e7 * GEO_LSB_PER_DEG_E7,
                         (int64_t)h_cm * 10 * GEO_LSB_PER_MM};
    return p;
}

/* The navigator started at pos (height reference h_cm) with velocity v_enu_mps and that
 * attitude, the dead reckoning at pos with the calibration: NAV_OK or the first error
 * (every start: commanded, in motion, re-acquired) */
static int nav_start(const geo_pos_t *pos, int32_t h_cm, const nav_real_t v_enu_mps[3],
                     nav_real_t roll_rad, nav_real_t pitch_rad, nav_real_t heading_rad,
                     sins_t *nav, dr_t *dr, const calib_t *cal)
{
    nav_real_t q[4];
    quat_from_euler(roll_rad, pitch_rad, heading_rad, q);
    const sins_config_t scfg = sins_default_config();
    int rc = sins_init(nav, &scfg, pos, v_enu_mps, q);
    if (rc == NAV_OK) {
        rc = calib_start_dr(cal, dr, pos);
    }
    sins_set_height_ref(nav, (nav_real_t)h_cm * NAV_C(0.01));
    return rc;
}

int align_start(const align_t *al, nav_real_t roll_rad, nav_real_t pitch_rad, sins_t *nav,
                dr_t *dr, const calib_t *cal)
{
    static const nav_real_t v0[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    return nav_start(&al->pos, al->h_cm, v0, roll_rad, pitch_rad, al->heading_rad, nav, dr, cal);
}

int align_gnss(align_t *al, const gnss_fix_t *fix, int wheels_turn)
{
    if (fix->speed_mps >= APP_GNSS_COURSE_MIN_MPS) {
        al->course_rad = fix->course_rad;
        al->course_valid = 1u;
        al->course_dyaw_rad = NAV_C(0.0);
    }
    /* the course is the heading while the z gyro says the car has not turned since (its
     * uncompensated bias turns that too: an old course runs out) */
    if (al->course_valid && nav_fabs(al->course_dyaw_rad) <= APP_GNSS_COURSE_TURN_RAD &&
        fix->has_h && wheels_turn == 0 && fix->speed_mps >= NAV_C(0.0) &&
        fix->speed_mps <= APP_GNSS_STILL_MPS) {
        align_set_initial(al, &fix->pos, fix->h_cm, 1, al->course_rad);
        return 1;
    }
    return 0;
}

void align_reacquire_begin(align_t *al, const sins_t *nav, nav_real_t mount_yaw_rad,
                           int moving)
{
    al->reacq_moved = moving != 0 ? 1u : 0u;
    nav_real_t roll, pitch, heading;
    sins_euler(nav, &roll, &pitch, &heading);
    al->reacq_roll_rad = roll;
    al->reacq_pitch_rad = pitch;
    al->reacq_heading_rad = heading;
    al->reacq_mount_rad = mount_yaw_rad;
    al->reacquire = 1u;
}

int align_reacquire_ready(const align_t *al, const gnss_fix_t *fix)
{
    return fix->has_vel && fix->has_h &&
           (fix->speed_mps >= APP_GNSS_COURSE_MIN_MPS ||
            (al->reacq_moved == 0u && fix->speed_mps >= NAV_C(0.0) &&
             fix->speed_mps <= APP_GNSS_STILL_MPS));
}

int align_reacquire(align_t *al, const gnss_fix_t *fix, sins_t *nav, dr_t *dr,
                    const calib_t *cal, int reversing)
{
    const nav_real_t heading =
        fix->speed_mps >= APP_GNSS_COURSE_MIN_MPS
            ? fix->course_rad + al->reacq_mount_rad + (reversing != 0 ? NAV_PI : NAV_C(0.0))
            : al->reacq_heading_rad;
    if (nav_start(&fix->pos, fix->h_cm, fix->v_enu_mps, al->reacq_roll_rad, al->reacq_pitch_rad,
                  heading, nav, dr, cal) != NAV_OK) {
        return NAV_EINVAL;
    }
    al->reacquire = 0u;
    return NAV_OK;
}

void align_motion_sample(align_t *al, const imu_inc_t *inc)
{
    al->course_dyaw_rad += inc->dtheta_b_rad[2];
    if (!al->mot_open) {
        return;
    }
    for (int i = 0; i < 3; i++) {
        nav_acc_add(&al->mot_dv_mps[i], &al->mot_dv_lo_mps[i], inc->dv_b_mps[i]);
    }
    al->mot_dyaw_rad += inc->dtheta_b_rad[2];
    al->mot_t_s += inc->dt_s;
}

/* the epoch's forward speed (signed: the wheels say reversing) if it is a driving one */
static int motion_speed(const gnss_fix_t *fix, const align_odo_t *odo, nav_real_t *v_mps)
{
    const nav_real_t sacc = fix->sacc_mps > APP_GNSS_SACC_MIN_MPS ? fix->sacc_mps
                                                                  : APP_GNSS_SACC_MIN_MPS;
    if (!fix->has_vel || !fix->has_h || fix->speed_mps < APP_GNSS_COURSE_MIN_MPS ||
        fix->speed_mps < APP_INMOTION_SPEED_SIGMAS * sacc) {
        return 0;
    }
    *v_mps = (odo->valid && odo->speed_mps < NAV_C(0.0)) ? -fix->speed_mps : fix->speed_mps;
    return 1;
}

static void motion_open(align_t *al, nav_real_t v_mps, const align_odo_t *odo)
{
    for (int i = 0; i < 3; i++) {
        al->mot_dv_mps[i] = NAV_C(0.0);
        al->mot_dv_lo_mps[i] = NAV_C(0.0);
    }
    al->mot_dyaw_rad = NAV_C(0.0);
    al->mot_t_s = NAV_C(0.0);
    al->mot_v0_gnss_mps = v_mps;
    al->mot_odo_valid = odo->valid;
    al->mot_v0_odo_mps = odo->speed_mps;
    al->mot_open = 1u;
}

int align_motion_epoch(align_t *al, const gnss_fix_t *fix, const align_odo_t *odo,
                       nav_real_t *roll_rad, nav_real_t *pitch_rad, nav_real_t *heading_rad)
{
    nav_real_t v = NAV_C(0.0);
    if (!motion_speed(fix, odo, &v)) {
        al->mot_open = 0u;
        return 0;
    }
    const nav_real_t T = al->mot_t_s;
    if (!al->mot_open || T > APP_INMOTION_WINDOW_MAX_S ||
        (al->mot_v0_gnss_mps < NAV_C(0.0)) != (v < NAV_C(0.0))) {
        motion_open(al, v, odo);
        return 0;
    }
    if (T < APP_INMOTION_WINDOW_S) {
        return 0; /* the window goes on to the next epoch */
    }
    /* the along-track change of speed: the odometer's when it was valid throughout */
    nav_real_t dv_along = v - al->mot_v0_gnss_mps;
    nav_real_t sv = fix->sacc_mps > APP_GNSS_SACC_MIN_MPS ? fix->sacc_mps : APP_GNSS_SACC_MIN_MPS;
    if (al->mot_odo_valid != 0u && odo->valid != 0u) {
        dv_along = odo->speed_mps - al->mot_v0_odo_mps;
        sv = APP_INMOTION_ODO_SIGMA_MPS;
    }
    const nav_real_t v_mean = NAV_C(0.5) * (v + al->mot_v0_gnss_mps);
    /* gravity's share of the summed specific force: f less (-v w_z, dv/dt, 0) */
    const nav_real_t gx = al->mot_dv_mps[0] + al->mot_dv_lo_mps[0] + v_mean * al->mot_dyaw_rad;
    const nav_real_t gy = al->mot_dv_mps[1] + al->mot_dv_lo_mps[1] - dv_along;
    const nav_real_t gz = al->mot_dv_mps[2] + al->mot_dv_lo_mps[2];
    *roll_rad = nav_atan2(-gx, gz);
    *pitch_rad = nav_atan2(gy, nav_sqrt(gx * gx + gz * gz));
    nav_real_t h = fix->course_rad + (v < NAV_C(0.0) ? NAV_PI : NAV_C(0.0));
    if (h >= NAV_C(2.0) * NAV_PI) {
        h -= NAV_C(2.0) * NAV_PI;
    }
    *heading_rad = h;
    const nav_real_t sacc = fix->sacc_mps > APP_GNSS_SACC_MIN_MPS ? fix->sacc_mps
                                                                  : APP_GNSS_SACC_MIN_MPS;
    const nav_real_t sh = sacc / fix->speed_mps;
    al->mot_heading_sigma_rad =
        sh > APP_INMOTION_HEADING_SIGMA_MIN_RAD ? sh : APP_INMOTION_HEADING_SIGMA_MIN_RAD;
    const nav_real_t st = NAV_C(1.4142) * sv / (T * NAV_C(9.8)); /* a / g: the tilt's error */
    al->mot_tilt_sigma_rad =
        st > APP_INMOTION_TILT_SIGMA_MIN_RAD ? st : APP_INMOTION_TILT_SIGMA_MIN_RAD;
    al->mot_open = 0u;
    return 1;
}

int align_motion_start(const gnss_fix_t *fix, nav_real_t roll_rad, nav_real_t pitch_rad,
                       nav_real_t heading_rad, sins_t *nav, dr_t *dr, const calib_t *cal)
{
    return nav_start(&fix->pos, fix->h_cm, fix->v_enu_mps, roll_rad, pitch_rad, heading_rad, nav,
                     dr, cal) != NAV_OK
               ? NAV_EINVAL
               : NAV_OK;
}
