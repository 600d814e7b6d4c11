/*
 * app_rx.h - receive and validate: one CAN frame in, one decoded input out, or the reason
 * it was refused. The checks of a single frame live here, in the order the protocol gives
 * them (docs/can.md): the identifier is one of navecu's inputs, the length is 8, the E2E
 * CRC matches, the alive counter steps forward (for the messages whose counter is per
 * frame), and single-frame values are within the DBC's range. What needs more than one
 * frame is checked where the frames meet: the IMU pair in imu_stream.h, the GNSS epoch in
 * gnss_epoch.h.
 *
 * Decoded values are in SI units (rad, m/s, m) or, where a float would lose the protocol's
 * exact value, in the protocol's integer unit named in the field (lat_e7: 1e-7 deg, h_cm:
 * cm), which the core's fixed-point position takes without rounding.
 * The car's own messages that the build's vehicle profile names (firmware/vehicle/
 * vehicle.h) are decoded here too: their wheel speeds become RX_WHEELS, signed by the gear
 * where the profile says so; the gear and the ESP yaw rate update rx_state_t.
 * This is the only application module that knows the codec's message structs.
 */
#ifndef NAVECU_APP_RX_H
#define NAVECU_APP_RX_H

#include <stddef.h>
#include <stdint.h>

#include "e2e.h"
#include "hal.h"
#include "navecu_protocol.h"
#include "sins.h"
#include "vehicle.h"

typedef enum {
    RX_NONE = 0,          /* nothing to act on: one of navecu's own outputs on the bus */
    RX_IMU_RATE,
    RX_IMU_ACCEL,
    RX_WHEELS,
    RX_GNSS_POSITION,
    RX_GNSS_VELOCITY,
    RX_GNSS_HEIGHT,
    RX_GNSS_STATUS,
    RX_GNSS_TIME,
    RX_KNOWN_POSITION,
    RX_COMMAND,
    RX_INITIAL_ATTITUDE,
    RX_IMU_TIME,
    RX_GNSS_RAW_SAT,   /* one of a satellite's five raw frames (gnss_raw.h) */
    RX_GNSS_RAW_EPOCH, /* GNSS_RawEpoch, closing a raw epoch */
} rx_kind_t;

/* Which of a satellite's five raw frames (rx_raw_sat.part): the bit of each, so that a
 * slot's frames can be collected in one byte. */
#define RX_RAW_PART_X 0x01u
#define RX_RAW_PART_Y 0x02u
#define RX_RAW_PART_Z 0x04u
#define RX_RAW_PART_RANGE 0x08u
#define RX_RAW_PART_RATE 0x10u
#define RX_RAW_PARTS_ALL 0x1Fu

/* Why a frame was refused (the counter of app_health_t it is counted in). */
typedef enum {
    RX_OK = 0,
    RX_FOREIGN,     /* foreign: a frame navecu does not read (another node's traffic) */
    RX_BAD_DLC,     /* bad_dlc */
    RX_BAD_CRC,     /* bad_crc */
    RX_BAD_COUNTER, /* bad_counter: repeated, invalid or out-of-sequence alive counter */
    RX_BAD_VALUE,   /* bad_value: outside the DBC's range */
    RX_GNSS_BAD,    /* gnss_rejected: an impossible GNSS position */
} rx_verdict_t;

/* The commands of CMD_Control (the DBC's value table Command). */
typedef enum {
    RX_CMD_NONE = 0,
    RX_CMD_RESET,
    RX_CMD_SET_INITIAL_POSITION,
    RX_CMD_STORE_CALIBRATION,
    RX_CMD_ERASE_CALIBRATION,
    RX_CMD_CALIBRATE_HERE,
    RX_CMD_CALIBRATE_AT_GNSS,
    RX_CMD_UNKNOWN, /* a value the protocol does not define */
} rx_command_t;

typedef struct {
    rx_kind_t kind;
    union {
        struct rx_imu_rate { /* IMU_Rate */
            uint8_t counter;
            int32_t raw[3]; /* angle increments, x y z, in the signal's LSB */
            uint8_t data[8];/* the payload, covered by the pair CRC in IMU_Accel */
        } imu_rate;
        struct rx_imu_accel { /* IMU_Accel */
            uint8_t counter;
            uint8_t fault;  /* the IMU reports a fault */
            int32_t raw[3]; /* velocity increments, x y z, in the signal's LSB */
            uint8_t data[8];
        } imu_accel;
        struct rx_imu_time { /* IMU_Time: the IMU's own time of one sample */
            uint8_t counter;  /* the sample's ImuCounter */
            uint32_t t_us;    /* SampleTime, microseconds, wrapping at 2^32 */
        } imu_time;
        struct rx_wheels {
            nav_real_t mps[4]; /* FL, FR, RL, RR, signed, reverse negative */
        } wheels;
        struct rx_position { /* GNSS_Position, CMD_KnownPosition */
            int32_t lat_e7, lon_e7;
        } position;
        struct rx_velocity { /* GNSS_Velocity */
            uint8_t epoch;
            nav_real_t v_enu_mps[3];
            nav_real_t sacc_mps; /* the receiver's speed accuracy */
        } velocity;
        struct rx_height { /* GNSS_Height */
            uint8_t epoch;
            int32_t h_cm;   /* above the ellipsoid */
        } height;
        struct rx_time {   /* GNSS_Time */
            uint8_t epoch;
            uint16_t gps_week;
        } time;
        struct rx_status { /* GNSS_Status, closing an epoch */
            uint8_t epoch;
            uint8_t defined;  /* epoch and fix type are values the protocol defines */
            uint8_t fix_3d;   /* fix type 3D or better */
            uint8_t n_sats;
            nav_real_t hacc_m, vacc_m; /* the receiver's accuracies */
            uint32_t tow_ms;  /* GPS time of week of the epoch */
            uint8_t repeat;   /* a fix with the TimeOfWeek of the previous fix: a repeat */
        } status;
        struct rx_command_in { /* CMD_Control */
            rx_command_t command;
            uint8_t heading_valid;
            uint8_t heading_in_range, height_in_range;
            nav_real_t heading_rad; /* clockwise from north */
            int32_t h_cm;
        } command;
        struct rx_attitude { /* CMD_InitialAttitude */
            nav_real_t roll_rad, pitch_rad;
        } attitude;
        struct rx_raw_sat { /* GNSS_RawSatX/Y/Z, GNSS_RawRange, GNSS_RawRate: the signals
                               in their protocol units (exact integers, gnss_raw.h) */
            uint8_t part;     /* RX_RAW_PART_* of the frame */
            uint8_t epoch, slot;
            int32_t pos_lsb;  /* X/Y/Z: ECEF position, 0.02 m */
            int16_t vel_lsb;  /* X/Y/Z: ECEF velocity, 0.125 m/s */
            uint32_t pr_lsb;  /* range: corrected pseudorange, 0.02 m */
            uint8_t system, sv_id, elevation_deg, pr_valid;
            int32_t rr_lsb;   /* rate: pseudorange rate, 0.01 m/s */
            uint8_t pr_sigma_lsb, rr_sigma_lsb, cn0_dbhz, rr_valid;
        } raw_sat;
        struct rx_raw_epoch { /* GNSS_RawEpoch */
            uint8_t epoch, n_meas, clock_reset;
            uint32_t tow_ms;  /* the measurement time, GPS time of week (receiver clock) */
        } raw_epoch;
    } u;
} rx_input_t;

/* The E2E receive state of the single-frame inputs: kept through a navigation reset, so
 * that a replayed old frame is never taken for a first one (and so the car's rolling
 * counters); and what the car's own messages said last (vehicle.h): the gear's direction
 * and the ESP's yaw rate. (The byte fields together: the car's counters fit in what was
 * padding, the size unchanged.) */
typedef struct {
    e2e_counter_t wheel, cmd, att;
    vehicle_counters_t car_counters; /* the car's rolling counters, where the profile names
                                        them */
    uint8_t have_gnss_tow;
    int8_t gear_direction;  /* +1 forward, -1 reverse, 0 park/neutral (the car's gear) */
    uint8_t have_gear;
    uint8_t have_esp_yaw;
    /* the TimeOfWeek of the last GNSS_Status reporting a fix (a repeat is decided from it:
     * the 4-bit GnssEpoch comes round over an outage of 15 epochs) */
    uint32_t gnss_tow_ms;
    nav_real_t esp_yaw_rate_rps; /* the car's ESP, left positive */
    uint32_t car_read[VEHICLE_MSG_N]; /* the car's frames read and passed, by vehicle_kind_t
                                         (saturating; host summary) */
} rx_state_t;

/* Decode and check one frame, navecu's messages on the identifiers can_ids. Returns RX_OK with *in filled (kind RX_NONE for navecu's
 * own outputs), or the reason it was refused (*in then undefined, except that a refused
 * GNSS_Position sets kind RX_GNSS_POSITION, which the epoch in assembly must know). */
rx_verdict_t app_rx_decode(rx_state_t *rx, const uint32_t can_ids[NAVECU_MSG_N],
                           const hal_can_frame_t *f, rx_input_t *in);

/* Raw IMU increments (the signals' LSB) to SI, over an interval of dt_s. */
void app_rx_imu_increment(const int32_t w_raw[3], const int32_t v_raw[3], nav_real_t dt_s,
                          imu_inc_t *inc);

/* The size of one LSB of the angle (rad) and velocity (m/s) increments. */
nav_real_t app_rx_angle_lsb_rad(void);
nav_real_t app_rx_vel_lsb_mps(void);

/* The CAN identifiers the application receives with can_ids (app_config_t.can_ids) and
 * the car's messages its vehicle profile reads, for receive filters: writes up to max of
 * them to ids and returns how many there are. */
size_t app_rx_ids(const uint32_t can_ids[NAVECU_MSG_N], uint32_t *ids, size_t max);

#endif /* NAVECU_APP_RX_H */
