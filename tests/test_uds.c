/*
 * test_uds.c - the UDS server (firmware/diag/uds.c): every service, every negative
 * response code on its path, suppressPosRspMsgIndicationBit, the session timings, S3, the
 * seed and key with the attempt counter and its delay, ECUReset, multi-DID reads.
 *
 * The requests and the expected responses are written byte for byte from ISO 14229-1 (as
 * docs/can.md, "Diagnostics (UDS)", lists them), not produced by the code under test. The
 * application behind the server is a fake with three DIDs.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "uds.h"

#define S 1000000u /* one second in us */

/* the fake application: 0x0100 (2 bytes, writable), 0x0101 (4 bytes, writable),
 * 0xF195 (read-only, "v1"), 0x0BIG (0x0102: longer than any buffer) */
typedef struct {
    uint8_t d100[2];
    uint8_t d101[4];
    uint8_t write_nrc; /* what write_did answers */
    int writes;
} fake_t;

static fake_t app;
static uds_t srv;
static uint8_t rsp[64];

static size_t fake_read(void *user, uint16_t did, uint8_t *buf, size_t cap)
{
    fake_t *f = user;
    switch (did) {
    case 0x0100u:
        if (cap >= 2u) {
            memcpy(buf, f->d100, 2u);
        }
        return 2u;
    case 0x0101u:
        if (cap >= 4u) {
            memcpy(buf, f->d101, 4u);
        }
        return 4u;
    case 0xF195u:
        if (cap >= 2u) {
            memcpy(buf, "v1", 2u);
        }
        return 2u;
    case 0x0102u:
        return cap + 1u;
    default:
        return 0u;
    }
}

static int fake_writable(void *user, uint16_t did)
{
    (void)user;
    return did == 0x0100u || did == 0x0101u;
}

static uint8_t fake_write(void *user, uint16_t did, const uint8_t *data, size_t len)
{
    fake_t *f = user;
    f->writes++;
    if (f->write_nrc != 0u) {
        return f->write_nrc;
    }
    if (did == 0x0100u) {
        if (len != 2u) {
            return UDS_NRC_INCORRECT_LENGTH;
        }
        memcpy(f->d100, data, 2u);
    } else {
        if (len != 4u) {
            return UDS_NRC_INCORRECT_LENGTH;
        }
        memcpy(f->d101, data, 4u);
    }
    return UDS_NRC_OK;
}

/* routines 0x0200 (no option record) succeeds, 0x0201 answers routine_nrc, 0x0202 sends a
 * 7F 31 78 first (uds_pending_sent) and succeeds; others unknown (fake_has_routine) */
static uint8_t routine_nrc;
static int routines;
static uint8_t fake_routine(void *user, uint16_t rid, const uint8_t *data, size_t len)
{
    (void)user;
    (void)data;
    routines++;
    if (rid == 0x0200u) {
        return len == 0u ? UDS_NRC_OK : UDS_NRC_INCORRECT_LENGTH;
    }
    if (rid == 0x0202u) {
        uds_pending_sent(&srv);
        return UDS_NRC_OK;
    }
    return rid == 0x0201u ? routine_nrc : UDS_NRC_REQUEST_OUT_OF_RANGE;
}

static int fake_has_routine(void *user, uint16_t rid)
{
    (void)user;
    return rid >= 0x0200u && rid <= 0x0202u;
}

static int setup(void **state)
{
    (void)state;
    memset(&app, 0, sizeof app);
    app.d100[0] = 0x12;
    app.d100[1] = 0x34;
    memcpy(app.d101, "\xA1\xA2\xA3\xA4", 4u);
    const uds_if_t itf = {.user = &app, .read_did = fake_read, .write_did = fake_write,
                         .is_writable = fake_writable, .start_routine = fake_routine,
                         .has_routine = fake_has_routine};
    assert_int_equal(uds_init(&srv, &itf, 12345u), 0);
    routines = 0;
    routine_nrc = UDS_NRC_CONDITIONS_NOT_CORRECT;
    return 0;
}

/* send req at t, expect exactly the bytes exp (n 0: no response) */
#define EXPECT(t, req, exp)                                                                  \
    do {                                                                                     \
        const uint8_t rq_[] = req;                                                           \
        const uint8_t ex_[] = exp;                                                           \
        const size_t n_ = uds_handle(&srv, rq_, sizeof rq_, (t), rsp, sizeof rsp);           \
        assert_int_equal(n_, sizeof ex_);                                                    \
        assert_memory_equal(rsp, ex_, sizeof ex_);                                           \
    } while (0)
#define EXPECT_NONE(t, req)                                                                  \
    do {                                                                                     \
        const uint8_t rq_[] = req;                                                           \
        assert_int_equal(uds_handle(&srv, rq_, sizeof rq_, (t), rsp, sizeof rsp), 0u);       \
    } while (0)
#define B(...) {__VA_ARGS__}

static uint32_t seed_of(const uint8_t *r)
{
    return ((uint32_t)r[2] << 24) | ((uint32_t)r[3] << 16) | ((uint32_t)r[4] << 8) | r[5];
}

/* the seed and its key in the session the server is in: unlocked */
static void unlock_in_session(uint64_t t)
{
    const uint8_t rq[] = {0x27, 0x01};
    assert_int_equal(uds_handle(&srv, rq, 2u, t, rsp, sizeof rsp), 6u);
    assert_int_equal(rsp[0], 0x67);
    assert_int_equal(rsp[1], 0x01);
    const uint32_t k = uds_key_of_seed(seed_of(rsp));
    const uint8_t key[] = {0x27, 0x02, (uint8_t)(k >> 24), (uint8_t)(k >> 16), (uint8_t)(k >> 8),
                           (uint8_t)k};
    assert_int_equal(uds_handle(&srv, key, sizeof key, t, rsp, sizeof rsp), 2u);
    assert_int_equal(rsp[0], 0x67);
    assert_int_equal(rsp[1], 0x02);
    assert_int_equal(srv.unlocked, 1);
}

/* the extended session, then the seed and its key: unlocked */
static void unlock(uint64_t t)
{
    EXPECT(t, B(0x10, 0x03), B(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4));
    unlock_in_session(t);
}

static void test_key_algorithm_as_documented(void **state)
{
    (void)state;
    /* docs/can.md: k = rotl32(s ^ 0x4E415645, 5) + 0x43553136 */
    assert_int_equal(uds_key_of_seed(0x4E415645u), 0x43553136u);
    /* 0x00000001 ^ 0x4E415645 = 0x4E415644; rotl 5 = 0xC82AC889; + 0x43553136 = 0x0B7FF9BF */
    assert_int_equal(uds_key_of_seed(1u), 0x0B7FF9BFu);
}

static void test_session_control_and_timings(void **state)
{
    (void)state;
    assert_int_equal(srv.session, UDS_SESSION_DEFAULT);
    /* P2 50 ms = 0x0032 (1 ms), P2* 5000 ms = 0x01F4 (10 ms) */
    EXPECT(0, B(0x10, 0x01), B(0x50, 0x01, 0x00, 0x32, 0x01, 0xF4));
    EXPECT(0, B(0x10, 0x03), B(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4));
    assert_int_equal(srv.session, UDS_SESSION_EXTENDED);
    EXPECT(0, B(0x10, 0x02), B(0x7F, 0x10, 0x12));    /* programming: not supported */
    EXPECT(0, B(0x10, 0x04), B(0x7F, 0x10, 0x12));
    EXPECT(0, B(0x10), B(0x7F, 0x10, 0x13));          /* no sub-function */
    EXPECT(0, B(0x10, 0x01, 0x00), B(0x7F, 0x10, 0x13));
    EXPECT(0, B(0x10, 0x82), B(0x7F, 0x10, 0x12));    /* suppressed: a negative still goes */
    assert_int_equal(srv.session, UDS_SESSION_EXTENDED);
    EXPECT_NONE(0, B(0x10, 0x81));                    /* suppressed positive */
    assert_int_equal(srv.session, UDS_SESSION_DEFAULT);
    EXPECT_NONE(0, B(0x10, 0x83));
    assert_int_equal(srv.session, UDS_SESSION_EXTENDED);
}

static void test_unknown_service_and_empty(void **state)
{
    (void)state;
    EXPECT(0, B(0x34, 0x00, 0x44), B(0x7F, 0x34, 0x11)); /* RequestDownload: not served */
    EXPECT(0, B(0x19, 0x02, 0xFF), B(0x7F, 0x19, 0x11));
    EXPECT(0, B(0x85, 0x02), B(0x7F, 0x85, 0x11));
    const uint8_t none[1] = {0};
    assert_int_equal(uds_handle(&srv, none, 0u, 0, rsp, sizeof rsp), 0u);
    assert_int_equal(srv.cnt.negative, 3u);
}

static void test_tester_present(void **state)
{
    (void)state;
    EXPECT(0, B(0x3E, 0x00), B(0x7E, 0x00));
    EXPECT_NONE(0, B(0x3E, 0x80));
    EXPECT(0, B(0x3E, 0x01), B(0x7F, 0x3E, 0x12));
    EXPECT(0, B(0x3E), B(0x7F, 0x3E, 0x13));
    EXPECT(0, B(0x3E, 0x00, 0x00), B(0x7F, 0x3E, 0x13));
}

static void test_s3_timeout_back_to_default_and_relocked(void **state)
{
    (void)state;
    unlock(1 * S);
    uds_poll(&srv, 1 * S + UDS_S3_US - 1u);
    assert_int_equal(srv.session, UDS_SESSION_EXTENDED);
    EXPECT(1 * S + UDS_S3_US - 1u, B(0x3E, 0x00), B(0x7E, 0x00)); /* restarts S3 */
    uds_poll(&srv, 1 * S + 2u * UDS_S3_US - 2u);
    assert_int_equal(srv.session, UDS_SESSION_EXTENDED);
    assert_int_equal(srv.unlocked, 1);
    uds_poll(&srv, 1 * S + 2u * UDS_S3_US - 1u);
    assert_int_equal(srv.session, UDS_SESSION_DEFAULT);
    assert_int_equal(srv.unlocked, 0);
    assert_int_equal(srv.cnt.s3_timeouts, 1u);
    /* the timeout also applies when the next request comes late without a poll */
    unlock(20 * S);
    EXPECT(20 * S + UDS_S3_US, B(0x2E, 0x01, 0x00, 0x55, 0x66), B(0x7F, 0x2E, 0x7F));
    /* a time that goes backwards is no time elapsed */
    EXPECT(30 * S, B(0x10, 0x03), B(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4));
    uds_poll(&srv, 1 * S);
    assert_int_equal(srv.session, UDS_SESSION_EXTENDED);
}

static void test_read_one_and_several_dids(void **state)
{
    (void)state;
    EXPECT(0, B(0x22, 0x01, 0x00), B(0x62, 0x01, 0x00, 0x12, 0x34));
    EXPECT(0, B(0x22, 0x01, 0x01, 0xF1, 0x95, 0x01, 0x00),
           B(0x62, 0x01, 0x01, 0xA1, 0xA2, 0xA3, 0xA4, 0xF1, 0x95, 'v', '1', 0x01, 0x00, 0x12, 0x34));
    /* an unsupported DID among supported ones is left out */
    EXPECT(0, B(0x22, 0x77, 0x77, 0x01, 0x00), B(0x62, 0x01, 0x00, 0x12, 0x34));
    /* none supported */
    EXPECT(0, B(0x22, 0x77, 0x77), B(0x7F, 0x22, 0x31));
    EXPECT(0, B(0x22, 0x77, 0x77, 0x88, 0x88), B(0x7F, 0x22, 0x31));
    /* lengths: no DID, half a DID */
    EXPECT(0, B(0x22), B(0x7F, 0x22, 0x13));
    EXPECT(0, B(0x22, 0x01), B(0x7F, 0x22, 0x13));
    EXPECT(0, B(0x22, 0x01, 0x00, 0x01), B(0x7F, 0x22, 0x13));
    /* too long for the response buffer */
    EXPECT(0, B(0x22, 0x01, 0x02), B(0x7F, 0x22, 0x14));
}

static void test_read_did_count_limit_and_response_too_long(void **state)
{
    (void)state;
    uint8_t req[1u + 2u * (UDS_MAX_READ_DIDS + 1u)];
    req[0] = 0x22;
    for (size_t i = 0u; i <= UDS_MAX_READ_DIDS; i++) {
        req[1u + 2u * i] = 0x01;
        req[2u + 2u * i] = 0x00;
    }
    uint8_t big[1u + 4u * UDS_MAX_READ_DIDS];
    /* UDS_MAX_READ_DIDS DIDs: allowed, 4 bytes each */
    assert_int_equal(uds_handle(&srv, req, 1u + 2u * UDS_MAX_READ_DIDS, 0, big, sizeof big),
                     1u + 4u * UDS_MAX_READ_DIDS);
    assert_int_equal(big[0], 0x62);
    /* one more: 0x13 */
    assert_int_equal(uds_handle(&srv, req, sizeof req, 0, big, sizeof big), 3u);
    assert_int_equal(big[2], 0x13);
    /* as many into a 64-byte buffer: 0x14 */
    assert_int_equal(uds_handle(&srv, req, 1u + 2u * UDS_MAX_READ_DIDS, 0, rsp, sizeof rsp), 3u);
    assert_memory_equal(rsp, "\x7F\x22\x14", 3u);
}

static void test_security_access_needs_extended_session(void **state)
{
    (void)state;
    EXPECT(0, B(0x27, 0x01), B(0x7F, 0x27, 0x7F));
    EXPECT(0, B(0x27), B(0x7F, 0x27, 0x7F)); /* the session is checked before the length */
    EXPECT(0, B(0x10, 0x03), B(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4));
    EXPECT(0, B(0x27), B(0x7F, 0x27, 0x13));
    EXPECT(0, B(0x27, 0x03), B(0x7F, 0x27, 0x12)); /* level 0x03 / 0x04: not there */
    EXPECT(0, B(0x27, 0x04, 1, 2, 3, 4), B(0x7F, 0x27, 0x12));
    EXPECT(0, B(0x27, 0x01, 0x00), B(0x7F, 0x27, 0x13));
    EXPECT(0, B(0x27, 0x02, 1, 2, 3), B(0x7F, 0x27, 0x13));
    /* a key without a seed */
    EXPECT(0, B(0x27, 0x02, 1, 2, 3, 4), B(0x7F, 0x27, 0x24));
}

static void test_seed_key_unlock_zero_seed_and_relock(void **state)
{
    (void)state;
    unlock(0);
    /* already unlocked: the seed is 0 */
    EXPECT(0, B(0x27, 0x01), B(0x67, 0x01, 0, 0, 0, 0));
    /* a session change relocks: the same session too */
    EXPECT(0, B(0x10, 0x03), B(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4));
    assert_int_equal(srv.unlocked, 0);
    const uint8_t rq[] = {0x27, 0x01};
    assert_int_equal(uds_handle(&srv, rq, 2u, 7, rsp, sizeof rsp), 6u);
    assert_int_not_equal(seed_of(rsp), 0u);
    /* the seed is good for one key: a second key is a sequence error */
    const uint32_t k = uds_key_of_seed(seed_of(rsp));
    const uint8_t key[] = {0x27, 0x02, (uint8_t)(k >> 24), (uint8_t)(k >> 16), (uint8_t)(k >> 8),
                           (uint8_t)k};
    assert_int_equal(uds_handle(&srv, key, sizeof key, 7, rsp, sizeof rsp), 2u);
    assert_int_equal(srv.unlocked, 1);
    assert_int_equal(uds_handle(&srv, key, sizeof key, 7, rsp, sizeof rsp), 3u);
    assert_memory_equal(rsp, "\x7F\x27\x24", 3u);
    assert_int_equal(srv.unlocked, 1); /* a sequence error does not relock */
    /* suppressed positive seed response (locked again first) */
    EXPECT_NONE(0, B(0x10, 0x83));
    EXPECT_NONE(0, B(0x27, 0x81));
    assert_int_equal(srv.seed_pending, 1);
}

static void wrong_key(uint64_t t, uint8_t expect_nrc)
{
    const uint8_t rq[] = {0x27, 0x01};
    assert_int_equal(uds_handle(&srv, rq, 2u, t, rsp, sizeof rsp), 6u);
    const uint32_t k = uds_key_of_seed(seed_of(rsp)) ^ 1u;
    const uint8_t key[] = {0x27, 0x02, (uint8_t)(k >> 24), (uint8_t)(k >> 16), (uint8_t)(k >> 8),
                           (uint8_t)k};
    assert_int_equal(uds_handle(&srv, key, sizeof key, t, rsp, sizeof rsp), 3u);
    const uint8_t exp[] = {0x7F, 0x27, expect_nrc};
    assert_memory_equal(rsp, exp, 3u);
}

static void test_three_wrong_keys_then_delay(void **state)
{
    (void)state;
    EXPECT(0, B(0x10, 0x03), B(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4));
    wrong_key(1 * S, 0x35);
    wrong_key(1 * S, 0x35);
    wrong_key(2 * S, 0x36);
    assert_int_equal(srv.cnt.wrong_keys, 3u);
    /* 10 s of 0x37 for seed and key alike (TesterPresent keeps the session meanwhile) */
    EXPECT(2 * S, B(0x27, 0x01), B(0x7F, 0x27, 0x37));
    EXPECT(2 * S, B(0x27, 0x02, 1, 2, 3, 4), B(0x7F, 0x27, 0x37));
    EXPECT(6 * S, B(0x3E, 0x00), B(0x7E, 0x00));
    EXPECT(10 * S, B(0x3E, 0x00), B(0x7E, 0x00));
    EXPECT(2 * S + UDS_SECURITY_DELAY_US - 1u, B(0x27, 0x01), B(0x7F, 0x27, 0x37));
    /* then three attempts again, and a good key clears the count */
    wrong_key(2 * S + UDS_SECURITY_DELAY_US, 0x35);
    const uint8_t rq[] = {0x27, 0x01};
    assert_int_equal(uds_handle(&srv, rq, 2u, 13 * S, rsp, sizeof rsp), 6u);
    const uint32_t k = uds_key_of_seed(seed_of(rsp));
    const uint8_t key[] = {0x27, 0x02, (uint8_t)(k >> 24), (uint8_t)(k >> 16), (uint8_t)(k >> 8),
                           (uint8_t)k};
    assert_int_equal(uds_handle(&srv, key, sizeof key, 13 * S, rsp, sizeof rsp), 2u);
    assert_int_equal(srv.attempts, 0);
    assert_int_equal(srv.unlocked, 1);
}

static void test_delay_ends_on_poll_too(void **state)
{
    (void)state;
    EXPECT(0, B(0x10, 0x03), B(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4));
    wrong_key(0, 0x35);
    wrong_key(0, 0x35);
    wrong_key(0, 0x36);
    uds_poll(&srv, UDS_SECURITY_DELAY_US - 1u);
    assert_int_equal(srv.delay_on, 1);
    uds_poll(&srv, UDS_SECURITY_DELAY_US);
    assert_int_equal(srv.delay_on, 0);
}

static void test_write_did_every_refusal_then_accepted(void **state)
{
    (void)state;
    /* default session: 0x7F, whatever the rest */
    EXPECT(0, B(0x2E, 0x01, 0x00, 0x55, 0x66), B(0x7F, 0x2E, 0x7F));
    EXPECT(0, B(0x2E), B(0x7F, 0x2E, 0x7F));
    EXPECT(0, B(0x10, 0x03), B(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4));
    /* too short for a DID and a value */
    EXPECT(0, B(0x2E, 0x01, 0x00), B(0x7F, 0x2E, 0x13));
    /* not writable (read-only, unknown): 0x31 before the security check */
    EXPECT(0, B(0x2E, 0xF1, 0x95, 0x41), B(0x7F, 0x2E, 0x31));
    EXPECT(0, B(0x2E, 0x77, 0x77, 0x41), B(0x7F, 0x2E, 0x31));
    /* locked */
    EXPECT(0, B(0x2E, 0x01, 0x00, 0x55, 0x66), B(0x7F, 0x2E, 0x33));
    assert_int_equal(app.writes, 0);
    unlock(0);
    /* the application's verdicts pass through */
    EXPECT(0, B(0x2E, 0x01, 0x00, 0x55), B(0x7F, 0x2E, 0x13));
    app.write_nrc = UDS_NRC_REQUEST_OUT_OF_RANGE;
    EXPECT(0, B(0x2E, 0x01, 0x00, 0x55, 0x66), B(0x7F, 0x2E, 0x31));
    app.write_nrc = UDS_NRC_CONDITIONS_NOT_CORRECT;
    EXPECT(0, B(0x2E, 0x01, 0x00, 0x55, 0x66), B(0x7F, 0x2E, 0x22));
    app.write_nrc = 0u;
    EXPECT(0, B(0x2E, 0x01, 0x00, 0x55, 0x66), B(0x6E, 0x01, 0x00));
    EXPECT(0, B(0x22, 0x01, 0x00), B(0x62, 0x01, 0x00, 0x55, 0x66));
}

static void test_ecu_reset(void **state)
{
    (void)state;
    EXPECT(0, B(0x11, 0x01), B(0x7F, 0x11, 0x33)); /* locked */
    EXPECT(0, B(0x11), B(0x7F, 0x11, 0x13));
    EXPECT(0, B(0x11, 0x02), B(0x7F, 0x11, 0x12)); /* keyOffOnReset: not supported */
    EXPECT(0, B(0x11, 0x03), B(0x7F, 0x11, 0x12));
    assert_int_equal(uds_take_reset(&srv), 0);
    unlock(0);
    EXPECT(0, B(0x11, 0x01, 0x00), B(0x7F, 0x11, 0x13));
    EXPECT(0, B(0x11, 0x01), B(0x51, 0x01));
    assert_int_equal(uds_take_reset(&srv), 1);
    assert_int_equal(uds_take_reset(&srv), 0); /* once */
    EXPECT_NONE(0, B(0x11, 0x81));
    assert_int_equal(uds_take_reset(&srv), 1);
}

static void test_init_refuses_incomplete_interface(void **state)
{
    (void)state;
    uds_t s;
    const uds_if_t no_write = {.user = &app, .read_did = fake_read, .write_did = NULL,
                              .is_writable = fake_writable};
    assert_int_equal(uds_init(&s, &no_write, 0u), -1);
    assert_int_equal(uds_init(NULL, &no_write, 0u), -1);
    const uds_if_t ok = {.user = &app, .read_did = fake_read, .write_did = fake_write,
                        .is_writable = fake_writable};
    assert_int_equal(uds_init(&s, &ok, 0u), 0); /* entropy 0 is allowed */
    assert_int_not_equal(s.prng, 0u);
    /* a response buffer under 8 bytes: nothing */
    const uint8_t rq[] = {0x3E, 0x00};
    uint8_t small[7];
    assert_int_equal(uds_handle(&s, rq, 2u, 0, small, sizeof small), 0u);
}

/* ---- the fault memory: a fake of 3 DTCs ---- */

static const uint32_t fake_dtc_numbers[3] = {0xD10187u, 0x510196u, 0x123456u};
static uint8_t fake_dtc_status[3];
static uint8_t fake_clear_nrc;
static uint32_t fake_clear_group;
static int fake_clears;

static size_t fake_dtc_count(void *user)
{
    (void)user;
    return 3u;
}

static int fake_dtc_get(void *user, size_t i, uint32_t *dtc, uint8_t *status)
{
    (void)user;
    if (i >= 3u) {
        return -1;
    }
    *dtc = fake_dtc_numbers[i];
    *status = fake_dtc_status[i];
    return 0;
}

static uint8_t fake_dtc_clear(void *user, uint32_t group)
{
    (void)user;
    fake_clears++;
    fake_clear_group = group;
    if (fake_clear_nrc == 0u) {
        memset(fake_dtc_status, 0x50, sizeof fake_dtc_status);
    }
    return fake_clear_nrc;
}

static uint8_t fake_dtc_avail(void *user)
{
    (void)user;
    return 0x7Fu;
}

static int setup_dtc(void **state)
{
    (void)state;
    memset(&app, 0, sizeof app);
    fake_dtc_status[0] = 0x2F; /* failing now, confirmed */
    fake_dtc_status[1] = 0x50; /* never tested since the clear */
    fake_dtc_status[2] = 0xA8; /* confirmed, not failing; bit 7 not supported: 0x28 sent */
    fake_clear_nrc = 0u;
    fake_clears = 0;
    fake_clear_group = 0u;
    const uds_if_t itf = {.user = &app,
                          .read_did = fake_read,
                          .write_did = fake_write,
                          .is_writable = fake_writable,
                          .dtc_count = fake_dtc_count,
                          .dtc_get = fake_dtc_get,
                          .dtc_clear = fake_dtc_clear,
                          .dtc_availability = fake_dtc_avail};
    assert_int_equal(uds_init(&srv, &itf, 1u), 0);
    return 0;
}

/* ISO 14229-1 11.3: 19 01 mask -> 59 01 availability format count(2) */
static void test_read_dtc_number_by_status_mask(void **state)
{
    (void)state;
    EXPECT(0, B(0x19, 0x01, 0x08), B(0x59, 0x01, 0x7F, 0x00, 0x00, 0x02)); /* confirmed */
    EXPECT(0, B(0x19, 0x01, 0x01), B(0x59, 0x01, 0x7F, 0x00, 0x00, 0x01)); /* failing */
    EXPECT(0, B(0x19, 0x01, 0x80), B(0x59, 0x01, 0x7F, 0x00, 0x00, 0x00)); /* bit 7: none */
    EXPECT(0, B(0x19, 0x01, 0xFF), B(0x59, 0x01, 0x7F, 0x00, 0x00, 0x03));
    EXPECT_NONE(0, B(0x19, 0x81, 0xFF)); /* suppressPosRspMsgIndicationBit */
}

/* 19 02 mask -> 59 02 availability [DTC(3) status] of the DTCs with status & mask != 0 */
static void test_read_dtc_by_status_mask(void **state)
{
    (void)state;
    EXPECT(0, B(0x19, 0x02, 0x08),
           B(0x59, 0x02, 0x7F, 0xD1, 0x01, 0x87, 0x2F, 0x12, 0x34, 0x56, 0x28));
    EXPECT(0, B(0x19, 0x02, 0x10), B(0x59, 0x02, 0x7F, 0x51, 0x01, 0x96, 0x50));
    EXPECT(0, B(0x19, 0x02, 0x00), B(0x59, 0x02, 0x7F)); /* no DTC matches: none listed */
}

/* 19 0A -> 59 0A availability [DTC(3) status] of every DTC */
static void test_read_supported_dtc(void **state)
{
    (void)state;
    EXPECT(0, B(0x19, 0x0A),
           B(0x59, 0x0A, 0x7F, 0xD1, 0x01, 0x87, 0x2F, 0x51, 0x01, 0x96, 0x50, 0x12, 0x34, 0x56,
             0x28));
}

static void test_read_dtc_refusals(void **state)
{
    (void)state;
    EXPECT(0, B(0x19), B(0x7F, 0x19, 0x13));                 /* no sub-function */
    EXPECT(0, B(0x19, 0x04, 0x00), B(0x7F, 0x19, 0x12));     /* a sub-function not served */
    EXPECT(0, B(0x19, 0x01), B(0x7F, 0x19, 0x13));           /* no mask */
    EXPECT(0, B(0x19, 0x02, 0x08, 0x00), B(0x7F, 0x19, 0x13)); /* one byte too many */
    EXPECT(0, B(0x19, 0x0A, 0x00), B(0x7F, 0x19, 0x13));
    /* a response longer than the buffer: 0x14 (3 DTCs need 15 bytes) */
    const uint8_t rq[] = {0x19, 0x0A};
    uint8_t small[12];
    assert_int_equal(uds_handle(&srv, rq, 2u, 0, small, sizeof small), 3u);
    assert_memory_equal(small, ((const uint8_t[]){0x7F, 0x19, 0x14}), 3u);
}

/* 14 FF FF FF -> 54, in the default session as ISO 14229-1 allows; another group 0x31 */
static void test_clear_dtc(void **state)
{
    (void)state;
    EXPECT(0, B(0x14, 0xFF, 0xFF, 0xFF), B(0x54));
    assert_int_equal(fake_clears, 1);
    assert_int_equal(fake_clear_group, 0xFFFFFFu);
    EXPECT(0, B(0x19, 0x01, 0x08), B(0x59, 0x01, 0x7F, 0x00, 0x00, 0x00)); /* gone */
    EXPECT(0, B(0x14, 0x00, 0x01, 0x00), B(0x7F, 0x14, 0x31)); /* one group: not served */
    EXPECT(0, B(0x14, 0xFF, 0xFF), B(0x7F, 0x14, 0x13));
    EXPECT(0, B(0x14, 0xFF, 0xFF, 0xFF, 0x00), B(0x7F, 0x14, 0x13));
    assert_int_equal(fake_clears, 1); /* none of the refused ones reached the application */
    fake_clear_nrc = 0x72u;           /* the NVM write fails: generalProgrammingFailure */
    EXPECT(0, B(0x14, 0xFF, 0xFF, 0xFF), B(0x7F, 0x14, 0x72));
    /* in the extended session too */
    EXPECT(0, B(0x10, 0x03), B(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4));
    fake_clear_nrc = 0u;
    EXPECT(0, B(0x14, 0xFF, 0xFF, 0xFF), B(0x54));
}

/* no fault memory in the interface: both services 0x11, whatever their length */
static void test_no_fault_memory_is_service_not_supported(void **state)
{
    (void)state;
    EXPECT(0, B(0x19, 0x01, 0xFF), B(0x7F, 0x19, 0x11));
    EXPECT(0, B(0x19), B(0x7F, 0x19, 0x11));
    EXPECT(0, B(0x14, 0xFF, 0xFF, 0xFF), B(0x7F, 0x14, 0x11));
}

/* RoutineControl 0x31: default session 0x7F; no sub-function 0x13; a sub-function other
 * than startRoutine 0x12; under 4 bytes 0x13; an unknown routine 0x31, then locked 0x33
 * (ISO 14229-1's order); then the application's answer (0x22, 0x72) as a negative
 * response, or 71 01 RID; suppressPosRsp, but not after a 7F 31 78 went out; an
 * application without routines: 0x11 in every session */
static void test_routine_control(void **state)
{
    (void)state;
    EXPECT(0, B(0x31, 0x01, 0x02, 0x00), B(0x7F, 0x31, 0x7F));
    EXPECT(0, B(0x10, 0x03), B(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4));
    EXPECT(0, B(0x31), B(0x7F, 0x31, 0x13));
    EXPECT(0, B(0x31, 0x02, 0x02, 0x00), B(0x7F, 0x31, 0x12));
    EXPECT(0, B(0x31, 0x03, 0x02, 0x00), B(0x7F, 0x31, 0x12));
    EXPECT(0, B(0x31, 0x01, 0x02), B(0x7F, 0x31, 0x13));
    EXPECT(0, B(0x31, 0x01, 0x02, 0x00), B(0x7F, 0x31, 0x33));
    EXPECT(0, B(0x31, 0x01, 0x12, 0x34), B(0x7F, 0x31, 0x31));
    assert_int_equal(routines, 0);
    unlock(0);
    EXPECT(0, B(0x31, 0x01, 0x02, 0x00), B(0x71, 0x01, 0x02, 0x00));
    EXPECT(0, B(0x31, 0x01, 0x02, 0x00, 0x55), B(0x7F, 0x31, 0x13));
    EXPECT(0, B(0x31, 0x01, 0x02, 0x01), B(0x7F, 0x31, 0x22));
    routine_nrc = UDS_NRC_GENERAL_PROGRAMMING_FAILURE;
    EXPECT(0, B(0x31, 0x01, 0x02, 0x01), B(0x7F, 0x31, 0x72));
    EXPECT(0, B(0x31, 0x01, 0x12, 0x34), B(0x7F, 0x31, 0x31));
    EXPECT_NONE(0, B(0x31, 0x81, 0x02, 0x00));
    EXPECT(0, B(0x31, 0x81, 0x12, 0x34), B(0x7F, 0x31, 0x31)); /* negative: sent */
    /* the tester waits for the final response once it saw a 7F 31 78, suppressed or not */
    EXPECT(0, B(0x31, 0x81, 0x02, 0x02), B(0x71, 0x01, 0x02, 0x02));
    EXPECT_NONE(0, B(0x31, 0x81, 0x02, 0x00)); /* the next request's own */
    assert_int_equal(routines, 7); /* the unknown ones never reach the application */

    uds_t s;
    const uds_if_t none = {.user = &app, .read_did = fake_read, .write_did = fake_write,
                           .is_writable = fake_writable};
    assert_int_equal(uds_init(&s, &none, 1u), 0);
    const uint8_t rq[] = {0x31, 0x01, 0x02, 0x00};
    assert_int_equal(uds_handle(&s, rq, sizeof rq, 0, rsp, sizeof rsp), 3u);
    assert_memory_equal(rsp, "\x7F\x31\x11", 3u);
}

/* the pluggable parts (uds_if_t.session_change, .service), as the bootloader uses them */
static uint8_t session_veto;   /* what fake_session answers */
static uint8_t last_session;
static size_t service_len;     /* the length fake_service reports */
static uint8_t service_seen[3]; /* session, unlocked, SID of its last call */

static uint8_t fake_session(void *user, uint8_t session)
{
    (void)user;
    last_session = session;
    return session_veto;
}

static uint8_t fake_service(void *user, uint8_t session, uint8_t unlocked, const uint8_t *req,
                            size_t len, uint8_t *out, size_t cap, size_t *rsp_len)
{
    (void)user;
    (void)len;
    (void)cap;
    service_seen[0] = session;
    service_seen[1] = unlocked;
    service_seen[2] = req[0];
    if (req[0] != 0x34u) {
        return UDS_NRC_SERVICE_NOT_SUPPORTED;
    }
    out[1] = 0x20u;
    *rsp_len = service_len;
    return UDS_NRC_OK;
}

static void test_pluggable_session_and_service(void **state)
{
    (void)state;
    const uds_if_t itf = {.user = &app, .read_did = fake_read, .write_did = fake_write,
                          .is_writable = fake_writable, .start_routine = fake_routine,
                          .has_routine = fake_has_routine, .session_change = fake_session, .service = fake_service};
    assert_int_equal(uds_init(&srv, &itf, 7u), 0);
    /* the hook decides every session; a veto is its NRC, the session unchanged */
    session_veto = UDS_NRC_CONDITIONS_NOT_CORRECT;
    EXPECT(0, B(0x10, 0x02), B(0x7F, 0x10, 0x22));
    assert_int_equal(last_session, UDS_SESSION_PROGRAMMING);
    assert_int_equal(srv.session, UDS_SESSION_DEFAULT);
    session_veto = UDS_NRC_OK;
    EXPECT(0, B(0x10, 0x02), B(0x50, 0x02, 0x00, 0x32, 0x01, 0xF4));
    assert_int_equal(srv.session, UDS_SESSION_PROGRAMMING);
    EXPECT(0, B(0x10, 0x04), B(0x7F, 0x10, 0x12)); /* still not a session */
    /* SecurityAccess and RoutineControl in the programming session */
    unlock_in_session(0);
    assert_int_equal(srv.session, UDS_SESSION_PROGRAMMING);
    EXPECT(0, B(0x31, 0x01, 0x02, 0x00), B(0x71, 0x01, 0x02, 0x00));
    /* a service of the hook: its response, with the session and security it was given */
    service_len = 2u;
    EXPECT(0, B(0x34, 0x00), B(0x74, 0x20));
    assert_memory_equal(service_seen, "\x02\x01\x34", 3u);
    EXPECT(0, B(0x85, 0x02), B(0x7F, 0x85, 0x11)); /* the hook's own "not mine" */
    /* a hook that breaks its contract (no response byte, or more than cap): 0x72 */
    service_len = 0u;
    EXPECT(0, B(0x34, 0x00), B(0x7F, 0x34, 0x72));
    service_len = sizeof rsp + 1u;
    EXPECT(0, B(0x34, 0x00), B(0x7F, 0x34, 0x72));
    /* the session's own positive response, as a bootloader sends it unasked */
    uint8_t r[6];
    assert_int_equal(uds_session_response(UDS_SESSION_PROGRAMMING, r), 6u);
    assert_memory_equal(r, "\x50\x02\x00\x32\x01\xF4", 6u);
    uds_set_session(&srv, UDS_SESSION_PROGRAMMING, 5u);
    assert_int_equal(srv.unlocked, 0);
    uds_poll(&srv, 5u + UDS_S3_US);
    assert_int_equal(srv.session, UDS_SESSION_DEFAULT); /* S3 from uds_set_session's time */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_key_algorithm_as_documented, setup),
        cmocka_unit_test_setup(test_session_control_and_timings, setup),
        cmocka_unit_test_setup(test_unknown_service_and_empty, setup),
        cmocka_unit_test_setup(test_tester_present, setup),
        cmocka_unit_test_setup(test_s3_timeout_back_to_default_and_relocked, setup),
        cmocka_unit_test_setup(test_read_one_and_several_dids, setup),
        cmocka_unit_test_setup(test_read_did_count_limit_and_response_too_long, setup),
        cmocka_unit_test_setup(test_security_access_needs_extended_session, setup),
        cmocka_unit_test_setup(test_seed_key_unlock_zero_seed_and_relock, setup),
        cmocka_unit_test_setup(test_three_wrong_keys_then_delay, setup),
        cmocka_unit_test_setup(test_delay_ends_on_poll_too, setup),
        cmocka_unit_test_setup(test_write_did_every_refusal_then_accepted, setup),
        cmocka_unit_test_setup(test_ecu_reset, setup),
        cmocka_unit_test_setup(test_init_refuses_incomplete_interface, setup),
        cmocka_unit_test_setup(test_read_dtc_number_by_status_mask, setup_dtc),
        cmocka_unit_test_setup(test_read_dtc_by_status_mask, setup_dtc),
        cmocka_unit_test_setup(test_read_supported_dtc, setup_dtc),
        cmocka_unit_test_setup(test_read_dtc_refusals, setup_dtc),
        cmocka_unit_test_setup(test_clear_dtc, setup_dtc),
        cmocka_unit_test_setup(test_no_fault_memory_is_service_not_supported, setup),
        cmocka_unit_test_setup(test_routine_control, setup),
        cmocka_unit_test_setup(test_pluggable_session_and_service, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
