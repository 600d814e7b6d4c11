/* output.c - the NAV_* frames, HealthFlags and the output mode; see output.h. */
#include "output.h"

#include <string.h>

#include "app.h"
#include "app_tuning.h"
#include "e2e.h"
#include "navecu_can.h"
#include "navecu_protocol.h"

enum { TX_HEIGHT = 0, TX_VEL, TX_ATT, TX_STATUS, TX_CAL, TX_RATES, TX_ATT_RATES, TX_ACCEL,
       TX_ACCEL_ENU, TX_ACCURACY, TX_HEARTBEAT };

static void send(tx_state_t *tx, hal_t *hal, uint32_t id, const uint8_t data[8])
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = 8u;
    memcpy(f.data, data, 8u);
    if (hal_can_send(hal, &f) == 0) {
        tx->frames_sent++;
    } else {
        app_count(&tx->send_errors);
    }
}

/* E2E-protect and send; the alive counter of output `which` is taken and advanced.
 * Out of line (noinline), as accuracy_raw and accuracy_lsb: GCC inlined these small helpers
 * at each of their 14, 3 and 4 calls, 304 bytes of the ECU's flash more in all
 * (docs/target.md); they run per output frame (at most 50 Hz), not per IMU sample. */
__attribute__((noinline)) static uint8_t next_counter(tx_state_t *tx, int which)
{
    const uint8_t c = tx->counter[which];
    tx->counter[which] = e2e_counter_next(c);
    return c;
}

static void send_protected(tx_state_t *tx, hal_t *hal, uint32_t id, uint8_t data[8])
{
    e2e_protect(id, data);
    send(tx, hal, id, data);
}

/* fixed-point LSB (GEO_LSB_PER_*) to a coarser integer unit, rounding half away from 0.
 * Out of line (noinline), as sat16: inlined at their 3 and 11 calls they took 56 bytes more
 * of the ECU's flash; per output frame, not per IMU sample. */
__attribute__((noinline)) static int64_t lsb_div_round(int64_t x, int64_t div)
{
    return (x >= 0 ? x + div / 2 : x - div / 2) / div;
}

/* a 1-sigma (scaled to the signal's LSB) rounded into an accuracy signal whose largest
 * raw value means "unknown": saturates one below it */
__attribute__((noinline)) static uint32_t accuracy_raw(nav_real_t sigma_lsb, uint32_t raw_max)
{
    const nav_real_t top = (nav_real_t)(raw_max - 1u);
    return sigma_lsb < top ? (uint32_t)(sigma_lsb + NAV_C(0.5)) : raw_max - 1u;
}

/* The attitude NAV_Attitude sends: the IMU's roll, the car's pitch (within +-90 deg) and
 * heading ([0, 2 pi)): the IMU's less the mounting (the filter's estimate) or, without
 * the filter, less the one-point calibration's dH. *mount_yaw, *mount_pitch: that
 * mounting. */
static void car_attitude(const app_t *a, nav_real_t att[3], nav_real_t *mount_yaw,
                         nav_real_t *mount_pitch)
{
    const ekf_t *ekf = app_filter(a);
    nav_real_t roll, pitch, heading;
    sins_euler(&a->run.nav, &roll, &pitch, &heading);
    *mount_yaw = ekf != NULL ? ekf->mount_yaw_rad : a->run.dr.dh_rad;
    *mount_pitch = ekf != NULL ? ekf->mount_pitch_rad : NAV_C(0.0);
    heading -= *mount_yaw;
    pitch -= *mount_pitch;
    if (heading < NAV_C(0.0)) {
        heading += NAV_C(2.0) * NAV_PI;
    } else if (heading >= NAV_C(2.0) * NAV_PI) {
        heading -= NAV_C(2.0) * NAV_PI;
    }
    /* the car's pitch within the DBC's +-90 deg: the IMU at 89.7 deg less a mounting pitch
     * of -1 deg would otherwise be sent as 90.7 (found by tests/fuzz/fuzz_options.c) */
    att[0] = roll;
    att[1] = nav_clamp(pitch, -NAV_C(0.5) * NAV_PI, NAV_C(0.5) * NAV_PI);
    att[2] = heading;
}

static void emit_navigation(app_t *a, hal_t *hal)
{
    tx_state_t *tx = &a->keep.tx;
    const sins_t *s = &a->run.nav;
    const ekf_t *ekf = app_filter(a);
    uint8_t d[8];
    if (!sins_finite(s)) {
        app_count(&a->keep.health.nonfinite_out); /* never on the bus; supervision resets it */
        return;
    }

    struct navecu_can_nav_position_t p;
    p.latitude = (int32_t)lsb_div_round(s->pos.lat, GEO_LSB_PER_DEG_E7);
    p.longitude = (int32_t)lsb_div_round(s->pos.lon, GEO_LSB_PER_DEG_E7);
    navecu_can_nav_position_pack(d, &p, sizeof d);
    send(tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_POSITION], d);

    struct navecu_can_nav_height_t h;
    h.height = (int32_t)lsb_div_round(s->pos.h, 10 * GEO_LSB_PER_MM); /* 0.01 m */
    h.vert_accuracy = NAVECU_NAV_HEIGHT_VERT_ACCURACY_RAW_MAX; /* "unknown" without the filter */
    if (ekf != NULL) {
        h.vert_accuracy =
            (uint8_t)accuracy_raw(fusion_sigma_v_m(&a->run.fusion, &a->cfg) * NAV_C(10.0),
                                  NAVECU_NAV_HEIGHT_VERT_ACCURACY_RAW_MAX);
    }
    /* time of validity on the IMU time base, so that a recorder need not trust arrival
     * times: a vcan recording and a --can-log run carry the same value */
    h.time_of_validity =
        (uint16_t)((app_time_us(a) / 1000u) & 0xFFFFu);
    h.nav_counter = next_counter(tx, TX_HEIGHT);
    h.nav_crc = 0u;
    navecu_can_nav_height_pack(d, &h, sizeof d);
    send_protected(tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_HEIGHT], d);

    struct navecu_can_nav_velocity_t v;
    int16_t ve[3]; /* the three axes have one range and resolution (the DBC's) */
    for (int i = 0; i < 3; i++) {
        ve[i] = navecu_can_nav_velocity_vel_east_encode(nav_clamp(
            s->v_n_mps[i], NAVECU_NAV_VELOCITY_VEL_EAST_MIN, NAVECU_NAV_VELOCITY_VEL_EAST_MAX));
    }
    v.vel_east = ve[0];
    v.vel_north = ve[1];
    v.vel_up = ve[2];
    v.nav_counter = next_counter(tx, TX_VEL);
    v.nav_crc = 0u;
    navecu_can_nav_velocity_pack(d, &v, sizeof d);
    send_protected(tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_VELOCITY], d);

    nav_real_t att[3], my, mp;
    car_attitude(a, att, &my, &mp);
    struct navecu_can_nav_attitude_t at;
    at.roll = navecu_can_nav_attitude_roll_encode(att[0] * NAV_DEG_PER_RAD);
    at.pitch = navecu_can_nav_attitude_pitch_encode(att[1] * NAV_DEG_PER_RAD);
    at.heading = navecu_can_nav_attitude_heading_encode(att[2] * NAV_DEG_PER_RAD);
    if (at.heading > navecu_can_nav_attitude_heading_encode(NAVECU_NAV_ATTITUDE_HEADING_MAX)) {
        at.heading = 0u; /* 359.996 deg rounds to 360.00: that is north */
    }
    at.nav_counter = next_counter(tx, TX_ATT);
    at.nav_crc = 0u;
    navecu_can_nav_attitude_pack(d, &at, sizeof d);
    send_protected(tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_ATTITUDE], d);

    /* the set's GNSS time of validity (raw microseconds: a float would keep 60 ms) */
    struct navecu_can_nav_time_t nt;
    uint64_t tow_us;
    uint16_t week;
    if (gnss_time_at(&a->keep.gnss_time, app_time_us(a),
                     gnss_time_latency(&a->keep.gnss_time, a->cfg.gnss_latency_s), &tow_us,
                     &week) != 0) {
        tow_us = NAVECU_NAV_TIME_TIME_OF_WEEK_RAW_MAX;
        week = NAVECU_NAV_TIME_GPS_WEEK_RAW_MAX;
    }
    nt.time_of_week = tow_us;
    nt.gps_week = week;
    nt.nav_crc = 0u;
    navecu_can_nav_time_pack(d, &nt, sizeof d);
    send_protected(tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_TIME], d);
}

static void emit_dynamics(app_t *a, hal_t *hal)
{
    tx_state_t *tx = &a->keep.tx;
    nav_real_t att[3], my, mp;
    car_attitude(a, att, &my, &mp);
    dynamics_out_t m;
    if (!sins_finite(&a->run.nav) || dynamics_take(&a->run.dyn, &a->run.nav, my, mp, &m) != 0) {
        return;
    }
    /* NAV_Rates, NAV_AttitudeRates, NAV_Accel and NAV_AccelEnu, in the order of their
     * message and alive-counter indices: each three signed 16-bit signals, a counter and a
     * CRC in the same layout (the DBC's), packed as NAV_Rates; the rates in deg/s, the
     * accelerations in m/s^2, each pair with one range and resolution. One loop, not four
     * copies of the same encode and send (flash, docs/target.md). */
    const nav_real_t *const src[4] = {m.rate_v_rps, m.att_rate_rps, m.accel_v_mps2,
                                      m.accel_n_mps2};
    const nav_real_t rlo = NAVECU_NAV_RATES_RATE_X_MIN, rhi = NAVECU_NAV_RATES_RATE_X_MAX;
    const nav_real_t alo = NAVECU_NAV_ACCEL_ACCEL_X_MIN, ahi = NAVECU_NAV_ACCEL_ACCEL_X_MAX;
    for (int k = 0; k < 4; k++) {
        int16_t e[3];
        for (int i = 0; i < 3; i++) {
            if (k < 2) {
                e[i] = navecu_can_nav_rates_rate_x_encode(
                    nav_clamp(src[k][i] * NAV_DEG_PER_RAD, rlo, rhi));
            } else {
                e[i] = navecu_can_nav_accel_accel_x_encode(nav_clamp(src[k][i], alo, ahi));
            }
        }
        struct navecu_can_nav_rates_t r;
        r.rate_x = e[0];
        r.rate_y = e[1];
        r.rate_z = e[2];
        r.nav_counter = next_counter(tx, TX_RATES + k);
        r.nav_crc = 0u;
        uint8_t d[8];
        navecu_can_nav_rates_pack(d, &r, sizeof d);
        send_protected(tx, hal, a->cfg.can_ids[(int)NAVECU_MSG_NAV_RATES + k], d);
    }
}
_Static_assert(TX_ATT_RATES == TX_RATES + 1 && TX_ACCEL == TX_RATES + 2 &&
                   TX_ACCEL_ENU == TX_RATES + 3,
               "emit_dynamics' counters in message order");
_Static_assert((int)NAVECU_MSG_NAV_ATTITUDE_RATES == (int)NAVECU_MSG_NAV_RATES + 1 &&
                   (int)NAVECU_MSG_NAV_ACCEL == (int)NAVECU_MSG_NAV_RATES + 2 &&
                   (int)NAVECU_MSG_NAV_ACCEL_ENU == (int)NAVECU_MSG_NAV_RATES + 3,
               "emit_dynamics' messages in this order");

/* an accuracy of NAV_Accuracy: never below one LSB (a sigma smaller than the resolution is
 * sent as the resolution, not as zero) */
__attribute__((noinline)) static uint16_t accuracy_lsb(nav_real_t sigma_lsb, uint32_t raw_max)
{
    return (uint16_t)accuracy_raw(sigma_lsb > NAV_C(1.0) ? sigma_lsb : NAV_C(1.0), raw_max);
}

/* NAV_Accuracy: the filter's 1-sigma of the velocity and of the car's heading (the
 * IMU's heading error psi_U less the mounting yaw's, with their covariance); without the
 * filter, the dead reckoning's heading sigma while its error model holds (dr_acc.h) */
static void emit_accuracy(app_t *a, hal_t *hal)
{
    const ekf_t *ekf = a->run.mode == APP_MODE_NAVIGATING ? app_filter(a) : NULL;
    const uint32_t unknown = NAVECU_NAV_ACCURACY_VEL_ACC_EAST_RAW_MAX;
    struct navecu_can_nav_accuracy_t m;
    m.vel_acc_east = m.vel_acc_north = m.vel_acc_up = m.heading_accuracy = (uint16_t)unknown;
    nav_real_t head_sigma = NAV_C(-1.0); /* the car's heading's 1-sigma, rad; < 0 unknown */
    if (ekf != NULL) {
        m.vel_acc_east = accuracy_lsb(ekf_state_sigma(ekf, EKF_DV) * NAV_C(100.0), unknown);
        m.vel_acc_north = accuracy_lsb(ekf_state_sigma(ekf, EKF_DV + 1) * NAV_C(100.0), unknown);
        m.vel_acc_up = accuracy_lsb(ekf_state_sigma(ekf, EKF_DV + 2) * NAV_C(100.0), unknown);
        const nav_real_t var = ekf_state_cov(ekf, EKF_PSI + 2, EKF_PSI + 2) +
                               ekf_state_cov(ekf, EKF_MY, EKF_MY) -
                               NAV_C(2.0) * ekf_state_cov(ekf, EKF_PSI + 2, EKF_MY);
        head_sigma = nav_sqrt(var > NAV_C(0.0) ? var : NAV_C(0.0));
    } else if (a->run.mode == APP_MODE_NAVIGATING && a->run.land.output_dr != 0u) {
        /* the dead reckoning's heading (the SINS's less dH): its error psi (dr_acc.h) */
        head_sigma = dr_acc_sigma_heading_rad(&a->run.land.acc);
    } else {
        /* no filter and no dead reckoning: unknown */
    }
    if (head_sigma >= NAV_C(0.0)) {
        m.heading_accuracy =
            accuracy_lsb(head_sigma * NAV_DEG_PER_RAD * NAV_C(100.0), unknown);
    }
    m.nav_counter = next_counter(&a->keep.tx, TX_ACCURACY);
    m.nav_crc = 0u;
    uint8_t d[8];
    navecu_can_nav_accuracy_pack(d, &m, sizeof d);
    send_protected(&a->keep.tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_ACCURACY], d);
}

__attribute__((noinline)) static uint16_t sat16(uint32_t x)
{
    return x > UINT16_MAX ? (uint16_t)UINT16_MAX : (uint16_t)x;
}

static uint8_t sat8(uint32_t x)
{
    return x > UINT8_MAX ? (uint8_t)UINT8_MAX : (uint8_t)x;
}

/* IMU_STALE: no IMU sample for APP_IMU_STALE_US of the HAL clock, since the last one or,
 * before the first, since power-on (the first NAV_Heartbeat; app_poll's app_imu_since) */
static int imu_stale(const app_t *a, const hal_t *hal)
{
    const uint64_t now = hal_time_us(hal);
    const uint64_t since = app_imu_since(a);
    return now > since && now - since > APP_IMU_STALE_US;
}

/* NO_GNSS: no usable GNSS epoch for APP_NO_GNSS_S of IMU time (or none since power-on) */
static int no_gnss(const app_t *a)
{
    return !app_stamp_within(&a->keep.gnss, a->keep.n_samples,
                             (uint64_t)APP_NO_GNSS_S * a->cfg.imu_rate_hz);
}

/* HealthFlags WATCHDOG_OFF and BUS_OFF are hal.h's HAL_FAULT_WATCHDOG and HAL_FAULT_BUS_OFF
 * moved up by one factor */
#define BOARD_TO_HEALTH (NAVECU_HEALTH_WATCHDOG_OFF / HAL_FAULT_WATCHDOG)
_Static_assert(NAVECU_HEALTH_BUS_OFF == HAL_FAULT_BUS_OFF * BOARD_TO_HEALTH,
               "HealthFlags' board faults in hal.h's order");
#define BOARD_FLAGS (NAVECU_HEALTH_WATCHDOG_OFF | NAVECU_HEALTH_BUS_OFF)

/* HealthFlags WATCHDOG_OFF and BUS_OFF now: the board's faults (hal_faults: the watchdog
 * not running, a bus-off since the last call), read once per NAV_Status or DTC test */
__attribute__((noinline)) static uint32_t board_flags(hal_t *hal)
{
    return (hal_faults(hal) & (HAL_FAULT_WATCHDOG | HAL_FAULT_BUS_OFF)) * BOARD_TO_HEALTH;
}

/* The car stands, for the DTCs tested only while it moves: navigating, the odometer's
 * standstill (its wheels at zero and no turn for 0.5 s); outside navigation, where nothing
 * updates that standstill (odo_tick runs in the navigator's step), its wheels reading zero
 * (a review found a car parked at power-on, waiting for GNSS, confirming U1102-87 after
 * 60 s). 0 or 1. */
static uint32_t car_stands(const app_t *a)
{
    const odo_t *o = &a->keep.odo;
    return a->run.mode == APP_MODE_NAVIGATING ? o->standing : (uint32_t)(o->valid & o->zero);
}

/* board: board_flags now */
static uint16_t health_flags(const app_t *a, const hal_t *hal, uint32_t board)
{
    const app_keep_t *k = &a->keep;
    const app_run_t *r = &a->run;
    const uint64_t n = k->n_samples;
    const uint64_t second = a->cfg.imu_rate_hz;
    uint32_t fl = 0u;
    if (imu_stale(a, hal)) {
        fl |= NAVECU_HEALTH_IMU_STALE;
    }
    if (k->imu.fault) {
        fl |= NAVECU_HEALTH_IMU_FAULT;
    }
    if (no_gnss(a)) {
        fl |= NAVECU_HEALTH_NO_GNSS;
    }
    if (app_stamp_within(&r->events.reject, n, APP_FLAG_HOLD_S * second)) {
        fl |= NAVECU_HEALTH_REJECTED;
    }
    if (k->cal.nvm_error) {
        fl |= NAVECU_HEALTH_NVM_ERROR;
    }
    /* the heading unknown: commanded without one, or the GNSS-only start (usable epochs,
     * no initial state: the course while driving gives it, docs/kalman.md) */
    if ((r->mode != APP_MODE_NAVIGATING && r->align.pos_valid && !r->align.heading_valid) ||
        (r->mode == APP_MODE_WAIT_INIT && !r->align.heading_valid &&
         !no_gnss(a))) {
        fl |= NAVECU_HEALTH_NO_HEADING;
    }
    if (app_stamp_within(&r->events.gap, n, APP_FLAG_HOLD_S * second)) {
        fl |= NAVECU_HEALTH_IMU_GAP;
    }
    if (app_stamp_within(&k->filter_reset, n, APP_FLAG_HOLD_LONG_S * second)) {
        fl |= NAVECU_HEALTH_FILTER_RESET;
    }
    if (app_stamp_within(&r->events.stuck, n, APP_FLAG_HOLD_LONG_S * second)) {
        fl |= NAVECU_HEALTH_IMU_SUSPECT;
    }
    if (app_stamp_within(&r->events.saturated, n, APP_FLAG_HOLD_S * second)) {
        fl |= NAVECU_HEALTH_IMU_SATURATED;
    }
    if (app_stamp_within(&r->events.odo_reject, n, APP_FLAG_HOLD_S * second)) {
        fl |= NAVECU_HEALTH_ODO_REJECTED;
    }
    if (r->align.reacquire) {
        fl |= NAVECU_HEALTH_REACQUIRE;
    }
    if (imu_rate_mismatch(&k->rate)) {
        fl |= NAVECU_HEALTH_IMU_RATE_MISMATCH;
    }
    fl |= board; /* the watchdog not running, a bus-off since the last NAV_Status */
    return (uint16_t)fl;
}

/* NAV_Status Mode: the solution being output */
static uint8_t output_mode(const app_t *a)
{
    switch (a->run.mode) {
    case APP_MODE_WAIT_INIT:
        return NAVECU_CAN_NAV_STATUS_MODE_WAIT_INIT_CHOICE;
    case APP_MODE_LEVELLING:
        return NAVECU_CAN_NAV_STATUS_MODE_LEVELLING_CHOICE;
    case APP_MODE_FAULT:
        return NAVECU_CAN_NAV_STATUS_MODE_FAULT_CHOICE;
    default:
        break;
    }
    const int dead_reckoning = app_filter(a) != NULL ? a->keep.odo.valid : a->run.land.output_dr;
    if (app_filter(a) != NULL &&
        app_stamp_within(&a->run.fusion.fix, a->keep.n_samples,
                         (uint64_t)APP_GNSS_FIX_FRESH_S * a->cfg.imu_rate_hz)) {
        return NAVECU_CAN_NAV_STATUS_MODE_GNSS_INS_CHOICE;
    }
    return dead_reckoning ? NAVECU_CAN_NAV_STATUS_MODE_DEAD_RECKONING_CHOICE
                          : NAVECU_CAN_NAV_STATUS_MODE_INERTIAL_CHOICE;
}

/* one page of counters, in rotation */
static void fill_counter_page(struct navecu_can_nav_status_t *st, const app_health_t *h)
{
    switch (st->status_page) {
    case 1u:
        st->cnt_foreign = (uint16_t)(h->foreign & 0xFFFFu); /* wraps: a rate, not a fault */
        st->cnt_bad_dlc = sat16(h->bad_dlc);
        st->cnt_bad_crc = sat8(h->bad_crc);
        break;
    case 2u:
        st->cnt_bad_counter = sat16(h->bad_counter);
        st->cnt_imu_pair_broken = sat16(h->imu_pair_broken);
        st->cnt_imu_lost = sat8(h->imu_lost);
        break;
    case 3u:
        st->cnt_bad_value = sat16(h->bad_value);
        st->cnt_gnss_rejected = sat16(h->gnss_rejected);
        st->cnt_rx_lost = sat8(h->rx_lost);
        break;
    case 4u:
        st->cnt_cmd_rejected = sat16(h->cmd_rejected);
        st->cnt_core_rejected = sat16(h->nav_rejected);
        st->cnt_time_jumps = sat8(h->time_jumps);
        break;
    case 5u:
        st->cnt_filter_resets = sat16(h->filter_resets);
        st->cnt_tasks_late = sat16(h->tasks_late);
        st->cnt_non_finite = sat8(h->nonfinite_out);
        break;
    default:
        st->cnt_imu_saturated = sat16(h->imu_saturated);
        st->cnt_odo_rejected = sat16(h->odo_rejected);
        st->cnt_imu_stuck = sat8(h->imu_stuck);
        break;
    }
}

void output_dtc_tests(app_t *a, hal_t *hal)
{
    a->keep.tx.last_status_t_us = hal_time_us(hal);
    /* only the flags that mean something before any IMU sample (the others hold for a
     * number of IMU samples: with none, one refused frame would stay REJECTED for good,
     * a review found) */
    const uint32_t nvm = a->keep.cal.nvm_error ? NAVECU_HEALTH_NVM_ERROR : 0u;
    /* and the board's, which an ECU whose IMU never speaks must store too (a review) */
    app_dtc_cycle_tested(a, hal, NAVECU_HEALTH_IMU_STALE | nvm | board_flags(hal),
                         NAVECU_HEALTH_IMU_STALE | NAVECU_HEALTH_NVM_ERROR | BOARD_FLAGS);
}

void output_status(app_t *a, hal_t *hal)
{
    tx_state_t *tx = &a->keep.tx;
    const ekf_t *ekf = app_filter(a);
    uint8_t d[8];
    a->keep.health.rx_lost = hal_can_rx_lost(hal);
    const uint32_t board = board_flags(hal);
    tx->last_status_t_us = hal_time_us(hal);
    struct navecu_can_nav_status_t st;
    memset(&st, 0, sizeof st);
    st.status_page = NAVECU_NAV_STATUS_PAGE_STATE;
    st.mode = output_mode(a);
    tx->last_mode = st.mode;
    st.health_flags = health_flags(a, hal, board);
    /* the DTCs' tests (app_dtc.h); those of waits of normal operation (dtc.toml
     * while_moving) only while the car moves (a car standing after power-on may wait for a
     * fix or a heading for as long as it stands) */
    app_dtc_cycle_tested(a, hal, st.health_flags, /* car_stands is 0 or 1 */
                         ~((uint32_t)DTC_WHILE_MOVING_FLAGS * car_stands(a)));

    /* the filter's; without it the dead reckoning's while it is the output and its error
     * model holds (dr_acc.h); else "unknown" */
    st.horiz_accuracy = NAVECU_NAV_STATUS_HORIZ_ACCURACY_RAW_MAX;
    if (a->run.mode == APP_MODE_NAVIGATING) {
        const nav_real_t sh =
            ekf != NULL ? fusion_sigma_h_m(&a->run.fusion, &a->cfg)
            : a->run.land.output_dr != 0u ? dr_acc_sigma_h_m(&a->run.land.acc)
                                          : NAV_C(-1.0);
        if (sh >= NAV_C(0.0)) {
            st.horiz_accuracy = (uint16_t)accuracy_raw(
                sh * NAV_C(100.0), NAVECU_NAV_STATUS_HORIZ_ACCURACY_RAW_MAX);
        }
    }
    /* the IMU rate measured from the data while it disagrees with the configured one */
    const uint32_t chz = imu_rate_measured_chz(&a->keep.rate);
    st.imu_rate_measured = navecu_can_nav_status_imu_rate_measured_encode(
        nav_clamp((nav_real_t)chz * NAV_C(0.01), NAVECU_NAV_STATUS_IMU_RATE_MEASURED_MIN,
                  NAVECU_NAV_STATUS_IMU_RATE_MEASURED_MAX));
    st.nav_counter = next_counter(tx, TX_STATUS);
    navecu_can_nav_status_pack(d, &st, sizeof d);
    send_protected(tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_STATUS], d);

    memset(&st, 0, sizeof st);
    st.status_page = tx->status_page < NAVECU_NAV_STATUS_PAGE_COUNTERS_FIRST
                         ? (uint8_t)NAVECU_NAV_STATUS_PAGE_COUNTERS_FIRST
                         : tx->status_page;
    fill_counter_page(&st, &a->keep.health);
    tx->status_page = (uint8_t)(st.status_page >= NAVECU_NAV_STATUS_PAGE_COUNTERS_LAST
                                    ? NAVECU_NAV_STATUS_PAGE_COUNTERS_FIRST
                                    : st.status_page + 1u);
    st.nav_counter = next_counter(tx, TX_STATUS);
    navecu_can_nav_status_pack(d, &st, sizeof d);
    send_protected(tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_STATUS], d);
}

void output_heartbeat(app_t *a, hal_t *hal)
{
    tx_state_t *tx = &a->keep.tx;
    const uint64_t now = hal_time_us(hal);
    if (!tx->hb_sent) {
        tx->boot_us = now;
    }
    const uint64_t up_s = now > tx->boot_us ? (now - tx->boot_us) / 1000000u : 0u;
    const uint32_t uptime_s = up_s > UINT32_MAX ? (uint32_t)UINT32_MAX : (uint32_t)up_s;
    if (tx->hb_sent && uptime_s == tx->hb_uptime_s) {
        return; /* one a second: at each whole second of uptime (a clock going back too) */
    }
    tx->hb_sent = 1u;
    tx->hb_uptime_s = uptime_s;
    struct navecu_can_nav_heartbeat_t m;
    (void)memset(&m, 0, sizeof m);
    m.mode = output_mode(a);
    m.imu_missing = (uint8_t)((!a->keep.imu.have_sample || imu_stale(a, hal)) ? 1u : 0u);
    m.gnss_missing = (uint8_t)(no_gnss(a) ? 1u : 0u);
    m.wheels_missing = (uint8_t)(a->keep.odo.valid != 0u ? 0u : 1u);
    m.uptime = uptime_s > NAVECU_NAV_HEARTBEAT_UPTIME_RAW_MAX ? NAVECU_NAV_HEARTBEAT_UPTIME_RAW_MAX
                                                                : uptime_s;
    m.nav_counter = next_counter(tx, TX_HEARTBEAT);
    m.nav_crc = 0u;
    uint8_t d[8];
    (void)navecu_can_nav_heartbeat_pack(d, &m, sizeof d);
    send_protected(tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_HEARTBEAT], d);
}

static void emit_calibration(app_t *a, hal_t *hal)
{
    const calib_t *c = &a->keep.cal;
    uint8_t d[8];
    struct navecu_can_nav_calibration_t m;
    memset(&m, 0, sizeof m);
    m.heading_correction = navecu_can_nav_calibration_heading_correction_encode(
        nav_clamp(c->dh_rad * NAV_DEG_PER_RAD, NAVECU_NAV_CALIBRATION_HEADING_CORRECTION_MIN,
               NAVECU_NAV_CALIBRATION_HEADING_CORRECTION_MAX));
    m.odo_scale_error = navecu_can_nav_calibration_odo_scale_error_encode(
        nav_clamp(c->mu, NAVECU_NAV_CALIBRATION_ODO_SCALE_ERROR_MIN,
               NAVECU_NAV_CALIBRATION_ODO_SCALE_ERROR_MAX));
    m.cal_valid = c->source != NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_NONE_CHOICE ? 1u : 0u;
    m.cal_stored = c->stored;
    m.cal_status = c->status;
    m.cal_source = c->source;
    m.cal_count = c->count;
    m.nav_counter = next_counter(&a->keep.tx, TX_CAL);
    navecu_can_nav_calibration_pack(d, &m, sizeof d);
    send_protected(&a->keep.tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_CALIBRATION], d);
}

/* NAV_Calibration pages 1 and 2: the automatic mounting estimate (a start with
 * imu_mount_source automatic only), in degrees */
static void emit_mount(app_t *a, hal_t *hal)
{
    const mount_est_result_t *r = app_mount_estimate(a);
    const nav_real_t k = NAV_DEG_PER_RAD;
    uint8_t d[8];
    struct navecu_can_nav_calibration_t m;
    (void)memset(&m, 0, sizeof m);
    m.cal_page = 1u;
    m.mount_roll = navecu_can_nav_calibration_mount_roll_encode(
        nav_clamp(r->rpy_rad[0] * k, NAVECU_NAV_CALIBRATION_MOUNT_ROLL_MIN,
                  NAVECU_NAV_CALIBRATION_MOUNT_ROLL_MAX));
    m.mount_pitch = navecu_can_nav_calibration_mount_pitch_encode(
        nav_clamp(r->rpy_rad[1] * k, NAVECU_NAV_CALIBRATION_MOUNT_PITCH_MIN,
                  NAVECU_NAV_CALIBRATION_MOUNT_PITCH_MAX));
    m.mount_yaw = navecu_can_nav_calibration_mount_yaw_encode(
        nav_clamp(r->rpy_rad[2] * k, NAVECU_NAV_CALIBRATION_MOUNT_YAW_MIN,
                  NAVECU_NAV_CALIBRATION_MOUNT_YAW_MAX));
    m.nav_counter = next_counter(&a->keep.tx, TX_CAL);
    (void)navecu_can_nav_calibration_pack(d, &m, sizeof d);
    send_protected(&a->keep.tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_CALIBRATION], d);
    (void)memset(&m, 0, sizeof m);
    m.cal_page = 2u;
    m.mount_sigma_roll_pitch = navecu_can_nav_calibration_mount_sigma_roll_pitch_encode(
        nav_clamp(r->sigma_rp_rad * k, NAVECU_NAV_CALIBRATION_MOUNT_SIGMA_ROLL_PITCH_MIN,
                  NAVECU_NAV_CALIBRATION_MOUNT_SIGMA_ROLL_PITCH_MAX));
    m.mount_sigma_yaw = navecu_can_nav_calibration_mount_sigma_yaw_encode(
        nav_clamp(r->sigma_yaw_rad * k, NAVECU_NAV_CALIBRATION_MOUNT_SIGMA_YAW_MIN,
                  NAVECU_NAV_CALIBRATION_MOUNT_SIGMA_YAW_MAX));
    m.mount_excitation = navecu_can_nav_calibration_mount_excitation_encode(
        nav_clamp(r->excite_m2ps3, NAVECU_NAV_CALIBRATION_MOUNT_EXCITATION_MIN,
                  NAVECU_NAV_CALIBRATION_MOUNT_EXCITATION_MAX));
    m.mount_state = a->keep.mount_state;
    m.nav_counter = next_counter(&a->keep.tx, TX_CAL);
    (void)navecu_can_nav_calibration_pack(d, &m, sizeof d);
    send_protected(&a->keep.tx, hal, a->cfg.can_ids[NAVECU_MSG_NAV_CALIBRATION], d);
}

/* an output at rate_hz goes every this many IMU samples: the IMU rate over it, rounded to
 * the nearest whole number (60 Hz at 100 Hz every 2nd sample, 50 Hz; truncated, it was
 * every sample, 100 Hz); at least 1. Out of line (noinline): inlined at its three calls it
 * took 8 bytes more. */
__attribute__((noinline)) static uint32_t every_samples(uint32_t imu_hz, uint32_t rate_hz)
{
    const uint32_t d = (imu_hz + rate_hz / 2u) / rate_hz;
    return d > 0u ? d : 1u;
}

void output_due(app_t *a, hal_t *hal)
{
    const uint64_t n = a->keep.n_samples;
    const uint32_t imu = a->cfg.imu_rate_hz;
    const uint32_t nav_div = every_samples(imu, a->cfg.nav_rate_hz);
    const uint32_t st_div = every_samples(imu, a->cfg.status_rate_hz);
    const uint8_t mode_now = output_mode(a);
    const uint8_t mode_changed = (mode_now != a->keep.tx.last_mode) ? 1u : 0u;
    if (mode_changed != 0u) { /* the new Mode before the first (or after the last) set in it */
        output_status(a, hal);
        emit_accuracy(a, hal);
    }
    if (a->run.mode == APP_MODE_NAVIGATING && n % nav_div == 0u) {
        emit_navigation(a, hal);
    }
    if (a->run.mode == APP_MODE_NAVIGATING && a->cfg.dyn_rate_hz != 0u &&
        n % every_samples(imu, a->cfg.dyn_rate_hz) == 0u) {
        emit_dynamics(a, hal);
    }
    if (n % st_div == 0u && mode_changed == 0u) {
        output_status(a, hal);
        emit_accuracy(a, hal);
    }
    if (n % imu == 0u) {
        emit_calibration(a, hal);
        if (a->keep.mount_state != (uint8_t)APP_MOUNT_FIXED) {
            emit_mount(a, hal);
        }
    }
}
