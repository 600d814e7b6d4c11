/* nvstore.c - the parameters in the NVM record (layout and rules in nvstore.h). */
#include "nvstore.h"

#include <string.h>

#include "app_tuning.h"
#include "app_uds.h"

/* the record being read or written: calstore's one extension buffer (calstore.h), off the
 * stack (not reentrant, as calstore) */
static calstore_ext_t *const ext = &calstore_ext_buf;

size_t nvstore_params_encode(const app_config_t *cfg, uint8_t *buf, size_t cap)
{
    size_t n = 0u;
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        const app_param_t *p = &app_params[k];
        if (p->uds_read_only) {
            continue;
        }
        if (cap - n < NVSTORE_ENTRY_HEAD) {
            return 0u;
        }
        const size_t len =
            app_uds_param_encode(cfg, (app_param_id_t)k, &buf[n + NVSTORE_ENTRY_HEAD],
                                 cap - n - NVSTORE_ENTRY_HEAD);
        if (len > cap - n - NVSTORE_ENTRY_HEAD) {
            return 0u;
        }
        buf[n] = (uint8_t)(p->did >> 8);
        buf[n + 1u] = (uint8_t)p->did;
        buf[n + 2u] = (uint8_t)len;
        n += NVSTORE_ENTRY_HEAD + len;
    }
    return n;
}

/* out of line (noinline): inlined at both its calls it took 8 bytes more (the base image) */
__attribute__((noinline)) static void count_refused(nvstore_status_t *st)
{
    if (st->refused < UINT8_MAX) {
        st->refused++;
    }
}

/* A record of a firmware before the forward accelerometer's own instability (DID 0x0239,
 * ekf.h state 25) holds the accelerometers' one figure (0x0234, stored as B sqrt(2 / 300 s)):
 * the forward axis takes that B, not the default preset's, within its parameter's range. */
static void fwd_instability_from_rw(app_config_t *cfg)
{
    const app_param_t *p = &app_params[APP_PARAM_ACCEL_FWD_INSTABILITY_MPS2];
    const nav_real_t b = cfg->accel_bias_rw_mps2_rts * APP_INSTABILITY_PER_RW;
    cfg->accel_fwd_instability_mps2 = b < p->min_si ? p->min_si : (b > p->max_si ? p->max_si : b);
}

void nvstore_params_decode(app_config_t *cfg, const uint8_t *buf, size_t len,
                           nvstore_status_t *st)
{
    *cfg = app_default_config();
    int rw_loaded = 0, fwd_loaded = 0;
    size_t k = 0u;
    while (k < len) {
        if (len - k < NVSTORE_ENTRY_HEAD ||
            len - k - NVSTORE_ENTRY_HEAD < (size_t)buf[k + 2u]) {
            count_refused(st); /* a truncated last entry */
            break;
        }
        const uint16_t did = (uint16_t)(((uint16_t)buf[k] << 8) | buf[k + 1u]);
        const size_t n = buf[k + 2u];
        const app_param_id_t id = app_uds_param_of_did(did);
        if (id == APP_PARAM_N || app_params[id].uds_read_only ||
            app_uds_param_value(cfg, id, &buf[k + NVSTORE_ENTRY_HEAD], n) != UDS_NRC_OK) {
            count_refused(st);
        } else {
            if (id == APP_PARAM_ACCEL_BIAS_RW_MPS2_RTS) {
                rw_loaded = 1;
            } else if (id == APP_PARAM_ACCEL_FWD_INSTABILITY_MPS2) {
                fwd_loaded = 1;
            } else {
                /* no other entry matters beyond its own value */
            }
            if (st->loaded < UINT8_MAX) {
                st->loaded++;
            }
        }
        k += NVSTORE_ENTRY_HEAD + n;
    }
    if (rw_loaded && !fwd_loaded) {
        fwd_instability_from_rw(cfg);
    }
    /* A set stored valid is valid as a whole, not after each of its entries (with the IMU
     * at 20 Hz and the outputs at 10 Hz, the IMU rate's entry comes first and breaks "an
     * output rate at most the IMU rate" against the default 50 Hz): the rules between
     * parameters are checked once, on the whole. A set that breaks them (a record of a
     * firmware with other rules) is refused whole: the defaults, its entries counted. */
    if (!app_config_valid(cfg)) {
        *cfg = app_default_config();
        const unsigned refused = (unsigned)st->refused + st->loaded;
        st->refused = (uint8_t)(refused < UINT8_MAX ? refused : UINT8_MAX);
        st->loaded = 0u;
    }
}

int nvstore_layer(hal_t *hal, app_config_t *cfg, nvstore_status_t *st)
{
    calstore_t cs;
    cal_record_t rec;
    *cfg = app_default_config();
    memset(st, 0, sizeof *st);
    const int rc = calstore_load_ext(hal, &cs, &rec, ext);
    st->seq = cs.seq;
    if (rc < 0) {
        st->source = (uint8_t)NVSTORE_SRC_ERROR;
        return rc;
    }
    if (ext->status == (uint8_t)CALSTORE_EXT_NEWER ||
        ext->status == (uint8_t)CALSTORE_EXT_CORRUPT) {
        st->version = ext->version;
        st->source = (uint8_t)NVSTORE_SRC_REFUSED;
    } else if (rc != (int)CALSTORE_OK) {
        st->source = (uint8_t)NVSTORE_SRC_DEFAULTS;
    } else if (ext->status == (uint8_t)CALSTORE_EXT_NONE) {
        st->version = (uint8_t)CALSTORE_VERSION;
        st->source = (uint8_t)NVSTORE_SRC_MIGRATED;
    } else {
        st->version = (uint8_t)CALSTORE_EXT_VERSION;
        st->source = (uint8_t)NVSTORE_SRC_NVM;
        nvstore_params_decode(cfg, ext->params, ext->params_len, st); /* over the defaults */
    }
    return rc;
}

/* the newest record's DTC bytes into ext->dtc (0xFF: none) */
static void load_dtc(hal_t *hal)
{
    calstore_t cs;
    cal_record_t rec;
    (void)calstore_load_ext(hal, &cs, &rec, ext);
    if (ext->status != (uint8_t)CALSTORE_EXT_OK) {
        memset(ext->dtc, 0xFF, sizeof ext->dtc);
    }
}

int nvstore_save(hal_t *hal, calstore_t *cs, const app_config_t *cfg, const cal_record_t *cal)
{
    if (hal == NULL || cs == NULL || cfg == NULL || cal == NULL) {
        return HAL_EINVAL;
    }
    load_dtc(hal);
    const size_t n = nvstore_params_encode(cfg, ext->params, sizeof ext->params);
    if (n == 0u) {
        return HAL_ENOSPC;
    }
    ext->params_len = (uint16_t)n;
    return calstore_save_ext(hal, cs, cal, ext);
}

int nvstore_erase_calibration(hal_t *hal, calstore_t *cs)
{
    if (hal == NULL || cs == NULL) {
        return HAL_EINVAL;
    }
    cal_record_t rec;
    calstore_t now;
    const int rc = calstore_load_ext(hal, &now, &rec, ext);
    if (rc == (int)CALSTORE_OK && ext->status == (uint8_t)CALSTORE_EXT_OK) {
        const cal_record_t none = {0.0f, 0.0f, 0.0f, (uint8_t)CAL_SRC_NONE};
        return calstore_save_ext(hal, cs, &none, ext);
    }
    return calstore_erase(hal, cs);
}

int nvstore_put_dtc_status(hal_t *hal, calstore_t *store, const uint8_t status[CALSTORE_DTC_N])
{
    if (hal == NULL || store == NULL || status == NULL) {
        return HAL_EINVAL;
    }
    cal_record_t rec;
    calstore_t now;
    const int rc = calstore_load_ext(hal, &now, &rec, ext);
    if (rc < 0) {
        return rc;
    }
    /* no record, or no usable extension: calstore_load_ext gave the defaults (no
     * calibration) and an extension with no parameters and DTC bytes 0xFF (calstore.h),
     * the record to write */
    if (ext->status == (uint8_t)CALSTORE_EXT_OK && memcmp(ext->dtc, status, CALSTORE_DTC_N) == 0) {
        return 0;
    }
    memcpy(ext->dtc, status, CALSTORE_DTC_N);
    return calstore_save_ext(hal, store, &rec, ext);
}

int nvstore_dtc_status(hal_t *hal, uint8_t out[CALSTORE_DTC_N])
{
    cal_record_t rec;
    calstore_t cs;
    const int rc = calstore_load_ext(hal, &cs, &rec, ext);
    memcpy(out, ext->dtc, CALSTORE_DTC_N);
    return rc < 0 ? rc : 0;
}
