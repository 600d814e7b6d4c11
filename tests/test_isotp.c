/*
 * test_isotp.c - the ISO 15765-2 transport (firmware/diag/isotp.c): every PDU type sent and
 * received, segmentation of 7, 8, 62 and ISOTP_MAX_LEN (4095) bytes, block size and STmin
 * as sender and receiver, FC WAIT both ways, overflow, every timeout, wrong sequence
 * numbers and a lost consecutive frame, unexpected PDUs, padding and short frames, and two
 * channels talking to each other.
 *
 * The ECU's channel listens on RX_ID and answers on TX_ID; frames "from the tester" are
 * built by hand from the standard's byte layouts (docs/can.md), not by the code under test.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "isotp.h"

#define RX_ID 0x7A0u
#define TX_ID 0x7A8u
#define MS 1000u
#define MAX_SENT 1200u

typedef struct {
    hal_can_frame_t f[MAX_SENT];
    size_t n;
    int refuse; /* 1: the transmit function refuses every frame (queue full) */
} sink_t;

static isotp_t ecu;
static sink_t sink;
static uint8_t msg[ISOTP_MAX_LEN];
static uint8_t got[ISOTP_MAX_LEN];

static int sink_tx(void *user, const hal_can_frame_t *f)
{
    sink_t *s = user;
    if (s->refuse != 0) {
        return HAL_ENOSPC;
    }
    assert_true(s->n < MAX_SENT);
    s->f[s->n] = *f;
    s->n++;
    return 0;
}

static hal_can_frame_t mkframe(uint32_t id, const uint8_t *d, size_t n)
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = (uint8_t)n;
    memcpy(f.data, d, n);
    return f;
}

/* a frame from the tester on RX_ID with exactly the bytes given (DLC = their number) */
#define TESTER(...) mkframe(RX_ID, (const uint8_t[]){__VA_ARGS__}, sizeof((const uint8_t[]){__VA_ARGS__}))

static void pattern(uint8_t *p, size_t n, unsigned seed)
{
    for (size_t i = 0; i < n; i++) {
        p[i] = (uint8_t)(i * 7u + seed + (i >> 8));
    }
}

static void setup_cfg(const isotp_config_t *cfg)
{
    memset(&sink, 0, sizeof sink);
    assert_int_equal(isotp_init(&ecu, cfg), 0);
}

static void setup_default(void)
{
    isotp_config_t cfg;
    isotp_config_defaults(&cfg, RX_ID, TX_ID);
    setup_cfg(&cfg);
}

static int feed(hal_can_frame_t f, uint64_t t)
{
    return isotp_on_frame(&ecu, &f, t);
}

static int poll_at(uint64_t t)
{
    return isotp_poll(&ecu, t, sink_tx, &sink);
}

static void assert_frame(size_t k, uint8_t dlc, const uint8_t *bytes, size_t n)
{
    assert_true(k < sink.n);
    const hal_can_frame_t *f = &sink.f[k];
    assert_int_equal(f->id, TX_ID);
    assert_int_equal(f->extended, 0);
    assert_int_equal(f->dlc, dlc);
    assert_memory_equal(f->data, bytes, n);
}
#define ASSERT_FRAME(k, dlc, ...)                                                            \
    assert_frame(k, dlc, (const uint8_t[]){__VA_ARGS__}, sizeof((const uint8_t[]){__VA_ARGS__}))

/* ---------------------------------------------------------------- configuration */

static void test_config_and_init(void **state)
{
    (void)state;
    isotp_config_t cfg;
    isotp_config_defaults(&cfg, RX_ID, TX_ID);
    assert_int_equal(cfg.padding, 1);
    assert_int_equal(cfg.pad_byte, 0xCC);
    assert_int_equal(cfg.block_size, 8);
    assert_int_equal(cfg.st_min, 0);
    assert_int_equal(cfg.n_as_us, 1000000u);
    assert_int_equal(cfg.n_ar_us, 1000000u);
    assert_int_equal(cfg.n_bs_us, 1000000u);
    assert_int_equal(cfg.n_cr_us, 1000000u);
    assert_int_equal(isotp_init(&ecu, &cfg), 0);
    assert_int_equal(ecu.rx_result, ISOTP_N_NONE);
    assert_int_equal(ecu.tx_result, ISOTP_N_NONE);
    assert_int_equal(isotp_tx_busy(&ecu), 0);
    assert_int_equal(isotp_rx_busy(&ecu), 0);

    isotp_config_t bad = cfg;
    assert_int_equal(isotp_init(NULL, &cfg), HAL_EINVAL);
    assert_int_equal(isotp_init(&ecu, NULL), HAL_EINVAL);
    bad.rx_id = 0x800u;
    assert_int_equal(isotp_init(&ecu, &bad), HAL_EINVAL);
    bad = cfg;
    bad.tx_id = RX_ID;
    assert_int_equal(isotp_init(&ecu, &bad), HAL_EINVAL);
    bad = cfg;
    bad.padding = 2u;
    assert_int_equal(isotp_init(&ecu, &bad), HAL_EINVAL);
    bad = cfg;
    bad.n_cr_us = 0u;
    assert_int_equal(isotp_init(&ecu, &bad), HAL_EINVAL);
    bad = cfg;
    bad.wait_period_us = 0u;
    assert_int_equal(isotp_init(&ecu, &bad), HAL_EINVAL);
    /* the ECU never announces a reserved STmin */
    const uint8_t reserved[] = {0x80u, 0xA0u, 0xF0u, 0xFAu, 0xFFu};
    for (size_t i = 0; i < sizeof reserved; i++) {
        bad = cfg;
        bad.st_min = reserved[i];
        assert_int_equal(isotp_init(&ecu, &bad), HAL_EINVAL);
    }
    bad = cfg;
    bad.st_min = 0xF9u;
    assert_int_equal(isotp_init(&ecu, &bad), 0);
}

/* STmin: 0x00..0x7F ms, 0xF1..0xF9 100..900 us, every reserved value 127 ms */
static void test_st_min_decoding(void **state)
{
    (void)state;
    for (unsigned raw = 0; raw <= 0xFFu; raw++) {
        uint32_t want = 127000u;
        if (raw <= 0x7Fu) {
            want = raw * 1000u;
        } else if (raw >= 0xF1u && raw <= 0xF9u) {
            want = (raw - 0xF0u) * 100u;
        }
        assert_int_equal(isotp_st_min_us((uint8_t)raw), want);
    }
    assert_int_equal(isotp_st_min_us(0x7Fu), 127000u);
    assert_int_equal(isotp_st_min_us(0xF1u), 100u);
    assert_int_equal(isotp_st_min_us(0xF9u), 900u);
}

/* ---------------------------------------------------------------- single frames */

static void test_send_single_frame_padded(void **state)
{
    (void)state;
    setup_default();
    const uint8_t one[1] = {0x3Eu};
    assert_int_equal(isotp_send(&ecu, one, 1u, 0u), 0);
    assert_int_equal(isotp_tx_busy(&ecu), 1);
    assert_int_equal(poll_at(0u), 1);
    ASSERT_FRAME(0, 8, 0x01, 0x3E, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC);
    assert_int_equal(isotp_tx_busy(&ecu), 0);
    assert_int_equal(ecu.tx_result, ISOTP_N_OK);
    assert_int_equal(ecu.cnt.tx_msgs, 1);

    pattern(msg, 7u, 1u);
    assert_int_equal(isotp_send(&ecu, msg, 7u, 10u), 0);
    assert_int_equal(poll_at(10u), 1);
    ASSERT_FRAME(1, 8, 0x07, msg[0], msg[1], msg[2], msg[3], msg[4], msg[5], msg[6]);
    assert_int_equal(poll_at(20u), 0); /* nothing more */
}

static void test_padding_configurable_and_off(void **state)
{
    (void)state;
    isotp_config_t cfg;
    isotp_config_defaults(&cfg, RX_ID, TX_ID);
    cfg.pad_byte = 0x55u;
    setup_cfg(&cfg);
    const uint8_t two[2] = {0x22u, 0xF1u};
    assert_int_equal(isotp_send(&ecu, two, 2u, 0u), 0);
    assert_int_equal(poll_at(0u), 1);
    ASSERT_FRAME(0, 8, 0x02, 0x22, 0xF1, 0x55, 0x55, 0x55, 0x55, 0x55);

    cfg.padding = 0u; /* the shortest DLC: SF 1 + L, FC 3, the last CF 1 + its bytes */
    setup_cfg(&cfg);
    assert_int_equal(isotp_send(&ecu, two, 2u, 0u), 0);
    assert_int_equal(poll_at(0u), 1);
    ASSERT_FRAME(0, 3, 0x02, 0x22, 0xF1);
    pattern(msg, 9u, 3u);
    assert_int_equal(isotp_send(&ecu, msg, 9u, 0u), 0);
    assert_int_equal(poll_at(0u), 1);
    ASSERT_FRAME(1, 8, 0x10, 0x09, msg[0], msg[1], msg[2], msg[3], msg[4], msg[5]);
    assert_int_equal(feed(TESTER(0x30, 0x00, 0x00), 1u), 1);
    assert_int_equal(poll_at(1u), 1);
    ASSERT_FRAME(2, 4, 0x21, msg[6], msg[7], msg[8]);
    assert_int_equal(feed(TESTER(0x10, 0x08, 1, 2, 3, 4, 5, 6), 2u), 1);
    assert_int_equal(poll_at(2u), 1);
    ASSERT_FRAME(3, 3, 0x30, 0x08, 0x00);
}

static void test_receive_single_frames(void **state)
{
    (void)state;
    setup_default();
    size_t len = 0;
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), HAL_EAGAIN);
    /* padded: DLC 8 whatever the length; padding bytes are not checked */
    assert_int_equal(feed(TESTER(0x02, 0x10, 0x03, 0xAA, 0x00, 0x12, 0x34, 0x56), 0u), 1);
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0);
    assert_int_equal(len, 2);
    assert_int_equal(got[0], 0x10);
    assert_int_equal(got[1], 0x03);
    assert_int_equal(ecu.rx_result, ISOTP_N_OK);
    /* unpadded: DLC 1 + SF_DL, accepted */
    assert_int_equal(feed(TESTER(0x01, 0x3E), 1u), 1);
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0);
    assert_int_equal(len, 1);
    assert_int_equal(got[0], 0x3E);
    /* 7 bytes, the most an SF holds */
    assert_int_equal(feed(TESTER(0x07, 1, 2, 3, 4, 5, 6, 7), 2u), 1);
    assert_int_equal(isotp_receive(&ecu, got, 7u, &len), 0);
    assert_int_equal(len, 7);
    assert_int_equal(got[6], 7);
    assert_int_equal(ecu.cnt.rx_msgs, 3);
    assert_int_equal(poll_at(3u), 0); /* an SF needs no flow control */
    assert_int_equal(ecu.cnt.rx_invalid, 0);
}

static void test_receive_invalid_single_frames(void **state)
{
    (void)state;
    setup_default();
    assert_int_equal(feed(TESTER(0x00, 1, 2, 3, 4, 5, 6, 7), 0u), 1); /* SF_DL 0 */
    assert_int_equal(feed(TESTER(0x08, 1, 2, 3, 4, 5, 6, 7), 0u), 1); /* SF_DL 8 on classic CAN */
    assert_int_equal(feed(TESTER(0x0F, 1, 2, 3, 4, 5, 6, 7), 0u), 1);
    assert_int_equal(feed(TESTER(0x03, 0x22, 0xF1), 0u), 1);          /* SF_DL 3 in DLC 3 */
    hal_can_frame_t empty = TESTER(0x00);
    empty.dlc = 0u;                                                   /* DLC 0 */
    assert_int_equal(feed(empty, 0u), 1);
    assert_int_equal(feed(TESTER(0x40, 1, 2), 0u), 1);                /* PCI type 4 */
    assert_int_equal(feed(TESTER(0xF0, 1, 2, 3, 4, 5, 6, 7), 0u), 1); /* PCI type 15 */
    assert_int_equal(ecu.cnt.rx_invalid, 7);
    assert_int_equal(ecu.cnt.rx_msgs, 0);
    size_t len = 0;
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), HAL_EAGAIN);
    /* a DLC above 8 is an argument error */
    hal_can_frame_t big = TESTER(0x01, 0x3E);
    big.dlc = 9u;
    assert_int_equal(feed(big, 0u), HAL_EINVAL);
}

static void test_other_ids_left_alone(void **state)
{
    (void)state;
    setup_default();
    hal_can_frame_t f = TESTER(0x01, 0x3E);
    f.id = TX_ID; /* our own response ID (an echo) */
    assert_int_equal(feed(f, 0u), 0);
    f.id = 0x100u;
    assert_int_equal(feed(f, 0u), 0);
    f.id = RX_ID;
    f.extended = 1u; /* a 29-bit frame with the same number */
    assert_int_equal(feed(f, 0u), 0);
    const isotp_counters_t zero = {0};
    assert_memory_equal(&ecu.cnt, &zero, sizeof zero);
    assert_int_equal(isotp_on_frame(NULL, &f, 0u), HAL_EINVAL);
    assert_int_equal(isotp_on_frame(&ecu, NULL, 0u), HAL_EINVAL);
    assert_int_equal(isotp_poll(&ecu, 0u, NULL, NULL), HAL_EINVAL);
}

/* ---------------------------------------------------------------- segmented send */

/* send n bytes to a tester that answers every FC with (bs, st_min): checks every frame
 * against the standard's layout and returns how many CFs were sent */
static size_t send_segmented(size_t n, uint8_t bs, uint8_t st_min)
{
    setup_default();
    pattern(msg, n, (unsigned)n);
    uint64_t t = 1000u;
    assert_int_equal(isotp_send(&ecu, msg, n, t), 0);
    assert_int_equal(poll_at(t), 1);
    ASSERT_FRAME(0, 8, (uint8_t)(0x10u | (n >> 8)), (uint8_t)(n & 0xFFu), msg[0], msg[1], msg[2],
                 msg[3], msg[4], msg[5]);
    t += 500u * MS;
    assert_int_equal(poll_at(t), 0); /* nothing before the FC */
    assert_int_equal(ecu.tx_state, ISOTP_TX_WAIT_FC);
    size_t pos = 6u, cfs = 0u;
    unsigned sn = 1u;
    const uint32_t gap = isotp_st_min_us(st_min);
    while (pos < n) {
        t += 1000u;
        assert_int_equal(feed(TESTER(0x30, bs, st_min), t), 1);
        size_t in_block = 0u;
        while (pos < n && (bs == 0u || in_block < bs)) {
            const size_t before = sink.n;
            if (cfs > 0u && in_block > 0u && gap > 0u) {
                assert_int_equal(poll_at(t + gap - 1u), 0); /* STmin not yet over */
                t += gap;
            }
            assert_true(poll_at(t) >= 1);
            assert_true(sink.n > before);
            for (size_t k = before; k < sink.n; k++) {
                const hal_can_frame_t *f = &sink.f[k];
                assert_int_equal(f->dlc, 8);
                assert_int_equal(f->data[0], 0x20u | sn);
                const size_t take = (n - pos) < 7u ? (n - pos) : 7u;
                assert_memory_equal(&f->data[1], &msg[pos], take);
                for (size_t b = 1u + take; b < 8u; b++) {
                    assert_int_equal(f->data[b], 0xCC); /* the last CF is padded */
                }
                pos += take;
                sn = (sn + 1u) & 0x0Fu;
                cfs++;
                in_block++;
            }
        }
        if (pos < n) {
            assert_int_equal(ecu.tx_state, ISOTP_TX_WAIT_FC); /* block done: waits */
            t += 100u * MS;
            assert_int_equal(poll_at(t), 0);
        }
    }
    assert_int_equal(pos, n);
    assert_int_equal(isotp_tx_busy(&ecu), 0);
    assert_int_equal(ecu.tx_result, ISOTP_N_OK);
    assert_int_equal(ecu.cnt.tx_msgs, 1);
    return cfs;
}

static void test_send_8_bytes(void **state)
{
    (void)state;
    assert_int_equal(send_segmented(8u, 0u, 0u), 1); /* FF 6 bytes + one CF of 2 */
}

static void test_send_62_bytes(void **state)
{
    (void)state;
    assert_int_equal(send_segmented(62u, 0u, 0u), 8); /* 6 + 8 x 7 */
}

static void test_send_max_bytes(void **state)
{
    (void)state;
    /* 4095 bytes: 585 CFs, the sequence number wraps 36 times; the ECU hands over at most
     * ISOTP_POLL_BURST frames a poll when BS = 0 and STmin = 0 */
    assert_int_equal(send_segmented(ISOTP_MAX_LEN, 0u, 0u), (ISOTP_MAX_LEN - 6u + 6u) / 7u);
    setup_default();
    pattern(msg, ISOTP_MAX_LEN, 9u);
    assert_int_equal(isotp_send(&ecu, msg, ISOTP_MAX_LEN, 0u), 0);
    assert_int_equal(poll_at(0u), 1);
    assert_int_equal(feed(TESTER(0x30, 0x00, 0x00), 1u), 1);
    assert_int_equal(poll_at(1u), (int)ISOTP_POLL_BURST);
}

/* the block size the tester announces: BS CFs, then the ECU waits for the next FC */
static void test_send_block_size(void **state)
{
    (void)state;
    assert_int_equal(send_segmented(62u, 3u, 0u), 8); /* blocks of 3, 3, 2 */
    assert_int_equal(send_segmented(ISOTP_MAX_LEN, 1u, 0u), 585);
    assert_int_equal(send_segmented(200u, 255u, 0u), 28);
}

/* the STmin the tester announces, ms and us ranges */
static void test_send_st_min(void **state)
{
    (void)state;
    assert_int_equal(send_segmented(62u, 0u, 10u), 8);    /* 10 ms */
    assert_int_equal(send_segmented(62u, 4u, 0x7Fu), 8);  /* 127 ms */
    assert_int_equal(send_segmented(62u, 0u, 0xF1u), 8);  /* 100 us */
    assert_int_equal(send_segmented(62u, 2u, 0xF9u), 8);  /* 900 us */
}

/* a reserved STmin in the tester's FC means 127 ms */
static void test_send_st_min_reserved(void **state)
{
    (void)state;
    const uint8_t reserved[] = {0x80u, 0xF0u, 0xFAu, 0xFFu};
    for (size_t i = 0; i < sizeof reserved; i++) {
        setup_default();
        pattern(msg, 30u, 1u);
        assert_int_equal(isotp_send(&ecu, msg, 30u, 0u), 0);
        assert_int_equal(poll_at(0u), 1);
        assert_int_equal(feed(TESTER(0x30, 0x00, reserved[i]), 10u), 1);
        assert_int_equal(poll_at(10u), 1);
        assert_int_equal(poll_at(10u + 126999u), 0);
        assert_int_equal(poll_at(10u + 127000u), 1);
        assert_int_equal(ecu.tx_st_min_us, 127000u);
    }
}

static void test_send_busy_and_bad_arguments(void **state)
{
    (void)state;
    setup_default();
    pattern(msg, 100u, 2u);
    assert_int_equal(isotp_send(&ecu, msg, 0u, 0u), HAL_EINVAL);
    assert_int_equal(isotp_send(&ecu, msg, ISOTP_MAX_LEN + 1u, 0u), HAL_EINVAL);
    assert_int_equal(isotp_send(&ecu, NULL, 3u, 0u), HAL_EINVAL);
    assert_int_equal(isotp_send(&ecu, msg, 100u, 0u), 0);
    assert_int_equal(isotp_send(&ecu, msg, 5u, 0u), HAL_EAGAIN); /* one at a time */
}

/* ---------------------------------------------------------------- segmented receive */

/* the tester sends n bytes honouring the ECU's FCs; checks the ECU's FC frames */
static void receive_segmented(size_t n, uint8_t bs, uint8_t st_min)
{
    isotp_config_t cfg;
    isotp_config_defaults(&cfg, RX_ID, TX_ID);
    cfg.block_size = bs;
    cfg.st_min = st_min;
    setup_cfg(&cfg);
    pattern(msg, n, (unsigned)n + 5u);
    uint64_t t = 0u;
    assert_int_equal(feed(TESTER((uint8_t)(0x10u | (n >> 8)), (uint8_t)(n & 0xFFu), msg[0], msg[1],
                                 msg[2], msg[3], msg[4], msg[5]), t), 1);
    assert_int_equal(isotp_rx_busy(&ecu), 1);
    size_t pos = 6u, fcs = 0u, in_block = 0u;
    unsigned sn = 1u;
    while (pos < n) {
        if (bs == 0u ? fcs == 0u : in_block == 0u) {
            const size_t before = sink.n;
            assert_int_equal(poll_at(t), 1);
            assert_int_equal(sink.n, before + 1u);
            ASSERT_FRAME(before, 8, 0x30, bs, st_min, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC);
            fcs++;
            in_block = bs;
        }
        uint8_t d[8];
        memset(d, 0xAA, sizeof d);
        d[0] = (uint8_t)(0x20u | sn);
        const size_t take = (n - pos) < 7u ? (n - pos) : 7u;
        memcpy(&d[1], &msg[pos], take);
        t += isotp_st_min_us(st_min) + 1u;
        assert_int_equal(feed(mkframe(RX_ID, d, 8u), t), 1);
        pos += take;
        sn = (sn + 1u) & 0x0Fu;
        if (bs != 0u) {
            in_block--;
        }
    }
    assert_int_equal(isotp_rx_busy(&ecu), 0);
    assert_int_equal(ecu.rx_result, ISOTP_N_OK);
    size_t len = 0;
    assert_int_equal(isotp_receive(&ecu, got, n - 1u, &len), HAL_ENOSPC); /* stays */
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0);
    assert_int_equal(len, n);
    assert_memory_equal(got, msg, n);
    assert_int_equal(ecu.cnt.rx_msgs, 1);
    const size_t cfs = (n - 6u + 6u) / 7u;
    assert_int_equal(fcs, bs == 0u ? 1u : (cfs + bs - 1u) / bs);
    const isotp_counters_t *c = &ecu.cnt;
    assert_int_equal(c->rx_invalid + c->rx_unexpected + c->rx_wrong_sn + c->rx_timeout_cr, 0);
}

static void test_receive_8_62_max(void **state)
{
    (void)state;
    receive_segmented(8u, 8u, 0u);
    receive_segmented(62u, 8u, 0u);
    receive_segmented(ISOTP_MAX_LEN, 8u, 0u);
}

/* the block size and STmin the ECU announces, both STmin ranges */
static void test_receive_announces_bs_st_min(void **state)
{
    (void)state;
    receive_segmented(62u, 0u, 0u);    /* one FC for the whole message */
    receive_segmented(62u, 3u, 20u);   /* an FC every 3 CFs, 20 ms */
    receive_segmented(ISOTP_MAX_LEN, 255u, 0xF5u); /* 500 us */
    receive_segmented(100u, 1u, 0x7Fu);
}

/* an unpadded last CF (DLC 1 + its bytes) is accepted; a short CF that is not the last,
 * or a last CF shorter than its bytes, is ignored */
static void test_receive_short_frames(void **state)
{
    (void)state;
    setup_default();
    pattern(msg, 16u, 4u);
    assert_int_equal(feed(TESTER(0x10, 16, msg[0], msg[1], msg[2], msg[3], msg[4], msg[5]), 0u), 1);
    assert_int_equal(feed(TESTER(0x10, 16, msg[0], msg[1], msg[2], msg[3], msg[4]), 0u), 1);
    assert_int_equal(ecu.cnt.rx_invalid, 1); /* an FF of DLC 7 */
    assert_int_equal(poll_at(0u), 1);
    assert_int_equal(feed(TESTER(0x21, msg[6], msg[7], msg[8], msg[9], msg[10], msg[11]), 1u), 1);
    assert_int_equal(ecu.cnt.rx_invalid, 2); /* a CF of 6 data bytes before the end */
    assert_int_equal(feed(TESTER(0x21, msg[6], msg[7], msg[8], msg[9], msg[10], msg[11], msg[12]), 2u), 1);
    assert_int_equal(feed(TESTER(0x22, msg[13], msg[14]), 3u), 1);
    assert_int_equal(ecu.cnt.rx_invalid, 3); /* the last CF needs 3 bytes */
    assert_int_equal(feed(TESTER(0x22, msg[13], msg[14], msg[15]), 4u), 1);
    size_t len = 0;
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0);
    assert_int_equal(len, 16);
    assert_memory_equal(got, msg, 16u);
}

static void test_receive_invalid_first_frames(void **state)
{
    (void)state;
    setup_default();
    assert_int_equal(feed(TESTER(0x10, 0x07, 1, 2, 3, 4, 5, 6), 0u), 1); /* FF_DL 7: an SF's */
    assert_int_equal(feed(TESTER(0x10, 0x00, 0x00, 0x00, 0x0F, 0xFF, 1, 2), 0u), 1); /* escape, 4095 */
    assert_int_equal(ecu.cnt.rx_invalid, 2);
    assert_int_equal(isotp_rx_busy(&ecu), 0);
    assert_int_equal(poll_at(0u), 0);
    /* the smallest FF_DL, 8 */
    assert_int_equal(feed(TESTER(0x10, 0x08, 1, 2, 3, 4, 5, 6), 1u), 1);
    assert_int_equal(poll_at(1u), 1);
    assert_int_equal(feed(TESTER(0x21, 7, 8), 2u), 1);
    size_t len = 0;
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0);
    assert_int_equal(len, 8);
}

/* ---------------------------------------------------------------- overflow */

static void test_receive_overflow(void **state)
{
    (void)state;
    setup_default();
    /* an escape-sequence FF (ISO 15765-2:2016): 32-bit FF_DL 5000 > ISOTP_MAX_LEN */
    assert_int_equal(feed(TESTER(0x10, 0x00, 0x00, 0x00, 0x13, 0x88, 1, 2), 0u), 1);
    assert_int_equal(poll_at(0u), 1);
    ASSERT_FRAME(0, 8, 0x32, 0x00, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC);
    assert_int_equal(ecu.cnt.rx_overflow, 1);
    assert_int_equal(ecu.rx_result, ISOTP_N_BUFFER_OVFLW);
    assert_int_equal(isotp_rx_busy(&ecu), 0);
    assert_int_equal(feed(TESTER(0x21, 1, 2, 3, 4, 5, 6, 7), 1u), 1); /* its CFs: ignored */
    assert_int_equal(ecu.cnt.rx_unexpected, 1);
    assert_int_equal(poll_at(2u), 0);
#if ISOTP_MAX_LEN < 4095u
    assert_int_equal(feed(TESTER(0x1F, 0xFF, 1, 2, 3, 4, 5, 6), 3u), 1);
    assert_int_equal(poll_at(3u), 1);
    assert_int_equal(sink.f[1].data[0], 0x32);
#endif
}

static void test_send_peer_overflow(void **state)
{
    (void)state;
    setup_default();
    pattern(msg, 3000u, 1u);
    assert_int_equal(isotp_send(&ecu, msg, 3000u, 0u), 0);
    assert_int_equal(poll_at(0u), 1);
    assert_int_equal(feed(TESTER(0x32, 0x00, 0x00), 5u), 1);
    assert_int_equal(isotp_tx_busy(&ecu), 0);
    assert_int_equal(ecu.tx_result, ISOTP_N_BUFFER_OVFLW);
    assert_int_equal(ecu.cnt.tx_overflow, 1);
    assert_int_equal(poll_at(6u), 0);
    /* an invalid flow status (3..15) aborts too */
    assert_int_equal(isotp_send(&ecu, msg, 30u, 10u), 0);
    assert_int_equal(poll_at(10u), 1);
    assert_int_equal(feed(TESTER(0x33, 0x00, 0x00), 11u), 1);
    assert_int_equal(ecu.tx_result, ISOTP_N_INVALID_FS);
    assert_int_equal(ecu.cnt.tx_invalid_fs, 1);
    /* an FC shorter than 3 bytes is ignored */
    assert_int_equal(isotp_send(&ecu, msg, 30u, 20u), 0);
    assert_int_equal(poll_at(20u), 1);
    assert_int_equal(feed(TESTER(0x30, 0x00), 21u), 1);
    assert_int_equal(ecu.cnt.rx_invalid, 1);
    assert_int_equal(ecu.tx_state, ISOTP_TX_WAIT_FC);
}

/* ---------------------------------------------------------------- WAIT */

/* the tester's FC WAIT: the ECU goes on waiting, N_Bs restarts with every WAIT */
static void test_send_wait_frames(void **state)
{
    (void)state;
    setup_default();
    pattern(msg, 20u, 6u);
    assert_int_equal(isotp_send(&ecu, msg, 20u, 0u), 0);
    assert_int_equal(poll_at(0u), 1);
    assert_int_equal(feed(TESTER(0x31, 0x00, 0x00), 900u * MS), 1);
    assert_int_equal(feed(TESTER(0x31, 0x00, 0x00), 1800u * MS), 1);
    assert_int_equal(poll_at(2700u * MS), 0);
    assert_int_equal(isotp_tx_busy(&ecu), 1); /* 2.7 s after the FF, 0.9 s after a WAIT */
    assert_int_equal(ecu.cnt.wait_received, 2);
    assert_int_equal(feed(TESTER(0x30, 0x00, 0x00), 2700u * MS), 1);
    assert_int_equal(poll_at(2700u * MS), 2);
    assert_int_equal(ecu.tx_result, ISOTP_N_OK);
    assert_int_equal(ecu.cnt.tx_timeout_bs, 0);

    /* with a limit on the WAITs accepted */
    isotp_config_t cfg;
    isotp_config_defaults(&cfg, RX_ID, TX_ID);
    cfg.wait_rx_max = 2u;
    setup_cfg(&cfg);
    assert_int_equal(isotp_send(&ecu, msg, 20u, 0u), 0);
    assert_int_equal(poll_at(0u), 1);
    assert_int_equal(feed(TESTER(0x31, 0x00, 0x00), 1u), 1);
    assert_int_equal(feed(TESTER(0x31, 0x00, 0x00), 2u), 1);
    assert_int_equal(isotp_tx_busy(&ecu), 1);
    assert_int_equal(feed(TESTER(0x31, 0x00, 0x00), 3u), 1);
    assert_int_equal(isotp_tx_busy(&ecu), 0);
    assert_int_equal(ecu.tx_result, ISOTP_N_WFT_OVRN);
    assert_int_equal(ecu.cnt.tx_wft_ovrn, 1);
}

/* the ECU's FC WAIT: a new FF while the last message is unread */
static void test_receive_sends_wait_until_read(void **state)
{
    (void)state;
    setup_default();
    assert_int_equal(feed(TESTER(0x02, 0x10, 0x01), 0u), 1); /* unread */
    pattern(msg, 20u, 8u);
    assert_int_equal(feed(TESTER(0x10, 20, msg[0], msg[1], msg[2], msg[3], msg[4], msg[5]), 10u), 1);
    assert_int_equal(poll_at(10u), 1);
    ASSERT_FRAME(0, 8, 0x31, 0x00, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC);
    assert_int_equal(poll_at(10u + 99999u), 0);
    assert_int_equal(poll_at(10u + 100000u), 1); /* the next WAIT, wait_period_us later */
    ASSERT_FRAME(1, 8, 0x31, 0x00, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC);
    assert_int_equal(ecu.cnt.wait_sent, 2);
    size_t len = 0;
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0); /* read: buffer free */
    assert_int_equal(len, 2);
    assert_int_equal(poll_at(150u * MS), 1);
    ASSERT_FRAME(2, 8, 0x30, 0x08, 0x00, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC);
    assert_int_equal(feed(TESTER(0x21, msg[6], msg[7], msg[8], msg[9], msg[10], msg[11], msg[12]), 151u * MS), 1);
    assert_int_equal(feed(TESTER(0x22, msg[13], msg[14], msg[15], msg[16], msg[17], msg[18], msg[19]), 152u * MS), 1);
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0);
    assert_int_equal(len, 20);
    assert_memory_equal(got, msg, 20u);
}

static void test_receive_wait_limit_then_overflow(void **state)
{
    (void)state;
    isotp_config_t cfg;
    isotp_config_defaults(&cfg, RX_ID, TX_ID);
    cfg.wft_max = 3u;
    setup_cfg(&cfg);
    assert_int_equal(feed(TESTER(0x01, 0x3E), 0u), 1); /* unread */
    assert_int_equal(feed(TESTER(0x10, 20, 1, 2, 3, 4, 5, 6), 0u), 1);
    for (unsigned k = 0; k < 3u; k++) {
        assert_int_equal(poll_at((uint64_t)k * 100u * MS), 1);
        ASSERT_FRAME(k, 8, 0x31, 0x00, 0x00);
    }
    assert_int_equal(poll_at(300u * MS), 1); /* N_WFTmax reached: FC OVFLW */
    ASSERT_FRAME(3, 8, 0x32, 0x00, 0x00);
    assert_int_equal(ecu.cnt.rx_wft_ovrn, 1);
    assert_int_equal(ecu.rx_result, ISOTP_N_WFT_OVRN);
    assert_int_equal(isotp_rx_busy(&ecu), 0);
    size_t len = 0;
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0); /* the first stays */
    assert_int_equal(len, 1);

    /* wft_max 0: no WAIT, FC OVFLW at once; an SF while the buffer is full is dropped */
    cfg.wft_max = 0u;
    setup_cfg(&cfg);
    assert_int_equal(feed(TESTER(0x01, 0x3E), 0u), 1);
    assert_int_equal(feed(TESTER(0x01, 0x11), 1u), 1);
    assert_int_equal(ecu.cnt.rx_busy, 1);
    assert_int_equal(feed(TESTER(0x10, 20, 1, 2, 3, 4, 5, 6), 2u), 1);
    assert_int_equal(poll_at(2u), 1);
    ASSERT_FRAME(0, 8, 0x32, 0x00, 0x00);
    assert_int_equal(ecu.cnt.rx_busy, 2);
    assert_int_equal(ecu.cnt.wait_sent, 0);
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0);
    assert_int_equal(got[0], 0x3E);
}

/* ---------------------------------------------------------------- timeouts */

static void test_timeout_n_cr(void **state)
{
    (void)state;
    setup_default();
    assert_int_equal(feed(TESTER(0x10, 20, 1, 2, 3, 4, 5, 6), 0u), 1);
    assert_int_equal(poll_at(5u), 1); /* FC CTS at 5 us: N_Cr starts */
    assert_int_equal(poll_at(5u + 1000000u), 0);
    assert_int_equal(isotp_rx_busy(&ecu), 1); /* exactly 1000 ms: still in time */
    assert_int_equal(poll_at(5u + 1000001u), 0);
    assert_int_equal(isotp_rx_busy(&ecu), 0);
    assert_int_equal(ecu.rx_result, ISOTP_N_TIMEOUT_CR);
    assert_int_equal(ecu.cnt.rx_timeout_cr, 1);
    /* between two CFs, and found by on_frame without a poll: the late CF is unexpected */
    assert_int_equal(feed(TESTER(0x10, 20, 1, 2, 3, 4, 5, 6), 2000000u), 1);
    assert_int_equal(poll_at(2000000u), 1);
    assert_int_equal(feed(TESTER(0x21, 7, 8, 9, 10, 11, 12, 13), 2500000u), 1);
    assert_int_equal(feed(TESTER(0x22, 14, 15, 16, 17, 18, 19, 20), 3500001u), 1);
    assert_int_equal(ecu.cnt.rx_timeout_cr, 2);
    assert_int_equal(ecu.cnt.rx_unexpected, 1);
    size_t len = 0;
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), HAL_EAGAIN); /* dropped */
    /* configurable */
    isotp_config_t cfg;
    isotp_config_defaults(&cfg, RX_ID, TX_ID);
    cfg.n_cr_us = 50u * MS;
    setup_cfg(&cfg);
    assert_int_equal(feed(TESTER(0x10, 20, 1, 2, 3, 4, 5, 6), 0u), 1);
    assert_int_equal(poll_at(0u), 1);
    assert_int_equal(poll_at(50u * MS + 1u), 0);
    assert_int_equal(ecu.rx_result, ISOTP_N_TIMEOUT_CR);
}

static void test_timeout_n_bs(void **state)
{
    (void)state;
    setup_default();
    pattern(msg, 100u, 3u);
    assert_int_equal(isotp_send(&ecu, msg, 100u, 0u), 0);
    assert_int_equal(poll_at(10u), 1); /* the FF went at 10 us: N_Bs starts */
    assert_int_equal(poll_at(10u + 1000000u), 0);
    assert_int_equal(isotp_tx_busy(&ecu), 1);
    assert_int_equal(poll_at(10u + 1000001u), 0);
    assert_int_equal(isotp_tx_busy(&ecu), 0);
    assert_int_equal(ecu.tx_result, ISOTP_N_TIMEOUT_BS);
    assert_int_equal(ecu.cnt.tx_timeout_bs, 1);
    /* after a block: BS 2, then no FC */
    assert_int_equal(isotp_send(&ecu, msg, 100u, 2000000u), 0);
    assert_int_equal(poll_at(2000000u), 1);
    assert_int_equal(feed(TESTER(0x30, 0x02, 0x00), 2000001u), 1);
    assert_int_equal(poll_at(2000001u), 2);
    assert_int_equal(ecu.tx_state, ISOTP_TX_WAIT_FC);
    assert_int_equal(feed(TESTER(0x30, 0x02, 0x00), 3000002u), 1); /* too late */
    assert_int_equal(ecu.cnt.tx_timeout_bs, 2);
    assert_int_equal(ecu.cnt.rx_unexpected, 1);
    /* the peer's N_Bs does not start before the FF is out (queue full for 0.9 s) */
    sink.refuse = 1;
    assert_int_equal(isotp_send(&ecu, msg, 100u, 5000000u), 0);
    assert_int_equal(poll_at(5000000u), 0);
    sink.refuse = 0;
    assert_int_equal(poll_at(5900000u), 1);
    assert_int_equal(poll_at(6800000u), 0);
    assert_int_equal(isotp_tx_busy(&ecu), 1);
}

static void test_timeout_n_as(void **state)
{
    (void)state;
    setup_default();
    sink.refuse = 1; /* the CAN queue stays full */
    const uint8_t sf[3] = {1, 2, 3};
    assert_int_equal(isotp_send(&ecu, sf, 3u, 100u), 0);
    assert_int_equal(poll_at(100u), 0);
    assert_int_equal(poll_at(100u + 1000000u), 0);
    assert_int_equal(isotp_tx_busy(&ecu), 1);
    assert_true(ecu.cnt.tx_refused >= 2u);
    assert_int_equal(poll_at(100u + 1000001u), 0);
    assert_int_equal(isotp_tx_busy(&ecu), 0);
    assert_int_equal(ecu.tx_result, ISOTP_N_TIMEOUT_A);
    assert_int_equal(ecu.cnt.tx_timeout_as, 1);
    /* a CF that cannot go: N_As from the moment it was due (after STmin) */
    sink.refuse = 0;
    pattern(msg, 30u, 1u);
    assert_int_equal(isotp_send(&ecu, msg, 30u, 0u), 0);
    assert_int_equal(poll_at(0u), 1);
    assert_int_equal(feed(TESTER(0x30, 0x00, 0x0A), 0u), 1);
    assert_int_equal(poll_at(0u), 1);
    sink.refuse = 1;
    assert_int_equal(poll_at(10u * MS + 1000000u), 0); /* due at 10 ms: in time */
    assert_int_equal(isotp_tx_busy(&ecu), 1);
    assert_int_equal(poll_at(10u * MS + 1000001u), 0);
    assert_int_equal(ecu.tx_result, ISOTP_N_TIMEOUT_A);
    assert_int_equal(ecu.cnt.tx_timeout_as, 2);
    /* a refused frame is offered again, unchanged */
    sink.refuse = 1;
    assert_int_equal(isotp_send(&ecu, sf, 3u, 0u), 0);
    assert_int_equal(poll_at(1u), 0);
    sink.refuse = 0;
    assert_int_equal(poll_at(2u), 1);
    ASSERT_FRAME(2, 8, 0x03, 1, 2, 3, 0xCC);
}

/* a single frame that must leave now or not at all (a 7F SID 78 before a long operation) */
static void test_send_now(void **state)
{
    (void)state;
    setup_default();
    const uint8_t pending[3] = {0x7Fu, 0x2Eu, 0x78u};
    assert_int_equal(isotp_send_now(&ecu, pending, 3u, 5u, sink_tx, &sink), 0);
    ASSERT_FRAME(0, 8, 0x03, 0x7F, 0x2E, 0x78, 0xCC);
    assert_int_equal(isotp_tx_busy(&ecu), 0);
    assert_int_equal(ecu.tx_result, ISOTP_N_OK);
    /* refused by the driver: given up at once, not offered again */
    sink.refuse = 1;
    assert_int_equal(isotp_send_now(&ecu, pending, 3u, 6u, sink_tx, &sink), HAL_EAGAIN);
    assert_int_equal(isotp_tx_busy(&ecu), 0);
    assert_int_equal(ecu.tx_result, ISOTP_N_TIMEOUT_A);
    sink.refuse = 0;
    assert_int_equal(poll_at(7u), 0);
    assert_int_equal(sink.n, 1u);
    /* not while another message is being sent, and never more than a single frame */
    pattern(msg, 30u, 2u);
    assert_int_equal(isotp_send(&ecu, msg, 30u, 8u), 0);
    assert_int_equal(isotp_send_now(&ecu, pending, 3u, 8u, sink_tx, &sink), HAL_EAGAIN);
    assert_int_equal(sink.n, 1u);
    assert_int_equal(isotp_send_now(&ecu, msg, 8u, 8u, sink_tx, &sink), HAL_EINVAL);
    assert_int_equal(isotp_send_now(&ecu, pending, 3u, 8u, NULL, &sink), HAL_EINVAL);
}

static void test_timeout_n_ar(void **state)
{
    (void)state;
    setup_default();
    sink.refuse = 1; /* the ECU's FC cannot be sent */
    assert_int_equal(feed(TESTER(0x10, 20, 1, 2, 3, 4, 5, 6), 0u), 1);
    assert_int_equal(poll_at(0u), 0);
    assert_int_equal(poll_at(1000000u), 0);
    assert_int_equal(isotp_rx_busy(&ecu), 1);
    assert_int_equal(poll_at(1000001u), 0);
    assert_int_equal(isotp_rx_busy(&ecu), 0);
    assert_int_equal(ecu.rx_result, ISOTP_N_TIMEOUT_A);
    assert_int_equal(ecu.cnt.rx_timeout_ar, 1);
}

/* a clock that goes backwards counts as no time: no timeout, no early CF */
static void test_time_backwards(void **state)
{
    (void)state;
    setup_default();
    assert_int_equal(feed(TESTER(0x10, 20, 1, 2, 3, 4, 5, 6), 5000000u), 1);
    assert_int_equal(poll_at(5000000u), 1);
    assert_int_equal(poll_at(1000u), 0);
    assert_int_equal(isotp_rx_busy(&ecu), 1);
    pattern(msg, 30u, 1u);
    assert_int_equal(isotp_send(&ecu, msg, 30u, 5000000u), 0);
    assert_int_equal(poll_at(5000000u), 1);
    assert_int_equal(feed(TESTER(0x30, 0x00, 0x14), 5000000u), 1); /* STmin 20 ms */
    assert_int_equal(poll_at(5000000u), 1);
    assert_int_equal(poll_at(0u), 0);
    assert_int_equal(ecu.cnt.tx_timeout_as + ecu.cnt.rx_timeout_cr, 0);
}

/* ---------------------------------------------------------------- sequence numbers */

static void start_reception(size_t n, uint64_t t)
{
    pattern(msg, n, 2u);
    assert_int_equal(feed(TESTER(0x10, (uint8_t)n, msg[0], msg[1], msg[2], msg[3], msg[4], msg[5]), t), 1);
    assert_int_equal(poll_at(t), 1);
}

static void test_wrong_sequence_number(void **state)
{
    (void)state;
    setup_default();
    start_reception(20u, 0u);
    assert_int_equal(feed(TESTER(0x22, 1, 2, 3, 4, 5, 6, 7), 1u), 1); /* 2 where 1 is due */
    assert_int_equal(ecu.cnt.rx_wrong_sn, 1);
    assert_int_equal(ecu.rx_result, ISOTP_N_WRONG_SN);
    assert_int_equal(isotp_rx_busy(&ecu), 0);
    assert_int_equal(feed(TESTER(0x23, 1, 2, 3, 4, 5, 6, 7), 2u), 1); /* the rest: unexpected */
    assert_int_equal(ecu.cnt.rx_unexpected, 1);
    size_t len = 0;
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), HAL_EAGAIN);
    /* a repeated CF is a wrong sequence number too */
    start_reception(30u, 10u);
    assert_int_equal(feed(TESTER(0x21, msg[6], msg[7], msg[8], msg[9], msg[10], msg[11], msg[12]), 11u), 1);
    assert_int_equal(feed(TESTER(0x21, msg[6], msg[7], msg[8], msg[9], msg[10], msg[11], msg[12]), 12u), 1);
    assert_int_equal(ecu.cnt.rx_wrong_sn, 2);
    /* SN 0 after 15: a 4095-byte reception checks the wrap (receive_segmented) */
}

/* a lost CF: the next one's sequence number is off, the message is dropped and reported;
 * a lost last CF: N_Cr; the next message is received whole */
static void test_lost_consecutive_frame(void **state)
{
    (void)state;
    setup_default();
    start_reception(27u, 0u); /* FF 6 + 3 CFs */
    assert_int_equal(feed(TESTER(0x21, msg[6], msg[7], msg[8], msg[9], msg[10], msg[11], msg[12]), 1u), 1);
    /* CF 2 lost */
    assert_int_equal(feed(TESTER(0x23, msg[20], msg[21], msg[22], msg[23], msg[24], msg[25], msg[26]), 2u), 1);
    assert_int_equal(ecu.rx_result, ISOTP_N_WRONG_SN);
    assert_int_equal(ecu.cnt.rx_wrong_sn, 1);
    size_t len = 0;
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), HAL_EAGAIN);

    start_reception(20u, 10u);
    assert_int_equal(feed(TESTER(0x21, msg[6], msg[7], msg[8], msg[9], msg[10], msg[11], msg[12]), 11u), 1);
    /* the last CF lost */
    assert_int_equal(poll_at(11u + 1000001u), 0);
    assert_int_equal(ecu.rx_result, ISOTP_N_TIMEOUT_CR);
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), HAL_EAGAIN);

    start_reception(20u, 2000000u);
    assert_int_equal(feed(TESTER(0x21, msg[6], msg[7], msg[8], msg[9], msg[10], msg[11], msg[12]), 2000001u), 1);
    assert_int_equal(feed(TESTER(0x22, msg[13], msg[14], msg[15], msg[16], msg[17], msg[18], msg[19]), 2000002u), 1);
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0);
    assert_int_equal(len, 20);
    assert_memory_equal(got, msg, 20u);
}

/* ---------------------------------------------------------------- unexpected PDUs */

static void test_unexpected_first_frame_during_reception(void **state)
{
    (void)state;
    setup_default();
    start_reception(20u, 0u);
    assert_int_equal(feed(TESTER(0x21, msg[6], msg[7], msg[8], msg[9], msg[10], msg[11], msg[12]), 1u), 1);
    /* a new FF: the old reception is dropped (N_UNEXP_PDU), the new one starts */
    uint8_t second[10];
    pattern(second, 10u, 77u);
    assert_int_equal(feed(TESTER(0x10, 10, second[0], second[1], second[2], second[3], second[4], second[5]), 2u), 1);
    assert_int_equal(ecu.cnt.rx_unexpected, 1);
    assert_int_equal(poll_at(2u), 1);
    ASSERT_FRAME(1, 8, 0x30, 0x08, 0x00);
    assert_int_equal(feed(TESTER(0x21, second[6], second[7], second[8], second[9]), 3u), 1);
    size_t len = 0;
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0);
    assert_int_equal(len, 10);
    assert_memory_equal(got, second, 10u);
    assert_int_equal(ecu.rx_result, ISOTP_N_OK);
    assert_int_equal(ecu.cnt.rx_msgs, 1);

    /* an SF during a reception: the reception dropped, the SF received */
    start_reception(20u, 10u);
    assert_int_equal(feed(TESTER(0x02, 0x11, 0x01), 11u), 1);
    assert_int_equal(ecu.cnt.rx_unexpected, 2);
    assert_int_equal(isotp_receive(&ecu, got, sizeof got, &len), 0);
    assert_int_equal(len, 2);
    assert_int_equal(got[0], 0x11);
    /* an FF before the ECU's FC to the previous FF went out */
    assert_int_equal(feed(TESTER(0x10, 20, 1, 2, 3, 4, 5, 6), 20u), 1);
    assert_int_equal(feed(TESTER(0x10, 20, 1, 2, 3, 4, 5, 6), 21u), 1);
    assert_int_equal(ecu.cnt.rx_unexpected, 3);
    assert_int_equal(poll_at(21u), 1); /* one FC, for the second */
}

static void test_unexpected_cf_and_fc(void **state)
{
    (void)state;
    setup_default();
    assert_int_equal(feed(TESTER(0x21, 1, 2, 3, 4, 5, 6, 7), 0u), 1); /* CF when idle */
    assert_int_equal(feed(TESTER(0x30, 0x00, 0x00), 0u), 1);           /* FC when idle */
    assert_int_equal(ecu.cnt.rx_unexpected, 2);
    assert_int_equal(poll_at(0u), 0);
    /* an FC while the ECU sends CFs with BS 0 (none awaited): ignored */
    pattern(msg, 100u, 1u);
    assert_int_equal(isotp_send(&ecu, msg, 100u, 0u), 0);
    assert_int_equal(poll_at(0u), 1);
    assert_int_equal(feed(TESTER(0x30, 0x00, 0x0A), 1u), 1);
    assert_int_equal(poll_at(1u), 1);
    assert_int_equal(feed(TESTER(0x32, 0x00, 0x00), 2u), 1); /* even an OVFLW */
    assert_int_equal(ecu.cnt.rx_unexpected, 3);
    assert_int_equal(isotp_tx_busy(&ecu), 1);
    /* a CF before the ECU's FC CTS went out */
    setup_default();
    assert_int_equal(feed(TESTER(0x10, 20, 1, 2, 3, 4, 5, 6), 0u), 1);
    assert_int_equal(feed(TESTER(0x21, 7, 8, 9, 10, 11, 12, 13), 0u), 1);
    assert_int_equal(ecu.cnt.rx_unexpected, 1);
    assert_int_equal(isotp_rx_busy(&ecu), 1);
}

/* ---------------------------------------------------------------- two channels */

typedef struct {
    isotp_t *peer;
    uint64_t now;
    size_t frames;
} wire_t;

static isotp_t tester;

/* the frame goes straight to the other channel */
static int wire_tx(void *user, const hal_can_frame_t *f)
{
    wire_t *w = user;
    w->frames++;
    assert_int_equal(f->dlc, 8);
    assert_int_equal(isotp_on_frame(w->peer, f, w->now), 1);
    return 0;
}

/* the ECU and a tester made of the same code, full duplex: a request and a response in
 * flight at once, with the tester's BS/STmin and the ECU's */
static void test_two_channels_full_duplex(void **state)
{
    (void)state;
    isotp_config_t ce, ct;
    isotp_config_defaults(&ce, RX_ID, TX_ID);
    isotp_config_defaults(&ct, TX_ID, RX_ID);
    ce.block_size = 5u;
    ce.st_min = 0xF3u; /* 300 us */
    ct.block_size = 2u;
    ct.st_min = 1u;
    assert_int_equal(isotp_init(&ecu, &ce), 0);
    assert_int_equal(isotp_init(&tester, &ct), 0);
    static uint8_t req[ISOTP_MAX_LEN], rsp[ISOTP_MAX_LEN];
    pattern(req, ISOTP_MAX_LEN, 11u);
    pattern(rsp, 1000u, 12u);
    wire_t to_ecu = {&ecu, 0u, 0u}, to_tester = {&tester, 0u, 0u};
    assert_int_equal(isotp_send(&tester, req, ISOTP_MAX_LEN, 0u), 0);
    assert_int_equal(isotp_send(&ecu, rsp, 1000u, 0u), 0);
    size_t len_e = 0, len_t = 0;
    int got_e = 0, got_t = 0;
    for (uint64_t t = 0; t < 5000000u && (got_e == 0 || got_t == 0); t += 100u) {
        to_ecu.now = t;
        to_tester.now = t;
        assert_true(isotp_poll(&tester, t, wire_tx, &to_ecu) >= 0);
        assert_true(isotp_poll(&ecu, t, wire_tx, &to_tester) >= 0);
        if (got_e == 0 && isotp_receive(&ecu, got, sizeof got, &len_e) == 0) {
            got_e = 1;
            assert_int_equal(len_e, ISOTP_MAX_LEN);
            assert_memory_equal(got, req, ISOTP_MAX_LEN);
        }
        if (got_t == 0 && isotp_receive(&tester, got, sizeof got, &len_t) == 0) {
            got_t = 1;
            assert_int_equal(len_t, 1000);
            assert_memory_equal(got, rsp, 1000u);
        }
    }
    assert_int_equal(got_e, 1);
    assert_int_equal(got_t, 1);
    assert_int_equal(ecu.tx_result, ISOTP_N_OK);
    assert_int_equal(tester.tx_result, ISOTP_N_OK);
    /* frames: the tester's FF, 585 CFs and an FC per block of 2 of the response's 142 CFs;
     * the ECU's FF, 142 CFs and an FC per block of 5 of the request's 585 */
    assert_int_equal(to_ecu.frames, 1u + 585u + 71u);
    assert_int_equal(to_tester.frames, 1u + 142u + 117u);
    const isotp_counters_t *c = &ecu.cnt;
    assert_int_equal(c->rx_invalid + c->rx_unexpected + c->rx_wrong_sn + c->tx_refused, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_config_and_init),
        cmocka_unit_test(test_st_min_decoding),
        cmocka_unit_test(test_send_single_frame_padded),
        cmocka_unit_test(test_padding_configurable_and_off),
        cmocka_unit_test(test_receive_single_frames),
        cmocka_unit_test(test_receive_invalid_single_frames),
        cmocka_unit_test(test_other_ids_left_alone),
        cmocka_unit_test(test_send_8_bytes),
        cmocka_unit_test(test_send_62_bytes),
        cmocka_unit_test(test_send_max_bytes),
        cmocka_unit_test(test_send_block_size),
        cmocka_unit_test(test_send_st_min),
        cmocka_unit_test(test_send_st_min_reserved),
        cmocka_unit_test(test_send_busy_and_bad_arguments),
        cmocka_unit_test(test_receive_8_62_max),
        cmocka_unit_test(test_receive_announces_bs_st_min),
        cmocka_unit_test(test_receive_short_frames),
        cmocka_unit_test(test_receive_invalid_first_frames),
        cmocka_unit_test(test_receive_overflow),
        cmocka_unit_test(test_send_peer_overflow),
        cmocka_unit_test(test_send_wait_frames),
        cmocka_unit_test(test_receive_sends_wait_until_read),
        cmocka_unit_test(test_receive_wait_limit_then_overflow),
        cmocka_unit_test(test_timeout_n_cr),
        cmocka_unit_test(test_timeout_n_bs),
        cmocka_unit_test(test_timeout_n_as),
        cmocka_unit_test(test_send_now),
        cmocka_unit_test(test_timeout_n_ar),
        cmocka_unit_test(test_time_backwards),
        cmocka_unit_test(test_wrong_sequence_number),
        cmocka_unit_test(test_lost_consecutive_frame),
        cmocka_unit_test(test_unexpected_first_frame_during_reception),
        cmocka_unit_test(test_unexpected_cf_and_fc),
        cmocka_unit_test(test_two_channels_full_duplex),
    };
    return cmocka_run_group_tests_name("isotp", tests, NULL, NULL);
}
