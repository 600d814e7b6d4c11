/* app.c - the navecu application; see app.h. */
#include "app.h"

#include <string.h>

#include "navecu_can.h"

enum { TX_HEIGHT = 0, TX_VEL, TX_ATT, TX_STATUS, TX_CAL };

#define LSB_PER_E7 GEO_LSB_PER_DEG_E7
#define PI_F NAV_C(3.14159265358979323846)
#define DEG_PER_RAD NAV_C(57.29577951308232)
#define GNSS_MIN_SATS 4u
#define GNSS_MIN_FIX 3u          /* 3D */
#define GNSS_COURSE_MIN_MPS NAV_C(5.0) /* GNSS course is a heading only when moving */
#define GNSS_STILL_MPS NAV_C(0.3)      /* below this GNSS speed the vehicle may be still */
#define IMU_STALE_US 500000u
#define FILTER_RESET_FLAG_S 10u /* NAV_Status flags a filter reset this long */
#define IMU_MAX_DELTA 4          /* IMU counter steps above this wait for confirmation */
#define COURSE_MISMATCH_RAD NAV_C(0.17453) /* 10 deg: GNSS course vs the filter's heading */
#define FILTER_REOPEN_LIMIT 3u  /* covariance reopens without a fix taken: diverged */
#define CMD_MAX_DELTA 3
#define GNSS_FIX_FRESH_S 2u      /* mode GnssIns while the last fix used is this recent */
#define STORE_MIN_S 10u          /* StoreCalibration at most this often (flash wear) */

app_config_t app_default_config(void)
{
    app_config_t cfg;
    cfg.imu_rate_hz = 100u;
    cfg.nav_rate_hz = 50u;
    cfg.status_rate_hz = 10u;
    cfg.level_s = 30u; /* docs/can.md: levelling error ~ LSB / level time */
    cfg.odo_axle = ODO_AXLE_REAR;
    /* A calibration point's position error e gives errors of about e / base in dH (rad)
     * and in mu: a 3 m point 2 km away, 0.09 deg and 0.15 % (docs/odometry.md). */
    cfg.cal_min_base_m = NAV_C(2000.0);
    /* the mid-grade IMU of seed 000 (tools/sim/sensors.py "mid-grade"): ARW 0.003 deg/sqrt(h),
     * turn-on bias 0.015 deg/h */
    cfg.gyro_arw_rad_rts = NAV_C(8.73e-7);
    cfg.gyro_bias_rps = NAV_C(7.27e-8);
    cfg.accel_bias_mps2 = NAV_C(1e-3);
    /* in-run instability 0.005 deg/h and 1e-4 m/s^2 over a 300 s correlation time as random
     * walks: sigma sqrt(2 / tau) */
    cfg.gyro_bias_rw_rps_rts = NAV_C(2.0e-9);
    cfg.accel_bias_rw_mps2_rts = NAV_C(8.2e-6);
    cfg.gnss_latency_s = NAV_C(0.1); /* u-blox-class receivers: about 0.1 s */
    cfg.gnss_corr_s = NAV_C(20.0);   /* standalone code receiver: atmosphere, orbits */
    cfg.gnss_lever_b_m[0] = cfg.gnss_lever_b_m[1] = cfg.gnss_lever_b_m[2] = NAV_C(0.0);
    cfg.odo_lever_b_m[0] = cfg.odo_lever_b_m[1] = cfg.odo_lever_b_m[2] = NAV_C(0.0);
    /* an automotive MEMS IMU's range: 300 deg/s, 8 g */
    cfg.gyro_range_rps = NAV_C(5.235988);
    cfg.accel_range_mps2 = NAV_C(78.4532);
    return cfg;
}

static void count(uint32_t *c)
{
    if (*c < UINT32_MAX) {
        (*c)++;
    }
}

/* the default profiling hook: nothing (app.h; a board may define its own) */
__attribute__((weak)) void app_trace(uint32_t point, uint32_t end)
{
    (void)point;
    (void)end;
}

/* count a rejection and remember when, for the REJECTED flag */
static void reject(app_t *a, uint32_t *c)
{
    count(c);
    a->last_reject_sample = a->n_samples;
    a->rejected_recently = 1u;
}

/* What reset_navigation keeps of app_t. Saved and restored field by field: a copy of the
 * whole app_t (4.4 KB) on the stack would be twice the stack budget (docs/target.md). */
typedef struct {
    app_config_t cfg;
    app_health_t health;
    e2e_counter_t rx_imu, rx_wheel, rx_cmd, rx_gnss_vel, rx_att;
    uint8_t tx_counter[6];
    uint8_t status_page;
    uint8_t have_sample;
    uint16_t flags_sticky;
    uint32_t frames_sent, send_errors;
    uint64_t n_samples, last_imu_t_us, last_rx_t_us, last_status_t_us, last_poll_us;
    uint64_t last_filter_reset_sample;
    uint8_t have_poll, had_filter_reset;
    calstore_t calstore;
    nav_real_t cal_dh_rad, cal_mu, cal_base_m;
    uint8_t cal_status, cal_source, cal_count, cal_stored;
    nav_real_t gz_sum, gz_sum_lo, gyro_bias_z_rps;
    uint32_t gz_n;
    odo_t odo;
} app_kept_t;

static void reset_navigation(app_t *a)
{
    /* Everything but configuration, health, E2E receive and transmit state, the time base
     * and the NVM fault: a reset restarts navigation, not the ECU. */
    app_kept_t k;
    k.cfg = a->cfg;
    k.health = a->health;
    k.rx_imu = a->rx_imu;
    k.rx_wheel = a->rx_wheel;
    k.rx_cmd = a->rx_cmd;
    k.rx_gnss_vel = a->rx_gnss_vel;
    k.rx_att = a->rx_att;
    memcpy(k.tx_counter, a->tx_counter, sizeof k.tx_counter);
    k.status_page = a->status_page;
    k.frames_sent = a->frames_sent;
    k.send_errors = a->send_errors;
    k.n_samples = a->n_samples;
    k.have_sample = a->have_sample;
    k.last_imu_t_us = a->last_imu_t_us;
    k.last_rx_t_us = a->last_rx_t_us;
    k.last_status_t_us = a->last_status_t_us;
    k.last_poll_us = a->last_poll_us;
    k.have_poll = a->have_poll;
    k.last_filter_reset_sample = a->last_filter_reset_sample;
    k.had_filter_reset = a->had_filter_reset;
    k.flags_sticky = a->flags_sticky;
    k.calstore = a->calstore;
    k.cal_dh_rad = a->cal_dh_rad;
    k.cal_mu = a->cal_mu;
    k.cal_status = a->cal_status;
    k.cal_source = a->cal_source;
    k.cal_count = a->cal_count;
    k.cal_stored = a->cal_stored;
    k.cal_base_m = a->cal_base_m;
    k.gz_sum = a->gz_sum;
    k.gz_sum_lo = a->gz_sum_lo;
    k.gz_n = a->gz_n;
    k.gyro_bias_z_rps = a->gyro_bias_z_rps;
    k.odo = a->odo;

    memset(a, 0, sizeof *a);
    a->cfg = k.cfg;
    a->health = k.health;
    a->rx_imu = k.rx_imu;
    a->rx_wheel = k.rx_wheel;
    a->rx_cmd = k.rx_cmd;
    a->rx_gnss_vel = k.rx_gnss_vel;
    a->rx_att = k.rx_att;
    memcpy(a->tx_counter, k.tx_counter, sizeof a->tx_counter);
    a->status_page = k.status_page;
    a->frames_sent = k.frames_sent;
    a->send_errors = k.send_errors;
    a->n_samples = k.n_samples; /* time runs on through a reset */
    a->have_sample = k.have_sample;
    a->last_imu_t_us = k.last_imu_t_us;
    a->last_rx_t_us = k.last_rx_t_us;
    a->last_status_t_us = k.last_status_t_us;
    a->last_poll_us = k.last_poll_us;
    a->have_poll = k.have_poll;
    a->last_filter_reset_sample = k.last_filter_reset_sample; /* the flag outlives the reset */
    a->had_filter_reset = k.had_filter_reset;
    a->flags_sticky = (uint16_t)(k.flags_sticky & (APP_FLAG_NVM_ERROR | APP_FLAG_IMU_FAULT));
    /* the calibration and the gyro bias belong to the car and the IMU, not to this run */
    a->calstore = k.calstore;
    a->cal_dh_rad = k.cal_dh_rad;
    a->cal_mu = k.cal_mu;
    a->cal_status = k.cal_status;
    a->cal_source = k.cal_source;
    a->cal_count = k.cal_count;
    a->cal_stored = k.cal_stored;
    a->cal_base_m = k.cal_base_m;
    a->gz_sum = k.gz_sum;
    a->gz_sum_lo = k.gz_sum_lo;
    a->gz_n = k.gz_n;
    a->gyro_bias_z_rps = k.gyro_bias_z_rps;
    a->odo = k.odo;
    a->mode = APP_MODE_WAIT_INIT;
}

int app_init(app_t *app, const app_config_t *cfg)
{
    if (cfg->imu_rate_hz < 10u || cfg->imu_rate_hz > 400u || cfg->nav_rate_hz == 0u ||
        cfg->status_rate_hz == 0u || cfg->nav_rate_hz > cfg->imu_rate_hz ||
        cfg->status_rate_hz > cfg->imu_rate_hz || cfg->level_s == 0u || cfg->level_s > 600u ||
        !(cfg->cal_min_base_m >= NAV_C(0.0)) || !(cfg->cal_min_base_m < NAV_C(1e6)) ||
        !(cfg->gyro_arw_rad_rts > NAV_C(0.0)) || !(cfg->gyro_arw_rad_rts < NAV_C(1.0)) ||
        !(cfg->gyro_bias_rps > NAV_C(0.0)) || !(cfg->gyro_bias_rps < NAV_C(1.0)) ||
        !(cfg->accel_bias_mps2 > NAV_C(0.0)) || !(cfg->accel_bias_mps2 < NAV_C(10.0)) ||
        !(cfg->gyro_bias_rw_rps_rts > NAV_C(0.0)) || !(cfg->gyro_bias_rw_rps_rts < NAV_C(1.0)) ||
        !(cfg->accel_bias_rw_mps2_rts > NAV_C(0.0)) || !(cfg->accel_bias_rw_mps2_rts < NAV_C(10.0)) ||
        !(cfg->gnss_latency_s >= NAV_C(0.0)) || !(cfg->gnss_latency_s <= NAV_C(0.5)) ||
        !(cfg->gnss_corr_s >= NAV_C(0.0)) || !(cfg->gnss_corr_s <= NAV_C(600.0)) ||
        !(nav_fabs(cfg->gnss_lever_b_m[0]) <= NAV_C(10.0)) ||
        !(nav_fabs(cfg->gnss_lever_b_m[1]) <= NAV_C(10.0)) ||
        !(nav_fabs(cfg->gnss_lever_b_m[2]) <= NAV_C(10.0)) ||
        !(nav_fabs(cfg->odo_lever_b_m[0]) <= NAV_C(10.0)) ||
        !(nav_fabs(cfg->odo_lever_b_m[1]) <= NAV_C(10.0)) ||
        !(nav_fabs(cfg->odo_lever_b_m[2]) <= NAV_C(10.0)) ||
        !(cfg->gyro_range_rps > NAV_C(0.0)) || !(cfg->gyro_range_rps <= NAV_C(100.0)) ||
        !(cfg->accel_range_mps2 > NAV_C(0.0)) || !(cfg->accel_range_mps2 <= NAV_C(2000.0))) {
        return NAV_EINVAL;
    }
    odo_config_t ocfg = odo_default_config();
    ocfg.axle = cfg->odo_axle;
    memset(app, 0, sizeof *app);
    if (odo_init(&app->odo, &ocfg) != NAV_OK) {
        return NAV_EINVAL;
    }
    app->cfg = *cfg;
    app->mode = APP_MODE_WAIT_INIT;
    app->calstore.slot = -1;
    return NAV_OK;
}

void app_boot(app_t *a, hal_t *hal)
{
    cal_record_t rec;
    const int rc = calstore_load(hal, &a->calstore, &rec);
    if (rc == CALSTORE_OK) {
        a->cal_dh_rad = (nav_real_t)rec.dh_rad;
        a->cal_mu = (nav_real_t)rec.odo_scale_err;
        a->cal_base_m = (nav_real_t)rec.base_m;
        a->cal_source = rec.source;
        a->cal_status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_FROM_NVM_CHOICE;
        a->cal_stored = 1u;
    } else if (rc == CALSTORE_CORRUPT) {
        a->cal_status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NVM_CORRUPT_CHOICE;
        a->flags_sticky |= APP_FLAG_NVM_ERROR;
    } else if (rc < 0) {
        a->flags_sticky |= APP_FLAG_NVM_ERROR;
    }
}

/* ---------------------------------------------------------------- output ---- */

static void send(app_t *a, hal_t *hal, uint32_t id, const uint8_t data[8])
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = 8u;
    memcpy(f.data, data, 8u);
    if (hal_can_send(hal, &f) == 0) {
        a->frames_sent++;
    } else {
        count(&a->send_errors);
    }
}

/* alive counter of an E2E output: return the current value and advance */
static uint8_t next_tx_counter(app_t *a, int which)
{
    const uint8_t c = a->tx_counter[which];
    a->tx_counter[which] = e2e_counter_next(c);
    return c;
}

/* fixed-point LSB (GEO_LSB_PER_*) to a coarser integer unit, rounding half away from 0 */
static int64_t lsb_div_round(int64_t x, int64_t div)
{
    return (x >= 0 ? x + div / 2 : x - div / 2) / div;
}

static nav_real_t clampr(nav_real_t x, nav_real_t lo, nav_real_t hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

static int navigator_finite(const sins_t *s);

static void emit_navigation(app_t *a, hal_t *hal)
{
    uint8_t d[8];
    const sins_t *s = &a->nav;
    if (!navigator_finite(s)) {
        count(&a->health.nonfinite_out); /* never on the bus; the supervision resets it */
        return;
    }

    struct navecu_can_nav_position_t p;
    p.latitude = (int32_t)lsb_div_round(s->pos.lat, LSB_PER_E7);
    p.longitude = (int32_t)lsb_div_round(s->pos.lon, LSB_PER_E7);
    navecu_can_nav_position_pack(d, &p, sizeof d);
    send(a, hal, NAVECU_CAN_NAV_POSITION_FRAME_ID, d);

    struct navecu_can_nav_height_t h;
    h.height = (int32_t)lsb_div_round(s->pos.h, 10 * GEO_LSB_PER_MM); /* 0.01 m */
    h.vert_accuracy = 255u; /* "unknown" without the filter */
    if (a->ekf_on) {
        const nav_real_t sv = nav_sqrt(a->ekf.P[EKF_DR + 2][EKF_DR + 2]) * NAV_C(10.0);
        h.vert_accuracy = sv < NAV_C(254.0) ? (uint8_t)(sv + NAV_C(0.5)) : 254u;
    }
    /* time of validity on the IMU time base, so that a recorder need not trust arrival
     * times: a vcan recording and a --can-log run carry the same value */
    h.time_of_validity = (uint16_t)((a->n_samples * 1000u / a->cfg.imu_rate_hz) & 0xFFFFu);
    h.nav_counter = next_tx_counter(a, TX_HEIGHT);
    h.nav_crc = 0u;
    navecu_can_nav_height_pack(d, &h, sizeof d);
    e2e_protect(NAVECU_CAN_NAV_HEIGHT_FRAME_ID, d);
    send(a, hal, NAVECU_CAN_NAV_HEIGHT_FRAME_ID, d);

    struct navecu_can_nav_velocity_t v;
    const nav_real_t vmax = NAV_C(327.67);
    v.vel_east = navecu_can_nav_velocity_vel_east_encode(clampr(s->v_n_mps[0], -vmax, vmax));
    v.vel_north = navecu_can_nav_velocity_vel_north_encode(clampr(s->v_n_mps[1], -vmax, vmax));
    v.vel_up = navecu_can_nav_velocity_vel_up_encode(clampr(s->v_n_mps[2], -vmax, vmax));
    v.nav_counter = next_tx_counter(a, TX_VEL);
    v.nav_crc = 0u;
    navecu_can_nav_velocity_pack(d, &v, sizeof d);
    e2e_protect(NAVECU_CAN_NAV_VELOCITY_FRAME_ID, d);
    send(a, hal, NAVECU_CAN_NAV_VELOCITY_FRAME_ID, d);

    nav_real_t roll, pitch, heading;
    sins_euler(s, &roll, &pitch, &heading);
    /* the car's heading and pitch, not the IMU's: less the mounting (the filter's
     * estimate) or, without the filter, the one-point calibration's dH */
    if (a->ekf_on) {
        heading -= a->ekf.mount_yaw_rad;
        pitch -= a->ekf.mount_pitch_rad;
    } else {
        heading -= a->dr.dh_rad;
    }
    if (heading < NAV_C(0.0)) {
        heading += NAV_C(2.0) * PI_F;
    } else if (heading >= NAV_C(2.0) * PI_F) {
        heading -= NAV_C(2.0) * PI_F;
    }
    /* the car's pitch within the DBC's +-90 deg: the IMU at 89.7 deg less a mounting pitch
     * of -1 deg would otherwise be sent as 90.7 (found by tests/fuzz/fuzz_options.c) */
    pitch = clampr(pitch, -NAV_C(0.5) * PI_F, NAV_C(0.5) * PI_F);
    struct navecu_can_nav_attitude_t at;
    at.roll = navecu_can_nav_attitude_roll_encode(roll * DEG_PER_RAD);
    at.pitch = navecu_can_nav_attitude_pitch_encode(pitch * DEG_PER_RAD);
    at.heading = navecu_can_nav_attitude_heading_encode(heading * DEG_PER_RAD);
    if (at.heading >= 36000u) {
        at.heading = 0u; /* 359.996 deg rounds to 360.00: that is north */
    }
    at.nav_counter = next_tx_counter(a, TX_ATT);
    at.nav_crc = 0u;
    navecu_can_nav_attitude_pack(d, &at, sizeof d);
    e2e_protect(NAVECU_CAN_NAV_ATTITUDE_FRAME_ID, d);
    send(a, hal, NAVECU_CAN_NAV_ATTITUDE_FRAME_ID, d);
}

static uint16_t sat16(uint32_t x)
{
    return x > UINT16_MAX ? (uint16_t)UINT16_MAX : (uint16_t)x;
}

static uint8_t sat8(uint32_t x)
{
    return x > UINT8_MAX ? (uint8_t)UINT8_MAX : (uint8_t)x;
}

static uint16_t health_flags(const app_t *a, const hal_t *hal)
{
    uint16_t fl = a->flags_sticky;
    const uint64_t now = hal_time_us(hal);
    if (a->have_sample && now > a->last_imu_t_us && now - a->last_imu_t_us > IMU_STALE_US) {
        fl |= APP_FLAG_IMU_STALE;
    }
    if (a->had_gap && a->n_samples - a->last_gap_sample <= a->cfg.imu_rate_hz) {
        fl |= APP_FLAG_IMU_GAP;
    }
    if (!a->have_gnss || a->n_samples - a->last_gnss_sample > 2u * a->cfg.imu_rate_hz) {
        fl |= APP_FLAG_NO_GNSS;
    }
    if (a->rejected_recently && a->n_samples - a->last_reject_sample <= a->cfg.imu_rate_hz) {
        fl |= APP_FLAG_REJECTED;
    }
    if (a->mode != APP_MODE_NAVIGATING && a->init_pos_valid && !a->init_heading_valid) {
        fl |= APP_FLAG_NO_HEADING;
    }
    if (a->had_filter_reset &&
        a->n_samples - a->last_filter_reset_sample <= FILTER_RESET_FLAG_S * a->cfg.imu_rate_hz) {
        fl |= APP_FLAG_FILTER_RESET;
    }
    if (a->had_stuck &&
        a->n_samples - a->last_stuck_sample <= FILTER_RESET_FLAG_S * a->cfg.imu_rate_hz) {
        fl |= APP_FLAG_IMU_SUSPECT;
    }
    if (a->had_sat && a->n_samples - a->last_sat_sample <= a->cfg.imu_rate_hz) {
        fl |= APP_FLAG_IMU_SATURATED;
    }
    if (a->had_odo_reject && a->n_samples - a->last_odo_reject_sample <= a->cfg.imu_rate_hz) {
        fl |= APP_FLAG_ODO_REJECTED;
    }
    if (a->reacquire) {
        fl |= APP_FLAG_REACQUIRE;
    }
    return fl;
}

/* NAV_Status Mode: the solution being output */
static uint32_t output_mode(const app_t *a)
{
    if (a->mode != APP_MODE_NAVIGATING) {
        return (uint32_t)a->mode;
    }
    if (a->ekf_on) {
        if (a->have_fix &&
            a->n_samples - a->last_fix_sample <= GNSS_FIX_FRESH_S * a->cfg.imu_rate_hz) {
            return NAVECU_CAN_NAV_STATUS_MODE_GNSS_INS_CHOICE;
        }
        return a->odo.valid ? NAVECU_CAN_NAV_STATUS_MODE_DEAD_RECKONING_CHOICE
                            : NAVECU_CAN_NAV_STATUS_MODE_INERTIAL_CHOICE;
    }
    return a->output_dr ? NAVECU_CAN_NAV_STATUS_MODE_DEAD_RECKONING_CHOICE
                        : NAVECU_CAN_NAV_STATUS_MODE_INERTIAL_CHOICE;
}

static void emit_status(app_t *a, hal_t *hal)
{
    uint8_t d[8];
    a->health.log_line_bad = hal_can_rx_malformed(hal);
    a->last_status_t_us = hal_time_us(hal);
    const app_health_t *h = &a->health;
    struct navecu_can_nav_status_t st;
    memset(&st, 0, sizeof st);
    st.status_page = 0u;
    st.mode = (uint8_t)output_mode(a);
    st.health_flags = health_flags(a, hal);
    st.horiz_accuracy = UINT16_MAX; /* "unknown" without the filter */
    if (a->ekf_on && a->mode == APP_MODE_NAVIGATING) {
        const nav_real_t sh = ekf_sigma_h_m(&a->ekf) * NAV_C(100.0);
        st.horiz_accuracy = sh < NAV_C(65534.0) ? (uint16_t)(sh + NAV_C(0.5)) : 65534u;
    }
    st.nav_counter = next_tx_counter(a, TX_STATUS);
    navecu_can_nav_status_pack(d, &st, sizeof d);
    e2e_protect(NAVECU_CAN_NAV_STATUS_FRAME_ID, d);
    send(a, hal, NAVECU_CAN_NAV_STATUS_FRAME_ID, d);

    /* one page of counters per status cycle, in rotation */
    memset(&st, 0, sizeof st);
    st.status_page = a->status_page == 0u ? 1u : a->status_page;
    if (st.status_page == 1u) {
        st.cnt_unknown_id = sat16(h->unknown_id);
        st.cnt_bad_dlc = sat16(h->bad_dlc);
        st.cnt_bad_crc = sat8(h->bad_crc);
    } else if (st.status_page == 2u) {
        st.cnt_bad_counter = sat16(h->bad_counter);
        st.cnt_imu_pair_broken = sat16(h->imu_pair_broken);
        st.cnt_imu_lost = sat8(h->imu_lost);
    } else if (st.status_page == 3u) {
        st.cnt_bad_value = sat16(h->bad_value);
        st.cnt_gnss_rejected = sat16(h->gnss_rejected);
        st.cnt_log_line_bad = sat8(h->log_line_bad);
    } else if (st.status_page == 4u) {
        st.cnt_cmd_rejected = sat16(h->cmd_rejected);
        st.cnt_core_rejected = sat16(h->nav_rejected);
        st.cnt_time_jumps = sat8(h->time_jumps);
    } else if (st.status_page == 5u) {
        st.cnt_filter_resets = sat16(h->filter_resets);
        st.cnt_tasks_late = sat16(h->tasks_late);
        st.cnt_non_finite = sat8(h->nonfinite_out);
    } else {
        st.cnt_imu_saturated = sat16(h->imu_saturated);
        st.cnt_odo_rejected = sat16(h->odo_rejected);
        st.cnt_imu_stuck = sat8(h->imu_stuck);
    }
    a->status_page = (uint8_t)(st.status_page >= 6u ? 1u : st.status_page + 1u);
    st.nav_counter = next_tx_counter(a, TX_STATUS);
    navecu_can_nav_status_pack(d, &st, sizeof d);
    e2e_protect(NAVECU_CAN_NAV_STATUS_FRAME_ID, d);
    send(a, hal, NAVECU_CAN_NAV_STATUS_FRAME_ID, d);
}

static void emit_calibration(app_t *a, hal_t *hal)
{
    uint8_t d[8];
    struct navecu_can_nav_calibration_t c;
    memset(&c, 0, sizeof c);
    c.heading_correction = navecu_can_nav_calibration_heading_correction_encode(
        clampr(a->cal_dh_rad * DEG_PER_RAD, NAV_C(-32.7), NAV_C(32.7)));
    c.odo_scale_error = navecu_can_nav_calibration_odo_scale_error_encode(
        clampr(a->cal_mu, NAV_C(-0.327), NAV_C(0.327)));
    c.cal_valid = a->cal_source != NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_NONE_CHOICE ? 1u : 0u;
    c.cal_stored = a->cal_stored;
    c.cal_status = a->cal_status;
    c.cal_source = a->cal_source;
    c.cal_count = a->cal_count;
    c.nav_counter = next_tx_counter(a, TX_CAL);
    navecu_can_nav_calibration_pack(d, &c, sizeof d);
    e2e_protect(NAVECU_CAN_NAV_CALIBRATION_FRAME_ID, d);
    send(a, hal, NAVECU_CAN_NAV_CALIBRATION_FRAME_ID, d);
}

static void emit_due(app_t *a, hal_t *hal)
{
    const uint64_t n = a->n_samples;
    const uint32_t imu = a->cfg.imu_rate_hz;
    const uint32_t nav_div = a->cfg.nav_rate_hz >= imu ? 1u : imu / a->cfg.nav_rate_hz;
    const uint32_t st_div = a->cfg.status_rate_hz >= imu ? 1u : imu / a->cfg.status_rate_hz;
    if (a->mode == APP_MODE_NAVIGATING && n % nav_div == 0u) {
        emit_navigation(a, hal);
    }
    if (n % st_div == 0u) {
        emit_status(a, hal);
    }
    if (n % imu == 0u) {
        emit_calibration(a, hal);
    }
}

/* ------------------------------------------------------- initialization ---- */

static void restart_levelling(app_t *a)
{
    a->level_n = 0u;
    for (int i = 0; i < 3; i++) {
        a->level_wsum[i] = NAV_C(0.0);
        a->level_wsum_lo[i] = NAV_C(0.0);
    }
}

static void start_levelling_if_ready(app_t *a)
{
    if (a->mode == APP_MODE_WAIT_INIT && a->init_pos_valid && a->init_heading_valid) {
        a->mode = APP_MODE_LEVELLING;
        restart_levelling(a);
    }
}

/* Levelling: the mean specific force of a vehicle at rest is C_nb (0, 0, g), whose body
 * components are g (-cos(p) sin(r), sin(p), cos(p) cos(r)) (docs/frames.md). Only the
 * direction of the weighted sum matters. */
static void start_navigation_at(app_t *a, nav_real_t roll, nav_real_t pitch);

static void start_navigation(app_t *a)
{
    const nav_real_t fx = a->level_wsum[0];
    const nav_real_t fy = a->level_wsum[1];
    const nav_real_t fz = a->level_wsum[2];
    start_navigation_at(a, nav_atan2(-fx, fz), nav_atan2(fy, nav_sqrt(fx * fx + fz * fz)));
}

/* Navigate from the initial position and heading with this roll and pitch (rad). */
static void start_navigation_at(app_t *a, nav_real_t roll, nav_real_t pitch)
{
    nav_real_t q[4];
    quat_from_euler(roll, pitch, a->init_heading_rad, q);
    const geo_pos_t pos = {(int64_t)a->init_lat_e7 * LSB_PER_E7,
                           (int64_t)a->init_lon_e7 * LSB_PER_E7,
                           (int64_t)a->init_h_cm * 10 * GEO_LSB_PER_MM};
    const nav_real_t v0[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    const sins_config_t scfg = sins_default_config();
    if (sins_init(&a->nav, &scfg, &pos, v0, q) != NAV_OK) {
        reject(a, &a->health.bad_value);
        a->mode = APP_MODE_FAULT;
        return;
    }
    /* Hold the vertical channel at the initial height until GNSS heights arrive. */
    sins_set_height_ref(&a->nav, (nav_real_t)a->init_h_cm * NAV_C(0.01));
    if (dr_init(&a->dr, &pos, a->cal_dh_rad, a->cal_mu) != NAV_OK) {
        reject(a, &a->health.bad_value);
        a->mode = APP_MODE_FAULT;
        return;
    }
    a->output_dr = 0u;
    a->holding = 0u;
    a->mode = APP_MODE_NAVIGATING;
}

/* ------------------------------------------------- odometer and standstill ---- */

/* Standstill (odo.h: every wheel at zero, the body not turning): the car neither moves nor
 * turns, whatever the sensors' errors say (seed 000: stillness keeps the SINS from
 * drifting). Velocity is set to zero, the heading is held where it was when the car
 * stopped, and the z gyro's reading minus the Earth's rate is a measurement of its bias.
 * The bias estimate is the posterior mean of a constant with prior N(0, sigma_b^2) from
 * samples of variance ARW^2 / dt:  b = sum(r_k) / (n + n0),  n0 = ARW^2 / (dt sigma_b^2);
 * it is subtracted from every later sample. */
static void standstill_step(app_t *a, const nav_real_t dtheta_raw_b[3], nav_real_t dt)
{
    static const nav_real_t zero_v[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    nav_real_t roll, pitch, heading;
    sins_euler(&a->nav, &roll, &pitch, &heading);
    if (!a->holding) {
        a->holding = 1u;
        a->hold_heading_rad = heading;
    }
    nav_real_t dh = a->hold_heading_rad - heading;
    if (dh > PI_F) {
        dh -= NAV_C(2.0) * PI_F;
    } else if (dh < -PI_F) {
        dh += NAV_C(2.0) * PI_F;
    }
    (void)sins_turn_heading(&a->nav, dh);
    (void)sins_set_velocity(&a->nav, zero_v);
    /* Earth rate seen by the body z axis: C_bn^T w_ie_n, third component */
    mat3_t C_bn;
    quat_to_dcm(a->nav.q_bn, &C_bn);
    earth_t e;
    earth_eval(geo_lat_rad(&a->nav.pos), geo_h_m(&a->nav.pos), &e);
    nav_real_t w_ie_b[3];
    mat3t_mul_vec(&C_bn, e.w_ie_n_rps, w_ie_b);
    nav_acc_add(&a->gz_sum, &a->gz_sum_lo, dtheta_raw_b[2] / dt - w_ie_b[2]);
    if (a->gz_n < UINT32_MAX) {
        a->gz_n++;
    }
    const nav_real_t arw = a->cfg.gyro_arw_rad_rts;
    const nav_real_t sb = a->cfg.gyro_bias_rps;
    const nav_real_t n0 = arw * arw / (dt * sb * sb);
    a->gyro_bias_z_rps = (a->gz_sum + a->gz_sum_lo) / ((nav_real_t)a->gz_n + n0);
}

/* Moving with a valid odometer: dead reckoning (seed 000 eqs 1-4, 11-12) is the output;
 * the SINS takes the odometer's velocity along the compensated heading (seed 000: the
 * odometer velocity damps the SINS velocity errors) and the dead-reckoned position, so
 * that it stays a good attitude and heading reference whatever the drive's length. */
static void odometer_step(app_t *a, nav_real_t dt)
{
    nav_real_t roll, pitch, heading;
    sins_euler(&a->nav, &roll, &pitch, &heading);
    const nav_real_t ds = a->odo.speed_mps * dt;
    if (dr_step(&a->dr, ds, heading, pitch) != NAV_OK) {
        reject(a, &a->health.nav_rejected);
        return;
    }
    const nav_real_t v = a->odo.speed_mps / (NAV_C(1.0) + a->dr.mu) * nav_cos(pitch);
    const nav_real_t hc = heading - a->dr.dh_rad;
    const nav_real_t v_n[3] = {v * nav_sin(hc), v * nav_cos(hc), a->nav.v_n_mps[2]};
    (void)sins_set_velocity(&a->nav, v_n);
    a->nav.pos = a->dr.pos;
    sins_set_height_ref(&a->nav, geo_h_m(&a->dr.pos));
}

/* ------------------------------------------------------------------ IMU ---- */

/* ------------------------------------------------------- Kalman filter ---- */

#define EKF_PRED_HZ 10u          /* covariance propagation and odometer updates */
#define ZUPT_SIGMA_MPS NAV_C(0.01)
#define ODO_SIGMA_MPS NAV_C(0.05) /* quantisation, latency and tyre slip, plus 1 % of speed */
#define NHC_SIGMA_MPS NAV_C(0.1)  /* side slip in turns, suspension motion */
#define ODO_MIN_SPEED_MPS NAV_C(0.5)
#define GATE_SIGMA NAV_C(5.0)
/* GNSS innovation gate, in sigmas of the innovation (both position and velocity): 3,
 * for receivers' multipath outliers that are far from Gaussian. Refusals in a row for
 * longer than GNSS_REOPEN_S reopen the filter's position and velocity: measured on the
 * Kingston drive (docs/kalman.md), a 5-sigma gate lets multipath in and a filter that
 * trusts itself after one bad fix refuses the good ones for half a minute. */
#ifndef GNSS_GATE_SIGMA
#define GNSS_GATE_SIGMA NAV_C(3.0)
#endif
#ifndef GNSS_REOPEN_S
#define GNSS_REOPEN_S 3u
#endif
#ifndef GNSS_SIGMA_FLOOR_M
#define GNSS_SIGMA_FLOOR_M NAV_C(1.0)
#endif

static void store_calibration(app_t *a, hal_t *hal);

/* z gyro rate (rad/s) the Earth alone would give the body now */
static nav_real_t earth_rate_body_z(const sins_t *s)
{
    mat3_t C_bn;
    quat_to_dcm(s->q_bn, &C_bn);
    earth_t e;
    earth_eval(geo_lat_rad(&s->pos), geo_h_m(&s->pos), &e);
    nav_real_t w_ie_b[3];
    mat3t_mul_vec(&C_bn, e.w_ie_n_rps, w_ie_b);
    return w_ie_b[2];
}

static void start_filter(app_t *a, nav_real_t hacc_m)
{
    ekf_config_t c = ekf_default_config();
    c.arw_rad_rts = a->cfg.gyro_arw_rad_rts;
    c.bg_rps = a->cfg.gyro_bias_rps;
    c.ba_mps2 = a->cfg.accel_bias_mps2;
    c.bg_rw_rps_rts = a->cfg.gyro_bias_rw_rps_rts;
    c.ba_rw_mps2_rts = a->cfg.accel_bias_rw_mps2_rts;
    c.pos_m = hacc_m > NAV_C(1.0) ? hacc_m : NAV_C(1.0);
    if (ekf_init(&a->ekf, &c, NAV_C(0.0)) != NAV_OK) {
        reject(a, &a->health.nav_rejected);
        return;
    }
    /* what standstill and calibration already know */
    a->ekf.bg_rps[2] = a->gyro_bias_z_rps;
    a->ekf.k = a->cal_mu;
    if (a->cal_source == NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_FILTER_CHOICE) {
        a->ekf.mount_yaw_rad = a->cal_dh_rad;
    }
    a->pred_n = 0u;
    a->pred_t_s = NAV_C(0.0);
    a->f_sum_n[0] = a->f_sum_n[1] = a->f_sum_n[2] = NAV_C(0.0);
    a->w_sum_rad[0] = a->w_sum_rad[1] = a->w_sum_rad[2] = NAV_C(0.0);
    a->odo_frames_used = a->odo.n_frames;
    a->ekf_start_sample = a->n_samples;
    a->ekf_nonfinite_seen = a->ekf.n_nonfinite; /* the supervision's reference: a new filter */
    a->ekf_negative_seen = a->ekf.n_negative_var;
    /* the filter owns the height now: the core's damping toward a held reference is a
     * force its model does not have */
    a->nav.h_ref_valid = 0u;
    a->ekf_on = 1u;
}

/* The filter's odometer scale and mounting yaw, once converged, are the calibration in
 * use (CalSource Filter); the dead reckoning uses them too. They are stored only at a
 * standstill (a flash sector erase stalls the ECU's CPU for hundreds of ms: docs/porting.md),
 * only when they differ from the stored record by more than the filter's accuracy, and at
 * most every FILTER_SAVE_MIN_S (flash wear: two sectors of 10 k erase cycles). */
#define FILTER_SAVE_MIN_S 600u
static void filter_calibration(app_t *a, hal_t *hal)
{
    const nav_real_t sk = nav_sqrt(a->ekf.P[EKF_K][EKF_K]);
    const nav_real_t sy = nav_sqrt(a->ekf.P[EKF_MY][EKF_MY]);
    if (sk > NAV_C(0.0005) || sy > NAV_C(0.0005) || /* 0.05 %, 0.03 deg */
        !(nav_fabs(a->ekf.k) <= NAV_C(0.2)) || !(nav_fabs(a->ekf.mount_yaw_rad) <= NAV_C(0.5))) {
        return; /* not converged, or outside what the store accepts */
    }
    a->cal_mu = a->ekf.k;
    a->cal_dh_rad = a->ekf.mount_yaw_rad;
    a->cal_source = NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_FILTER_CHOICE;
    a->dr.mu = a->ekf.k;
    a->dr.dh_rad = a->ekf.mount_yaw_rad;
    const int changed = !a->ekf_cal_stored ||
                        nav_fabs(a->cal_mu - a->stored_mu) > NAV_C(2.0) * sk ||
                        nav_fabs(a->cal_dh_rad - a->stored_dh_rad) > NAV_C(2.0) * sy;
    if (changed) {
        a->cal_stored = 0u;
    }
    const uint64_t min_gap = (uint64_t)FILTER_SAVE_MIN_S * a->cfg.imu_rate_hz;
    if (changed && a->odo.standing &&
        (!a->ekf_cal_stored || a->n_samples - a->last_save_sample >= min_gap)) {
        a->ekf_cal_stored = 1u;
        a->cal_base_m = NAV_C(0.0);
        store_calibration(a, hal);
    }
}

static void navigate_filtered(app_t *a, imu_inc_t *inc);

/* IMU samples per velocity-history entry: entries at most 10 ms apart whatever the IMU
 * rate, so APP_VHIST entries cover 0.64 s (the latency allowed plus lateness) */
static uint32_t vhist_div(const app_t *a)
{
    return (a->cfg.imu_rate_hz + 99u) / 100u;
}

/* velocity history for the GNSS time of validity */
static void record_velocity(app_t *a)
{
    if (a->n_samples % vhist_div(a) != 0u) {
        return;
    }
    for (int i = 0; i < 3; i++) {
        a->vhist[a->vhist_n % APP_VHIST][i] = a->nav.v_n_mps[i];
    }
    a->vhist_n++;
}

static void process_sample(app_t *a, hal_t *hal, const int32_t w_raw[3], const int32_t v_raw[3])
{
    a->n_samples++;
    if (a->mode == APP_MODE_LEVELLING) {
        /* The specific force is the least-squares slope of the summed increments over the
         * window, i.e. a mean with parabolic weights w_k = k (N - k). A plain mean is off
         * by up to one LSB / window length, because the sender's quantisation carry is
         * unknown at both ends of the window; the parabolic weights give the ends almost
         * no weight, which cuts that error by about sqrt(N) (docs/can.md, IMU). */
        const uint32_t n_total = (uint32_t)a->cfg.level_s * a->cfg.imu_rate_hz;
        a->level_n++;
        const nav_real_t k = (nav_real_t)a->level_n;
        const nav_real_t w = k * ((nav_real_t)n_total - k);
        for (int i = 0; i < 3; i++) {
            nav_acc_add(&a->level_wsum[i], &a->level_wsum_lo[i], w * (nav_real_t)v_raw[i]);
        }
        if (a->level_n >= n_total) {
            start_navigation(a);
        }
    } else if (a->mode == APP_MODE_NAVIGATING) {
        imu_inc_t inc;
        inc.dtheta_b_rad[0] = navecu_can_imu_rate_angle_inc_x_decode(w_raw[0]);
        inc.dtheta_b_rad[1] = navecu_can_imu_rate_angle_inc_y_decode(w_raw[1]);
        inc.dtheta_b_rad[2] = navecu_can_imu_rate_angle_inc_z_decode(w_raw[2]);
        inc.dv_b_mps[0] = navecu_can_imu_accel_vel_inc_x_decode(v_raw[0]);
        inc.dv_b_mps[1] = navecu_can_imu_accel_vel_inc_y_decode(v_raw[1]);
        inc.dv_b_mps[2] = navecu_can_imu_accel_vel_inc_z_decode(v_raw[2]);
        inc.dt_s = NAV_C(1.0) / (nav_real_t)a->cfg.imu_rate_hz;
        if (a->ekf_on) {
            navigate_filtered(a, &inc);
            emit_due(a, hal);
            return;
        }
        const nav_real_t raw_z = inc.dtheta_b_rad[2];
        inc.dtheta_b_rad[2] -= a->gyro_bias_z_rps * inc.dt_s;
        a->yaw_rate_rps = inc.dtheta_b_rad[2] / inc.dt_s;
        if (sins_step(&a->nav, &inc) != NAV_OK) {
            reject(a, &a->health.nav_rejected);
        }
        odo_tick(&a->odo, inc.dt_s, a->yaw_rate_rps);
        if (a->odo.standing) {
            const nav_real_t raw[3] = {inc.dtheta_b_rad[0], inc.dtheta_b_rad[1], raw_z};
            standstill_step(a, raw, inc.dt_s);
            a->output_dr = 1u;
        } else {
            a->holding = 0u;
            if (a->odo.valid) {
                odometer_step(a, inc.dt_s);
                a->output_dr = 1u;
            } else {
                /* no odometer: the free SINS carries on, dead reckoning follows it */
                dr_set_position(&a->dr, &a->nav.pos);
                a->output_dr = 0u;
            }
        }
        record_velocity(a);
    }
    emit_due(a, hal);
}

/* One IMU sample with the filter running: compensated increments, the strapdown step,
 * the dead reckoning alongside, and at EKF_PRED_HZ the prediction, the odometer or
 * standstill updates and the feedback. */
static void begin_reacquire(app_t *a);

/* the wheel speeds disagree with the filter beyond its gate (lock, spin, slip) */
static void odo_refused(app_t *a)
{
    reject(a, &a->health.odo_rejected);
    a->had_odo_reject = 1u;
    a->last_odo_reject_sample = a->n_samples;
}

/* ---- filter supervision (docs/reliability.md) ----
 * The filter has diverged when its state, its covariance or the navigator it corrects is
 * no longer finite, when a variance went negative (ekf_health repairs the covariance and
 * counts it), or when GNSS fixes stay beyond the innovation gate through
 * FILTER_REOPEN_LIMIT covariance reopens in a row while the odometer is refused too or the
 * GNSS course disagrees with the filter's heading (every source then says the filter is
 * wrong; GNSS refused alone is a receiver fault, e.g. a frozen fix, which the gate is
 * there to keep out). A diverged filter is stopped. With GNSS, navigation re-acquires
 * from the next GNSS epoch (position, velocity, and the course as heading, as after a long
 * IMU gap) and the filter restarts at the epoch after; without GNSS it goes on as the land
 * navigation system (SINS with the odometer); if the navigator itself is not finite,
 * navigation restarts from the initial state. Counted in health.filter_resets, flagged
 * for FILTER_RESET_FLAG_S. */
/* 1 when the angle x (rad), wrapped to [-pi, pi], exceeds tol in magnitude; also for a
 * non-finite or huge x (beyond 64 rad, where no angle of the navigator should be). No
 * loop: a wrap by repeated subtraction never ends on an infinite or very large float. */
static int angle_exceeds(nav_real_t x, nav_real_t tol)
{
    if (!(nav_fabs(x) <= NAV_C(64.0))) {
        return 1;
    }
    const nav_real_t turns = x / (NAV_C(2.0) * PI_F);
    const int32_t n = (int32_t)(turns >= NAV_C(0.0) ? turns + NAV_C(0.5) : turns - NAV_C(0.5));
    return nav_fabs(x - (nav_real_t)n * NAV_C(2.0) * PI_F) > tol;
}

static int all_finite(const nav_real_t *v, int n)
{
    for (int i = 0; i < n; i++) {
        if (!nav_isfinite(v[i])) {
            return 0;
        }
    }
    return 1;
}

static int navigator_finite(const sins_t *s)
{
    return all_finite(s->v_n_mps, 3) && all_finite(s->q_bn, 4);
}

static int filter_diverged(app_t *a)
{
    const ekf_t *k = &a->ekf;
    /* GNSS refused through reopens is a GNSS fault (a frozen or jumping receiver) as long
     * as the rest agrees with the filter; it is the filter that is wrong when the odometer
     * is refused too, or when the GNSS course, driving, differs from the filter's heading
     * by more than COURSE_MISMATCH_RAD (a heading lost to a stuck or saturated gyro, which
     * the odometer's speed cannot see) */
    nav_real_t roll, pitch, heading;
    sins_euler(&a->nav, &roll, &pitch, &heading);
    const nav_real_t course_err = a->gnss_course_rad - (heading - k->mount_yaw_rad);
    const int odo_disagrees =
        a->had_odo_reject &&
        a->n_samples - a->last_odo_reject_sample <= (uint64_t)GNSS_REOPEN_S * a->cfg.imu_rate_hz;
    /* only with GNSS at hand: in a tunnel the last course and the count of reopens are
     * old news, and a reset there would leave nothing to re-acquire from */
    const int gnss_fresh = a->have_gnss && a->n_samples - a->last_gnss_sample <= a->cfg.imu_rate_hz;
    const int course_disagrees = gnss_fresh && a->gnss_speed_mps >= GNSS_COURSE_MIN_MPS &&
                                 angle_exceeds(course_err, COURSE_MISMATCH_RAD);
    const int aiding_disagrees = gnss_fresh && a->gnss_reopen_run >= FILTER_REOPEN_LIMIT &&
                                 (odo_disagrees || course_disagrees);
    int diverged = k->n_nonfinite != a->ekf_nonfinite_seen ||
                   k->n_negative_var != a->ekf_negative_seen || aiding_disagrees;
    a->ekf_nonfinite_seen = k->n_nonfinite;
    a->ekf_negative_seen = k->n_negative_var;
    const nav_real_t scalars[4] = {k->k, k->mount_yaw_rad, k->mount_pitch_rad, NAV_C(0.0)};
    if (!all_finite(k->x, EKF_N) || !all_finite(k->bg_rps, 3) || !all_finite(k->ba_mps2, 3) ||
        !all_finite(scalars, 4) || !navigator_finite(&a->nav)) {
        diverged = 1;
    }
    for (int i = 0; i < EKF_N && !diverged; i++) {
        if (!(k->P[i][i] >= NAV_C(0.0)) || !nav_isfinite(k->P[i][i])) {
            diverged = 1;
        }
    }
    return diverged;
}

static void filter_reset(app_t *a)
{
    count(&a->health.filter_resets);
    a->had_filter_reset = 1u;
    a->last_filter_reset_sample = a->n_samples;
    a->ekf_on = 0u;
    a->gnss_gated_run = 0u;
    a->gnss_reopen_run = 0u;
    a->have_fix = 0u;
    if (!navigator_finite(&a->nav)) {
        reset_navigation(a);
        return;
    }
    if (a->have_gnss) {
        /* the navigator the filter corrected is suspect too: GNSS gives position,
         * velocity and heading again at its next epoch, as after a long IMU gap */
        begin_reacquire(a);
        return;
    }
    /* without the filter the height needs the core's damping again (start_filter took it) */
    sins_set_height_ref(&a->nav, geo_h_m(&a->nav.pos));
}

/* After each filter step: reset it if it diverged. Returns 1 if it was reset. */
static int supervise_filter(app_t *a)
{
    if (!a->ekf_on || !filter_diverged(a)) {
        return 0;
    }
    filter_reset(a);
    return 1;
}

static void navigate_filtered(app_t *a, imu_inc_t *inc)
{
    const nav_real_t dt = inc->dt_s;
    for (int i = 0; i < 3; i++) {
        inc->dtheta_b_rad[i] -= a->ekf.bg_rps[i] * dt;
        inc->dv_b_mps[i] -= a->ekf.ba_mps2[i] * dt;
    }
    a->yaw_rate_rps = inc->dtheta_b_rad[2] / dt;
    app_trace(APP_TRACE_MECHANIZATION, 0u);
    const int mech_rc = sins_step(&a->nav, inc);
    app_trace(APP_TRACE_MECHANIZATION, 1u);
    if (mech_rc != NAV_OK) {
        reject(a, &a->health.nav_rejected);
        if (!navigator_finite(&a->nav)) {
            filter_reset(a); /* every later sample would be refused too */
        }
        return;
    }
    odo_tick(&a->odo, dt, a->yaw_rate_rps);
    mat3_t C;
    quat_to_dcm(a->nav.q_bn, &C);
    nav_real_t dv_n[3];
    mat3_mul_vec(&C, inc->dv_b_mps, dv_n);
    for (int i = 0; i < 3; i++) {
        a->f_sum_n[i] += dv_n[i];
    }
    record_velocity(a);
    for (int i = 0; i < 3; i++) {
        a->w_sum_rad[i] += inc->dtheta_b_rad[i];
    }
    a->pred_t_s += dt;
    a->pred_n++;
    nav_real_t roll, pitch, heading;
    sins_euler(&a->nav, &roll, &pitch, &heading);
    if (a->odo.valid && !a->odo.standing) {
        (void)dr_step(&a->dr, a->odo.speed_mps * dt, heading, pitch);
    } else if (!a->odo.valid) {
        dr_set_position(&a->dr, &a->nav.pos);
    }
    /* no heading hold with the filter: it would undo the filter's heading corrections
     * while their variance is spent; the zero-rate update does the job */
    a->holding = 0u;
    const uint32_t div = a->cfg.imu_rate_hz >= EKF_PRED_HZ ? a->cfg.imu_rate_hz / EKF_PRED_HZ : 1u;
    if (a->pred_n < div) {
        return;
    }
    const nav_real_t T = a->pred_t_s;
    const nav_real_t f_mean[3] = {a->f_sum_n[0] / T, a->f_sum_n[1] / T, a->f_sum_n[2] / T};
    app_trace(APP_TRACE_PREDICTION, 0u);
    ekf_predict(&a->ekf, &a->nav, f_mean, T);
    app_trace(APP_TRACE_PREDICTION, 1u);
    /* a slow wheel-speed source is a late, averaged speed: its noise grows with the
     * acceleration times its period, and its zero hides a car creeping below one step */
    nav_real_t acc = NAV_C(0.0);
    for (int i = 0; i < 2; i++) {
        const nav_real_t d = a->nav.v_n_mps[i] - a->v_prev_pred_mps[i];
        acc += d * d;
        a->v_prev_pred_mps[i] = a->nav.v_n_mps[i];
    }
    acc = nav_sqrt(acc) / T;
    const nav_real_t per = a->odo.period_s;
    if (a->odo.valid && a->odo.standing) {
        if (ekf_zero_velocity(&a->ekf, &a->nav, ZUPT_SIGMA_MPS + NAV_C(0.1) * per, GATE_SIGMA) ==
            0) {
            odo_refused(a); /* "standing" wheels while the car moves: a locked wheel */
        }
        const nav_real_t resid = a->w_sum_rad[2] / T - earth_rate_body_z(&a->nav);
        (void)ekf_zero_rate(&a->ekf, resid, a->cfg.gyro_arw_rad_rts / nav_sqrt(T));
    } else if (a->odo.valid && a->odo.n_frames != a->odo_frames_used &&
               nav_fabs(a->odo.speed_mps) > ODO_MIN_SPEED_MPS) {
        a->odo_frames_used = a->odo.n_frames;
        const nav_real_t sf = ODO_SIGMA_MPS + NAV_C(0.01) * nav_fabs(a->odo.speed_mps) +
                              NAV_C(0.5) * acc * per;
        const nav_real_t w_b[3] = {a->w_sum_rad[0] / T, a->w_sum_rad[1] / T,
                                   a->w_sum_rad[2] / T};
        app_trace(APP_TRACE_ODOMETER_UPDATE, 0u);
        const int n_used = ekf_odometer(&a->ekf, &a->nav, w_b, a->cfg.odo_lever_b_m,
                                        a->odo.speed_mps, sf, NHC_SIGMA_MPS, GATE_SIGMA);
        app_trace(APP_TRACE_ODOMETER_UPDATE, 1u);
        if (n_used == 0) {
            odo_refused(a); /* the odometer disagrees beyond its gate */
        }
    }
    if (ekf_feedback(&a->ekf, &a->nav) != NAV_OK) {
        reject(a, &a->health.nav_rejected);
    }
    (void)supervise_filter(a);
    a->pred_n = 0u;
    a->pred_t_s = NAV_C(0.0);
    a->f_sum_n[0] = a->f_sum_n[1] = a->f_sum_n[2] = NAV_C(0.0);
    a->w_sum_rad[0] = a->w_sum_rad[1] = a->w_sum_rad[2] = NAV_C(0.0);
}

/* A GNSS fix for the filter. Its time of validity is the arrival minus the receiver's
 * latency; an epoch that arrives later than usual is seen in TimeOfWeek: the offset
 * (IMU time - TimeOfWeek) of each epoch is compared with its running minimum (allowing
 * 50 ppm of clock drift), the excess added to the latency. The navigator's position and
 * velocity at that time come from the velocity history; beyond it the fix is refused. */
static void gnss_update(app_t *a, hal_t *hal, uint32_t tow_ms, int have_vel, int have_h)
{
    const int64_t t_imu_us = (int64_t)(a->n_samples * 1000000u / a->cfg.imu_rate_hz);
    const int64_t off = t_imu_us - (int64_t)tow_ms * 1000;
    /* A receiver clock that jumps (week rollover, reset) moves the offset for good; a late
     * epoch moves it once. A step earlier by more than 1 s, later by more than 10 s, or
     * later by more than 0.5 s three epochs in a row is a time jump: counted, and the
     * offset starts again from it. */
    const int64_t excess = off - a->gnss_off_min_us;
    a->gnss_late_run = (uint8_t)(a->gnss_off_valid && excess > 500000
                                     ? (a->gnss_late_run < 255u ? a->gnss_late_run + 1u : 255u)
                                     : 0u);
    const int jumped = a->gnss_off_valid &&
                       (excess < -1000000 || excess > 10000000 || a->gnss_late_run >= 3u);
    if (jumped) {
        count(&a->health.time_jumps);
        a->gnss_late_run = 0u;
    }
    if (!a->gnss_off_valid || off < a->gnss_off_min_us || jumped) {
        a->gnss_off_min_us = off; /* first epoch, an earlier one, or a time jump */
        a->gnss_off_valid = 1u;
    } else {
        /* the minimum may creep up by 50 ppm of the IMU time elapsed (clock drift) */
        a->gnss_off_min_us += (t_imu_us - a->gnss_prev_t_us) / 20000;
        if (off < a->gnss_off_min_us) {
            a->gnss_off_min_us = off;
        }
    }
    a->gnss_prev_t_us = t_imu_us;
    const nav_real_t late_s = (nav_real_t)(off - a->gnss_off_min_us) * NAV_C(1e-6);
    const nav_real_t tau = a->cfg.gnss_latency_s + late_s;
    const nav_real_t dt = (nav_real_t)vhist_div(a) / (nav_real_t)a->cfg.imu_rate_hz;
    const nav_real_t back = tau / dt; /* history entries back */
    const uint32_t m = (uint32_t)back;
    if (m + 1u >= APP_VHIST || m + 1u >= a->vhist_n) {
        reject(a, &a->health.gnss_rejected); /* older than the history */
        return;
    }
    /* position then = now - integral of v over tau (latest samples first) */
    nav_real_t d[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    for (uint32_t j = 0u; j <= m; j++) {
        const nav_real_t w = j < m ? dt : (back - (nav_real_t)m) * dt;
        const nav_real_t *v = a->vhist[(a->vhist_n - 1u - j) % APP_VHIST];
        for (int i = 0; i < 3; i++) {
            d[i] += w * v[i];
        }
    }
    geo_pos_t then = a->nav.pos;
    const nav_real_t lat = geo_lat_rad(&then);
    const nav_real_t h = geo_h_m(&then);
    nav_real_t R_M, R_N;
    earth_radii(nav_sin(lat), &R_M, &R_N);
    if (geo_pos_add(&then, -d[1] / (R_M + h), -d[0] / ((R_N + h) * nav_cos(lat)), -d[2]) !=
        NAV_OK) {
        reject(a, &a->health.gnss_rejected);
        return;
    }
    const geo_pos_t meas = {(int64_t)a->gnss_lat_e7 * LSB_PER_E7, (int64_t)a->gnss_lon_e7 * LSB_PER_E7,
                            (int64_t)a->gnss_h_cm * 10 * GEO_LSB_PER_MM};
    nav_real_t sh = clampr((nav_real_t)a->gnss_hacc_dm * NAV_C(0.1) * NAV_C(0.7071),
                           GNSS_SIGMA_FLOOR_M, NAV_C(100.0));
    nav_real_t sv = clampr((nav_real_t)a->gnss_vacc_dm * NAV_C(0.1), NAV_C(0.5),
                           NAV_C(100.0));
    /* A receiver's position errors are correlated over tens of seconds (multipath,
     * atmosphere, orbits), the filter's noise model is white: N fixes within the
     * correlation time carry the information of about one. Each fix's variance is
     * multiplied by (correlation time / fix interval), so the filter neither averages the
     * errors away on paper nor reports a 1-sigma far below the receiver's (docs/kalman.md,
     * honest accuracy). */
    nav_real_t ep_s = (nav_real_t)(a->n_samples - a->gnss_prev_sample) /
                      (nav_real_t)a->cfg.imu_rate_hz;
    a->gnss_prev_sample = a->n_samples;
    const nav_real_t corr_s = a->cfg.gnss_corr_s > ep_s ? a->cfg.gnss_corr_s : ep_s;
    ep_s = clampr(ep_s, NAV_C(0.05), corr_s);
    const nav_real_t r_scale = corr_s / ep_s;
    if (!a->ekf_on) {
        /* The navigator may have drifted far more than the receiver's error before the
         * filter: it starts at the fix (moved on by the motion since its time of validity,
         * less the antenna lever arm), and the filter's position sigma is the receiver's. */
        mat3_t C;
        quat_to_dcm(a->nav.q_bn, &C);
        nav_real_t l_n[3];
        mat3_mul_vec(&C, a->cfg.gnss_lever_b_m, l_n);
        geo_pos_t p = meas;
        if (!have_h) {
            p.h = a->nav.pos.h;
        }
        const nav_real_t dh_m = have_h ? d[2] - l_n[2] : d[2];
        if (geo_pos_add(&p, (d[1] - l_n[1]) / (R_M + h), (d[0] - l_n[0]) / ((R_N + h) * nav_cos(lat)),
                        dh_m) != NAV_OK) {
            reject(a, &a->health.gnss_rejected);
            return;
        }
        a->nav.pos = p;
        then = p;
        (void)geo_pos_add(&then, -d[1] / (R_M + h), -d[0] / ((R_N + h) * nav_cos(lat)), -d[2]);
        start_filter(a, sh);
        if (!a->ekf_on) {
            return;
        }
    }
    const int rp = ekf_gnss_position(&a->ekf, &a->nav, &then, &meas, a->cfg.gnss_lever_b_m, sh,
                                     sv, GNSS_GATE_SIGMA, r_scale, have_h);
    int rv = 1;
    if (have_vel) {
        nav_real_t vm[3];
        vm[0] = navecu_can_gnss_velocity_vel_east_decode(a->gnss_vel_raw[0]);
        vm[1] = navecu_can_gnss_velocity_vel_north_decode(a->gnss_vel_raw[1]);
        vm[2] = navecu_can_gnss_velocity_vel_up_decode(a->gnss_vel_raw[2]);
        const nav_real_t *vthen = a->vhist[(a->vhist_n - 1u - (uint32_t)(back + NAV_C(0.5))) %
                                           APP_VHIST];
        const nav_real_t ss = clampr((nav_real_t)a->gnss_sacc_raw * NAV_C(0.1), NAV_C(0.05),
                                     NAV_C(2.0));
        rv = ekf_gnss_velocity(&a->ekf, vthen, vm, ss, NAV_C(1.5) * ss, GNSS_GATE_SIGMA);
    }
    if (rp < 2 || rv == 0) {
        reject(a, &a->health.gnss_rejected); /* beyond the innovation gate */
    }
    /* Several fixes in a row refused: after a bad fix slipped through, or a long outage,
     * the filter may be the one that is wrong; forget its position and velocity and let
     * the next fix in (counted: ekf.n_reopened). */
    const int taken = rp >= 2; /* the horizontal fix was taken */
    a->gnss_gated_run = !taken ? (uint8_t)(a->gnss_gated_run < 255u ? a->gnss_gated_run + 1u : 255u)
                               : 0u;
    const uint64_t since = a->have_fix ? a->last_fix_sample : a->ekf_start_sample;
    if (a->gnss_gated_run >= 2u &&
        a->n_samples - since > (uint64_t)GNSS_REOPEN_S * a->cfg.imu_rate_hz) {
        ekf_reopen(&a->ekf, NAV_C(3.0) * sh, NAV_C(1.0));
        a->gnss_gated_run = 0u;
        a->gnss_reopen_run = (uint8_t)(a->gnss_reopen_run < 255u ? a->gnss_reopen_run + 1u : 255u);
    }
    if (taken) {
        a->last_fix_sample = a->n_samples;
        a->have_fix = 1u;
        a->gnss_reopen_run = 0u;
    }
    if (ekf_feedback(&a->ekf, &a->nav) != NAV_OK) {
        reject(a, &a->health.nav_rejected);
    }
    if (supervise_filter(a)) {
        return;
    }
    filter_calibration(a, hal);
}

/* ---- IMU plausibility (docs/reliability.md) ----
 * Saturation: a rate or specific force at the configured range of the IMU (the sensor
 * clips there, so what it reports is not the motion). A stuck axis: its raw increment
 * repeats exactly for IMU_STUCK_S or longer while the vehicle moves (another axis spans
 * more than 1 deg/s or 0.5 m/s^2): counted once per episode, flagged while it lasts. Both are counted and flagged;
 * the samples are still used, since neither says what the true value was. */
#define IMU_STUCK_S 2u
static void imu_plausibility(app_t *a, const int32_t w_raw[3], const int32_t v_raw[3])
{
    const nav_real_t dt = NAV_C(1.0) / (nav_real_t)a->cfg.imu_rate_hz;
    int32_t raw[6];
    for (int i = 0; i < 3; i++) {
        raw[i] = w_raw[i];
        raw[i + 3] = v_raw[i];
    }
    /* the ranges in raw units (once: integer compares per sample) */
    if (a->imu_sat_raw[0] == 0) {
        /* at most 100 rad/s and 2000 m/s^2 (app_init) over 0.1 s: within int32 */
        const nav_real_t w_lim = a->cfg.gyro_range_rps * dt * NAV_C(0.999) /
                                 navecu_can_imu_rate_angle_inc_x_decode(1);
        const nav_real_t v_lim = a->cfg.accel_range_mps2 * dt * NAV_C(0.999) /
                                 navecu_can_imu_accel_vel_inc_x_decode(1);
        a->imu_sat_raw[0] = (int32_t)w_lim;
        a->imu_sat_raw[1] = (int32_t)v_lim;
    }
    int saturated = 0;
    for (int i = 0; i < 6; i++) {
        const int32_t lim = a->imu_sat_raw[i < 3 ? 0 : 1];
        saturated |= raw[i] >= lim || raw[i] <= -lim;
    }
    if (saturated) {
        count(&a->health.imu_saturated);
        a->had_sat = 1u;
        a->last_sat_sample = a->n_samples;
    }
    const uint32_t n_stuck = IMU_STUCK_S * a->cfg.imu_rate_hz;
    /* blocks of half the window: the last block and the one before lie within the last
     * n_stuck samples, i.e. within the time the stuck axis has been repeating */
    if (a->imu_blk_n == 0u || a->imu_blk_n >= n_stuck / 2u) {
        for (int i = 0; i < 6; i++) {
            a->imu_prev_min[i] = a->imu_blk_n == 0u ? raw[i] : a->imu_blk_min[i];
            a->imu_prev_max[i] = a->imu_blk_n == 0u ? raw[i] : a->imu_blk_max[i];
            a->imu_blk_min[i] = a->imu_blk_max[i] = raw[i];
        }
        a->imu_blk_n = 0u;
    }
    a->imu_blk_n++;
    for (int i = 0; i < 6; i++) {
        a->imu_same_n[i] = (a->have_sample && raw[i] == a->imu_last_raw[i])
                               ? (a->imu_same_n[i] < UINT32_MAX ? a->imu_same_n[i] + 1u : UINT32_MAX)
                               : 0u;
        a->imu_last_raw[i] = raw[i];
        a->imu_blk_min[i] = raw[i] < a->imu_blk_min[i] ? raw[i] : a->imu_blk_min[i];
        a->imu_blk_max[i] = raw[i] > a->imu_blk_max[i] ? raw[i] : a->imu_blk_max[i];
    }
    /* the vehicle moves: a gyro axis spans more than 1 deg/s, or a horizontal
     * accelerometer axis more than 0.5 m/s^2, over the last one to two blocks (turning,
     * braking, accelerating), while an axis repeats: a working sensor's noise would have
     * moved its last bits (the gyro's 2^-21 rad LSB is far below a MEMS gyro's noise per
     * sample). An ideal, noiseless simulated IMU can repeat while the car accelerates in a
     * straight line and is then flagged too: the flag only informs. */
    int repeating = 0;
    for (int i = 0; i < 6; i++) {
        repeating |= a->imu_same_n[i] >= n_stuck;
        if (a->imu_same_n[i] < n_stuck) {
            a->imu_stuck_seen &= (uint8_t)~(1u << i); /* it moved: a new episode may come */
        }
    }
    if (!repeating) {
        return; /* the usual case: nothing more to look at */
    }
    const nav_real_t w_move = NAV_C(0.017453) * dt / navecu_can_imu_rate_angle_inc_x_decode(1);
    const nav_real_t v_move = NAV_C(0.5) * dt / navecu_can_imu_accel_vel_inc_x_decode(1);
    int moving = 0;
    for (int j = 0; j < 5; j++) { /* the three gyro axes, accelerometer x and y */
        const int32_t lo = a->imu_blk_min[j] < a->imu_prev_min[j] ? a->imu_blk_min[j]
                                                                  : a->imu_prev_min[j];
        const int32_t hi = a->imu_blk_max[j] > a->imu_prev_max[j] ? a->imu_blk_max[j]
                                                                  : a->imu_prev_max[j];
        moving |= (nav_real_t)((int64_t)hi - (int64_t)lo) > (j < 3 ? w_move : v_move) &&
                  a->imu_same_n[j] < n_stuck;
    }
    for (int i = 0; i < 6; i++) {
        if (a->imu_same_n[i] < n_stuck) {
            continue;
        }
        if (moving && (a->imu_stuck_seen & (1u << i)) == 0u) {
            a->imu_stuck_seen |= (uint8_t)(1u << i); /* counted once per episode */
            count(&a->health.imu_stuck);
        }
        if (moving) {
            a->had_stuck = 1u;
            a->last_stuck_sample = a->n_samples;
        }
    }
}

/* ---- re-acquisition after an IMU gap too long to bridge ----
 * The motion during the gap is unknown, so position, velocity and heading are lost; the
 * roll and pitch are kept (a car's change little), and so is the heading when the car is
 * found standing. The next GNSS epoch with a velocity gives the position and the velocity,
 * and, at GNSS_COURSE_MIN_MPS or more, the heading (the course plus the mounting yaw in
 * use); navigation resumes there, the filter restarting at the epoch after. Output mode
 * Fault and HealthFlags REACQUIRE until then. */
static void begin_reacquire(app_t *a)
{
    nav_real_t roll, pitch, heading;
    sins_euler(&a->nav, &roll, &pitch, &heading);
    a->reacq_roll_rad = roll;
    a->reacq_pitch_rad = pitch;
    a->reacq_heading_rad = heading;
    a->reacq_mount_rad = a->ekf_on ? a->ekf.mount_yaw_rad : a->dr.dh_rad;
    a->reacquire = 1u;
    a->ekf_on = 0u;
    a->have_fix = 0u;
    a->mode = APP_MODE_FAULT;
}

/* Resume at the GNSS epoch just received (its frames decoded in a->gnss_*). */
static void reacquire_from_gnss(app_t *a, nav_real_t speed_mps, nav_real_t course_rad)
{
    const nav_real_t heading = speed_mps >= GNSS_COURSE_MIN_MPS
                                   ? course_rad + a->reacq_mount_rad
                                   : a->reacq_heading_rad;
    nav_real_t q[4];
    quat_from_euler(a->reacq_roll_rad, a->reacq_pitch_rad, heading, q);
    const geo_pos_t pos = {(int64_t)a->gnss_lat_e7 * LSB_PER_E7,
                           (int64_t)a->gnss_lon_e7 * LSB_PER_E7,
                           (int64_t)a->gnss_h_cm * 10 * GEO_LSB_PER_MM};
    const nav_real_t v[3] = {navecu_can_gnss_velocity_vel_east_decode(a->gnss_vel_raw[0]),
                             navecu_can_gnss_velocity_vel_north_decode(a->gnss_vel_raw[1]),
                             navecu_can_gnss_velocity_vel_up_decode(a->gnss_vel_raw[2])};
    const sins_config_t scfg = sins_default_config();
    if (sins_init(&a->nav, &scfg, &pos, v, q) != NAV_OK ||
        dr_init(&a->dr, &pos, a->cal_dh_rad, a->cal_mu) != NAV_OK) {
        reject(a, &a->health.gnss_rejected);
        return;
    }
    sins_set_height_ref(&a->nav, (nav_real_t)a->gnss_h_cm * NAV_C(0.01));
    a->reacquire = 0u;
    a->output_dr = 0u;
    a->holding = 0u;
    a->vhist_n = 0u; /* the velocities before the gap are not this navigator's */
    a->mode = APP_MODE_NAVIGATING;
}

/* from + (to - from) * num / den, rounded to nearest (0 < num < den) */
static int32_t interpolate_raw(int32_t from, int32_t to, uint64_t num, uint64_t den)
{
    const int64_t d = (int64_t)to - (int64_t)from;
    const int64_t scaled = d * (int64_t)num;
    const int64_t half = (int64_t)den / 2;
    const int64_t q = scaled >= 0 ? (scaled + half) / (int64_t)den : -((-scaled + half) / (int64_t)den);
    return (int32_t)((int64_t)from + q);
}

static void on_imu_rate(app_t *a, const hal_can_frame_t *f)
{
    struct navecu_can_imu_rate_t m;
    navecu_can_imu_rate_unpack(&m, f->data, 8u);
    if (m.imu_counter > E2E_COUNTER_MAX) {
        reject(a, &a->health.bad_counter);
        return;
    }
    if (a->rate_pending) {
        reject(a, &a->health.imu_pair_broken); /* the previous IMU_Rate got no IMU_Accel */
    }
    a->rate_pending = 1u;
    a->rate_counter = m.imu_counter;
    memcpy(a->rate_data, f->data, 8u);
    a->rate_raw[0] = m.angle_inc_x;
    a->rate_raw[1] = m.angle_inc_y;
    a->rate_raw[2] = m.angle_inc_z;
}

static void on_imu_accel(app_t *a, hal_t *hal, const hal_can_frame_t *f)
{
    struct navecu_can_imu_accel_t m;
    navecu_can_imu_accel_unpack(&m, f->data, 8u);
    if (!a->rate_pending || m.imu_counter != a->rate_counter) {
        a->rate_pending = 0u;
        reject(a, &a->health.imu_pair_broken);
        return;
    }
    a->rate_pending = 0u;
    /* one E2E data element in two frames: the CRC covers IMU_Rate too */
    if (f->data[7] != e2e_pair_crc(NAVECU_CAN_IMU_ACCEL_FRAME_ID, a->rate_data, f->data)) {
        reject(a, &a->health.bad_crc);
        return;
    }
    e2e_counter_t probe = a->rx_imu;
    const int step = e2e_counter_step(&probe, m.imu_counter);
    if (step <= 0) {
        reject(a, &a->health.bad_counter); /* repeated sample or invalid counter */
        return;
    }
    /* a sample held for a counter jump is confirmed by one of its next few successors
     * (1..IMU_MAX_DELTA after it, as lost frames may take the very next): the gap was real */
    const int after_held = ((int)m.imu_counter - (int)a->imu_resync_counter + 15) % 15;
    const int confirmed = a->imu_resync_valid && after_held >= 1 && after_held <= IMU_MAX_DELTA;
    if (!confirmed && step >= 15 - IMU_MAX_DELTA) {
        /* 1..4 behind the counter held: old data (or the counter held was itself a
         * corrupt one ahead of time): dropped until the counter catches up, so a wrong
         * counter never moves time ahead for good. */
        reject(a, &a->health.bad_counter);
        return;
    }
    if (!confirmed && step > IMU_MAX_DELTA) {
        /* E2E "wrong sequence": a corrupted counter, or a real gap of IMU_MAX_DELTA samples
         * or more. The next samples decide: if one follows this one closely, the gap was
         * real and is bridged then (this sample counted among the lost); if they follow the
         * last good one, this counter was wrong and only this sample is lost.
         * Counter-only, so the same at any replay speed. */
        a->imu_resync_valid = 1u;
        a->imu_resync_counter = m.imu_counter;
        reject(a, &a->health.bad_counter);
        return;
    }
    a->imu_resync_valid = 0u;
    a->rx_imu = probe;
    if (m.imu_fault) {
        a->flags_sticky |= APP_FLAG_IMU_FAULT;
    } else {
        a->flags_sticky &= (uint16_t)~APP_FLAG_IMU_FAULT;
    }
    /* The 4-bit counter cannot see a gap of 15 samples or more. The receive time can:
     * when more than half a counter cycle beyond the counter's step has elapsed, add the
     * whole cycles it missed. (Time is used only here, for gaps; a replay at any speed
     * that keeps samples less than 7 periods apart gives the same result.) */
    uint64_t lost = (uint64_t)step - 1u;
    if (a->have_sample && f->t_us > a->last_imu_t_us) {
        const uint64_t period_us = 1000000u / a->cfg.imu_rate_hz;
        const uint64_t by_time = (f->t_us - a->last_imu_t_us + period_us / 2u) / period_us;
        if (by_time > (uint64_t)step + 7u) {
            lost += (by_time - (uint64_t)step + 7u) / 15u * 15u;
            count(&a->health.time_jumps);
        }
    }
    const int32_t v_raw[3] = {m.vel_inc_x, m.vel_inc_y, m.vel_inc_z};
    int32_t prev_raw[6]; /* the last sample before a gap (the start of the bridge) */
    for (int i = 0; i < 6; i++) {
        prev_raw[i] = a->have_sample ? a->imu_last_raw[i] : (i < 3 ? a->rate_raw[i] : v_raw[i - 3]);
    }
    imu_plausibility(a, a->rate_raw, v_raw);
    a->have_sample = 1u;
    a->last_imu_t_us = f->t_us;
    if (lost > 0u) {
        /* Lost samples are bridged by interpolating between the samples around the gap:
         * the motion in the gap is unknown, the straight line between its ends keeps time,
         * the Earth-rate and gravity terms and smooth motion right. Beyond APP_MAX_BRIDGE_MS the solution cannot be trusted:
         * it re-acquires from GNSS (begin_reacquire). */
        a->health.imu_lost = lost > UINT32_MAX - a->health.imu_lost
                                 ? UINT32_MAX
                                 : a->health.imu_lost + (uint32_t)lost;
        a->had_gap = 1u;
        if (lost > (uint64_t)APP_MAX_BRIDGE_MS * a->cfg.imu_rate_hz / 1000u) {
            if (a->mode == APP_MODE_NAVIGATING) {
                begin_reacquire(a);
            } else if (a->mode == APP_MODE_LEVELLING) {
                a->mode = APP_MODE_FAULT;
            }
            a->n_samples += lost;
        } else {
            /* the lost samples, interpolated linearly between the last sample before the
             * gap and this one (integer arithmetic: the same on every target) */
            for (uint64_t k = 0u; k < lost; k++) {
                int32_t wi[3];
                int32_t vi[3];
                for (int i = 0; i < 3; i++) {
                    wi[i] = interpolate_raw(prev_raw[i], a->rate_raw[i], k + 1u, lost + 1u);
                    vi[i] = interpolate_raw(prev_raw[i + 3], v_raw[i], k + 1u, lost + 1u);
                }
                process_sample(a, hal, wi, vi);
            }
        }
        a->last_gap_sample = a->n_samples; /* the flag holds for a second after the gap */
    }
    process_sample(a, hal, a->rate_raw, v_raw);
}

/* ------------------------------------------------------------- odometer ---- */

static void on_wheel_speeds(app_t *a, const hal_can_frame_t *f)
{
    struct navecu_can_wheel_speeds_t m;
    navecu_can_wheel_speeds_unpack(&m, f->data, 8u);
    if (e2e_counter_step(&a->rx_wheel, m.wheel_counter) <= 0) {
        reject(a, &a->health.bad_counter);
        return;
    }
    const nav_real_t w[4] = {navecu_can_wheel_speeds_wheel_speed_fl_decode(m.wheel_speed_fl),
                             navecu_can_wheel_speeds_wheel_speed_fr_decode(m.wheel_speed_fr),
                             navecu_can_wheel_speeds_wheel_speed_rl_decode(m.wheel_speed_rl),
                             navecu_can_wheel_speeds_wheel_speed_rr_decode(m.wheel_speed_rr)};
    if (odo_wheels(&a->odo, w, a->yaw_rate_rps) != NAV_OK) {
        reject(a, &a->health.bad_value); /* a locked or spinning wheel, or out of range */
        return;
    }
    /* levelling assumes the vehicle is still: rolling wheels restart it */
    if (a->mode == APP_MODE_LEVELLING && !a->odo.zero) {
        restart_levelling(a);
    }
}

/* ---------------------------------------------------------- calibration ---- */

static void store_calibration(app_t *a, hal_t *hal)
{
    cal_record_t rec;
    rec.dh_rad = (float)a->cal_dh_rad;
    rec.odo_scale_err = (float)a->cal_mu;
    rec.base_m = (float)a->cal_base_m;
    rec.source = a->cal_source;
    a->last_save_sample = a->n_samples;
    if (calstore_save(hal, &a->calstore, &rec) == 0) {
        a->cal_stored = 1u;
        a->stored_mu = a->cal_mu;
        a->stored_dh_rad = a->cal_dh_rad;
        a->flags_sticky &= (uint16_t)~APP_FLAG_NVM_ERROR;
    } else {
        a->cal_stored = 0u;
        a->flags_sticky |= APP_FLAG_NVM_ERROR;
    }
}

/* One-point calibration (seed 000 eqs 7-12) at the true position lat/lon (1e-7 deg):
 * refused with a reason in CalStatus when not navigating on the odometer or too close to
 * the base; otherwise the new estimates are used from the next step on, the position is
 * reset to the point, and the result is stored. */
static void calibrate_at(app_t *a, hal_t *hal, int32_t lat_e7, int32_t lon_e7, uint8_t source)
{
    /* with the filter running, GNSS calibrates the odometer and the mounting: the
     * one-point calibration is for GNSS-denied driving */
    if (a->mode != APP_MODE_NAVIGATING || !a->output_dr || a->ekf_on) {
        a->cal_status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE;
        reject(a, &a->health.cmd_rejected);
        return;
    }
    geo_pos_t p = a->dr.pos;
    p.lat = (int64_t)lat_e7 * LSB_PER_E7;
    p.lon = (int64_t)lon_e7 * LSB_PER_E7;
    dr_cal_t res;
    const int rc = dr_calibrate(&a->dr, &p, a->cfg.cal_min_base_m, &res);
    if (rc != NAV_OK) {
        a->cal_status = rc == NAV_ERANGE
                            ? NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_TOO_CLOSE_CHOICE
                            : NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE;
        reject(a, &a->health.cmd_rejected);
        return;
    }
    a->cal_dh_rad = a->dr.dh_rad;
    a->cal_mu = a->dr.mu;
    a->cal_base_m = res.base_m;
    a->cal_source = source;
    a->cal_status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_ONE_POINT_CHOICE;
    if (a->cal_count < UINT8_MAX) {
        a->cal_count++;
    }
    a->nav.pos = a->dr.pos;
    store_calibration(a, hal);
}

/* ----------------------------------------------------------------- GNSS ---- */

static int lat_lon_ok(int32_t lat_e7, int32_t lon_e7)
{
    return lat_e7 >= -900000000 && lat_e7 <= 900000000 && lon_e7 > -1800000000 &&
           lon_e7 <= 1800000000;
}

/* A GNSS_Status closes the epoch: the position, velocity and height received since the
 * previous one belong to it if their epoch numbers match (docs/can.md, GNSS epochs). */
static void on_gnss_status(app_t *a, hal_t *hal, const hal_can_frame_t *f)
{
    struct navecu_can_gnss_status_t m;
    navecu_can_gnss_status_unpack(&m, f->data, 8u);
    const int have_pos = a->gnss_pos_pending;
    int have_vel = a->gnss_vel_pending;
    int have_h = a->gnss_h_pending;
    const int pos_rejected = a->gnss_pos_rejected;
    a->gnss_pos_pending = a->gnss_vel_pending = a->gnss_h_pending = 0u;
    a->gnss_pos_rejected = 0u;
    if (m.gnss_epoch > E2E_COUNTER_MAX || m.fix_type > 6u) {
        reject(a, &a->health.bad_value); /* values the protocol does not define */
        return;
    }
    if ((have_vel && a->gnss_vel_epoch != m.gnss_epoch) ||
        (have_h && a->gnss_h_epoch != m.gnss_epoch)) {
        reject(a, &a->health.gnss_rejected); /* frames of another epoch: drop them */
        have_vel = have_vel && a->gnss_vel_epoch == m.gnss_epoch;
        have_h = have_h && a->gnss_h_epoch == m.gnss_epoch;
    }
    nav_real_t speed = NAV_C(-1.0);
    nav_real_t course = NAV_C(0.0);
    if (have_vel) {
        const nav_real_t ve = navecu_can_gnss_velocity_vel_east_decode(a->gnss_vel_raw[0]);
        const nav_real_t vn = navecu_can_gnss_velocity_vel_north_decode(a->gnss_vel_raw[1]);
        speed = nav_sqrt(ve * ve + vn * vn);
        course = nav_atan2(ve, vn);
        if (course < NAV_C(0.0)) {
            course += NAV_C(2.0) * PI_F;
        }
        a->gnss_course_rad = course;
        a->gnss_speed_mps = speed;
    }
    if (m.fix_type < GNSS_MIN_FIX || m.num_satellites < GNSS_MIN_SATS) {
        return; /* no usable fix: not an error, the receiver says so */
    }
    if (!have_pos) {
        if (!pos_rejected) {
            reject(a, &a->health.gnss_rejected); /* a fix reported without its position */
        }
        return;
    }
    a->have_gnss = 1u;
    a->last_gnss_sample = a->n_samples;
    a->gnss_hacc_dm = m.horiz_accuracy;
    a->gnss_vacc_dm = m.vert_accuracy;
    if (a->cal_at_gnss) {
        /* the fix marked as the calibration point is that and nothing else: it neither
         * starts the filter nor feeds it */
        a->cal_at_gnss = 0u;
        calibrate_at(a, hal, a->gnss_lat_e7, a->gnss_lon_e7,
                     NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_GNSS_CHOICE);
        return;
    }
    if (a->reacquire && a->mode == APP_MODE_FAULT) {
        if (have_vel && have_h &&
            (speed >= GNSS_COURSE_MIN_MPS || (speed >= NAV_C(0.0) && speed <= GNSS_STILL_MPS))) {
            reacquire_from_gnss(a, speed, course);
        }
        return; /* between 0.3 and 5 m/s the course is not a heading: wait */
    }
    if (a->mode == APP_MODE_NAVIGATING) {
        app_trace(APP_TRACE_GNSS_UPDATE, 0u);
        gnss_update(a, hal, m.time_of_week, have_vel, have_h);
        app_trace(APP_TRACE_GNSS_UPDATE, 1u);
    }
    if (have_h && a->mode == APP_MODE_NAVIGATING && !a->ekf_on) {
        sins_set_height_ref(&a->nav, (nav_real_t)a->gnss_h_cm * NAV_C(0.01));
    }
    /* Levelling assumes the vehicle is still: GNSS motion restarts it. */
    if (a->mode == APP_MODE_LEVELLING && speed > GNSS_STILL_MPS) {
        restart_levelling(a);
    }
    /* Initialization from GNSS alone: the heading is the GNSS course while driving; the
     * position, height and levelling come at the next stop. */
    if (a->mode == APP_MODE_WAIT_INIT && !a->init_pos_valid) {
        if (speed >= GNSS_COURSE_MIN_MPS) {
            a->course_rad = course;
            a->course_valid = 1u;
        }
        if (a->course_valid && have_h && speed >= NAV_C(0.0) && speed <= GNSS_STILL_MPS) {
            a->init_pos_valid = 1u;
            a->init_lat_e7 = a->gnss_lat_e7;
            a->init_lon_e7 = a->gnss_lon_e7;
            a->init_h_cm = a->gnss_h_cm;
            a->init_heading_rad = a->course_rad;
            a->init_heading_valid = 1u;
            start_levelling_if_ready(a);
        }
    }
}

/* ------------------------------------------------------------- commands ---- */

/* A command's alive counter: CMD_MAX_DELTA - 1 lost frames are tolerated; a larger step is
 * an old or foreign frame (E2E "wrong sequence"): dropped, counted, and the counter
 * resynchronizes on it. Returns 1 to accept the command. */
static int command_counter_ok(app_t *a, e2e_counter_t *c, uint8_t counter)
{
    const int step = e2e_counter_step(c, counter);
    if (step <= 0 || step > CMD_MAX_DELTA) {
        reject(a, &a->health.bad_counter);
        return 0;
    }
    return 1;
}

static void on_cmd_control(app_t *a, hal_t *hal, const hal_can_frame_t *f)
{
    struct navecu_can_cmd_control_t m;
    navecu_can_cmd_control_unpack(&m, f->data, 8u);
    if (!command_counter_ok(a, &a->rx_cmd, m.cmd_counter)) {
        return;
    }
    switch (m.command) {
    case 0u: /* None */
        break;
    case 1u: /* Reset */
        reset_navigation(a);
        break;
    case 2u: /* SetInitialPosition */
        if (!a->known_pos_valid || !navecu_can_cmd_control_height_is_in_range(m.height) ||
            (m.heading_valid && !navecu_can_cmd_control_heading_is_in_range(m.heading))) {
            reject(a, &a->health.cmd_rejected);
            break;
        }
        const int32_t lat_e7 = a->known_lat_e7, lon_e7 = a->known_lon_e7;
        reset_navigation(a);
        a->init_pos_valid = 1u;
        a->init_lat_e7 = lat_e7;
        a->init_lon_e7 = lon_e7;
        a->init_h_cm = m.height * 10;
        a->init_heading_valid = m.heading_valid ? 1u : 0u;
        a->init_heading_rad = (nav_real_t)m.heading * NAV_C(0.01) / DEG_PER_RAD;
        start_levelling_if_ready(a);
        break;
    case 3u: /* StoreCalibration: the values in use */
        if (a->cal_source == NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_NONE_CHOICE ||
            (a->last_save_sample != 0u &&
             a->n_samples - a->last_save_sample < (uint64_t)STORE_MIN_S * a->cfg.imu_rate_hz)) {
            /* nothing calibrated to store, or asked again within STORE_MIN_S (flash wear) */
            reject(a, &a->health.cmd_rejected);
            break;
        }
        store_calibration(a, hal);
        break;
    case 4u: /* EraseCalibration: the store and the values in use */
        if (calstore_erase(hal, &a->calstore) != 0) {
            a->flags_sticky |= APP_FLAG_NVM_ERROR;
            break;
        }
        a->flags_sticky &= (uint16_t)~APP_FLAG_NVM_ERROR;
        a->cal_dh_rad = NAV_C(0.0);
        a->cal_mu = NAV_C(0.0);
        a->cal_base_m = NAV_C(0.0);
        a->cal_source = NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_NONE_CHOICE;
        a->cal_status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NONE_CHOICE;
        a->cal_stored = 0u;
        a->dr.dh_rad = NAV_C(0.0);
        a->dr.mu = NAV_C(0.0);
        break;
    case 5u: /* CalibrateHere: the last CMD_KnownPosition is where the car is */
        if (!a->known_pos_valid) {
            a->cal_status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE;
            reject(a, &a->health.cmd_rejected);
            break;
        }
        a->known_pos_valid = 0u; /* a point is used once: the next needs its own */
        calibrate_at(a, hal, a->known_lat_e7, a->known_lon_e7,
                     NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_KNOWN_POSITION_CHOICE);
        break;
    case 6u: /* CalibrateAtGnss: at the next accepted fix */
        if (a->mode != APP_MODE_NAVIGATING) {
            a->cal_status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE;
            reject(a, &a->health.cmd_rejected);
            break;
        }
        a->cal_at_gnss = 1u;
        break;
    default:
        reject(a, &a->health.cmd_rejected);
        break;
    }
}

/* Roll and pitch from another source end levelling at once (a perfect start). */
static void on_cmd_initial_attitude(app_t *a, const hal_can_frame_t *f)
{
    struct navecu_can_cmd_initial_attitude_t m;
    navecu_can_cmd_initial_attitude_unpack(&m, f->data, 8u);
    if (!command_counter_ok(a, &a->rx_att, m.att_counter)) {
        return;
    }
    if (!navecu_can_cmd_initial_attitude_init_roll_is_in_range(m.init_roll) ||
        !navecu_can_cmd_initial_attitude_init_pitch_is_in_range(m.init_pitch)) {
        reject(a, &a->health.bad_value);
        return;
    }
    if (a->mode != APP_MODE_LEVELLING) {
        reject(a, &a->health.cmd_rejected); /* only between SetInitialPosition and navigating */
        return;
    }
    start_navigation_at(a, navecu_can_cmd_initial_attitude_init_roll_decode(m.init_roll),
                        navecu_can_cmd_initial_attitude_init_pitch_decode(m.init_pitch));
}

/* ------------------------------------------------------------- dispatch ---- */

/* 1 if the message with this identifier carries its own E2E CRC in byte 7 (the IMU pair
 * is checked as a whole when IMU_Accel arrives) */
static int is_e2e(uint32_t id)
{
    return id == NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID || id == NAVECU_CAN_GNSS_VELOCITY_FRAME_ID ||
           id == NAVECU_CAN_CMD_CONTROL_FRAME_ID || id == NAVECU_CAN_CMD_INITIAL_ATTITUDE_FRAME_ID;
}

void app_handle_frame(app_t *a, hal_t *hal, const hal_can_frame_t *f)
{
    a->health.log_line_bad = hal_can_rx_malformed(hal);
    if (f->t_us < a->last_rx_t_us) {
        count(&a->health.time_jumps); /* counted; the IMU counter keeps the time base */
    } else {
        a->last_rx_t_us = f->t_us;
    }
    const uint32_t id = f->id;
    if (f->extended) {
        reject(a, &a->health.unknown_id);
        return;
    }
    switch (id) {
    case NAVECU_CAN_IMU_RATE_FRAME_ID:
    case NAVECU_CAN_IMU_ACCEL_FRAME_ID:
    case NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID:
    case NAVECU_CAN_GNSS_POSITION_FRAME_ID:
    case NAVECU_CAN_GNSS_VELOCITY_FRAME_ID:
    case NAVECU_CAN_GNSS_STATUS_FRAME_ID:
    case NAVECU_CAN_GNSS_HEIGHT_FRAME_ID:
    case NAVECU_CAN_CMD_KNOWN_POSITION_FRAME_ID:
    case NAVECU_CAN_CMD_CONTROL_FRAME_ID:
    case NAVECU_CAN_CMD_INITIAL_ATTITUDE_FRAME_ID:
        break;
    case NAVECU_CAN_NAV_POSITION_FRAME_ID:
    case NAVECU_CAN_NAV_HEIGHT_FRAME_ID:
    case NAVECU_CAN_NAV_VELOCITY_FRAME_ID:
    case NAVECU_CAN_NAV_ATTITUDE_FRAME_ID:
    case NAVECU_CAN_NAV_STATUS_FRAME_ID:
    case NAVECU_CAN_NAV_CALIBRATION_FRAME_ID:
        return; /* our own outputs, seen on a shared bus */
    default:
        reject(a, &a->health.unknown_id);
        return;
    }
    if (f->dlc != 8u) {
        reject(a, &a->health.bad_dlc);
        return;
    }
    if (is_e2e(id) && !e2e_crc_ok(id, f->data)) {
        reject(a, &a->health.bad_crc);
        return;
    }

    switch (id) {
    case NAVECU_CAN_IMU_RATE_FRAME_ID:
        on_imu_rate(a, f);
        break;
    case NAVECU_CAN_IMU_ACCEL_FRAME_ID:
        on_imu_accel(a, hal, f);
        break;
    case NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID:
        on_wheel_speeds(a, f);
        break;
    case NAVECU_CAN_GNSS_POSITION_FRAME_ID: {
        struct navecu_can_gnss_position_t m;
        navecu_can_gnss_position_unpack(&m, f->data, 8u);
        if (!lat_lon_ok(m.latitude, m.longitude)) {
            reject(a, &a->health.gnss_rejected); /* impossible position */
            a->gnss_pos_pending = 0u;
            a->gnss_pos_rejected = 1u;
            break;
        }
        a->gnss_lat_e7 = m.latitude;
        a->gnss_lon_e7 = m.longitude;
        a->gnss_pos_pending = 1u;
        break;
    }
    case NAVECU_CAN_GNSS_VELOCITY_FRAME_ID: {
        struct navecu_can_gnss_velocity_t m;
        navecu_can_gnss_velocity_unpack(&m, f->data, 8u);
        if (e2e_counter_step(&a->rx_gnss_vel, m.gnss_epoch) <= 0) {
            reject(a, &a->health.bad_counter); /* repeated epoch or the invalid 15 */
            break;
        }
        a->gnss_vel_epoch = m.gnss_epoch;
        a->gnss_vel_raw[0] = m.vel_east;
        a->gnss_vel_raw[1] = m.vel_north;
        a->gnss_vel_raw[2] = m.vel_up;
        a->gnss_sacc_raw = m.speed_accuracy;
        a->gnss_vel_pending = 1u;
        break;
    }
    case NAVECU_CAN_GNSS_HEIGHT_FRAME_ID: {
        struct navecu_can_gnss_height_t m;
        navecu_can_gnss_height_unpack(&m, f->data, 8u);
        if (!navecu_can_gnss_height_height_is_in_range(m.height)) {
            reject(a, &a->health.bad_value);
            break;
        }
        a->gnss_h_cm = m.height;
        a->gnss_h_epoch = m.gnss_epoch;
        a->gnss_h_pending = 1u;
        break;
    }
    case NAVECU_CAN_GNSS_STATUS_FRAME_ID:
        on_gnss_status(a, hal, f);
        break;
    case NAVECU_CAN_CMD_KNOWN_POSITION_FRAME_ID: {
        struct navecu_can_cmd_known_position_t m;
        navecu_can_cmd_known_position_unpack(&m, f->data, 8u);
        if (!lat_lon_ok(m.latitude, m.longitude)) {
            reject(a, &a->health.bad_value);
            break;
        }
        a->known_lat_e7 = m.latitude;
        a->known_lon_e7 = m.longitude;
        a->known_pos_valid = 1u;
        break;
    }
    case NAVECU_CAN_CMD_INITIAL_ATTITUDE_FRAME_ID:
        on_cmd_initial_attitude(a, f);
        break;
    default: /* NAVECU_CAN_CMD_CONTROL_FRAME_ID */
        on_cmd_control(a, hal, f);
        break;
    }
}

void app_poll(app_t *a, hal_t *hal)
{
    const uint64_t now = hal_time_us(hal);
    a->last_poll_us = now;
    a->have_poll = 1u;
    const uint64_t stale_since = a->last_imu_t_us + IMU_STALE_US;
    const uint64_t period_us = 1000000u / a->cfg.status_rate_hz;
    if (a->have_sample && now > stale_since && now > a->last_status_t_us &&
        now - a->last_status_t_us >= period_us) {
        emit_status(a, hal);
    }
}

int app_tasks_ok(app_t *a, uint64_t now_us)
{
    int ok = 1;
    const uint64_t poll_deadline_us =
        (uint64_t)APP_STATUS_DEADLINE_PERIODS * 1000000u / a->cfg.status_rate_hz;
    if (!a->have_poll || (now_us > a->last_poll_us && now_us - a->last_poll_us > poll_deadline_us)) {
        ok = 0; /* app_poll, which keeps NAV_Status going, did not run */
    }
    const uint32_t div = a->cfg.imu_rate_hz >= EKF_PRED_HZ ? a->cfg.imu_rate_hz / EKF_PRED_HZ : 1u;
    if (a->ekf_on && a->mode == APP_MODE_NAVIGATING &&
        a->pred_n > APP_PREDICT_DEADLINE_PERIODS * div) {
        ok = 0; /* IMU samples went by without the filter's prediction */
    }
    if (!ok) {
        count(&a->health.tasks_late);
    }
    return ok;
}

size_t app_rx_ids(uint32_t *ids, size_t max)
{
    static const uint32_t rx[] = {
        NAVECU_CAN_IMU_RATE_FRAME_ID,        NAVECU_CAN_IMU_ACCEL_FRAME_ID,
        NAVECU_CAN_WHEEL_SPEEDS_FRAME_ID,    NAVECU_CAN_GNSS_POSITION_FRAME_ID,
        NAVECU_CAN_GNSS_VELOCITY_FRAME_ID,   NAVECU_CAN_GNSS_STATUS_FRAME_ID,
        NAVECU_CAN_GNSS_HEIGHT_FRAME_ID,     NAVECU_CAN_CMD_KNOWN_POSITION_FRAME_ID,
        NAVECU_CAN_CMD_CONTROL_FRAME_ID,     NAVECU_CAN_CMD_INITIAL_ATTITUDE_FRAME_ID,
    };
    const size_t n = sizeof rx / sizeof rx[0];
    for (size_t i = 0u; i < n && i < max; i++) {
        ids[i] = rx[i];
    }
    return n;
}
