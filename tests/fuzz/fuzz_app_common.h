/*
 * fuzz_app_common.h - the application driven by fuzz input against the in-memory HAL
 * (tests/support/fake_hal.h), and the invariants checked after every frame. Used by
 * fuzz_app.c, fuzz_options.c and the regression tests (tests/test_fuzz_regressions.c).
 *
 * Invariants (fz_check; fuzz_fail on a violation):
 *  - app->mode is one of the app_mode_t values;
 *  - no health counter of app->health ever decreases (all of app_health_t's uint32_t);
 *  - every frame the application sent is a classic 8-byte standard frame of a NAV_*
 *    message, decodes with the generated codec to finite values inside the DBC ranges
 *    (codec_check.h, CODEC_REQUIRE_RANGE), and every output but NAV_Position carries a
 *    valid E2E CRC.
 * UBSan (float-cast-overflow) catches a NaN or huge value reaching a codec encode.
 *
 * The input is a sequence of records (fz_run_records); each is either a raw frame (any
 * bytes, under one of the application's receive IDs, an unknown or an own output ID;
 * flags may fix its E2E CRC, alive counter and DLC so that it passes validation), or a
 * macro that sends valid traffic the fuzzer could hardly build byte by byte: N IMU
 * samples, a WheelSpeeds frame, a whole GNSS epoch, or a pause. fz_prelude sends a valid
 * initialization (known position, SetInitialPosition, InitialAttitude) so that inputs
 * reach navigation quickly; the harnesses call it only when the input asks for it.
 */
#ifndef NAVECU_FUZZ_APP_COMMON_H
#define NAVECU_FUZZ_APP_COMMON_H

#include <stddef.h>
#include <stdint.h>

#include "app.h"
#include "fake_hal.h"

#define FZ_HEALTH_N (sizeof(app_health_t) / sizeof(uint32_t))
#define FZ_MAX_SAMPLES 6000u /* IMU samples per input at most (60 s at 100 Hz) */
#define FZ_MAX_RECORDS 400u  /* records per input at most */

typedef struct {
    app_t *app;
    hal_t *hal;
    uint32_t health[FZ_HEALTH_N]; /* the counters after the previous frame */
    uint8_t imu_counter, wheel_counter, cmd_counter, att_counter, gnss_epoch;
    uint8_t last_rate[8];         /* the last IMU_Rate sent: the pair CRC covers it */
    uint32_t samples;             /* IMU samples sent by macros */
    uint32_t frames;              /* frames fed */
    uint32_t tow_ms;              /* GNSS time of week of the next epoch */
    uint32_t imu_stamp_us;        /* IMU_Time of the last sample (imu_time = stamped) */
    int32_t lat_e7, lon_e7;       /* where the prelude put the vehicle */
} fz_app_t;

/* Start checking app (initialised and booted) on hal: snapshot of the counters. */
void fz_begin(fz_app_t *z, app_t *app, hal_t *hal);

/* One frame through app_handle_frame at the HAL's time, then app_poll, then fz_check. */
void fz_feed(fz_app_t *z, const hal_can_frame_t *f);

/* The invariants above; empties the fake HAL's transmit capture. */
void fz_check(fz_app_t *z);

/* A valid initialization: known position, SetInitialPosition (heading 30 deg, 100 m) and,
 * if attitude, CMD_InitialAttitude (level), so that the application navigates at once. */
void fz_prelude(fz_app_t *z, int attitude);

/* Interpret data[0..size) as records (see fuzz_app_common.c) until it or the budget ends. */
void fz_run_records(fz_app_t *z, const uint8_t *data, size_t size);

#endif
