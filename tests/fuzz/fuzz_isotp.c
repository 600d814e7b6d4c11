/*
 * fuzz_isotp.c - libFuzzer harness: the ISO-TP transport (firmware/diag/isotp.h) on any
 * configuration and any sequence of received frames, polls, sends, reads, refusing
 * transmit queues and clock steps (forwards, backwards, far).
 *
 * Input: a configuration of 8 bytes, then records until the input ends:
 *   cfg:  flags(1: bit0 padding, bit1 refuse from the start) pad_byte(1) block_size(1)
 *         st_min(1, a reserved value becomes 0x7F) wft_max(1) wait_rx_max(1)
 *         timeout_ms(1: N_As = N_Ar = N_Bs = N_Cr = 1 + 4 x this) wait_period_ms(1: 1 + this)
 *   op 0  frame:   dt(1, x 100 us) where(1: 0 rx_id, 1 tx_id, 2 rx_id extended, 3 other)
 *                  dlc(1, mod 9) data(8)
 *   op 1  poll:    dt(2, LE, x 10 us)
 *   op 2  send:    dt(1, x 100 us) len(2, LE, mod ISOTP_MAX_LEN + 2: 0 and MAX + 1 refused)
 *   op 3  receive: cap(2, LE)
 *   op 4  the transmit function refuses (or accepts again) every frame
 *   op 5  clock:   step(1): < 128 backwards step x 1 ms, else forwards (step - 128) x 100 ms
 *
 * Invariants (abort on violation):
 *  - the state is always valid: both states and results in their enums, the FC due is CTS,
 *    WAIT or OVFLW, sequence numbers < 16, rx_pos <= rx_len <= ISOTP_MAX_LEN,
 *    ready_len <= ISOTP_MAX_LEN, a reception waiting for CFs has 6 <= rx_pos < rx_len and
 *    an empty ready buffer, tx_pos <= tx_len <= ISOTP_MAX_LEN, tx_data set exactly while a
 *    transmission is in progress;
 *  - no counter ever decreases; rx_msgs and tx_msgs grow by at most one per call;
 *  - every frame handed to the transmit function is a classic frame on tx_id, DLC 8 with
 *    the unused bytes = pad_byte when padding is on, else the shortest DLC, with a PCI of
 *    SF/FF/CF/FC laid out as ISO 15765-2 says (FC status 0..2, SF_DL 1..7, FF_DL 8..4095);
 *  - a reference receiver written from the standard reassembles the ECU's SF/FF/CFs: the
 *    sequence numbers run 1, 2, .. 15, 0, .., no CF exceeds FF_DL, and every transmission the
 *    channel reports complete (tx_msgs + 1) is exactly the bytes given to isotp_send;
 *  - isotp_receive returns a length <= cap and <= ISOTP_MAX_LEN, and a single frame
 *    received with the buffer free comes back byte for byte;
 *  - out-of-bounds reads or writes: AddressSanitizer.
 */
#include <stdint.h>
#include <string.h>

#include "fuzz_fail.h"
#include "isotp.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define RX_ID 0x7A0u
#define TX_ID 0x7A8u
#define OTHER_ID 0x7DFu

static isotp_t ch;
static uint8_t msg[ISOTP_MAX_LEN + 1u];
static uint8_t out[ISOTP_MAX_LEN + 8u];

/* the reference receiver of what the channel sends, and the message it was given */
static struct {
    int refuse;
    uint8_t padding, pad;
    /* reassembly */
    int active;          /* FF seen, CFs expected */
    size_t len, pos;
    unsigned sn;
    uint8_t buf[ISOTP_MAX_LEN];
    int complete;        /* the last SF, or the last CF of a message, was seen */
    size_t complete_len;
    /* what isotp_send was given */
    size_t sent_len;
    uint8_t sent[ISOTP_MAX_LEN];
} ref;

static void check_frame(const hal_can_frame_t *f)
{
    if (f->id != TX_ID || f->extended != 0u || f->dlc == 0u || f->dlc > 8u) {
        fuzz_fail("frame sent: id 0x%X ext %u dlc %u", (unsigned)f->id, f->extended, f->dlc);
    }
    const unsigned pci = f->data[0] >> 4;
    unsigned used = 0u;
    if (pci == 0u) {
        const unsigned sf_dl = f->data[0] & 0x0Fu;
        if (sf_dl < 1u || sf_dl > 7u) {
            fuzz_fail("SF_DL %u", sf_dl);
        }
        used = 1u + sf_dl;
        if (ref.active) {
            fuzz_fail("an SF while a segmented transmission is in progress");
        }
        memcpy(ref.buf, &f->data[1], sf_dl);
        ref.complete = 1;
        ref.complete_len = sf_dl;
    } else if (pci == 1u) {
        const size_t ff_dl = ((size_t)(f->data[0] & 0x0Fu) << 8) | f->data[1];
        if (ff_dl < 8u || ff_dl > ISOTP_MAX_LEN || f->dlc != 8u) {
            fuzz_fail("FF_DL %zu, dlc %u", ff_dl, f->dlc);
        }
        if (ref.active) {
            fuzz_fail("an FF while a segmented transmission is in progress");
        }
        used = 8u;
        memcpy(ref.buf, &f->data[2], 6u);
        ref.active = 1;
        ref.len = ff_dl;
        ref.pos = 6u;
        ref.sn = 1u;
    } else if (pci == 2u) {
        if (!ref.active) {
            fuzz_fail("a CF with no FF before it");
        }
        if ((f->data[0] & 0x0Fu) != ref.sn) {
            fuzz_fail("CF SN %u, expected %u", f->data[0] & 0x0Fu, ref.sn);
        }
        const size_t take = (ref.len - ref.pos) < 7u ? (ref.len - ref.pos) : 7u;
        used = 1u + (unsigned)take;
        memcpy(&ref.buf[ref.pos], &f->data[1], take);
        ref.pos += take;
        ref.sn = (ref.sn + 1u) & 0x0Fu;
        if (ref.pos == ref.len) {
            ref.active = 0;
            ref.complete = 1;
            ref.complete_len = ref.len;
        }
    } else if (pci == 3u) {
        if ((f->data[0] & 0x0Fu) > 2u) {
            fuzz_fail("FC flow status %u", f->data[0] & 0x0Fu);
        }
        used = 3u;
    } else {
        fuzz_fail("PCI type %u sent", pci);
    }
    if (ref.padding) {
        if (f->dlc != 8u) {
            fuzz_fail("padding on, DLC %u", f->dlc);
        }
        for (unsigned b = used; b < 8u; b++) {
            if (f->data[b] != ref.pad) {
                fuzz_fail("padding byte %u is 0x%02X, not 0x%02X", b, f->data[b], ref.pad);
            }
        }
    } else if (f->dlc != used) {
        fuzz_fail("padding off, DLC %u for %u bytes", f->dlc, used);
    }
}

static int tx(void *user, const hal_can_frame_t *f)
{
    (void)user;
    if (ref.refuse) {
        return HAL_ENOSPC;
    }
    check_frame(f);
    return 0;
}

static void check_state(const isotp_t *c, const isotp_counters_t *before)
{
    if ((unsigned)c->rx_state > (unsigned)ISOTP_RX_WAIT_CF ||
        (unsigned)c->tx_state > (unsigned)ISOTP_TX_WAIT_FC ||
        (unsigned)c->rx_result > (unsigned)ISOTP_N_NONE ||
        (unsigned)c->tx_result > (unsigned)ISOTP_N_NONE) {
        fuzz_fail("state out of its enum: rx %u tx %u", (unsigned)c->rx_state, (unsigned)c->tx_state);
    }
    if (c->rx_state == ISOTP_RX_FC && c->rx_fc > ISOTP_FS_OVFLW) {
        fuzz_fail("FC due with flow status %u", c->rx_fc);
    }
    if (c->rx_sn > 15u || c->tx_sn > 15u) {
        fuzz_fail("sequence numbers %u %u", c->rx_sn, c->tx_sn);
    }
    if (c->rx_pos > c->rx_len || c->rx_len > ISOTP_MAX_LEN || c->ready_len > ISOTP_MAX_LEN) {
        fuzz_fail("reception %u of %u, ready %u", c->rx_pos, c->rx_len, c->ready_len);
    }
    if (c->rx_state == ISOTP_RX_WAIT_CF &&
        (c->rx_pos < 6u || c->rx_pos >= c->rx_len || c->ready_len != 0u)) {
        fuzz_fail("awaiting CFs at %u of %u with %u bytes ready", c->rx_pos, c->rx_len, c->ready_len);
    }
    if (c->tx_pos > c->tx_len || c->tx_len > ISOTP_MAX_LEN) {
        fuzz_fail("transmission %u of %u", c->tx_pos, c->tx_len);
    }
    if ((c->tx_state != ISOTP_TX_IDLE) != (c->tx_data != NULL) ||
        (c->tx_state != ISOTP_TX_IDLE && c->tx_len == 0u)) {
        fuzz_fail("tx_data %p in state %u", (const void *)c->tx_data, (unsigned)c->tx_state);
    }
    const uint32_t *a = (const uint32_t *)(const void *)before;
    const uint32_t *b = (const uint32_t *)(const void *)&c->cnt;
    for (size_t k = 0; k < sizeof(isotp_counters_t) / sizeof(uint32_t); k++) {
        if (b[k] < a[k]) {
            fuzz_fail("counter %zu went down: %u -> %u", k, a[k], b[k]);
        }
    }
    if (c->cnt.rx_msgs > before->rx_msgs + 1u || c->cnt.tx_msgs > before->tx_msgs + 1u) {
        fuzz_fail("more than one message completed in one call");
    }
    if (c->cnt.tx_msgs == before->tx_msgs + 1u) {
        if (!ref.complete || ref.complete_len != ref.sent_len ||
            memcmp(ref.buf, ref.sent, ref.sent_len) != 0) {
            fuzz_fail("transmission reported complete, but the frames carried %zu bytes of "
                      "the %zu given (or others)", ref.complete ? ref.complete_len : 0u, ref.sent_len);
        }
    }
    if (c->tx_state == ISOTP_TX_IDLE) {
        ref.active = 0; /* an aborted or finished transmission: the next starts afresh */
    }
    ref.complete = 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 8u) {
        return 0;
    }
    memset(&ref, 0, sizeof ref);
    isotp_config_t cfg;
    isotp_config_defaults(&cfg, RX_ID, TX_ID);
    cfg.padding = (uint8_t)(data[0] & 1u);
    ref.refuse = (data[0] & 2u) != 0u;
    cfg.pad_byte = data[1];
    cfg.block_size = data[2];
    cfg.st_min = data[3];
    if (isotp_st_min_us(cfg.st_min) == 127000u) {
        cfg.st_min = 0x7Fu;
    }
    cfg.wft_max = data[4];
    cfg.wait_rx_max = data[5];
    const uint32_t timeout_us = (1u + 4u * data[6]) * 1000u;
    cfg.n_as_us = cfg.n_ar_us = cfg.n_bs_us = cfg.n_cr_us = timeout_us;
    cfg.wait_period_us = (1u + data[7]) * 1000u;
    if (isotp_init(&ch, &cfg) != 0) {
        fuzz_fail("isotp_init refused a valid configuration");
    }
    ref.padding = cfg.padding;
    ref.pad = cfg.pad_byte;
    uint64_t now = 1000000000u; /* far from 0: steps back stay positive */
    size_t i = 8u;
    while (i < size) {
        const uint8_t op = (uint8_t)(data[i] % 6u);
        i++;
        isotp_counters_t before = ch.cnt;
        if (op == 0u) {
            if (i + 11u > size) {
                break;
            }
            hal_can_frame_t f;
            memset(&f, 0, sizeof f);
            now += (uint64_t)data[i] * 100u;
            const unsigned where = data[i + 1u] % 4u;
            f.id = where == 1u ? TX_ID : (where == 3u ? OTHER_ID : RX_ID);
            f.extended = where == 2u ? 1u : 0u;
            f.dlc = (uint8_t)(data[i + 2u] % 9u);
            memcpy(f.data, &data[i + 3u], 8u);
            i += 11u;
            const int was_free = ch.ready_len == 0u;
            const uint32_t msgs = ch.cnt.rx_msgs;
            const int r = isotp_on_frame(&ch, &f, now);
            if (r != (where == 0u ? 1 : 0)) {
                fuzz_fail("isotp_on_frame returned %d for a frame on %s", r,
                          where == 0u ? "rx_id" : "another ID");
            }
            check_state(&ch, &before);
            const unsigned sf_dl = f.data[0] & 0x0Fu;
            if (where == 0u && f.dlc > 0u && (f.data[0] >> 4) == 0u && sf_dl >= 1u && sf_dl <= 7u &&
                sf_dl < f.dlc && was_free) {
                /* a valid SF with the buffer free: received, byte for byte */
                size_t len = 0u;
                if (ch.cnt.rx_msgs != msgs + 1u || isotp_receive(&ch, out, sizeof out, &len) != 0 ||
                    len != sf_dl || memcmp(out, &f.data[1], sf_dl) != 0) {
                    fuzz_fail("a valid SF of %u bytes was not received as sent", sf_dl);
                }
            }
        } else if (op == 1u) {
            if (i + 2u > size) {
                break;
            }
            now += (uint64_t)(data[i] | (unsigned)data[i + 1u] << 8) * 10u;
            i += 2u;
            const int n = isotp_poll(&ch, now, tx, NULL);
            if (n < 0 || n > (int)ISOTP_POLL_BURST) {
                fuzz_fail("isotp_poll returned %d", n);
            }
            check_state(&ch, &before);
        } else if (op == 2u) {
            if (i + 3u > size) {
                break;
            }
            now += (uint64_t)data[i] * 100u;
            const size_t len = (size_t)(data[i + 1u] | (unsigned)data[i + 2u] << 8) % (ISOTP_MAX_LEN + 2u);
            i += 3u;
            const int busy = isotp_tx_busy(&ch);
            for (size_t k = 0; busy == 0 && k < len; k++) {
                msg[k] = (uint8_t)(k * 13u + len); /* never under a transmission: not copied */
            }
            const int r = isotp_send(&ch, msg, len, now);
            const int want = (len == 0u || len > ISOTP_MAX_LEN) ? HAL_EINVAL : (busy ? HAL_EAGAIN : 0);
            if (r != want) {
                fuzz_fail("isotp_send(%zu) returned %d, expected %d", len, r, want);
            }
            if (r == 0) {
                memcpy(ref.sent, msg, len);
                ref.sent_len = len;
                ref.active = 0;
            }
            check_state(&ch, &before);
        } else if (op == 3u) {
            if (i + 2u > size) {
                break;
            }
            const size_t cap = (size_t)(data[i] | (unsigned)data[i + 1u] << 8) % (sizeof out + 1u);
            i += 2u;
            const uint16_t ready = ch.ready_len;
            size_t len = 0u;
            const int r = isotp_receive(&ch, out, cap, &len);
            if (r == 0 && (len > cap || len > ISOTP_MAX_LEN || len != ready || len == 0u)) {
                fuzz_fail("isotp_receive gave %zu bytes for cap %zu (ready %u)", len, cap, ready);
            }
            if (r != 0 && r != HAL_EAGAIN && r != HAL_ENOSPC) {
                fuzz_fail("isotp_receive returned %d", r);
            }
            check_state(&ch, &before);
        } else if (op == 4u) {
            ref.refuse = !ref.refuse;
        } else {
            if (i + 1u > size) {
                break;
            }
            const uint8_t step = data[i];
            i++;
            if (step < 128u) {
                now -= (uint64_t)step * 1000u;
            } else {
                now += (uint64_t)(step - 128u) * 100000u;
            }
        }
    }
    return 0;
}
