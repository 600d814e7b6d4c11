/*
 * fuzz_calstore.c - libFuzzer harness: the calibration record store (calstore.h) on
 * arbitrary flash contents, against the in-memory HAL of tests/support/fake_hal.h
 * (2 sectors of FAKE_NVM_SECTOR_SIZE bytes, NOR-flash rules, power cuts). The version 2
 * extension (calstore.h) is checked here as far as calstore_save carries it over; its
 * contents are fuzz_nvstore.c's.
 *
 * Input: flags(1) record(13: dh, mu, base as float bits, source) cut_units(2, LE)
 * torn(1), then the NVM image (missing bytes read 0xFF: erased).
 *   flags & 0x01: save the record          flags & 0x02: cut the power during the save
 *   flags & 0x04: program writes backwards flags & 0x08: a second save after the first
 *   flags & 0x10: erase the store at the end
 *
 * Invariants (abort on violation):
 *  - calstore_load agrees with a reference reader written from calstore.h's layout
 *    (status, seq, slot and the record bit for bit), and a record it returns as valid
 *    has its payload in range;
 *  - calstore_save refuses (HAL_EINVAL, flash untouched) exactly the records outside the
 *    payload range; otherwise it succeeds, writes only the slot not holding the newest
 *    record (the rest of that sector erased), and a load returns what was saved with
 *    seq + 1; a second save alternates slots and a load returns it with seq + 2;
 *  - a power cut anywhere in the save (the fake HAL's units, torn byte, either program
 *    order) leaves a store whose load returns the previous newest record or the new one
 *    (nothing else; with no previous record: the new one or no valid record);
 *  - calstore_erase leaves CALSTORE_EMPTY.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "calstore.h"
#include "fake_hal.h"
#include "fuzz_fail.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define HDR 17u

static hal_t hal;

/* ---- the reference reader, from calstore.h alone ---- */

static uint32_t ref_crc32(const uint8_t *p, size_t n)
{
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t k = 0u; k < n; k++) {
        crc ^= p[k];
        for (int b = 0; b < 8; b++) {
            crc = (crc & 1u) != 0u ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
        }
    }
    return crc ^ 0xFFFFFFFFu;
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float f32(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static int rec_in_range(const cal_record_t *r)
{
    if (r->source == 0u) { /* no calibration: a record holding the extension only */
        return memcmp(&r->dh_rad, "\0\0\0\0", 4u) == 0 &&
               memcmp(&r->odo_scale_err, "\0\0\0\0", 4u) == 0 &&
               memcmp(&r->base_m, "\0\0\0\0", 4u) == 0;
    }
    return isfinite(r->dh_rad) && isfinite(r->odo_scale_err) && isfinite(r->base_m) &&
           fabsf(r->dh_rad) <= CALSTORE_DH_MAX_RAD && fabsf(r->odo_scale_err) <= CALSTORE_MU_MAX &&
           r->base_m >= 0.0f && r->source >= 1u && r->source <= 3u;
}

static int rec_same(const cal_record_t *a, const cal_record_t *b)
{
    return memcmp(&a->dh_rad, &b->dh_rad, 4u) == 0 &&
           memcmp(&a->odo_scale_err, &b->odo_scale_err, 4u) == 0 &&
           memcmp(&a->base_m, &b->base_m, 4u) == 0 && a->source == b->source;
}

typedef enum { REF_ERASED, REF_VALID, REF_INVALID } ref_slot_t;

/* 1 if the slot's extension is a valid version 2 one of seq (calstore.h's layout) */
static int ref_ext_ok(const uint8_t *s, uint32_t seq)
{
    const uint8_t *e = s + CALSTORE_EXT_OFFSET;
    const size_t body = (size_t)e[6] | (size_t)e[7] << 8;
    const size_t plen = (size_t)e[12] | (size_t)e[13] << 8;
    return memcmp(e, "NPAR", 4u) == 0 && e[4] == 2u && plen <= CALSTORE_PARAMS_MAX &&
           body == CALSTORE_EXT_HEAD + plen && le32(e + 8) == seq &&
           le32(e + body) == ref_crc32(e, body);
}

static ref_slot_t ref_slot(const uint8_t *s, uint32_t *seq, cal_record_t *r)
{
    int erased = 1;
    for (unsigned k = 0u; k < CALSTORE_SLOT_BYTES; k++) {
        erased = erased && s[k] == 0xFFu;
    }
    /* an extension without its record (an interrupted first save) is not erased */
    for (unsigned k = CALSTORE_EXT_OFFSET; k < CALSTORE_SLOT_V2_BYTES; k++) {
        erased = erased && s[k] == 0xFFu;
    }
    if (erased) {
        return REF_ERASED;
    }
    if (memcmp(s, "NCAL", 4u) != 0 || s[4] != 1u || s[6] != 24u || s[7] != 0u ||
        le32(s + 24) != ref_crc32(s, 24u) || le32(s + 28) != 0xFFFFFFFFu ||
        memcmp(s + 32, "DONE", 4u) != 0) {
        return REF_INVALID;
    }
    r->source = s[5];
    r->dh_rad = f32(le32(s + 12));
    r->odo_scale_err = f32(le32(s + 16));
    r->base_m = f32(le32(s + 20));
    *seq = le32(s + 8);
    return rec_in_range(r) ? REF_VALID : REF_INVALID;
}

typedef struct {
    int status;
    uint32_t seq;
    int slot;
    cal_record_t rec;
    int ext_ok; /* the newest record has a valid extension (calstore_save carries it) */
} ref_t;

static ref_t ref_load(const uint8_t nvm[FAKE_NVM_SIZE])
{
    ref_t out = {CALSTORE_EMPTY, 0u, -1, {0.0f, 0.0f, 0.0f, 0u}, 0};
    unsigned n_erased = 0u;
    for (unsigned k = 0u; k < 2u; k++) {
        uint32_t seq = 0u;
        cal_record_t r;
        memset(&r, 0, sizeof r);
        const ref_slot_t st = ref_slot(nvm + k * FAKE_NVM_SECTOR_SIZE, &seq, &r);
        if (st == REF_ERASED) {
            n_erased++;
        } else if (st == REF_VALID) {
            /* the highest seq modulo 2^32; a tie (equal, or 2^31 apart) keeps slot 0 */
            if (out.slot < 0 || (uint32_t)(seq - out.seq) - 1u < 0x7FFFFFFFu) {
                out.slot = (int)k;
                out.seq = seq;
                out.rec = r;
            }
        }
    }
    out.status = out.slot >= 0 ? CALSTORE_OK : (n_erased == 2u ? CALSTORE_EMPTY : CALSTORE_CORRUPT);
    out.ext_ok = out.slot >= 0 && ref_ext_ok(nvm + (size_t)out.slot * FAKE_NVM_SECTOR_SIZE, out.seq);
    return out;
}

/* ---- checks ---- */

static ref_t load_checked(const char *when)
{
    calstore_t cs = {0xDEADBEEFu, 7};
    cal_record_t rec;
    memset(&rec, 0xA5, sizeof rec);
    const int rc = calstore_load(&hal, &cs, &rec);
    const ref_t ref = ref_load(hal.nvm);
    if (rc != ref.status) {
        fuzz_fail("calstore_load %s: %d, the layout says %d", when, rc, ref.status);
    }
    if (rc == CALSTORE_OK) {
        if (!rec_in_range(&rec)) {
            fuzz_fail("calstore_load %s: a valid record out of range (%g %g %g %u)", when,
                      (double)rec.dh_rad, (double)rec.odo_scale_err, (double)rec.base_m, rec.source);
        }
        if (cs.slot != ref.slot || cs.seq != ref.seq || !rec_same(&rec, &ref.rec)) {
            fuzz_fail("calstore_load %s: slot %d seq %u, the layout says slot %d seq %u%s", when,
                      cs.slot, cs.seq, ref.slot, ref.seq,
                      rec_same(&rec, &ref.rec) ? "" : " (and another record)");
        }
    } else if (cs.slot != -1 || cs.seq != 0u || rec.source != CAL_SRC_NONE ||
               memcmp(&rec.dh_rad, "\0\0\0\0", 4u) != 0) {
        fuzz_fail("calstore_load %s: status %d without the defaults {0, -1}, {0, 0, 0, 0}", when, rc);
    }
    return ref;
}

static void save_checked(calstore_t *cs, const cal_record_t *rec, const ref_t *before)
{
    uint8_t old[FAKE_NVM_SIZE];
    memcpy(old, hal.nvm, sizeof old);
    const int rc = calstore_save(&hal, cs, rec);
    if (!rec_in_range(rec)) {
        if (rc != HAL_EINVAL || memcmp(old, hal.nvm, sizeof old) != 0) {
            fuzz_fail("calstore_save of an out-of-range record: %d (or the flash changed)", rc);
        }
        return;
    }
    if (rc != 0) {
        fuzz_fail("calstore_save of a good record on a working flash: %d", rc);
    }
    const int target = before->slot == 0 ? 1 : 0;
    const uint8_t *other = hal.nvm + (size_t)(1 - target) * FAKE_NVM_SECTOR_SIZE;
    if (memcmp(other, old + (size_t)(1 - target) * FAKE_NVM_SECTOR_SIZE, FAKE_NVM_SECTOR_SIZE) != 0) {
        fuzz_fail("calstore_save touched slot %d, which holds the newest record", 1 - target);
    }
    const uint32_t want_seq = before->seq + 1u;
    const uint8_t *t = hal.nvm + (size_t)target * FAKE_NVM_SECTOR_SIZE;
    size_t used_to = CALSTORE_SLOT_BYTES;
    if (before->ext_ok) {
        /* the newest record's extension, carried over with the new seq */
        const uint8_t *e = t + CALSTORE_EXT_OFFSET;
        const uint8_t *o = old + (size_t)before->slot * FAKE_NVM_SECTOR_SIZE + CALSTORE_EXT_OFFSET;
        const size_t plen = (size_t)o[12] | (size_t)o[13] << 8;
        if (!ref_ext_ok(t, want_seq) || memcmp(e, o, 8u) != 0 ||
            memcmp(e + 12, o + 12, CALSTORE_EXT_HEAD - 12u + plen) != 0) {
            fuzz_fail("calstore_save did not carry the newest record's extension over");
        }
        for (size_t k = CALSTORE_SLOT_BYTES; k < CALSTORE_EXT_OFFSET; k++) {
            if (t[k] != 0xFFu) {
                fuzz_fail("calstore_save left byte %zu of its sector programmed", k);
            }
        }
        used_to = CALSTORE_EXT_OFFSET + CALSTORE_EXT_HEAD + plen + 4u;
    }
    for (size_t k = used_to; k < FAKE_NVM_SECTOR_SIZE; k++) {
        if (t[k] != 0xFFu) {
            fuzz_fail("calstore_save left byte %zu of its sector programmed", k);
        }
    }
    const ref_t after = load_checked("after a save");
    if (after.status != CALSTORE_OK || after.slot != target || after.seq != want_seq ||
        !rec_same(&after.rec, rec) || cs->seq != want_seq || cs->slot != target) {
        fuzz_fail("after calstore_save: load gives status %d slot %d seq %u, cs {%u, %d}; "
                  "saved to slot %d with seq %u", after.status, after.slot, after.seq, cs->seq,
                  cs->slot, target, want_seq);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    uint8_t hdr[HDR];
    memset(hdr, 0, sizeof hdr);
    memcpy(hdr, data, size < HDR ? size : HDR);
    fake_hal_reset(&hal);
    if (size > HDR) {
        const size_t n = size - HDR < FAKE_NVM_SIZE ? size - HDR : FAKE_NVM_SIZE;
        memcpy(hal.nvm, data + HDR, n);
    }
    const uint8_t flags = hdr[0];
    cal_record_t rec;
    memcpy(&rec.dh_rad, hdr + 1, 4u);
    memcpy(&rec.odo_scale_err, hdr + 5, 4u);
    memcpy(&rec.base_m, hdr + 9, 4u);
    rec.source = hdr[13];
    const uint32_t cut_units = (uint32_t)hdr[14] | (uint32_t)hdr[15] << 8;
    const uint8_t torn = hdr[16];

    const ref_t before = load_checked("of the input image");
    calstore_t cs = {before.seq, (int8_t)before.slot};
    hal.nvm_program_backwards = (flags & 0x04u) != 0u;

    if ((flags & 0x03u) == 0x03u) {
        /* a power cut in the middle of the save, then a reboot */
        fake_hal_nvm_cut_after(&hal, cut_units % 512u, torn);
        (void)calstore_save(&hal, &cs, &rec);
        fake_hal_nvm_power_on(&hal);
        const ref_t after = load_checked("after a cut save");
        const int is_old = before.status == CALSTORE_OK ? after.status == CALSTORE_OK &&
                                                               after.seq == before.seq &&
                                                               rec_same(&after.rec, &before.rec)
                                                         : after.status != CALSTORE_OK;
        const int is_new = rec_in_range(&rec) && after.status == CALSTORE_OK &&
                           after.seq == before.seq + 1u && rec_same(&after.rec, &rec);
        if (!is_old && !is_new) {
            fuzz_fail("power cut after %u units (torn 0x%02X%s): load gives status %d seq %u, "
                      "neither the previous record (status %d seq %u) nor the new one",
                      cut_units % 512u, torn, hal.nvm_program_backwards ? ", backwards" : "",
                      after.status, after.seq, before.status, before.seq);
        }
    } else if ((flags & 0x01u) != 0u) {
        save_checked(&cs, &rec, &before);
        if ((flags & 0x08u) != 0u && rec_in_range(&rec)) {
            const ref_t mid = load_checked("between saves");
            cal_record_t rec2 = rec;
            rec2.dh_rad = -rec.dh_rad;
            rec2.source = (uint8_t)(rec.source % 3u + 1u);
            save_checked(&cs, &rec2, &mid);
        }
    }
    if ((flags & 0x10u) != 0u) {
        calstore_t ce = cs;
        if (calstore_erase(&hal, &ce) != 0 || ce.slot != -1 || ce.seq != 0u) {
            fuzz_fail("calstore_erase on a working flash failed");
        }
        const ref_t e = load_checked("after an erase");
        if (e.status != CALSTORE_EMPTY) {
            fuzz_fail("after calstore_erase: status %d, not CALSTORE_EMPTY", e.status);
        }
    }
    return 0;
}
