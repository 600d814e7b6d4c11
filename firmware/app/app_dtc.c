/* app_dtc.c - the application's fault memory and its NVM seam; see app_dtc.h. */
#include "app_dtc.h"

#include "app.h"
#include "uds.h"

#include "calstore.h"
#include "nvstore.h"

_Static_assert(DTC_MAX == CALSTORE_DTC_N, "the NVM record holds a status byte per DTC");

/*
 * The stored bytes of the DTCs in changed (bit i: DTC i) go to NVM, all in one record
 * write, when the application may write NVM (app_nvm_write_allowed: a flash erase stalls
 * the CPU, so never while moving); until then they wait in dtc_dirty. 0, or -1 when the
 * write failed (counted in dtc_persist_failed; NAV_Status NVM_ERROR; the bytes are not
 * retried until the next change, so a failing flash is not hammered).
 */
static int persist_changed(app_t *a, hal_t *hal, uint32_t changed, int now_anyway)
{
    a->keep.dtc_dirty |= changed;
    if (a->keep.dtc_dirty == 0u || hal == NULL || (!now_anyway && !app_nvm_write_allowed(a))) {
        return 0;
    }
    uint8_t b[CALSTORE_DTC_N];
    for (size_t i = 0u; i < (size_t)CALSTORE_DTC_N; i++) {
        b[i] = i < (size_t)DTC_N ? dtc_stored(&a->keep.dtc, i) : 0xFFu;
    }
    a->keep.dtc_dirty = 0u;
    app_count(&a->keep.dtc_persist_writes);
    if (nvstore_put_dtc_status(hal, &a->keep.cal.store, b) != 0) {
        app_count(&a->keep.dtc_persist_failed);
        a->keep.cal.nvm_error = 1u;
        return -1;
    }
    return 0;
}

void app_dtc_load(app_t *a, const uint8_t *status, size_t n)
{
    if (dtc_load(&a->keep.dtc, status, n) != 0u) {
        /* an impossible stored byte (that DTC starts as after a clear, a confirmed one may
         * be lost): NAV_Status NVM_ERROR and its DTC, as a refused parameter entry; and the
         * bytes written again at the next chance (persist_changed), so a corrupt byte is
         * not refused anew at every start */
        a->keep.cal.nvm_error = 1u;
        a->keep.dtc_dirty = ((uint32_t)1u << DTC_N) - 1u;
    }
}

void app_dtc_cycle(app_t *a, hal_t *hal, uint32_t health_flags)
{
    app_dtc_cycle_tested(a, hal, health_flags, UINT32_MAX);
}

void app_dtc_cycle_tested(app_t *a, hal_t *hal, uint32_t health_flags, uint32_t tested)
{
    const uint32_t changed =
        dtc_update_tested(&a->keep.dtc, health_flags, tested, hal_time_us(hal));
    (void)persist_changed(a, hal, changed, 0); /* a failure is counted in persist_failed */
}

void app_dtc_flush(app_t *a, hal_t *hal)
{
    (void)persist_changed(a, hal, 0u, 1); /* a failure is counted in persist_failed */
}

uint8_t app_dtc_clear(app_t *a, hal_t *hal)
{
    if (!app_nvm_write_allowed(a)) {
        return UDS_NRC_CONDITIONS_NOT_CORRECT; /* the NVM write would stall navigation */
    }
    const uint32_t changed = dtc_clear_all(&a->keep.dtc);
    return persist_changed(a, hal, changed, 0) == 0 ? UDS_NRC_OK
                                                 : UDS_NRC_GENERAL_PROGRAMMING_FAILURE;
}
