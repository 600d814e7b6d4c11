/*
 * fuzz_app.c - libFuzzer harness: the application fed an arbitrary frame sequence
 * against the in-memory HAL, with the invariants of fuzz_app_common.h checked after
 * every frame (valid mode, health counters never decrease, every sent frame a NAV_*
 * output that decodes finite and in range with a valid E2E CRC; ASan and UBSan).
 *
 * Input: a flags byte, then records (fuzz_app_common.c).
 *   flags & 0x01: start with a valid initialization (navigating at once)
 *   flags & 0x02: start with SetInitialPosition only (levelling)
 *   flags & 0x04: the NVM holds a stored calibration at boot (flags & 0x08: with one
 *                 byte of it flipped, at the offset given by the flags' high nibble)
 *   flags & 0x0C == 0x08: imu_time = stamped (IMU_Time before each macro IMU sample)
 * The initialization is the input's choice, so the fuzzer keeps full control.
 */
#include <stdint.h>
#include <string.h>

#include "app.h"
#include "calstore.h"
#include "fake_hal.h"
#include "fuzz_app_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static hal_t hal;
static app_t app;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const uint8_t flags = size > 0u ? data[0] : 0u;
    fake_hal_reset(&hal);
    if ((flags & 0x04u) != 0u) {
        calstore_t cs = {0u, -1};
        const cal_record_t rec = {0.01f, 0.012f, 2500.0f, CAL_SRC_KNOWN_POSITION};
        (void)calstore_save(&hal, &cs, &rec);
        if ((flags & 0x08u) != 0u) {
            fake_hal_nvm_corrupt(&hal, (size_t)(flags >> 4) * 2u, 0x10u);
        }
    }
    app_config_t cfg = app_default_config();
    /* flags 0x08 without 0x04 (no stored calibration to corrupt): the IMU's own times */
    cfg.imu_time = (flags & 0x0Cu) == 0x08u ? IMU_TIME_STAMPED : IMU_TIME_GRID;
    if (app_init(&app, &cfg) != 0) {
        return 0;
    }
    app_boot(&app, &hal);
    fz_app_t z;
    fz_begin(&z, &app, &hal);
    if ((flags & 0x03u) != 0u) {
        fz_prelude(&z, (flags & 0x01u) != 0u);
    }
    if (size > 1u) {
        fz_run_records(&z, data + 1, size - 1u);
    }
    return 0;
}
