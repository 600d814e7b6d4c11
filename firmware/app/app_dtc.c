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
 * WIRED TO NVSTORE AT MERGE. The nvm branch's record keeps DTC_MAX status bytes; the
 * coordinator replaces this body with
 *     if (nvstore_put_dtc_status(hal, <the application's store>, index, status) != 0) {
 *         app_count(&a->keep.dtc_persist_failed);
 *         return -1;
 *     }
 *     return 0;
 * and calls app_dtc_load(a, <the record's DTC bytes>, DTC_MAX) in app_boot after the
 * record is read (nothing, i.e. app_dtc_load(a, NULL, 0), for a missing or refused
 * record). Until then nothing is written: the counts show it (dtc_persist_writes).
 */
static int app_dtc_persist(app_t *a, hal_t *hal, size_t index, uint8_t status)
{
    (void)hal;
    (void)index;
    (void)status;
    app_count(&a->keep.dtc_persist_writes);
    return 0;
}
