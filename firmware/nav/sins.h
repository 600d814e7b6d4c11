/*
 * sins.h - strapdown inertial navigation in the local-level ENU frame on WGS-84.
 *
 * The mechanization of seed 001 (eqs. 2-7): attitude from the Poisson equation
 * dC_bn/dt = C_bn [w_nb_b x], velocity from dv_n/dt = C_bn f_b - (2 w_ie_n + w_en_n) x v_n
 * + g_n, position from dlat/dt = v_N/(R_M+h), dlon/dt = v_E/((R_N+h) cos lat), dh/dt = v_U.
 * It is integrated in the increment form of Savage ("Strapdown Inertial Navigation
 * Integration Algorithm Design", JGCD 21(1-2), 1998): the IMU delivers angle and velocity
 * increments over each sample interval; two-sample coning and sculling corrections use the
 * previous sample; the navigation frame's own rotation over the interval is applied to
 * attitude and velocity; Coriolis, transport and gravity terms are taken at mid-interval.
 *
 * The core knows nothing of where increments come from (CAN, a file, a test): a caller
 * owns one sins_t per navigator and feeds sins_step() in time order.
 */
#ifndef NAVECU_SINS_H
#define NAVECU_SINS_H

#include "earth.h"
#include "nav_math.h"

/* One IMU sample: integrals over the sample interval, body frame (x right, y fwd, z up). */
typedef struct {
    nav_real_t dtheta_b_rad[3]; /* integral of the angular rate w_ib_b */
    nav_real_t dv_b_mps[3];     /* integral of the specific force f_b */
    nav_real_t dt_s;            /* length of the interval */
} imu_inc_t;

typedef struct {
    uint8_t coning_sculling; /* 1: apply the two-sample coning and sculling terms */
    nav_real_t max_dt_s;     /* sins_step rejects intervals longer than this */
    nav_real_t vdamp_tau_s;  /* vertical damping time constant when a height reference
                                is set (sins_set_height_ref); 0: always undamped; else at
                                least 10 max_dt_s, or the discrete loop goes unstable */
} sins_config_t;

typedef struct {
    sins_config_t cfg;
    geo_pos_t pos;              /* position, 64-bit fixed point */
    nav_real_t q_bn[4];         /* attitude, body to ENU; unit norm to rounding */
    nav_real_t q_bn_lo[4];      /* rounding carried by compensated accumulation */
    nav_real_t v_n_mps[3];      /* velocity relative to the Earth, ENU */
    nav_real_t v_n_lo_mps[3];   /* rounding carried by compensated accumulation */
    nav_real_t v_n_prev_mps[3]; /* velocity one step earlier (mid-interval extrapolation) */
    nav_real_t dtheta_prev_b_rad[3]; /* previous increments for coning and sculling */
    nav_real_t dv_prev_b_mps[3];
    nav_real_t dt_prev_s;       /* interval of the previous accepted step */
    nav_real_t h_ref_m;         /* height reference for vertical damping */
    uint8_t have_prev;          /* previous increments are valid */
    uint8_t h_ref_valid;
    uint32_t n_steps;           /* accepted sins_step calls */
} sins_t;

#define sins_default_config NAV_SYM(sins_default_config)
#define sins_init NAV_SYM(sins_init)
#define sins_step NAV_SYM(sins_step)
#define sins_set_height_ref NAV_SYM(sins_set_height_ref)
#define sins_euler NAV_SYM(sins_euler)
#define sins_set_velocity NAV_SYM(sins_set_velocity)
#define sins_turn_heading NAV_SYM(sins_turn_heading)
#define sins_clear_height_ref NAV_SYM(sins_clear_height_ref)
#define sins_set_position NAV_SYM(sins_set_position)
#define sins_earth_rate_b NAV_SYM(sins_earth_rate_b)
#define sins_finite NAV_SYM(sins_finite)

/* coning/sculling on, max_dt 0.2 s (IMUs of 10-400 Hz with a dropped sample or two),
 * vertical damping time constant 100 s. */
sins_config_t sins_default_config(void);

/*
 * Start navigating from a known state: position pos, Earth-relative velocity v_n_mps
 * (ENU, m/s), attitude q_bn (normalized here). Returns NAV_OK, or NAV_EINVAL (s untouched)
 * if a value is not finite, |lat| > 89 deg, the height is outside [-1, 20] km, |v| > 1000
 * m/s, |q| is far from 1, or the config is out of range (max_dt_s in (0, 1], vdamp_tau_s
 * 0 or >= 10 max_dt_s).
 */
int sins_init(sins_t *s, const sins_config_t *cfg, const geo_pos_t *pos,
              const nav_real_t v_n_mps[3], const nav_real_t q_bn[4]);

/*
 * Advance the state by one IMU interval. Returns NAV_OK; NAV_EINVAL if the increment is
 * not finite, dt_s is outside (0, max_dt_s], or the rotation exceeds pi in one interval;
 * NAV_ERANGE if the result would leave the valid region (|lat| > 89 deg, height outside
 * [-1, 20] km, |v| > 1000 m/s). On an error the state is unchanged, and the next accepted
 * step has no coning/sculling history (it cannot be trusted across a rejected sample).
 * Intervals may vary; the two-sample corrections are used only between equal intervals
 * (within 1 %), and the mid-interval velocity extrapolation scales with dt/dt_prev.
 */
int sins_step(sins_t *s, const imu_inc_t *inc);

/*
 * Damp the vertical channel toward h_ref_m (m above the ellipsoid), from a barometer,
 * GNSS, or a held value. Free-inertial height diverges with time constant sqrt(R/2g)
 * (about 570 s); a second-order loop with both poles at -1/vdamp_tau_s replaces that.
 * A non-finite h_ref_m, or vdamp_tau_s = 0, turns damping off.
 */
void sins_set_height_ref(sins_t *s, nav_real_t h_ref_m);

/* Stop damping the vertical channel (another source, e.g. the Kalman filter, owns the
 * height now). */
void sins_clear_height_ref(sins_t *s);

/* Replace the position by one from another source (dead reckoning, a GNSS fix, a known
 * point). NAV_OK, or NAV_EINVAL (s unchanged) outside sins_init's region. */
int sins_set_position(sins_t *s, const geo_pos_t *pos);

/* The Earth's rotation rate seen by the body axes now: w_ie_b = C_bn^T w_ie_n (rad/s),
 * what a perfect gyro reads at rest. */
void sins_earth_rate_b(const sins_t *s, nav_real_t w_ie_b_rps[3]);

/* 1 if the attitude and the velocity are finite (a navigator that can still be output and
 * corrected), else 0. */
int sins_finite(const sins_t *s);

/* roll, pitch, heading (rad) of the current attitude, conventions of nav_math.h */
void sins_euler(const sins_t *s, nav_real_t *roll_rad, nav_real_t *pitch_rad,
                nav_real_t *heading_rad);

/*
 * Replace the Earth-relative velocity (ENU, m/s) by one from another source: the odometer
 * while driving, zero at a standstill (seed 000: "odometer velocity, used to damp the
 * oscillating SINS velocity errors"). Returns NAV_OK, or NAV_EINVAL (s unchanged) for a
 * non-finite value or |v| > 1000 m/s.
 */
int sins_set_velocity(sins_t *s, const nav_real_t v_n_mps[3]);

/*
 * Turn the attitude about the local vertical so that the heading changes by dheading_rad
 * (clockwise from north positive); roll and pitch are kept. Used to hold the heading while
 * the wheels say the car stands. Returns NAV_OK, or NAV_EINVAL for |dheading| > pi or a
 * non-finite value.
 */
int sins_turn_heading(sins_t *s, nav_real_t dheading_rad);

#endif /* NAVECU_SINS_H */
