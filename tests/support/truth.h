/*
 * truth.h - exact IMU increments for an analytically described motion (test support).
 *
 * A motion is given as functions of time: Earth-relative velocity and its derivative in
 * ENU, attitude q_bn and the body rate relative to ENU. From them the generator forms the
 * specific force and inertial angular rate in the body frame (seed 001 eq. 4 solved for
 * f_b; w_ib_b = C_nb (w_ie_n + w_en_n) + w_nb_b) and integrates them over each sample
 * interval with 5-point Gauss-Legendre quadrature, the truth position with RK4. Earth model:
 * the double variant of firmware/nav/earth.c, itself tested against WGS-84 published values.
 * Plain double API; no firmware types leak out.
 */
#ifndef NAVECU_TEST_TRUTH_H
#define NAVECU_TEST_TRUTH_H

typedef struct {
    double v_n_mps[3];    /* Earth-relative velocity, ENU */
    double a_n_mps2[3];   /* time derivative of the ENU components of v_n */
    double q_bn[4];       /* attitude, body to ENU, unit */
    double w_nb_b_rps[3]; /* body rate relative to ENU, body axes */
} kin_t;

typedef void (*kin_fn)(const void *ctx, double t_s, kin_t *out);

typedef struct {
    kin_fn kin;
    const void *ctx;
    double t_s;                  /* time of the current truth state */
    double lat_rad, lon_rad, h_m; /* truth position at t_s */
} truth_gen_t;

void truth_init(truth_gen_t *g, kin_fn kin, const void *ctx, double lat_rad, double lon_rad,
                double h_m);

/* Advance the truth by dt_s; write the exact gyro and accelerometer increments of the
 * interval (body frame, rad and m/s). */
void truth_step(truth_gen_t *g, double dt_s, double dtheta_b_rad[3], double dv_b_mps[3]);

/* Helpers for motions described by Euler angles (3-1-2, conventions of nav_math.h). */
void truth_q_from_euler(double roll, double pitch, double heading, double q_bn[4]);
void truth_w_nb_from_euler_rates(double roll, double pitch, double roll_rate,
                                 double pitch_rate, double heading_rate, double w_nb_b[3]);

/* WGS-84 radii of curvature (m) and normal gravity (m/s^2), double variant of earth.c */
void truth_radii(double lat_rad, double *R_M_m, double *R_N_m);
double truth_gravity(double lat_rad, double h_m);

/* Rotation angle (rad) between two attitudes. */
double truth_att_err_rad(const double q_true[4], const double q_est[4]);

/* Horizontal distance (m) between two nearby positions at latitude lat, height h. */
double truth_horiz_dist_m(double lat1, double lon1, double lat2, double lon2, double h_m);

#endif
