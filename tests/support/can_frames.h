/*
 * can_frames.h - CAN frames as navecu's senders put them on the bus (the generated codec
 * and the E2E protection of docs/can.md), for tests of the application and its modules,
 * and readers of the frames the application sent (captured by fake_hal.h).
 */
#ifndef NAVECU_TEST_CAN_FRAMES_H
#define NAVECU_TEST_CAN_FRAMES_H

#include <stdint.h>

#include "hal.h"
#include "navecu_can.h"

/* A standard 8-byte frame with identifier id, payload d, received at t_us. */
hal_can_frame_t cf_frame(uint32_t id, const uint8_t d[8], uint64_t t_us);

/* The two frames of one IMU sample (angle increments w, velocity increments v in the
 * signals' LSB) with the pair CRC in IMU_Accel. */
void cf_imu_pair(const int32_t w[3], const int32_t v[3], uint8_t counter, uint8_t fault,
                 uint64_t t_us, hal_can_frame_t *rate, hal_can_frame_t *accel);

/* WheelSpeeds FL, FR, RL, RR in 0.02 m/s steps, E2E-protected. */
hal_can_frame_t cf_wheels(const int16_t raw[4], uint8_t counter, uint64_t t_us);

/* The frames of a GNSS epoch. Velocity is E2E-protected (its CRC field is overwritten). */
hal_can_frame_t cf_gnss_position(int32_t lat_e7, int32_t lon_e7, uint64_t t_us);
hal_can_frame_t cf_gnss_velocity(const struct navecu_can_gnss_velocity_t *m, uint64_t t_us);
hal_can_frame_t cf_gnss_height(int32_t h_cm, uint8_t epoch, uint64_t t_us);
hal_can_frame_t cf_gnss_status(const struct navecu_can_gnss_status_t *m, uint64_t t_us);

/* The commands; CMD_Control and CMD_InitialAttitude E2E-protected. */
hal_can_frame_t cf_known_position(int32_t lat_e7, int32_t lon_e7, uint64_t t_us);
hal_can_frame_t cf_control(const struct navecu_can_cmd_control_t *m, uint64_t t_us);
hal_can_frame_t cf_initial_attitude(int32_t roll_raw, int32_t pitch_raw, uint8_t counter,
                                    uint64_t t_us);

/* The last captured frame with identifier id, or NULL. */
const hal_can_frame_t *cf_last_tx(const hal_t *hal, uint32_t id);

/* Captured frames with identifier id. */
uint32_t cf_tx_count(const hal_t *hal, uint32_t id);

/* The latest NAV_Status page 0 (mode, HealthFlags, accuracy); all zero if none was sent. */
struct navecu_can_nav_status_t cf_last_status_page0(const hal_t *hal);

#endif
