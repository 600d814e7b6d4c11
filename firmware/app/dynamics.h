/*
 * dynamics.h - the vehicle's motion for the outputs that other ECUs use beside position
 * (seed 001 lists "the attitude angles and their rates, the velocities and their
 * derivatives"): angular rates and acceleration in the vehicle frame, the ENU velocity
 * derivative, the rates of roll, pitch and heading, each the mean over the output
 * interval of the IMU samples in it. The angle rates come from the body rate relative to
 * the local-level frame through the Euler kinematics of docs/frames.md' 3-1-2 sequence
 * (C_bn = Rz(-H) Rx(p) Ry(r)):
 *     w_nb_b = (cr p' + sr cp H',  r' - sp H',  sr p' - cr cp H')
 *  => p' = cr wx + sr wz,  H' = (sr wx - cr wz) / cp,  r' = wy + sp H'
 * not from differences of the estimated angles, which would carry the filter's
 * corrections as rate spikes.
 *
 * Vehicle frame: x right, y forward, z up, the IMU's axes turned by the mounting estimate
 * (yaw: the IMU's forward axis clockwise of the car's; pitch: the IMU's nose up of the
 * car's; the same convention as the filter's odometer rows, firmware/nav/ekf.h). The
 * acceleration is relative to the Earth, without gravity: the mean specific force in ENU
 * plus the normal gravity; the Coriolis and transport-rate terms (2 w_ie x v + w_en x v,
 * below 5 mm/s^2 at 40 m/s) are neglected.
 */
#ifndef NAVECU_DYNAMICS_H
#define NAVECU_DYNAMICS_H

#include <stdint.h>

#include "sins.h"

typedef struct {
    nav_real_t w_sum_b_rad[3];   /* compensated angle increments, IMU axes */
    nav_real_t dv_sum_n_mps[3];  /* compensated velocity increments, ENU */
    nav_real_t t_s;              /* time accumulated */
} dynamics_t;

/* The motion over one output interval, in SI units. */
typedef struct {
    nav_real_t rate_v_rps[3];    /* angular rate, vehicle frame */
    nav_real_t accel_v_mps2[3];  /* acceleration without gravity, vehicle frame */
    nav_real_t accel_n_mps2[3];  /* the same, ENU: the velocity's derivative */
    nav_real_t att_rate_rps[3];  /* d/dt of roll, pitch, heading (clockwise positive) */
} dynamics_out_t;

/* One IMU sample's compensated increments after the navigator's step. */
void dynamics_sample(dynamics_t *d, const sins_t *nav, const imu_inc_t *inc);

/* The mean motion since the last call, with the mounting (rad); restarts the interval.
 * Returns 0, or -1 when no sample came since the last call (*out untouched). */
int dynamics_take(dynamics_t *d, const sins_t *nav, nav_real_t mount_yaw_rad,
                  nav_real_t mount_pitch_rad, dynamics_out_t *out);

#endif /* NAVECU_DYNAMICS_H */
