/*
 * calstore.h - the heading/odometer calibration in non-volatile memory, safe against a
 * power loss at any moment of a save: the last record whose save completed stays
 * readable, and a half-written record is never taken for a good one.
 *
 * Two slots, slot k at the start of NVM sector k (k = 0, 1; the rest of each sector stays
 * erased; sectors >= 2 of the region are not touched). A save erases the slot that does
 * not hold the newest valid record, writes the new record there with seq + 1, reads it
 * back, and only then writes the commit marker in a second, separate write. Load takes
 * the valid record with the highest seq (modulo 2^32). So at every instant of a save the
 * other slot still holds the previous record, untouched.
 *
 * Slot layout, format version 1 (36 bytes; multi-byte fields little-endian; floats as
 * their IEEE 754 binary32 bit patterns, serialised byte by byte, independent of the
 * compiler's struct layout and of the CPU's byte order):
 *
 *   offset size field
 *    0     4   magic: the bytes 'N' 'C' 'A' 'L' (0x4C41434E as a little-endian uint32)
 *    4     1   format version: CALSTORE_VERSION (1)
 *    5     1   source: CAL_SRC_KNOWN_POSITION 1, CAL_SRC_GNSS 2, CAL_SRC_FILTER 3
 *    6     2   body length: CALSTORE_BODY_BYTES (24), the bytes the CRC covers
 *    8     4   seq: save counter, +1 per save, wraps from 0xFFFFFFFF to 0
 *   12     4   dh_rad        (float bits)
 *   16     4   odo_scale_err (float bits)
 *   20     4   base_m        (float bits)
 *   24     4   CRC-32 of bytes 0..23
 *   28     4   never written: must read 0xFF
 *   32     4   commit marker: the bytes 'D' 'O' 'N' 'E', written last, on its own
 *
 * CRC-32: the IEEE 802.3 / zlib CRC (polynomial 0x04C11DB7, reflected as 0xEDB88320,
 * initial value 0xFFFFFFFF, final XOR 0xFFFFFFFF; "123456789" gives 0xCBF43926),
 * computed a nibble at a time with a 16-entry table.
 *
 * The commit marker sits in its own 32-byte-aligned block, so it stays a separate program
 * operation even on flashes that program 8- or 32-byte words with ECC.
 *
 * A slot is valid when every byte above is exactly as a save writes it: commit marker,
 * magic, version, body length, the 0xFF gap, the CRC, and a payload that passes the
 * range check below. Anything else (a torn write, a bit flip anywhere in the 36 bytes, a
 * half-erased sector) makes it invalid, and load falls back to the other slot.
 *
 * Payload range (reject non-finite or absurd values, on save and on load):
 *   |dh_rad| <= CALSTORE_DH_MAX_RAD, |odo_scale_err| <= CALSTORE_MU_MAX,
 *   0 <= base_m, all three finite; source in 1..3.
 *
 * Blocking: a save erases one sector and a calstore_erase two; on a single-bank flash
 * such as the STM32F405's the CPU stalls for the erase time (hundreds of ms per 16 KiB
 * sector): save when the vehicle is stopped or the IMU steps may wait (docs/porting.md).
 *
 * No allocation, no recursion, no OS header; one calstore_t per NVM region, owned by the
 * caller; not reentrant.
 */
#ifndef NAVECU_CALSTORE_H
#define NAVECU_CALSTORE_H

#include <stddef.h>
#include <stdint.h>

#include "dr.h"
#include "hal.h"
#include "navecu_can.h"

/* the stored source is NAV_Calibration's CalSource (the DBC's value table) */
#define CAL_SRC_NONE NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_NONE_CHOICE /* never stored */
#define CAL_SRC_KNOWN_POSITION NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_KNOWN_POSITION_CHOICE
#define CAL_SRC_GNSS NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_GNSS_CHOICE
#define CAL_SRC_FILTER NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_FILTER_CHOICE

#define CALSTORE_VERSION 1u
#define CALSTORE_BODY_BYTES 24u    /* bytes 0..23, covered by the CRC */
#define CALSTORE_CRC_OFFSET 24u
#define CALSTORE_COMMIT_OFFSET 32u
#define CALSTORE_SLOT_BYTES 36u    /* bytes of a slot that are read and checked */
#define CALSTORE_DH_MAX_RAD DR_DH_MAX_RAD /* largest |dh_rad| accepted (dr.h) */
#define CALSTORE_MU_MAX DR_MU_MAX         /* largest |odo_scale_err| accepted */

typedef struct {
    float dh_rad;         /* heading correction dH, seed 000 eq 9 (rad) */
    float odo_scale_err;  /* odometer scale error mu, seed 000 eq 10 (dimensionless) */
    float base_m;         /* distance from the start to the calibration point (m): quality */
    uint8_t source;       /* CAL_SRC_KNOWN_POSITION 1, CAL_SRC_GNSS 2, CAL_SRC_FILTER 3 */
} cal_record_t;

/* What the caller knows of the store: seq and slot of the newest valid record.
 * slot -1: none valid (seq is then 0 after a load or an erase). */
typedef struct {
    uint32_t seq;
    int8_t slot;
} calstore_t;

typedef enum { CALSTORE_OK = 0, CALSTORE_EMPTY = 1, CALSTORE_CORRUPT = 2 } calstore_status_t;

/*
 * The record's extension, format version 2 (the parameters and the DTC status bytes; the
 * application's codec of the parameters is nvstore.h's). It sits in the same slot as the
 * 36-byte calibration record above, at CALSTORE_EXT_OFFSET, and is written BEFORE the
 * calibration record's bytes and its commit marker, so that marker commits both: a power
 * cut anywhere in a save leaves the slot without its marker (invalid, the other slot is
 * loaded), never a calibration of one save with the parameters of another. A record
 * with an extension may hold no calibration: source CAL_SRC_NONE with dh_rad, odo_scale_err
 * and base_m all +0.0 (a parameters-only save); calstore_load returns it as CALSTORE_OK
 * with source CAL_SRC_NONE.
 *
 * Extension layout (slot offset CALSTORE_EXT_OFFSET + ...; multi-byte fields little-endian):
 *   offset size field
 *    0     4   magic: the bytes 'N' 'P' 'A' 'R'
 *    4     1   format version: CALSTORE_EXT_VERSION (2)
 *    5     1   0x00
 *    6     2   extension length L = CALSTORE_EXT_HEAD + P, the bytes the CRC covers
 *    8     4   seq: the calibration record's seq (the two are one record)
 *   12     2   P: bytes of parameter entries (<= CALSTORE_PARAMS_MAX)
 *   14     2   0x0000
 *   16    16   DTC status bytes 0..15 (CALSTORE_DTC_N; the dtc owner's meaning)
 *   32     P   parameter entries, opaque here (nvstore.h: DID, length, value)
 *   32+P   4   CRC-32 (as above) of extension bytes 0..31+P
 * The rest of the sector stays erased.
 *
 * Load, of the newest valid slot (calstore_load_ext):
 *   no extension (its magic bytes erased): a version 1 record, ext->status CALSTORE_EXT_NONE;
 *   magic, version 2, length in range, seq equal, CRC right: CALSTORE_EXT_OK;
 *   magic with another version byte: CALSTORE_EXT_NEWER, refused, its bytes not read;
 *   anything else: CALSTORE_EXT_CORRUPT (a bit flip: the marker committed it), refused.
 * A slot whose header version byte is not 1 is not valid (as before); if no slot is valid
 * and one of them carries the magic with another version, ext->status is CALSTORE_EXT_NEWER.
 * A refused extension leaves ext->params_len 0 and the DTC bytes 0xFF (none).
 */
#define CALSTORE_EXT_OFFSET 64u
#define CALSTORE_EXT_VERSION 2u
#define CALSTORE_EXT_HEAD 32u
#define CALSTORE_DTC_N 16u
#define CALSTORE_PARAMS_MAX 384u
#define CALSTORE_EXT_MAX_BYTES (CALSTORE_EXT_HEAD + CALSTORE_PARAMS_MAX + 4u)
/* the sector size an extension needs (smaller: calstore_save_ext returns HAL_ENOSPC) */
#define CALSTORE_SLOT_V2_BYTES (CALSTORE_EXT_OFFSET + CALSTORE_EXT_MAX_BYTES)

typedef enum {
    CALSTORE_EXT_NONE = 0,    /* a version 1 record, or no record */
    CALSTORE_EXT_OK = 1,
    CALSTORE_EXT_NEWER = 2,   /* an unknown (newer) version: refused */
    CALSTORE_EXT_CORRUPT = 3, /* refused */
} calstore_ext_status_t;

typedef struct {
    uint8_t status;       /* calstore_ext_status_t, on load */
    uint8_t version;      /* the version byte read (0: no extension) */
    uint16_t params_len;  /* bytes in params */
    uint8_t dtc[CALSTORE_DTC_N];
    uint8_t params[CALSTORE_PARAMS_MAX];
} calstore_ext_t;

/* calstore_load, and the newest valid record's extension in *ext (always written, except
 * on HAL_EINVAL; refused or absent: params_len 0, DTC bytes 0xFF). */
int calstore_load_ext(hal_t *hal, calstore_t *cs, cal_record_t *rec, calstore_ext_t *ext);

/* calstore_save of *rec with the extension *ext (params_len <= CALSTORE_PARAMS_MAX, else
 * HAL_EINVAL), power-safe as calstore_save. HAL_ENOSPC when the sectors are smaller than
 * CALSTORE_SLOT_V2_BYTES. */
int calstore_save_ext(hal_t *hal, calstore_t *cs, const cal_record_t *rec,
                      const calstore_ext_t *ext);

/* The one extension buffer of calstore_save (the newest record's extension, carried on
 * with the new calibration) and of nvstore.c (the record it reads or writes): static, off
 * the stack, one for both as calstore is not reentrant. Each call that uses it fills it
 * (calstore_load_ext, with a hal) before it reads it: nothing in it outlives the call. */
extern calstore_ext_t calstore_ext_buf;

/*
 * Read both slots and return the newest valid record.
 *   hal: its NVM region must have >= 2 sectors of >= CALSTORE_SLOT_BYTES bytes.
 *   cs:  out: seq and slot of the record returned, or {0, -1}.
 *   rec: out: the newest valid record, or the defaults {0, 0, 0, CAL_SRC_NONE}.
 * Returns CALSTORE_OK (*rec = newest valid record); CALSTORE_EMPTY (the 36 bytes of both
 * slots are erased: defaults, not an error); CALSTORE_CORRUPT (no valid record, but some
 * slot is not erased: defaults; the caller flags it. An interrupted first save ends here
 * too: its slot is neither valid nor erased); HAL_EINVAL (a NULL argument), HAL_ENOSPC
 * (the region is too small), or the HAL's error from hal_nvm_read (defaults).
 * *cs and *rec are written on every return except HAL_EINVAL.
 */
int calstore_load(hal_t *hal, calstore_t *cs, cal_record_t *rec);

/*
 * Store *rec as the new newest record, power-safe (see above). The newest record's
 * extension, if it has a valid one, is written again with it (calstore_save_ext), so a
 * calibration save keeps the stored parameters; without one the slot is the 36-byte
 * version 1 record only.
 *   cs: in: from calstore_load, calstore_save or calstore_erase. Save does not trust it
 *       to choose the slot: it reads both slots again, so a stale cs (an hal_nvm_erase
 *       behind its back, a save without a load) can never overwrite the newest record.
 *       Its seq is used only when no slot is valid: the record gets cs->seq + 1.
 *       out: the seq and slot of the record written, on success only.
 * Returns 0; HAL_EINVAL (a NULL argument, or *rec outside the payload range: nothing is
 * written); HAL_ENOSPC (the region is too small); HAL_EIO if the record does not read
 * back as written (it is then not committed); or the HAL's error from an NVM call. On any
 * error the previous newest record is still the one calstore_load returns.
 */
int calstore_save(hal_t *hal, calstore_t *cs, const cal_record_t *rec);

/*
 * Erase both slots: calstore_load then returns CALSTORE_EMPTY. The slot that does not
 * hold the newest record is erased first, so a power loss in between leaves the newest
 * record, as if the erase had not been asked for. cs becomes {0, -1} on success.
 * Returns 0, HAL_EINVAL (a NULL argument), HAL_ENOSPC, or the HAL's error.
 */
int calstore_erase(hal_t *hal, calstore_t *cs);

/* The CRC-32 above of data[0..len) (exposed for tests and tools). */
uint32_t calstore_crc32(const uint8_t *data, size_t len);

#endif /* NAVECU_CALSTORE_H */
