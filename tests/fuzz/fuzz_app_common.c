/*
 * fuzz_app_common.c - see fuzz_app_common.h.
 *
 * Records (op = first byte; kind = op & 0x0F; the other bytes follow in this order):
 *   kind 0..9   raw frame under receive ID app_rx_ids()[kind]:
 *               dt_ms(1) [dlc(1) if op & 0x40] data(8)
 *   kind 10     raw frame under any 11-bit ID: id(2, little-endian, & 0x7FF) dt_ms dlc? data
 *   kind 11     raw frame under a codec message's ID (outputs too): k(1) dt_ms dlc? data
 *               raw-frame flags: 0x10 fix the E2E CRC (the pair CRC for IMU_Accel),
 *               (IMU_Time's alive counter is the IMU pair's next one),
 *               0x20 fix the alive counter / GNSS epoch, 0x40 DLC from the input (else 8),
 *               0x80 extended frame
 *   kind 12     IMU samples: n(1) w(3 x int8) v(3 x int8) shifts(1) wheel(1 x int8):
 *               n+1 valid IMU pairs of w << (shifts & 7), v << ((shifts >> 3) & 7) LSB
 *               (+ gravity on z), one sample period apart; op & 0x10: WheelSpeeds
 *               (wheel * 8 LSB on every wheel) with every second sample; op & 0x20: the
 *               ImuFault bit; op & 0x40: every 8th sample is lost (counter step 2);
 *               with imu_time = stamped each pair follows its IMU_Time, a period apart,
 *               op & 0x80: (1 + k % 8) quarter periods apart (refused, gaps, accepted)
 *   kind 13     WheelSpeeds: dt_ms(1) speeds(4 x int8, * 8 LSB), valid counter and CRC
 *               (op & 0x10: the counter is repeated, not advanced)
 *   kind 14     GNSS epoch: dlat(2) dlon(2) (int16 * 4 e-7 deg from the prelude's point)
 *               ve vn(int8 * 16 cm/s) hacc(dm) flags: flags & 7 = FixType (0: 3D),
 *               0x08 no velocity, 0x10 no height, 0x20 status of another epoch,
 *               0x40 TimeOfWeek jumps by 100 s, 0x80 satellites 2
 *   kind 15     pause: dt_ms(2, little-endian), then app_poll
 */
#include "fuzz_app_common.h"

#include <string.h>

#include "codec_check.h"
#include "e2e.h"
#include "fuzz_fail.h"
#include "navecu_can.h"

_Static_assert(sizeof(app_health_t) % sizeof(uint32_t) == 0u,
               "app_health_t is made of uint32_t counters");

#define LAT0_E7 450000000
#define LON0_E7 100000000
#define H0_DM 1000 /* CMD_Control Height, 0.1 m */

void fz_begin(fz_app_t *z, app_t *app, hal_t *hal)
{
    memset(z, 0, sizeof *z);
    z->app = app;
    z->hal = hal;
    z->lat_e7 = LAT0_E7;
    z->lon_e7 = LON0_E7;
    z->tow_ms = 100000u;
    memcpy(z->health, &app->keep.health, sizeof z->health);
    hal->tx_n = 0u;
}

/* The stock identifier of the output message the application sends on id with its configured
   identifiers (navecu_protocol.h's message table), or 0 when id is none of its outputs. */
static uint32_t output_stock_id(const app_t *a, uint32_t id)
{
    static const uint32_t stock[NAVECU_MSG_N] = NAVECU_MSG_STOCK_IDS;
    static const uint8_t is_input[NAVECU_MSG_N] = NAVECU_MSG_IS_INPUT;
    for (size_t m = 0u; m < (size_t)NAVECU_MSG_N; m++) {
        if (is_input[m] == 0u && a->cfg.can_ids[m] == id) {
            return stock[m];
        }
    }
    return 0u;
}

void fz_check(fz_app_t *z)
{
    const app_t *a = z->app;
    hal_t *hal = z->hal;
    switch (a->run.mode) {
    case APP_MODE_WAIT_INIT:
    case APP_MODE_LEVELLING:
    case APP_MODE_NAVIGATING:
    case APP_MODE_FAULT:
        break;
    default:
        fuzz_fail("app: mode %d is not an app_mode_t (frame %u)", (int)a->run.mode, z->frames);
    }
    uint32_t h[FZ_HEALTH_N];
    memcpy(h, &a->keep.health, sizeof h);
    for (size_t k = 0u; k < FZ_HEALTH_N; k++) {
        if (h[k] < z->health[k]) {
            fuzz_fail("app: health counter #%zu decreased from %u to %u (frame %u)", k,
                      z->health[k], h[k], z->frames);
        }
    }
    memcpy(z->health, h, sizeof h);
    for (uint32_t k = 0u; k < hal->tx_n; k++) {
        const hal_can_frame_t *f = &hal->tx[k];
        const uint32_t stock_id = output_stock_id(a, f->id);
        if (f->dlc != 8u || f->extended != 0u || stock_id == 0u) {
            fuzz_fail("app: sent frame id 0x%X ext %u dlc %u is not a NAV_* output", (unsigned)f->id,
                      f->extended, f->dlc);
        }
        codec_ctx_t c;
        memset(&c, 0, sizeof c);
        c.flags = CODEC_REQUIRE_RANGE;
        uint8_t d[8];
        memcpy(d, f->data, 8u);
        (void)codec_check_frame(&c, stock_id, d);
        if (stock_id != NAVECU_CAN_NAV_POSITION_FRAME_ID && !e2e_crc_ok(f->id, f->data)) {
            fuzz_fail("app: sent frame 0x%X has a wrong E2E CRC", (unsigned)f->id);
        }
    }
    hal->tx_n = 0u;
    if (hal->tx_dropped != 0u) {
        fuzz_fail("app: more than %u frames sent for one input frame", FAKE_TX_MAX);
    }
}

void fz_feed(fz_app_t *z, const hal_can_frame_t *f)
{
    app_handle_frame(z->app, z->hal, f);
    app_poll(z->app, z->hal);
    z->frames++;
    fz_check(z);
}

static hal_can_frame_t mk_frame(const fz_app_t *z, uint32_t id, const uint8_t d[8])
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = 8u;
    memcpy(f.data, d, 8u);
    f.t_us = z->hal->t_us;
    return f;
}

static void send(fz_app_t *z, uint32_t id, const uint8_t d[8])
{
    const hal_can_frame_t f = mk_frame(z, id, d);
    if (id == NAVECU_CAN_IMU_RATE_FRAME_ID) {
        memcpy(z->last_rate, d, 8u);
    }
    fz_feed(z, &f);
}

static uint8_t next(uint8_t *counter)
{
    const uint8_t c = *counter;
    *counter = e2e_counter_next(c);
    return c;
}

void fz_prelude(fz_app_t *z, int attitude)
{
    uint8_t d[8];
    struct navecu_can_cmd_known_position_t k = {z->lat_e7, z->lon_e7};
    navecu_can_cmd_known_position_pack(d, &k, 8u);
    send(z, NAVECU_CAN_CMD_KNOWN_POSITION_FRAME_ID, d);

    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = NAVECU_CAN_CMD_CONTROL_COMMAND_SET_INITIAL_POSITION_CHOICE;
    c.heading_valid = 1u;
    c.heading = 3000u; /* 30 deg */
    c.height = H0_DM;
    c.cmd_counter = next(&z->cmd_counter);
    navecu_can_cmd_control_pack(d, &c, 8u);
    e2e_protect(NAVECU_CAN_CMD_CONTROL_FRAME_ID, d);
    send(z, NAVECU_CAN_CMD_CONTROL_FRAME_ID, d);

    if (attitude) {
        struct navecu_can_cmd_initial_attitude_t m;
        memset(&m, 0, sizeof m);
        m.att_counter = next(&z->att_counter);
        navecu_can_cmd_initial_attitude_pack(d, &m, 8u);
        e2e_protect(NAVECU_CAN_CMD_INITIAL_ATTITUDE_FRAME_ID, d);
        send(z, NAVECU_CAN_CMD_INITIAL_ATTITUDE_FRAME_ID, d);
    }
}

/* Set the alive counter (or GNSS epoch) of a raw frame to the one a good sender uses. */
static void fix_counter(fz_app_t *z, uint32_t id, uint8_t d[8])
{
    switch (id) {
    case NAVECU_CAN_IMU_RATE_FRAME_ID: {
        struct navecu_can_imu_rate_t m;
        navecu_can_imu_rate_unpack(&m, d, 8u);
        m.imu_counter = z->imu_counter;
        navecu_can_imu_rate_pack(d, &m, 8u);
        break;
    }
    case NAVECU_CAN_IMU_TIME_FRAME_ID: {
        struct navecu_can_imu_time_t m;
        navecu_can_imu_time_unpack(&m, d, 8u);
        m.imu_counter = z->imu_counter;
        navecu_can_imu_time_pack(d, &m, 8u);
        break;
    }
    case NAVECU_CAN_IMU_ACCEL_FRAME_ID: {
        struct navecu_can_imu_accel_t m;
        navecu_can_imu_accel_unpack(&m, d, 8u);
        m.imu_counter = next(&z->imu_counter);
        navecu_can_imu_accel_pack(d, &m, 8u);
        break;
    }
    case NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID: {
        struct navecu_can_wheel_speeds_t m;
        navecu_can_wheel_speeds_unpack(&m, d, 8u);
        m.wheel_counter = next(&z->wheel_counter);
        navecu_can_wheel_speeds_pack(d, &m, 8u);
        break;
    }
    case NAVECU_CAN_GNSS_VELOCITY_FRAME_ID: {
        struct navecu_can_gnss_velocity_t m;
        navecu_can_gnss_velocity_unpack(&m, d, 8u);
        m.gnss_epoch = z->gnss_epoch;
        navecu_can_gnss_velocity_pack(d, &m, 8u);
        break;
    }
    case NAVECU_CAN_GNSS_HEIGHT_FRAME_ID: {
        struct navecu_can_gnss_height_t m;
        navecu_can_gnss_height_unpack(&m, d, 8u);
        m.gnss_epoch = z->gnss_epoch;
        navecu_can_gnss_height_pack(d, &m, 8u);
        break;
    }
    case NAVECU_CAN_GNSS_STATUS_FRAME_ID: {
        struct navecu_can_gnss_status_t m;
        navecu_can_gnss_status_unpack(&m, d, 8u);
        m.gnss_epoch = next(&z->gnss_epoch);
        navecu_can_gnss_status_pack(d, &m, 8u);
        break;
    }
    case NAVECU_CAN_CMD_CONTROL_FRAME_ID: {
        struct navecu_can_cmd_control_t m;
        navecu_can_cmd_control_unpack(&m, d, 8u);
        m.cmd_counter = next(&z->cmd_counter);
        navecu_can_cmd_control_pack(d, &m, 8u);
        break;
    }
    case NAVECU_CAN_CMD_INITIAL_ATTITUDE_FRAME_ID: {
        struct navecu_can_cmd_initial_attitude_t m;
        navecu_can_cmd_initial_attitude_unpack(&m, d, 8u);
        m.att_counter = next(&z->att_counter);
        navecu_can_cmd_initial_attitude_pack(d, &m, 8u);
        break;
    }
    default:
        break;
    }
}

static void fix_crc(const fz_app_t *z, uint32_t id, uint8_t d[8])
{
    switch (id) {
    case NAVECU_CAN_IMU_ACCEL_FRAME_ID:
        d[7] = e2e_pair_crc(id, z->last_rate, d);
        break;
    case NAVECU_CAN_IMU_TIME_FRAME_ID:
    case NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID:
    case NAVECU_CAN_GNSS_VELOCITY_FRAME_ID:
    case NAVECU_CAN_CMD_CONTROL_FRAME_ID:
    case NAVECU_CAN_CMD_INITIAL_ATTITUDE_FRAME_ID:
        e2e_protect(id, d);
        break;
    default:
        break;
    }
}

/* byte reader over the input: missing bytes read as 0 */
typedef struct {
    const uint8_t *p;
    size_t n, i;
} rd_t;

static uint8_t rd8(rd_t *r)
{
    return r->i < r->n ? r->p[r->i++] : 0u;
}

static uint16_t rd16(rd_t *r)
{
    const uint8_t lo = rd8(r);
    return (uint16_t)(lo | (uint16_t)(rd8(r) << 8));
}

static int8_t rds8(rd_t *r)
{
    const uint8_t u = rd8(r);
    return (int8_t)(u >= 128u ? (int)u - 256 : (int)u);
}

static void advance_ms(fz_app_t *z, uint32_t ms)
{
    z->hal->t_us += (uint64_t)ms * 1000u;
}

static void raw_frame(fz_app_t *z, uint8_t op, uint32_t id, rd_t *r)
{
    advance_ms(z, rd8(r));
    uint8_t dlc = 8u;
    if ((op & 0x40u) != 0u) {
        dlc = (uint8_t)(rd8(r) % 16u); /* 9..15: what a CAN FD length code would say */
    }
    uint8_t d[8];
    for (int k = 0; k < 8; k++) {
        d[k] = rd8(r);
    }
    if ((op & 0x20u) != 0u) {
        fix_counter(z, id, d);
    }
    if ((op & 0x10u) != 0u) {
        fix_crc(z, id, d);
    }
    hal_can_frame_t f = mk_frame(z, id, d);
    f.dlc = dlc;
    f.extended = (op & 0x80u) != 0u ? 1u : 0u;
    if (id == NAVECU_CAN_IMU_RATE_FRAME_ID) {
        memcpy(z->last_rate, d, 8u);
    }
    fz_feed(z, &f);
}

static void wheels(fz_app_t *z, const int16_t raw[4], int repeat)
{
    uint8_t d[8];
    struct navecu_can_wheel_speeds_t w;
    memset(&w, 0, sizeof w);
    w.wheel_speed_fl = raw[0];
    w.wheel_speed_fr = raw[1];
    w.wheel_speed_rl = raw[2];
    w.wheel_speed_rr = raw[3];
    w.wheel_counter = repeat ? z->wheel_counter : next(&z->wheel_counter);
    navecu_can_wheel_speeds_pack(d, &w, 8u);
    e2e_protect(NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID, d);
    send(z, NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID, d);
}

static void imu_samples(fz_app_t *z, uint8_t op, rd_t *r)
{
    const uint32_t n = (uint32_t)rd8(r) + 1u;
    int32_t w[3], v[3];
    for (int i = 0; i < 3; i++) {
        w[i] = rds8(r);
    }
    for (int i = 0; i < 3; i++) {
        v[i] = rds8(r);
    }
    const uint8_t sh = rd8(r);
    const int16_t ws = (int16_t)(rds8(r) * 8);
    const uint32_t rate = z->app->cfg.imu_rate_hz >= 1u ? z->app->cfg.imu_rate_hz : 100u;
    /* gravity: 9.80665 m/s^2 over one sample, in LSB of 2^-12 m/s */
    const int32_t g_lsb = (int32_t)(9.80665f * 4096.0f / (float)rate + 0.5f);
    for (int i = 0; i < 3; i++) {
        w[i] *= (int32_t)1 << (sh & 7u);
        v[i] *= (int32_t)1 << ((sh >> 3) & 7u);
    }
    v[2] += g_lsb;
    const int16_t wr[4] = {ws, ws, ws, ws};
    const int stamped = z->app->cfg.imu_time == IMU_TIME_STAMPED;
    for (uint32_t k = 0u; k < n && z->samples < FZ_MAX_SAMPLES; k++) {
        z->samples++;
        z->hal->t_us += 1000000u / rate;
        z->imu_stamp_us += (op & 0x80u) != 0u ? (1u + k % 8u) * (250000u / rate) : 1000000u / rate;
        if ((op & 0x40u) != 0u && k % 8u == 7u) {
            (void)next(&z->imu_counter); /* a lost sample */
            continue;
        }
        if ((op & 0x10u) != 0u && k % 2u == 0u) {
            wheels(z, wr, 0);
        }
        uint8_t dr[8], da[8];
        struct navecu_can_imu_rate_t mr = {w[0], w[1], w[2], z->imu_counter};
        navecu_can_imu_rate_pack(dr, &mr, 8u);
        struct navecu_can_imu_accel_t ma = {v[0], v[1], v[2], (op & 0x20u) != 0u ? 1u : 0u,
                                            next(&z->imu_counter), 0u};
        navecu_can_imu_accel_pack(da, &ma, 8u);
        da[7] = e2e_pair_crc(NAVECU_CAN_IMU_ACCEL_FRAME_ID, dr, da);
        if (stamped) {
            uint8_t dt[8];
            struct navecu_can_imu_time_t mt = {z->imu_stamp_us, mr.imu_counter, 0u};
            navecu_can_imu_time_pack(dt, &mt, 8u);
            e2e_protect(NAVECU_CAN_IMU_TIME_FRAME_ID, dt);
            send(z, NAVECU_CAN_IMU_TIME_FRAME_ID, dt);
        }
        send(z, NAVECU_CAN_IMU_RATE_FRAME_ID, dr);
        send(z, NAVECU_CAN_IMU_ACCEL_FRAME_ID, da);
    }
}

static void gnss_epoch(fz_app_t *z, rd_t *r)
{
    const int16_t dlat = (int16_t)rd16(r);
    const int16_t dlon = (int16_t)rd16(r);
    const int8_t ve = rds8(r);
    const int8_t vn = rds8(r);
    const uint8_t hacc = rd8(r);
    const uint8_t fl = rd8(r);
    const uint32_t rate = z->app->cfg.imu_rate_hz >= 1u ? z->app->cfg.imu_rate_hz : 100u;
    uint8_t d[8];

    struct navecu_can_gnss_position_t p = {z->lat_e7 + 4 * (int32_t)dlat, z->lon_e7 + 4 * (int32_t)dlon};
    navecu_can_gnss_position_pack(d, &p, 8u);
    send(z, NAVECU_CAN_GNSS_POSITION_FRAME_ID, d);
    if ((fl & 0x08u) == 0u) {
        struct navecu_can_gnss_velocity_t v;
        memset(&v, 0, sizeof v);
        v.vel_east = (int16_t)(ve * 16);
        v.vel_north = (int16_t)(vn * 16);
        v.gnss_epoch = z->gnss_epoch;
        v.speed_accuracy = 5u;
        navecu_can_gnss_velocity_pack(d, &v, 8u);
        e2e_protect(NAVECU_CAN_GNSS_VELOCITY_FRAME_ID, d);
        send(z, NAVECU_CAN_GNSS_VELOCITY_FRAME_ID, d);
    }
    if ((fl & 0x10u) == 0u) {
        struct navecu_can_gnss_height_t h = {H0_DM * 10, z->gnss_epoch};
        navecu_can_gnss_height_pack(d, &h, 8u);
        send(z, NAVECU_CAN_GNSS_HEIGHT_FRAME_ID, d);
    }
    struct navecu_can_gnss_status_t s;
    memset(&s, 0, sizeof s);
    s.fix_type = (fl & 7u) != 0u ? (uint8_t)(fl & 7u) : 3u;
    s.num_satellites = (fl & 0x80u) != 0u ? 2u : 9u;
    s.horiz_accuracy = hacc;
    s.vert_accuracy = 30u;
    s.gnss_epoch = (fl & 0x20u) != 0u ? e2e_counter_next(z->gnss_epoch) : z->gnss_epoch;
    if ((fl & 0x40u) != 0u) {
        z->tow_ms += 100000u;
    }
    s.time_of_week = (z->tow_ms + z->samples * 1000u / rate) % 604800000u;
    navecu_can_gnss_status_pack(d, &s, 8u);
    send(z, NAVECU_CAN_GNSS_STATUS_FRAME_ID, d);
    (void)next(&z->gnss_epoch);
}

void fz_run_records(fz_app_t *z, const uint8_t *data, size_t size)
{
    uint32_t ids[16];
    size_t n_ids = app_rx_ids(z->app->cfg.can_ids, ids, 16u);
    if (n_ids > 16u) {
        n_ids = 16u;
    }
    rd_t r = {data, size, 0u};
    for (uint32_t rec = 0u; r.i < r.n && rec < FZ_MAX_RECORDS; rec++) {
        const uint8_t op = rd8(&r);
        const unsigned kind = op & 0x0Fu;
        if (kind <= 9u) {
            raw_frame(z, op, n_ids > 0u ? ids[kind % n_ids] : 0u, &r);
        } else if (kind == 10u) {
            raw_frame(z, op, rd16(&r) & 0x7FFu, &r);
        } else if (kind == 11u) {
            raw_frame(z, op, codec_msg_id(rd8(&r) % codec_n_msgs()), &r);
        } else if (kind == 12u) {
            imu_samples(z, op, &r);
        } else if (kind == 13u) {
            advance_ms(z, rd8(&r));
            int16_t w[4];
            for (int i = 0; i < 4; i++) {
                w[i] = (int16_t)(rds8(&r) * 8);
            }
            wheels(z, w, (op & 0x10u) != 0u);
        } else if (kind == 14u) {
            gnss_epoch(z, &r);
        } else {
            advance_ms(z, rd16(&r));
            app_poll(z->app, z->hal);
            fz_check(z);
        }
    }
}
