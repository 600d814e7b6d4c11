/*
 * test_app_uds.c - the UDS server inside the application (firmware/app/app_uds.c) against
 * the in-memory HAL: requests as ISO-TP frames on the request ID through app_handle_frame,
 * responses read back from the frames sent on the response ID. Every parameter DID and the
 * identification DIDs read (one by one and all at once, a multi-frame response), the
 * frames never counted as navecu's input, writes refused and accepted through the
 * parameter table's checks, the navigation-stopped rule, ECUReset, S3 on the HAL clock,
 * the identifier rules of app_config_valid and the receive list.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app.h"
#include "app_fixture.h"
#include "can_frames.h"
#include "fake_hal.h"
#include "test_util.h"
#include "vehicle.h"

#define REQ 0x7A0u
#define RSP 0x7A8u

static hal_t hal;
static app_t app;
static uint8_t rsp[ISOTP_MAX_LEN];

static int setup(void **state)
{
    (void)state;
    assert_int_equal(fx_fresh_app(&app, &hal), NAV_OK);
    hal.t_us = 1000000u;
    return 0;
}

static void tester_frame(const uint8_t *d, uint8_t n)
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = REQ;
    f.dlc = 8u;
    memset(f.data, 0xCC, 8u);
    memcpy(f.data, d, n);
    f.t_us = hal.t_us;
    app_handle_frame(&app, &hal, &f);
    app_poll(&app, &hal);
}

/* one request (SF, or FF + CFs) and its response reassembled: its length, 0 for none */
static int pendings; /* 7F SID 78 responsePending seen by request() */

static size_t request(const uint8_t *req, size_t n)
{
    const uint32_t mark = hal.tx_n;
    if (n <= 7u) {
        uint8_t sf[8] = {(uint8_t)n};
        memcpy(&sf[1], req, n);
        tester_frame(sf, (uint8_t)(n + 1u));
    } else {
        uint8_t ff[8] = {(uint8_t)(0x10u | (n >> 8)), (uint8_t)n};
        memcpy(&ff[2], req, 6u);
        tester_frame(ff, 8u);
        size_t pos = 6u;
        for (uint8_t sn = 1u; pos < n; sn++) {
            uint8_t cf[8] = {(uint8_t)(0x20u | (sn & 0xFu))};
            const size_t k = n - pos < 7u ? n - pos : 7u;
            memcpy(&cf[1], &req[pos], k);
            tester_frame(cf, (uint8_t)(1u + k));
            pos += k;
        }
    }
    size_t len = 0u;
    size_t got = 0u;
    int polls = 0;
    for (uint32_t i = mark;; i++) {
        if (i >= hal.tx_n && len > 0u && got < len && polls++ < 100) {
            app_poll(&app, &hal); /* the next burst of CFs */
        }
        if (i >= hal.tx_n) {
            break;
        }
        const hal_can_frame_t *f = &hal.tx[i];
        if (f->id != RSP) {
            continue;
        }
        const uint8_t pci = (uint8_t)(f->data[0] >> 4);
        if (pci == 3u) {
            continue; /* the ECU's FC for our FF */
        }
        if (pci == 0u) {
            len = f->data[0] & 0xFu;
            memcpy(rsp, &f->data[1], len);
            if (len == 3u && rsp[0] == 0x7F && rsp[2] == 0x78) {
                pendings++; /* responsePending: the final response follows */
                len = 0u;
                continue;
            }
            return len;
        }
        if (pci == 1u) {
            len = ((size_t)(f->data[0] & 0xFu) << 8) | f->data[1];
            memcpy(rsp, &f->data[2], 6u);
            got = 6u;
            const uint8_t fc[3] = {0x30, 0x00, 0x00}; /* CTS, all at once */
            tester_frame(fc, 3u);
            continue;
        }
        const size_t k = len - got < 7u ? len - got : 7u;
        memcpy(&rsp[got], &f->data[1], k);
        got += k;
        if (got == len) {
            return len;
        }
    }
    return got == len ? len : 0u;
}

#define REQUEST(...)                                                                         \
    request((const uint8_t[]){__VA_ARGS__}, sizeof((const uint8_t[]){__VA_ARGS__}))

static void expect_nrc(size_t n, uint8_t sid, uint8_t code)
{
    assert_int_equal(n, 3u);
    assert_int_equal(rsp[0], 0x7F);
    assert_int_equal(rsp[1], sid);
    assert_int_equal(rsp[2], code);
}

static uint32_t be32(const uint8_t *p)
{
    return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
}

static float f32_of(const uint8_t *p)
{
    const uint32_t u = be32(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* bit for bit (no -Wfloat-equal) */
static int same_f(float a, float b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

static void unlock(void)
{
    assert_int_equal(REQUEST(0x10, 0x03), 6u);
    assert_int_equal(REQUEST(0x27, 0x01), 6u);
    const uint32_t k = uds_key_of_seed(be32(&rsp[2]));
    const uint8_t key[] = {0x27, 0x02, (uint8_t)(k >> 24), (uint8_t)(k >> 16), (uint8_t)(k >> 8),
                           (uint8_t)k};
    assert_int_equal(request(key, sizeof key), 2u);
    assert_int_equal(rsp[0], 0x67);
}

/* the value of parameter k as the DID's bytes at p, checked against app_param_get */
static size_t check_param_value(int k, const uint8_t *p)
{
    nav_real_t v[3];
    app_param_get(&app.cfg, (app_param_id_t)k, v);
    switch (app_params[k].type) {
    case APP_PARAM_U16:
        assert_int_equal(((uint32_t)p[0] << 8) | p[1], (uint32_t)v[0]);
        return 2u;
    case APP_PARAM_ENUM:
        assert_int_equal(p[0], (uint32_t)v[0]);
        return 1u;
    case APP_PARAM_VEC3:
        for (int i = 0; i < 3; i++) {
            assert_true(same_f(f32_of(&p[4 * i]), (float)v[i]));
        }
        return 12u;
    default:
        assert_true(same_f(f32_of(p), (float)v[0]));
        return 4u;
    }
}

static void test_every_parameter_did_read(void **state)
{
    (void)state;
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        const uint8_t req[3] = {0x22, (uint8_t)(app_params[k].did >> 8), (uint8_t)app_params[k].did};
        const size_t n = request(req, sizeof req);
        assert_true(n >= 4u);
        assert_int_equal(rsp[0], 0x62);
        assert_memory_equal(&rsp[1], &req[1], 2u);
        assert_int_equal(n, 3u + check_param_value(k, &rsp[3]));
    }
    /* the defaults, in SI: imu_rate_hz 100, the UDS IDs */
    assert_int_equal(REQUEST(0x22, 0x02, 0x00), 5u);
    assert_memory_equal(rsp, "\x62\x02\x00\x00\x64", 5u);
    assert_int_equal(REQUEST(0x22, 0x02, 0x50, 0x02, 0x51), 9u);
    assert_memory_equal(rsp, "\x62\x02\x50\x07\xA0\x02\x51\x07\xA8", 9u);
    /* nothing of it reached navecu's dispatch */
    assert_int_equal(app_health(&app)->foreign, 0u);
    assert_int_equal(app_samples(&app), 0u);
}

static void test_identification_dids(void **state)
{
    (void)state;
    size_t n = REQUEST(0x22, 0xF1, 0x95);
    assert_int_equal(n, 3u + strlen(NAVECU_SW_VERSION));
    assert_memory_equal(&rsp[3], NAVECU_SW_VERSION, n - 3u);
    n = REQUEST(0x22, 0xF1, 0x8C);
    assert_memory_equal(&rsp[3], NAVECU_ECU_SERIAL, n - 3u);
    n = REQUEST(0x22, 0xF1, 0xA0);
    assert_int_equal(n, 3u + strlen(vehicle_profile.name));
    assert_memory_equal(&rsp[3], "native", 6u);
    n = REQUEST(0x22, 0xF1, 0xA2);
    assert_int_equal(n, 3u + strlen(NAVECU_BUILD));
    assert_memory_equal(&rsp[3], "host f32 ", 9u); /* this test's build */
    expect_nrc(REQUEST(0x22, 0xF1, 0x90), 0x22, 0x31); /* no VIN */
    /* identification DIDs are read-only */
    unlock();
    expect_nrc(REQUEST(0x2E, 0xF1, 0x95, 0x41), 0x2E, 0x31);
}

/* the mounting estimate's DID: 29 bytes, read-only; fixed mode: state 0, sigmas pi */
static void test_mount_estimate_did(void **state)
{
    (void)state;
    size_t n = REQUEST(0x22, 0x02, 0x60);
    assert_int_equal(n, 3u + 29u);
    assert_int_equal(rsp[0], 0x62);
    assert_int_equal(rsp[3], 0u); /* MountState fixed */
    /* sigma roll/pitch (bytes 13..16 of the value): pi as float32 big-endian */
    const uint8_t pi_be[4] = {0x40, 0x49, 0x0F, 0xDB};
    assert_memory_equal(&rsp[3u + 13u], pi_be, 4u);
    assert_memory_equal(&rsp[3u + 17u], pi_be, 4u);
    app.keep.mount_state = 2u;
    app.keep.mest.res.n_windows = 0x01020304u;
    n = REQUEST(0x22, 0x02, 0x60);
    assert_int_equal(rsp[3], 2u);
    const uint8_t win[4] = {1u, 2u, 3u, 4u};
    assert_memory_equal(&rsp[3u + 25u], win, 4u);
    unlock();
    expect_nrc(REQUEST(0x2E, 0x02, 0x60, 0x00), 0x2E, 0x31);
}

static void test_all_dids_in_one_request(void **state)
{
    (void)state;
    uint8_t req[1 + 2 * (APP_PARAM_N + 7)];
    size_t m = 0u;
    req[m++] = 0x22;
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        req[m++] = (uint8_t)(app_params[k].did >> 8);
        req[m++] = (uint8_t)app_params[k].did;
    }
    /* the identification DIDs, then the records: every DID the application reads */
    const uint16_t ident[7] = {APP_UDS_DID_SERIAL,     APP_UDS_DID_SW_VERSION,
                               APP_UDS_DID_VEHICLE,    APP_UDS_DID_BUILD,
                               APP_UDS_DID_NVM_STATUS, APP_UDS_DID_CMD_STATUS,
                               APP_UDS_DID_MOUNT_EST};
    for (int i = 0; i < 7; i++) {
        req[m++] = (uint8_t)(ident[i] >> 8);
        req[m++] = (uint8_t)ident[i];
    }
    const size_t n = request(req, m); /* FF + CFs in, FF + CFs out */
    assert_true(n > 7u);
    assert_int_equal(rsp[0], 0x62);
    size_t pos = 1u;
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        assert_int_equal(((uint32_t)rsp[pos] << 8) | rsp[pos + 1u], app_params[k].did);
        pos += 2u + check_param_value(k, &rsp[pos + 2u]);
    }
    pos += 2u + strlen(NAVECU_ECU_SERIAL) + 2u + strlen(NAVECU_SW_VERSION) + 2u +
           strlen(vehicle_profile.name) + 2u + strlen(NAVECU_BUILD);
    pos += 2u + 8u + 2u + 5u + 2u + APP_UDS_MOUNT_EST_LEN; /* F1A1, F1A3, 0260 (can.md) */
    assert_int_equal(n, pos);
    /* docs/can.md: every DID at once fits the ECU's ISO-TP buffer (ISOTP_MAX_LEN 512 in
     * the Makefile's M4_DEFS; the host keeps 4,095) */
    print_message("every DID at once: %zu bytes\n", n);
    assert_true(n <= 512u);
}

static void test_write_refused_then_accepted_and_read_back(void **state)
{
    (void)state;
    /* level_s (0x0204), u16: 45 s */
    expect_nrc(REQUEST(0x2E, 0x02, 0x04, 0x00, 0x2D), 0x2E, 0x7F); /* default session */
    assert_int_equal(REQUEST(0x10, 0x03), 6u);
    expect_nrc(REQUEST(0x2E, 0x02, 0x04, 0x00, 0x2D), 0x2E, 0x33); /* locked */
    unlock();
    expect_nrc(REQUEST(0x2E, 0x02, 0x04, 0x2D), 0x2E, 0x13);       /* 1 byte for a u16 */
    expect_nrc(REQUEST(0x2E, 0x02, 0x04, 0x00, 0x00), 0x2E, 0x31); /* 0 s: out of range */
    expect_nrc(REQUEST(0x2E, 0x02, 0x04, 0x02, 0x59), 0x2E, 0x31); /* 601 s */
    expect_nrc(REQUEST(0x2E, 0x77, 0x77, 0x00), 0x2E, 0x31);       /* no such DID */
    /* nav_rate_hz 200 > imu_rate_hz 100: a rule between parameters */
    expect_nrc(REQUEST(0x2E, 0x02, 0x01, 0x00, 0xC8), 0x2E, 0x31);
    /* a float: gnss_latency_s (0x0240) NaN, then 0.1 s */
    expect_nrc(REQUEST(0x2E, 0x02, 0x40, 0x7F, 0xC0, 0x00, 0x00), 0x2E, 0x31);
    assert_int_equal(REQUEST(0x2E, 0x02, 0x40, 0x3D, 0xCC, 0xCC, 0xCD), 3u);
    assert_memory_equal(rsp, "\x6E\x02\x40", 3u);
    assert_true(same_f((float)app.cfg.gnss_latency_s, 0.1f));
    assert_int_equal(REQUEST(0x2E, 0x02, 0x04, 0x00, 0x2D), 3u);
    assert_memory_equal(rsp, "\x6E\x02\x04", 3u);
    assert_int_equal(app.cfg.level_s, 45u);
    assert_int_equal(REQUEST(0x22, 0x02, 0x04), 5u);
    assert_memory_equal(rsp, "\x62\x02\x04\x00\x2D", 5u);
    /* a vec3: gnss_lever_b_m (0x0242) 1, -0.5, 0.25 m */
    assert_int_equal(REQUEST(0x2E, 0x02, 0x42, 0x3F, 0x80, 0x00, 0x00, 0xBF, 0x00, 0x00, 0x00,
                             0x3E, 0x80, 0x00, 0x00),
                     3u);
    assert_true(same_f((float)app.cfg.gnss_lever_b_m[1], -0.5f));
    /* an enum: odo_axle (0x0210) 1 = front; 2 is none */
    expect_nrc(REQUEST(0x2E, 0x02, 0x10, 0x02), 0x2E, 0x31);
    assert_int_equal(REQUEST(0x2E, 0x02, 0x10, 0x01), 3u);
    assert_int_equal(app.cfg.odo_axle, ODO_AXLE_FRONT);
}

static void test_reset_parameter_needs_navigation_stopped(void **state)
{
    (void)state;
    unlock();
    app.run.mode = APP_MODE_NAVIGATING; /* as a started navigation leaves it */
    expect_nrc(REQUEST(0x2E, 0x02, 0x00, 0x00, 0xC8), 0x2E, 0x22); /* imu_rate_hz 200 */
    app.run.mode = APP_MODE_LEVELLING;
    expect_nrc(REQUEST(0x2E, 0x02, 0x00, 0x00, 0xC8), 0x2E, 0x22);
    /* an "at once" parameter may change while navigating */
    app.run.mode = APP_MODE_NAVIGATING;
    assert_int_equal(REQUEST(0x2E, 0x02, 0x02, 0x00, 0x05), 3u); /* status_rate_hz 5 */
    /* the gyro's ARW too: app_init copies it into the IMU link and the standstill's test
     * (0.42 deg/sqrt(h) = 1.2217e-4 rad/sqrt(s), float32 0x39001B94) */
    expect_nrc(REQUEST(0x2E, 0x02, 0x30, 0x39, 0x00, 0x1B, 0x94), 0x2E, 0x22);
    app.run.mode = APP_MODE_WAIT_INIT;
    assert_int_equal(REQUEST(0x2E, 0x02, 0x00, 0x00, 0xC8), 3u);
    assert_int_equal(app.cfg.imu_rate_hz, 200u);
    assert_int_equal(REQUEST(0x2E, 0x02, 0x30, 0x39, 0x00, 0x1B, 0x94), 3u);
}

static void test_ecu_reset_restarts_with_the_configuration(void **state)
{
    (void)state;
    expect_nrc(REQUEST(0x11, 0x01), 0x11, 0x33); /* locked */
    unlock();
    assert_int_equal(REQUEST(0x2E, 0x02, 0x04, 0x00, 0x2D), 3u);
    app.keep.n_samples = 1234u; /* as if it had run */
    app.keep.health.bad_crc = 7u;
    assert_int_equal(REQUEST(0x11, 0x01), 2u); /* the response went out first */
    assert_memory_equal(rsp, "\x51\x01", 2u);
    app_poll(&app, &hal);
    assert_int_equal(app_samples(&app), 0u);
    assert_int_equal(app_health(&app)->bad_crc, 0u);
    assert_int_equal(app.cfg.level_s, 45u); /* the configuration in RAM survives */
    assert_int_equal(app.uds.srv.session, UDS_SESSION_DEFAULT);
    assert_int_equal(app.uds.srv.unlocked, 0);
    expect_nrc(REQUEST(0x2E, 0x02, 0x04, 0x00, 0x2D), 0x2E, 0x7F);
    /* suppressed: the restart at once, nothing sent */
    unlock();
    app.keep.n_samples = 99u;
    assert_int_equal(REQUEST(0x11, 0x81), 0u);
    assert_int_equal(app_samples(&app), 0u);
}

static void test_uds_ids_read_only(void **state)
{
    (void)state;
    unlock();
    /* the boards' receive filters are set from them at start: not writable over UDS */
    expect_nrc(REQUEST(0x2E, 0x02, 0x50, 0x07, 0xB0), 0x2E, 0x31);
    expect_nrc(REQUEST(0x2E, 0x02, 0x51, 0x07, 0xB8), 0x2E, 0x31);
    assert_int_equal(app.cfg.uds_request_id, 0x7A0u);
    /* configured at start, the channel uses them */
    app_config_t c = app_default_config();
    c.uds_request_id = 0x7B0u;
    c.uds_response_id = 0x7B8u;
    assert_int_equal(app_init(&app, &c), NAV_OK);
    assert_int_equal(REQUEST(0x3E, 0x00), 0u); /* 0x7A0 is not the channel's: foreign */
    assert_int_equal(app_health(&app)->foreign, 1u);
    assert_int_equal(app.uds.tp.cfg.rx_id, 0x7B0u);
    assert_int_equal(app.uds.tp.cfg.tx_id, 0x7B8u);
}

/* 0x10 02: the bootloader's session. Without one (the host, QEMU): 0x22, the session
 * unchanged; with one: 7F 10 78 first, then the board resets into it (the fake HAL
 * returns, so the application says 0x22 after it) */
static void test_programming_session_enters_the_bootloader(void **state)
{
    (void)state;
    pendings = 0;
    expect_nrc(REQUEST(0x10, 0x02), 0x10, 0x22);
    assert_int_equal(pendings, 0);
    assert_int_equal(hal.bootloader_entered, 0u);
    assert_int_equal(app.uds.srv.session, UDS_SESSION_DEFAULT);
    hal.has_bootloader = 1;
    expect_nrc(REQUEST(0x10, 0x02), 0x10, 0x22);
    assert_int_equal(pendings, 1);
    assert_int_equal(hal.bootloader_entered, 1u);
    /* the other sessions are the server's as before */
    assert_int_equal(REQUEST(0x10, 0x03), 6u);
    assert_int_equal(app.uds.srv.session, UDS_SESSION_EXTENDED);
    expect_nrc(REQUEST(0x10, 0x04), 0x10, 0x12);
}

static void test_s3_on_the_hal_clock(void **state)
{
    (void)state;
    unlock();
    hal.t_us += UDS_S3_US - 1000u;
    app_poll(&app, &hal);
    assert_int_equal(app.uds.srv.session, UDS_SESSION_EXTENDED);
    hal.t_us += 1000u;
    app_poll(&app, &hal);
    assert_int_equal(app.uds.srv.session, UDS_SESSION_DEFAULT);
    assert_int_equal(app.uds.srv.unlocked, 0);
}

/* three wrong keys: 0x35, 0x35, 0x36, then the 10 s delay on the HAL clock (0x37), which
 * the programming session does not bypass (0x22) */
static void test_three_wrong_keys_then_delay_on_the_hal_clock(void **state)
{
    (void)state;
    assert_int_equal(REQUEST(0x10, 0x03), 6u);
    const uint8_t codes[3] = {0x35, 0x35, 0x36};
    for (int i = 0; i < 3; i++) {
        assert_int_equal(REQUEST(0x27, 0x01), 6u);
        const uint32_t k = uds_key_of_seed(be32(&rsp[2])) + 1u;
        const uint8_t key[] = {0x27, 0x02, (uint8_t)(k >> 24), (uint8_t)(k >> 16),
                               (uint8_t)(k >> 8), (uint8_t)k};
        expect_nrc(request(key, sizeof key), 0x27, codes[i]);
    }
    expect_nrc(REQUEST(0x27, 0x01), 0x27, 0x37);
    /* nor through the bootloader, which would start with a fresh count (a review's) */
    hal.has_bootloader = 1;
    expect_nrc(REQUEST(0x10, 0x02), 0x10, 0x22);
    assert_int_equal(hal.bootloader_entered, 0u);
    assert_int_equal(REQUEST(0x10, 0x03), 6u);
    for (int s = 0; s < 10; s++) {
        hal.t_us += 1000000u;
        assert_int_equal(REQUEST(0x3E, 0x00), 2u);
    }
    assert_int_equal(REQUEST(0x27, 0x01), 6u);
}

static void test_identifier_rules_and_receive_list(void **state)
{
    (void)state;
    app_config_t c = app_default_config();
    assert_true(app_config_valid(&c));
    c.uds_response_id = c.uds_request_id;
    assert_false(app_config_valid(&c));
    c = app_default_config();
    c.uds_response_id = (uint16_t)c.can_ids[NAVECU_MSG_NAV_STATUS];
    assert_false(app_config_valid(&c));
    c = app_default_config();
    uint32_t ids[32];
    const size_t n = app_uds_rx_ids(&c, ids, 32u);
    assert_int_equal(n, app_rx_ids(c.can_ids, ids, 32u) + 1u);
    (void)app_uds_rx_ids(&c, ids, 32u);
    assert_int_equal(ids[n - 1u], 0x7A0u);
    for (size_t i = 0u; i + 1u < n; i++) {
        assert_int_not_equal(ids[i], 0x7A0u);
    }
}

/* the IMU silent for 3 s: NAV_Status (app_poll's heartbeat) carries IMU_STALE, its DTC
 * U1101-87 (0xD10187) is failing at once and confirmed 2 s later; read with 0x19 01 / 02 /
 * 0A in the default session, cleared with 0x14 FF FF FF, read gone */
static void silent_imu(uint64_t for_us)
{
    for (uint64_t t = 0u; t < for_us; t += 10000u) {
        hal.t_us += 10000u;
        app_poll(&app, &hal);
    }
}

/* An IMU that never sends after power-on (found by a UDS client written from docs/can.md:
 * with no sample there was no NAV_Status, so no DTC test, and U1101-87 stayed 0x50): from
 * 0.5 s after power-on the DTCs are tested at the status rate on the HAL clock, the IMU's
 * failing and then confirmed after its 2 s, and still no NAV_Status is sent (the
 * data-driven outputs wait for data: a live replay's outputs do not depend on how long the
 * ECU waited for it) */
static void test_dtc_of_an_imu_absent_from_power_on(void **state)
{
    (void)state;
    app_poll(&app, &hal); /* power-on: the first heartbeat, uptime 0 */
    const uint32_t tx_before = hal.tx_n;
    silent_imu(400000u); /* 0.4 s: not stale yet */
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_IMU_STALE), 0x50u);
    silent_imu(3000000u);
    for (uint32_t i = tx_before; i < hal.tx_n; i++) {
        assert_int_not_equal(hal.tx[i].id, NAVECU_CAN_NAV_STATUS_FRAME_ID);
    }
    const uint8_t status = dtc_status(&app.keep.dtc, DTC_IMU_STALE);
    assert_true((status & DTC_CDTC) != 0u);
}

/* navigating and moving, the IMU's fault tested failing for 1.1 s: C1101 confirmed, its
 * stored byte held for a standstill (dtc_dirty) */
static void imu_fault_confirmed_while_driving(void)
{
    app.run.mode = APP_MODE_NAVIGATING;
    app.keep.odo.standing = 0u;
    app_dtc_cycle(&app, &hal, NAVECU_HEALTH_IMU_FAULT);
    hal.t_us += 1100000u;
    app_dtc_cycle(&app, &hal, NAVECU_HEALTH_IMU_FAULT);
}

/* Before the first IMU sample only IMU_STALE's and NVM_ERROR's DTCs are tested: the other
 * flags hold for a number of IMU samples, and with none one refused frame stayed REJECTED
 * and confirmed U1103 for good (a review's) */
static void test_one_rejection_without_imu_confirms_nothing(void **state)
{
    (void)state;
    app_poll(&app, &hal);
    silent_imu(1000000u);
    const app_diag_t d = app_diag_of(&app);
    app_diag_reject(&d, &app.keep.health.bad_crc);
    silent_imu(30000000u);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_REJECTED), 0x50u); /* not tested */
    assert_true((dtc_status(&app.keep.dtc, DTC_IMU_STALE) & DTC_CDTC) != 0u);
}

/* A DTC confirmed while driving, then 10 02: the bytes held for a standstill are written
 * before the reset into the bootloader, as before an ECUReset (a review's) */
static void test_programming_session_while_moving_keeps_dtcs(void **state)
{
    (void)state;
    imu_fault_confirmed_while_driving();
    assert_true((dtc_status(&app.keep.dtc, DTC_IMU_FAULT) & DTC_CDTC) != 0u);
    assert_true(app.keep.dtc_dirty != 0u);
    hal.has_bootloader = 1;
    assert_int_equal(REQUEST(0x10, 0x03), 6u);
    expect_nrc(REQUEST(0x10, 0x02), 0x10, 0x22); /* the fake HAL returns from the reset */
    assert_int_equal(hal.bootloader_entered, 1u);
    assert_int_equal(app.keep.dtc_dirty, 0u);
}

static void test_dtc_of_a_silent_imu_read_and_cleared(void **state)
{
    (void)state;
    app.keep.imu.have_sample = 1u; /* the IMU was there, and fell silent at t 1 s */
    app.keep.imu.last_t_us = hal.t_us;
    /* before any test: every DTC 0x50, none confirmed */
    size_t n = REQUEST(0x19, 0x01, 0x08);
    assert_int_equal(n, 6u);
    assert_memory_equal(rsp, ((const uint8_t[]){0x59, 0x01, 0x7F, 0x00, 0x00, 0x00}), 6u);
    silent_imu(1500000u); /* stale after 0.5 s: failing for 1 s, not confirmed */
    n = REQUEST(0x19, 0x02, 0x01);
    /* not NO_GNSS (U1102-87, no GNSS at all for 1.5 s): debounced, it fails only after
     * 60 s (a start's first fix is no failure; dtc.toml) */
    assert_int_equal(n, 7u);
    assert_memory_equal(rsp, ((const uint8_t[]){0x59, 0x02, 0x7F, 0xD1, 0x01, 0x87, 0x27}), 7u);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_NO_GNSS), 0x50u);
    silent_imu(1500000u); /* 2.5 s of failure: confirmed */
    n = REQUEST(0x19, 0x02, 0x08);
    assert_int_equal(n, 7u);
    assert_memory_equal(rsp, ((const uint8_t[]){0x59, 0x02, 0x7F, 0xD1, 0x01, 0x87, 0x2F}), 7u);
    /* every DTC of the table, each with its status */
    n = REQUEST(0x19, 0x0A);
    assert_int_equal(n, 3u + 4u * (size_t)DTC_N);
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        const uint8_t *r = &rsp[3u + 4u * i];
        const uint32_t num = ((uint32_t)r[0] << 16) | ((uint32_t)r[1] << 8) | r[2];
        assert_int_equal(num, dtc_table[i].number);
        assert_int_equal(r[3], dtc_status(&app.keep.dtc, i));
    }
    const uint32_t writes = app.keep.dtc_persist_writes;
    assert_true(writes > 0u); /* the stored bytes went to NVM (navigation not started) */
    assert_int_equal(app.keep.dtc_dirty, 0u);
    uint8_t stored[CALSTORE_DTC_N];
    assert_int_equal(nvstore_dtc_status(&hal, stored), 0);
    assert_int_equal(stored[0], dtc_stored(&app.keep.dtc, 0u));
    assert_true((stored[0] & 0x08u) != 0u); /* confirmedDTC in NVM */
    /* a power cycle: the fault memory comes back from NVM (confirmed, not failing yet) */
    assert_int_equal(app_start(&app, &hal), NAV_OK);
    n = REQUEST(0x19, 0x02, 0x08);
    assert_int_equal(n, 7u);
    assert_int_equal(rsp[3], 0xD1);
    assert_true((rsp[6] & 0x08u) != 0u);
    /* moving while navigating: the clear (an NVM write) is refused, nothing cleared */
    app.run.mode = APP_MODE_NAVIGATING;
    app.keep.odo.standing = 0u;
    expect_nrc(REQUEST(0x14, 0xFF, 0xFF, 0xFF), 0x14, 0x22);
    assert_int_equal(REQUEST(0x19, 0x01, 0x08), 6u);
    assert_int_equal(rsp[5], 1u);
    app.run.mode = APP_MODE_WAIT_INIT;
    const uint32_t writes2 = app.keep.dtc_persist_writes;
    n = REQUEST(0x14, 0xFF, 0xFF, 0xFF);
    assert_int_equal(n, 1u);
    assert_int_equal(rsp[0], 0x54);
    assert_int_equal(app.keep.dtc_persist_writes, writes2 + 1u); /* the clear: one write */
    assert_int_equal(nvstore_dtc_status(&hal, stored), 0);
    assert_int_equal(stored[0] & 0x08u, 0u);
    n = REQUEST(0x19, 0x01, 0x2F);
    assert_memory_equal(rsp, ((const uint8_t[]){0x59, 0x01, 0x7F, 0x00, 0x00, 0x00}), 6u);
    n = REQUEST(0x14, 0x00, 0x00, 0x00);
    expect_nrc(n, 0x14, 0x31);
    /* the frames of the exchange were never navecu's input */
    assert_int_equal(app.keep.health.foreign, 0u);
}

/* the app started as the boards start it (app_start: defaults, NVM, no board layer) */
static int setup_started(void **state)
{
    (void)state;
    fake_hal_reset(&hal);
    assert_int_equal(app_start(&app, &hal), NAV_OK);
    hal.t_us = 1000000u;
    return 0;
}

#define ROUTINE(rid) REQUEST(0x31, 0x01, (uint8_t)((rid) >> 8), (uint8_t)(rid))

static void expect_routine_ok(size_t n, uint16_t rid)
{
    assert_int_equal(n, 4u);
    assert_int_equal(rsp[0], 0x71);
    assert_int_equal(rsp[1], 0x01);
    assert_int_equal(rsp[2], rid >> 8);
    assert_int_equal(rsp[3], rid & 0xFFu);
}

/* RoutineControl: the extended session (0x7F), a sub-function other than startRoutine
 * (0x12), too short or with an option record (0x13), locked (0x33), an unknown routine
 * (0x31); 0x0204 AdoptMounting without a converged estimate (0x22), with one: the
 * parameters take it in RAM, the source becomes fixed */
static void test_routine_checks(void **state)
{
    (void)state;
    expect_nrc(ROUTINE(0x0200u), 0x31, 0x7F);
    assert_int_equal(REQUEST(0x10, 0x03), 6u);
    expect_nrc(REQUEST(0x31, 0x02, 0x02, 0x00), 0x31, 0x12);
    expect_nrc(REQUEST(0x31, 0x01, 0x02), 0x31, 0x13);
    expect_nrc(ROUTINE(0x0200u), 0x31, 0x33);
    assert_int_equal(hal.nvm_units, 0u); /* nothing written */
    unlock();
    expect_nrc(REQUEST(0x31, 0x01, 0x02, 0x00, 0x01), 0x31, 0x13);
    expect_nrc(ROUTINE(0x0205u), 0x31, 0x31);
    expect_nrc(ROUTINE(0x01FFu), 0x31, 0x31);
    expect_nrc(ROUTINE(0xFF00u), 0x31, 0x31);
    expect_nrc(ROUTINE(0x0204u), 0x31, 0x22); /* fixed mode: no estimate */
    app.keep.mount_state = (uint8_t)APP_MOUNT_ESTIMATED;
    app.keep.mest.res.rpy_rad[0] = 3.0f;
    app.keep.mest.res.rpy_rad[1] = -0.5f;
    app.keep.mest.res.rpy_rad[2] = 1.5f;
    app.cfg.imu_mount_source = MOUNT_SOURCE_AUTOMATIC;
    expect_routine_ok(ROUTINE(0x0204u), 0x0204u);
    assert_true(app.cfg.imu_mount_rad[0] > 2.99f && app.cfg.imu_mount_rad[0] < 3.01f);
    assert_true(app.cfg.imu_mount_rad[1] > -0.51f && app.cfg.imu_mount_rad[1] < -0.49f);
    assert_true(app.cfg.imu_mount_rad[2] > 1.49f && app.cfg.imu_mount_rad[2] < 1.51f);
    assert_int_equal(app.cfg.imu_mount_source, MOUNT_SOURCE_FIXED);
    assert_int_equal(hal.nvm_units, 0u);
}

/* GIVEN level_s written (45) WHEN ECUReset without a save THEN the default again (the
 * layers run again); WHEN written, StoreParameters, ECUReset THEN 45, the NVM status DID
 * says version 2, source NVM, 26 entries loaded, none refused, seq 1 */
static void test_store_parameters_and_reset(void **state)
{
    (void)state;
    const uint16_t level0 = app.cfg.level_s;
    unlock();
    assert_int_equal(REQUEST(0x2E, 0x02, 0x04, 0x00, 0x2D), 3u);
    assert_int_equal(REQUEST(0x11, 0x01), 2u);
    app_poll(&app, &hal);
    assert_int_equal(app.cfg.level_s, level0);
    assert_int_equal(REQUEST(0x22, 0xF1, 0xA1), 11u);
    assert_memory_equal(&rsp[3], "\x00\x00\x00\x00\x00\x00\x00\x00", 8u);

    unlock();
    assert_int_equal(REQUEST(0x2E, 0x02, 0x04, 0x00, 0x2D), 3u);
    pendings = 0;
    expect_routine_ok(ROUTINE(0x0200u), 0x0200u);
    /* the NVM write is announced with 7F 31 78 responsePending before the final 71 */
    assert_int_equal(pendings, 1);
    assert_int_equal(app.uds.pending_sent, 1u);
    assert_int_equal(REQUEST(0x11, 0x01), 2u);
    app_poll(&app, &hal);
    assert_int_equal(app.cfg.level_s, 45u);
    assert_int_equal(REQUEST(0x22, 0xF1, 0xA1), 11u);
    size_t writable = 0u;
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        writable += app_params[k].uds_read_only ? 0u : 1u;
    }
    const uint8_t want[8] = {2u, NVSTORE_SRC_NVM, (uint8_t)writable, 0u, 0u, 0u, 0u, 1u};
    assert_memory_equal(&rsp[3], want, 8u);
    /* RestoreDefaults: in RAM only, the NVM keeps 45 until the next save */
    unlock();
    expect_routine_ok(ROUTINE(0x0202u), 0x0202u);
    assert_int_equal(app.cfg.level_s, level0);
    assert_int_equal(REQUEST(0x11, 0x01), 2u);
    app_poll(&app, &hal);
    assert_int_equal(app.cfg.level_s, 45u);
}

/* navigating and moving: StoreParameters, StoreCalibration, EraseCalibration and
 * RestoreDefaults refused (0x22); standing: the save allowed, RestoreDefaults not
 * (navigation runs on copies of some parameters); an NVM failure: 0x72 */
static void test_routine_conditions_and_nvm_failure(void **state)
{
    (void)state;
    unlock();
    app.run.mode = APP_MODE_NAVIGATING;
    app.keep.odo.standing = 0u;
    expect_nrc(ROUTINE(0x0200u), 0x31, 0x22);
    expect_nrc(ROUTINE(0x0201u), 0x31, 0x22);
    expect_nrc(ROUTINE(0x0202u), 0x31, 0x22);
    expect_nrc(ROUTINE(0x0203u), 0x31, 0x22);
    assert_int_equal(hal.nvm_units, 0u);
    assert_int_equal(app.uds.pending_sent, 0u); /* refused at once: no responsePending */
    app.keep.odo.standing = 1u;
    expect_routine_ok(ROUTINE(0x0200u), 0x0200u);
    expect_nrc(ROUTINE(0x0202u), 0x31, 0x22);
    hal.nvm_fail = 1;
    expect_nrc(ROUTINE(0x0200u), 0x31, 0x72);
    assert_int_equal(app.keep.cal.nvm_error, 1u);
    hal.nvm_fail = 0;
    expect_routine_ok(ROUTINE(0x0200u), 0x0200u);
    assert_int_equal(app.keep.cal.nvm_error, 0u);
}

/* StoreCalibration: nothing calibrated, 0x22; a calibration in use: stored, with the
 * stored parameters kept; EraseCalibration: the stored and the used calibration gone,
 * the parameters kept */
static void test_calibration_routines(void **state)
{
    (void)state;
    unlock();
    expect_nrc(ROUTINE(0x0203u), 0x31, 0x22);
    assert_int_equal(REQUEST(0x2E, 0x02, 0x04, 0x00, 0x2D), 3u);
    expect_routine_ok(ROUTINE(0x0200u), 0x0200u);
    app.keep.cal.source = CAL_SRC_KNOWN_POSITION;
    app.keep.cal.mu = 0.0125f;
    app.keep.n_samples = 5000u;
    expect_routine_ok(ROUTINE(0x0203u), 0x0203u);
    calstore_t cs;
    cal_record_t rec;
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_OK);
    assert_near(rec.odo_scale_err, 0.0125f, 0.0);
    app_config_t c;
    nvstore_status_t st;
    (void)nvstore_layer(&hal, &c, &st);
    assert_int_equal(c.level_s, 45u);
    expect_routine_ok(ROUTINE(0x0201u), 0x0201u);
    assert_int_equal(app.keep.cal.source, CAL_SRC_NONE);
    assert_near(app.keep.cal.mu, 0.0, 0.0);
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_OK);
    assert_int_equal(rec.source, CAL_SRC_NONE);
    (void)nvstore_layer(&hal, &c, &st);
    assert_int_equal(c.level_s, 45u);
    /* after a reboot: no calibration, the parameters */
    assert_int_equal(app_start(&app, &hal), NAV_OK);
    assert_int_equal(app.keep.cal.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NONE_CHOICE);
    assert_int_equal(app.cfg.level_s, 45u);
}

/* GIVEN a stored record with one good entry (level_s 45) and one out of range
 * (gnss_latency_s 1e6 s) WHEN started THEN level_s 45, gnss_latency_s its default, DID
 * 0xF1A1 says 1 loaded, 1 refused, and NAV_Status's NVM_ERROR is raised */
static void test_refused_entries_reported(void **state)
{
    (void)state;
    const float big = 1.0e6f;
    uint32_t u;
    memcpy(&u, &big, sizeof u);
    const uint8_t blob[] = {0x02, 0x04, 2, 0, 45,
                            0x02, 0x40, 4, (uint8_t)(u >> 24), (uint8_t)(u >> 16),
                            (uint8_t)(u >> 8), (uint8_t)u};
    static calstore_ext_t ext;
    memset(&ext, 0, sizeof ext);
    memset(ext.dtc, 0xFF, sizeof ext.dtc);
    memcpy(ext.params, blob, sizeof blob);
    ext.params_len = (uint16_t)sizeof blob;
    calstore_t cs = {0u, -1};
    const cal_record_t none = {0.0f, 0.0f, 0.0f, CAL_SRC_NONE};
    assert_int_equal(calstore_save_ext(&hal, &cs, &none, &ext), 0);
    assert_int_equal(app_start(&app, &hal), NAV_OK);
    const app_config_t d = app_default_config();
    assert_int_equal(app.cfg.level_s, 45u);
    assert_near(app.cfg.gnss_latency_s, d.gnss_latency_s, 0.0);
    assert_int_equal(app.keep.cal.nvm_error, 1u);
    assert_int_equal(REQUEST(0x22, 0xF1, 0xA1), 11u);
    const uint8_t want[8] = {2u, NVSTORE_SRC_NVM, 1u, 1u, 0u, 0u, 0u, 1u};
    assert_memory_equal(&rsp[3], want, 8u);
}

/* GIVEN a stored record whose DTC bytes are one confirmed DTC (IMU_STALE 0x2C) and one
 * impossible byte (IMU_FAULT 0x01: testFailed is never stored) WHEN started THEN the good
 * one comes back, the impossible one starts as after a clear and is counted, and
 * NAV_Status's NVM_ERROR is raised (a review found the refusal counted where nothing read
 * it: a confirmed DTC could be lost without a word) */
static void test_refused_dtc_byte_reported(void **state)
{
    (void)state;
    static calstore_ext_t ext;
    memset(&ext, 0, sizeof ext);
    memset(ext.dtc, 0xFF, sizeof ext.dtc);
    ext.dtc[DTC_IMU_STALE] = 0x2Cu;
    ext.dtc[DTC_IMU_FAULT] = 0x01u;
    calstore_t cs = {0u, -1};
    const cal_record_t none = {0.0f, 0.0f, 0.0f, CAL_SRC_NONE};
    assert_int_equal(calstore_save_ext(&hal, &cs, &none, &ext), 0);
    assert_int_equal(app_start(&app, &hal), NAV_OK);
    assert_int_equal(dtc_stored(&app.keep.dtc, DTC_IMU_STALE), 0x2Cu);
    assert_int_equal(dtc_status(&app.keep.dtc, DTC_IMU_FAULT), 0x50u);
    assert_int_equal(app.keep.dtc.load_rejected, 1u);
    assert_int_equal(app.keep.cal.nvm_error, 1u);
    /* the bytes are written again at the first test (navigation not started): the next
     * start refuses nothing (a review found the corrupt byte refused at every start) */
    app_dtc_cycle(&app, &hal, 0u);
    uint8_t stored[CALSTORE_DTC_N];
    assert_int_equal(nvstore_dtc_status(&hal, stored), 0);
    assert_int_equal(stored[DTC_IMU_FAULT], 0x00u); /* started as after a clear, passed */
    assert_int_equal(stored[DTC_IMU_STALE], dtc_stored(&app.keep.dtc, DTC_IMU_STALE));
    assert_true((stored[DTC_IMU_STALE] & DTC_CDTC) != 0u); /* still confirmed */
    assert_int_equal(app_start(&app, &hal), NAV_OK);
    assert_int_equal(app.keep.dtc.load_rejected, 0u);
    /* and a record whose bytes are all good raises nothing */
    ext.dtc[DTC_IMU_FAULT] = 0x24u;
    assert_int_equal(calstore_save_ext(&hal, &cs, &none, &ext), 0);
    assert_int_equal(app_start(&app, &hal), NAV_OK);
    assert_int_equal(app.keep.dtc.load_rejected, 0u);
    assert_int_equal(app.keep.cal.nvm_error, 0u);
}

/* 0xF1A3, the commands' status: the last refusal's reason and the count (commands.h):
 * SetInitialPosition without a CMD_KnownPosition is refused with reason 1 */
static void test_command_status_did(void **state)
{
    (void)state;
    assert_int_equal(REQUEST(0x22, 0xF1, 0xA3), 8u);
    const uint8_t none[5] = {0u, 0u, 0u, 0u, 0u};
    assert_memory_equal(&rsp[3], none, 5u);
    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = 2u; /* SetInitialPosition, no CMD_KnownPosition before */
    const hal_can_frame_t f = cf_control(&c, hal.t_us);
    app_handle_frame(&app, &hal, &f);
    assert_int_equal(REQUEST(0x22, 0xF1, 0xA3), 8u);
    const uint8_t want[5] = {1u, 0u, 0u, 0u, 1u};
    assert_memory_equal(&rsp[3], want, 5u);
}

/* the board's layer goes over the NVM's, at start and at every ECUReset: this test's
 * (app_board_layer overrides app.c's weak default) sets level_s 20 when layer_on */
static int layer_on;
int app_board_layer(app_config_t *cfg)
{
    if (layer_on) {
        cfg->level_s = 20u;
    }
    return layer_on > 1 ? -1 : 0;
}

static void test_board_layer_over_nvm(void **state)
{
    (void)state;
    unlock();
    assert_int_equal(REQUEST(0x2E, 0x02, 0x04, 0x00, 0x2D), 3u);
    expect_routine_ok(ROUTINE(0x0200u), 0x0200u);
    layer_on = 1;
    assert_int_equal(app_start(&app, &hal), NAV_OK);
    assert_int_equal(app.cfg.level_s, 20u);
    unlock();
    assert_int_equal(REQUEST(0x2E, 0x02, 0x04, 0x00, 0x2D), 3u);
    assert_int_equal(REQUEST(0x11, 0x01), 2u);
    app_poll(&app, &hal);
    assert_int_equal(app.cfg.level_s, 20u);
    /* a layer that refuses: app_start refuses */
    layer_on = 2;
    assert_int_equal(app_start(&app, &hal), NAV_EINVAL);
    layer_on = 0;
}


/* ---- found by a review (each failed before its fix) ---- */
static void dump_rsp_frames(const char *tag, uint32_t from)
{
    print_message("%s:", tag);
    for (uint32_t i = from; i < hal.tx_n; i++) {
        if (hal.tx[i].id == RSP) {
            print_message(" [");
            for (int k = 0; k < 8; k++) {
                print_message("%02X", hal.tx[i].data[k]);
            }
            print_message("]");
        }
    }
    print_message("\n");
}

/* a 7F 31 78 refused by the CAN driver (its queue full) is given up, not left in the
 * channel (which would keep a pointer to a stack array and refuse the final response):
 * the final response goes out once the queue drains */
static void test_pending_refused_by_a_full_can_queue(void **state)
{
    (void)state;
    unlock();
    const uint32_t mark = hal.tx_n;
    hal.tx_n = FAKE_TX_MAX; /* the CAN driver's queue is full */
    const uint8_t sf[8] = {0x04, 0x31, 0x01, 0x02, 0x00};
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = REQ; f.dlc = 8u; memset(f.data, 0xCC, 8u); memcpy(f.data, sf, 5u);
    f.t_us = hal.t_us;
    app_handle_frame(&app, &hal, &f);
    /* the queue drains */
    hal.tx_n = mark;
    for (int i = 0; i < 5; i++) {
        hal.t_us += 10000u;
        app_poll(&app, &hal);
    }
    dump_rsp_frames("frames on 0x7A8 after the queue drained", mark);
    int saw_final = 0, saw_pending = 0;
    for (uint32_t i = mark; i < hal.tx_n; i++) {
        if (hal.tx[i].id != RSP) continue;
        if (memcmp(hal.tx[i].data, "\x04\x71\x01\x02\x00", 5) == 0) saw_final = 1;
        if (memcmp(hal.tx[i].data, "\x03\x7F\x31\x78", 4) == 0) saw_pending = 1;
    }
    print_message("pending seen %d, final 71 01 02 00 seen %d\n", saw_pending, saw_final);
    assert_false(saw_pending);
    assert_true(saw_final);
}

/* suppressPosRspMsgIndicationBit after a 7F 31 78: ISO 14229-1 wants the final positive
 * response anyway */
static void test_suppressed_response_after_a_pending(void **state)
{
    (void)state;
    unlock();
    const uint32_t mark = hal.tx_n;
    pendings = 0;
    const size_t n = REQUEST(0x31, 0x81, 0x02, 0x00);
    dump_rsp_frames("31 81 02 00", mark);
    print_message("pendings=%d final len=%zu\n", pendings, n);
    assert_int_equal(pendings, 1);
    assert_int_equal(n, 4u);
}

/* a DTC confirmed while driving (its NVM write held until a standstill), then ECUReset
 * (allowed while moving): the reset writes it first, and it is still confirmed after */
static void test_ecu_reset_while_moving_keeps_dtcs(void **state)
{
    (void)state;
    imu_fault_confirmed_while_driving();
    const uint8_t before = dtc_status(&app.keep.dtc, DTC_IMU_FAULT);
    print_message("IMU_FAULT status before ECUReset 0x%02X, dirty 0x%X\n", before,
                  (unsigned)app.keep.dtc_dirty);
    assert_true((before & DTC_CDTC) != 0u);
    unlock();
    assert_int_equal(REQUEST(0x11, 0x01), 2u);
    app_poll(&app, &hal);
    const uint8_t after = dtc_status(&app.keep.dtc, DTC_IMU_FAULT);
    print_message("IMU_FAULT status after ECUReset 0x%02X\n", after);
    assert_true((after & DTC_CDTC) != 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_every_parameter_did_read, setup),
        cmocka_unit_test_setup(test_identification_dids, setup),
        cmocka_unit_test_setup(test_mount_estimate_did, setup),
        cmocka_unit_test_setup(test_command_status_did, setup),
        cmocka_unit_test_setup(test_all_dids_in_one_request, setup),
        cmocka_unit_test_setup(test_write_refused_then_accepted_and_read_back, setup),
        cmocka_unit_test_setup(test_reset_parameter_needs_navigation_stopped, setup),
        cmocka_unit_test_setup(test_ecu_reset_restarts_with_the_configuration, setup),
        cmocka_unit_test_setup(test_uds_ids_read_only, setup),
        cmocka_unit_test_setup(test_s3_on_the_hal_clock, setup),
        cmocka_unit_test_setup(test_three_wrong_keys_then_delay_on_the_hal_clock, setup),
        cmocka_unit_test_setup(test_identifier_rules_and_receive_list, setup),
        cmocka_unit_test_setup(test_dtc_of_a_silent_imu_read_and_cleared, setup),
        cmocka_unit_test_setup(test_dtc_of_an_imu_absent_from_power_on, setup),
        cmocka_unit_test_setup(test_one_rejection_without_imu_confirms_nothing, setup),
        cmocka_unit_test_setup(test_programming_session_while_moving_keeps_dtcs, setup),
        cmocka_unit_test_setup(test_pending_refused_by_a_full_can_queue, setup_started),
        cmocka_unit_test_setup(test_suppressed_response_after_a_pending, setup_started),
        cmocka_unit_test_setup(test_ecu_reset_while_moving_keeps_dtcs, setup_started),
        cmocka_unit_test_setup(test_routine_checks, setup_started),
        cmocka_unit_test_setup(test_store_parameters_and_reset, setup_started),
        cmocka_unit_test_setup(test_routine_conditions_and_nvm_failure, setup_started),
        cmocka_unit_test_setup(test_calibration_routines, setup_started),
        cmocka_unit_test_setup(test_board_layer_over_nvm, setup_started),
        cmocka_unit_test_setup(test_refused_dtc_byte_reported, setup),
        cmocka_unit_test_setup(test_refused_entries_reported, setup_started),
        cmocka_unit_test_setup(test_programming_session_enters_the_bootloader, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
