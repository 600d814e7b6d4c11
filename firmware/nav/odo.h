/*
 * odo.h - the car's odometer from its four wheel speeds: the forward speed of the
 * vehicle's reference point, reverse motion, and standstill.
 *
 * Reference point: the middle of the rear axle by default. There the velocity is along
 * the car's longitudinal axis (no side slip of a non-steered axle: the non-holonomic
 * constraint holds exactly), and the mean of the two rear wheel speeds is its speed in
 * any turn (the inner and outer wheels differ by +-yaw rate x half track). On a
 * front-wheel-drive car the rear axle is also the non-driven one, so wheel spin under
 * traction does not enter. A rear-driven car may select the front axle: the front wheels
 * steer, so each front wheel's speed is sqrt(v_lon^2 + (r L)^2) for the rear-axle speed
 * v_lon, yaw rate r and wheelbase L; the mean of the front speeds is corrected by that.
 *
 * Quantisation: the DBC's 0.02 m/s steps are rounded by the sender (docs/can.md), an
 * unbiased error of at most 0.01 m/s per wheel that averages out in the distance; nothing
 * here truncates. Standstill: every wheel below half a step (it reads exactly zero) for
 * still_time_s, with the IMU quiet (|yaw rate| below still_rate_rps).
 */
#ifndef NAVECU_ODO_H
#define NAVECU_ODO_H

#include "nav_types.h"

typedef enum {
    ODO_AXLE_REAR = 0,  /* mean of the rear wheels (reference point: rear axle centre) */
    ODO_AXLE_FRONT = 1, /* mean of the front wheels, steering-corrected to the rear axle */
} odo_axle_t;

typedef struct {
    odo_axle_t axle;
    nav_real_t wheelbase_m;     /* for ODO_AXLE_FRONT */
    nav_real_t still_speed_mps; /* a wheel below this reads zero (half the signal's step) */
    nav_real_t still_time_s;    /* zero speeds this long before standstill is declared */
    nav_real_t still_rate_rps;  /* and the body turning slower than this */
    nav_real_t timeout_s;       /* a speed older than this is not used (stale odometer) */
    nav_real_t max_speed_mps;   /* implausible beyond this: the frame is refused */
    nav_real_t max_wheel_spread;/* refused if the axle's wheels differ by more than this
                                   fraction of their mean plus the turn's own difference
                                   (a locked or spinning wheel) */
    nav_real_t track_m;         /* for the turn's inner/outer wheel difference */
} odo_config_t;

/* zero_for_s stops growing here (an hour: float32 steps of a 100 Hz sample stay exact) */
#define ODO_ZERO_FOR_MAX_S NAV_C(3600.0)

typedef struct {
    odo_config_t cfg;
    nav_real_t speed_mps;      /* forward speed of the reference point, reverse negative */
    nav_real_t age_s;          /* time since the last accepted wheel frame */
    nav_real_t period_s;       /* mean interval between accepted frames (slow average) */
    nav_real_t still_for_s;    /* time all wheels have read zero */
    nav_real_t zero_for_s;     /* the same, whatever the yaw rate (ODO_ZERO_FOR_MAX_S at most) */
    uint8_t valid;             /* a speed was accepted and is younger than timeout_s */
    uint8_t standing;          /* standstill */
    uint8_t zero;              /* the last accepted frame had every wheel at zero */
    uint32_t n_frames;         /* accepted frames */
} odo_t;

#define odo_default_config NAV_SYM(odo_default_config)
#define odo_init NAV_SYM(odo_init)
#define odo_wheels NAV_SYM(odo_wheels)
#define odo_tick NAV_SYM(odo_tick)
#define odo_age NAV_SYM(odo_age)

/* Rear axle, wheelbase 2.7 m, track 1.6 m, zero below 0.01 m/s, standstill after 0.5 s
 * below 0.5 deg/s, timeout 1.5 s (covers 1 Hz OBD-II speed sources), 90 m/s maximum,
 * 30 % wheel spread. */
odo_config_t odo_default_config(void);

/* Start with no speed. Returns NAV_OK or NAV_EINVAL for a config out of range. */
int odo_init(odo_t *o, const odo_config_t *cfg);

/*
 * One WheelSpeeds frame: front-left, front-right, rear-left, rear-right (m/s, signed,
 * reverse negative), and the body yaw rate (rad/s, about the car's up axis) at that time.
 * Returns NAV_OK; NAV_EINVAL for a non-finite or implausible value (the frame is refused,
 * which the caller counts (the application: CntBadValue), and the previous speed ages on).
 */
int odo_wheels(odo_t *o, const nav_real_t wheel_mps[4], nav_real_t yaw_rate_rps);

/* Advance time by dt_s (one IMU interval) with the body's yaw rate (rad/s): ages the
 * speed (odo_age) and updates standstill. */
void odo_tick(odo_t *o, nav_real_t dt_s, nav_real_t yaw_rate_rps);

/* Age the speed by dt_s (one IMU interval) without the standstill's update: valid ends
 * timeout_s after the last accepted frame, and with it the standstill (the caller's
 * odometer outside navigation, before it and while it re-acquires, when nothing calls
 * odo_tick; and navigating, for a sample the strapdown core refused, whose rates are no
 * evidence of standing still). */
void odo_age(odo_t *o, nav_real_t dt_s);

#endif /* NAVECU_ODO_H */
