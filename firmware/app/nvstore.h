/*
 * nvstore.h - the parameters in NVM: the calibration record's version 2 extension
 * (calstore.h, its slots, seq, CRC-32 and commit marker: power-loss safe) holds one entry
 * per UDS-writable parameter of the table (params.toml), and 16 DTC status bytes.
 *
 * Entry: DID (2 bytes, big-endian), length n (1 byte), value (n bytes, the DID's UDS
 * encoding: app_uds_param_encode / app_uds_param_value, so one codec serves UDS and NVM),
 * entries back to back in the table's order. On load the entries are applied over the
 * configuration: an unknown DID, a DID that is read-only, a wrong length or a value out
 * of its range is refused and counted (nvstore_status_t refused), and that parameter
 * keeps its default; a truncated last entry is refused. The rules between parameters (app_config_valid) are checked once, on the
 * whole result (a set stored valid need not be valid halfway through it); a set that
 * breaks them is refused whole: the defaults, every entry counted refused. A parameter
 * with no entry keeps its value.
 *
 * Layers (docs/configuration.md): the table's defaults, then this record, then the board's
 * own (the host's command-line options); nvstore_layer does the first two.
 *
 * No allocation, no recursion; not reentrant (calstore's buffers).
 */
#ifndef NAVECU_NVSTORE_H
#define NAVECU_NVSTORE_H

#include <stddef.h>
#include <stdint.h>

#include "app_config.h"
#include "calstore.h"
#include "hal.h"

/* where the parameters in use came from (NVM status DID 0xF1A1, byte 1) */
#define NVSTORE_SRC_DEFAULTS 0u /* no record, or a record without parameters */
#define NVSTORE_SRC_NVM 1u      /* the version 2 record's entries */
#define NVSTORE_SRC_MIGRATED 2u /* a version 1 record: its calibration kept, parameters
                                   the defaults (flagged until a StoreParameters) */
#define NVSTORE_SRC_REFUSED 3u  /* an extension of an unknown (newer) version or corrupt:
                                   refused, never read; the defaults */
#define NVSTORE_SRC_ERROR 4u    /* the NVM could not be read: the defaults */

#define NVSTORE_ENTRY_HEAD 3u   /* DID hi, DID lo, length */

typedef struct {
    uint8_t version;  /* the record loaded: 0 none, 1, 2 (CALSTORE_EXT_VERSION); the
                         unknown version's byte when refused */
    uint8_t source;   /* NVSTORE_SRC_* */
    uint8_t loaded;   /* entries applied */
    uint8_t refused;  /* entries refused (saturating at 255) */
    uint32_t seq;     /* the record's seq (0: none) */
} nvstore_status_t;

/* The entries of every UDS-writable parameter of *cfg into buf (cap bytes); their length,
 * or 0 if they do not fit. */
size_t nvstore_params_encode(const app_config_t *cfg, uint8_t *buf, size_t cap);

/* *cfg = the defaults with the entries buf[0..len) applied (the rules above);
 * st->loaded and st->refused counted on. */
void nvstore_params_decode(app_config_t *cfg, const uint8_t *buf, size_t len,
                           nvstore_status_t *st);

/* The first two layers: *cfg = app_default_config(), then the stored parameters over it.
 * *st says what was loaded. Returns calstore_load's status (CALSTORE_OK, _EMPTY,
 * _CORRUPT) or the HAL's error; the configuration is valid whatever it returns. */
int nvstore_layer(hal_t *hal, app_config_t *cfg, nvstore_status_t *st);

/* StoreParameters: *cfg's parameters with the calibration *cal (source CAL_SRC_NONE: none)
 * and the stored DTC status bytes, as the new record (calstore_save_ext). 0 or the
 * error (HAL_ENOSPC also when the entries do not fit CALSTORE_PARAMS_MAX). */
int nvstore_save(hal_t *hal, calstore_t *cs, const app_config_t *cfg, const cal_record_t *cal);

/* The calibration erased, the stored parameters and DTC bytes kept (a record with no
 * calibration); without stored parameters, calstore_erase. 0 or the error. */
int nvstore_erase_calibration(hal_t *hal, calstore_t *cs);

/* For the DTC owner (app_dtc.c): the CALSTORE_DTC_N stored DTC status bytes set to
 * status[] in one new record (calibration and parameters kept; nothing written when they
 * are already so), so a clear of every DTC is one write, not one per DTC.
 * 0, HAL_EINVAL (NULLs), or the NVM error. */
int nvstore_put_dtc_status(hal_t *hal, calstore_t *store, const uint8_t status[CALSTORE_DTC_N]);

/* At boot: the stored DTC status bytes into out[0..CALSTORE_DTC_N) (0xFF each: none
 * stored). 0 or the error of calstore_load_ext. */
int nvstore_dtc_status(hal_t *hal, uint8_t out[CALSTORE_DTC_N]);

#endif /* NAVECU_NVSTORE_H */
