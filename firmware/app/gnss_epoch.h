/*
 * gnss_epoch.h - GNSS epoch assembly: GNSS_Position, GNSS_Velocity and GNSS_Height
 * collected until the GNSS_Status that closes the epoch (docs/can.md, GNSS epochs); the
 * frames belong to it when their epoch numbers match. A closed epoch is one gnss_fix_t:
 * position in the core's exact fixed point, velocity, speed and course, the receiver's
 * accuracies, and the time of validity as GPS time of week.
 */
#ifndef NAVECU_GNSS_EPOCH_H
#define NAVECU_GNSS_EPOCH_H

#include <stdint.h>

#include "app_rx.h"
#include "earth.h"

typedef struct {
    uint8_t pos_pending, vel_pending, h_pending, week_pending;
    uint8_t pos_refused;     /* this epoch's position was refused (counted once) */
    uint8_t vel_epoch, h_epoch, week_epoch;
    uint16_t gps_week;
    int32_t lat_e7, lon_e7;
    int32_t h_cm;            /* the latest height received (kept across epochs) */
    nav_real_t v_enu_mps[3];
    nav_real_t sacc_mps;
} gnss_asm_t;

typedef struct {
    uint8_t has_vel, has_h, has_week;
    uint16_t gps_week;       /* with has_week */
    geo_pos_t pos;           /* latitude, longitude; height from the latest GNSS_Height */
    int32_t h_cm;            /* that height, above the ellipsoid */
    nav_real_t v_enu_mps[3]; /* with has_vel */
    nav_real_t speed_mps;    /* horizontal; -1 without a velocity */
    nav_real_t course_rad;   /* clockwise from north, [0, 2 pi); 0 without a velocity */
    nav_real_t hacc_m, vacc_m, sacc_mps; /* the receiver's accuracies */
    uint32_t tow_ms;         /* time of validity, GPS time of week */
} gnss_fix_t;

/* What closing an epoch found (several may hold). */
typedef struct {
    uint8_t undefined;       /* bad_value: the status frame's epoch or fix type is undefined */
    uint8_t mismatch;        /* gnss_rejected: frames of another epoch were dropped */
    uint8_t repeat;          /* bad_counter: the previous fix's epoch again, all dropped */
    uint8_t no_fix;          /* the receiver has no usable fix: not an error */
    uint8_t no_position;     /* gnss_rejected: a fix reported without its position */
    uint8_t usable;          /* *fix holds a usable epoch */
    uint8_t has_course;      /* the epoch had a velocity: speed and course are valid */
} gnss_close_t;

void gnss_epoch_position(gnss_asm_t *g, int32_t lat_e7, int32_t lon_e7);
/* this epoch's position was refused as impossible */
void gnss_epoch_position_refused(gnss_asm_t *g);
/* 1 for a repeated frame (a velocity of this epoch number already in assembly: dropped,
 * the first one stays), else 0 */
int gnss_epoch_velocity(gnss_asm_t *g, uint8_t epoch, const nav_real_t v_enu_mps[3],
                        nav_real_t sacc_mps);
void gnss_epoch_height(gnss_asm_t *g, uint8_t epoch, int32_t h_cm);
void gnss_epoch_week(gnss_asm_t *g, uint8_t epoch, uint16_t gps_week);

/* Close the epoch with its GNSS_Status (decoded by app_rx). The frames in assembly are
 * consumed whatever the result; *fix is filled as far as the epoch allows (speed and
 * course with has_course, all of it with usable). */
gnss_close_t gnss_epoch_close(gnss_asm_t *g, const rx_input_t *status, gnss_fix_t *fix);

#endif /* NAVECU_GNSS_EPOCH_H */
