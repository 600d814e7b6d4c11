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

/* One decoded command (kind RX_KNOWN_POSITION, RX_COMMAND or RX_INITIAL_ATTITUDE). */
void commands_handle(app_t *a, hal_t *hal, const rx_input_t *in);

/* A one-point calibration at the latitude and longitude of point with CalSource source
 * (CalibrateHere, or the fix CalibrateAtGnss marked). */
void commands_calibrate_at(app_t *a, hal_t *hal, const geo_pos_t *point, uint8_t source);

/* Navigate from the initial state with this roll and pitch (rad): mode Navigating, or
 * Fault (counted in bad_value) if the core refuses the state. */
void commands_start_navigation(app_t *a, nav_real_t roll_rad, nav_real_t pitch_rad);

#endif /* NAVECU_COMMANDS_H */
