/*
 * calstore.c - the calibration record in NVM (layout and contracts in calstore.h).
 */
#include "calstore.h"

#include <string.h>

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

typedef enum { SLOT_ERASED, SLOT_VALID, SLOT_INVALID } slot_state_t;

/* Both slots as read: the newest valid one (-1: none) and how many are erased. */
typedef struct {
    int8_t newest;
    uint32_t seq;
    cal_record_t rec;
    unsigned n_erased;
} scan_t;

uint32_t calstore_crc32(const uint8_t *data, size_t len)
{
    /* CRC of each nibble value, reflected polynomial 0xEDB88320 */
    static const uint32_t table[16] = {
        0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u,
        0x4DB26158u, 0x5005713Cu, 0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
        0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu,
    };
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t k = 0u; k < len; k++) {
        crc ^= data[k];
        crc = (crc >> 4) ^ table[crc & 0xFu];
        crc = (crc >> 4) ^ table[crc & 0xFu];
    }
    return crc ^ 0xFFFFFFFFu;
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

static cal_record_t default_record(void)
{
    const cal_record_t r = {0.0f, 0.0f, 0.0f, (uint8_t)CAL_SRC_NONE};
    return r;
}

/* 1 if *r may be stored and used (calstore.h: payload range); comparisons fail on NaN */
static int record_ok(const cal_record_t *r)
{
    return bits_finite(float_bits(r->dh_rad)) && bits_finite(float_bits(r->odo_scale_err)) &&
           bits_finite(float_bits(r->base_m)) && r->dh_rad >= -CALSTORE_DH_MAX_RAD &&
           r->dh_rad <= CALSTORE_DH_MAX_RAD && r->odo_scale_err >= -CALSTORE_MU_MAX &&
           r->odo_scale_err <= CALSTORE_MU_MAX && r->base_m >= 0.0f &&
           r->source >= CAL_SRC_KNOWN_POSITION && r->source <= CAL_SRC_FILTER;
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

/* Read and classify both slots. 0 or the HAL's error. On a tie (equal seqs, or seqs
 * 2^31 apart: neither is after the other) slot 0 wins, so the choice is deterministic. */
static int scan_slots(hal_t *hal, size_t stride, scan_t *s)
{
    s->newest = -1;
    s->seq = 0u;
    s->rec = default_record();
    s->n_erased = 0u;
    for (unsigned k = 0u; k < N_SLOTS; k++) {
        uint8_t img[CALSTORE_SLOT_BYTES];
        uint32_t seq = 0u;
        cal_record_t rec;
        const int rc = slot_read(hal, stride, k, img);
        if (rc != 0) {
            return rc;
        }
        switch (slot_decode(img, &seq, &rec)) {
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
static unsigned other_slot(int8_t newest)
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

int calstore_save(hal_t *hal, calstore_t *cs, const cal_record_t *rec)
{
    if (hal == NULL || cs == NULL || rec == NULL || !record_ok(rec)) {
        return HAL_EINVAL;
    }
    const size_t stride = slot_stride(hal);
    if (stride == 0u) {
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
