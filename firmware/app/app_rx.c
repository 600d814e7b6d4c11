/* app_rx.c - receive and validate one frame; see app_rx.h. */
#include "app_rx.h"

#include <string.h>

#include "app_tuning.h"
#include "navecu_can.h"
#include "vehicle.h"

static const uint8_t IS_INPUT[NAVECU_MSG_N] = NAVECU_MSG_IS_INPUT;

size_t app_rx_ids(const uint32_t can_ids[NAVECU_MSG_N], uint32_t *ids, size_t max)
{
    size_t n = 0u;
    for (int m = 0; m < (int)NAVECU_MSG_N; m++) {
        if (IS_INPUT[m]) {
            if (n < max) {
                ids[n] = can_ids[m];
            }
            n++;
        }
    }
    /* and the car's messages that the vehicle profile reads */
    return n + vehicle_rx_ids(n < max ? ids + n : ids, n < max ? max - n : 0u);
}

/* the message of navecu's protocol on this identifier, or NAVECU_MSG_N for none */
static int msg_of(const uint32_t can_ids[NAVECU_MSG_N], uint32_t id)
{
    for (int m = 0; m < (int)NAVECU_MSG_N; m++) {
        if (can_ids[m] == id) {
            return m;
        }
    }
    return (int)NAVECU_MSG_N;
}

/* 1 if the message carries its own E2E CRC in byte 7 (the IMU pair is checked as a whole
 * when IMU_Accel arrives, imu_stream.h) */
static int is_e2e(int msg)
{
    return msg == NAVECU_MSG_WHEEL_SPEEDS || msg == NAVECU_MSG_GNSS_VELOCITY ||
           msg == NAVECU_MSG_GNSS_TIME || msg == NAVECU_MSG_IMU_TIME ||
           msg == NAVECU_MSG_CMD_CONTROL || msg == NAVECU_MSG_CMD_INITIAL_ATTITUDE ||
           msg == NAVECU_MSG_GNSS_RAW_SAT_X || msg == NAVECU_MSG_GNSS_RAW_SAT_Y ||
           msg == NAVECU_MSG_GNSS_RAW_SAT_Z || msg == NAVECU_MSG_GNSS_RAW_RANGE ||
           msg == NAVECU_MSG_GNSS_RAW_RATE || msg == NAVECU_MSG_GNSS_RAW_EPOCH;
}

/* GNSS and known positions: the DBC's ranges, -180 deg included */
static int lat_lon_ok(int32_t lat_e7, int32_t lon_e7)
{
    return navecu_can_gnss_position_latitude_is_in_range(lat_e7) &&
           navecu_can_gnss_position_longitude_is_in_range(lon_e7);
}

/* longitude -180 deg is the meridian of +180 deg: handed on as +180, the core's
 * longitudes being (-180, 180] (earth.h) */
static int32_t lon_wrapped_e7(int32_t lon_e7)
{
    return lon_e7 == -1800000000 ? 1800000000 : lon_e7;
}

/* A command's alive counter: APP_CMD_MAX_DELTA - 1 lost frames are tolerated; a larger
 * step is an old or foreign frame (E2E "wrong sequence"): dropped, and the counter
 * resynchronizes on it. */
static int command_counter_ok(e2e_counter_t *c, uint8_t counter)
{
    const int step = e2e_counter_step(c, counter);
    return step > 0 && step <= APP_CMD_MAX_DELTA;
}

static rx_command_t command_of(uint8_t raw)
{
    return raw < (uint8_t)RX_CMD_UNKNOWN ? (rx_command_t)raw : RX_CMD_UNKNOWN;
}

static rx_verdict_t decode_imu(int msg, const uint8_t d[8], rx_input_t *in)
{
    if (msg == NAVECU_MSG_IMU_TIME) {
        struct navecu_can_imu_time_t m;
        navecu_can_imu_time_unpack(&m, d, 8u);
        if (m.imu_counter > E2E_COUNTER_MAX) {
            return RX_BAD_COUNTER;
        }
        in->kind = RX_IMU_TIME;
        in->u.imu_time.counter = m.imu_counter;
        in->u.imu_time.t_us = m.sample_time;
        return RX_OK;
    }
    if (msg == NAVECU_MSG_IMU_RATE) {
        struct navecu_can_imu_rate_t m;
        navecu_can_imu_rate_unpack(&m, d, 8u);
        if (m.imu_counter > E2E_COUNTER_MAX) {
            return RX_BAD_COUNTER;
        }
        in->kind = RX_IMU_RATE;
        in->u.imu_rate.counter = m.imu_counter;
        in->u.imu_rate.raw[0] = m.angle_inc_x;
        in->u.imu_rate.raw[1] = m.angle_inc_y;
        in->u.imu_rate.raw[2] = m.angle_inc_z;
        memcpy(in->u.imu_rate.data, d, 8u);
        return RX_OK;
    }
    struct navecu_can_imu_accel_t m;
    navecu_can_imu_accel_unpack(&m, d, 8u);
    in->kind = RX_IMU_ACCEL;
    in->u.imu_accel.counter = m.imu_counter;
    in->u.imu_accel.fault = m.imu_fault;
    in->u.imu_accel.raw[0] = m.vel_inc_x;
    in->u.imu_accel.raw[1] = m.vel_inc_y;
    in->u.imu_accel.raw[2] = m.vel_inc_z;
    memcpy(in->u.imu_accel.data, d, 8u);
    return RX_OK;
}

static rx_verdict_t decode_gnss(rx_state_t *rx, int msg, const uint8_t d[8], rx_input_t *in)
{
    if (msg == NAVECU_MSG_GNSS_POSITION) {
        struct navecu_can_gnss_position_t m;
        navecu_can_gnss_position_unpack(&m, d, 8u);
        in->kind = RX_GNSS_POSITION;
        in->u.position.lat_e7 = m.latitude;
        in->u.position.lon_e7 = lon_wrapped_e7(m.longitude);
        return lat_lon_ok(m.latitude, m.longitude) ? RX_OK : RX_GNSS_BAD;
    }
    if (msg == NAVECU_MSG_GNSS_VELOCITY) {
        struct navecu_can_gnss_velocity_t m;
        navecu_can_gnss_velocity_unpack(&m, d, 8u);
        if (m.gnss_epoch > E2E_COUNTER_MAX) {
            return RX_BAD_COUNTER; /* the invalid 15; a repeated epoch is the status's to
                                      tell, from its TimeOfWeek */
        }
        in->kind = RX_GNSS_VELOCITY;
        in->u.velocity.epoch = m.gnss_epoch;
        in->u.velocity.v_enu_mps[0] = navecu_can_gnss_velocity_vel_east_decode(m.vel_east);
        in->u.velocity.v_enu_mps[1] = navecu_can_gnss_velocity_vel_north_decode(m.vel_north);
        in->u.velocity.v_enu_mps[2] = navecu_can_gnss_velocity_vel_up_decode(m.vel_up);
        in->u.velocity.sacc_mps = navecu_can_gnss_velocity_speed_accuracy_decode(m.speed_accuracy);
        return RX_OK;
    }
    if (msg == NAVECU_MSG_GNSS_TIME) {
        struct navecu_can_gnss_time_t m;
        navecu_can_gnss_time_unpack(&m, d, 8u);
        if (!navecu_can_gnss_time_gps_week_is_in_range(m.gps_week) || m.gnss_epoch > E2E_COUNTER_MAX) {
            return RX_BAD_VALUE;
        }
        in->kind = RX_GNSS_TIME;
        in->u.time.epoch = m.gnss_epoch;
        in->u.time.gps_week = m.gps_week;
        return RX_OK;
    }
    if (msg == NAVECU_MSG_GNSS_HEIGHT) {
        struct navecu_can_gnss_height_t m;
        navecu_can_gnss_height_unpack(&m, d, 8u);
        if (!navecu_can_gnss_height_height_is_in_range(m.height)) {
            return RX_BAD_VALUE;
        }
        in->kind = RX_GNSS_HEIGHT;
        in->u.height.epoch = m.gnss_epoch;
        in->u.height.h_cm = m.height;
        return RX_OK;
    }
    struct navecu_can_gnss_status_t m;
    navecu_can_gnss_status_unpack(&m, d, 8u);
    in->kind = RX_GNSS_STATUS;
    in->u.status.epoch = m.gnss_epoch;
    in->u.status.defined = m.gnss_epoch <= E2E_COUNTER_MAX &&
                           m.fix_type <= NAVECU_CAN_GNSS_STATUS_FIX_TYPE_RTK_FIXED_CHOICE &&
                           navecu_can_gnss_status_time_of_week_is_in_range(m.time_of_week);
    in->u.status.fix_3d = m.fix_type >= NAVECU_CAN_GNSS_STATUS_FIX_TYPE_FIX3_D_CHOICE;
    in->u.status.n_sats = m.num_satellites;
    in->u.status.hacc_m = navecu_can_gnss_status_horiz_accuracy_decode(m.horiz_accuracy);
    in->u.status.vacc_m = navecu_can_gnss_status_vert_accuracy_decode(m.vert_accuracy);
    in->u.status.tow_ms = m.time_of_week;
    /* a repeat: a fix at the TimeOfWeek of the previous fix (the epoch number alone cannot
     * tell, it comes round over an outage); statuses without a fix do not count */
    in->u.status.repeat = 0u;
    if (in->u.status.defined != 0u && in->u.status.fix_3d != 0u &&
        in->u.status.n_sats >= APP_GNSS_MIN_SATS) {
        if (rx->have_gnss_tow != 0u && rx->gnss_tow_ms == m.time_of_week) {
            in->u.status.repeat = 1u;
        }
        rx->gnss_tow_ms = m.time_of_week;
        rx->have_gnss_tow = 1u;
    }
    return RX_OK;
}

/* One axis of a satellite's position and velocity (GNSS_RawSatX/Y/Z). */
static void raw_axis(struct rx_raw_sat *r, uint8_t part, uint8_t epoch, uint8_t slot,
                     int32_t pos_lsb, int16_t vel_lsb)
{
    r->part = part;
    r->epoch = epoch;
    r->slot = slot;
    r->pos_lsb = pos_lsb;
    r->vel_lsb = vel_lsb;
}

/* One of the raw GNSS frames (issue #20): the values stay in the protocol's integer units
 * (a 32-bit position at 0.02 m does not fit float32's significand; gnss_raw.h converts
 * them in its fixed-point domain). The epoch number (the E2E counter of these frames) must
 * be 0..14; the slot, identity and elevation within the DBC's ranges. */
static rx_verdict_t decode_raw(int msg, const uint8_t d[8], rx_input_t *in)
{
    struct rx_raw_sat *r = &in->u.raw_sat;
    (void)memset(r, 0, sizeof *r);
    in->kind = RX_GNSS_RAW_SAT;
    if (msg == (int)NAVECU_MSG_GNSS_RAW_EPOCH) {
        struct navecu_can_gnss_raw_epoch_t m;
        (void)navecu_can_gnss_raw_epoch_unpack(&m, d, 8u);
        if (m.gnss_epoch > E2E_COUNTER_MAX) {
            return RX_BAD_COUNTER;
        }
        if (!navecu_can_gnss_raw_epoch_num_meas_is_in_range(m.num_meas) ||
            !navecu_can_gnss_raw_epoch_time_of_week_is_in_range(m.time_of_week)) {
            return RX_BAD_VALUE;
        }
        in->kind = RX_GNSS_RAW_EPOCH;
        in->u.raw_epoch.epoch = m.gnss_epoch;
        in->u.raw_epoch.n_meas = m.num_meas;
        in->u.raw_epoch.clock_reset = m.clock_reset;
        in->u.raw_epoch.tow_ms = m.time_of_week;
        return RX_OK;
    }
    if (msg == (int)NAVECU_MSG_GNSS_RAW_RANGE) {
        struct navecu_can_gnss_raw_range_t m;
        (void)navecu_can_gnss_raw_range_unpack(&m, d, 8u);
        r->part = (uint8_t)RX_RAW_PART_RANGE;
        r->epoch = m.gnss_epoch;
        r->slot = m.raw_slot;
        r->pr_lsb = m.pseudorange;
        r->system = m.gnss_system;
        r->sv_id = m.sv_id;
        r->elevation_deg = m.elevation;
        r->pr_valid = m.pseudorange_valid;
        if (!navecu_can_gnss_raw_range_elevation_is_in_range(m.elevation)) {
            return RX_BAD_VALUE;
        }
    } else if (msg == (int)NAVECU_MSG_GNSS_RAW_RATE) {
        struct navecu_can_gnss_raw_rate_t m;
        (void)navecu_can_gnss_raw_rate_unpack(&m, d, 8u);
        r->part = (uint8_t)RX_RAW_PART_RATE;
        r->epoch = m.gnss_epoch;
        r->slot = m.raw_slot;
        r->rr_lsb = m.range_rate;
        r->pr_sigma_lsb = m.pseudorange_sigma;
        r->rr_sigma_lsb = m.range_rate_sigma;
        r->cn0_dbhz = m.cn0;
        r->rr_valid = m.range_rate_valid;
    } else {
        /* GNSS_RawSatX, Y and Z share one layout (navecu.dbc): X's unpacks all three */
        struct navecu_can_gnss_raw_sat_x_t m;
        (void)navecu_can_gnss_raw_sat_x_unpack(&m, d, 8u);
        const uint8_t part = msg == (int)NAVECU_MSG_GNSS_RAW_SAT_X   ? RX_RAW_PART_X
                             : msg == (int)NAVECU_MSG_GNSS_RAW_SAT_Y ? RX_RAW_PART_Y
                                                                      : RX_RAW_PART_Z;
        raw_axis(r, part, m.gnss_epoch, m.raw_slot, m.sat_pos_x, m.sat_vel_x);
    }
    return r->epoch > E2E_COUNTER_MAX ? RX_BAD_COUNTER : RX_OK;
}

static rx_verdict_t decode_command(rx_state_t *rx, int msg, const uint8_t d[8],
                                   rx_input_t *in)
{
    if (msg == NAVECU_MSG_CMD_KNOWN_POSITION) {
        struct navecu_can_cmd_known_position_t m;
        navecu_can_cmd_known_position_unpack(&m, d, 8u);
        if (!lat_lon_ok(m.latitude, m.longitude)) {
            return RX_BAD_VALUE;
        }
        in->kind = RX_KNOWN_POSITION;
        in->u.position.lat_e7 = m.latitude;
        in->u.position.lon_e7 = lon_wrapped_e7(m.longitude);
        return RX_OK;
    }
    if (msg == NAVECU_MSG_CMD_INITIAL_ATTITUDE) {
        struct navecu_can_cmd_initial_attitude_t m;
        navecu_can_cmd_initial_attitude_unpack(&m, d, 8u);
        if (!command_counter_ok(&rx->att, m.att_counter)) {
            return RX_BAD_COUNTER;
        }
        if (!navecu_can_cmd_initial_attitude_init_roll_is_in_range(m.init_roll) ||
            !navecu_can_cmd_initial_attitude_init_pitch_is_in_range(m.init_pitch)) {
            return RX_BAD_VALUE;
        }
        in->kind = RX_INITIAL_ATTITUDE;
        in->u.attitude.roll_rad = navecu_can_cmd_initial_attitude_init_roll_decode(m.init_roll);
        in->u.attitude.pitch_rad = navecu_can_cmd_initial_attitude_init_pitch_decode(m.init_pitch);
        return RX_OK;
    }
    struct navecu_can_cmd_control_t m;
    navecu_can_cmd_control_unpack(&m, d, 8u);
    if (!command_counter_ok(&rx->cmd, m.cmd_counter)) {
        return RX_BAD_COUNTER;
    }
    in->kind = RX_COMMAND;
    in->u.command.command = command_of(m.command);
    in->u.command.heading_valid = m.heading_valid ? 1u : 0u;
    in->u.command.heading_in_range = navecu_can_cmd_control_heading_is_in_range(m.heading);
    in->u.command.height_in_range = navecu_can_cmd_control_height_is_in_range(m.height);
    in->u.command.heading_rad = navecu_can_cmd_control_heading_decode(m.heading) / NAV_DEG_PER_RAD;
    in->u.command.h_cm = m.height * 10;
    return RX_OK;
}

/* One of the car's messages (vehicle.h), or RX_FOREIGN for a frame the car's profile
 * does not name either. */
static rx_verdict_t decode_car(rx_state_t *rx, const hal_can_frame_t *f, rx_input_t *in)
{
    vehicle_msg_t m;
    const vehicle_verdict_t v = vehicle_decode(f, &rx->car_counters, &m);
    if (m.kind == VEHICLE_MSG_NONE) {
        return RX_FOREIGN;
    }
#if VEHICLE_SPLIT_WHEELS
    if (v == VEHICLE_WHEELS_HELD) {
        /* one axle's wheel speeds, read and held until the other axle's (vehicle_pair.h):
         * counted as read, nothing to act on yet */
        if (rx->car_read[VEHICLE_MSG_WHEELS] < UINT32_MAX) {
            rx->car_read[VEHICLE_MSG_WHEELS]++;
        }
        return RX_OK;
    }
#endif
    if (v != VEHICLE_OK) {
        return v == VEHICLE_BAD_DLC        ? RX_BAD_DLC
               : v == VEHICLE_BAD_CHECKSUM ? RX_BAD_CRC
               : v == VEHICLE_BAD_COUNTER  ? RX_BAD_COUNTER
                                           : RX_BAD_VALUE;
    }
    if ((unsigned)m.kind < (unsigned)VEHICLE_MSG_N && rx->car_read[m.kind] < UINT32_MAX) {
        rx->car_read[m.kind]++;
    }
    if (m.kind == VEHICLE_MSG_GEAR) {
        rx->gear_direction = m.gear_direction;
        rx->have_gear = 1u;
    } else if (m.kind == VEHICLE_MSG_YAW_RATE) {
        rx->esp_yaw_rate_rps = m.yaw_rate_rps;
        rx->have_esp_yaw = 1u;
    } else {
        /* unsigned speeds: backwards in reverse gear (before the first gear frame, and in
         * park or neutral, forward); signed ones as they are */
        const nav_real_t sign = vehicle_profile.direction == VEHICLE_DIR_GEAR &&
                                        rx->have_gear && rx->gear_direction < 0
                                    ? NAV_C(-1.0)
                                    : NAV_C(1.0);
        in->kind = RX_WHEELS;
        for (int i = 0; i < 4; i++) {
            in->u.wheels.mps[i] = sign * m.wheel_mps[i];
        }
    }
    return RX_OK;
}

rx_verdict_t app_rx_decode(rx_state_t *rx, const uint32_t can_ids[NAVECU_MSG_N],
                           const hal_can_frame_t *f, rx_input_t *in)
{
    in->kind = RX_NONE;
    if (f->extended) {
        return RX_FOREIGN;
    }
    const int msg = msg_of(can_ids, f->id);
    if (msg == (int)NAVECU_MSG_N) {
        return decode_car(rx, f, in);
    }
    if (!IS_INPUT[msg]) {
        return RX_OK; /* our own outputs, seen on a shared bus */
    }
    if (f->dlc != 8u) {
        return RX_BAD_DLC;
    }
    if (is_e2e(msg) && !e2e_crc_ok(f->id, f->data)) {
        return RX_BAD_CRC;
    }
    switch (msg) {
    case NAVECU_MSG_IMU_RATE:
    case NAVECU_MSG_IMU_ACCEL:
    case NAVECU_MSG_IMU_TIME:
        return decode_imu(msg, f->data, in);
    case NAVECU_MSG_WHEEL_SPEEDS: {
        struct navecu_can_wheel_speeds_t m;
        navecu_can_wheel_speeds_unpack(&m, f->data, 8u);
        if (e2e_counter_step(&rx->wheel, m.wheel_counter) <= 0) {
            return RX_BAD_COUNTER;
        }
        in->kind = RX_WHEELS;
        in->u.wheels.mps[0] = navecu_can_wheel_speeds_wheel_speed_fl_decode(m.wheel_speed_fl);
        in->u.wheels.mps[1] = navecu_can_wheel_speeds_wheel_speed_fr_decode(m.wheel_speed_fr);
        in->u.wheels.mps[2] = navecu_can_wheel_speeds_wheel_speed_rl_decode(m.wheel_speed_rl);
        in->u.wheels.mps[3] = navecu_can_wheel_speeds_wheel_speed_rr_decode(m.wheel_speed_rr);
        return RX_OK;
    }
    case NAVECU_MSG_GNSS_POSITION:
    case NAVECU_MSG_GNSS_VELOCITY:
    case NAVECU_MSG_GNSS_HEIGHT:
    case NAVECU_MSG_GNSS_STATUS:
    case NAVECU_MSG_GNSS_TIME:
        return decode_gnss(rx, msg, f->data, in);
    case NAVECU_MSG_GNSS_RAW_SAT_X:
    case NAVECU_MSG_GNSS_RAW_SAT_Y:
    case NAVECU_MSG_GNSS_RAW_SAT_Z:
    case NAVECU_MSG_GNSS_RAW_RANGE:
    case NAVECU_MSG_GNSS_RAW_RATE:
    case NAVECU_MSG_GNSS_RAW_EPOCH:
        return decode_raw(msg, f->data, in);
    default: /* CMD_KnownPosition, CMD_Control, CMD_InitialAttitude */
        return decode_command(rx, msg, f->data, in);
    }
}

void app_rx_imu_increment(const int32_t w_raw[3], const int32_t v_raw[3], nav_real_t dt_s,
                          imu_inc_t *inc)
{
    inc->dtheta_b_rad[0] = navecu_can_imu_rate_angle_inc_x_decode(w_raw[0]);
    inc->dtheta_b_rad[1] = navecu_can_imu_rate_angle_inc_y_decode(w_raw[1]);
    inc->dtheta_b_rad[2] = navecu_can_imu_rate_angle_inc_z_decode(w_raw[2]);
    inc->dv_b_mps[0] = navecu_can_imu_accel_vel_inc_x_decode(v_raw[0]);
    inc->dv_b_mps[1] = navecu_can_imu_accel_vel_inc_y_decode(v_raw[1]);
    inc->dv_b_mps[2] = navecu_can_imu_accel_vel_inc_z_decode(v_raw[2]);
    inc->dt_s = dt_s;
}

nav_real_t app_rx_angle_lsb_rad(void)
{
    return navecu_can_imu_rate_angle_inc_x_decode(1);
}

nav_real_t app_rx_vel_lsb_mps(void)
{
    return navecu_can_imu_accel_vel_inc_x_decode(1);
}
