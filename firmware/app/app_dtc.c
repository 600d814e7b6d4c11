/* app_dtc.c - the application's fault memory and its NVM seam; see app_dtc.h. */
#include "app_dtc.h"

#include "app.h"
#include "uds.h"

static int app_dtc_persist(app_t *a, hal_t *hal, size_t index, uint8_t status);

/* the stored bytes in changed (bit i: DTC i) to NVM; 0, or -1 if one write failed */
static int persist_changed(app_t *a, hal_t *hal, uint32_t changed)
{
    int r = 0;
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        if ((changed & ((uint32_t)1u << i)) != 0u &&
            app_dtc_persist(a, hal, i, dtc_stored(&a->keep.dtc, i)) != 0) {
            r = -1;
        }
    }
    return r;
}

void app_dtc_load(app_t *a, const uint8_t *status, size_t n)
{
    (void)dtc_load(&a->keep.dtc, status, n);
}

void app_dtc_cycle(app_t *a, hal_t *hal, uint32_t health_flags)
{
    const uint32_t changed = dtc_update(&a->keep.dtc, health_flags, hal_time_us(hal));
    (void)persist_changed(a, hal, changed); /* a failure is counted in persist_failed */
}

uint8_t app_dtc_clear(app_t *a, hal_t *hal)
{
    const uint32_t changed = dtc_clear_all(&a->keep.dtc);
    return persist_changed(a, hal, changed) == 0 ? UDS_NRC_OK
                                                 : UDS_NRC_GENERAL_PROGRAMMING_FAILURE;
}

/*
 * WIRED TO NVSTORE AT MERGE. The nvm branch's record (nvstore.h) keeps CALSTORE_DTC_N (16
 * = DTC_MAX) status bytes; the coordinator replaces this body with
 *     app_count(&a->keep.dtc_persist_writes);
 *     if (hal == NULL ||
 *         nvstore_put_dtc_status(hal, &a->keep.cal.store, (unsigned)index, status) != 0) {
 *         app_count(&a->keep.dtc_persist_failed);
 *         return -1;
 *     }
 *     return 0;
 * and ends app_boot (after calib_boot) with
 *     uint8_t b[CALSTORE_DTC_N];
 *     if (nvstore_dtc_status(hal, b) == 0) {
 *         app_dtc_load(a, b, sizeof b);   (0xFF, "none stored": as after a clear)
 *     }
 * (on an error every DTC stays as app_init left it: as after a clear). Until then
 * nothing is written: dtc_persist_writes counts the bytes that would have been.
 */
static int app_dtc_persist(app_t *a, hal_t *hal, size_t index, uint8_t status)
{
    (void)hal;
    (void)index;
    (void)status;
    app_count(&a->keep.dtc_persist_writes);
    return 0;
}
