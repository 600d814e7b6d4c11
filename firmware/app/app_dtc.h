/*
 * app_dtc.h - the application's fault memory (dtc.h): the NAV_Status health conditions as
 * DTCs, tested with each NAV_Status, served by UDS 0x19 / 0x14 (app_uds.c), their stored
 * status bytes kept in NVM.
 *
 * NVM: the record's DTC_MAX status bytes (nvstore.h) are passed to app_dtc_load by app_boot
 * at every start; a change of stored bytes is written in one record write when
 * app_nvm_write_allowed (app.h), else held in dtc_dirty until then; a failure is counted in
 * dtc_persist_failed and raises NVM_ERROR.
 */
#ifndef NAVECU_APP_DTC_H
#define NAVECU_APP_DTC_H

#include <stddef.h>
#include <stdint.h>

#include "dtc.h"
#include "hal.h"

struct app; /* app.h */

/* Boot (the start of an operation cycle): the stored status bytes read from NVM, n of
 * them (NULL or n 0: none stored, every DTC as after a clear). Refused bytes are counted
 * (dtc_t load_rejected; dtc.h says which) and raise NVM_ERROR (calib_t nvm_error). */
void app_dtc_load(struct app *a, const uint8_t *status, size_t n);

/* With each NAV_Status (output.c): the DTCs tested against its HealthFlags at the HAL
 * time now; the stored bytes that changed go to NVM (above). */
void app_dtc_cycle(struct app *a, hal_t *hal, uint32_t health_flags);

/* app_dtc_cycle of the DTCs whose HealthFlags bits are in tested only (dtc_update_tested) */
void app_dtc_cycle_tested(struct app *a, hal_t *hal, uint32_t health_flags, uint32_t tested);

/* Before an ECUReset: the stored bytes still waiting for a standstill go to NVM now (the
 * reset stops navigation anyway; without this a DTC confirmed while moving would be lost). */
void app_dtc_flush(struct app *a, hal_t *hal);

/* ClearDiagnosticInformation (UDS 0x14, all DTCs): UDS_NRC_OK, 0x22 when NVM may not be
 * written now (moving while navigating; nothing cleared), or 0x72
 * generalProgrammingFailure when a stored byte could not be written (the RAM status is
 * cleared all the same; the tester may repeat the request). */
uint8_t app_dtc_clear(struct app *a, hal_t *hal);

#endif /* NAVECU_APP_DTC_H */
