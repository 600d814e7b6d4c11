/*
 * dr_acc.h - the dead reckoning's accuracy: the covariance of its error (dr.h), what
 * NAV_Status HorizAccuracy reports while the dead reckoning is the output (no filter yet:
 * a start without GNSS, docs/odometry.md).
 *
 * Seed 000's error model (eqs 5-6) with the z gyro's drift: the dead-reckoned position's
 * error against the truth, east and north, grows with each compensated step (dE, dN) as
 *     d(err_E) = mu dE + psi dN,   d(err_N) = mu dN - psi dE
 * where mu is the odometer scale's residual error and psi the heading's (the SINS heading
 * less dH against the true course: SINS heading error and mounting together, eqs 5-6's
 * dH), and the heading drifts with the z gyro's residual bias b while the car moves
 * and with its scale factor error s times the angle turned (standing, landnav.h holds the
 * heading):
 *     d(psi) = b dt + s d(theta) + n,   db = w
 * (n the gyro's angle random walk, w its in-run instability, a random walk)
 * The six errors x = (err_E m, err_N m, mu, psi rad, b rad/s, s) are propagated as a
 * covariance, P' = F P F' + Q, exactly for this linear model; the standstill's bias
 * estimate (landnav.h: b_new = b_old + K (sample - b_old), K its gain) is applied to b's
 * error as it is: e_b' = (1 - K) e_b - K noise. HorizAccuracy = sqrt(P_EE + P_NN).
 *
 * A one-point calibration (dr.h) resets the position to the point (its sigma) and replaces
 * mu and psi by the calibration's own errors: the point's and the base's position errors
 * over the base length (eqs 9-10 to first order: sqrt(s_point^2 + s_base^2) / base per
 * axis, for mu and for dH alike), correlated with the position's through the point's error
 * e (mu's error e.t / |t|^2, psi's (e_E t_N - e_N t_E) / |t|^2: driving on along t, the
 * scale's error adds to the point's), and for psi also the heading's drift over the leg (dH is
 * the leg's heading error averaged over its distance; the heading at the point is off it by
 * up to all of the drift: half for a drift that grew linearly along a uniformly driven
 * leg, all of it when the leg's distance was driven at its start). The gyro's errors stay;
 * their correlation with what was reset is dropped.
 */
#ifndef NAVECU_DR_ACC_H
#define NAVECU_DR_ACC_H

#include "nav_types.h"

#define DR_ACC_E 0   /* east error, m */
#define DR_ACC_N 1   /* north error, m */
#define DR_ACC_MU 2  /* odometer scale error */
#define DR_ACC_PSI 3 /* heading error, rad */
#define DR_ACC_B 4   /* z gyro bias residual, rad/s */
#define DR_ACC_S 5   /* z gyro scale factor error */
#define DR_ACC_NX 6

typedef struct {
    nav_real_t P[DR_ACC_NX][DR_ACC_NX]; /* the errors' covariance (states above) */
    nav_real_t psi_var_base;            /* P[PSI][PSI] at the base: the leg's drift since */
    nav_real_t base_var_m2;             /* the base position's variance per axis */
    uint8_t valid;                      /* 0: the model does not hold (not started, the
                                           free SINS carried the position) */
} dr_acc_t;

#define dr_acc_start NAV_SYM(dr_acc_start)
#define dr_acc_move NAV_SYM(dr_acc_move)
#define dr_acc_hold NAV_SYM(dr_acc_hold)
#define dr_acc_calibrated NAV_SYM(dr_acc_calibrated)
#define dr_acc_sigma_h_m NAV_SYM(dr_acc_sigma_h_m)
#define dr_acc_sigma_heading_rad NAV_SYM(dr_acc_sigma_heading_rad)

/* Start at the base: the position's sigma per axis (m), the scale's and the heading's
 * errors (1 sigma), the z gyro bias's (rad/s) and scale factor's; uncorrelated. */
void dr_acc_start(dr_acc_t *a, nav_real_t pos_sigma_m, nav_real_t mu_sigma,
                  nav_real_t psi_sigma_rad, nav_real_t b_sigma_rps, nav_real_t s_sigma);

/* One IMU interval dt_s while moving, the dead reckoning's compensated step (dE, dN, m),
 * the angle the z gyro turned through in it (rad); the gyro's angle random walk arw
 * (rad/sqrt(s)) and its bias's instability b_rw (rad/s/sqrt(s)). Not finite: the model
 * no longer holds. */
void dr_acc_move(dr_acc_t *a, nav_real_t de_m, nav_real_t dn_m, nav_real_t dtheta_rad,
                 nav_real_t dt_s, nav_real_t arw_rad_rts, nav_real_t b_rw_rps_rts);

/* One IMU interval at a standstill: the heading held, the bias estimated with gain
 * gain (0..1) from a sample of variance sample_var (rad^2/s^2); its instability as in
 * dr_acc_move. */
void dr_acc_hold(dr_acc_t *a, nav_real_t dt_s, nav_real_t b_rw_rps_rts, nav_real_t gain,
                 nav_real_t sample_var);

/* A one-point calibration at a point known to point_sigma_m per axis, t (t_e_m, t_n_m) the
 * point less the base (dr_cal_t): the point is the new base. Nothing while the model does
 * not hold (valid 0: it stays unknown; the calibration's leg was not the model's). */
void dr_acc_calibrated(dr_acc_t *a, nav_real_t point_sigma_m, nav_real_t t_e_m,
                       nav_real_t t_n_m);

/* The horizontal accuracy, sqrt(P_EE + P_NN) (m, as HorizAccuracy); -1 when not valid. */
nav_real_t dr_acc_sigma_h_m(const dr_acc_t *a);

/* The heading's accuracy, sqrt(P_psi,psi) (rad, as HeadingAccuracy); -1 when not valid. */
nav_real_t dr_acc_sigma_heading_rad(const dr_acc_t *a);

#endif /* NAVECU_DR_ACC_H */
