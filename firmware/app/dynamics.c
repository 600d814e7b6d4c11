/* dynamics.c - mean rates and accelerations over an output interval; see dynamics.h. */
#include "dynamics.h"

void dynamics_sample(dynamics_t *d, const sins_t *nav, const imu_inc_t *inc)
{
    mat3_t C;
    quat_to_dcm(nav->q_bn, &C);
    nav_real_t dv_n[3];
    mat3_mul_vec(&C, inc->dv_b_mps, dv_n);
    for (int i = 0; i < 3; i++) {
        d->w_sum_b_rad[i] += inc->dtheta_b_rad[i];
        d->dv_sum_n_mps[i] += dv_n[i];
    }
    d->t_s += inc->dt_s;
}

/* a vector of the IMU's axes in the vehicle's: the mounting yaw about z, then its pitch
 * about x (to first order: x_car = x + yaw y, z_car = z + pitch y, as in ekf_meas.c) */
static void to_vehicle(nav_real_t yaw, nav_real_t pitch, const nav_real_t b[3], nav_real_t v[3])
{
    const nav_real_t cy = nav_cos(yaw), sy = nav_sin(yaw);
    const nav_real_t cp = nav_cos(pitch), sp = nav_sin(pitch);
    const nav_real_t y1 = -sy * b[0] + cy * b[1];
    v[0] = cy * b[0] + sy * b[1];
    v[1] = cp * y1 - sp * b[2];
    v[2] = sp * y1 + cp * b[2];
}

int dynamics_take(dynamics_t *d, const sins_t *nav, nav_real_t mount_yaw_rad,
                  nav_real_t mount_pitch_rad, dynamics_out_t *out)
{
    if (!(d->t_s > NAV_C(0.0))) {
        return -1;
    }
    const nav_real_t T = d->t_s;
    const nav_real_t w_b[3] = {d->w_sum_b_rad[0] / T, d->w_sum_b_rad[1] / T, d->w_sum_b_rad[2] / T};
    to_vehicle(mount_yaw_rad, mount_pitch_rad, w_b, out->rate_v_rps);
    const nav_real_t g = earth_gravity(nav_sin(geo_lat_rad(&nav->pos)), geo_h_m(&nav->pos));
    for (int i = 0; i < 3; i++) {
        out->accel_n_mps2[i] = d->dv_sum_n_mps[i] / T;
    }
    out->accel_n_mps2[2] -= g; /* specific force + gravity (ENU: gravity is -g up) */
    mat3_t C;
    quat_to_dcm(nav->q_bn, &C);
    nav_real_t a_b[3];
    mat3t_mul_vec(&C, out->accel_n_mps2, a_b);
    to_vehicle(mount_yaw_rad, mount_pitch_rad, a_b, out->accel_v_mps2);
    /* the Euler kinematics (dynamics.h) on the body rate relative to the local level */
    nav_real_t w_ie_b[3], roll, pitch, heading;
    sins_earth_rate_b(nav, w_ie_b);
    sins_euler(nav, &roll, &pitch, &heading);
    const nav_real_t wx = w_b[0] - w_ie_b[0], wy = w_b[1] - w_ie_b[1], wz = w_b[2] - w_ie_b[2];
    const nav_real_t cr = nav_cos(roll), sr = nav_sin(roll);
    const nav_real_t cp = nav_cos(pitch), sp = nav_sin(pitch);
    const nav_real_t h_rate = nav_fabs(cp) > NAV_C(1e-3) ? (sr * wx - cr * wz) / cp : NAV_C(0.0);
    out->att_rate_rps[0] = wy + sp * h_rate;
    out->att_rate_rps[1] = cr * wx + sr * wz;
    out->att_rate_rps[2] = h_rate;
    for (int i = 0; i < 3; i++) {
        d->w_sum_b_rad[i] = NAV_C(0.0);
        d->dv_sum_n_mps[i] = NAV_C(0.0);
    }
    d->t_s = NAV_C(0.0);
    return 0;
}
