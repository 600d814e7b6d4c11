/*
 * test_app_rx.c - app_rx.h: one frame in, a decoded input in SI units or the reason it was
 * refused. Frames are packed with the generated codec and protected as the senders do
 * (tests/support/can_frames.h); expected values are worked out by hand from the DBC's
 * scales (docs/can.md).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app_rx.h"
#include "navecu_protocol.h"
#include "can_frames.h"
#include "e2e.h"
#include "navecu_can.h"
#include "test_util.h"

static rx_state_t rx;
static rx_input_t in;
static const uint32_t STOCK_IDS[NAVECU_MSG_N] = NAVECU_MSG_STOCK_IDS;

static int setup(void **state)
{
    (void)state;
    memset(&rx, 0, sizeof rx);
    memset(&in, 0, sizeof in);
    return 0;
}

static rx_verdict_t decode(const hal_can_frame_t *f)
{
    return app_rx_decode(&rx, STOCK_IDS, f, &in);
}

static hal_can_frame_t wheels(int16_t raw, uint8_t counter)
{
    const int16_t four[4] = {raw, raw, raw, raw};
    return cf_wheels(four, counter, 0u);
}

static hal_can_frame_t control(uint8_t command, uint8_t counter)
{
    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = command;
    c.cmd_counter = counter;
    return cf_control(&c, 0u);
}

static hal_can_frame_t velocity(int16_t east, int16_t north, int16_t up, uint8_t epoch,
                                uint8_t sacc)
{
    struct navecu_can_gnss_velocity_t v;
    memset(&v, 0, sizeof v);
    v.vel_east = east;
    v.vel_north = north;
    v.vel_up = up;
    v.gnss_epoch = epoch;
    v.speed_accuracy = sacc;
    return cf_gnss_velocity(&v, 0u);
}

/* ---- identifiers and lengths ---- */

/* An extended identifier is never navecu's, even with the number of one of its inputs. */
static void test_extended_id_refused(void **state)
{
    (void)state;
    hal_can_frame_t f = wheels(0, 0u);
    f.extended = 1u;
    assert_int_equal(decode(&f), RX_FOREIGN);
    f = cf_gnss_position(0, 0, 0u);
    f.extended = 1u;
    assert_int_equal(decode(&f), RX_FOREIGN);
}

static void test_foreign_id_refused(void **state)
{
    (void)state;
    const uint8_t d[8] = {0};
    hal_can_frame_t f = cf_frame(0x555u, d, 0u);
    assert_int_equal(decode(&f), RX_FOREIGN);
    f = cf_frame(0x103u, d, 0u); /* beside IMU_Time (0x102): not an input */
    assert_int_equal(decode(&f), RX_FOREIGN);
    /* the identifier is checked before the length: a foreign short frame is foreign traffic */
    f.dlc = 3u;
    assert_int_equal(decode(&f), RX_FOREIGN);
}

/* GIVEN each of navecu's eighteen inputs with DLC 7 WHEN decoded THEN bad_dlc. */
static void test_dlc_7_refused(void **state)
{
    (void)state;
    uint32_t ids[24];
    const size_t n = app_rx_ids(STOCK_IDS, ids, 24u);
    assert_int_equal(n, 18u);
    const uint8_t d[8] = {0};
    for (size_t i = 0u; i < n; i++) {
        hal_can_frame_t f = cf_frame(ids[i], d, 0u);
        f.dlc = 7u;
        assert_int_equal(decode(&f), RX_BAD_DLC);
    }
}

/* The eighteen input identifiers of the DBC (the raw GNSS frames 0x131..0x136 among them),
 * and a short array gets only what fits. */
static void test_rx_ids(void **state)
{
    (void)state;
    const uint32_t expected[18] = {0x100u, 0x101u, 0x102u, 0x110u, 0x120u, 0x121u,
                                   0x122u, 0x123u, 0x125u, 0x131u, 0x132u, 0x133u,
                                   0x134u, 0x135u, 0x136u, 0x200u, 0x201u, 0x202u};
    uint32_t ids[18];
    assert_int_equal(app_rx_ids(STOCK_IDS, ids, 18u), 18u);
    for (int i = 0; i < 18; i++) {
        int found = 0;
        for (int j = 0; j < 18; j++) {
            found |= ids[j] == expected[i];
        }
        assert_true(found);
    }
    uint32_t few[4] = {0u, 0u, 0u, 0xDEADu};
    assert_int_equal(app_rx_ids(STOCK_IDS, few, 3u), 18u);
    assert_int_equal(few[3], 0xDEADu); /* nothing written beyond max */
}

/* GIVEN navecu's own outputs seen on a shared bus THEN nothing to act on (RX_OK, kind
 * RX_NONE), whatever their length; an extended one is foreign. */
static void test_own_outputs_ignored(void **state)
{
    (void)state;
    const uint32_t own[6] = {0x300u, 0x301u, 0x302u, 0x303u, 0x310u, 0x311u};
    const uint8_t d[8] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
    for (int i = 0; i < 6; i++) {
        hal_can_frame_t f = cf_frame(own[i], d, 0u);
        f.dlc = 2u;
        in.kind = RX_WHEELS;
        assert_int_equal(decode(&f), RX_OK);
        assert_int_equal(in.kind, RX_NONE);
        f.extended = 1u;
        assert_int_equal(decode(&f), RX_FOREIGN);
    }
}

/* ---- E2E: CRC and alive counters ---- */

static void test_bad_crc_refused(void **state)
{
    (void)state;
    hal_can_frame_t f = wheels(100, 0u);
    f.data[7] ^= 0x01u;
    assert_int_equal(decode(&f), RX_BAD_CRC);
    f = control(1u, 0u);
    f.data[0] ^= 0x10u; /* a payload bit flipped: the CRC no longer matches */
    assert_int_equal(decode(&f), RX_BAD_CRC);
    f = velocity(0, 0, 0, 0u, 0u);
    f.data[7] ^= 0x80u;
    assert_int_equal(decode(&f), RX_BAD_CRC);
    f = cf_initial_attitude(0, 0, 0u, 0u);
    f.data[7] ^= 0x02u;
    assert_int_equal(decode(&f), RX_BAD_CRC);
    /* the refused frames did not take the counters: counter 0 is still a first frame */
    f = wheels(100, 0u);
    assert_int_equal(decode(&f), RX_OK);
}

/* GIVEN WheelSpeeds counter 3 accepted WHEN counter 3 comes again THEN bad_counter; the
 * invalid counter 15 too; counter 5 (one frame lost) is accepted. */
static void test_repeated_counter_refused(void **state)
{
    (void)state;
    hal_can_frame_t f = wheels(0, 3u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(decode(&f), RX_BAD_COUNTER);
    f = wheels(0, 15u);
    assert_int_equal(decode(&f), RX_BAD_COUNTER);
    f = wheels(0, 5u);
    assert_int_equal(decode(&f), RX_OK);
    /* GNSS_Velocity's epoch number is its counter: 15 is invalid; a repeated number is
     * no repeat by itself (it comes round over an outage), the status's TimeOfWeek
     * decides (test_gnss_status_repeat) */
    f = velocity(0, 0, 0, 7u, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(decode(&f), RX_OK);
    f = velocity(0, 0, 0, 15u, 0u);
    assert_int_equal(decode(&f), RX_BAD_COUNTER);
}

static hal_can_frame_t gnss_status(uint8_t epoch, uint8_t fix_type, uint32_t tow_ms)
{
    struct navecu_can_gnss_status_t m;
    memset(&m, 0, sizeof m);
    m.gnss_epoch = epoch;
    m.fix_type = fix_type;
    m.num_satellites = 9u;
    m.time_of_week = tow_ms;
    return cf_gnss_status(&m, 0u);
}

/* GIVEN a GNSS_Status with a fix at TimeOfWeek t WHEN a fix at t comes again THEN it is
 * marked a repeat, whatever its epoch number; a fix at another time is not, even with the
 * same epoch number (the counter came round); statuses without a fix are never repeats
 * and do not move the time compared with. */
static void test_gnss_status_repeat(void **state)
{
    (void)state;
    hal_can_frame_t f = gnss_status(4u, 3u, 1000u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.repeat, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.repeat, 1u);
    f = gnss_status(5u, 3u, 1000u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.repeat, 1u);
    f = gnss_status(4u, 3u, 4000u); /* 15 epochs of 200 ms later: the same number */
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.repeat, 0u);
    f = gnss_status(5u, 0u, 4000u); /* no fix */
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.repeat, 0u);
    f = gnss_status(5u, 0u, 4000u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.repeat, 0u);
    f = gnss_status(6u, 3u, 4000u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.repeat, 1u);
}

/* GIVEN CMD_Control counter 0 WHEN the next one steps by 4 (3 lost, more than
 * APP_CMD_MAX_DELTA - 1) THEN it is refused, and the counter resynchronizes on it: the
 * step of 1 after it is accepted. A step of 3 is accepted. */
static void test_command_counter_window(void **state)
{
    (void)state;
    hal_can_frame_t f = control(0u, 0u);
    assert_int_equal(decode(&f), RX_OK);
    f = control(0u, 3u);
    assert_int_equal(decode(&f), RX_OK);
    f = control(0u, 7u);
    assert_int_equal(decode(&f), RX_BAD_COUNTER);
    f = control(0u, 8u);
    assert_int_equal(decode(&f), RX_OK);
    f = cf_initial_attitude(0, 0, 4u, 0u);
    assert_int_equal(decode(&f), RX_OK);
    f = cf_initial_attitude(0, 0, 4u, 0u);
    assert_int_equal(decode(&f), RX_BAD_COUNTER);
}

/* ---- positions ---- */

static void test_lat_lon_range(void **state)
{
    (void)state;
    /* the poles and +180 deg are positions */
    hal_can_frame_t f = cf_gnss_position(900000000, 1800000000, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.position.lat_e7, 900000000);
    assert_int_equal(in.u.position.lon_e7, 1800000000);
    f = cf_gnss_position(-900000000, 0, 0u);
    assert_int_equal(decode(&f), RX_OK);
    /* beyond: an impossible GNSS position, and the epoch in assembly must know of it */
    f = cf_gnss_position(900000001, 0, 0u);
    in.kind = RX_NONE;
    assert_int_equal(decode(&f), RX_GNSS_BAD);
    assert_int_equal(in.kind, RX_GNSS_POSITION);
    f = cf_gnss_position(0, 1800000001, 0u);
    assert_int_equal(decode(&f), RX_GNSS_BAD);
    f = cf_gnss_position(-900000001, 0, 0u);
    assert_int_equal(decode(&f), RX_GNSS_BAD);
    /* a known position out of range is a bad value (the operator's, not the receiver's) */
    f = cf_known_position(900000001, 0, 0u);
    assert_int_equal(decode(&f), RX_BAD_VALUE);
    f = cf_known_position(0, -1800000001, 0u);
    assert_int_equal(decode(&f), RX_BAD_VALUE);
    f = cf_known_position(450000000, -1799999999, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.kind, RX_KNOWN_POSITION);
    assert_int_equal(in.u.position.lat_e7, 450000000);
    assert_int_equal(in.u.position.lon_e7, -1799999999);
}

/* Longitude exactly -180 deg is within the DBC's range (issue #17): accepted, and handed on
 * as +180 deg, the same meridian, because the core wraps longitude to (-180, 180]. */
static void test_longitude_minus_180_accepted(void **state)
{
    (void)state;
    hal_can_frame_t f = cf_gnss_position(0, -1800000000, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.kind, RX_GNSS_POSITION);
    assert_int_equal(in.u.position.lon_e7, 1800000000);
    f = cf_known_position(-450000000, -1800000000, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.kind, RX_KNOWN_POSITION);
    assert_int_equal(in.u.position.lat_e7, -450000000);
    assert_int_equal(in.u.position.lon_e7, 1800000000);
}

/* ---- decoded values ---- */

/* GIVEN an IMU pair packed with the codec THEN the raw LSB values, the counter, the fault
 * bit and the payloads come out as sent (the pair CRC is imu_stream's, so byte 7 of
 * IMU_Accel is not looked at here). */
static void test_imu_frames_decoded(void **state)
{
    (void)state;
    const int32_t w[3] = {123456, -1, -524288}; /* the 20-bit signal's extremes */
    const int32_t v[3] = {65535, -65536, 1};     /* the 17-bit signal's extremes */
    hal_can_frame_t fr, fa;
    cf_imu_pair(w, v, 7u, 1u, 0u, &fr, &fa);
    assert_int_equal(decode(&fr), RX_OK);
    assert_int_equal(in.kind, RX_IMU_RATE);
    assert_int_equal(in.u.imu_rate.counter, 7);
    for (int i = 0; i < 3; i++) {
        assert_int_equal(in.u.imu_rate.raw[i], w[i]);
    }
    assert_memory_equal(in.u.imu_rate.data, fr.data, 8u);
    fa.data[7] ^= 0xFFu;
    assert_int_equal(decode(&fa), RX_OK);
    assert_int_equal(in.kind, RX_IMU_ACCEL);
    assert_int_equal(in.u.imu_accel.counter, 7);
    assert_int_equal(in.u.imu_accel.fault, 1);
    for (int i = 0; i < 3; i++) {
        assert_int_equal(in.u.imu_accel.raw[i], v[i]);
    }
    assert_memory_equal(in.u.imu_accel.data, fa.data, 8u);
    /* IMU_Rate's counter 15 is invalid */
    cf_imu_pair(w, v, 15u, 0u, 0u, &fr, &fa);
    assert_int_equal(decode(&fr), RX_BAD_COUNTER);
}

/* Raw increments to SI: 2^-21 rad and 2^-12 m/s per LSB, exactly. */
static void test_imu_increment_si(void **state)
{
    (void)state;
    assert_near(app_rx_angle_lsb_rad(), 1.0 / 2097152.0, 0.0);
    assert_near(app_rx_vel_lsb_mps(), 1.0 / 4096.0, 0.0);
    const int32_t w[3] = {524288, -2097, 1};
    const int32_t v[3] = {4096, -40960, 0};
    imu_inc_t inc;
    app_rx_imu_increment(w, v, 0.01f, &inc);
    assert_near(inc.dtheta_b_rad[0], 0.25, 0.0);
    assert_near(inc.dtheta_b_rad[1], -2097.0 / 2097152.0, 0.0);
    assert_near(inc.dtheta_b_rad[2], 1.0 / 2097152.0, 0.0);
    assert_near(inc.dv_b_mps[0], 1.0, 0.0);
    assert_near(inc.dv_b_mps[1], -10.0, 0.0);
    assert_near(inc.dv_b_mps[2], 0.0, 0.0);
    assert_near(inc.dt_s, 0.01f, 0.0);
}

/* WheelSpeeds at 0.02 m/s per step, signed (reverse negative), FL FR RL RR in order. */
static void test_wheels_decoded(void **state)
{
    (void)state;
    const int16_t raw[4] = {500, -125, 4095, -4096};
    const hal_can_frame_t f = cf_wheels(raw, 0u, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.kind, RX_WHEELS);
    assert_near(in.u.wheels.mps[0], 10.0, 0.0);
    assert_near(in.u.wheels.mps[1], -2.5, 0.0);
    assert_near(in.u.wheels.mps[2], 81.9, 1e-5);   /* 81.9 has no exact float */
    assert_near(in.u.wheels.mps[3], -81.92, 1e-5);
}

/* GNSS_Velocity: ENU at 0.01 m/s, speed accuracy at 0.1 m/s. */
static void test_gnss_velocity_decoded(void **state)
{
    (void)state;
    const hal_can_frame_t f = velocity(1000, -250, 50, 4u, 3u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.kind, RX_GNSS_VELOCITY);
    assert_int_equal(in.u.velocity.epoch, 4);
    assert_near(in.u.velocity.v_enu_mps[0], 10.0, 0.0);
    assert_near(in.u.velocity.v_enu_mps[1], -2.5, 0.0);
    assert_near(in.u.velocity.v_enu_mps[2], 0.5, 0.0);
    assert_near(in.u.velocity.sacc_mps, 0.3, 1e-7);
}

/* GNSS_Height in cm, kept as cm; beyond the DBC's -1000..50000 m refused. */
static void test_gnss_height_decoded(void **state)
{
    (void)state;
    hal_can_frame_t f = cf_gnss_height(12345, 9u, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.kind, RX_GNSS_HEIGHT);
    assert_int_equal(in.u.height.epoch, 9);
    assert_int_equal(in.u.height.h_cm, 12345);
    f = cf_gnss_height(5000000, 0u, 0u); /* 50000.00 m: the top */
    assert_int_equal(decode(&f), RX_OK);
    f = cf_gnss_height(5000001, 0u, 0u);
    assert_int_equal(decode(&f), RX_BAD_VALUE);
    f = cf_gnss_height(-100001, 0u, 0u);
    assert_int_equal(decode(&f), RX_BAD_VALUE);
}

static hal_can_frame_t status(uint8_t fix_type, uint8_t sats, uint8_t epoch)
{
    struct navecu_can_gnss_status_t s;
    memset(&s, 0, sizeof s);
    s.fix_type = fix_type;
    s.num_satellites = sats;
    s.horiz_accuracy = 25u;
    s.vert_accuracy = 31u;
    s.gnss_epoch = epoch;
    s.time_of_week = 604799999u;
    return cf_gnss_status(&s, 0u);
}

/* GNSS_Status: its values, "defined" for fix types 0..6, epochs 0..14 and a TimeOfWeek within
 * the week, 3D from type 3. */
static void test_gnss_status_decoded(void **state)
{
    (void)state;
    hal_can_frame_t f = status(3u, 9u, 4u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.kind, RX_GNSS_STATUS);
    assert_int_equal(in.u.status.epoch, 4);
    assert_int_equal(in.u.status.defined, 1);
    assert_int_equal(in.u.status.fix_3d, 1);
    assert_int_equal(in.u.status.n_sats, 9);
    assert_near(in.u.status.hacc_m, 2.5, 0.0);
    assert_near(in.u.status.vacc_m, 3.1, 1e-6);
    assert_int_equal(in.u.status.tow_ms, 604799999u);
    f = status(2u, 9u, 4u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.fix_3d, 0);
    assert_int_equal(in.u.status.defined, 1);
    f = status(6u, 9u, 4u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.defined, 1);
    f = status(7u, 9u, 4u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.defined, 0);
    f = status(3u, 9u, 15u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.defined, 0);
    /* a TimeOfWeek beyond the week's last millisecond (604,799,999) is no time of week */
    struct navecu_can_gnss_status_t s;
    memset(&s, 0, sizeof s);
    s.fix_type = 3u;
    s.num_satellites = 9u;
    s.gnss_epoch = 4u;
    s.time_of_week = 604800000u;
    f = cf_gnss_status(&s, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.status.defined, 0);
}

/* CMD_Control: heading 0.01 deg -> rad, height 0.1 m -> cm, and the range flags. */
static void test_command_decoded(void **state)
{
    (void)state;
    struct navecu_can_cmd_control_t c;
    memset(&c, 0, sizeof c);
    c.command = 2u;
    c.heading_valid = 1u;
    c.heading = 9000u;  /* 90.00 deg */
    c.height = -1234;   /* -123.4 m */
    c.cmd_counter = 0u;
    hal_can_frame_t f = cf_control(&c, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.kind, RX_COMMAND);
    assert_int_equal(in.u.command.command, RX_CMD_SET_INITIAL_POSITION);
    assert_int_equal(in.u.command.heading_valid, 1);
    assert_int_equal(in.u.command.heading_in_range, 1);
    assert_int_equal(in.u.command.height_in_range, 1);
    assert_near(in.u.command.heading_rad, 1.5707963267948966, 2e-7);
    assert_int_equal(in.u.command.h_cm, -12340);
    /* 360.00 deg and 50000.1 m are beyond the DBC's ranges; command 9 is not defined */
    c.command = 9u;
    c.heading = 36000u;
    c.height = 500001;
    c.cmd_counter = 1u;
    f = cf_control(&c, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.command.command, RX_CMD_UNKNOWN);
    assert_int_equal(in.u.command.heading_in_range, 0);
    assert_int_equal(in.u.command.height_in_range, 0);
    c.command = 6u;
    c.cmd_counter = 2u;
    f = cf_control(&c, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.u.command.command, RX_CMD_CALIBRATE_AT_GNSS);
}

/* CMD_InitialAttitude at 2^-22 rad; a pitch beyond +-pi/2 is a bad value. */
static void test_initial_attitude_decoded(void **state)
{
    (void)state;
    hal_can_frame_t f = cf_initial_attitude(4194304, -2097152, 0u, 0u);
    assert_int_equal(decode(&f), RX_OK);
    assert_int_equal(in.kind, RX_INITIAL_ATTITUDE);
    assert_near(in.u.attitude.roll_rad, 1.0, 0.0);
    assert_near(in.u.attitude.pitch_rad, -0.5, 0.0);
    /* pi/2 / 2^-22 = 6588397.3: raw 6588397 is in range, 6588398 is not */
    f = cf_initial_attitude(0, 6588397, 1u, 0u);
    assert_int_equal(decode(&f), RX_OK);
    f = cf_initial_attitude(0, 6588398, 2u, 0u);
    assert_int_equal(decode(&f), RX_BAD_VALUE);
}

/* GNSS_RawSatX, Y and Z: each axis's frame packed with its own codec, decoded to its part
 * with the position and velocity in their LSB (app_rx.c unpacks the three with X's
 * layout: the DBC gives them one) */
static void test_raw_sat_axes_decoded(void **state)
{
    (void)state;
    const uint32_t ids[3] = {NAVECU_CAN_GNSS_RAW_SAT_X_FRAME_ID, NAVECU_CAN_GNSS_RAW_SAT_Y_FRAME_ID,
                             NAVECU_CAN_GNSS_RAW_SAT_Z_FRAME_ID};
    const uint8_t parts[3] = {RX_RAW_PART_X, RX_RAW_PART_Y, RX_RAW_PART_Z};
    const int32_t pos[3] = {INT32_MIN, -123456789, INT32_MAX};
    const int16_t vel[3] = {INT16_MAX, INT16_MIN, -2};
    for (int k = 0; k < 3; k++) {
        uint8_t d[8];
        const uint8_t slot = (uint8_t)(15 - k);
        const uint8_t epoch = (uint8_t)(14 - 3 * k);
        if (k == 0) {
            struct navecu_can_gnss_raw_sat_x_t m = {pos[k], vel[k], slot, epoch, 0u};
            navecu_can_gnss_raw_sat_x_pack(d, &m, 8u);
        } else if (k == 1) {
            struct navecu_can_gnss_raw_sat_y_t m = {pos[k], vel[k], slot, epoch, 0u};
            navecu_can_gnss_raw_sat_y_pack(d, &m, 8u);
        } else {
            struct navecu_can_gnss_raw_sat_z_t m = {pos[k], vel[k], slot, epoch, 0u};
            navecu_can_gnss_raw_sat_z_pack(d, &m, 8u);
        }
        e2e_protect(ids[k], d);
        const hal_can_frame_t f = cf_frame(ids[k], d, 0u);
        memset(&in, 0xA5, sizeof in);
        assert_int_equal(decode(&f), RX_OK);
        assert_int_equal(in.kind, RX_GNSS_RAW_SAT);
        assert_int_equal(in.u.raw_sat.part, parts[k]);
        assert_int_equal(in.u.raw_sat.epoch, epoch);
        assert_int_equal(in.u.raw_sat.slot, slot);
        assert_int_equal(in.u.raw_sat.pos_lsb, pos[k]);
        assert_int_equal(in.u.raw_sat.vel_lsb, vel[k]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_extended_id_refused, setup),
        cmocka_unit_test_setup(test_foreign_id_refused, setup),
        cmocka_unit_test_setup(test_dlc_7_refused, setup),
        cmocka_unit_test_setup(test_rx_ids, setup),
        cmocka_unit_test_setup(test_own_outputs_ignored, setup),
        cmocka_unit_test_setup(test_bad_crc_refused, setup),
        cmocka_unit_test_setup(test_repeated_counter_refused, setup),
        cmocka_unit_test_setup(test_gnss_status_repeat, setup),
        cmocka_unit_test_setup(test_command_counter_window, setup),
        cmocka_unit_test_setup(test_lat_lon_range, setup),
        cmocka_unit_test_setup(test_longitude_minus_180_accepted, setup),
        cmocka_unit_test_setup(test_imu_frames_decoded, setup),
        cmocka_unit_test_setup(test_imu_increment_si, setup),
        cmocka_unit_test_setup(test_wheels_decoded, setup),
        cmocka_unit_test_setup(test_gnss_velocity_decoded, setup),
        cmocka_unit_test_setup(test_gnss_height_decoded, setup),
        cmocka_unit_test_setup(test_gnss_status_decoded, setup),
        cmocka_unit_test_setup(test_command_decoded, setup),
        cmocka_unit_test_setup(test_initial_attitude_decoded, setup),
        cmocka_unit_test_setup(test_raw_sat_axes_decoded, setup),
    };
    return cmocka_run_group_tests_name("app_rx", tests, NULL, NULL);
}
