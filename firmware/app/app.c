/* app.c - the navecu application's dispatcher: each frame to its room; see app.h. */
#include "app.h"

#include <string.h>

#include "app_tuning.h"
#include "commands.h"
#include "navecu_can.h"

/* the default profiling hook: nothing (app.h; a board may define its own) */
__attribute__((weak)) void app_trace(uint32_t point, uint32_t end)
{
    (void)point;
    (void)end;
}

app_diag_t app_diag_of(app_t *a)
{
    const app_diag_t d = {&a->keep.health, &a->run.events, a->keep.n_samples, app_time_us(a)};
    return d;
}

/* count a refused input and flag REJECTED */
static void reject(app_t *a, uint32_t *counter)
{
    const app_diag_t d = app_diag_of(a);
    app_diag_reject(&d, counter);
}

int app_init(app_t *app, const app_config_t *cfg)
{
    if (!app_config_valid(cfg)) {
        return NAV_EINVAL;
    }
    odo_config_t ocfg = odo_default_config();
    ocfg.axle = cfg->odo_axle;
    ocfg.track_m = cfg->odo_track_m;
    ocfg.wheelbase_m = cfg->odo_wheelbase_m;
    /* the still test reads one IMU sample's yaw rate: not below its own noise */
    const nav_real_t rate_noise_rps = APP_STILL_RATE_SIGMAS * cfg->gyro_arw_rad_rts *
                                      nav_sqrt((nav_real_t)cfg->imu_rate_hz);
    if (rate_noise_rps > ocfg.still_rate_rps) {
        ocfg.still_rate_rps = rate_noise_rps;
    }
    memset(app, 0, sizeof *app);
#if VEHICLE_SPLIT_WHEELS
    vehicle_reset(); /* and what the vehicle layer holds of the receive state (vehicle.h) */
#endif
    if (odo_init(&app->keep.odo, &ocfg) != NAV_OK) {
        return NAV_EINVAL;
    }
    app->cfg = *cfg;
    calib_init(&app->keep.cal);
    imu_rate_init(&app->keep.rate);
    imu_link_init(&app->keep.imu, cfg->imu_rate_hz, cfg->gyro_range_rps, cfg->accel_range_mps2,
                  cfg->can_ids[NAVECU_MSG_IMU_ACCEL]);
    imu_link_stamped(&app->keep.imu, cfg->imu_time == IMU_TIME_STAMPED);
    imu_link_noise(&app->keep.imu, cfg->gyro_arw_rad_rts);
    mounting_init(&app->keep.mount, cfg->imu_mount_rad);
    const mount_est_config_t mcfg = {cfg->mount_est_sigma_rad, cfg->mount_est_excite_m2ps3};
    const int mest_rc = mount_est_init(&app->keep.mest, &mcfg); /* "no estimate" in fixed mode */
    if (cfg->imu_mount_source == MOUNT_SOURCE_AUTOMATIC) {
        const nav_real_t zero[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
        if (mest_rc != NAV_OK) {
            return NAV_EINVAL;
        }
        mounting_init(&app->keep.mount, zero); /* the estimate's, when it converges */
        app->keep.mount_state = (uint8_t)APP_MOUNT_ESTIMATING;
    }
    dtc_init(&app->keep.dtc); /* as after a clear until app_dtc_load (app_dtc.h) */
    app->run.mode = APP_MODE_WAIT_INIT;
    (void)app_uds_init(app); /* valid IDs (app_config_valid): cannot fail */
    return NAV_OK;
}

void app_boot(app_t *a, hal_t *hal)
{
    calib_boot(&a->keep.cal, hal);
    uint8_t dtc_bytes[CALSTORE_DTC_N];
    if (nvstore_dtc_status(hal, dtc_bytes) == 0) {
        app_dtc_load(a, dtc_bytes, sizeof dtc_bytes); /* 0xFF: none stored, as after a clear */
    }
}

int app_nvm_write_allowed(const app_t *a)
{
    return (a->run.mode == APP_MODE_WAIT_INIT || a->keep.odo.standing != 0u) ? 1 : 0;
}

/* the default vehicle layer's state: none (vehicle.h; a profile with split wheel speeds
 * generates its own vehicle_reset) */
__attribute__((weak)) void vehicle_reset(void)
{
}

/* the default board layer: nothing over the NVM's (app.h; the host has its own) */
__attribute__((weak)) int app_board_layer(app_config_t *cfg)
{
    (void)cfg;
    return 0;
}

/* the configuration app_init gets from app_init_defaults and app_start: off the stack, and
 * one copy for both (each fills it whole before app_init copies it, and it is read nowhere
 * else) */
static app_config_t layered;

int app_init_defaults(app_t *a)
{
    app_config_defaults(&layered);
    return app_init(a, &layered);
}

int app_start(app_t *a, hal_t *hal)
{
    app_config_t *const cfg = &layered;
    nvstore_status_t st;
    (void)nvstore_layer(hal, cfg, &st); /* any failure leaves valid defaults */
    if (app_board_layer(cfg) != 0 || app_init(a, cfg) != NAV_OK) {
        return NAV_EINVAL;
    }
    a->nvm = st;
    a->started = 1u;
    app_boot(a, hal);
    if (st.source == NVSTORE_SRC_REFUSED || st.refused != 0u) {
        a->keep.cal.nvm_error = 1u; /* NAV_Status NVM_ERROR: what NVM held was refused */
    }
    return NAV_OK;
}

void app_reset(app_t *a)
{
    /* a reset restarts navigation, not the ECU: app_keep_t stays (app.h) */
    memset(&a->run, 0, sizeof a->run);
    gnss_time_forget(&a->keep.gnss_time); /* the receiver's clock and latency stay */
    a->run.mode = APP_MODE_WAIT_INIT;
}

/* ------------------------------------------------------------ IMU samples ---- */

/* out of line (noinline): the link built the ten pointers at each of its three calls,
 * 56 bytes of the ECU's flash more */
__attribute__((noinline)) static fusion_ctx_t fusion_ctx(app_t *a, const app_diag_t *d)
{
    const fusion_ctx_t c = {&a->run.nav,          &a->run.dr,  &a->keep.odo, &a->run.land,
                            &a->cfg,              d,           &a->keep.filter_reset,
                            &a->keep.gnss,        &a->keep.gnss_time, &a->keep.raw_counts};
    return c;
}

/* the car moves: its wheels read a speed, or without wheel speeds a speed above a
 * standstill's (the wheels first: a diverged navigator's velocity is no evidence, a review
 * found; odo.zero, not odo.standing, which only the navigator updates). Out of line
 * (noinline): inlined at both its calls it took 24-32 bytes more. */
__attribute__((noinline)) static int car_moving(const app_t *a, nav_real_t speed_mps)
{
    if (a->keep.odo.valid != 0u) {
        return (a->keep.odo.zero == 0u) ? 1 : 0;
    }
    return (speed_mps > APP_GNSS_STILL_MPS) ? 1 : 0;
}

/* An IMU gap too long to bridge, or a filter reset: position, velocity and (when driving)
 * heading come from the next GNSS epoch; the attitude before is kept. */
static void begin_reacquire(app_t *a)
{
    const nav_real_t mount = a->run.fusion.on ? a->run.fusion.ekf.mount_yaw_rad : a->run.dr.dh_rad;
    const nav_real_t *v = a->run.nav.v_n_mps;
    align_reacquire_begin(&a->run.align, &a->run.nav, mount,
                          car_moving(a, nav_sqrt(v[0] * v[0] + v[1] * v[1])));
    fusion_stop(&a->run.fusion);
    a->run.mode = APP_MODE_FAULT;
}

/* after a GNSS update: the filter's odometer scale and mounting offered to the calibration
 * (calib.h: adopted by its policy) */
static void adopt_filter_calibration(app_t *a, hal_t *hal)
{
    calib_adopt_filter(&a->keep.cal, &a->run.cal, hal, a->keep.n_samples, a->cfg.imu_rate_hz,
                       &a->run.fusion.ekf, &a->run.dr, a->keep.odo.standing);
}

static void after_fusion(app_t *a, fusion_action_t act)
{
    if (act == FUSION_RESTART) {
        app_reset(a);
    } else if (act == FUSION_REACQUIRE) {
        begin_reacquire(a);
    }
}

/* The IMU samples disagree with the configured rate (imu_rate.h): no navigation. A
 * navigator stops and re-acquires from GNSS once the rate matches again (its state was
 * integrated with the wrong time step); waiting for an initial state and levelling are
 * held in mode Fault and go on from the start when it matches. Applied after every frame,
 * so that nothing (a command, a reset) starts navigation while the mismatch lasts. Out of
 * line (noinline): the link inlined it at both its calls, 24-32 bytes more. */
__attribute__((noinline)) static void hold_for_rate(app_t *a)
{
    if (a->run.mode == APP_MODE_NAVIGATING) {
        begin_reacquire(a);
    } else if (a->run.mode == APP_MODE_WAIT_INIT || a->run.mode == APP_MODE_LEVELLING) {
        a->run.rate_resume = a->run.mode;
        a->run.rate_held = 1u;
        a->run.mode = APP_MODE_FAULT;
    } else {
        /* Fault already (re-acquiring, or held by a rate mismatch): it stays */
    }
}

/* An IMU gap the firmware cannot bridge (too long, or the IMU's clock jumped): navigating,
 * the solution re-acquires from GNSS; levelling, the average so far is of an unknown
 * interval: the levelling starts over (the car still stands, or the wheels and GNSS
 * will say it moved and stop it, docs/can.md) */
static void gap_unbridged(app_t *a)
{
#if VEHICLE_SPLIT_WHEELS
    /* a silence of the whole bus stops the IMU too, and with it the odometer's timeout:
     * a wheel-speed half held from before it must not pair with one after (a review) */
    vehicle_reset();
#endif
    if (a->run.mode == APP_MODE_NAVIGATING) {
        begin_reacquire(a);
    } else if (a->run.mode == APP_MODE_LEVELLING) {
        align_level_restart(&a->run.align);
    } else {
        /* waiting: an in-motion alignment window sums the samples since its epoch, which
         * the gap's are missing from: it starts again at the next epoch (review); the
         * GNSS-only start's course misses the gap's turn: no longer a heading (review) */
        a->run.align.mot_open = 0u;
        a->run.align.course_valid = 0u;
    }
}

static void release_for_rate(app_t *a)
{
    if (a->run.rate_held && a->run.mode == APP_MODE_FAULT) {
        a->run.mode = a->run.rate_resume;
        if (a->run.mode == APP_MODE_LEVELLING) {
            align_level_restart(&a->run.align);
        }
    }
    a->run.rate_held = 0u;
}

/* The automatic mounting estimate (imu_mount_source automatic): every sample in the
 * IMU's axes with the odometer's speed. When it converges it becomes the mounting, and a
 * start held for it goes on from GNSS while driving (the course is the heading; roll and
 * pitch start level, the filter takes them from there). */
static void mount_auto_sample(app_t *a, const int32_t w_raw[3], const int32_t v_raw[3],
                              nav_real_t dt_s)
{
    imu_inc_t inc;
    app_rx_imu_increment(w_raw, v_raw, dt_s, &inc);
    const odo_t *o = &a->keep.odo;
    const int rc = mount_est_sample(&a->keep.mest, &inc, o->speed_mps, o->valid ? 1 : 0);
    if (rc == NAV_EINVAL) {
        reject(a, &a->keep.health.bad_value);
        return;
    }
    if (rc != 1) {
        return;
    }
    mount_est_solve(&a->keep.mest);
    if (!a->keep.mest.res.converged || a->keep.mount_state != (uint8_t)APP_MOUNT_ESTIMATING) {
        return; /* after it converged it goes on refining (reported, adoptable); the
                   mounting in use stays the one navigation started with */
    }
    mounting_init(&a->keep.mount, a->keep.mest.res.rpy_rad);
    a->keep.mount_state = (uint8_t)APP_MOUNT_ESTIMATED;
    /* the filter refines the residual pitch and yaw from the estimate's own sigma, not
     * from the default 1 deg of a configured mounting (converged up to
     * mount_est_sigma_rad, which may be set above it) */
    a->keep.mount_sigma_rad[0] = a->keep.mest.res.sigma_rp_rad;
    a->keep.mount_sigma_rad[1] = a->keep.mest.res.sigma_yaw_rad;
    if (a->run.mount_held && a->run.mode == APP_MODE_FAULT) {
        align_t *al = &a->run.align;
        al->reacq_roll_rad = NAV_C(0.0);
        al->reacq_pitch_rad = NAV_C(0.0);
        al->reacq_heading_rad = NAV_C(0.0);
        al->reacq_mount_rad = NAV_C(0.0);
        al->reacquire = 1u;
        a->run.mount_start = 1u;
    }
    a->run.mount_held = 0u;
}

int app_adopt_mounting(app_t *a)
{
    if (a->keep.mount_state != (uint8_t)APP_MOUNT_ESTIMATED) {
        return -1;
    }
    for (int i = 0; i < 3; i++) {
        a->cfg.imu_mount_rad[i] = a->keep.mest.res.rpy_rad[i];
    }
    a->cfg.imu_mount_source = MOUNT_SOURCE_FIXED;
    return 0;
}

/* The in-motion alignment may start navigation (align.h): waiting for an initial state
 * with no heading (none at all, or SetInitialPosition with HeadingValid 0), the mounting
 * known (in automatic mode the start held for its estimate is the same from GNSS). Out of line
 * (noinline): the link inlined it at both its calls, 40 bytes more of the ECU's flash. */
__attribute__((noinline)) static int motion_align_waits(const app_t *a)
{
    return (a->run.mode == APP_MODE_WAIT_INIT && !a->run.align.heading_valid &&
            a->keep.mount_state != (uint8_t)APP_MOUNT_ESTIMATING)
               ? 1
               : 0;
}

/* The fix carried from its time of validity to now, the frames' arrival: its position
 * moved by its velocity times the receiver's latency (the learnt one, else the parameter);
 * a navigator started from the fix as it is would lag by speed x latency (1.2 m at 12 m/s
 * and 100 ms: the independent client's finding) until the filter's first update. */
static gnss_fix_t fix_now(const app_t *a, const gnss_fix_t *fix)
{
    gnss_fix_t f = *fix;
    if (!fix->has_vel) {
        return f;
    }
    const nav_real_t dt_s = gnss_time_latency(&a->keep.gnss_time, a->cfg.gnss_latency_s);
    const nav_real_t lat = geo_lat_rad(&f.pos);
    const nav_real_t h = geo_h_m(&f.pos);
    nav_real_t R_M, R_N;
    earth_radii(nav_sin(lat), &R_M, &R_N);
    geo_pos_t p = f.pos;
    if (geo_pos_add(&p, fix->v_enu_mps[1] * dt_s / (R_M + h),
                    fix->v_enu_mps[0] * dt_s / ((R_N + h) * nav_cos(lat)),
                    fix->v_enu_mps[2] * dt_s) == NAV_OK) {
        f.pos = p;
    }
    return f;
}

/* A GNSS epoch while the in-motion alignment waits: navigation starts from the fix (as it
 * is now, fix_now) when the window it closes gives roll, pitch and heading. Returns 1 if
 * it started. */
static int motion_align_epoch(app_t *a, const gnss_fix_t *fix)
{
    const align_odo_t odo = {a->keep.odo.valid ? 1u : 0u, a->keep.odo.speed_mps};
    nav_real_t roll, pitch, heading;
    if (!align_motion_epoch(&a->run.align, fix, &odo, &roll, &pitch, &heading)) {
        return 0;
    }
    /* the navigator's heading is the IMU's: the car's plus the mounting yaw in use */
    const gnss_fix_t now = fix_now(a, fix);
    if (align_motion_start(&now, roll, pitch, heading + a->keep.cal.dh_rad, &a->run.nav,
                           &a->run.dr, &a->keep.cal) != NAV_OK) {
        reject(a, &a->keep.health.gnss_rejected);
        return 0;
    }
    landnav_restart(&a->run.land);
    gnss_time_forget(&a->keep.gnss_time);
    a->run.fusion.init_heading_sigma_rad = a->run.align.mot_heading_sigma_rad;
    a->run.fusion.init_tilt_sigma_rad = a->run.align.mot_tilt_sigma_rad;
    a->run.mode = APP_MODE_NAVIGATING;
    return 1;
}

/* One IMU sample's process noise beyond the IMU's own, for the filter's next prediction,
 * on each axis: angle (IMU_Rate) and velocity (IMU_Accel) increments, isotropic, so in
 * any frame (docs/kalman.md, Propagation). While the filter is off, its next start
 * (ekf_init) clears it.
 * - Bridged samples (bridged: the gap is): a bridged sample's increment is the straight
 *   line between the gap's ends and the motion in between is unknown. Each is taken to be
 *   off by as much as the increment changed across the gap (d: the sample after it less
 *   the one before), d's length 1 sigma on every axis: n |d|^2 for n samples if their
 *   errors were independent (sensor noise), (n |d| / 2)^2 for a change of the motion
 *   anywhere in the gap (the straight line is then off by up to |d| / 2 on average, on
 *   every sample alike); the larger of the two. Without it, with 36 % of the samples
 *   bridged (docs/reliability.md, frame loss 20 %), the filter's innovation gate refused
 *   719 measurements and it adopted a mounting yaw 0.52 deg off at a sigma of 0.03 deg.
 * - A sensor with an axis at its range (s->saturated): that axis says only that the true
 *   value is at least the range. Its excess is taken as large as the range itself, 1 sigma
 *   on every axis of that sensor. Without it, with the gyro's range at 15 deg/s
 *   (docs/reliability.md, gyro saturation), the filter was reset 5 times, ended 36.5 m RMS
 *   and adopted a mounting yaw 0.33 deg off.
 * - A sensor with a stuck axis (s->stuck: from APP_IMU_STUCK_S into the episode, while its
 *   value repeats): that axis says nothing of the motion; a car's motion as the 1 sigma
 *   of every axis of that sensor (stuck_raw: APP_STUCK_RATE_RPS, APP_STUCK_ACCEL_MPS2, at
 *   most the range). Without it, with the z gyro stuck through a roundabout
 *   (docs/reliability.md, stuck gyro axis), the position went 41 m off while its reported
 *   accuracy stayed 3.6 m, and the filter was reset (72.3 m at most, 2.99 m RMS); with it,
 *   the car's constraints and the fixes hold the heading: 2.38 m at most, 0.99 m RMS. A
 *   saturated axis takes the range (the larger) when both. */
static void sample_noise(app_t *a, const imu_sample_t *s, int bridged)
{
    /* run for every sample (adding zeros when it is as measured): skipping those cost
     * 32 B of flash the RAV4 image does not have, and the sum is cheap (make target-bench
     * 2.976 -> 2.98 % with it) */
    nav_real_t var[2] = {NAV_C(0.0), NAV_C(0.0)}; /* raw LSB^2 */
    for (int k = 0; k < 2; k++) {
        const uint8_t axes = k == 0 ? IMU_AXES_GYRO : IMU_AXES_ACCEL;
        nav_real_t r = NAV_C(0.0);
        if ((s->stuck & axes) != 0u) {
            r = (nav_real_t)a->keep.imu.stuck_raw[k];
        }
        if ((s->saturated & axes) != 0u) {
            r = (nav_real_t)a->keep.imu.sat_raw[k];
        }
        var[k] = r * r;
    }
    if (bridged) {
        const nav_real_t nl = (nav_real_t)(uint32_t)s->lost; /* at most APP_MAX_BRIDGE_MS */
        const nav_real_t n = nl > NAV_C(4.0) ? NAV_C(0.25) * nl * nl : nl;
        /* the bridged samples lead up to a saturated or stuck value: as unknown */
        var[0] *= nl + NAV_C(1.0);
        var[1] *= nl + NAV_C(1.0);
        for (int i = 0; i < 6; i++) {
            /* raw values of 20 and 17 bits (docs/can.md): exact in float32 */
            const nav_real_t d = (nav_real_t)s->raw[i] - (nav_real_t)s->prev_raw[i];
            var[i / 3] += n * d * d;
        }
    }
    const nav_real_t lsb_a = app_rx_angle_lsb_rad();
    const nav_real_t lsb_v = app_rx_vel_lsb_mps();
    ekf_add_increment_noise(&a->run.fusion.ekf, var[0] * lsb_a * lsb_a,
                            var[1] * lsb_v * lsb_v);
}

/* One IMU sample (raw LSB) of dt_us (stamped; 0: the nominal period): levelling, or a
 * navigation step with or without the filter, then the outputs due. */
static void process_sample(app_t *a, hal_t *hal, const int32_t w_raw[3], const int32_t v_raw[3],
                           uint32_t dt_us)
{
    a->keep.n_samples++;
    const uint32_t step_us = dt_us != 0u ? dt_us : 1000000u / a->cfg.imu_rate_hz;
    a->keep.imu_t_us += step_us;
    /* stamped: the increments over their own interval (no resampling) */
    const nav_real_t dt_s = dt_us != 0u ? (nav_real_t)dt_us * NAV_C(1e-6)
                                        : NAV_C(1.0) / (nav_real_t)a->cfg.imu_rate_hz;
#if VEHICLE_SPLIT_WHEELS
    const uint8_t wheels_were_fresh = a->keep.odo.valid;
#endif
    if (a->run.mode != APP_MODE_NAVIGATING) {
        /* the odometer's timeout in every mode (WheelsMissing, the in-motion alignment,
         * the mounting estimate, the re-acquisition's "the car moves"); navigating, the
         * navigator's step ages it with the standstill (odo_tick), or without it for a
         * sample the strapdown core refused (odo_age) */
        odo_age(&a->keep.odo, dt_s);
    }
    if (a->keep.mount_state != (uint8_t)APP_MOUNT_FIXED) {
        mount_auto_sample(a, w_raw, v_raw, dt_s);
    }
    /* the increments in the car's frame, for the in-motion alignment or the navigator
     * (never both in one sample) */
    imu_inc_t inc;
    app_rx_imu_increment(w_raw, v_raw, dt_s, &inc);
    mounting_apply(&a->keep.mount, &inc);
    if (motion_align_waits(a)) {
        align_motion_sample(&a->run.align, &inc);
    }
    if (a->run.mode == APP_MODE_LEVELLING) {
        const uint32_t n_total = (uint32_t)a->cfg.level_s * a->cfg.imu_rate_hz;
        if (align_level_sample(&a->run.align, v_raw, n_total)) {
            nav_real_t roll, pitch;
            align_level_attitude(&a->run.align, &a->keep.mount, &roll, &pitch);
            commands_start_navigation(a, roll, pitch);
        }
    } else if (a->run.mode == APP_MODE_NAVIGATING) {
        const app_diag_t d = app_diag_of(a);
        calib_trip_odo(&a->run.cal, a->keep.odo.valid, a->keep.odo.speed_mps, dt_s);
        if (a->run.fusion.on) {
            const fusion_ctx_t c = fusion_ctx(a, &d);
            after_fusion(a, fusion_imu_step(&a->run.fusion, &c, &inc, &a->run.yaw_rate_rps));
        } else {
            const zbias_prior_t prior = app_zbias_prior(&a->cfg);
            const uint32_t zn = a->keep.zbias.n;
            const int refused = landnav_step(&a->run.land, &a->keep.zbias, &prior, &a->run.nav,
                                             &a->run.dr, &a->keep.odo, &inc, &a->run.yaw_rate_rps);
            if (a->keep.zbias.n != zn) {
                a->keep.zbias_sample = a->keep.n_samples;
            }
            for (int i = 0; i < refused; i++) {
                reject(a, &a->keep.health.nav_rejected);
            }
            gnss_time_record(&a->keep.gnss_time, a->keep.n_samples, a->cfg.imu_rate_hz,
                             a->run.nav.v_n_mps);
        }
        if (a->run.mode == APP_MODE_NAVIGATING) {
            dynamics_sample(&a->run.dyn, &a->run.nav, &inc);
        }
    }
#if VEHICLE_SPLIT_WHEELS
    if (wheels_were_fresh != 0u && a->keep.odo.valid == 0u) {
        /* the wheel speeds timed out (the odometer's timeout, IMU time, in every mode): an
         * axle's half held from before the silence must not pair with the first after it */
        vehicle_reset();
    }
#endif
    output_due(a, hal);
}

static void on_imu_accel(app_t *a, hal_t *hal, const rx_input_t *in, uint64_t t_us)
{
    imu_sample_t s;
    const imu_verdict_t v =
        imu_stream_accel(&a->run.imu, &a->keep.imu, in->u.imu_accel.counter, in->u.imu_accel.fault,
                         in->u.imu_accel.raw, in->u.imu_accel.data, t_us, &s);
    if (v == IMU_REJ_TIME) {
        app_count(&a->keep.health.imu_timing); /* of bad_value: the IMU_Time stamps */
        reject(a, &a->keep.health.bad_value);
        imu_rate_refused(&a->keep.rate); /* a sample all the same: the rate check's */
        return;
    }
    if (v != IMU_SAMPLE) {
        app_health_t *h = &a->keep.health;
        reject(a, v == IMU_REJ_PAIR ? &h->imu_pair_broken
                                    : (v == IMU_REJ_CRC ? &h->bad_crc : &h->bad_counter));
        return;
    }
    for (uint8_t i = 0u; i < s.dropped; i++) {
        reject(a, &a->keep.health.imu_pair_broken); /* an IMU_Rate that got no IMU_Accel */
    }
    imu_rate_sample(&a->keep.rate, s.lost - s.lost_by_time, s.time_gap);
    gnss_time_imu_next(&a->keep.gnss_time, s.lost > 0u || s.time_reset || s.time_gap);
    if (a->cfg.imu_time == IMU_TIME_STAMPED) {
        imu_rate_stamp(&a->keep.rate, s.time_reset ? 0u : s.dt_us);
    }
    if (s.time_reset) {
        /* the IMU's clock jumped: the time since the last sample is unknown, as after a
         * gap too long to bridge */
        app_count(&a->keep.health.time_jumps);
        a->run.events.gap.seen = 1u;
        gap_unbridged(a);
        app_stamp(&a->run.events.gap, a->keep.n_samples);
    }
    if (s.time_gap) {
        app_count(&a->keep.health.time_jumps);
    }
    if (s.saturated != 0u) {
        app_count(&a->keep.health.imu_saturated);
        app_stamp(&a->run.events.saturated, a->keep.n_samples);
    }
    for (uint8_t i = 0u; i < s.stuck_new; i++) {
        app_count(&a->keep.health.imu_stuck);
    }
    if (s.stuck) {
        app_stamp(&a->run.events.stuck, a->keep.n_samples);
    }
    int bridged = 0;
    if (s.lost > 0u && s.lost <= (uint64_t)APP_MAX_BRIDGE_MS * a->cfg.imu_rate_hz / 1000u) {
        bridged = 1;
    }
    sample_noise(a, &s, bridged);
    /* a stuck yaw gyro: the navigator takes the car's yaw rate (landnav_car_yaw) */
    a->run.land.yaw_car = (uint8_t)(((unsigned)s.stuck >> a->keep.mount.yaw_axis) & 1u);
    if (s.lost > 0u) {
        /* Lost samples are bridged by interpolating between the samples around the gap:
         * the motion in the gap is unknown, the straight line between its ends keeps time,
         * the Earth-rate and gravity terms and smooth motion right. Beyond
         * APP_MAX_BRIDGE_MS the solution cannot be trusted: it re-acquires from GNSS. The
         * IMU_GAP flag's time is the gap's end (below). */
        app_count_n(&a->keep.health.imu_lost, s.lost);
        a->run.events.gap.seen = 1u;
        if (!bridged) {
            gap_unbridged(a);
            a->keep.n_samples += s.lost;
            a->keep.imu_t_us += (uint64_t)s.dt_us - imu_stream_dt_us(&s, s.lost);
        } else {
            for (uint64_t k = 0u; k < s.lost; k++) {
                int32_t w[3];
                int32_t v3[3];
                imu_stream_bridge(&s, k, w, v3);
                process_sample(a, hal, w, v3, imu_stream_dt_us(&s, k));
            }
        }
        app_stamp(&a->run.events.gap, a->keep.n_samples);
    }
    process_sample(a, hal, &s.raw[0], &s.raw[3], imu_stream_dt_us(&s, s.lost));
}

/* ---------------------------------------------------------------- GNSS ---- */

/* The accuracies every user of a usable fix takes (the filter, the in-motion alignment,
 * the re-acquisition): the receiver's, or with gnss_accuracy = declared the declared
 * figures of a receiver that reports none (docs/configuration.md); and a speed sigma no
 * better than the fix's geometry allows. The Doppler velocity's and the code position's
 * errors both scale with the same dilution of precision, in the ratio of the range-rate
 * to the range noise (APP_GNSS_SACC_PER_HACC): a receiver whose speed accuracy ignores a
 * degraded fix (or a declared constant) is floored by its horizontal accuracy, the 2-D
 * radius, not per axis: conservative by sqrt(2), on purpose (a poor fix's velocity errors
 * are far from Gaussian: on the Kingston drive, 2.9 m/s RMS beyond 20 m; the first fixes
 * after the receiver's own outages say 37 m and their velocities are 1 m/s off,
 * docs/kalman.md). */
static void fix_accuracies(const app_config_t *cfg, gnss_fix_t *fix)
{
    if (cfg->gnss_accuracy == GNSS_ACC_DECLARED) {
        fix->hacc_m = cfg->gnss_hacc_m;
        fix->vacc_m = cfg->gnss_vacc_m;
        fix->sacc_mps = cfg->gnss_sacc_mps;
    }
    const nav_real_t sacc_geom = APP_GNSS_SACC_PER_HACC * fix->hacc_m;
    if (fix->has_vel != 0u && fix->sacc_mps < sacc_geom) {
        fix->sacc_mps = sacc_geom;
    }
}


static void on_gnss_status(app_t *a, hal_t *hal, const rx_input_t *in)
{
    gnss_fix_t fix;
    const gnss_close_t r = gnss_epoch_close(&a->run.gnss_asm, in, &fix);
    if (r.undefined) {
        reject(a, &a->keep.health.bad_value); /* values the protocol does not define */
        return;
    }
    if (r.repeat) {
        reject(a, &a->keep.health.bad_counter); /* the previous fix's epoch again */
        return;
    }
    if (r.mismatch) {
        reject(a, &a->keep.health.gnss_rejected); /* frames of another epoch dropped */
    }
    if (r.no_position) {
        reject(a, &a->keep.health.gnss_rejected); /* a fix reported without its position */
    }
    if (r.has_course) {
        fusion_note_course(&a->run.fusion, fix.speed_mps, fix.course_rad);
        if (fix.speed_mps > APP_CMD_MOVING_GNSS_MPS) {
            commands_motion_seen(a); /* a commanded point is where the car was */
        }
    }
    if (!r.usable) {
        return;
    }
    fix_accuracies(&a->cfg, &fix);
    app_stamp(&a->keep.gnss, a->keep.n_samples);
    const imu_rate_change_t rate = imu_rate_epoch(&a->keep.rate, a->cfg.imu_rate_hz, fix.tow_ms);
    if (rate == IMU_RATE_MISMATCH) {
        app_count(&a->keep.health.imu_rate_mismatch);
        hold_for_rate(a);
    } else if (rate == IMU_RATE_MATCH) {
        release_for_rate(a); /* a navigator re-acquires below, at this epoch if it can */
    } else {
        /* no change */
    }
    if (fix.has_week) {
        gnss_time_week(&a->keep.gnss_time, fix.gps_week);
    }
    if (a->run.mode != APP_MODE_NAVIGATING) {
        /* the receiver's clock against the IMU's from every usable epoch, so NAV_Time is
         * known from a start's first sample (while navigating fusion_gnss does it) */
        const gnss_when_t w = gnss_time_align(&a->keep.gnss_time, app_time_us(a),
                                              a->cfg.imu_rate_hz, fix.tow_ms,
                                              gnss_time_latency(&a->keep.gnss_time,
                                                                a->cfg.gnss_latency_s));
        if (w.jumped) {
            app_count(&a->keep.health.time_jumps);
        }
    }
    if (a->run.cal.at_gnss) {
        /* the fix marked as the calibration point is that and nothing else: it neither
         * starts the filter nor feeds it */
        a->run.cal.at_gnss = 0u;
        commands_calibrate_at(a, hal, &fix.pos, NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_GNSS_CHOICE,
                              fusion_fix_sigma_axis_m(fix.hacc_m));
        return;
    }
    if (a->run.align.reacquire && a->run.mode == APP_MODE_FAULT) {
        /* the start after the mounting estimate: driving, the course is the heading */
        int course_ok = 1;
        if (a->run.mount_start && fix.speed_mps < APP_GNSS_COURSE_MIN_MPS) {
            course_ok = 0;
        }
        if (car_moving(a, fix.speed_mps)) {
            a->run.align.reacq_moved = 1u; /* the heading before may be gone */
        }
        if (!imu_rate_mismatch(&a->keep.rate) && course_ok &&
            align_reacquire_ready(&a->run.align, &fix)) {
            const gnss_fix_t now = fix_now(a, &fix);
            if (align_reacquire(&a->run.align, &now, &a->run.nav, &a->run.dr, &a->keep.cal,
                                a->keep.odo.valid && a->keep.odo.speed_mps < NAV_C(0.0)) !=
                NAV_OK) {
                reject(a, &a->keep.health.gnss_rejected);
                return;
            }
            landnav_restart(&a->run.land);
            gnss_time_forget(&a->keep.gnss_time); /* the velocities before the gap */
            a->run.mode = APP_MODE_NAVIGATING;
            a->run.mount_start = 0u;
        }
        return; /* between 0.3 and 5 m/s the course is not a heading, or the IMU rate
                   disagrees with the data: wait */
    }
    if (motion_align_waits(a) && !imu_rate_mismatch(&a->keep.rate) &&
        motion_align_epoch(a, &fix)) {
        return; /* the filter starts at the next epoch */
    }
    if (a->run.mode == APP_MODE_NAVIGATING) {
        const app_diag_t d = app_diag_of(a);
        const fusion_ctx_t c = fusion_ctx(a, &d);
        const fusion_prior_t prior = {
            a->keep.zbias.bias_rps, a->keep.cal.mu,
            a->keep.cal.source == NAVECU_CAN_NAV_CALIBRATION_CAL_SOURCE_FILTER_CHOICE,
            a->keep.cal.dh_rad,
            {a->keep.mount_sigma_rad[0], a->keep.mount_sigma_rad[1]}};
        int adopt = 0;
        app_trace(APP_TRACE_GNSS_UPDATE, 0u);
        const fusion_action_t act = fusion_gnss(&a->run.fusion, &c, &prior, &fix, &adopt);
        if (adopt) {
            adopt_filter_calibration(a, hal);
        }
        after_fusion(a, act);
        app_trace(APP_TRACE_GNSS_UPDATE, 1u);
    }
    if (fix.has_h && a->run.mode == APP_MODE_NAVIGATING && !a->run.fusion.on) {
        sins_set_height_ref(&a->run.nav, (nav_real_t)fix.h_cm * NAV_C(0.01));
    }
    /* levelling assumes the vehicle is still: GNSS motion restarts it */
    if (a->run.mode == APP_MODE_LEVELLING && fix.speed_mps > APP_GNSS_STILL_MPS) {
        align_level_restart(&a->run.align);
    }
    if (a->run.mode == APP_MODE_WAIT_INIT && !a->run.align.pos_valid &&
        align_gnss(&a->run.align, &fix, a->keep.odo.valid && !a->keep.odo.zero) &&
        align_ready(&a->run.align)) {
        a->run.mode = APP_MODE_LEVELLING;
        align_level_restart(&a->run.align);
    }
}

/* A raw GNSS frame (issue #20): assembled into its epoch and checked (gnss_raw.h), a
 * repeat counted in bad_counter, a dropped or incomplete epoch in gnss_rejected (once per
 * epoch); a closed epoch's complete satellites are counted, and fused by the filter when
 * gnss_input says so (fusion_raw). */
static void on_gnss_raw(app_t *a, hal_t *hal, const rx_input_t *in)
{
    if (in->kind == RX_GNSS_RAW_SAT) {
        const gnss_raw_frame_t r = gnss_raw_frame(&a->keep.raw, in);
        if (r == GNSS_RAW_REPEAT) {
            reject(a, &a->keep.health.bad_counter);
        } else if (r == GNSS_RAW_DROPPED) {
            reject(a, &a->keep.health.gnss_rejected);
        } else {
            /* taken */
        }
        return;
    }
    const gnss_raw_close_t c = gnss_raw_close(&a->keep.raw, in);
    if (c.repeat != 0u) {
        reject(a, &a->keep.health.bad_counter);
    } else if (c.mismatch != 0u || c.incomplete != 0u || c.extra != 0u || c.duplicate != 0u) {
        reject(a, &a->keep.health.gnss_rejected);
    } else {
        /* a well-formed epoch */
    }
    if (c.usable == 0u) {
        return;
    }
    app_count(&a->keep.raw_epochs);
    app_count_n(&a->keep.raw_sats, c.n_sats);
    if (a->run.mode == APP_MODE_NAVIGATING && !imu_rate_mismatch(&a->keep.rate)) {
        const app_diag_t d = app_diag_of(a);
        const fusion_ctx_t fc = fusion_ctx(a, &d);
        int adopt = 0;
        app_trace(APP_TRACE_GNSS_UPDATE, 0u);
        const fusion_action_t act =
            fusion_raw(&a->run.fusion, &fc, &a->keep.raw, &c, in->u.raw_epoch.tow_ms,
                       in->u.raw_epoch.clock_reset != 0u, &adopt);
        if (adopt) {
            adopt_filter_calibration(a, hal);
        }
        after_fusion(a, act);
        app_trace(APP_TRACE_GNSS_UPDATE, 1u);
    }
}

/* ------------------------------------------------------------- dispatch ---- */

static uint32_t *rx_counter(app_health_t *h, rx_verdict_t v)
{
    switch (v) {
    case RX_BAD_DLC:
        return &h->bad_dlc;
    case RX_BAD_CRC:
        return &h->bad_crc;
    case RX_BAD_COUNTER:
        return &h->bad_counter;
    case RX_BAD_VALUE:
        return &h->bad_value;
    default:
        return &h->gnss_rejected;
    }
}

/* odo_direction = navigator: the wheel speeds are magnitudes (an OBD-II speed cannot tell
 * reversing); they take the sign of the navigator's forward velocity once it moves backward
 * faster than APP_ODO_REVERSE_MPS (the IMU sees a car reverse away from a stop before its
 * first reading the rows use, APP_ODO_MIN_SPEED_MPS) */
static void wheels_directed(const app_t *a, nav_real_t wheel_mps[4])
{
    mat3_t C;
    quat_to_dcm(a->run.nav.q_bn, &C);
    nav_real_t v_b[3];
    mat3t_mul_vec(&C, a->run.nav.v_n_mps, v_b);
    const nav_real_t sign = v_b[1] < -APP_ODO_REVERSE_MPS ? NAV_C(-1.0) : NAV_C(1.0);
    for (int i = 0; i < 4; i++) {
        wheel_mps[i] = sign * nav_fabs(wheel_mps[i]);
    }
}

void app_handle_frame(app_t *a, hal_t *hal, const hal_can_frame_t *f)
{
    if (app_uds_frame(a, hal, f)) {
        return; /* diagnostics: never navecu's input, never foreign */
    }
    if (f->t_us < a->keep.last_rx_t_us) {
        app_count(&a->keep.health.time_jumps); /* the IMU counter keeps the time base */
    } else {
        a->keep.last_rx_t_us = f->t_us;
    }
    rx_input_t in;
    const rx_verdict_t v = app_rx_decode(&a->keep.rx, a->cfg.can_ids, f, &in);
    if (v == RX_FOREIGN) {
        a->keep.health.foreign++; /* a shared bus: counted apart, never REJECTED */
        return;
    }
    if (v != RX_OK) {
        reject(a, rx_counter(&a->keep.health, v));
        if (in.kind == RX_GNSS_POSITION) {
            gnss_epoch_position_refused(&a->run.gnss_asm);
        }
        return;
    }
    switch (in.kind) {
    case RX_IMU_RATE:
        if (imu_stream_rate(&a->run.imu, in.u.imu_rate.counter, in.u.imu_rate.raw,
                            in.u.imu_rate.data)) {
            reject(a, &a->keep.health.imu_pair_broken); /* the previous one had no IMU_Accel */
        }
        break;
    case RX_IMU_ACCEL:
        on_imu_accel(a, hal, &in, f->t_us);
        break;
    case RX_IMU_TIME:
        imu_stream_time(&a->run.imu, &a->keep.imu, in.u.imu_time.counter, in.u.imu_time.t_us);
        break;
    case RX_WHEELS:
        if (a->cfg.odo_direction == ODO_DIR_NAVIGATOR) {
            wheels_directed(a, in.u.wheels.mps);
        }
        if (odo_wheels(&a->keep.odo, in.u.wheels.mps, a->run.yaw_rate_rps) != NAV_OK) {
            reject(a, &a->keep.health.bad_value); /* a locked or spinning wheel, or range */
        } else if (!a->keep.odo.zero) {
            commands_motion_seen(a); /* a commanded point is where the car was (commands.h) */
        }
        break;
    case RX_GNSS_POSITION:
        gnss_epoch_position(&a->run.gnss_asm, in.u.position.lat_e7, in.u.position.lon_e7);
        break;
    case RX_GNSS_VELOCITY:
        if (gnss_epoch_velocity(&a->run.gnss_asm, in.u.velocity.epoch, in.u.velocity.v_enu_mps,
                                in.u.velocity.sacc_mps) != 0) {
            reject(a, &a->keep.health.bad_counter); /* a repeated frame within the epoch */
        }
        break;
    case RX_GNSS_HEIGHT:
        gnss_epoch_height(&a->run.gnss_asm, in.u.height.epoch, in.u.height.h_cm);
        break;
    case RX_GNSS_STATUS:
        on_gnss_status(a, hal, &in);
        break;
    case RX_GNSS_TIME:
        gnss_epoch_week(&a->run.gnss_asm, in.u.time.epoch, in.u.time.gps_week);
        break;
    case RX_GNSS_RAW_SAT:
    case RX_GNSS_RAW_EPOCH:
        on_gnss_raw(a, hal, &in);
        break;
    case RX_KNOWN_POSITION:
    case RX_COMMAND:
    case RX_INITIAL_ATTITUDE:
        commands_handle(a, hal, &in);
        break;
    default: /* RX_NONE: our own outputs on a shared bus */
        break;
    }
    if (imu_rate_mismatch(&a->keep.rate)) {
        hold_for_rate(a);
    }
}

void app_poll(app_t *a, hal_t *hal)
{
    app_uds_poll(a, hal); /* first: an ECUReset restarts the application */
    const uint64_t now = hal_time_us(hal);
    a->keep.last_poll_us = now;
    a->keep.have_poll = 1u;
    output_heartbeat(a, hal); /* time-driven, from boot; no other output depends on it */
    /* the IMU silent: NAV_Status on the HAL clock; none since power-on: the DTCs tested */
    const uint64_t stale_since = app_imu_since(a) + APP_IMU_STALE_US;
    const uint64_t period_us = 1000000u / a->cfg.status_rate_hz;
    const uint64_t last = a->keep.tx.last_status_t_us;
    if (now > stale_since && now > last && now - last >= period_us) {
        if (a->keep.imu.have_sample) {
            output_status(a, hal);
        } else {
            output_dtc_tests(a, hal);
        }
    }
}

int app_tasks_ok(app_t *a, uint64_t now_us)
{
    int ok = 1;
    const uint64_t poll_deadline_us =
        (uint64_t)APP_STATUS_DEADLINE_PERIODS * 1000000u / a->cfg.status_rate_hz;
    if (!a->keep.have_poll ||
        (now_us > a->keep.last_poll_us && now_us - a->keep.last_poll_us > poll_deadline_us)) {
        ok = 0; /* app_poll, which keeps NAV_Status going, did not run */
    }
    const uint32_t div = fusion_pred_div(a->cfg.imu_rate_hz);
    if (a->run.fusion.on && a->run.mode == APP_MODE_NAVIGATING &&
        a->run.fusion.pred_n > APP_PREDICT_DEADLINE_PERIODS * div) {
        ok = 0; /* IMU samples went by without the filter's prediction */
    }
    if (!ok) {
        app_count(&a->keep.health.tasks_late);
    }
    return ok;
}
