/* GENERATED FILE - DO NOT EDIT. Source: firmware/app/params.toml.
 * Regenerate with 'make params' (tools/gen_params.py); 'make test' fails if stale. */

#include "app_params.h"

#include "app_config.h"

const app_param_t app_params[APP_PARAM_N] = {
    [APP_PARAM_IMU_RATE_HZ] = {0x0200u, APP_PARAM_U16, 0u, 0u, 1u, 0u, NAV_C(10.0), NAV_C(400.0), NAV_C(100.0)},
    [APP_PARAM_NAV_RATE_HZ] = {0x0201u, APP_PARAM_U16, 0u, 0u, 0u, 0u, NAV_C(1.0), NAV_C(400.0), NAV_C(50.0)},
    [APP_PARAM_STATUS_RATE_HZ] = {0x0202u, APP_PARAM_U16, 0u, 0u, 0u, 0u, NAV_C(1.0), NAV_C(400.0), NAV_C(10.0)},
    [APP_PARAM_DYN_RATE_HZ] = {0x0203u, APP_PARAM_U16, 0u, 0u, 0u, 0u, NAV_C(0.0), NAV_C(400.0), NAV_C(50.0)},
    [APP_PARAM_LEVEL_S] = {0x0204u, APP_PARAM_U16, 0u, 0u, 0u, 0u, NAV_C(1.0), NAV_C(600.0), NAV_C(30.0)},
    [APP_PARAM_ODO_AXLE] = {0x0210u, APP_PARAM_ENUM, 0u, 0u, 1u, 0u, NAV_C(0.0), NAV_C(1.0), NAV_C(0.0)},
    [APP_PARAM_ODO_TRACK_M] = {0x0211u, APP_PARAM_REAL, 1u, 1u, 1u, 0u, NAV_C(0.5), NAV_C(3.0), NAV_C(0.0)},
    [APP_PARAM_ODO_WHEELBASE_M] = {0x0212u, APP_PARAM_REAL, 1u, 1u, 1u, 0u, NAV_C(1.0), NAV_C(6.0), NAV_C(0.0)},
    [APP_PARAM_ODO_LEVER_B_M] = {0x0213u, APP_PARAM_VEC3, 0u, 0u, 0u, 0u, NAV_C(-10.0), NAV_C(10.0), NAV_C(0.0)},
    [APP_PARAM_ODO_LEVER_SIGMA_M] = {0x0214u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(0.0), NAV_C(5.0), NAV_C(1.0)},
    [APP_PARAM_ODO_STEP_MPS] = {0x0216u, APP_PARAM_REAL, 0u, 1u, 0u, 0u, NAV_C(0.001), NAV_C(1.0), NAV_C(0.0)},
    [APP_PARAM_ODO_DIRECTION] = {0x0215u, APP_PARAM_ENUM, 0u, 0u, 0u, 0u, NAV_C(0.0), NAV_C(1.0), NAV_C(0.0)},
    [APP_PARAM_ODO_LATENCY_S] = {0x0217u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(0.0), NAV_C(0.5), NAV_C(0.0)},
    [APP_PARAM_CAL_MIN_BASE_M] = {0x0220u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(0.0), NAV_C(100000.0), NAV_C(2000.0)},
    [APP_PARAM_IMU_MOUNT_RAD] = {0x0205u, APP_PARAM_VEC3, 0u, 0u, 1u, 0u, NAV_C(-3.141592653589793), NAV_C(3.141592653589793), NAV_C(0.0)},
    [APP_PARAM_IMU_MOUNT_SOURCE] = {0x0206u, APP_PARAM_ENUM, 0u, 0u, 1u, 0u, NAV_C(0.0), NAV_C(1.0), NAV_C(0.0)},
    [APP_PARAM_MOUNT_EST_SIGMA_RAD] = {0x0207u, APP_PARAM_REAL, 0u, 0u, 1u, 0u, NAV_C(0.00017453292519943296), NAV_C(0.17453292519943295), NAV_C(0.017453292519943295)},
    [APP_PARAM_MOUNT_EST_EXCITE_M2PS3] = {0x0208u, APP_PARAM_REAL, 0u, 0u, 1u, 0u, NAV_C(0.0), NAV_C(100000.0), NAV_C(50.0)},
    [APP_PARAM_GYRO_ARW_RAD_RTS] = {0x0230u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(2.908882086657216e-10), NAV_C(0.02908882086657216), NAV_C(0.0005817764173314432)},
    [APP_PARAM_GYRO_BIAS_RPS] = {0x0231u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(4.84813681109536e-12), NAV_C(0.0484813681109536), NAV_C(0.0009999999697132222)},
    [APP_PARAM_ACCEL_BIAS_MPS2] = {0x0232u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(9.80665e-07), NAV_C(9.80665), NAV_C(0.199999762095)},
    [APP_PARAM_GYRO_BIAS_RW_RPS_RTS] = {0x0233u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(3.9584871301292103e-13), NAV_C(0.0039584871301292105), NAV_C(7.916974260258421e-06)},
    [APP_PARAM_GYRO_BIAS_CORR_TIME_S] = {0x0238u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(10.0), NAV_C(100000.0), NAV_C(100.0)},
    [APP_PARAM_ACCEL_BIAS_RW_MPS2_RTS] = {0x0234u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(8.007096195354886e-09), NAV_C(0.8007096195354885), NAV_C(0.0016329912193692611)},
    [APP_PARAM_GYRO_RANGE_RPS] = {0x0235u, APP_PARAM_REAL, 0u, 0u, 1u, 0u, NAV_C(0.017453292519943295), NAV_C(87.26646259971648), NAV_C(5.235987755982989)},
    [APP_PARAM_ACCEL_RANGE_MPS2] = {0x0236u, APP_PARAM_REAL, 0u, 0u, 1u, 0u, NAV_C(1.0), NAV_C(2000.0), NAV_C(78.4532)},
    [APP_PARAM_GYRO_SCALE] = {0x0237u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(1e-07), NAV_C(0.09999999999999999), NAV_C(0.01)},
    [APP_PARAM_GNSS_LATENCY_S] = {0x0240u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(0.0), NAV_C(0.5), NAV_C(0.1)},
    [APP_PARAM_GNSS_CORR_S] = {0x0241u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(0.0), NAV_C(600.0), NAV_C(20.0)},
    [APP_PARAM_GNSS_VEL_CORR_S] = {0x024Au, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(0.0), NAV_C(60.0), NAV_C(0.0)},
    [APP_PARAM_GNSS_WHITE_RATIO] = {0x0248u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(0.05), NAV_C(1.0), NAV_C(0.33)},
    [APP_PARAM_GNSS_ACCURACY] = {0x0243u, APP_PARAM_ENUM, 0u, 0u, 0u, 0u, NAV_C(0.0), NAV_C(1.0), NAV_C(0.0)},
    [APP_PARAM_GNSS_HACC_M] = {0x0244u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(0.1), NAV_C(102.3), NAV_C(3.0)},
    [APP_PARAM_GNSS_VACC_M] = {0x0245u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(0.1), NAV_C(102.3), NAV_C(5.0)},
    [APP_PARAM_GNSS_SACC_MPS] = {0x0246u, APP_PARAM_REAL, 0u, 0u, 0u, 0u, NAV_C(0.01), NAV_C(1.5), NAV_C(0.2)},
    [APP_PARAM_GNSS_VEL_UP] = {0x0247u, APP_PARAM_ENUM, 0u, 0u, 0u, 0u, NAV_C(0.0), NAV_C(1.0), NAV_C(0.0)},
    [APP_PARAM_GNSS_INPUT] = {0x0249u, APP_PARAM_ENUM, 0u, 0u, 0u, 0u, NAV_C(0.0), NAV_C(2.0), NAV_C(2.0)},
    [APP_PARAM_GNSS_LEVER_B_M] = {0x0242u, APP_PARAM_VEC3, 0u, 0u, 0u, 0u, NAV_C(-10.0), NAV_C(10.0), NAV_C(0.0)},
    [APP_PARAM_UDS_REQUEST_ID] = {0x0250u, APP_PARAM_U16, 0u, 0u, 1u, 1u, NAV_C(1.0), NAV_C(2047.0), NAV_C(1952.0)},
    [APP_PARAM_UDS_RESPONSE_ID] = {0x0251u, APP_PARAM_U16, 0u, 0u, 1u, 1u, NAV_C(1.0), NAV_C(2047.0), NAV_C(1960.0)},
    [APP_PARAM_IMU_TIME] = {0x0209u, APP_PARAM_ENUM, 0u, 0u, 1u, 0u, NAV_C(0.0), NAV_C(1.0), NAV_C(0.0)},
};

#ifndef APP_PARAM_NO_NAMES
const char *const app_param_names[APP_PARAM_N] = {
    [APP_PARAM_IMU_RATE_HZ] = "imu_rate_hz",
    [APP_PARAM_NAV_RATE_HZ] = "nav_rate_hz",
    [APP_PARAM_STATUS_RATE_HZ] = "status_rate_hz",
    [APP_PARAM_DYN_RATE_HZ] = "dyn_rate_hz",
    [APP_PARAM_LEVEL_S] = "level_s",
    [APP_PARAM_ODO_AXLE] = "odo_axle",
    [APP_PARAM_ODO_TRACK_M] = "odo_track_m",
    [APP_PARAM_ODO_WHEELBASE_M] = "odo_wheelbase_m",
    [APP_PARAM_ODO_LEVER_B_M] = "odo_lever_b_m",
    [APP_PARAM_ODO_LEVER_SIGMA_M] = "odo_lever_sigma_m",
    [APP_PARAM_ODO_STEP_MPS] = "odo_step_mps",
    [APP_PARAM_ODO_DIRECTION] = "odo_direction",
    [APP_PARAM_ODO_LATENCY_S] = "odo_latency_s",
    [APP_PARAM_CAL_MIN_BASE_M] = "cal_min_base_m",
    [APP_PARAM_IMU_MOUNT_RAD] = "imu_mount_rad",
    [APP_PARAM_IMU_MOUNT_SOURCE] = "imu_mount_source",
    [APP_PARAM_MOUNT_EST_SIGMA_RAD] = "mount_est_sigma_rad",
    [APP_PARAM_MOUNT_EST_EXCITE_M2PS3] = "mount_est_excite_m2ps3",
    [APP_PARAM_GYRO_ARW_RAD_RTS] = "gyro_arw_rad_rts",
    [APP_PARAM_GYRO_BIAS_RPS] = "gyro_bias_rps",
    [APP_PARAM_ACCEL_BIAS_MPS2] = "accel_bias_mps2",
    [APP_PARAM_GYRO_BIAS_RW_RPS_RTS] = "gyro_bias_rw_rps_rts",
    [APP_PARAM_GYRO_BIAS_CORR_TIME_S] = "gyro_bias_corr_time_s",
    [APP_PARAM_ACCEL_BIAS_RW_MPS2_RTS] = "accel_bias_rw_mps2_rts",
    [APP_PARAM_GYRO_RANGE_RPS] = "gyro_range_rps",
    [APP_PARAM_ACCEL_RANGE_MPS2] = "accel_range_mps2",
    [APP_PARAM_GYRO_SCALE] = "gyro_scale",
    [APP_PARAM_GNSS_LATENCY_S] = "gnss_latency_s",
    [APP_PARAM_GNSS_CORR_S] = "gnss_corr_s",
    [APP_PARAM_GNSS_VEL_CORR_S] = "gnss_vel_corr_s",
    [APP_PARAM_GNSS_WHITE_RATIO] = "gnss_white_ratio",
    [APP_PARAM_GNSS_ACCURACY] = "gnss_accuracy",
    [APP_PARAM_GNSS_HACC_M] = "gnss_hacc_m",
    [APP_PARAM_GNSS_VACC_M] = "gnss_vacc_m",
    [APP_PARAM_GNSS_SACC_MPS] = "gnss_sacc_mps",
    [APP_PARAM_GNSS_VEL_UP] = "gnss_vel_up",
    [APP_PARAM_GNSS_INPUT] = "gnss_input",
    [APP_PARAM_GNSS_LEVER_B_M] = "gnss_lever_b_m",
    [APP_PARAM_UDS_REQUEST_ID] = "uds_request_id",
    [APP_PARAM_UDS_RESPONSE_ID] = "uds_response_id",
    [APP_PARAM_IMU_TIME] = "imu_time",
};
#endif

const app_param_id_t app_preset_params[APP_PRESET_PARAMS] = {
    APP_PARAM_GYRO_ARW_RAD_RTS,
    APP_PARAM_GYRO_BIAS_RPS,
    APP_PARAM_ACCEL_BIAS_MPS2,
    APP_PARAM_GYRO_BIAS_RW_RPS_RTS,
    APP_PARAM_GYRO_BIAS_CORR_TIME_S,
    APP_PARAM_ACCEL_BIAS_RW_MPS2_RTS,
    APP_PARAM_GYRO_RANGE_RPS,
    APP_PARAM_ACCEL_RANGE_MPS2,
    APP_PARAM_GYRO_SCALE,
};

const app_preset_t app_presets[APP_PRESET_N] = {
    [APP_PRESET_CONSUMER] = {{NAV_C(0.00012217304763960306), NAV_C(0.0017453292519943296), NAV_C(0.392266), NAV_C(1.1875461390387631e-05), NAV_C(100.0), NAV_C(0.003202838478141954), NAV_C(34.90658503988659), NAV_C(156.9064), NAV_C(0.02)}},
    [APP_PRESET_AUTOMOTIVE] = {{NAV_C(0.0005817764173314432), NAV_C(0.0009999999697132222), NAV_C(0.199999762095), NAV_C(7.916974260258421e-06), NAV_C(100.0), NAV_C(0.0016329912193692611), NAV_C(5.235987755982989), NAV_C(78.4532), NAV_C(0.01)}},
    [APP_PRESET_TACTICAL] = {{NAV_C(1.454441043328608e-05), NAV_C(4.99999984856611e-06), NAV_C(0.0300000133475), NAV_C(1.9792435650646052e-07), NAV_C(100.0), NAV_C(0.000244949083260199), NAV_C(6.981317007977318), NAV_C(98.0665), NAV_C(0.0003)}},
    [APP_PRESET_NAVIGATION] = {{NAV_C(8.726646259971648e-07), NAV_C(7.272205216643039e-08), NAV_C(0.0010000037138), NAV_C(1.9792435650646052e-09), NAV_C(300.0), NAV_C(8.164996132327283e-06), NAV_C(5.235987755982989), NAV_C(78.4532), NAV_C(4.9999999999999996e-05)}},
};

#ifndef APP_PARAM_NO_NAMES
const char *const app_preset_names[APP_PRESET_N] = {
    [APP_PRESET_CONSUMER] = "consumer",
    [APP_PRESET_AUTOMOTIVE] = "automotive",
    [APP_PRESET_TACTICAL] = "tactical",
    [APP_PRESET_NAVIGATION] = "navigation",
};
#endif

void app_param_get(const app_config_t *cfg, app_param_id_t id, nav_real_t v[3])
{
    v[0] = NAV_C(0.0);
    v[1] = NAV_C(0.0);
    v[2] = NAV_C(0.0);
    switch (id) {
    case APP_PARAM_IMU_RATE_HZ:
        v[0] = (nav_real_t)cfg->imu_rate_hz;
        break;
    case APP_PARAM_NAV_RATE_HZ:
        v[0] = (nav_real_t)cfg->nav_rate_hz;
        break;
    case APP_PARAM_STATUS_RATE_HZ:
        v[0] = (nav_real_t)cfg->status_rate_hz;
        break;
    case APP_PARAM_DYN_RATE_HZ:
        v[0] = (nav_real_t)cfg->dyn_rate_hz;
        break;
    case APP_PARAM_LEVEL_S:
        v[0] = (nav_real_t)cfg->level_s;
        break;
    case APP_PARAM_ODO_AXLE:
        if (cfg->odo_axle == ODO_AXLE_REAR) {
            v[0] = NAV_C(0.0);
        }
        if (cfg->odo_axle == ODO_AXLE_FRONT) {
            v[0] = NAV_C(1.0);
        }
        break;
    case APP_PARAM_ODO_TRACK_M:
        v[0] = cfg->odo_track_m;
        break;
    case APP_PARAM_ODO_WHEELBASE_M:
        v[0] = cfg->odo_wheelbase_m;
        break;
    case APP_PARAM_ODO_LEVER_B_M:
        v[0] = cfg->odo_lever_b_m[0];
        v[1] = cfg->odo_lever_b_m[1];
        v[2] = cfg->odo_lever_b_m[2];
        break;
    case APP_PARAM_ODO_LEVER_SIGMA_M:
        v[0] = cfg->odo_lever_sigma_m;
        break;
    case APP_PARAM_ODO_STEP_MPS:
        v[0] = cfg->odo_step_mps;
        break;
    case APP_PARAM_ODO_DIRECTION:
        if (cfg->odo_direction == ODO_DIR_AS_READ) {
            v[0] = NAV_C(0.0);
        }
        if (cfg->odo_direction == ODO_DIR_NAVIGATOR) {
            v[0] = NAV_C(1.0);
        }
        break;
    case APP_PARAM_ODO_LATENCY_S:
        v[0] = cfg->odo_latency_s;
        break;
    case APP_PARAM_CAL_MIN_BASE_M:
        v[0] = cfg->cal_min_base_m;
        break;
    case APP_PARAM_IMU_MOUNT_RAD:
        v[0] = cfg->imu_mount_rad[0];
        v[1] = cfg->imu_mount_rad[1];
        v[2] = cfg->imu_mount_rad[2];
        break;
    case APP_PARAM_IMU_MOUNT_SOURCE:
        if (cfg->imu_mount_source == MOUNT_SOURCE_FIXED) {
            v[0] = NAV_C(0.0);
        }
        if (cfg->imu_mount_source == MOUNT_SOURCE_AUTOMATIC) {
            v[0] = NAV_C(1.0);
        }
        break;
    case APP_PARAM_MOUNT_EST_SIGMA_RAD:
        v[0] = cfg->mount_est_sigma_rad;
        break;
    case APP_PARAM_MOUNT_EST_EXCITE_M2PS3:
        v[0] = cfg->mount_est_excite_m2ps3;
        break;
    case APP_PARAM_GYRO_ARW_RAD_RTS:
        v[0] = cfg->gyro_arw_rad_rts;
        break;
    case APP_PARAM_GYRO_BIAS_RPS:
        v[0] = cfg->gyro_bias_rps;
        break;
    case APP_PARAM_ACCEL_BIAS_MPS2:
        v[0] = cfg->accel_bias_mps2;
        break;
    case APP_PARAM_GYRO_BIAS_RW_RPS_RTS:
        v[0] = cfg->gyro_bias_rw_rps_rts;
        break;
    case APP_PARAM_GYRO_BIAS_CORR_TIME_S:
        v[0] = cfg->gyro_bias_corr_time_s;
        break;
    case APP_PARAM_ACCEL_BIAS_RW_MPS2_RTS:
        v[0] = cfg->accel_bias_rw_mps2_rts;
        break;
    case APP_PARAM_GYRO_RANGE_RPS:
        v[0] = cfg->gyro_range_rps;
        break;
    case APP_PARAM_ACCEL_RANGE_MPS2:
        v[0] = cfg->accel_range_mps2;
        break;
    case APP_PARAM_GYRO_SCALE:
        v[0] = cfg->gyro_scale;
        break;
    case APP_PARAM_GNSS_LATENCY_S:
        v[0] = cfg->gnss_latency_s;
        break;
    case APP_PARAM_GNSS_CORR_S:
        v[0] = cfg->gnss_corr_s;
        break;
    case APP_PARAM_GNSS_VEL_CORR_S:
        v[0] = cfg->gnss_vel_corr_s;
        break;
    case APP_PARAM_GNSS_WHITE_RATIO:
        v[0] = cfg->gnss_white_ratio;
        break;
    case APP_PARAM_GNSS_ACCURACY:
        if (cfg->gnss_accuracy == GNSS_ACC_REPORTED) {
            v[0] = NAV_C(0.0);
        }
        if (cfg->gnss_accuracy == GNSS_ACC_DECLARED) {
            v[0] = NAV_C(1.0);
        }
        break;
    case APP_PARAM_GNSS_HACC_M:
        v[0] = cfg->gnss_hacc_m;
        break;
    case APP_PARAM_GNSS_VACC_M:
        v[0] = cfg->gnss_vacc_m;
        break;
    case APP_PARAM_GNSS_SACC_MPS:
        v[0] = cfg->gnss_sacc_mps;
        break;
    case APP_PARAM_GNSS_VEL_UP:
        if (cfg->gnss_vel_up == GNSS_VUP_MEASURED) {
            v[0] = NAV_C(0.0);
        }
        if (cfg->gnss_vel_up == GNSS_VUP_NONE) {
            v[0] = NAV_C(1.0);
        }
        break;
    case APP_PARAM_GNSS_INPUT:
        if (cfg->gnss_input == GNSS_INPUT_FIX) {
            v[0] = NAV_C(0.0);
        }
        if (cfg->gnss_input == GNSS_INPUT_RAW) {
            v[0] = NAV_C(1.0);
        }
        if (cfg->gnss_input == GNSS_INPUT_BOTH) {
            v[0] = NAV_C(2.0);
        }
        break;
    case APP_PARAM_GNSS_LEVER_B_M:
        v[0] = cfg->gnss_lever_b_m[0];
        v[1] = cfg->gnss_lever_b_m[1];
        v[2] = cfg->gnss_lever_b_m[2];
        break;
    case APP_PARAM_UDS_REQUEST_ID:
        v[0] = (nav_real_t)cfg->uds_request_id;
        break;
    case APP_PARAM_UDS_RESPONSE_ID:
        v[0] = (nav_real_t)cfg->uds_response_id;
        break;
    case APP_PARAM_IMU_TIME:
        if (cfg->imu_time == IMU_TIME_GRID) {
            v[0] = NAV_C(0.0);
        }
        if (cfg->imu_time == IMU_TIME_STAMPED) {
            v[0] = NAV_C(1.0);
        }
        break;
    default:
        break;
    }
}

int app_param_set(app_config_t *cfg, app_param_id_t id, const nav_real_t v[3])
{
    if (!app_param_in_range(id, v)) {
        return -1;
    }
    switch (id) {
    case APP_PARAM_IMU_RATE_HZ:
        cfg->imu_rate_hz = (uint16_t)v[0];
        break;
    case APP_PARAM_NAV_RATE_HZ:
        cfg->nav_rate_hz = (uint16_t)v[0];
        break;
    case APP_PARAM_STATUS_RATE_HZ:
        cfg->status_rate_hz = (uint16_t)v[0];
        break;
    case APP_PARAM_DYN_RATE_HZ:
        cfg->dyn_rate_hz = (uint16_t)v[0];
        break;
    case APP_PARAM_LEVEL_S:
        cfg->level_s = (uint16_t)v[0];
        break;
    case APP_PARAM_ODO_AXLE:
        cfg->odo_axle = ODO_AXLE_REAR;
        if (v[0] > NAV_C(0.5)) {
            cfg->odo_axle = ODO_AXLE_FRONT;
        }
        break;
    case APP_PARAM_ODO_TRACK_M:
        cfg->odo_track_m = v[0];
        break;
    case APP_PARAM_ODO_WHEELBASE_M:
        cfg->odo_wheelbase_m = v[0];
        break;
    case APP_PARAM_ODO_LEVER_B_M:
        cfg->odo_lever_b_m[0] = v[0];
        cfg->odo_lever_b_m[1] = v[1];
        cfg->odo_lever_b_m[2] = v[2];
        break;
    case APP_PARAM_ODO_LEVER_SIGMA_M:
        cfg->odo_lever_sigma_m = v[0];
        break;
    case APP_PARAM_ODO_STEP_MPS:
        cfg->odo_step_mps = v[0];
        break;
    case APP_PARAM_ODO_DIRECTION:
        cfg->odo_direction = ODO_DIR_AS_READ;
        if (v[0] > NAV_C(0.5)) {
            cfg->odo_direction = ODO_DIR_NAVIGATOR;
        }
        break;
    case APP_PARAM_ODO_LATENCY_S:
        cfg->odo_latency_s = v[0];
        break;
    case APP_PARAM_CAL_MIN_BASE_M:
        cfg->cal_min_base_m = v[0];
        break;
    case APP_PARAM_IMU_MOUNT_RAD:
        cfg->imu_mount_rad[0] = v[0];
        cfg->imu_mount_rad[1] = v[1];
        cfg->imu_mount_rad[2] = v[2];
        break;
    case APP_PARAM_IMU_MOUNT_SOURCE:
        cfg->imu_mount_source = MOUNT_SOURCE_FIXED;
        if (v[0] > NAV_C(0.5)) {
            cfg->imu_mount_source = MOUNT_SOURCE_AUTOMATIC;
        }
        break;
    case APP_PARAM_MOUNT_EST_SIGMA_RAD:
        cfg->mount_est_sigma_rad = v[0];
        break;
    case APP_PARAM_MOUNT_EST_EXCITE_M2PS3:
        cfg->mount_est_excite_m2ps3 = v[0];
        break;
    case APP_PARAM_GYRO_ARW_RAD_RTS:
        cfg->gyro_arw_rad_rts = v[0];
        break;
    case APP_PARAM_GYRO_BIAS_RPS:
        cfg->gyro_bias_rps = v[0];
        break;
    case APP_PARAM_ACCEL_BIAS_MPS2:
        cfg->accel_bias_mps2 = v[0];
        break;
    case APP_PARAM_GYRO_BIAS_RW_RPS_RTS:
        cfg->gyro_bias_rw_rps_rts = v[0];
        break;
    case APP_PARAM_GYRO_BIAS_CORR_TIME_S:
        cfg->gyro_bias_corr_time_s = v[0];
        break;
    case APP_PARAM_ACCEL_BIAS_RW_MPS2_RTS:
        cfg->accel_bias_rw_mps2_rts = v[0];
        break;
    case APP_PARAM_GYRO_RANGE_RPS:
        cfg->gyro_range_rps = v[0];
        break;
    case APP_PARAM_ACCEL_RANGE_MPS2:
        cfg->accel_range_mps2 = v[0];
        break;
    case APP_PARAM_GYRO_SCALE:
        cfg->gyro_scale = v[0];
        break;
    case APP_PARAM_GNSS_LATENCY_S:
        cfg->gnss_latency_s = v[0];
        break;
    case APP_PARAM_GNSS_CORR_S:
        cfg->gnss_corr_s = v[0];
        break;
    case APP_PARAM_GNSS_VEL_CORR_S:
        cfg->gnss_vel_corr_s = v[0];
        break;
    case APP_PARAM_GNSS_WHITE_RATIO:
        cfg->gnss_white_ratio = v[0];
        break;
    case APP_PARAM_GNSS_ACCURACY:
        cfg->gnss_accuracy = GNSS_ACC_REPORTED;
        if (v[0] > NAV_C(0.5)) {
            cfg->gnss_accuracy = GNSS_ACC_DECLARED;
        }
        break;
    case APP_PARAM_GNSS_HACC_M:
        cfg->gnss_hacc_m = v[0];
        break;
    case APP_PARAM_GNSS_VACC_M:
        cfg->gnss_vacc_m = v[0];
        break;
    case APP_PARAM_GNSS_SACC_MPS:
        cfg->gnss_sacc_mps = v[0];
        break;
    case APP_PARAM_GNSS_VEL_UP:
        cfg->gnss_vel_up = GNSS_VUP_MEASURED;
        if (v[0] > NAV_C(0.5)) {
            cfg->gnss_vel_up = GNSS_VUP_NONE;
        }
        break;
    case APP_PARAM_GNSS_INPUT:
        cfg->gnss_input = GNSS_INPUT_FIX;
        if (v[0] > NAV_C(0.5)) {
            cfg->gnss_input = GNSS_INPUT_RAW;
        }
        if (v[0] > NAV_C(1.5)) {
            cfg->gnss_input = GNSS_INPUT_BOTH;
        }
        break;
    case APP_PARAM_GNSS_LEVER_B_M:
        cfg->gnss_lever_b_m[0] = v[0];
        cfg->gnss_lever_b_m[1] = v[1];
        cfg->gnss_lever_b_m[2] = v[2];
        break;
    case APP_PARAM_UDS_REQUEST_ID:
        cfg->uds_request_id = (uint16_t)v[0];
        break;
    case APP_PARAM_UDS_RESPONSE_ID:
        cfg->uds_response_id = (uint16_t)v[0];
        break;
    case APP_PARAM_IMU_TIME:
        cfg->imu_time = IMU_TIME_GRID;
        if (v[0] > NAV_C(0.5)) {
            cfg->imu_time = IMU_TIME_STAMPED;
        }
        break;
    default:
        return -1;
    }
    return 0;
}
