/* app_config.c - the default configuration and its range check; see app_config.h. */
#include "app_config.h"

#include "vehicle.h"

app_config_t app_default_config(void)
{
    app_config_t cfg;
    app_config_defaults(&cfg);
    return cfg;
}

void app_config_defaults(app_config_t *out)
{
    out->imu_rate_hz = 100u;
    out->nav_rate_hz = 50u;
    out->status_rate_hz = 10u;
    out->dyn_rate_hz = 50u;
    out->level_s = 30u; /* docs/can.md: levelling error ~ LSB / level time */
    out->odo_axle = ODO_AXLE_REAR;
    out->odo_track_m = vehicle_profile.track_m;
    out->odo_wheelbase_m = vehicle_profile.wheelbase_m;
    /* A calibration point's position error e gives errors of about e / base in dH (rad)
     * and in mu: a 3 m point 2 km away, 0.09 deg and 0.15 % (docs/odometry.md). */
    out->cal_min_base_m = NAV_C(2000.0);
    /* the mid-grade IMU of seed 000 (tools/sim/sensors.py "mid-grade"): ARW 0.003 deg/sqrt(h),
     * turn-on bias 0.015 deg/h */
    out->gyro_arw_rad_rts = NAV_C(8.73e-7);
    out->gyro_bias_rps = NAV_C(7.27e-8);
    out->accel_bias_mps2 = NAV_C(1e-3);
    /* in-run instability 0.005 deg/h and 1e-4 m/s^2 over a 300 s correlation time as random
     * walks: sigma sqrt(2 / tau) */
    out->gyro_bias_rw_rps_rts = NAV_C(2.0e-9);
    out->accel_bias_rw_mps2_rts = NAV_C(8.2e-6);
    out->gnss_latency_s = NAV_C(0.1); /* u-blox-class receivers: about 0.1 s */
    out->gnss_corr_s = NAV_C(20.0);   /* standalone code receiver: atmosphere, orbits */
    out->gnss_lever_b_m[0] = out->gnss_lever_b_m[1] = out->gnss_lever_b_m[2] = NAV_C(0.0);
    out->odo_lever_b_m[0] = out->odo_lever_b_m[1] = out->odo_lever_b_m[2] = NAV_C(0.0);
    /* an automotive MEMS IMU's range: 300 deg/s, 8 g */
    out->gyro_range_rps = NAV_C(5.235988);
    out->accel_range_mps2 = NAV_C(78.4532);
    for (int i = 0; i < (int)NAVECU_MSG_N; i++) {
        out->can_ids[i] = vehicle_profile.can_ids[i];
    }
}

static int within(nav_real_t x, nav_real_t lo_excl, nav_real_t hi_excl)
{
    return x > lo_excl && x < hi_excl; /* false for NaN */
}

static int lever_ok(const nav_real_t l[3])
{
    return nav_fabs(l[0]) <= NAV_C(10.0) && nav_fabs(l[1]) <= NAV_C(10.0) &&
           nav_fabs(l[2]) <= NAV_C(10.0);
}

/* every identifier a standard (11-bit) one, none used twice */
static int can_ids_ok(const uint32_t ids[NAVECU_MSG_N])
{
    for (int i = 0; i < (int)NAVECU_MSG_N; i++) {
        if (ids[i] > 0x7FFu) {
            return 0;
        }
        for (int j = 0; j < i; j++) {
            if (ids[j] == ids[i]) {
                return 0;
            }
        }
    }
    return 1;
}

int app_config_valid(const app_config_t *cfg)
{
    return can_ids_ok(cfg->can_ids) && cfg->imu_rate_hz >= 10u && cfg->imu_rate_hz <= 400u && cfg->nav_rate_hz != 0u &&
           cfg->status_rate_hz != 0u && cfg->nav_rate_hz <= cfg->imu_rate_hz &&
           cfg->status_rate_hz <= cfg->imu_rate_hz && cfg->dyn_rate_hz <= cfg->imu_rate_hz &&
           cfg->level_s != 0u &&
           cfg->level_s <= 600u && cfg->odo_track_m > NAV_C(0.5) && cfg->odo_track_m < NAV_C(3.0) &&
           cfg->odo_wheelbase_m > NAV_C(1.0) && cfg->odo_wheelbase_m < NAV_C(6.0) &&
           cfg->cal_min_base_m >= NAV_C(0.0) &&
           cfg->cal_min_base_m < NAV_C(1e6) && within(cfg->gyro_arw_rad_rts, NAV_C(0.0), NAV_C(1.0)) &&
           within(cfg->gyro_bias_rps, NAV_C(0.0), NAV_C(1.0)) &&
           within(cfg->accel_bias_mps2, NAV_C(0.0), NAV_C(10.0)) &&
           within(cfg->gyro_bias_rw_rps_rts, NAV_C(0.0), NAV_C(1.0)) &&
           within(cfg->accel_bias_rw_mps2_rts, NAV_C(0.0), NAV_C(10.0)) &&
           cfg->gnss_latency_s >= NAV_C(0.0) && cfg->gnss_latency_s <= NAV_C(0.5) &&
           cfg->gnss_corr_s >= NAV_C(0.0) && cfg->gnss_corr_s <= NAV_C(600.0) &&
           lever_ok(cfg->gnss_lever_b_m) && lever_ok(cfg->odo_lever_b_m) &&
           cfg->gyro_range_rps > NAV_C(0.0) && cfg->gyro_range_rps <= NAV_C(100.0) &&
           cfg->accel_range_mps2 > NAV_C(0.0) && cfg->accel_range_mps2 <= NAV_C(2000.0);
}
