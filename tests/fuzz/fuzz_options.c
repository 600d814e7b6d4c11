/*
 * fuzz_options.c - libFuzzer harness: the application's configuration.
 *
 * host_sim/main.c parses its options inline in main(), so its parsers cannot be called
 * from here (tests/fuzz/README.md says what refactor would expose them). What is fuzzed
 * is the gate every configuration passes: app_init on an arbitrary app_config_t, its
 * integers and floats taken from the input's bytes as they are (NaN, infinities, huge,
 * tiny and subnormal values included), then app_boot and a frame sequence.
 *
 * Input: imu_rate_hz, nav_rate_hz, status_rate_hz, level_s (4 x uint16, little-endian),
 * odo_axle (1 byte), 14 floats as IEEE bit patterns (cal_min_base_m, gyro_arw_rad_rts,
 * gyro_bias_rps, accel_bias_mps2, gyro_bias_rw_rps_rts, accel_bias_rw_mps2_rts,
 * gnss_latency_s, gnss_lever_b_m[3], gnss_corr_s, odo_lever_b_m[3]), a flags byte
 * (0x01: a valid initialization, navigating at once; 0x02: SetInitialPosition only),
 * then records (fuzz_app_common.c). Bytes the input does not have keep the defaults of
 * app_default_config(), so short inputs are mostly valid configurations.
 *
 * Invariants: app_init either refuses (non-zero) or accepts a configuration whose floats
 * are all finite and whose values are within the ranges app.h and navecu --help document
 * (IMU rate 10..400 Hz, output rates 1..IMU rate, levelling 1..600 s, a valid odo_axle,
 * GNSS latency 0..0.5 s, lever arms within 10 m, positive noise sigmas); after that the
 * invariants of fuzz_app_common.h hold on every frame.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "app.h"
#include "fake_hal.h"
#include "fuzz_app_common.h"
#include "fuzz_fail.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define CFG_BYTES (4u * 2u + 1u + 14u * 4u)

static hal_t hal;
static app_t app;

static uint16_t u16le(const uint8_t *p)
{
    return (uint16_t)(p[0] | (uint16_t)(p[1] << 8));
}

static nav_real_t realbits(const uint8_t *p)
{
    float f;
    memcpy(&f, p, sizeof f);
    return (nav_real_t)f;
}

static void cfg_from(app_config_t *cfg, const uint8_t in[CFG_BYTES])
{
    const uint8_t *p = in;
    cfg->imu_rate_hz = u16le(p);
    cfg->nav_rate_hz = u16le(p + 2);
    cfg->status_rate_hz = u16le(p + 4);
    cfg->level_s = u16le(p + 6);
    p += 8;
    cfg->odo_axle = (odo_axle_t)(*p++ % 4u); /* 2, 3: not an odo_axle_t */
    nav_real_t *const reals[] = {
        &cfg->cal_min_base_m,       &cfg->gyro_arw_rad_rts,  &cfg->gyro_bias_rps,
        &cfg->accel_bias_mps2,      &cfg->gyro_bias_rw_rps_rts, &cfg->accel_bias_rw_mps2_rts,
        &cfg->gnss_latency_s,       &cfg->gnss_lever_b_m[0], &cfg->gnss_lever_b_m[1],
        &cfg->gnss_lever_b_m[2],    &cfg->gnss_corr_s,       &cfg->odo_lever_b_m[0],
        &cfg->odo_lever_b_m[1],     &cfg->odo_lever_b_m[2],
    };
    for (size_t k = 0u; k < sizeof reals / sizeof reals[0]; k++) {
        *reals[k] = realbits(p + 4u * k);
    }
}

static void expect(int ok, const char *what, const app_config_t *c)
{
    if (!ok) {
        fuzz_fail("app_init accepted a configuration with %s (imu %u nav %u status %u level %u "
                  "axle %d arw %g bg %g ba %g bgrw %g barw %g lat %g corr %g base %g)",
                  what, c->imu_rate_hz, c->nav_rate_hz, c->status_rate_hz, c->level_s,
                  (int)c->odo_axle, (double)c->gyro_arw_rad_rts, (double)c->gyro_bias_rps,
                  (double)c->accel_bias_mps2, (double)c->gyro_bias_rw_rps_rts,
                  (double)c->accel_bias_rw_mps2_rts, (double)c->gnss_latency_s,
                  (double)c->gnss_corr_s, (double)c->cal_min_base_m);
    }
}

static int lever_ok(const nav_real_t l[3])
{
    return fabs((double)l[0]) <= 10.0 && fabs((double)l[1]) <= 10.0 && fabs((double)l[2]) <= 10.0;
}

/* the documented ranges (app.h; navecu --help for what app.h leaves open) */
static void check_accepted(const app_config_t *c)
{
    expect(c->imu_rate_hz >= 10u && c->imu_rate_hz <= 400u, "an IMU rate outside 10..400 Hz", c);
    expect(c->nav_rate_hz >= 1u && c->nav_rate_hz <= c->imu_rate_hz,
           "a NAV rate outside 1..IMU rate (app.h: <= imu_rate_hz)", c);
    expect(c->status_rate_hz >= 1u && c->status_rate_hz <= c->imu_rate_hz,
           "a status rate outside 1..IMU rate (app.h: <= imu_rate_hz)", c);
    expect(c->level_s >= 1u && c->level_s <= 600u, "a levelling time outside 1..600 s", c);
    expect(c->odo_axle == ODO_AXLE_REAR || c->odo_axle == ODO_AXLE_FRONT, "no odo_axle_t", c);
    const nav_real_t r[] = {c->cal_min_base_m,   c->gyro_arw_rad_rts,   c->gyro_bias_rps,
                            c->accel_bias_mps2,  c->gyro_bias_rw_rps_rts, c->accel_bias_rw_mps2_rts,
                            c->gnss_latency_s,   c->gnss_corr_s};
    for (size_t k = 0u; k < sizeof r / sizeof r[0]; k++) {
        expect(isfinite(r[k]), "a non-finite value", c);
    }
    expect(c->cal_min_base_m >= 0.0f, "a negative calibration base", c);
    expect(c->gyro_arw_rad_rts > 0.0f && c->gyro_bias_rps > 0.0f && c->accel_bias_mps2 > 0.0f &&
               c->gyro_bias_rw_rps_rts > 0.0f && c->accel_bias_rw_mps2_rts > 0.0f,
           "a noise sigma <= 0", c);
    expect(c->gnss_latency_s >= 0.0f && c->gnss_latency_s <= 0.5f, "a GNSS latency outside 0..0.5 s", c);
    expect(c->gnss_corr_s >= 0.0f, "a negative GNSS correlation time", c);
    expect(lever_ok(c->gnss_lever_b_m) && lever_ok(c->odo_lever_b_m), "a lever arm beyond 10 m", c);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    uint8_t in[CFG_BYTES + 1u];
    app_config_t cfg = app_default_config();
    /* the defaults' bytes under the input, so that short inputs are mostly valid configs */
    memset(in, 0, sizeof in);
    {
        uint8_t *p = in;
        const uint16_t u[4] = {cfg.imu_rate_hz, cfg.nav_rate_hz, cfg.status_rate_hz, cfg.level_s};
        for (int k = 0; k < 4; k++) {
            p[0] = (uint8_t)u[k];
            p[1] = (uint8_t)(u[k] >> 8);
            p += 2;
        }
        *p++ = (uint8_t)cfg.odo_axle;
        const float f[14] = {(float)cfg.cal_min_base_m,    (float)cfg.gyro_arw_rad_rts,
                             (float)cfg.gyro_bias_rps,     (float)cfg.accel_bias_mps2,
                             (float)cfg.gyro_bias_rw_rps_rts, (float)cfg.accel_bias_rw_mps2_rts,
                             (float)cfg.gnss_latency_s,    (float)cfg.gnss_lever_b_m[0],
                             (float)cfg.gnss_lever_b_m[1], (float)cfg.gnss_lever_b_m[2],
                             (float)cfg.gnss_corr_s,       (float)cfg.odo_lever_b_m[0],
                             (float)cfg.odo_lever_b_m[1],  (float)cfg.odo_lever_b_m[2]};
        memcpy(p, f, sizeof f);
    }
    memcpy(in, data, size < sizeof in ? size : sizeof in);
    cfg_from(&cfg, in);
    const uint8_t flags = in[CFG_BYTES];

    fake_hal_reset(&hal);
    if (app_init(&app, &cfg) != 0) {
        return 0;
    }
    check_accepted(&cfg);
    app_boot(&app, &hal);
    fz_app_t z;
    fz_begin(&z, &app, &hal);
    if ((flags & 0x03u) != 0u) {
        fz_prelude(&z, (flags & 0x01u) != 0u);
    }
    if (size > sizeof in) {
        fz_run_records(&z, data + sizeof in, size - sizeof in);
    }
    return 0;
}
