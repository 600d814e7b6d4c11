/* GENERATED FILE - DO NOT EDIT. Source: firmware/app/params.toml.
 * Regenerate with 'make params' (tools/gen_params.py); 'make test' fails if stale. */

#ifndef NAVECU_APP_PARAMS_H
#define NAVECU_APP_PARAMS_H

#include <stddef.h>
#include <stdint.h>

#include "nav_types.h"

/* what a parameter holds: one value (APP_PARAM_U16, an integer; APP_PARAM_ENUM, the
 * index of its value name; APP_PARAM_REAL) or three (APP_PARAM_VEC3) */
typedef enum {
    APP_PARAM_U16 = 0,
    APP_PARAM_REAL = 1,
    APP_PARAM_VEC3 = 2,
    APP_PARAM_ENUM = 3,
} app_param_type_t;

/* 20 bytes a row on the ECU (24 with a byte per flag): the flags and the small
 * numbers in one word of bit-fields */
typedef struct {
    nav_real_t min_si, max_si; /* range, SI units (enum: 0..values - 1) */
    nav_real_t default_si;  /* default, SI; a vec3's x, y and z alike (vehicle_default:
                               unused) */
    uint16_t did;           /* UDS data identifier */
    uint16_t offset;        /* its field in app_config_t: offsetof */
    unsigned int type : 2;  /* an app_param_type_t */
    unsigned int min_exclusive : 1;   /* the range excludes min */
    unsigned int vehicle_default : 1; /* the default is the vehicle profile's */
    unsigned int at_reset : 1;  /* apply = "reset": copied at app_init, so a UDS write
                                   needs navigation stopped and is in force after
                                   ECUReset */
    unsigned int uds_read_only : 1; /* uds_write = false: ReadDataByIdentifier only */
    unsigned int size : 8;  /* and sizeof (an enum's is the target's: 1 or 4 bytes) */
} app_param_t;

/* the parameters, in the table's order */
typedef enum {
    APP_PARAM_IMU_RATE_HZ = 0,
    APP_PARAM_NAV_RATE_HZ = 1,
    APP_PARAM_STATUS_RATE_HZ = 2,
    APP_PARAM_DYN_RATE_HZ = 3,
    APP_PARAM_LEVEL_S = 4,
    APP_PARAM_ODO_AXLE = 5,
    APP_PARAM_ODO_TRACK_M = 6,
    APP_PARAM_ODO_WHEELBASE_M = 7,
    APP_PARAM_ODO_LEVER_B_M = 8,
    APP_PARAM_ODO_LEVER_SIGMA_M = 9,
    APP_PARAM_ODO_STEP_MPS = 10,
    APP_PARAM_ODO_DIRECTION = 11,
    APP_PARAM_ODO_LATENCY_S = 12,
    APP_PARAM_CAL_MIN_BASE_M = 13,
    APP_PARAM_IMU_MOUNT_RAD = 14,
    APP_PARAM_IMU_MOUNT_SOURCE = 15,
    APP_PARAM_MOUNT_EST_SIGMA_RAD = 16,
    APP_PARAM_MOUNT_EST_EXCITE_M2PS3 = 17,
    APP_PARAM_GYRO_ARW_RAD_RTS = 18,
    APP_PARAM_GYRO_BIAS_RPS = 19,
    APP_PARAM_ACCEL_BIAS_MPS2 = 20,
    APP_PARAM_GYRO_BIAS_RW_RPS_RTS = 21,
    APP_PARAM_GYRO_BIAS_CORR_TIME_S = 22,
    APP_PARAM_ACCEL_BIAS_RW_MPS2_RTS = 23,
    APP_PARAM_ACCEL_FWD_INSTABILITY_MPS2 = 24,
    APP_PARAM_GYRO_RANGE_RPS = 25,
    APP_PARAM_ACCEL_RANGE_MPS2 = 26,
    APP_PARAM_GYRO_SCALE = 27,
    APP_PARAM_GNSS_LATENCY_S = 28,
    APP_PARAM_GNSS_CORR_S = 29,
    APP_PARAM_GNSS_VEL_CORR_S = 30,
    APP_PARAM_GNSS_WHITE_RATIO = 31,
    APP_PARAM_GNSS_ACCURACY = 32,
    APP_PARAM_GNSS_HACC_M = 33,
    APP_PARAM_GNSS_VACC_M = 34,
    APP_PARAM_GNSS_SACC_MPS = 35,
    APP_PARAM_GNSS_VEL_UP = 36,
    APP_PARAM_GNSS_INPUT = 37,
    APP_PARAM_GNSS_LEVER_B_M = 38,
    APP_PARAM_UDS_REQUEST_ID = 39,
    APP_PARAM_UDS_RESPONSE_ID = 40,
    APP_PARAM_IMU_TIME = 41,
    APP_PARAM_N = 42
} app_param_id_t;

extern const app_param_t app_params[APP_PARAM_N];

/* the names are the hosts' (the command line, its reports, the tests): tables of
 * their own, which an ECU build (APP_PARAM_NO_NAMES) leaves out, so that its flash
 * keeps neither their bytes nor a pointer per parameter and preset */
#ifndef APP_PARAM_NO_NAMES
extern const char *const app_param_names[APP_PARAM_N]; /* the app_config_t fields' */
#endif

/* IMU presets: the values (SI) of the parameters app_preset_params names, together */
#define APP_PRESET_PARAMS 10
typedef enum {
    APP_PRESET_CONSUMER = 0,
    APP_PRESET_AUTOMOTIVE = 1,
    APP_PRESET_TACTICAL = 2,
    APP_PRESET_NAVIGATION = 3,
    APP_PRESET_N = 4
} app_preset_id_t;
#define APP_PRESET_DEFAULT APP_PRESET_AUTOMOTIVE

typedef struct {
    nav_real_t value_si[APP_PRESET_PARAMS];
} app_preset_t;

extern const app_param_id_t app_preset_params[APP_PRESET_PARAMS];
extern const app_preset_t app_presets[APP_PRESET_N];
#ifndef APP_PARAM_NO_NAMES
extern const char *const app_preset_names[APP_PRESET_N];
#endif

#endif /* NAVECU_APP_PARAMS_H */
