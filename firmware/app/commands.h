/*
 * commands.h - the operator's commands (docs/can.md): CMD_KnownPosition (where the car
 * is), CMD_Control (reset, set the initial position, store or erase the calibration, a
 * one-point calibration here or at the next GNSS fix) and CMD_InitialAttitude (roll and
 * pitch from another source: levelling ends at once). Their E2E checks and ranges are
 * app_rx's; here is what each means in the application's state, and when one is refused
 * (counted in cmd_rejected).
 */
#ifndef NAVECU_COMMANDS_H
#define NAVECU_COMMANDS_H

#include "app.h"

/* Why a command was refused (app_keep_t cmd_refusal, NAV_Status page 4 CmdRefusal,
 * docs/can.md). A commanded position is tied to the time it was given: it is never
 * applied to a car that has moved since (refused, not carried forward). */
typedef enum {
    CMD_REFUSAL_NONE = 0,
    CMD_REFUSAL_NO_KNOWN_POSITION = 1, /* no CMD_KnownPosition before it */
    CMD_REFUSAL_OUT_OF_RANGE = 2,      /* height or heading outside the signal's range */
    CMD_REFUSAL_MOVING = 3,            /* SetInitialPosition while the car moves */
    CMD_REFUSAL_STALE_POSITION = 4,    /* the car moved since CMD_KnownPosition, or before
                                          levelling ended: the commanded point dropped */
    CMD_REFUSAL_NOT_NOW = 5,           /* not in this state (InitialAttitude, calibrations) */
    CMD_REFUSAL_MOVED_TO_UDS = 6,      /* Store/EraseCalibration: UDS RoutineControl only */
    CMD_REFUSAL_UNDEFINED = 7          /* a command value the protocol does not define */
} cmd_refusal_t;

/* The car moves (CMD_MOVING_GNSS_MPS): the wheels turn (a valid odometer not at zero) or
 * the latest GNSS epoch, fresh, is faster than APP_CMD_MOVING_GNSS_MPS. */
int commands_car_moving(const app_t *a);

/* Motion seen (a wheel frame not at zero, or a GNSS epoch above APP_CMD_MOVING_GNSS_MPS):
 * a CMD_KnownPosition given before is stale; levelling from a commanded point stops, the
 * point dropped (refusal STALE_POSITION), and the start waits again: in motion, the
 * in-motion alignment (align.h). */
void commands_motion_seen(app_t *a);

/* One decoded command (kind RX_KNOWN_POSITION, RX_COMMAND or RX_INITIAL_ATTITUDE). */
void commands_handle(app_t *a, hal_t *hal, const rx_input_t *in);

/* A one-point calibration at the latitude and longitude of point with CalSource source
 * (CalibrateHere, or the fix CalibrateAtGnss marked). */
void commands_calibrate_at(app_t *a, hal_t *hal, const geo_pos_t *point, uint8_t source,
                           nav_real_t point_sigma_m);

/* Navigate from the initial state with this roll and pitch (rad): mode Navigating, or
 * Fault (counted in bad_value) if the core refuses the state. */
void commands_start_navigation(app_t *a, nav_real_t roll_rad, nav_real_t pitch_rad);

#endif /* NAVECU_COMMANDS_H */
