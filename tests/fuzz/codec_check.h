/*
 * codec_check.h - invariants of the generated CAN codec (firmware/can/gen/navecu_can.h),
 * checked message by message on any 8 bytes. Shared by the fuzz harnesses: fuzz_codec
 * checks every message on arbitrary bytes, fuzz_app checks every frame the application
 * sends (with CODEC_REQUIRE_RANGE: an output must decode to values inside the DBC ranges).
 *
 * Per signal of the unpacked message (CODEC_SIG):
 *  - decode(raw) is finite;
 *  - with CODEC_REQUIRE_RANGE, is_in_range(raw);
 *  - raw in range => decode(raw) is in the physical range (to 1 ulp: cantools' float
 *    codec decodes raw 32767 x 0.001 to 32.767002, one ulp above the float 32.767f its
 *    range check compares with; tests/fuzz/crashes/fuzz_codec/heading-correction-max)
 *    and encode(decode(raw)) gives
 *    raw back (within the float32 precision of decode for raw values beyond 2^22);
 *  - for a physical value x from the fuzz input with is_in_phys_range(x) (the codec's
 *    documented precondition of encode): encode(x) is in range and decode(encode(x)) is
 *    within half an LSB of x (plus float32 rounding).
 * Raw-only signals (CODEC_SIG_RAW_ONLY) get only the range check.
 * Per message: unpack of 8 bytes returns 0, unpack(pack(unpack(d))) == unpack(d), and an
 * unpack of fewer than 8 bytes returns -EINVAL without reading them (ASan checks that).
 *
 * The per-message functions are generated from the codec header at build time
 * (tests/fuzz/gen_codec_checks.py -> build/fuzz/gen/codec_checks.inc), so a DBC change
 * can never make them stale.
 */
#ifndef NAVECU_FUZZ_CODEC_CHECK_H
#define NAVECU_FUZZ_CODEC_CHECK_H

#include <stddef.h>
#include <stdint.h>

#define CODEC_REQUIRE_RANGE 0x1u /* every raw signal value must be is_in_range */

typedef struct {
    uint32_t flags;             /* CODEC_REQUIRE_RANGE */
    const uint8_t *phys;        /* bytes for physical values, 4 per signal (NULL: none) */
    size_t n_phys, phys_pos;
    const uint8_t *short_buf;   /* a buffer of exactly short_len (< 8) bytes, or NULL */
    size_t short_len;
    const char *msg;            /* the message being checked (failure reports) */
    uint32_t id;                /* the frame identifier being checked */
} codec_ctx_t;

typedef struct {
    uint32_t id;
    const char *name;
    void (*check)(codec_ctx_t *c, const uint8_t d[8]);
} codec_msg_t;

/* Check the message with identifier id on d; returns 0 if the codec has no such message. */
int codec_check_frame(codec_ctx_t *c, uint32_t id, const uint8_t d[8]);

/* Check every message of the codec on d. */
void codec_check_all(codec_ctx_t *c, const uint8_t d[8]);

/* Number of messages in the codec, and the identifier of message k. */
size_t codec_n_msgs(void);
uint32_t codec_msg_id(size_t k);

/* helpers of CODEC_SIG */
_Noreturn void codec_fail(const codec_ctx_t *c, const char *sig, const char *what, double a,
                          double b);
float codec_next_float(codec_ctx_t *c, int *have);
int codec_raw_roundtrip_ok(double raw, double raw2);
int codec_phys_roundtrip_ok(double x, double back, double lsb);

#define CODEC_SIG(c, sig, raw, pfx)                                                          \
    do {                                                                                     \
        const double lsb_ = (double)pfx##_decode(1) - (double)pfx##_decode(0);               \
        const float x_ = pfx##_decode(raw);                                                  \
        const int in_ = pfx##_is_in_range(raw) ? 1 : 0;                                     \
        if (!isfinite(x_)) {                                                                 \
            codec_fail(c, sig, "decode(raw) is not finite", (double)(raw), (double)x_);      \
        }                                                                                    \
        if (((c)->flags & CODEC_REQUIRE_RANGE) != 0u && !in_) {                              \
            codec_fail(c, sig, "raw value outside the DBC range", (double)(raw), (double)x_); \
        }                                                                                    \
        if (in_) {                                                                           \
            if (!pfx##_is_in_phys_range(x_) &&                                              \
                !pfx##_is_in_phys_range(nextafterf(x_, 0.0f))) {                            \
                codec_fail(c, sig, "raw in range but decode(raw) not in the physical range", \
                           (double)(raw), (double)x_);                                       \
            }                                                                                \
            if (!codec_raw_roundtrip_ok((double)(raw), (double)pfx##_encode(x_))) {          \
                codec_fail(c, sig, "encode(decode(raw)) != raw", (double)(raw),              \
                           (double)pfx##_encode(x_));                                        \
            }                                                                                \
        }                                                                                    \
        int have_ = 0;                                                                       \
        const float y_ = codec_next_float(c, &have_);                                        \
        if (have_ && pfx##_is_in_phys_range(y_)) {                                           \
            if (!pfx##_is_in_range(pfx##_encode(y_))) {                                      \
                codec_fail(c, sig, "x in physical range but encode(x) out of range",         \
                           (double)y_, (double)pfx##_encode(y_));                            \
            }                                                                                \
            const double back_ = (double)pfx##_decode(pfx##_encode(y_));                     \
            if (!codec_phys_roundtrip_ok((double)y_, back_, lsb_)) {                         \
                codec_fail(c, sig, "decode(encode(x)) more than half an LSB from x",         \
                           (double)y_, back_);                                               \
            }                                                                                \
        }                                                                                    \
    } while (0)

/* A 32-bit integer signal of scale 1 (tests/fuzz/gen_codec_checks.py, "raw-only"): the
 * firmware reads it raw, never through the float32 API, which cannot hold it; only the
 * DBC range is checked here (the pack/unpack identity is checked per message). */
#define CODEC_SIG_RAW_ONLY(c, sig, raw, pfx)                                                 \
    do {                                                                                     \
        if (((c)->flags & CODEC_REQUIRE_RANGE) != 0u && !pfx##_is_in_range(raw)) {           \
            codec_fail(c, sig, "raw value outside the DBC range", (double)(raw), 0.0);       \
        }                                                                                    \
    } while (0)

#define CODEC_SHORT(c, unpack, type, d)                                                      \
    do {                                                                                     \
        if ((c)->short_buf != NULL && (c)->short_len < 8u) {                                 \
            type t_;                                                                         \
            memset(&t_, 0, sizeof t_);                                                       \
            const int rc_ = unpack(&t_, (c)->short_buf, (c)->short_len);                     \
            if (rc_ != -EINVAL) {                                                            \
                codec_fail(c, "", "unpack of fewer than 8 bytes did not return -EINVAL",      \
                           (double)(c)->short_len, (double)rc_);                             \
            }                                                                                \
        }                                                                                    \
        (void)(d);                                                                           \
    } while (0)

#endif
