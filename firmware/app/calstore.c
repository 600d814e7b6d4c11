/*
 * calstore.c - the calibration record in NVM (layout and contracts in calstore.h).
 */
#include "calstore.h"

#include <string.h>

#include "crc32.h"

_Static_assert(sizeof(float) == 4u, "calstore stores floats as 32-bit IEEE bit patterns");

#define N_SLOTS 2u
#define OFF_MAGIC 0u
#define OFF_VERSION 4u
#define OFF_SOURCE 5u
#define OFF_LEN 6u
#define OFF_SEQ 8u
#define OFF_DH 12u
#define OFF_MU 16u
#define OFF_BASE 20u
#define OFF_GAP 28u

static const uint8_t magic[4] = {'N', 'C', 'A', 'L'};
static const uint8_t commit[4] = {'D', 'O', 'N', 'E'};
static const uint8_t ext_magic[4] = {'N', 'P', 'A', 'R'};

#define EXT_OFF_VERSION 4u
#define EXT_OFF_LEN 6u
#define EXT_OFF_SEQ 8u
#define EXT_OFF_PLEN 12u
#define EXT_OFF_DTC 16u
#define CHUNK 32u

/* the extension image of a save or a load: off the stack (calstore is not reentrant) */
static uint8_t ext_img[CALSTORE_EXT_MAX_BYTES];

calstore_ext_t calstore_ext_buf; /* calstore.h */

typedef enum { SLOT_ERASED, SLOT_VALID, SLOT_INVALID } slot_state_t;

/* Both slots as read: the newest valid one (-1: none) and how many are erased. */
typedef struct {
    int8_t newest;
    uint32_t seq;
    cal_record_t rec;
    unsigned n_erased;
    unsigned n_newer; /* slots with the magic and commit marker but another version */
} scan_t;

uint32_t calstore_crc32(const uint8_t *data, size_t len)
{
    return crc32_of(data, len); /* firmware/diag/crc32.c, shared with the bootloader */
}

static void put_u32le(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static uint32_t get_u32le(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static float bits_float(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* 1 unless the exponent is all ones (infinity or NaN) */
static int bits_finite(uint32_t u)
{
    return ((u >> 23) & 0xFFu) != 0xFFu;
}

/* Out of line (noinline), as other_slot: inlined at their two calls each they took 24
 * bytes more of the ECU's flash (docs/target.md); at an NVM load or save only. */
__attribute__((noinline)) static cal_record_t default_record(void)
{
    const cal_record_t r = {0.0f, 0.0f, 0.0f, (uint8_t)CAL_SRC_NONE};
    return r;
}

/* 1 if *r may be stored and used (calstore.h: payload range); comparisons fail on NaN */
static int record_ok(const cal_record_t *r)
{
    if (r->source == (uint8_t)CAL_SRC_NONE) {
        /* no calibration stored (a record that holds parameters only) */
        return float_bits(r->dh_rad) == 0u && float_bits(r->odo_scale_err) == 0u &&
               float_bits(r->base_m) == 0u;
    }
    return bits_finite(float_bits(r->dh_rad)) && bits_finite(float_bits(r->odo_scale_err)) &&
           bits_finite(float_bits(r->base_m)) && r->dh_rad >= -CALSTORE_DH_MAX_RAD &&
           r->dh_rad <= CALSTORE_DH_MAX_RAD && r->odo_scale_err >= -CALSTORE_MU_MAX &&
           r->odo_scale_err <= CALSTORE_MU_MAX && r->base_m >= 0.0f &&
           r->source <= CAL_SRC_FILTER;
}

/* The 36-byte slot image of (rec, seq), gap and commit marker included. */
static void slot_encode(const cal_record_t *rec, uint32_t seq, uint8_t img[CALSTORE_SLOT_BYTES])
{
    memset(img, 0xFF, CALSTORE_SLOT_BYTES);
    memcpy(img + OFF_MAGIC, magic, sizeof magic);
    img[OFF_VERSION] = (uint8_t)CALSTORE_VERSION;
    img[OFF_SOURCE] = rec->source;
    img[OFF_LEN] = (uint8_t)CALSTORE_BODY_BYTES;
    img[OFF_LEN + 1u] = (uint8_t)(CALSTORE_BODY_BYTES >> 8);
    put_u32le(img + OFF_SEQ, seq);
    put_u32le(img + OFF_DH, float_bits(rec->dh_rad));
    put_u32le(img + OFF_MU, float_bits(rec->odo_scale_err));
    put_u32le(img + OFF_BASE, float_bits(rec->base_m));
    put_u32le(img + CALSTORE_CRC_OFFSET, calstore_crc32(img, CALSTORE_BODY_BYTES));
    memcpy(img + CALSTORE_COMMIT_OFFSET, commit, sizeof commit);
}

static int all_erased(const uint8_t *p, size_t len)
{
    for (size_t k = 0u; k < len; k++) {
        if (p[k] != 0xFFu) {
            return 0;
        }
    }
    return 1;
}

/* Classify one slot image; on SLOT_VALID fill *seq and *rec. */
static slot_state_t slot_decode(const uint8_t img[CALSTORE_SLOT_BYTES], uint32_t *seq,
                                cal_record_t *rec)
{
    if (all_erased(img, CALSTORE_SLOT_BYTES)) {
        return SLOT_ERASED;
    }
    if (memcmp(img + CALSTORE_COMMIT_OFFSET, commit, sizeof commit) != 0 ||
        memcmp(img + OFF_MAGIC, magic, sizeof magic) != 0 || img[OFF_VERSION] != CALSTORE_VERSION ||
        img[OFF_LEN] != (uint8_t)CALSTORE_BODY_BYTES ||
        img[OFF_LEN + 1u] != (uint8_t)(CALSTORE_BODY_BYTES >> 8) ||
        !all_erased(img + OFF_GAP, CALSTORE_COMMIT_OFFSET - OFF_GAP) ||
        get_u32le(img + CALSTORE_CRC_OFFSET) != calstore_crc32(img, CALSTORE_BODY_BYTES)) {
        return SLOT_INVALID;
    }
    cal_record_t r;
    r.dh_rad = bits_float(get_u32le(img + OFF_DH));
    r.odo_scale_err = bits_float(get_u32le(img + OFF_MU));
    r.base_m = bits_float(get_u32le(img + OFF_BASE));
    r.source = img[OFF_SOURCE];
    if (!record_ok(&r)) {
        return SLOT_INVALID;
    }
    *seq = get_u32le(img + OFF_SEQ);
    *rec = r;
    return SLOT_VALID;
}

/* 1 if seq a is after seq b modulo 2^32 (a - b in 1 .. 2^31 - 1) */
static int seq_after(uint32_t a, uint32_t b)
{
    return (uint32_t)(a - b) - 1u < 0x7FFFFFFFu;
}

/* Sector size if the region holds both slots; 0 if it is too small. */
static size_t slot_stride(const hal_t *hal)
{
    const size_t sector = hal_nvm_sector_size(hal);
    if (sector < CALSTORE_SLOT_BYTES || hal_nvm_size(hal) / sector < N_SLOTS) {
        return 0u;
    }
    return sector;
}

static int slot_read(hal_t *hal, size_t stride, unsigned slot, uint8_t img[CALSTORE_SLOT_BYTES])
{
    return hal_nvm_read(hal, (size_t)slot * stride, img, CALSTORE_SLOT_BYTES);
}

/* 1 if NVM [off, off + len) reads back as data (as erased flash when data is NULL), 0 if
 * not, the HAL's error (< 0) */
static int nvm_reads_as(hal_t *hal, size_t off, const uint8_t *data, size_t len)
{
    uint8_t buf[CHUNK];
    for (size_t k = 0u; k < len; k += CHUNK) {
        const size_t n = len - k < CHUNK ? len - k : CHUNK;
        const int rc = hal_nvm_read(hal, off + k, buf, n);
        if (rc != 0) {
            return rc;
        }
        if ((data == NULL) ? (all_erased(buf, n) == 0) : (memcmp(buf, data + k, n) != 0)) {
            return 0;
        }
    }
    return 1;
}

/* the sectors hold an extension */
static int ext_fits(size_t stride)
{
    return stride >= CALSTORE_SLOT_V2_BYTES;
}

/* Read and classify both slots. 0 or the HAL's error. On a tie (equal seqs, or seqs
 * 2^31 apart: neither is after the other) slot 0 wins, so the choice is deterministic. */
static int scan_slots(hal_t *hal, size_t stride, scan_t *s)
{
    s->newest = -1;
    s->seq = 0u;
    s->rec = default_record();
    s->n_erased = 0u;
    s->n_newer = 0u;
    for (unsigned k = 0u; k < N_SLOTS; k++) {
        uint8_t img[CALSTORE_SLOT_BYTES];
        uint32_t seq = 0u;
        cal_record_t rec;
        const int rc = slot_read(hal, stride, k, img);
        if (rc != 0) {
            return rc;
        }
        slot_state_t st = slot_decode(img, &seq, &rec);
        if (st == SLOT_ERASED && ext_fits(stride)) {
            /* an interrupted first save may have written only the extension */
            const int e = nvm_reads_as(hal, (size_t)k * stride + CALSTORE_EXT_OFFSET, NULL,
                                       CALSTORE_EXT_MAX_BYTES);
            if (e < 0) {
                return e;
            }
            st = e != 0 ? SLOT_ERASED : SLOT_INVALID;
        }
        if (st == SLOT_INVALID && memcmp(img + OFF_MAGIC, magic, sizeof magic) == 0 &&
            memcmp(img + CALSTORE_COMMIT_OFFSET, commit, sizeof commit) == 0 &&
            img[OFF_VERSION] != CALSTORE_VERSION) {
            s->n_newer++;
        }
        switch (st) {
        case SLOT_ERASED:
            s->n_erased++;
            break;
        case SLOT_VALID:
            if (s->newest < 0 || seq_after(seq, s->seq)) {
                s->newest = (int8_t)k;
                s->seq = seq;
                s->rec = rec;
            }
            break;
        case SLOT_INVALID:
        default:
            break;
        }
    }
    return 0;
}

/* The slot a save writes (and an erase erases first): the one not holding the newest. */
__attribute__((noinline)) static unsigned other_slot(int8_t newest)
{
    return newest == 0 ? 1u : 0u;
}

int calstore_load(hal_t *hal, calstore_t *cs, cal_record_t *rec)
{
    if (hal == NULL || cs == NULL || rec == NULL) {
        return HAL_EINVAL;
    }
    *rec = default_record();
    cs->seq = 0u;
    cs->slot = -1;
    const size_t stride = slot_stride(hal);
    if (stride == 0u) {
        return HAL_ENOSPC;
    }
    scan_t s;
    const int rc = scan_slots(hal, stride, &s);
    if (rc != 0) {
        return rc;
    }
    if (s.newest >= 0) {
        *rec = s.rec;
        cs->seq = s.seq;
        cs->slot = s.newest;
        return CALSTORE_OK;
    }
    return s.n_erased == N_SLOTS ? CALSTORE_EMPTY : CALSTORE_CORRUPT;
}

/* The extension image of *ext with seq into ext_img; its length. */
static size_t ext_encode(const calstore_ext_t *ext, uint32_t seq)
{
    const size_t body = CALSTORE_EXT_HEAD + (size_t)ext->params_len;
    memset(ext_img, 0x00, CALSTORE_EXT_HEAD);
    memcpy(ext_img, ext_magic, sizeof ext_magic);
    ext_img[EXT_OFF_VERSION] = (uint8_t)CALSTORE_EXT_VERSION;
    ext_img[EXT_OFF_LEN] = (uint8_t)body;
    ext_img[EXT_OFF_LEN + 1u] = (uint8_t)(body >> 8);
    put_u32le(ext_img + EXT_OFF_SEQ, seq);
    ext_img[EXT_OFF_PLEN] = (uint8_t)ext->params_len;
    ext_img[EXT_OFF_PLEN + 1u] = (uint8_t)(ext->params_len >> 8);
    memcpy(ext_img + EXT_OFF_DTC, ext->dtc, CALSTORE_DTC_N);
    memcpy(ext_img + CALSTORE_EXT_HEAD, ext->params, ext->params_len);
    put_u32le(ext_img + body, calstore_crc32(ext_img, body));
    return body + 4u;
}

/* out of line (noinline): inlined at its four calls it took 8-16 bytes more */
__attribute__((noinline)) static void ext_clear(calstore_ext_t *ext, uint8_t status,
                                                uint8_t version)
{
    ext->status = status;
    ext->version = version;
    ext->params_len = 0u;
    memset(ext->dtc, 0xFF, sizeof ext->dtc);
}

/* Read and check the extension of the slot at base (its seq: seq). 0 or the HAL's error. */
static int ext_read(hal_t *hal, size_t base, uint32_t seq, calstore_ext_t *ext)
{
    uint8_t *img = ext_img;
    int rc = hal_nvm_read(hal, base + CALSTORE_EXT_OFFSET, img, CALSTORE_EXT_HEAD);
    if (rc != 0) {
        return rc;
    }
    if (all_erased(img, sizeof ext_magic)) {
        ext_clear(ext, (uint8_t)CALSTORE_EXT_NONE, 0u);
        return 0;
    }
    if (memcmp(img, ext_magic, sizeof ext_magic) == 0 &&
        img[EXT_OFF_VERSION] != CALSTORE_EXT_VERSION) {
        ext_clear(ext, (uint8_t)CALSTORE_EXT_NEWER, img[EXT_OFF_VERSION]);
        return 0;
    }
    const size_t body = (size_t)img[EXT_OFF_LEN] | (size_t)img[EXT_OFF_LEN + 1u] << 8;
    const size_t plen = (size_t)img[EXT_OFF_PLEN] | (size_t)img[EXT_OFF_PLEN + 1u] << 8;
    ext_clear(ext, (uint8_t)CALSTORE_EXT_CORRUPT, img[EXT_OFF_VERSION]);
    if (memcmp(img, ext_magic, sizeof ext_magic) != 0 || plen > CALSTORE_PARAMS_MAX ||
        body != CALSTORE_EXT_HEAD + plen || get_u32le(img + EXT_OFF_SEQ) != seq) {
        return 0;
    }
    rc = hal_nvm_read(hal, base + CALSTORE_EXT_OFFSET + CALSTORE_EXT_HEAD,
                      img + CALSTORE_EXT_HEAD, plen + 4u);
    if (rc != 0) {
        return rc;
    }
    if (get_u32le(img + body) != calstore_crc32(img, body)) {
        return 0;
    }
    ext->status = (uint8_t)CALSTORE_EXT_OK;
    ext->params_len = (uint16_t)plen;
    memcpy(ext->dtc, img + EXT_OFF_DTC, CALSTORE_DTC_N);
    memcpy(ext->params, img + CALSTORE_EXT_HEAD, plen);
    return 0;
}

int calstore_load_ext(hal_t *hal, calstore_t *cs, cal_record_t *rec, calstore_ext_t *ext)
{
    if (ext == NULL) {
        return HAL_EINVAL;
    }
    const int rc = calstore_load(hal, cs, rec);
    if (rc == HAL_EINVAL) {
        return rc;
    }
    ext_clear(ext, (uint8_t)CALSTORE_EXT_NONE, 0u);
    const size_t stride = slot_stride(hal);
    if (rc == (int)CALSTORE_CORRUPT && stride != 0u) {
        scan_t s;
        if (scan_slots(hal, stride, &s) == 0 && s.n_newer > 0u) {
            ext->status = (uint8_t)CALSTORE_EXT_NEWER;
        }
        return rc;
    }
    if (rc != (int)CALSTORE_OK || !ext_fits(stride)) {
        return rc;
    }
    const int erc = ext_read(hal, (size_t)(uint8_t)cs->slot * stride, cs->seq, ext);
    return erc != 0 ? erc : rc;
}

/* The save of calstore.h: *rec and, if ext is not NULL, its extension. */
static int save_record(hal_t *hal, calstore_t *cs, const cal_record_t *rec,
                       const calstore_ext_t *ext)
{
    const size_t stride = slot_stride(hal);
    if (stride == 0u || (ext != NULL && !ext_fits(stride))) {
        return HAL_ENOSPC;
    }
    scan_t s;
    int rc = scan_slots(hal, stride, &s);
    if (rc != 0) {
        return rc;
    }
    const unsigned target = other_slot(s.newest);
    const uint32_t seq = (s.newest >= 0 ? s.seq : cs->seq) + 1u;
    const size_t base = (size_t)target * stride;
    uint8_t img[CALSTORE_SLOT_BYTES];
    uint8_t back[CALSTORE_SLOT_BYTES];
    slot_encode(rec, seq, img);

    rc = hal_nvm_erase_sector(hal, target);
    if (rc != 0) {
        return rc;
    }
    if (ext != NULL) {
        /* the extension first: the calibration record's commit marker commits it too */
        const size_t n = ext_encode(ext, seq);
        rc = hal_nvm_write(hal, base + CALSTORE_EXT_OFFSET, ext_img, n);
        if (rc != 0) {
            return rc;
        }
        rc = nvm_reads_as(hal, base + CALSTORE_EXT_OFFSET, ext_img, n);
        if (rc <= 0) {
            return rc < 0 ? rc : HAL_EIO;
        }
    }
    rc = hal_nvm_write(hal, base, img, CALSTORE_CRC_OFFSET + 4u);
    if (rc != 0) {
        return rc;
    }
    /* commit only what reads back exactly, with the marker still erased */
    rc = slot_read(hal, stride, target, back);
    if (rc != 0) {
        return rc;
    }
    if (memcmp(back, img, CALSTORE_COMMIT_OFFSET) != 0 ||
        !all_erased(back + CALSTORE_COMMIT_OFFSET, sizeof commit)) {
        return HAL_EIO;
    }
    rc = hal_nvm_write(hal, base + CALSTORE_COMMIT_OFFSET, img + CALSTORE_COMMIT_OFFSET,
                       sizeof commit);
    if (rc != 0) {
        return rc;
    }
    rc = slot_read(hal, stride, target, back);
    if (rc != 0) {
        return rc;
    }
    if (memcmp(back, img, CALSTORE_SLOT_BYTES) != 0) {
        return HAL_EIO;
    }
    cs->seq = seq;
    cs->slot = (int8_t)target;
    return 0;
}

int calstore_save_ext(hal_t *hal, calstore_t *cs, const cal_record_t *rec,
                      const calstore_ext_t *ext)
{
    if (hal == NULL || cs == NULL || rec == NULL || ext == NULL || !record_ok(rec) ||
        ext->params_len > CALSTORE_PARAMS_MAX) {
        return HAL_EINVAL;
    }
    return save_record(hal, cs, rec, ext);
}

int calstore_save(hal_t *hal, calstore_t *cs, const cal_record_t *rec)
{
    if (hal == NULL || cs == NULL || rec == NULL || !record_ok(rec)) {
        return HAL_EINVAL;
    }
    /* the newest record's extension goes on with the new calibration (off the stack) */
    calstore_ext_t *const carried = &calstore_ext_buf;
    calstore_t now;
    cal_record_t old;
    const int rc = calstore_load_ext(hal, &now, &old, carried);
    if (rc == (int)CALSTORE_OK && carried->status == (uint8_t)CALSTORE_EXT_OK) {
        return save_record(hal, cs, rec, carried);
    }
    return save_record(hal, cs, rec, NULL);
}

int calstore_erase(hal_t *hal, calstore_t *cs)
{
    if (hal == NULL || cs == NULL) {
        return HAL_EINVAL;
    }
    const size_t stride = slot_stride(hal);
    if (stride == 0u) {
        return HAL_ENOSPC;
    }
    scan_t s;
    /* the scan only orders the two erases: unreadable slots are erased all the same */
    if (scan_slots(hal, stride, &s) != 0) {
        s.newest = -1;
    }
    const unsigned first = other_slot(s.newest);
    int rc = hal_nvm_erase_sector(hal, first);
    if (rc == 0) {
        rc = hal_nvm_erase_sector(hal, 1u - first);
    }
    if (rc != 0) {
        return rc;
    }
    cs->seq = 0u;
    cs->slot = -1;
    return 0;
}
