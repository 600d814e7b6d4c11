/*
 * align.h - initialisation and alignment: the initial position and heading (commanded,
 * or from GNSS alone), levelling at rest, the start of navigation, and re-acquisition
 * from GNSS after an IMU gap too long to bridge or a filter reset.
 *
 * Levelling: the mean specific force of a vehicle at rest is C_nb (0, 0, g), whose body
 * components are g (-cos(p) sin(r), sin(p), cos(p) cos(r)) (docs/frames.md); it is the
 * least-squares slope of the summed velocity increments over the window, a mean with
 * parabolic weights w_k = k (N - k): a plain mean is off by up to one LSB / window length,
 * because the sender's quantisation carry is unknown at both ends of the window; the
 * parabolic weights give the ends almost no weight, which cuts that error by about
 * sqrt(N) (docs/can.md, IMU).
 */
#ifndef NAVECU_ALIGN_H
#define NAVECU_ALIGN_H

#include <stdint.h>

#include "calib.h"
#include "dr.h"
#include "gnss_epoch.h"
#include "mounting.h"
#include "sins.h"

typedef struct {
    /* CMD_KnownPosition: where the car is (SetInitialPosition, CalibrateHere) */
    uint8_t known_valid;
    uint8_t known_moved; /* the car moved since it was given (commands.h) */
    int32_t known_lat_e7, known_lon_e7;
    /* the initial state navigation starts from */
    uint8_t pos_valid, heading_valid;
    uint8_t commanded;      /* set by SetInitialPosition (not by the GNSS-only start) */
    geo_pos_t pos;          /* position, height from h_cm */
    int32_t h_cm;           /* height above the ellipsoid */
    nav_real_t heading_rad;
    /* levelling */
    nav_real_t level_wsum[3], level_wsum_lo[3]; /* weighted velocity increments, raw LSB */
    uint32_t level_n;                           /* samples levelled so far */
    /* GNSS-only initialisation: a course seen while moving */
    uint8_t course_valid;
    nav_real_t course_rad;
    nav_real_t course_dyaw_rad; /* the z gyro's turn since it */
    /* re-acquisition: the attitude before the gap, the mounting yaw in use */
    uint8_t reacquire;
    uint8_t reacq_moved; /* the car moved since: the heading before is no longer known */
    nav_real_t reacq_roll_rad, reacq_pitch_rad, reacq_heading_rad, reacq_mount_rad;
    /* in-motion alignment: the window since a GNSS epoch (align_motion_*) */
    uint8_t mot_open;                 /* a window runs */
    uint8_t mot_odo_valid;            /* the odometer was valid at the window's start */
    nav_real_t mot_dv_mps[3];         /* sum of the velocity increments, vehicle axes */
    nav_real_t mot_dv_lo_mps[3];
    nav_real_t mot_dyaw_rad;          /* sum of the yaw increments (vehicle up axis) */
    nav_real_t mot_t_s;               /* the window's length */
    nav_real_t mot_v0_gnss_mps;       /* signed forward GNSS speed at the window's start */
    nav_real_t mot_v0_odo_mps;        /* the odometer's speed at the window's start */
    /* what the in-motion start found, for the filter's initial sigmas */
    nav_real_t mot_heading_sigma_rad, mot_tilt_sigma_rad;
} align_t;

/* The odometer as the in-motion alignment sees it: forward speed (reverse negative). */
typedef struct {
    uint8_t valid;
    nav_real_t speed_mps;
} align_odo_t;

/* The initial state (SetInitialPosition, or the GNSS-only start). */
void align_set_initial(align_t *al, const geo_pos_t *pos, int32_t h_cm, int heading_valid,
                       nav_real_t heading_rad);

/* A position of the protocol's units: latitude and longitude in 1e-7 deg, height in cm. */
geo_pos_t align_pos_of(int32_t lat_e7, int32_t lon_e7, int32_t h_cm);

/* 1 when position and heading are known: levelling may start. */
int align_ready(const align_t *al);

/* (Re)start levelling. */
void align_level_restart(align_t *al);

/* One sample's velocity increments (raw LSB) of an n_total-sample window. Returns 1 when
 * the window is complete. */
int align_level_sample(align_t *al, const int32_t v_raw[3], uint32_t n_total);

/* Roll and pitch (rad) of the vehicle from the levelled specific force (IMU axes), turned
 * into the vehicle's axes by the configured mounting. */
void align_level_attitude(const align_t *al, const mounting_t *mount, nav_real_t *roll_rad,
                          nav_real_t *pitch_rad);

/* Navigate from the initial position and heading with roll and pitch (rad), at rest: the
 * navigator, its height reference (held at the initial height until GNSS heights
 * arrive), the dead reckoning with the calibration in use. NAV_OK or the core's error. */
int align_start(const align_t *al, nav_real_t roll_rad, nav_real_t pitch_rad, sins_t *nav,
                dr_t *dr, const calib_t *cal);

/* GNSS-only initialisation, while waiting for an initial state without one: the heading
 * is the GNSS course while driving (5 m/s or more), while the z gyro says the car has not
 * turned since by more than APP_GNSS_COURSE_TURN_RAD (align_motion_sample: a car that
 * turns below 5 m/s before it stops; a review found it started 90 deg off); the position,
 * height and levelling come at the next stop, once the wheels stand too (wheels_turn 0: the receiver's speed falls below a
 * standstill's while a braking car still rolls, and the wheels would stop the levelling,
 * the course forgotten). Returns 1 when the epoch set the initial state. */
int align_gnss(align_t *al, const gnss_fix_t *fix, int wheels_turn);

/* An IMU gap too long to bridge or a filter reset: keep roll, pitch and heading and the
 * mounting yaw (rad) in use; position, velocity and heading come from GNSS. moving: the
 * car was moving then (the heading kept is then not the one after the gap). */
void align_reacquire_begin(align_t *al, const sins_t *nav, nav_real_t mount_yaw_rad,
                           int moving);

/* 1 if the epoch can re-acquire: velocity and height, and either driving (the course is a
 * heading) or standing still since the re-acquisition began (the heading before is kept;
 * a car that moved meanwhile, in the gap or waiting, may have turned: it waits for the
 * course). */
int align_reacquire_ready(const align_t *al, const gnss_fix_t *fix);

/* Resume at this epoch, reversing (the wheels say so): the heading is the course's
 * opposite. NAV_OK, or the core's error (the epoch is refused). */
int align_reacquire(align_t *al, const gnss_fix_t *fix, sins_t *nav, dr_t *dr,
                    const calib_t *cal, int reversing);

/* In-motion alignment (docs/kalman.md, Initialisation), while waiting for an initial
 * state with no heading: a car that powers on or is reset while driving. Between two GNSS
 * epochs at least APP_INMOTION_WINDOW_S apart, both driving (speed at least
 * APP_GNSS_COURSE_MIN_MPS and APP_INMOTION_SPEED_SIGMAS x its sigma), the specific force
 * f_b (vehicle axes) summed over the window less the vehicle's own acceleration: along
 * track (y) the change of speed (the odometer's, else GNSS's), across (x) the centripetal
 * -v w_z (v the window's mean speed, w_z the yaw increments' sum); what is left is gravity,
 * whose direction is roll and pitch (as levelling). The heading is the GNSS course (plus
 * pi when the wheels say reversing), position, height and velocity are the fix's. */

/* One sample (vehicle axes, after the mounting) into the window, if one runs. */
void align_motion_sample(align_t *al, const imu_inc_t *inc);

/* A GNSS epoch: 1 when the window it closes gives an in-motion start (then roll, pitch
 * and heading (rad) are set, and mot_heading_sigma_rad / mot_tilt_sigma_rad); otherwise a
 * new window starts at this epoch when it is a driving one, and 0. */
int align_motion_epoch(align_t *al, const gnss_fix_t *fix, const align_odo_t *odo,
                       nav_real_t *roll_rad, nav_real_t *pitch_rad, nav_real_t *heading_rad);

/* Navigate from the fix with that attitude (as align_reacquire). NAV_OK or the core's
 * error. */
int align_motion_start(const gnss_fix_t *fix, nav_real_t roll_rad, nav_real_t pitch_rad,
                       nav_real_t heading_rad, sins_t *nav, dr_t *dr, const calib_t *cal);

#endif /* NAVECU_ALIGN_H */
