/*
 * vehicle_counter.h - a car message's rolling (alive) counter, where a vehicle profile names
 * one ("counter" in a vehicles/ profile, docs/vehicles.md); called by the generated
 * vehicle_profile.c, linked only into the images of profiles that name a counter.
 *
 * The counter is the DBC signal's raw value, decoded by the generated codec; it runs 0, 1,
 * ..., modulus - 1, 0, ... (modulus 2^length of the signal unless the profile says
 * otherwise, e.g. 15 for a 4-bit counter that never sends 15). The same rule as navecu's
 * own E2E counters (e2e_counter_step, docs/can.md), with the car's modulus.
 */
#ifndef NAVECU_VEHICLE_COUNTER_H
#define NAVECU_VEHICLE_COUNTER_H

#include <stdint.h>

#include "vehicle.h"

/*
 * Check the counter of a frame of kind against the last one accepted for that kind (c,
 * the caller's receive state). Returns the step, (counter - last) mod modulus: 1 = the
 * next frame, 2..modulus - 1 = step - 1 frames were lost; 0 for a repeated counter (the
 * frame is a repeat and must be dropped); -1 for a counter of modulus or more (not a value
 * the sender counts through), or a kind or modulus out of range (modulus 2..256). The
 * first counter of a kind after init is accepted with step 1. A step of 1 or more updates
 * the state; 0 and -1 do not.
 */
int vehicle_counter_step(vehicle_counters_t *c, vehicle_kind_t kind, uint8_t counter,
                         uint16_t modulus);

#endif /* NAVECU_VEHICLE_COUNTER_H */
