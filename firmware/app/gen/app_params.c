/* GENERATED FILE - DO NOT EDIT. Source: firmware/app/params.toml.
 * Regenerate with 'make params' (tools/gen_params.py); 'make test' fails if stale. */

#include "app_params.h"

#include "app_config.h"

const app_param_t app_params[APP_PARAM_N] = {
    [APP_PARAM_IMU_RATE_HZ] = {NAV_C(10.0), NAV_C(400.0), NAV_C(100.0), 0x0200u, offsetof(app_config_t, imu_rate_hz), APP_PARAM_U16, 0u, 0u, 1u, 0u, sizeof(((app_config_t *)0)->imu_rate_hz)},
    [APP_PARAM_NAV_RATE_HZ] = {NAV_C(1.0), NAV_C(400.0), NAV_C(50.0), 0x0201u, offsetof(app_config_t, nav_rate_hz), APP_PARAM_U16, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->nav_rate_hz)},
    [APP_PARAM_STATUS_RATE_HZ] = {NAV_C(1.0), NAV_C(400.0), NAV_C(10.0), 0x0202u, offsetof(app_config_t, status_rate_hz), APP_PARAM_U16, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->status_rate_hz)},
    [APP_PARAM_DYN_RATE_HZ] = {NAV_C(0.0), NAV_C(400.0), NAV_C(50.0), 0x0203u, offsetof(app_config_t, dyn_rate_hz), APP_PARAM_U16, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->dyn_rate_hz)},
    [APP_PARAM_LEVEL_S] = {NAV_C(1.0), NAV_C(600.0), NAV_C(30.0), 0x0204u, offsetof(app_config_t, level_s), APP_PARAM_U16, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->level_s)},
    [APP_PARAM_ODO_AXLE] = {NAV_C(0.0), NAV_C(1.0), NAV_C(0.0), 0x0210u, offsetof(app_config_t, odo_axle), APP_PARAM_ENUM, 0u, 0u, 1u, 0u, sizeof(((app_config_t *)0)->odo_axle)},
    [APP_PARAM_ODO_TRACK_M] = {NAV_C(0.5), NAV_C(3.0), NAV_C(0.0), 0x0211u, offsetof(app_config_t, odo_track_m), APP_PARAM_REAL, 1u, 1u, 1u, 0u, sizeof(((app_config_t *)0)->odo_track_m)},
    [APP_PARAM_ODO_WHEELBASE_M] = {NAV_C(1.0), NAV_C(6.0), NAV_C(0.0), 0x0212u, offsetof(app_config_t, odo_wheelbase_m), APP_PARAM_REAL, 1u, 1u, 1u, 0u, sizeof(((app_config_t *)0)->odo_wheelbase_m)},
    [APP_PARAM_ODO_LEVER_B_M] = {NAV_C(-10.0), NAV_C(10.0), NAV_C(0.0), 0x0213u, offsetof(app_config_t, odo_lever_b_m), APP_PARAM_VEC3, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->odo_lever_b_m)},
    [APP_PARAM_ODO_LEVER_SIGMA_M] = {NAV_C(0.0), NAV_C(5.0), NAV_C(1.0), 0x0214u, offsetof(app_config_t, odo_lever_sigma_m), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->odo_lever_sigma_m)},
    [APP_PARAM_ODO_STEP_MPS] = {NAV_C(0.001), NAV_C(1.0), NAV_C(0.0), 0x0216u, offsetof(app_config_t, odo_step_mps), APP_PARAM_REAL, 0u, 1u, 0u, 0u, sizeof(((app_config_t *)0)->odo_step_mps)},
    [APP_PARAM_ODO_DIRECTION] = {NAV_C(0.0), NAV_C(1.0), NAV_C(0.0), 0x0215u, offsetof(app_config_t, odo_direction), APP_PARAM_ENUM, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->odo_direction)},
    [APP_PARAM_ODO_LATENCY_S] = {NAV_C(0.0), NAV_C(0.5), NAV_C(0.0), 0x0217u, offsetof(app_config_t, odo_latency_s), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->odo_latency_s)},
    [APP_PARAM_CAL_MIN_BASE_M] = {NAV_C(0.0), NAV_C(100000.0), NAV_C(2000.0), 0x0220u, offsetof(app_config_t, cal_min_base_m), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->cal_min_base_m)},
    [APP_PARAM_IMU_MOUNT_RAD] = {NAV_C(-3.141592653589793), NAV_C(3.141592653589793), NAV_C(0.0), 0x0205u, offsetof(app_config_t, imu_mount_rad), APP_PARAM_VEC3, 0u, 0u, 1u, 0u, sizeof(((app_config_t *)0)->imu_mount_rad)},
    [APP_PARAM_IMU_MOUNT_SOURCE] = {NAV_C(0.0), NAV_C(1.0), NAV_C(0.0), 0x0206u, offsetof(app_config_t, imu_mount_source), APP_PARAM_ENUM, 0u, 0u, 1u, 0u, sizeof(((app_config_t *)0)->imu_mount_source)},
    [APP_PARAM_MOUNT_EST_SIGMA_RAD] = {NAV_C(0.00017453292519943296), NAV_C(0.17453292519943295), NAV_C(0.017453292519943295), 0x0207u, offsetof(app_config_t, mount_est_sigma_rad), APP_PARAM_REAL, 0u, 0u, 1u, 0u, sizeof(((app_config_t *)0)->mount_est_sigma_rad)},
    [APP_PARAM_MOUNT_EST_EXCITE_M2PS3] = {NAV_C(0.0), NAV_C(100000.0), NAV_C(50.0), 0x0208u, offsetof(app_config_t, mount_est_excite_m2ps3), APP_PARAM_REAL, 0u, 0u, 1u, 0u, sizeof(((app_config_t *)0)->mount_est_excite_m2ps3)},
    [APP_PARAM_GYRO_ARW_RAD_RTS] = {NAV_C(2.908882086657216e-10), NAV_C(0.02908882086657216), NAV_C(0.0005817764173314432), 0x0230u, offsetof(app_config_t, gyro_arw_rad_rts), APP_PARAM_REAL, 0u, 0u, 1u, 0u, sizeof(((app_config_t *)0)->gyro_arw_rad_rts)},
    [APP_PARAM_GYRO_BIAS_RPS] = {NAV_C(4.84813681109536e-12), NAV_C(0.0484813681109536), NAV_C(0.0009999999697132222), 0x0231u, offsetof(app_config_t, gyro_bias_rps), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gyro_bias_rps)},
    [APP_PARAM_ACCEL_BIAS_MPS2] = {NAV_C(9.80665e-07), NAV_C(9.80665), NAV_C(0.199999762095), 0x0232u, offsetof(app_config_t, accel_bias_mps2), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->accel_bias_mps2)},
    [APP_PARAM_GYRO_BIAS_RW_RPS_RTS] = {NAV_C(3.9584871301292103e-13), NAV_C(0.0039584871301292105), NAV_C(7.916974260258421e-06), 0x0233u, offsetof(app_config_t, gyro_bias_rw_rps_rts), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gyro_bias_rw_rps_rts)},
    [APP_PARAM_GYRO_BIAS_CORR_TIME_S] = {NAV_C(10.0), NAV_C(100000.0), NAV_C(100.0), 0x0238u, offsetof(app_config_t, gyro_bias_corr_time_s), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gyro_bias_corr_time_s)},
    [APP_PARAM_ACCEL_BIAS_RW_MPS2_RTS] = {NAV_C(8.007096195354886e-09), NAV_C(0.8007096195354885), NAV_C(0.0016329912193692611), 0x0234u, offsetof(app_config_t, accel_bias_rw_mps2_rts), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->accel_bias_rw_mps2_rts)},
    [APP_PARAM_ACCEL_FWD_INSTABILITY_MPS2] = {NAV_C(9.806650000000001e-08), NAV_C(9.80665), NAV_C(0.0199999762095), 0x0239u, offsetof(app_config_t, accel_fwd_instability_mps2), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->accel_fwd_instability_mps2)},
    [APP_PARAM_GYRO_RANGE_RPS] = {NAV_C(0.017453292519943295), NAV_C(87.26646259971648), NAV_C(5.235987755982989), 0x0235u, offsetof(app_config_t, gyro_range_rps), APP_PARAM_REAL, 0u, 0u, 1u, 0u, sizeof(((app_config_t *)0)->gyro_range_rps)},
    [APP_PARAM_ACCEL_RANGE_MPS2] = {NAV_C(9.80665), NAV_C(2000.0), NAV_C(78.4532), 0x0236u, offsetof(app_config_t, accel_range_mps2), APP_PARAM_REAL, 0u, 0u, 1u, 0u, sizeof(((app_config_t *)0)->accel_range_mps2)},
    [APP_PARAM_GYRO_SCALE] = {NAV_C(1e-07), NAV_C(0.09999999999999999), NAV_C(0.01), 0x0237u, offsetof(app_config_t, gyro_scale), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gyro_scale)},
    [APP_PARAM_GNSS_LATENCY_S] = {NAV_C(0.0), NAV_C(0.5), NAV_C(0.1), 0x0240u, offsetof(app_config_t, gnss_latency_s), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gnss_latency_s)},
    [APP_PARAM_GNSS_CORR_S] = {NAV_C(0.0), NAV_C(600.0), NAV_C(20.0), 0x0241u, offsetof(app_config_t, gnss_corr_s), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gnss_corr_s)},
    [APP_PARAM_GNSS_VEL_CORR_S] = {NAV_C(0.0), NAV_C(60.0), NAV_C(0.0), 0x024Au, offsetof(app_config_t, gnss_vel_corr_s), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gnss_vel_corr_s)},
    [APP_PARAM_GNSS_WHITE_RATIO] = {NAV_C(0.05), NAV_C(1.0), NAV_C(0.33), 0x0248u, offsetof(app_config_t, gnss_white_ratio), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gnss_white_ratio)},
    [APP_PARAM_GNSS_ACCURACY] = {NAV_C(0.0), NAV_C(1.0), NAV_C(0.0), 0x0243u, offsetof(app_config_t, gnss_accuracy), APP_PARAM_ENUM, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gnss_accuracy)},
    [APP_PARAM_GNSS_HACC_M] = {NAV_C(0.1), NAV_C(102.3), NAV_C(3.0), 0x0244u, offsetof(app_config_t, gnss_hacc_m), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gnss_hacc_m)},
    [APP_PARAM_GNSS_VACC_M] = {NAV_C(0.1), NAV_C(102.3), NAV_C(5.0), 0x0245u, offsetof(app_config_t, gnss_vacc_m), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gnss_vacc_m)},
    [APP_PARAM_GNSS_SACC_MPS] = {NAV_C(0.01), NAV_C(1.5), NAV_C(0.2), 0x0246u, offsetof(app_config_t, gnss_sacc_mps), APP_PARAM_REAL, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gnss_sacc_mps)},
    [APP_PARAM_GNSS_VEL_UP] = {NAV_C(0.0), NAV_C(1.0), NAV_C(0.0), 0x0247u, offsetof(app_config_t, gnss_vel_up), APP_PARAM_ENUM, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gnss_vel_up)},
    [APP_PARAM_GNSS_INPUT] = {NAV_C(0.0), NAV_C(2.0), NAV_C(2.0), 0x0249u, offsetof(app_config_t, gnss_input), APP_PARAM_ENUM, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gnss_input)},
    [APP_PARAM_GNSS_LEVER_B_M] = {NAV_C(-10.0), NAV_C(10.0), NAV_C(0.0), 0x0242u, offsetof(app_config_t, gnss_lever_b_m), APP_PARAM_VEC3, 0u, 0u, 0u, 0u, sizeof(((app_config_t *)0)->gnss_lever_b_m)},
    [APP_PARAM_UDS_REQUEST_ID] = {NAV_C(1.0), NAV_C(2047.0), NAV_C(1952.0), 0x0250u, offsetof(app_config_t, uds_request_id), APP_PARAM_U16, 0u, 0u, 1u, 1u, sizeof(((app_config_t *)0)->uds_request_id)},
    [APP_PARAM_UDS_RESPONSE_ID] = {NAV_C(1.0), NAV_C(2047.0), NAV_C(1960.0), 0x0251u, offsetof(app_config_t, uds_response_id), APP_PARAM_U16, 0u, 0u, 1u, 1u, sizeof(((app_config_t *)0)->uds_response_id)},
    [APP_PARAM_IMU_TIME] = {NAV_C(0.0), NAV_C(1.0), NAV_C(0.0), 0x0209u, offsetof(app_config_t, imu_time), APP_PARAM_ENUM, 0u, 0u, 1u, 0u, sizeof(((app_config_t *)0)->imu_time)},
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
    [APP_PARAM_ACCEL_FWD_INSTABILITY_MPS2] = "accel_fwd_instability_mps2",
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
    APP_PARAM_ACCEL_FWD_INSTABILITY_MPS2,
    APP_PARAM_GYRO_RANGE_RPS,
    APP_PARAM_ACCEL_RANGE_MPS2,
    APP_PARAM_GYRO_SCALE,
};

const app_preset_t app_presets[APP_PRESET_N] = {
    [APP_PRESET_CONSUMER] = {{NAV_C(0.00012217304763960306), NAV_C(0.0017453292519943296), NAV_C(0.392266), NAV_C(1.1875461390387631e-05), NAV_C(100.0), NAV_C(0.003202838478141954), NAV_C(0.0392266), NAV_C(34.90658503988659), NAV_C(156.9064), NAV_C(0.02)}},
    [APP_PRESET_AUTOMOTIVE] = {{NAV_C(0.0005817764173314432), NAV_C(0.0009999999697132222), NAV_C(0.199999762095), NAV_C(7.916974260258421e-06), NAV_C(100.0), NAV_C(0.0016329912193692611), NAV_C(0.0199999762095), NAV_C(5.235987755982989), NAV_C(78.4532), NAV_C(0.01)}},
    [APP_PRESET_TACTICAL] = {{NAV_C(1.454441043328608e-05), NAV_C(4.99999984856611e-06), NAV_C(0.0300000133475), NAV_C(1.9792435650646052e-07), NAV_C(100.0), NAV_C(0.000244949083260199), NAV_C(0.00300000133475), NAV_C(6.981317007977318), NAV_C(98.0665), NAV_C(0.0003)}},
    [APP_PRESET_NAVIGATION] = {{NAV_C(8.726646259971648e-07), NAV_C(7.272205216643039e-08), NAV_C(0.0010000037138), NAV_C(1.9792435650646052e-09), NAV_C(300.0), NAV_C(8.164996132327283e-06), NAV_C(0.00010000037138), NAV_C(5.235987755982989), NAV_C(78.4532), NAV_C(4.9999999999999996e-05)}},
};

#ifndef APP_PARAM_NO_NAMES
const char *const app_preset_names[APP_PRESET_N] = {
    [APP_PRESET_CONSUMER] = "consumer",
    [APP_PRESET_AUTOMOTIVE] = "automotive",
    [APP_PRESET_TACTICAL] = "tactical",
    [APP_PRESET_NAVIGATION] = "navigation",
};
#endif

/* app_param_get and app_param_set (app_config.c) read and write a field through its
 * offset and size: an enum's index is its C constant's value */
_Static_assert(sizeof(((app_config_t *)0)->imu_rate_hz) == sizeof(uint16_t), "imu_rate_hz: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->nav_rate_hz) == sizeof(uint16_t), "nav_rate_hz: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->status_rate_hz) == sizeof(uint16_t), "status_rate_hz: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->dyn_rate_hz) == sizeof(uint16_t), "dyn_rate_hz: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->level_s) == sizeof(uint16_t), "level_s: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->odo_axle) == 1u || sizeof(((app_config_t *)0)->odo_axle) == 4u, "odo_axle: 1 or 4 bytes");
_Static_assert(ODO_AXLE_REAR == 0, "odo_axle: value 0 is ODO_AXLE_REAR");
_Static_assert(ODO_AXLE_FRONT == 1, "odo_axle: value 1 is ODO_AXLE_FRONT");
_Static_assert(sizeof(((app_config_t *)0)->odo_track_m) == sizeof(nav_real_t), "odo_track_m: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->odo_wheelbase_m) == sizeof(nav_real_t), "odo_wheelbase_m: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->odo_lever_b_m) == 3u * sizeof(nav_real_t), "odo_lever_b_m: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->odo_lever_sigma_m) == sizeof(nav_real_t), "odo_lever_sigma_m: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->odo_step_mps) == sizeof(nav_real_t), "odo_step_mps: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->odo_direction) == 1u || sizeof(((app_config_t *)0)->odo_direction) == 4u, "odo_direction: 1 or 4 bytes");
_Static_assert(ODO_DIR_AS_READ == 0, "odo_direction: value 0 is ODO_DIR_AS_READ");
_Static_assert(ODO_DIR_NAVIGATOR == 1, "odo_direction: value 1 is ODO_DIR_NAVIGATOR");
_Static_assert(sizeof(((app_config_t *)0)->odo_latency_s) == sizeof(nav_real_t), "odo_latency_s: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->cal_min_base_m) == sizeof(nav_real_t), "cal_min_base_m: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->imu_mount_rad) == 3u * sizeof(nav_real_t), "imu_mount_rad: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->imu_mount_source) == 1u || sizeof(((app_config_t *)0)->imu_mount_source) == 4u, "imu_mount_source: 1 or 4 bytes");
_Static_assert(MOUNT_SOURCE_FIXED == 0, "imu_mount_source: value 0 is MOUNT_SOURCE_FIXED");
_Static_assert(MOUNT_SOURCE_AUTOMATIC == 1, "imu_mount_source: value 1 is MOUNT_SOURCE_AUTOMATIC");
_Static_assert(sizeof(((app_config_t *)0)->mount_est_sigma_rad) == sizeof(nav_real_t), "mount_est_sigma_rad: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->mount_est_excite_m2ps3) == sizeof(nav_real_t), "mount_est_excite_m2ps3: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gyro_arw_rad_rts) == sizeof(nav_real_t), "gyro_arw_rad_rts: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gyro_bias_rps) == sizeof(nav_real_t), "gyro_bias_rps: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->accel_bias_mps2) == sizeof(nav_real_t), "accel_bias_mps2: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gyro_bias_rw_rps_rts) == sizeof(nav_real_t), "gyro_bias_rw_rps_rts: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gyro_bias_corr_time_s) == sizeof(nav_real_t), "gyro_bias_corr_time_s: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->accel_bias_rw_mps2_rts) == sizeof(nav_real_t), "accel_bias_rw_mps2_rts: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->accel_fwd_instability_mps2) == sizeof(nav_real_t), "accel_fwd_instability_mps2: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gyro_range_rps) == sizeof(nav_real_t), "gyro_range_rps: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->accel_range_mps2) == sizeof(nav_real_t), "accel_range_mps2: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gyro_scale) == sizeof(nav_real_t), "gyro_scale: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gnss_latency_s) == sizeof(nav_real_t), "gnss_latency_s: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gnss_corr_s) == sizeof(nav_real_t), "gnss_corr_s: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gnss_vel_corr_s) == sizeof(nav_real_t), "gnss_vel_corr_s: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gnss_white_ratio) == sizeof(nav_real_t), "gnss_white_ratio: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gnss_accuracy) == 1u || sizeof(((app_config_t *)0)->gnss_accuracy) == 4u, "gnss_accuracy: 1 or 4 bytes");
_Static_assert(GNSS_ACC_REPORTED == 0, "gnss_accuracy: value 0 is GNSS_ACC_REPORTED");
_Static_assert(GNSS_ACC_DECLARED == 1, "gnss_accuracy: value 1 is GNSS_ACC_DECLARED");
_Static_assert(sizeof(((app_config_t *)0)->gnss_hacc_m) == sizeof(nav_real_t), "gnss_hacc_m: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gnss_vacc_m) == sizeof(nav_real_t), "gnss_vacc_m: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gnss_sacc_mps) == sizeof(nav_real_t), "gnss_sacc_mps: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->gnss_vel_up) == 1u || sizeof(((app_config_t *)0)->gnss_vel_up) == 4u, "gnss_vel_up: 1 or 4 bytes");
_Static_assert(GNSS_VUP_MEASURED == 0, "gnss_vel_up: value 0 is GNSS_VUP_MEASURED");
_Static_assert(GNSS_VUP_NONE == 1, "gnss_vel_up: value 1 is GNSS_VUP_NONE");
_Static_assert(sizeof(((app_config_t *)0)->gnss_input) == 1u || sizeof(((app_config_t *)0)->gnss_input) == 4u, "gnss_input: 1 or 4 bytes");
_Static_assert(GNSS_INPUT_FIX == 0, "gnss_input: value 0 is GNSS_INPUT_FIX");
_Static_assert(GNSS_INPUT_RAW == 1, "gnss_input: value 1 is GNSS_INPUT_RAW");
_Static_assert(GNSS_INPUT_BOTH == 2, "gnss_input: value 2 is GNSS_INPUT_BOTH");
_Static_assert(sizeof(((app_config_t *)0)->gnss_lever_b_m) == 3u * sizeof(nav_real_t), "gnss_lever_b_m: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->uds_request_id) == sizeof(uint16_t), "uds_request_id: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->uds_response_id) == sizeof(uint16_t), "uds_response_id: its type's size");
_Static_assert(sizeof(((app_config_t *)0)->imu_time) == 1u || sizeof(((app_config_t *)0)->imu_time) == 4u, "imu_time: 1 or 4 bytes");
_Static_assert(IMU_TIME_GRID == 0, "imu_time: value 0 is IMU_TIME_GRID");
_Static_assert(IMU_TIME_STAMPED == 1, "imu_time: value 1 is IMU_TIME_STAMPED");
