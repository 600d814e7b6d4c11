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
#include "fake_hal.h"
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
    uint8_t req[1 + 2 * (APP_PARAM_N + 3)];
    size_t m = 0u;
    req[m++] = 0x22;
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        req[m++] = (uint8_t)(app_params[k].did >> 8);
        req[m++] = (uint8_t)app_params[k].did;
    }
    const uint16_t ident[3] = {0xF18Cu, 0xF195u, 0xF1A0u};
    for (int i = 0; i < 3; i++) {
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
           strlen(vehicle_profile.name);
    assert_int_equal(n, pos);
    /* docs/can.md and the ECU's 512-byte ISO-TP buffer: every DID at once fits */
    assert_true(n < 300u);
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
    app.run.mode = APP_MODE_WAIT_INIT;
    assert_int_equal(REQUEST(0x2E, 0x02, 0x00, 0x00, 0xC8), 3u);
    assert_int_equal(app.cfg.imu_rate_hz, 200u);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_every_parameter_did_read, setup),
        cmocka_unit_test_setup(test_identification_dids, setup),
        cmocka_unit_test_setup(test_mount_estimate_did, setup),
        cmocka_unit_test_setup(test_all_dids_in_one_request, setup),
        cmocka_unit_test_setup(test_write_refused_then_accepted_and_read_back, setup),
        cmocka_unit_test_setup(test_reset_parameter_needs_navigation_stopped, setup),
        cmocka_unit_test_setup(test_ecu_reset_restarts_with_the_configuration, setup),
        cmocka_unit_test_setup(test_uds_ids_read_only, setup),
        cmocka_unit_test_setup(test_s3_on_the_hal_clock, setup),
        cmocka_unit_test_setup(test_three_wrong_keys_then_delay_on_the_hal_clock, setup),
        cmocka_unit_test_setup(test_identifier_rules_and_receive_list, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
