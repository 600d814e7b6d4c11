/* can_frames.c - frames as the senders encode them; see can_frames.h. */
#include "can_frames.h"

#include <string.h>

#include "e2e.h"
#include "fake_hal.h"

hal_can_frame_t cf_frame(uint32_t id, const uint8_t d[8], uint64_t t_us)
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = 8u;
    memcpy(f.data, d, 8u);
    f.t_us = t_us;
    return f;
}

void cf_imu_pair(const int32_t w[3], const int32_t v[3], uint8_t counter, uint8_t fault,
                 uint64_t t_us, hal_can_frame_t *rate, hal_can_frame_t *accel)
{
    uint8_t dr[8], da[8];
    struct navecu_can_imu_rate_t r = {w[0], w[1], w[2], counter};
    navecu_can_imu_rate_pack(dr, &r, 8u);
    struct navecu_can_imu_accel_t a = {v[0], v[1], v[2], fault, counter, 0u};
    navecu_can_imu_accel_pack(da, &a, 8u);
    da[7] = e2e_pair_crc(NAVECU_CAN_IMU_ACCEL_FRAME_ID, dr, da);
    *rate = cf_frame(NAVECU_CAN_IMU_RATE_FRAME_ID, dr, t_us);
    *accel = cf_frame(NAVECU_CAN_IMU_ACCEL_FRAME_ID, da, t_us);
}

hal_can_frame_t cf_wheels(const int16_t raw[4], uint8_t counter, uint64_t t_us)
{
    uint8_t d[8];
    struct navecu_can_wheel_speeds_t w;
    memset(&w, 0, sizeof w);
    w.wheel_speed_fl = raw[0];
    w.wheel_speed_fr = raw[1];
    w.wheel_speed_rl = raw[2];
    w.wheel_speed_rr = raw[3];
    w.wheel_counter = counter;
    navecu_can_wheel_speeds_pack(d, &w, 8u);
    e2e_protect(NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID, d);
    return cf_frame(NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID, d, t_us);
}

hal_can_frame_t cf_gnss_position(int32_t lat_e7, int32_t lon_e7, uint64_t t_us)
{
    uint8_t d[8];
    struct navecu_can_gnss_position_t m = {lat_e7, lon_e7};
    navecu_can_gnss_position_pack(d, &m, 8u);
    return cf_frame(NAVECU_CAN_GNSS_POSITION_FRAME_ID, d, t_us);
}

hal_can_frame_t cf_gnss_velocity(const struct navecu_can_gnss_velocity_t *m, uint64_t t_us)
{
    uint8_t d[8];
    navecu_can_gnss_velocity_pack(d, m, 8u);
    e2e_protect(NAVECU_CAN_GNSS_VELOCITY_FRAME_ID, d);
    return cf_frame(NAVECU_CAN_GNSS_VELOCITY_FRAME_ID, d, t_us);
}

hal_can_frame_t cf_gnss_height(int32_t h_cm, uint8_t epoch, uint64_t t_us)
{
    uint8_t d[8];
    struct navecu_can_gnss_height_t m = {h_cm, epoch};
    navecu_can_gnss_height_pack(d, &m, 8u);
    return cf_frame(NAVECU_CAN_GNSS_HEIGHT_FRAME_ID, d, t_us);
}

hal_can_frame_t cf_gnss_status(const struct navecu_can_gnss_status_t *m, uint64_t t_us)
{
    uint8_t d[8];
    navecu_can_gnss_status_pack(d, m, 8u);
    return cf_frame(NAVECU_CAN_GNSS_STATUS_FRAME_ID, d, t_us);
}

hal_can_frame_t cf_known_position(int32_t lat_e7, int32_t lon_e7, uint64_t t_us)
{
    uint8_t d[8];
    struct navecu_can_cmd_known_position_t k = {lat_e7, lon_e7};
    navecu_can_cmd_known_position_pack(d, &k, 8u);
    return cf_frame(NAVECU_CAN_CMD_KNOWN_POSITION_FRAME_ID, d, t_us);
}

hal_can_frame_t cf_control(const struct navecu_can_cmd_control_t *m, uint64_t t_us)
{
    uint8_t d[8];
    navecu_can_cmd_control_pack(d, m, 8u);
    e2e_protect(NAVECU_CAN_CMD_CONTROL_FRAME_ID, d);
    return cf_frame(NAVECU_CAN_CMD_CONTROL_FRAME_ID, d, t_us);
}

hal_can_frame_t cf_initial_attitude(int32_t roll_raw, int32_t pitch_raw, uint8_t counter,
                                    uint64_t t_us)
{
    uint8_t d[8];
    struct navecu_can_cmd_initial_attitude_t m;
    memset(&m, 0, sizeof m);
    m.init_roll = roll_raw;
    m.init_pitch = pitch_raw;
    m.att_counter = counter;
    navecu_can_cmd_initial_attitude_pack(d, &m, 8u);
    e2e_protect(NAVECU_CAN_CMD_INITIAL_ATTITUDE_FRAME_ID, d);
    return cf_frame(NAVECU_CAN_CMD_INITIAL_ATTITUDE_FRAME_ID, d, t_us);
}

const hal_can_frame_t *cf_last_tx(const hal_t *hal, uint32_t id)
{
    for (uint32_t i = hal->tx_n; i > 0u; i--) {
        if (hal->tx[i - 1u].id == id) {
            return &hal->tx[i - 1u];
        }
    }
    return NULL;
}

uint32_t cf_tx_count(const hal_t *hal, uint32_t id)
{
    uint32_t n = 0u;
    for (uint32_t i = 0u; i < hal->tx_n; i++) {
        n += hal->tx[i].id == id;
    }
    return n;
}

struct navecu_can_nav_status_t cf_last_status_page0(const hal_t *hal)
{
    struct navecu_can_nav_status_t st;
    memset(&st, 0, sizeof st);
    for (uint32_t i = hal->tx_n; i > 0u; i--) {
        const hal_can_frame_t *fr = &hal->tx[i - 1u];
        if (fr->id == NAVECU_CAN_NAV_STATUS_FRAME_ID && (fr->data[0] & 0x0Fu) == 0u) {
            navecu_can_nav_status_unpack(&st, fr->data, 8u);
            break;
        }
    }
    return st;
}
