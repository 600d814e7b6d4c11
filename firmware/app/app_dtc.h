/*
 * app_dtc.h - the application's fault memory (dtc.h): the NAV_Status health conditions as
 * DTCs, tested with each NAV_Status, served by UDS 0x19 / 0x14 (app_uds.c), their stored
 * status bytes kept in NVM.
 *
 * NVM seam (the nvm branch's record of DTC_MAX status bytes): at boot the board's code
 * passes the record's bytes to app_dtc_load; every change of a stored byte goes to
 * app_dtc_persist (app_dtc.c: 0, or -1 on an NVM failure, counted in dtc_persist_failed).
 * Until that record exists app_dtc_persist writes nothing (a stub marked "WIRED TO NVSTORE
 * AT MERGE" in app_dtc.c) and app_init starts every DTC as after a clear: the fault memory lives in RAM
 * and is lost at ECUReset and at power-down.
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
 * (dtc_t load_rejected; dtc.h says which). */
void app_dtc_load(struct app *a, const uint8_t *status, size_t n);

/* With each NAV_Status (output.c): the DTCs tested against its HealthFlags at the HAL
 * time now; every stored byte that changed goes to app_dtc_persist. */
void app_dtc_cycle(struct app *a, hal_t *hal, uint32_t health_flags);

/* ClearDiagnosticInformation (UDS 0x14, all DTCs): UDS_NRC_OK, or 0x72
 * generalProgrammingFailure when a stored byte could not be written (the RAM status is
 * cleared all the same; the tester may repeat the request). */
uint8_t app_dtc_clear(struct app *a, hal_t *hal);

#endif /* NAVECU_APP_DTC_H */
