/* codec_check.c - the codec invariants of codec_check.h. */
#include "codec_check.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "fuzz_fail.h"
#include "navecu_can.h"

/* the generated per-message checks and their table (gen_codec_checks.py) */
#include "codec_checks.inc"

void codec_fail(const codec_ctx_t *c, const char *sig, const char *what, double a, double b)
{
    fuzz_fail("codec: frame 0x%03X %s%s%s: %s (%.9g, %.9g)", (unsigned)c->id,
              c->msg != NULL ? c->msg : "?", sig[0] != '\0' ? "." : "", sig, what, a, b);
}

float codec_next_float(codec_ctx_t *c, int *have)
{
    float x = 0.0f;
    *have = 0;
    if (c->phys != NULL && c->phys_pos + 4u <= c->n_phys) {
        memcpy(&x, c->phys + c->phys_pos, sizeof x);
        c->phys_pos += 4u;
        *have = 1;
    }
    return x;
}

int codec_raw_roundtrip_ok(double raw, double raw2)
{
    /* decode is float32: raw values beyond 2^22 lose their last bits in (float)raw */
    return fabs(raw2 - raw) <= 0.5 + fabs(raw) * 0x1p-22;
}

int codec_phys_roundtrip_ok(double x, double back, double lsb)
{
    /* half an LSB, plus the float32 rounding of x / scale, (float)raw and raw * scale */
    return fabs(back - x) <= 0.5 * fabs(lsb) * (1.0 + 1e-6) + fabs(x) * 0x1p-21 + 1e-30;
}

int codec_check_frame(codec_ctx_t *c, uint32_t id, const uint8_t d[8])
{
    for (size_t k = 0u; k < CODEC_N_MSGS; k++) {
        if (codec_msgs[k].id == id) {
            c->id = id;
            codec_msgs[k].check(c, d);
            return 1;
        }
    }
    return 0;
}

void codec_check_all(codec_ctx_t *c, const uint8_t d[8])
{
    for (size_t k = 0u; k < CODEC_N_MSGS; k++) {
        c->id = codec_msgs[k].id;
        codec_msgs[k].check(c, d);
    }
}

size_t codec_n_msgs(void)
{
    return CODEC_N_MSGS;
}

uint32_t codec_msg_id(size_t k)
{
    return k < CODEC_N_MSGS ? codec_msgs[k].id : 0u;
}
