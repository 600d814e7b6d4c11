/*
 * mount_est.h - the automatic coarse estimate of the IMU's mounting (the rotation
 * mounting.h applies) from the data alone: gravity, the car's accelerations from its
 * wheel speeds and its turns.
 *
 * The IMU's specific force, averaged over windows of MOUNT_EST_WINDOW_S, is f_i = C_iv m +
 * b + noise, with the vehicle-frame model (x right, y forward, z up)
 *     m = (-v w_z, dv/dt, g)
 * (lateral: the centripetal acceleration of a turn at speed v and yaw rate w_z; forward:
 * the derivative of the odometer's speed; down: gravity; at rest m = (0, 0, g)). w_z is
 * the gyro's rate along the current estimate of the vehicle's up axis (the normalised
 * mean specific force). The columns of X = C_iv (the vehicle's axes in the IMU's) are the
 * least-squares solution of the normal equations
 *     X S_mm = S_fm,   S_mm = sum m m^T,  S_fm = sum f m^T
 * (three 3x3 sums, the solution by the adjugate: no iteration, no SVD). The column of g
 * takes the vehicle's up axis (a constant accelerometer bias b is not separable from it:
 * b / g in roll and pitch); the forward column and the up axis crossed with the lateral
 * column both estimate the forward axis, combined by their weights. Orthonormalised
 * (Gram-Schmidt: up first, the forward axis made square to it, right = forward x up),
 * C_vi = X^T gives roll, pitch and yaw in mounting.h's convention.
 *
 * sigma: the residual variance per component s2 = sum |f - X m|^2 / (3 (N - 3)) and the
 * diagonal of S_mm^-1 give each column's standard deviation; roll and pitch take the up
 * column's, yaw the combination of the forward and lateral columns'. The estimate is
 * converged when both sigmas are below sigma_rad and the excitation sum (a_fwd^2 +
 * a_lat^2) dt (m^2/s^3) reaches excite_m2ps3 (the turns and accelerations that make the
 * yaw observable, not only its sigma). Windows are treated as independent: their
 * correlated part (a road's slope, tyre slip) is what the excitation threshold covers.
 *
 * Pure and fixed-size; a sample with a non-finite value, or a window of an implausible
 * specific force (beyond MOUNT_EST_MAX_F_MPS2), is refused and counted in n_refused.
 */
#ifndef NAVECU_MOUNT_EST_H
#define NAVECU_MOUNT_EST_H

#include <stdint.h>

#include "earth.h"
#include "sins.h"

#define MOUNT_EST_WINDOW_S NAV_C(0.5)     /* the averaging window */
#define MOUNT_EST_MAX_F_MPS2 NAV_C(40.0)  /* a window's mean |f| beyond this is refused */
#define MOUNT_EST_G_MPS2 NAV_C(STD_GRAVITY_MPS2) /* gravity of the model (the latitude's is
                                                   within 0.3 %: a scale, no angle) */
#define MOUNT_EST_MIN_WINDOWS 8u          /* below this no estimate */

typedef struct {
    nav_real_t sigma_rad;     /* converged when the sigmas are below this */
    nav_real_t excite_m2ps3;  /* and the excitation reached this */
} mount_est_config_t;

typedef struct {
    nav_real_t rpy_rad[3];    /* roll, pitch, yaw of the IMU in the vehicle (mounting.h) */
    nav_real_t sigma_rp_rad;  /* 1 sigma of roll and pitch (the up axis) */
    nav_real_t sigma_yaw_rad; /* 1 sigma of yaw (NAV_PI: not observed yet) */
    nav_real_t excite_m2ps3;  /* the excitation so far */
    uint32_t n_windows;       /* windows accumulated */
    uint8_t valid;            /* roll and pitch estimated (yaw maybe not: sigma_yaw) */
    uint8_t converged;        /* both sigmas and the excitation within the config */
} mount_est_result_t;

typedef struct {
    mount_est_config_t cfg;
    /* the window in assembly: IMU axes */
    nav_real_t win_dv[3], win_dth[3];
    nav_real_t win_t_s;
    nav_real_t v_start_mps;
    uint8_t have_start;
    /* the sums, compensated (nav_acc_add) */
    nav_real_t s_mm[3][3], s_mm_lo[3][3];
    nav_real_t s_fm[3][3], s_fm_lo[3][3];
    nav_real_t s_ff, s_ff_lo;
    nav_real_t s_f[3], s_f_lo[3];
    nav_real_t excite, excite_lo;
    uint32_t n_windows;
    uint32_t n_refused;
    mount_est_result_t res;   /* the latest solution (mount_est_solve) */
} mount_est_t;

/* Start empty. NAV_OK, or NAV_EINVAL for a sigma or excitation not finite or <= 0 / < 0. */
int mount_est_init(mount_est_t *e, const mount_est_config_t *cfg);

/*
 * One IMU sample's increments in the IMU's own axes (before any mounting), over
 * inc->dt_s, with the odometer's forward speed at its time (speed_valid 0: no speed; the window is
 * dropped). Returns 1 when it closed a window (mount_est_solve then has news), 0
 * otherwise, NAV_EINVAL for a refused sample (counted).
 */
int mount_est_sample(mount_est_t *e, const imu_inc_t *inc, nav_real_t speed_mps, int speed_valid);

/* Solve the normal equations: e->res (valid 0 below MOUNT_EST_MIN_WINDOWS or when the up
 * axis is not determined). */
void mount_est_solve(mount_est_t *e);

#endif /* NAVECU_MOUNT_EST_H */
