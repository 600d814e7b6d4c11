/*
 * landnav.h - the land navigation system without the Kalman filter (seed 000): the
 * strapdown step with the standstill gyro bias removed, standstill (zero velocity, the
 * heading held, the z gyro bias estimated), and dead reckoning with the odometer along
 * the SINS heading, which is then the output.
 *
 * Standstill (odo.h: every wheel at zero, the body not turning): the car neither moves
 * nor turns, whatever the sensors' errors say (seed 000: stillness keeps the SINS from
 * drifting). Velocity is set to zero, the heading is held where it was when the car
 * stopped, and the z gyro's reading minus the Earth's rate is a measurement of its bias.
 * The bias estimate is the posterior mean of a constant with prior N(0, sigma_b^2) from
 * samples of variance ARW^2 / dt:  b = sum(r_k) / (n + n0),  n0 = ARW^2 / (dt sigma_b^2);
 * it is subtracted from every later sample.
 *
 * Moving with a valid odometer: dead reckoning (seed 000 eqs 1-4, 11-12) is the output;
 * the SINS takes the odometer's velocity along the compensated heading (seed 000: the
 * odometer velocity damps the SINS velocity errors) and the dead-reckoned position, so
 * that it stays a good attitude and heading reference whatever the drive's length.
 */
#ifndef NAVECU_LANDNAV_H
#define NAVECU_LANDNAV_H

#include <stdint.h>

#include "dr.h"
#include "dr_acc.h"
#include "odo.h"
#include "sins.h"

/* The z gyro bias learnt at standstill: it belongs to the IMU, not to a trip, and
 * survives a navigation reset. */
typedef struct {
    nav_real_t sum_rps, sum_lo_rps; /* sum of (gyro z - Earth rate) at standstill */
    uint32_t n;                     /* samples in the sum */
    nav_real_t bias_rps;            /* the estimate applied to every sample */
} zbias_t;

typedef struct {
    uint8_t output_dr;          /* the dead-reckoned solution is the output (mode 4) */
    uint8_t holding;            /* standstill: heading held at hold_heading_rad */
    uint8_t yaw_car;            /* the gyro axis nearest the car's z is stuck (the
                                   application's, per sample): the yaw increment is the
                                   car's, landnav_car_yaw, here and in the filter's step */
    nav_real_t hold_heading_rad;
    dr_acc_t acc;               /* the dead reckoning's accuracy (dr_acc.h), started by
                                   the application with the navigation */
} landnav_t;

/* The gyro's noise for the bias estimate: ARW (rad/sqrt(s)), turn-on bias 1-sigma (rad/s);
 * and for the accuracy, its in-run instability (rad/s/sqrt(s)). */
typedef struct {
    nav_real_t gyro_arw_rad_rts;
    nav_real_t gyro_bias_rps;
    nav_real_t gyro_bias_rw_rps_rts;
} zbias_prior_t;

/* The z bias estimate's 1-sigma (rad/s): the posterior of a constant from its prior and
 * the standstill samples so far (dt_s the IMU interval), and the bias's walk (the
 * instability) over elapsed_s since the last of them, no wider than the prior (a bias
 * stays within its turn-on spread). */
nav_real_t zbias_sigma_rps(const zbias_t *zb, const zbias_prior_t *prior, nav_real_t dt_s,
                           nav_real_t elapsed_s);

/* The yaw angle increment (rad) of a car that does not slip sideways, for a stuck yaw
 * gyro (docs/kalman.md): its lateral specific force is the forward speed times the yaw
 * rate, w_z = -(f_x - g C_bn[2][0]) / v_y (x right, y forward, z up; the gravity's share
 * by the navigator's roll and pitch, a banked road's; v_y the navigator's forward speed,
 * signed, so reversing holds), 0 below APP_STUCK_YAW_MIN_MPS; plus the Earth's rate about
 * the body z, which the strapdown step takes off (the transport rate, 3e-6 rad/s at
 * 20 m/s, left out). inc: the sample's increments in the car's axes, the accelerometer's
 * bias already taken off where an estimate exists. */
nav_real_t landnav_car_yaw(const sins_t *nav, const imu_inc_t *inc);

/* One IMU sample (SI increments; the z angle is bias-compensated here, or the car's with
 * ln->yaw_car) without the filter: the strapdown step, then standstill, dead reckoning, or
 * the free SINS. *yaw_rate gets the compensated body z rate (rad/s). Returns the number of
 * steps the core refused (count them in nav_rejected). */
int landnav_step(landnav_t *ln, zbias_t *zb, const zbias_prior_t *prior, sins_t *nav, dr_t *dr,
                 odo_t *odo, imu_inc_t *inc, nav_real_t *yaw_rate_rps);

/* The Kalman filter runs: no heading held at standstill (its zero-rate update holds it). */
void landnav_release_hold(landnav_t *ln);

/* A new navigator: no heading held, the free SINS is the output until the odometer says
 * otherwise; the accuracy not known until the application starts it. */
void landnav_restart(landnav_t *ln);

#endif /* NAVECU_LANDNAV_H */
