/*
 * fuzz_nvstore.c - libFuzzer harness: the parameters in NVM (nvstore.h) on arbitrary flash
 * contents, against the in-memory HAL of tests/support/fake_hal.h (NOR-flash rules, power
 * cuts). Arbitrary extensions and parameter entries reach nvstore_params_decode through a
 * valid record (flags & 0x20: the input's entry bytes saved as a record first).
 *
 * Input: flags(1) cut_units(2, LE) torn(1) level(1) dtc_index(1) dtc_status(1) n_entry(1),
 * then n_entry bytes of parameter entries, then the NVM image (missing bytes read 0xFF).
 *   flags & 0x01: save the loaded parameters with level_s changed (StoreParameters)
 *   flags & 0x02: cut the power during that save     flags & 0x04: program backwards
 *   flags & 0x08: set a DTC status byte               flags & 0x10: erase the calibration
 *   flags & 0x20: the entry bytes stored first (a record with no calibration)
 *
 * Invariants (abort on violation):
 *  - nvstore_layer always leaves a configuration app_config_valid accepts; its counts fit
 *    the entries; a refused or absent extension leaves every parameter at its default;
 *  - a save followed by a load gives the saved parameters, every entry applied, none
 *    refused, source NVM;
 *  - a power cut anywhere in the save loads the parameters loaded before it or the new
 *    ones, nothing else;
 *  - a DTC status byte set reads back, the parameters unchanged; an erase of the
 *    calibration keeps the parameters.
 */
#include <stdint.h>
#include <string.h>

#include "app_config.h"
#include "calstore.h"
#include "fake_hal.h"
#include "fuzz_fail.h"
#include "nvstore.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define HDR 8u

static hal_t hal;
static calstore_ext_t ext;

typedef struct {
    size_t n;
    uint8_t b[CALSTORE_PARAMS_MAX];
} params_t;

static params_t encoded(const app_config_t *c)
{
    params_t p;
    p.n = nvstore_params_encode(c, p.b, sizeof p.b);
    if (p.n == 0u) {
        fuzz_fail("nvstore_params_encode: the parameters do not fit the record");
    }
    return p;
}

static int same(const params_t *a, const params_t *b)
{
    return a->n == b->n && memcmp(a->b, b->b, a->n) == 0;
}

static params_t layer_checked(const char *when, nvstore_status_t *st)
{
    app_config_t cfg;
    memset(&cfg, 0xA5, sizeof cfg);
    (void)nvstore_layer(&hal, &cfg, st);
    if (!app_config_valid(&cfg)) {
        fuzz_fail("nvstore_layer %s: a configuration app_config_valid refuses", when);
    }
    const app_config_t d = app_default_config();
    const params_t p = encoded(&cfg), pd = encoded(&d);
    if (st->source != NVSTORE_SRC_NVM && (!same(&p, &pd) || st->loaded != 0u)) {
        fuzz_fail("nvstore_layer %s: source %u but not the defaults", when, st->source);
    }
    return p;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    uint8_t hdr[HDR];
    memset(hdr, 0, sizeof hdr);
    memcpy(hdr, data, size < HDR ? size : HDR);
    fake_hal_reset(&hal);
    size_t pos = size < HDR ? size : HDR;
    const size_t n_entry = size - pos < hdr[7] ? size - pos : hdr[7];
    const uint8_t *entries = data + pos;
    pos += n_entry;
    if (size > pos) {
        const size_t n = size - pos < FAKE_NVM_SIZE ? size - pos : FAKE_NVM_SIZE;
        memcpy(hal.nvm, data + pos, n);
    }
    const uint8_t flags = hdr[0];
    const uint32_t cut_units = (uint32_t)hdr[1] | (uint32_t)hdr[2] << 8;
    calstore_t cs = {0u, -1};

    if ((flags & 0x20u) != 0u) {
        memset(&ext, 0, sizeof ext);
        memset(ext.dtc, 0xFF, sizeof ext.dtc);
        memcpy(ext.params, entries, n_entry);
        ext.params_len = (uint16_t)n_entry;
        const cal_record_t none = {0.0f, 0.0f, 0.0f, (uint8_t)CAL_SRC_NONE};
        if (calstore_save_ext(&hal, &cs, &none, &ext) != 0) {
            fuzz_fail("calstore_save_ext of %zu entry bytes on a working flash failed", n_entry);
        }
    }
    nvstore_status_t st;
    const params_t before = layer_checked("of the input", &st);
    if (st.source == NVSTORE_SRC_NVM && (flags & 0x20u) != 0u &&
        (size_t)st.loaded * NVSTORE_ENTRY_HEAD + st.refused > n_entry + 1u) {
        fuzz_fail("nvstore_layer: %u loaded + %u refused from %zu bytes", st.loaded, st.refused,
                  n_entry);
    }
    app_config_t next = app_default_config();
    (void)nvstore_layer(&hal, &next, &st);
    next.level_s = (uint16_t)(1u + hdr[4] % 600u);
    const params_t want = encoded(&next);
    hal.nvm_program_backwards = (flags & 0x04u) != 0u;
    const cal_record_t cal = {0.0f, 0.0f, 0.0f, (uint8_t)CAL_SRC_NONE};

    if ((flags & 0x03u) == 0x03u) {
        fake_hal_nvm_cut_after(&hal, cut_units % 512u, hdr[3]);
        (void)nvstore_save(&hal, &cs, &next, &cal);
        fake_hal_nvm_power_on(&hal);
        const params_t after = layer_checked("after a cut save", &st);
        if (!same(&after, &before) && !same(&after, &want)) {
            fuzz_fail("power cut after %u units: neither the previous parameters nor the new",
                      cut_units % 512u);
        }
    } else if ((flags & 0x01u) != 0u) {
        if (nvstore_save(&hal, &cs, &next, &cal) != 0) {
            fuzz_fail("nvstore_save on a working flash failed");
        }
        const params_t after = layer_checked("after a save", &st);
        if (!same(&after, &want) || st.source != NVSTORE_SRC_NVM || st.refused != 0u) {
            fuzz_fail("after nvstore_save: not the saved parameters (source %u, %u refused)",
                      st.source, st.refused);
        }
    }
    fake_hal_nvm_power_on(&hal);
    hal.nvm_program_backwards = 0;
    nvstore_status_t st0;
    const params_t now = layer_checked("before the DTC/erase steps", &st0);
    if ((flags & 0x08u) != 0u) {
        const unsigned index = hdr[5] % CALSTORE_DTC_N;
        uint8_t put[CALSTORE_DTC_N];
        uint8_t dtc[CALSTORE_DTC_N];
        if (nvstore_dtc_status(&hal, put) != 0) {
            memset(put, 0xFF, sizeof put);
        }
        put[index] = hdr[6];
        const int rc = nvstore_put_dtc_status(&hal, &cs, put);
        if (rc != 0 || nvstore_dtc_status(&hal, dtc) != 0 || memcmp(dtc, put, sizeof put) != 0) {
            fuzz_fail("nvstore_put_dtc_status(%u, 0x%02X) did not read back", index, hdr[6]);
        } else {
            const params_t p = layer_checked("after a DTC write", &st);
            if (st0.source == NVSTORE_SRC_NVM && !same(&p, &now)) {
                fuzz_fail("a DTC write changed the parameters");
            }
        }
    }
    if ((flags & 0x10u) != 0u) {
        const params_t p0 = layer_checked("before an erase", &st0);
        if (nvstore_erase_calibration(&hal, &cs) != 0) {
            fuzz_fail("nvstore_erase_calibration on a working flash failed");
        }
        const params_t p = layer_checked("after an erase", &st);
        if (st0.source == NVSTORE_SRC_NVM && !same(&p, &p0)) {
            fuzz_fail("an erase of the calibration changed the parameters");
        }
    }
    return 0;
}
