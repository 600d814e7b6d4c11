/*
 * fuzz_codec.c - libFuzzer harness: the frame decoder and validator on arbitrary frames.
 *
 * Input: id (4 bytes, little-endian), dlc (1 byte), data (8 bytes; missing bytes are 0),
 * a bit index (1 byte), then the rest: physical values (4-byte floats) for the encode
 * round trip, and alive counters for the E2E counter model.
 *
 * Invariants (abort on violation):
 *  - codec (codec_check.h): every generated unpack succeeds on any 8 bytes and refuses
 *    fewer without reading them; every signal decodes finite; in-range raw values survive
 *    decode/encode; in-range physical values survive encode/decode within half an LSB;
 *    pack/unpack round-trips; for every message of the DBC, whatever the frame's ID;
 *  - E2E (e2e.h): the CRC equals a bitwise CRC-8 SAE J1850 written from the spec, over
 *    the ID's 2 bytes and bytes 0..6; e2e_crc_ok agrees with it; a protected frame passes
 *    and any single flipped bit (data, CRC byte or ID) fails; the same for the IMU pair
 *    CRC; e2e_counter_step and e2e_counter_next follow the spec's counter model.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "codec_check.h"
#include "e2e.h"
#include "fuzz_fail.h"
#include "navecu_can.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* CRC-8 SAE J1850 bit by bit, straight from the definition (poly 0x1D, MSB first) */
static uint8_t ref_crc8(uint8_t crc, const uint8_t *p, size_t n)
{
    for (size_t k = 0u; k < n; k++) {
        crc ^= p[k];
        for (int b = 0; b < 8; b++) {
            crc = (uint8_t)((crc & 0x80u) != 0u ? (uint8_t)(crc << 1) ^ 0x1Du : (uint8_t)(crc << 1));
        }
    }
    return crc;
}

static uint8_t ref_frame_crc(uint32_t id, const uint8_t d[8])
{
    const uint8_t idb[2] = {(uint8_t)id, (uint8_t)(id >> 8)};
    uint8_t crc = ref_crc8(0xFFu, idb, 2u);
    crc = ref_crc8(crc, d, 7u);
    return (uint8_t)(crc ^ 0xFFu);
}

static uint8_t ref_pair_crc(uint32_t id, const uint8_t first[8], const uint8_t second[8])
{
    const uint8_t idb[2] = {(uint8_t)id, (uint8_t)(id >> 8)};
    uint8_t crc = ref_crc8(0xFFu, idb, 2u);
    crc = ref_crc8(crc, first, 8u);
    crc = ref_crc8(crc, second, 7u);
    return (uint8_t)(crc ^ 0xFFu);
}

static void check_e2e(uint32_t id, const uint8_t d[8], const uint8_t d2[8], unsigned bit,
                      const uint8_t *rest, size_t n_rest)
{
    /* the plain CRC over any bytes, against the reference */
    const uint8_t got = (uint8_t)(e2e_crc8_update(0xFFu, rest, (uint32_t)n_rest) ^ 0xFFu);
    const uint8_t want = (uint8_t)(ref_crc8(0xFFu, rest, n_rest) ^ 0xFFu);
    if (got != want) {
        fuzz_fail("e2e_crc8_update over %zu bytes: 0x%02X, spec 0x%02X", n_rest, got, want);
    }
    const uint8_t fc = e2e_frame_crc(id, d);
    if (fc != ref_frame_crc(id, d)) {
        fuzz_fail("e2e_frame_crc(0x%X): 0x%02X, spec 0x%02X", (unsigned)id, fc, ref_frame_crc(id, d));
    }
    if (e2e_crc_ok(id, d) != (d[7] == fc ? 1 : 0)) {
        fuzz_fail("e2e_crc_ok(0x%X) disagrees with the CRC", (unsigned)id);
    }
    uint8_t p[8];
    memcpy(p, d, 8u);
    e2e_protect(id, p);
    if (!e2e_crc_ok(id, p) || memcmp(p, d, 7u) != 0) {
        fuzz_fail("e2e_protect(0x%X): the frame does not pass, or bytes 0..6 changed", (unsigned)id);
    }
    const unsigned fb = bit % 64u;
    p[fb / 8u] ^= (uint8_t)(1u << (fb % 8u));
    if (e2e_crc_ok(id, p)) {
        fuzz_fail("E2E: bit %u flipped in a protected frame 0x%X is not detected", fb, (unsigned)id);
    }
    p[fb / 8u] ^= (uint8_t)(1u << (fb % 8u));
    const uint32_t id_flip = id ^ (1u << (bit % 16u));
    if (e2e_crc_ok(id_flip, p)) {
        fuzz_fail("E2E: frame of 0x%X accepted as 0x%X", (unsigned)id, (unsigned)id_flip);
    }
    /* the IMU pair CRC */
    const uint8_t pc = e2e_pair_crc(id, d, d2);
    if (pc != ref_pair_crc(id, d, d2)) {
        fuzz_fail("e2e_pair_crc(0x%X): 0x%02X, spec 0x%02X", (unsigned)id, pc, ref_pair_crc(id, d, d2));
    }
    uint8_t f1[8], f2[8];
    memcpy(f1, d, 8u);
    memcpy(f2, d2, 8u);
    const unsigned pb = bit % 120u; /* 64 bits of the first frame, 56 of the second */
    if (pb < 64u) {
        f1[pb / 8u] ^= (uint8_t)(1u << (pb % 8u));
    } else {
        f2[(pb - 64u) / 8u] ^= (uint8_t)(1u << (pb % 8u));
    }
    if (e2e_pair_crc(id, f1, f2) == pc) {
        fuzz_fail("E2E pair: bit %u flipped is not detected", pb);
    }
}

/* the alive counter against the spec's model (e2e.h) */
static void check_counter(const uint8_t *rest, size_t n)
{
    e2e_counter_t c;
    memset(&c, 0, sizeof c);
    int valid = 0;
    unsigned last = 0u;
    for (size_t k = 0u; k < n && k < 64u; k++) {
        const uint8_t v = (uint8_t)(rest[k] % 17u); /* 0..16: the valid range and beyond */
        int want;
        if (v > E2E_COUNTER_MAX) {
            want = -1;
        } else if (!valid) {
            valid = 1;
            last = v;
            want = 1;
        } else {
            want = (int)((v + 15u - last) % 15u);
            if (want != 0) {
                last = v;
            }
        }
        const int got = e2e_counter_step(&c, v);
        if (got != want) {
            fuzz_fail("e2e_counter_step(%u) after %u: %d, spec %d", v, last, got, want);
        }
        if (valid && (c.valid == 0u || c.last != last)) {
            fuzz_fail("e2e_counter_step: state {%u, %u}, spec {1, %u}", c.last, c.valid, last);
        }
        if (v <= E2E_COUNTER_MAX) {
            const uint8_t nx = e2e_counter_next(v);
            if (nx != (v + 1u) % 15u) {
                fuzz_fail("e2e_counter_next(%u) = %u", v, nx);
            }
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    uint8_t in[14];
    memset(in, 0, sizeof in);
    memcpy(in, data, size < sizeof in ? size : sizeof in);
    const uint8_t *rest = size > sizeof in ? data + sizeof in : NULL;
    const size_t n_rest = size > sizeof in ? size - sizeof in : 0u;

    const uint32_t id = (uint32_t)in[0] | (uint32_t)in[1] << 8 | (uint32_t)in[2] << 16 |
                        (uint32_t)in[3] << 24;
    const uint8_t dlc = in[4];
    const uint8_t *d = in + 5;
    const unsigned bit = in[13];

    /* a buffer of exactly dlc bytes (< 8), so that ASan sees any read beyond it */
    uint8_t *short_buf = NULL;
    if (dlc < 8u) {
        short_buf = malloc(dlc > 0u ? dlc : 1u);
        if (short_buf == NULL) {
            return 0;
        }
        memcpy(short_buf, d, dlc);
    }
    codec_ctx_t c;
    memset(&c, 0, sizeof c);
    c.phys = rest;
    c.n_phys = n_rest;
    c.short_buf = short_buf;
    c.short_len = dlc;
    /* the frame's own message with the frame's length, then every message on its bytes */
    (void)codec_check_frame(&c, id, d);
    c.short_buf = NULL;
    codec_check_all(&c, d);
    free(short_buf);

    uint8_t d2[8];
    for (unsigned k = 0u; k < 8u; k++) {
        d2[k] = (uint8_t)(n_rest > k ? rest[n_rest - 1u - k] : d[k] ^ 0x5Au);
    }
    check_e2e(id, d, d2, bit, rest, n_rest);
    check_counter(rest, n_rest);
    return 0;
}
