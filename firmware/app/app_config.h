/*
 * app_config.h - what an integrator configures: the IMU, the GNSS receiver, the car's
 * odometer and the output rates. Every field but can_ids is a parameter of the one table
 * firmware/app/params.toml (docs/configuration.md): its range, default, unit and UDS data
 * identifier are there, generated into app_params.[ch]. app_default_config() gives the
 * values the ECU runs with when nothing else is configured; app_config_valid() is the one
 * range check every source of a configuration (the host's options, a stored record) goes
 * through.
 */
#ifndef NAVECU_APP_CONFIG_H
#define NAVECU_APP_CONFIG_H

#include <stdint.h>

#include "app_params.h"
#include "nav_types.h"
#include "navecu_protocol.h"
#include "odo.h"

/* where the GNSS accuracies come from (the parameter gnss_accuracy) */
typedef enum {
    GNSS_ACC_REPORTED = 0, /* the receiver's own, in GNSS_Status and GNSS_Velocity */
    GNSS_ACC_DECLARED = 1, /* a receiver that reports none: gnss_hacc_m, gnss_vacc_m,
                              gnss_sacc_mps (its datasheet's figures) */
} gnss_acc_source_t;

/* where the IMU's mounting comes from (the parameter imu_mount_source) */
typedef enum {
    MOUNT_SOURCE_FIXED = 0,     /* imu_mount_rad */
    MOUNT_SOURCE_AUTOMATIC = 1, /* estimated from the data (mount_est.h) */
} mount_source_t;

/* whether the receiver measures the vertical velocity (the parameter gnss_vel_up) */
typedef enum {
    GNSS_VUP_MEASURED = 0,
    GNSS_VUP_NONE = 1, /* GNSS_Velocity VelUp is not a measurement: not fused */
} gnss_vel_up_t;

/* what the filter fuses of the receiver (the parameter gnss_input) */
typedef enum {
    GNSS_INPUT_FIX = 0,  /* fixes: position and velocity (loosely coupled) */
    GNSS_INPUT_RAW = 1,  /* raw pseudoranges and rates (tightly coupled); fixes start it */
    GNSS_INPUT_BOTH = 2, /* per epoch the fix, or the raw measurements of an epoch without */
} gnss_input_t;

/* where the wheel speeds' direction of travel comes from (the parameter odo_direction) */
typedef enum {
    ODO_DIR_AS_READ = 0,   /* their sign (signed WheelSpeeds, or the profile's gear) */
    ODO_DIR_NAVIGATOR = 1, /* magnitudes: the navigator's forward velocity's sign */
} odo_direction_t;

/* the IMU's sample time (the parameter imu_time) */
typedef enum {
    IMU_TIME_GRID = 0,    /* every sample 1/imu_rate_hz long */
    IMU_TIME_STAMPED = 1, /* each sample from its IMU_Time stamp to the previous one's
                             (imu_stream.h); imu_rate_hz is the nominal rate */
} imu_time_t;

typedef struct {
    uint16_t imu_rate_hz;    /* IMU sample rate, 10..400 */
    imu_time_t imu_time;     /* grid, or stamped by IMU_Time */
    uint16_t nav_rate_hz;    /* NAV_Position/Height/Velocity/Attitude rate, <= imu_rate_hz */
    uint16_t status_rate_hz; /* NAV_Status (and NAV_Accuracy) rate, <= imu_rate_hz */
    uint16_t dyn_rate_hz;    /* NAV_Rates/AttitudeRates/Accel/AccelEnu rate, <= imu_rate_hz;
                                0: not sent */
    uint16_t level_s;        /* accelerometer levelling time before navigation starts */
    odo_axle_t odo_axle;     /* wheels that measure the distance (odo.h) */
    nav_real_t odo_track_m;       /* the measuring axle's track (the turn's wheel difference) */
    nav_real_t odo_wheelbase_m;   /* for the front axle's steering correction */
    nav_real_t cal_min_base_m;    /* one-point calibration refused closer than this to its base */
    /* the gyro's noise and bias, for the bias estimate at standstill (a scalar Kalman
     * filter of a constant with a zero-mean prior): */
    nav_real_t gyro_arw_rad_rts;  /* angle random walk, rad/sqrt(s) */
    nav_real_t gyro_bias_rps;     /* 1-sigma of the turn-on bias, rad/s */
    nav_real_t accel_bias_mps2;   /* 1-sigma of the accelerometer bias, m/s^2 */
    nav_real_t gyro_bias_rw_rps_rts;    /* in-run gyro bias random walk, rad/s/sqrt(s) */
    nav_real_t gyro_bias_corr_time_s;   /* the z gyro's in-run bias correlation time, s */
    nav_real_t accel_bias_rw_mps2_rts;  /* in-run accelerometer bias random walk */
    nav_real_t accel_fwd_instability_mps2; /* the forward (y) accelerometer's bias
                                              instability, its Allan floor */
    nav_real_t gyro_scale;        /* 1-sigma of the z gyro's scale factor error (a ratio) */
    nav_real_t gnss_latency_s;    /* receiver output latency: fix time of validity to
                                     arrival (more when TimeOfWeek shows a late epoch) */
    nav_real_t gnss_lever_b_m[3]; /* GNSS antenna from the IMU, body axes, m */
    nav_real_t gnss_corr_s;       /* correlation time of the receiver's position errors */
    nav_real_t gnss_vel_corr_s;   /* and of its velocity errors (0: independent) */
    nav_real_t gnss_white_ratio;  /* white part of its declared accuracy (sigma ratio) */
    gnss_acc_source_t gnss_accuracy; /* reported, or declared by the next three */
    nav_real_t gnss_hacc_m;       /* declared horizontal accuracy, 68 % radius */
    nav_real_t gnss_vacc_m;       /* declared vertical accuracy, 1 sigma */
    nav_real_t gnss_sacc_mps;     /* declared speed accuracy */
    gnss_vel_up_t gnss_vel_up;    /* the receiver measures VelUp, or not */
    gnss_input_t gnss_input;      /* what the filter fuses: fixes, raw measurements, both */
    nav_real_t odo_lever_b_m[3];  /* the odometer's reference point (rear axle middle) from
                                     the IMU, body axes, m */
    nav_real_t odo_lever_sigma_m; /* its 1-sigma uncertainty, m */
    odo_direction_t odo_direction; /* the speeds' sign as read, or the navigator's */
    nav_real_t odo_step_mps;      /* the source's speed resolution (the offset's prior) */
    nav_real_t odo_latency_s;     /* a reading's moment to its arrival */
    nav_real_t imu_mount_rad[3];  /* the IMU's attitude in the vehicle: roll, pitch, yaw
                                     (mounting.h) */
    mount_source_t imu_mount_source; /* imu_mount_rad, or the automatic estimate */
    nav_real_t mount_est_sigma_rad;  /* the automatic estimate's convergence sigma */
    nav_real_t mount_est_excite_m2ps3; /* and its excitation */
    nav_real_t gyro_range_rps;    /* the IMU's measurement range: a rate at or beyond it is */
    nav_real_t accel_range_mps2;  /* saturated (counted, flagged, uncertain by the range) */
    uint16_t uds_request_id;      /* the UDS server's physical request ID (11-bit) */
    uint16_t uds_response_id;     /* its response ID (11-bit) */
    /* navecu's own CAN identifiers (11-bit, all different), indexed by navecu_msg_t
     * (navecu_protocol.h): the DBC's by default, the vehicle profile's on a car whose bus
     * already uses them (vehicles/, docs/vehicles.md) */
    uint32_t can_ids[NAVECU_MSG_N];
} app_config_t;

/* Defaults: the table's (IMU 100 Hz, outputs 50 Hz, status 10 Hz, levelling 30 s, the IMU
 * figures of its default preset, automotive MEMS; a u-blox-class standalone receiver); the
 * car's geometry and navecu's CAN identifiers from the build's vehicle profile
 * (firmware/vehicle/vehicle.h). */
app_config_t app_default_config(void);

/* The same, written into *cfg (no copy of the struct on the caller's stack: a board's). */
void app_config_defaults(app_config_t *cfg);

/* Set the IMU parameters of preset id together (app_presets, generated from the table's
 * [presets.NAME]): 0, or -1 for an unknown preset (cfg unchanged). */
int app_config_preset(app_config_t *cfg, app_preset_id_t id);

/* The first rule of a configuration it breaks (APP_CONFIG_OK: none): every field within
 * its range (the parameter table), the CAN identifiers 11-bit and distinct (navecu's
 * messages and the two UDS identifiers together), the output rates at most the IMU rate. */
typedef enum {
    APP_CONFIG_OK = 0,
    APP_CONFIG_RANGE,       /* a parameter out of its range */
    APP_CONFIG_UDS_ON_NAV,  /* a UDS identifier is one of navecu's message identifiers */
    APP_CONFIG_CAN_IDS,     /* navecu's identifiers not 11-bit, or one used twice */
    APP_CONFIG_UDS_SAME,    /* the UDS request and response identifiers are the same */
    APP_CONFIG_RATES,       /* an output rate above the IMU rate */
} app_config_rule_t;

app_config_rule_t app_config_check(const app_config_t *cfg);

/* 1 if app_config_check finds no rule broken, else 0. */
int app_config_valid(const app_config_t *cfg);

/* Parameter id's value(s), SI units (one value in v[0]; APP_PARAM_VEC3 three; an enum its
 * index), through the table's offset and size of its field. */
void app_param_get(const app_config_t *cfg, app_param_id_t id, nav_real_t v[3]);

/* Set parameter id from v (as app_param_get gives it): 0, or -1 (cfg unchanged) when v is
 * outside the parameter's range. */
int app_param_set(app_config_t *cfg, app_param_id_t id, const nav_real_t v[3]);

/* 1 if v is a value of parameter id (its range; a whole number for APP_PARAM_U16 and
 * APP_PARAM_ENUM), else 0. */
int app_param_in_range(app_param_id_t id, const nav_real_t v[3]);

#endif /* NAVECU_APP_CONFIG_H */
