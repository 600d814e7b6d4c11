/*
 * vehicle.h - the car navecu is built for: its own bus messages that navecu reads (the
 * wheel speeds, and where the car has them the gear and the ESP yaw rate), the car's
 * geometry, and the CAN identifiers navecu's own messages take on that car's bus.
 *
 * Implemented by code generated at build time from a vehicle profile (vehicles/NAME.toml)
 * and the car's DBC: tools/vehicle.py writes build/vehicle/NAME/ with the car messages'
 * codec (cantools' C generator, no hand-written bit packing) and vehicle_profile.c, which
 * defines what is declared here. `make VEHICLE=NAME` selects the profile (default:
 * native, navecu's own WheelSpeeds message and the DBC's identifiers). docs/vehicles.md.
 */
#ifndef NAVECU_VEHICLE_H
#define NAVECU_VEHICLE_H

#include <stddef.h>
#include <stdint.h>

#include "hal.h"
#include "nav_types.h"
#include "navecu_protocol.h"

/* 1 where the build's profile may send its wheel speeds in two messages, one per axle
 * (vehicle_pair.h): the application then handles VEHICLE_WHEELS_HELD and calls
 * vehicle_reset. The ECU's images are compiled per profile, and the Makefile sets it to 0
 * for a profile whose wheel speeds come in one message, so that their images hold no code
 * for it (the generated layer of a split profile refuses to build with 0); the host's
 * libraries serve every profile and keep the default, 1. */
#ifndef VEHICLE_SPLIT_WHEELS
#define VEHICLE_SPLIT_WHEELS 1
#endif

/* where the direction of travel comes from */
typedef enum {
    VEHICLE_DIR_SIGNED = 0, /* the wheel speeds are signed (navecu's WheelSpeeds) */
    VEHICLE_DIR_GEAR = 1,   /* unsigned speeds; reverse when the gear says so */
    VEHICLE_DIR_NONE = 2,   /* unsigned speeds, always taken as forward */
} vehicle_direction_t;

typedef struct {
    const char *name;            /* the profile's name (vehicles/NAME.toml) */
    vehicle_direction_t direction;
    uint8_t native_wheels;       /* 1: the wheel speeds come in navecu's WheelSpeeds */
    nav_real_t track_m;          /* rear track: the turn's inner/outer wheel difference */
    nav_real_t wheelbase_m;      /* for the front axle's steering correction */
    nav_real_t wheel_step_mps;   /* the wheel speed signal's resolution, its DBC scale, m/s
                                    (the parameter odo_step_mps's default) */
    uint16_t can_ids[NAVECU_MSG_N]; /* navecu's identifiers on this car (navecu_msg_t): 11-bit
                                       (tools/vehicle.py checks it), 2 bytes each */
} vehicle_profile_t;

/* the build's profile (generated) */
extern const vehicle_profile_t vehicle_profile;

typedef enum {
    VEHICLE_MSG_NONE = 0,  /* not one of the car's messages navecu reads (or a gear frame of
                              a value the profile holds: passed over, the direction kept) */
    VEHICLE_MSG_WHEELS,    /* wheel_mps */
    VEHICLE_MSG_GEAR,      /* gear_direction */
    VEHICLE_MSG_YAW_RATE,  /* yaw_rate_rps */
    VEHICLE_MSG_N
} vehicle_kind_t;

typedef enum {
    VEHICLE_OK = 0,
    VEHICLE_BAD_DLC,       /* not the length the car's DBC gives the message */
    VEHICLE_BAD_CHECKSUM,  /* the car's own checksum (where the profile names one) */
    VEHICLE_BAD_COUNTER,   /* the car's rolling counter (where the profile names one):
                              repeated, or a value the sender does not count through */
    VEHICLE_BAD_VALUE,     /* outside the DBC's range, or a gear the profile does not know */
    VEHICLE_WHEELS_HELD,   /* passed: one axle's wheel speeds, of a car that sends the axles
                              in two messages, held until the other axle's (vehicle_pair.h);
                              nothing to act on yet (kind VEHICLE_MSG_WHEELS, no values) */
} vehicle_verdict_t;

/* The receive state of the car's rolling counters (vehicle_counter.h): kept by the caller
 * (rx_state_t, through a navigation reset like navecu's own E2E counters), updated by
 * vehicle_decode; all zero at init: no counter seen yet. 2 bytes a message kind, whatever
 * the profile. */
typedef struct {
    /* by vehicle_kind_t - 1: 0 none accepted yet, else the last counter accepted + 1 */
    uint16_t last[(unsigned)VEHICLE_MSG_N - 1u];
} vehicle_counters_t;

typedef struct {
    vehicle_kind_t kind;
    nav_real_t wheel_mps[4];   /* FL, FR, RL, RR, m/s: signed with VEHICLE_DIR_SIGNED */
    int8_t gear_direction;     /* +1 a forward gear, -1 reverse, 0 neither (park, neutral) */
    nav_real_t yaw_rate_rps;   /* about the car's up axis, left positive */
} vehicle_msg_t;

/* Decode f if it is one of the car's messages the profile names (its kind is then not
 * VEHICLE_MSG_NONE); the verdict says whether it passed the car's checks, in this order:
 * the DLC, the car's checksum, the rolling counter (against c, which a counter that passes
 * updates: a frame refused afterwards for its values has still counted), the ranges.
 * Generated; c is untouched by a profile that names no counter. Where the profile's wheel
 * speeds come in two messages (front and rear axle), a half that passes is held and gives
 * VEHICLE_WHEELS_HELD, and the half that completes the pair gives VEHICLE_OK with the four
 * wheels (vehicle_pair.h). */
vehicle_verdict_t vehicle_decode(const hal_can_frame_t *f, vehicle_counters_t *c,
                                 vehicle_msg_t *m);

/* Forget what vehicle_decode holds of its own: the held half of split wheel speeds and the
 * rolling counters the caller's vehicle_counters_t has no room for (the rear axle's).
 * Called where the caller clears the state it keeps (app_init: power-on, ECUReset), and when
 * the wheel speeds time out while navigating (the odometer's timeout, app.c). Generated
 * for profiles with split wheel speeds only; every other profile's vehicle layer holds
 * nothing, and app.c's default (weak, empty) is taken. */
void vehicle_reset(void);

/* The car's identifiers navecu receives: writes up to max to ids, returns how many there
 * are. Generated. */
size_t vehicle_rx_ids(uint32_t *ids, size_t max);

#endif /* NAVECU_VEHICLE_H */
