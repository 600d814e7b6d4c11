/*
 * vehicle_pair.h - the four wheel speeds of a car that sends them in two messages, one per
 * axle ([wheels] messages = {front, rear} in a vehicle profile, docs/vehicles.md: Nissan's
 * WHEEL_SPEEDS_FRONT/REAR, GM's EBCMWheelSpdFront/Rear); called by the generated
 * vehicle_profile.c, linked only into the images of such profiles.
 *
 * The pairing rule, decided from the frames alone (never from their arrival times): each
 * axle's half that passed the car's checks is held; when the other axle's half has arrived
 * since the last sample, the two make one sample of the four wheels (on the second of the
 * two to arrive) and nothing stays held. A half that arrives again before the other axle's
 * replaces the held one (the newer speeds; the older half is dropped: it was counted as a
 * frame read, rx_state_t.car_read, and no sample counts it). A refused half (DLC, checksum, counter, range) is
 * never given to it. If one axle's message stops, no sample is made: the odometer's timeout
 * says so, and the application then forgets the held half (vehicle_reset, app.c), so a half
 * from before a silence of both axles never pairs with one after it (docs/vehicles.md).
 */
#ifndef NAVECU_VEHICLE_PAIR_H
#define NAVECU_VEHICLE_PAIR_H

#include <stdint.h>

#include "nav_types.h"

typedef enum {
    VEHICLE_AXLE_FRONT = 0,
    VEHICLE_AXLE_REAR = 1,
} vehicle_axle_t;

/* The half held: all zero at init (none). Kept by the generated vehicle_profile.c and
 * cleared by its vehicle_reset (vehicle.h). */
typedef struct {
    nav_real_t left_mps, right_mps; /* the held axle's speeds */
    uint8_t held;                   /* 0 none, 1 + vehicle_axle_t of the half held */
} vehicle_pair_t;

/*
 * One axle's half (left, right: m/s, as decoded) that passed the car's checks. Returns 1
 * when it completes a sample: wheel_mps is then FL, FR, RL, RR and nothing stays held;
 * 0 when it is held (wheel_mps untouched).
 */
int vehicle_pair_half(vehicle_pair_t *p, vehicle_axle_t axle, nav_real_t left_mps,
                      nav_real_t right_mps, nav_real_t wheel_mps[4]);

#endif /* NAVECU_VEHICLE_PAIR_H */
