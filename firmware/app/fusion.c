/* fusion.c - the Kalman filter's schedule, updates and supervision; see fusion.h. */
#include "fusion.h"

#include "app.h"
#include "app_tuning.h"

/* clear_interval, corr_spans, bias_is_state, bias_step and rr_sigma_mps out of line
 * (noinline): GCC inlined them at each of their two or three calls, 176 bytes more of the
 * ECU's flash in all (docs/target.md); they run per prediction (10 Hz), GNSS epoch or
 * satellite, not per IMU sample. fusion_pred_div out of line too: inlined at its two calls
 * (fusion.c's and app.c's, per IMU sample) it took 16 bytes more. */

__attribute__((noinline)) uint32_t fusion_pred_div(uint32_t imu_rate_hz)
{
    return imu_rate_hz >= APP_EKF_PRED_HZ ? imu_rate_hz / APP_EKF_PRED_HZ : 1u;
}

void fusion_note_course(fusion_t *fu, nav_real_t speed_mps, nav_real_t course_rad)
{
    fu->course_rad = course_rad;
    fu->speed_mps = speed_mps;
}

void fusion_stop(fusion_t *fu)
{
    fu->on = 0u;
    fu->fix.seen = 0u;
    fu->clock_valid = 0u; /* a new filter starts from an unknown clock (ekf_init) */
}

__attribute__((noinline)) static void clear_interval(fusion_t *fu)
{
    fu->pred_n = 0u;
    fu->pred_t_s = NAV_C(0.0);
    fu->f_sum_n[0] = fu->f_sum_n[1] = fu->f_sum_n[2] = NAV_C(0.0);
    fu->w_sum_rad[0] = fu->w_sum_rad[1] = fu->w_sum_rad[2] = NAV_C(0.0);
}

/* 1 when the angle x (rad), wrapped to [-pi, pi], exceeds tol in magnitude; also for a
 * non-finite or huge x (beyond APP_ANGLE_SANE_RAD, where no angle of the navigator should
 * be). No loop: a wrap by repeated subtraction never ends on an infinite or very large
 * float. */
static int angle_exceeds(nav_real_t x, nav_real_t tol)
{
    if (!(nav_fabs(x) <= APP_ANGLE_SANE_RAD)) {
        return 1;
    }
    const nav_real_t turns = x / (NAV_C(2.0) * NAV_PI);
    const int32_t n = (int32_t)(turns >= NAV_C(0.0) ? turns + NAV_C(0.5) : turns - NAV_C(0.5));
    return nav_fabs(x - (nav_real_t)n * NAV_C(2.0) * NAV_PI) > tol;
}

static int diverged(fusion_t *fu, const fusion_ctx_t *c)
{
    const ekf_t *k = &fu->ekf;
    const uint64_t n = c->diag->n_samples;
    const uint32_t rate = c->cfg->imu_rate_hz;
    /* GNSS refused through reopens is a GNSS fault (a frozen or jumping receiver) as long
     * as the rest agrees with the filter; it is the filter that is wrong when the odometer
     * is refused too, or when the GNSS course, driving, differs from the filter's heading
     * by more than APP_COURSE_MISMATCH_RAD (a heading lost to a stuck or saturated gyro,
     * which the odometer's speed cannot see) */
    nav_real_t roll, pitch, heading;
    sins_euler(c->nav, &roll, &pitch, &heading);
    const nav_real_t course_err = fu->course_rad - (heading - k->mount_yaw_rad);
    const int odo_disagrees = app_stamp_within(&c->diag->events->odo_reject, n,
                                               (uint64_t)APP_GNSS_REOPEN_S * rate);
    /* only with GNSS at hand: in a tunnel the last course and the count of reopens are
     * old news, and a reset there would leave nothing to re-acquire from */
    const int gnss_fresh = app_stamp_within(c->gnss, n, rate);
    const int course_disagrees = gnss_fresh && fu->speed_mps >= APP_GNSS_COURSE_MIN_MPS &&
                                 angle_exceeds(course_err, APP_COURSE_MISMATCH_RAD);
    /* and, whatever the rest says, when the fixes have been refused for
     * APP_FILTER_LOCKOUT_S while they keep coming: a receiver's fixes are seldom that long
     * metres off at the accuracy they declare, and a filter that drifted beyond its own
     * gate (its heading a degree off after a stuck gyro, the odometer agreeing) would
     * refuse them for good, its reopened sigma claiming metres while it is 100 m off */
    /* without wheel speeds the filter takes (no odometer or standstill update within
     * APP_GNSS_REOPEN_S), the receiver's velocity is the other witness: a receiver's
     * position jumps (multipath, a reset) while its velocity, from the Dopplers, agrees
     * with the filter; its velocity refused too, APP_FILTER_REOPEN_LIMIT fixes
     * in a row, the filter is wrong (the RAV4's minute without its wheels refused every
     * fix after a 30-s outage, its reopened HorizAccuracy 10 m: docs/reliability.md).
     * Fixes only: raw epochs (gnss_input raw) wait for the lock-out limit */
    const int vel_disagrees =
        !app_stamp_within(&fu->odo_used, n, (uint64_t)APP_GNSS_REOPEN_S * rate) &&
        fu->vel_gated_run >= APP_FILTER_REOPEN_LIMIT;
    const int aiding_disagrees =
        gnss_fresh && fu->reopen_run >= APP_FILTER_REOPEN_LIMIT &&
        (odo_disagrees || course_disagrees || vel_disagrees || fu->locked_out);
    const int bad = fu->state_lost || k->n_nonfinite != fu->nonfinite_seen ||
                    k->n_negative_var != fu->negative_seen || aiding_disagrees;
    fu->state_lost = 0u;
    fu->nonfinite_seen = k->n_nonfinite;
    fu->negative_seen = k->n_negative_var;
    return bad || !ekf_state_ok(k) || !sins_finite(c->nav);
}

static fusion_action_t reset(fusion_t *fu, const fusion_ctx_t *c)
{
    app_count(&c->diag->health->filter_resets);
    app_stamp(c->filter_reset, c->diag->n_samples);
    fu->on = 0u;
    fu->gated_run = 0u;
    fu->reopen_run = 0u;
    fu->vel_gated_run = 0u;
    fu->fix.seen = 0u;
    raw_bias_forget(&fu->raw_bias); /* learnt against the filter that diverged */
    if (!sins_finite(c->nav)) {
        return FUSION_RESTART;
    }
    if (c->gnss->seen) {
        /* the navigator the filter corrected is suspect too: GNSS gives position,
         * velocity and heading again at its next epoch, as after a long IMU gap */
        return FUSION_REACQUIRE;
    }
    /* without the filter the height needs the core's damping again (fusion_start took it) */
    sins_set_height_ref(c->nav, geo_h_m(&c->nav->pos));
    return FUSION_GO_ON;
}

/* After each filter step: reset it if it diverged. */
/* The filter's corrections into the navigator. A state that is no longer finite (NaN
 * passes every gate: it compares false) is the filter's divergence, for supervise to
 * find: ekf_feedback refuses it and zeroes the state, which would otherwise look sound
 * again. */
static void feed_back(fusion_t *fu, const fusion_ctx_t *c)
{
    if (!ekf_state_ok(&fu->ekf)) {
        fu->state_lost = 1u;
    }
    if (ekf_feedback(&fu->ekf, c->nav) != NAV_OK) {
        app_diag_reject(c->diag, &c->diag->health->nav_rejected);
    }
}

static fusion_action_t supervise(fusion_t *fu, const fusion_ctx_t *c, int *was_reset)
{
    *was_reset = 0;
    if (!fu->on || !diverged(fu, c)) {
        return FUSION_GO_ON;
    }
    *was_reset = 1;
    return reset(fu, c);
}

/* the wheel speeds disagree with the filter beyond its gate (lock, spin, slip) */
static void odo_refused(const fusion_ctx_t *c)
{
    app_diag_reject(c->diag, &c->diag->health->odo_rejected);
    app_stamp(&c->diag->events->odo_reject, c->diag->n_samples);
}

/* How many intervals of interval_s an error correlated over corr_s spans, at least one:
 * readings closer than the correlation carry less than independent ones, and their
 * variance is multiplied by this (docs/kalman.md; the receiver's velocity, a slow
 * odometer, the raw ranges, one zero reading's updates). */
__attribute__((noinline)) static nav_real_t corr_spans(nav_real_t corr_s,
                                                      nav_real_t interval_s)
{
    return corr_s > interval_s ? corr_s / interval_s : NAV_C(1.0);
}

/* The standstill updates of one prediction interval T (s), the wheels reading zero: zero
 * velocity and zero yaw rate. Zero wheels say the car stood when they were read, up to a
 * period plus the source's latency ago (per, s: 1 s for an OBD-II speed): a car
 * accelerating away or braking to its stop meanwhile is not standing. The interval's mean
 * horizontal specific force (f_mean_n, ENU) is the evidence: at rest it is the tilt error
 * times g (0.02 m/s^2 at 0.1 deg) and the accelerometer's noise over the interval; a
 * drive-off or a braking is 0.5..3 m/s^2. Measured on the Kingston drive (1 Hz speed): a
 * ZUPT through each drive-off held the solution behind by 0.3 m along track
 * (docs/odometry.md). */
static void standstill_updates(fusion_t *fu, const fusion_ctx_t *c, nav_real_t T, nav_real_t per,
                               const nav_real_t f_mean_n[3])
{
    const nav_real_t a_h_mps2 =
        nav_sqrt(f_mean_n[0] * f_mean_n[0] + f_mean_n[1] * f_mean_n[1]);
    const nav_real_t sz = APP_ZUPT_SIGMA_MPS + APP_ZUPT_SIGMA_PER_PERIOD_MPS * per;
    if (a_h_mps2 > APP_STILL_ACC_MPS2) {
        /* moving while the wheels still read zero: no update of either kind. The reading
         * is a stop when the car is within reach of one: the source's step plus what the
         * acceleration changes in one of its periods, within the standstill update's gate
         * (its sigma, and the filter's velocity sigma; a car's wheel-speed latency of tens
         * of ms is within them). Faster, the wheels are locked (or their sensor stuck):
         * refused and counted, as the gate would (the fault drive's lock under braking had
         * gone unreported, docs/reliability.md) */
        const nav_real_t *v = c->nav->v_n_mps;
        const nav_real_t reach = c->cfg->odo_step_mps + a_h_mps2 * per + APP_ODO_GATE_SIGMA * sz;
        const nav_real_t var_v = fu->ekf.P[EKF_DV][EKF_DV] + fu->ekf.P[EKF_DV + 1][EKF_DV + 1];
        if (v[0] * v[0] + v[1] * v[1] >
            reach * reach + APP_ODO_GATE_SIGMA * APP_ODO_GATE_SIGMA * var_v) {
            odo_refused(c);
        }
        return;
    }
    /* Standing wheels say |v| < half a step, not which way the car would go: no heading
     * information (the heading's 5 deg sigma would otherwise take the first centimetres
     * of a drive-off, the IMU's acceleration before a wheel reads a step, as a heading
     * error: 0.2 deg in 0.4 s, every heading but east) */
    fu->ekf.hold_heading = 1u;
    /* one zero reading is one measurement: its error (a car creeping below one step) is
     * the same in every prediction interval until the next frame, so the frame's sigma is
     * shared by the per / T updates it serves (each sqrt(per / T) times it) */
    const nav_real_t n_upd = corr_spans(per, T);
    const int zv = ekf_zero_velocity(&fu->ekf, c->nav, sz * nav_sqrt(n_upd), APP_ODO_GATE_SIGMA);
    fu->ekf.hold_heading = 0u;
    if (zv == 0) {
        odo_refused(c); /* "standing" wheels while the car moves: a locked wheel */
    }
    if (zv > 0) {
        app_stamp(&fu->odo_used, c->diag->n_samples);
    }
    if (c->land->yaw_car != 0u) {
        return; /* the yaw is the car's (a stuck gyro): nothing of the gyro's z errors */
    }
    nav_real_t w_ie_b[3];
    sins_earth_rate_b(c->nav, w_ie_b);
    const nav_real_t resid = fu->w_sum_rad[2] / T - w_ie_b[2];
    (void)ekf_zero_rate(&fu->ekf, resid, c->cfg->gyro_arw_rad_rts / nav_sqrt(T));
}

/* The odometer's reading moved on to now: it describes the car odo_latency_s before it
 * arrived, and it arrived age_s ago; moved with the interval's mean along-track
 * acceleration (the horizontal specific force along the navigator's velocity, v_h its
 * horizontal speed; a reading ahead (1) or reversing (0); issue #18). */
static nav_real_t odo_speed_now(const fusion_ctx_t *c, const nav_real_t f_mean_n[3],
                                uint8_t ahead, nav_real_t v_h)
{
    const nav_real_t *v = c->nav->v_n_mps;
    nav_real_t speed = c->odo->speed_mps;
    if (v_h > APP_ODO_MIN_SPEED_MPS) {
        const nav_real_t a_along = (f_mean_n[0] * v[0] + f_mean_n[1] * v[1]) / v_h;
        const nav_real_t lag_s = c->cfg->odo_latency_s + c->odo->age_s;
        speed += (ahead != 0u ? lag_s : -lag_s) * a_along;
    }
    return speed;
}

/* The odometer or standstill updates of one prediction interval T (s) with the mean body
 * rate over it: a slow wheel-speed source is a late, averaged speed, its noise grows with
 * the acceleration times its period, and its zero hides a car creeping below one step. */
static void odometer_updates(fusion_t *fu, const fusion_ctx_t *c, nav_real_t T,
                             const nav_real_t f_mean_n[3])
{
    const odo_t *odo = c->odo;
    const nav_real_t *v = c->nav->v_n_mps;
    /* the velocity at the previous prediction, kept for this one's odometer update (the
     * interval's change of velocity and of speed, computed only when one comes) */
    const nav_real_t vp[2] = {fu->v_prev_pred_mps[0], fu->v_prev_pred_mps[1]};
    fu->v_prev_pred_mps[0] = v[0];
    fu->v_prev_pred_mps[1] = v[1];
    const nav_real_t per = odo->period_s;
    if (odo->valid && odo->standing) {
        standstill_updates(fu, c, T, per, f_mean_n);
    } else if (odo->valid && odo->n_frames != fu->odo_frames_used &&
               nav_fabs(odo->speed_mps) > APP_ODO_MIN_SPEED_MPS) {
        fu->odo_frames_used = odo->n_frames;
        const uint8_t ahead = odo->speed_mps > NAV_C(0.0) ? 1u : 0u;
        const nav_real_t v_h = nav_sqrt(v[0] * v[0] + v[1] * v[1]);
        const nav_real_t speed = odo_speed_now(c, f_mean_n, ahead, v_h);
        /* moved on to a stop or through it, the reading tells no speed to update with */
        if (!(ahead != 0u ? speed > APP_ODO_MIN_SPEED_MPS : speed < -APP_ODO_MIN_SPEED_MPS)) {
            return;
        }
        nav_real_t acc = NAV_C(0.0);
        for (int i = 0; i < 2; i++) {
            const nav_real_t d = v[i] - vp[i];
            acc += d * d;
        }
        acc = nav_sqrt(acc) / T;
        nav_real_t sf = APP_ODO_SIGMA_MPS + APP_ODO_SIGMA_SPEED_FRAC * nav_fabs(odo->speed_mps) +
                        APP_ODO_SIGMA_ACC_PERIOD * acc * per;
        if (per > T) {
            /* a slow source: its error holds over several readings (APP_ODO_SLOW_CORR_S) */
            sf *= nav_sqrt(corr_spans(APP_ODO_SLOW_CORR_S, per));
        }
        const nav_real_t *w_b = fu->w_b_last_rps; /* the interval's mean (fusion_imu_step) */
        /* the car's lateral and vertical velocity are zero at the measuring axle, which is
         * where odo_lever_b_m says to within odo_lever_sigma_m: in a turn the IMU moves
         * sideways by the yaw rate times the error of that lever arm (Kingston, lever arm
         * unknown: without this term the full fusion was worse than GNSS alone) */
        const nav_real_t s_nhc = APP_NHC_SIGMA_MPS + c->cfg->odo_lever_sigma_m * nav_fabs(w_b[2]);
        /* and the body pitches on its suspension as the car brakes or accelerates (dive
         * and squat, APP_DIVE_RAD_PER_MPS2 per m/s^2 along the track), turning that much of
         * the speed into the body's vertical: 0.6 m/s braking at 2 m/s^2 from 36 m/s. With
         * the lateral row's sigma there, the filter took it as a climb: the height sank
         * 12 m through the next stop and its zero-velocity update was refused for all of it
         * (a simulated motorway drive, tools/sim/scenarios/motorway.toml, 1510 refusals) */
        /* along the track: the change of the speed over the interval, not of the velocity
         * (a turn's centripetal acceleration pitches nothing) */
        const nav_real_t speed_prev = nav_sqrt(vp[0] * vp[0] + vp[1] * vp[1]);
        const nav_real_t a_along = (v_h - speed_prev) / T;
        const nav_real_t s_vert = s_nhc + APP_DIVE_RAD_PER_MPS2 * v_h * nav_fabs(a_along);
        app_trace(APP_TRACE_ODOMETER_UPDATE, 0u);
        const int n_used = ekf_odometer(&fu->ekf, c->nav, w_b, c->cfg->odo_lever_b_m,
                                        speed, sf, s_nhc, s_vert, APP_ODO_GATE_SIGMA);
        app_trace(APP_TRACE_ODOMETER_UPDATE, 1u);
        if (n_used == 0) {
            odo_refused(c); /* the odometer disagrees beyond its gate */
        }
        if (n_used > 0) {
            app_stamp(&fu->odo_used, c->diag->n_samples);
        }
    }
}

fusion_action_t fusion_imu_step(fusion_t *fu, const fusion_ctx_t *c, imu_inc_t *inc,
                                nav_real_t *yaw_rate_rps)
{
    const nav_real_t dt = inc->dt_s;
    for (int i = 0; i < 3; i++) {
        inc->dtheta_b_rad[i] -= fu->ekf.bg_rps[i] * dt;
        inc->dv_b_mps[i] -= fu->ekf.ba_mps2[i] * dt;
    }
    inc->dv_b_mps[1] -= fu->ekf.af_mps2 * dt;    /* ekf.h, state 25 */
    if (c->land->yaw_car != 0u) {
        /* a stuck yaw gyro: the car's own rate from the compensated lateral force; none of
         * the gyro's z estimates are in it */
        inc->dtheta_b_rad[2] = landnav_car_yaw(c->nav, inc);
    } else {
        inc->dtheta_b_rad[2] -= fu->ekf.gz_rps * dt; /* ekf.h, state 24 */
        inc->dtheta_b_rad[2] /= NAV_C(1.0) + fu->ekf.gyro_scale_z; /* ekf.h, state 23 */
    }
    *yaw_rate_rps = inc->dtheta_b_rad[2] / dt;
    app_trace(APP_TRACE_MECHANIZATION, 0u);
    const int mech_rc = sins_step(c->nav, inc);
    app_trace(APP_TRACE_MECHANIZATION, 1u);
    if (mech_rc != NAV_OK) {
        app_diag_reject(c->diag, &c->diag->health->nav_rejected);
        /* the sample's time still passes for the wheel speeds (their timeout and period
         * are IMU time); its rates, refused, are no evidence of standing still */
        odo_age(c->odo, dt);
        if (!sins_finite(c->nav)) {
            return reset(fu, c); /* every later sample would be refused too */
        }
        /* the velocity history keeps its entry per sample count (the navigator's velocity,
         * unchanged), as the navigation without the filter records it: the GNSS epochs'
         * latency looks back by sample count */
        gnss_time_record(c->time, c->diag->n_samples, c->cfg->imu_rate_hz, c->nav->v_n_mps);
        return FUSION_GO_ON;
    }
    odo_tick(c->odo, dt, *yaw_rate_rps);
    mat3_t C;
    quat_to_dcm(c->nav->q_bn, &C);
    nav_real_t dv_n[3];
    mat3_mul_vec(&C, inc->dv_b_mps, dv_n);
    for (int i = 0; i < 3; i++) {
        fu->f_sum_n[i] += dv_n[i];
    }
    gnss_time_record(c->time, c->diag->n_samples, c->cfg->imu_rate_hz, c->nav->v_n_mps);
    for (int i = 0; i < 3; i++) {
        fu->w_sum_rad[i] += inc->dtheta_b_rad[i];
    }
    fu->pred_t_s += dt;
    fu->pred_n++;
    nav_real_t roll, pitch, heading;
    sins_euler(c->nav, &roll, &pitch, &heading);
    if (c->odo->valid && !c->odo->standing) {
        (void)dr_step(c->dr, c->odo->speed_mps * dt, heading, pitch);
    } else if (!c->odo->valid) {
        dr_set_position(c->dr, &c->nav->pos);
    }
    /* no heading hold with the filter: it would undo the filter's heading corrections
     * while their variance is spent; the zero-rate update does the job */
    landnav_release_hold(c->land);
    if (fu->pred_n < fusion_pred_div(c->cfg->imu_rate_hz)) {
        return FUSION_GO_ON;
    }
    const nav_real_t T = fu->pred_t_s;
    const nav_real_t f_mean[3] = {fu->f_sum_n[0] / T, fu->f_sum_n[1] / T, fu->f_sum_n[2] / T};
    app_trace(APP_TRACE_PREDICTION, 0u);
    for (int i = 0; i < 3; i++) {
        fu->w_b_last_rps[i] = fu->w_sum_rad[i] / T;
    }
    ekf_predict(&fu->ekf, c->nav, f_mean, fu->w_b_last_rps[2], T);
    app_trace(APP_TRACE_PREDICTION, 1u);
    odometer_updates(fu, c, T, f_mean);
    feed_back(fu, c);
    int was_reset;
    const fusion_action_t act = supervise(fu, c, &was_reset);
    clear_interval(fu);
    return act;
}

static int start(fusion_t *fu, const fusion_ctx_t *c, const fusion_prior_t *prior,
                 nav_real_t hacc_m)
{
    const app_config_t *cfg = c->cfg;
    ekf_config_t ec = ekf_default_config();
    ec.arw_rad_rts = cfg->gyro_arw_rad_rts;
    ec.bg_rps = cfg->gyro_bias_rps;
    ec.ba_mps2 = cfg->accel_bias_mps2;
    ec.bg_rw_rps_rts = cfg->gyro_bias_rw_rps_rts;
    ec.gz_sigma_rps = cfg->gyro_bias_rw_rps_rts * APP_GYRO_GM_SIGMA_PER_RW;
    ec.gz_tau_s = cfg->gyro_bias_corr_time_s;
    /* the forward accelerometer's in-run part (ekf.h, state 25): its data sheet's Allan
     * floor as a Gauss-Markov process of that peak, the IMU's one correlation time */
    ec.af_sigma_mps2 = cfg->accel_fwd_instability_mps2 / EKF_GM_ADEV_PEAK;
    ec.af_tau_s = cfg->gyro_bias_corr_time_s;
    ec.ba_rw_mps2_rts = cfg->accel_bias_rw_mps2_rts;
    ec.gyro_scale = cfg->gyro_scale;
    ec.pos_m = hacc_m > APP_EKF_POS_SIGMA_MIN_M ? hacc_m : APP_EKF_POS_SIGMA_MIN_M;
    /* a truncated speed reads up to a step low: half a step, 1 sigma (ekf.h, state 22) */
    ec.odo_offset_mps = NAV_C(0.5) * cfg->odo_step_mps;
    if (fu->init_tilt_sigma_rad > NAV_C(0.0)) {
        ec.tilt_rad = fu->init_tilt_sigma_rad;
    }
    const nav_real_t heading_sigma_rad = fu->init_heading_sigma_rad; /* 0: the default */
    fu->init_heading_sigma_rad = NAV_C(0.0);
    fu->init_tilt_sigma_rad = NAV_C(0.0);
    if (ekf_init(&fu->ekf, &ec, heading_sigma_rad) != NAV_OK) {
        app_diag_reject(c->diag, &c->diag->health->nav_rejected);
        return 0;
    }
    /* the standstill's z bias, its in-run part at that moment included, goes to the
     * constant turn-on state: the in-run state starts at 0 with its steady sigma, which
     * covers the difference (ekf.h, state 24) */
    (void)ekf_set_gyro_bias(&fu->ekf, 2, prior->gyro_bias_z_rps);
    (void)ekf_set_odo_scale(&fu->ekf, prior->odo_scale);
    if (prior->have_mount_yaw) {
        (void)ekf_set_mount_yaw(&fu->ekf, prior->mount_yaw_rad);
    }
    if (ekf_widen_mount(&fu->ekf, prior->mount_sigma_rad[0], prior->mount_sigma_rad[1]) !=
        NAV_OK) {
        app_diag_reject(c->diag, &c->diag->health->nav_rejected);
    }
    clear_interval(fu);
    fu->clock_valid = 0u; /* ekf_init's clock is an unknown one: estimated afresh */
    fu->raw_have_tow = 0u;
    fu->odo_frames_used = c->odo->n_frames;
    fu->start_sample = c->diag->n_samples;
    fu->refused_since = fu->start_sample; /* no refusals yet (gate_run) */
    fu->nonfinite_seen = fu->ekf.n_nonfinite; /* the supervision's reference: a new filter */
    fu->negative_seen = fu->ekf.n_negative_var;
    /* the filter owns the height now: the core's damping toward a held reference is a
     * force its model does not have */
    sins_clear_height_ref(c->nav);
    fu->on = 1u;
    return 1;
}

/* *p moved by (e, n, u) m east, north and up, with the earth's radii of curvature at
 * latitude lat and height h (the callers': the navigator's position): geo_pos_add's
 * result. One function for the three such moves of start_at_fix and epoch_then, which
 * each formed the radii and the divisions (flash, docs/target.md). */
static int move_enu(geo_pos_t *p, nav_real_t lat, nav_real_t h, nav_real_t e, nav_real_t n,
                    nav_real_t u)
{
    nav_real_t R_M, R_N;
    earth_radii(nav_sin(lat), &R_M, &R_N);
    return geo_pos_add(p, n / (R_M + h), e / ((R_N + h) * nav_cos(lat)), u);
}

/* The navigator may have drifted far more than the receiver's error before the filter:
 * it starts at the fix (moved on by the motion d (ENU, m) since its time of validity,
 * less the antenna lever arm), and the filter's position sigma is the receiver's.
 * lat, h: the navigator's now. Returns 0 when the fix is refused. */
static int start_at_fix(fusion_t *fu, const fusion_ctx_t *c, const fusion_prior_t *prior,
                        const gnss_fix_t *fix, const nav_real_t d[3], nav_real_t sh,
                        geo_pos_t *then)
{
    sins_t *nav = c->nav;
    const nav_real_t lat = geo_lat_rad(&nav->pos);
    const nav_real_t h = geo_h_m(&nav->pos);
    mat3_t C;
    quat_to_dcm(nav->q_bn, &C);
    nav_real_t l_n[3];
    mat3_mul_vec(&C, c->cfg->gnss_lever_b_m, l_n);
    geo_pos_t p = fix->pos;
    if (!fix->has_h) {
        p.h = nav->pos.h;
    }
    const nav_real_t dh_m = fix->has_h ? d[2] - l_n[2] : d[2];
    if (move_enu(&p, lat, h, d[0] - l_n[0], d[1] - l_n[1], dh_m) != NAV_OK ||
        sins_set_position(nav, &p) != NAV_OK) {
        app_diag_reject(c->diag, &c->diag->health->gnss_rejected);
        return 0;
    }
    *then = p;
    (void)move_enu(then, lat, h, -d[0], -d[1], -d[2]);
    return start(fu, c, prior, sh);
}

/* Several fixes in a row refused: after a bad fix slipped through, or a long outage, the
 * filter may be the one that is wrong; forget its position and velocity and let the next
 * fix in (counted: ekf.n_reopened). */
static void gate_run(fusion_t *fu, const fusion_ctx_t *c, int taken, nav_real_t sh)
{
    const uint64_t n = c->diag->n_samples;
    fu->gated_run = !taken ? (uint8_t)(fu->gated_run < 255u ? fu->gated_run + 1u : 255u) : 0u;
    const uint64_t since = fu->fix.seen ? fu->fix.sample : fu->start_sample;
    const uint64_t reopen_n = (uint64_t)APP_GNSS_REOPEN_S * c->cfg->imu_rate_hz;
    /* the refusals' run starts at the first fix refused after one taken or after a gap
     * in the fixes: a GNSS outage is not a refusal (a review: counted from the last fix
     * taken, a tunnel of a minute made the first refused fixes after it a lock-out) */
    if (taken || n - fu->gate_prev_sample > reopen_n) {
        fu->refused_since = n;
    }
    fu->gate_prev_sample = n;
    fu->locked_out = 0u;
    if (n - fu->refused_since > (uint64_t)APP_FILTER_LOCKOUT_S * c->cfg->imu_rate_hz) {
        fu->locked_out = 1u;
    }
    if (fu->gated_run >= APP_GNSS_REOPEN_AFTER && n - since > reopen_n) {
        ekf_reopen(&fu->ekf, APP_GNSS_REOPEN_POS_SIGMAS * sh, APP_GNSS_REOPEN_VEL_MPS);
        fu->gated_run = 0u;
        fu->reopen_run = (uint8_t)(fu->reopen_run < 255u ? fu->reopen_run + 1u : 255u);
    }
    if (taken) {
        app_stamp(&fu->fix, n);
        fu->reopen_run = 0u;
    }
}

/* An epoch valid at `when` (gnss_time_align) against the navigator's history: the
 * navigator's position then (then) and its motion since (d, ENU m). 0 when it is not in
 * the history (refused and counted, unless it is older than the history: valid before
 * the navigation started, not a fault of the receiver) or the position cannot form. */
static int epoch_then(const fusion_ctx_t *c, const gnss_when_t *when, nav_real_t d[3],
                      geo_pos_t *then)
{
    if (!when->in_history) {
        if (!when->before_history) {
            app_diag_reject(c->diag, &c->diag->health->gnss_rejected);
        }
        return 0;
    }
    gnss_time_displacement(c->time, when, d);
    *then = c->nav->pos;
    if (move_enu(then, geo_lat_rad(then), geo_h_m(then), -d[0], -d[1], -d[2]) != NAV_OK) {
        app_diag_reject(c->diag, &c->diag->health->gnss_rejected);
        return 0;
    }
    return 1;
}

/* The correlated GNSS error is the filter's state when gnss_corr_s spans
 * APP_GNSS_STATE_MIN_FIXES of the receiver's usual epoch intervals (fusion_gnss) */
__attribute__((noinline)) static int bias_is_state(const fusion_t *fu, const app_config_t *cfg)
{
    return fu->gnss_ep_typ_s > NAV_C(0.0) &&
           cfg->gnss_corr_s >= APP_GNSS_STATE_MIN_FIXES * fu->gnss_ep_typ_s;
}

/* The Gauss-Markov state lets the filter average the correlated error away over several
 * correlation times, and its position sigma falls below the error's own: a drive of a
 * few correlation times holds a few samples of that error, and a receiver's slow errors
 * (multipath of one street, the atmosphere's residual) are not zero over them. On the
 * simulator's default drive one seed's receiver error stayed 3-7 m east for 8 minutes
 * against its 2 m per axis, and 77 % of the epochs were within twice the filter's sigma.
 * The claim adds, per axis, a constant error as large as the recent fixes' correlated
 * part (ekf_gnss_sc_m), which no fix can tell from the car's position (docs/kalman.md,
 * correlated GNSS errors). */
nav_real_t fusion_sigma_h_m(const fusion_t *fu, const app_config_t *cfg)
{
    const nav_real_t s = ekf_sigma_h_m(&fu->ekf);
    const nav_real_t sc = bias_is_state(fu, cfg) ? ekf_gnss_sc_m(&fu->ekf) : NAV_C(0.0);
    return nav_sqrt(s * s + NAV_C(2.0) * sc * sc);
}

/* The height's is not a state: its fixes' variance is multiplied by the correlation time
 * over the fix interval (fusion_gnss), as if they were independent once per correlation
 * time, and over a drive of many correlation times the filter's height sigma falls as
 * their count grows, while the error it is left with is the correlated error's average
 * over the last few correlation times, which does not (the simulator's seeds 1-8: the
 * height within twice its sigma on 46.7 % of one default seed's epochs, its receiver's
 * vertical error 3 m high for the whole drive; 73-82 % on outage5 and
 * outage5-automotive seeds). The claim adds the recent fixes' correlated vertical part
 * (ekf_gnss_scv_m), as the horizontal's adds theirs, while the receiver's correlated error
 * is the filter's state. */
nav_real_t fusion_sigma_v_m(const fusion_t *fu, const app_config_t *cfg)
{
    const nav_real_t s = ekf_state_sigma(&fu->ekf, EKF_DR + 2);
    const nav_real_t sc = bias_is_state(fu, cfg) ? ekf_gnss_scv_m(&fu->ekf) : NAV_C(0.0);
    return nav_sqrt(s * s + sc * sc);
}

/* The correlation time of the receiver's errors, its fixes' and its ranges' (s):
 * gnss_corr_s while the car moves, plus the time its wheels have read zero while they do.
 * A receiver's errors decorrelate as its antenna moves through the multipath around it;
 * standing, they change only with the satellites' slow motion. Measured on the Kingston
 * drive (python -m tools.kingston.analyse): the fixes' error correlates 0.24 at 4 s and
 * 0.08 at 10 s while driving, 0.74 and 0.37 in the stops, 0.93 at 10 s and 0.86 at 20 s in
 * the first one. Taken as independent every 4 s, a 20-s stop counted as 5 fixes of one
 * offset: the filter's error rose from 0.67 to 1.83 m while its sigma fell from 2.03 to
 * 1.03 m (python -m tools.kingston.run with outages 60 s every 240 s from 100 s, the stop
 * at 1371-1392 s). With the time standing added, a stop's fixes carry about the logarithm
 * of its length in independent ones. The time is odo zero_for_s, which a sample of
 * yaw-rate noise does not end as it ends "standing" (a review: each such sample restarted
 * the sum, about every 160 s with an automotive IMU), and at most
 * APP_GNSS_STAND_CORR_MAX_S (the satellites move on, and a standing antenna's multipath
 * with them; without a bound the reported accuracy of a car parked for hours kept
 * falling). */
__attribute__((noinline)) nav_real_t fusion_rx_corr_s(const app_config_t *cfg, const odo_t *odo)
{
    /* zero unless the wheels read zero (odo.c clears it on a moving or stale reading) */
    const nav_real_t t = odo->zero_for_s;
    return cfg->gnss_corr_s + (t < APP_GNSS_STAND_CORR_MAX_S ? t : APP_GNSS_STAND_CORR_MAX_S);
}

/* the correlated part of a declared GNSS sigma: sqrt(1 - gnss_white_ratio^2) of it */
__attribute__((noinline)) static nav_real_t gnss_corr_part(const app_config_t *cfg)
{
    return nav_sqrt(NAV_C(1.0) - cfg->gnss_white_ratio * cfg->gnss_white_ratio);
}

/* the correlated error state moved on to sample n, its stationary sigma now shc_m, its
 * correlation time corr_s (fusion_rx_corr_s) */
__attribute__((noinline)) static void bias_step(fusion_t *fu, const app_config_t *cfg,
                                                uint64_t n, nav_real_t shc_m, nav_real_t corr_s,
                                                nav_real_t svc_m)
{
    const uint64_t since = n - fu->gnss_bias_sample;
    ekf_gnss_bias_step(&fu->ekf, (nav_real_t)since / (nav_real_t)cfg->imu_rate_hz,
                       corr_s, shc_m, fu->gnss_sc_prev_m, svc_m);
    fu->gnss_sc_prev_m = shc_m;
    fu->gnss_bias_sample = n;
}

fusion_action_t fusion_gnss(fusion_t *fu, const fusion_ctx_t *c, const fusion_prior_t *prior,
                            const gnss_fix_t *fix, int *adopt)
{
    const app_config_t *cfg = c->cfg;
    const uint64_t n = c->diag->n_samples;
    *adopt = 0;
    gnss_when_t when = gnss_time_align(c->time, c->diag->t_us, cfg->imu_rate_hz, fix->tow_ms,
                                       gnss_time_latency(c->time, cfg->gnss_latency_s));
    if (when.jumped) {
        app_count(&c->diag->health->time_jumps);
    }
    /* the accuracies are the receiver's or, with gnss_accuracy = declared, the declared
     * figures (app.c puts them into the fix) */
    const nav_real_t ss = nav_clamp(fix->sacc_mps, APP_GNSS_SACC_MIN_MPS, APP_GNSS_SACC_MAX_MPS);
    /* the latency is learnt only while the filter takes wheel speeds (an odometer or
     * standstill update within APP_GNSS_REOPEN_S): without them the navigator's velocity
     * is the fixes' own, and while the car accelerates steadily a velocity error of dv
     * reads as a latency of dv / a (the RAV4's minute without its wheels learnt 0.3 s too
     * much and ran 5 m ahead: docs/kalman.md); frames that decode but are never taken
     * (another car's on the wheel-speed identifier) are no anchor either */
    if (fix->has_vel &&
        app_stamp_within(&fu->odo_used, n, (uint64_t)APP_GNSS_REOPEN_S * cfg->imu_rate_hz)) {
        (void)gnss_time_learn(c->time, &when, fix->v_enu_mps, ss, cfg->gnss_latency_s);
    }
    nav_real_t d[3];
    geo_pos_t then;
    if (!epoch_then(c, &when, d, &then)) {
        return FUSION_GO_ON;
    }
    const nav_real_t sh = fusion_fix_sigma_axis_m(fix->hacc_m);
    const nav_real_t sv = nav_clamp(fix->vacc_m, APP_GNSS_SIGMA_V_MIN_M, APP_GNSS_SIGMA_MAX_M);
    /* A receiver's position errors are correlated over tens of seconds (multipath,
     * atmosphere, orbits), and N fixes within the correlation time carry the information
     * of about one. Horizontally the correlated part is a first-order Gauss-Markov state
     * of the filter (correlation time gnss_corr_s, the declared per-axis accuracy split
     * into a white part (gnss_white_ratio), the update's noise, and the correlated rest, the state's
     * stationary sigma: ekf_gnss_bias_step); the filter's position sigma keeps the part no
     * number of fixes averages away. The height's variance is multiplied by (correlation
     * time / fix interval) instead (docs/kalman.md, honest accuracy). */
    const nav_real_t dt_fix_s =
        (nav_real_t)(n - fu->prev_fix_sample) / (nav_real_t)cfg->imu_rate_hz;
    nav_real_t ep_s = dt_fix_s;
    fu->prev_fix_sample = n;
    const nav_real_t corr_rx_s = fusion_rx_corr_s(c->cfg, c->odo);
    const nav_real_t corr_s = corr_rx_s > ep_s ? corr_rx_s : ep_s;
    ep_s = nav_clamp(ep_s, APP_GNSS_EPOCH_MIN_S, corr_s);
    const nav_real_t r_scale = corr_s / ep_s;
    /* The correlated part is the filter's state when it spans APP_GNSS_STATE_MIN_FIXES of
     * the receiver's fix intervals (its usual one, whatever the gap before this fix).
     * Shorter, consecutive fixes are nearly independent and the variance inflation is
     * the model (the update without the state). */
    /* the receiver's usual fix interval, from the first: a shorter interval takes it half
     * way (from the first, which counts from the boot, to the rate in a few fixes; a
     * single early epoch halves the distance once), a longer one up to 2.5 times it an
     * eighth of the way back (one missed epoch counts a little; a gap or an outage is not
     * the rate) */
    const nav_real_t ep_raw_s =
        dt_fix_s > APP_GNSS_EPOCH_MIN_S ? dt_fix_s : APP_GNSS_EPOCH_MIN_S;
    if (!(fu->gnss_ep_typ_s > NAV_C(0.0))) {
        fu->gnss_ep_typ_s = ep_raw_s;
    } else {
        const nav_real_t w = ep_raw_s < fu->gnss_ep_typ_s                   ? NAV_C(0.5)
                             : ep_raw_s < NAV_C(2.5) * fu->gnss_ep_typ_s ? NAV_C(0.125)
                                                                         : NAV_C(0.0);
        fu->gnss_ep_typ_s += (ep_raw_s - fu->gnss_ep_typ_s) * w;
    }
    const uint8_t as_state = bias_is_state(fu, cfg) ? 1u : 0u;
    const nav_real_t shw =
        as_state != 0u ? cfg->gnss_white_ratio * sh : sh * nav_sqrt(r_scale);
    const nav_real_t corr_part = gnss_corr_part(cfg);
    const nav_real_t shc = sh * corr_part;
    /* the fix's correlated vertical part, for the height's claim (fusion_sigma_v_m) */
    const nav_real_t svc = fix->has_h ? sv * corr_part : NAV_C(0.0);
    if (fu->on && cfg->gnss_input == GNSS_INPUT_RAW) {
        /* raw measurements are the filter's GNSS input (gnss_input): the fix has served the
         * receiver's clock, latency and usual interval (above) */
        return FUSION_GO_ON;
    }
    const uint8_t starting = fu->on != 0u ? (uint8_t)0u : (uint8_t)1u;
    if (starting != 0u) {
        if (!start_at_fix(fu, c, prior, fix, d, sh, &then)) {
            return FUSION_GO_ON;
        }
        ekf_gnss_bias_start(&fu->ekf, shc, svc);
        fu->gnss_sc_prev_m = shc;
        fu->gnss_bias_sample = n;
    } else {
        if (as_state != 0u) {
            bias_step(fu, cfg, n, shc, corr_rx_s, svc);
        }
    }
    /* The fix's heading information is its course, sigma ss / speed: below
     * APP_GNSS_HEADING_SPEED_SIGMAS speed sigmas (a course sigma above 1/that rad) it is
     * the receiver's noise and quantisation, and at drive-off it moved a good heading by
     * 0.2 deg; the fix updates everything but the heading then (the odometer, the course
     * at speed and the turns observe it) */
    const nav_real_t v2 = fix->has_vel ? fix->v_enu_mps[0] * fix->v_enu_mps[0] +
                                             fix->v_enu_mps[1] * fix->v_enu_mps[1]
                                       : NAV_C(0.0);
    const nav_real_t v_min = APP_GNSS_HEADING_SPEED_SIGMAS * ss;
    fu->ekf.hold_heading = v2 < v_min * v_min ? 1u : 0u;
    const int rp = ekf_gnss_position(&fu->ekf, c->nav, &then, &fix->pos, cfg->gnss_lever_b_m,
                                     sh, shw, sv, APP_GNSS_GATE_SIGMA, r_scale, fix->has_h,
                                     as_state);
    int rv = 1;
    if (fix->has_vel) {
        const nav_real_t *vthen = gnss_time_velocity_then(c->time, &when);
        /* the velocity's errors correlated over gnss_vel_corr_s (the receiver's own
         * smoothing): the variance inflated by it over the fix interval, as the height's */
        const nav_real_t vc_s = cfg->gnss_vel_corr_s;
        const nav_real_t sv_mps = ss * nav_sqrt(corr_spans(vc_s, ep_s));
        rv = cfg->gnss_vel_up == GNSS_VUP_NONE
                 ? ekf_gnss_velocity_horizontal(&fu->ekf, vthen, fix->v_enu_mps, sv_mps,
                                                APP_GNSS_GATE_SIGMA)
                 : ekf_gnss_velocity(&fu->ekf, vthen, fix->v_enu_mps, sv_mps,
                                     APP_GNSS_VUP_SIGMA_RATIO * sv_mps, APP_GNSS_GATE_SIGMA);
        /* refused: the witness of a diverged filter without wheel speeds (diverged); the
         * rows are gated together, so 3 vertical refusals in a row count too */
        fu->vel_gated_run =
            rv == 0 ? (uint8_t)(fu->vel_gated_run < 255u ? fu->vel_gated_run + 1u : 255u) : 0u;
    }
    if (rp < 2 || rv == 0) {
        app_diag_reject(c->diag, &c->diag->health->gnss_rejected); /* beyond the gate */
    }
    fu->ekf.hold_heading = 0u;
    gate_run(fu, c, rp >= 2, sh); /* rp >= 2: the horizontal fix was taken */
    feed_back(fu, c);
    if (starting != 0u) {
        /* the first interval's change of velocity is from here, the start's own fix taken:
         * one left from before (a filter stopped long ago, or never run, at 0) put a car
         * started moving 15 m/s ahead of itself, 150 m/s^2 over 0.1 s, into its first
         * odometer update's sigma, and so did the start fix's correction of the velocity */
        for (int i = 0; i < 2; i++) {
            fu->v_prev_pred_mps[i] = c->nav->v_n_mps[i];
        }
    }
    int was_reset;
    const fusion_action_t act = supervise(fu, c, &was_reset);
    *adopt = !was_reset;
    return act;
}

/* ------------------------------------------------------ raw GNSS (issue #20) ----
 * Tightly coupled: each satellite's pseudorange and range rate a scalar update of the
 * filter (ekf_rows_pseudorange, ekf_rows_range_rate), docs/kalman.md "Tightly coupled
 * GNSS". Per epoch:
 * 1. the epoch's time of validity in the navigator's history, as for a fix;
 * 2. the clock: moved on by its drift since the last epoch; estimated afresh from the
 *    median of the satellites' residuals at the first epoch, after a gap longer than
 *    APP_RAW_CLOCK_KEEP_S, after the filter was reopened, and at a receiver clock reset
 *    (flagged, or every residual off by the same beyond APP_RAW_CLOCK_JUMP_SIGMAS of the
 *    clock's sigma and APP_RAW_CLOCK_JUMP_M);
 * 3. fault exclusion: a satellite whose residual differs from the epoch's median by more
 *    than APP_RAW_FDE_SIGMAS of (its sigma and the filter's position sigma) is excluded
 *    and counted (a multipath or a tracking fault: the median is the other satellites'
 *    consensus on the clock; with two satellites that disagree, neither can be told
 *    right, and both are excluded);
 * 4. the updates, highest satellite first, each gated by the filter (APP_GNSS_GATE_SIGMA);
 *    the pseudoranges' variances multiplied by gnss_corr_s over the epoch interval, as
 *    the fixes' height (errors correlated from epoch to epoch), the range rates' not. */

#define RAW_MAX ((int)GNSS_RAW_MAX_SATS)

/* the median of n values (1 <= n <= RAW_MAX): a sorted copy */
static nav_real_t median_of(const nav_real_t *v, int n)
{
    nav_real_t s[RAW_MAX];
    for (int i = 0; i < RAW_MAX; i++) {
        s[i] = NAV_C(0.0);
    }
    for (int i = 0; i < n; i++) {
        nav_real_t x = v[i];
        int j = i;
        while (j > 0 && s[j - 1] > x) {
            s[j] = s[j - 1];
            j--;
        }
        s[j] = x;
    }
    return (n % 2) != 0 ? s[n / 2] : NAV_C(0.5) * (s[n / 2 - 1] + s[n / 2]);
}

/* one satellite's pseudorange sigma (m) and range-rate sigma (m/s): the receiver's, no
 * better than the floors (a receiver's tracking figure is not its range error) */
static nav_real_t pr_sigma_m(const gnss_raw_sat_t *m)
{
    const nav_real_t el = (nav_real_t)m->elevation_deg * NAV_C(0.017453292519943295);
    const nav_real_t s_el = nav_sin(el > APP_RAW_EL_MIN_RAD ? el : APP_RAW_EL_MIN_RAD);
    const nav_real_t floor_m = APP_RAW_PR_SIGMA_ZENITH_M / s_el;
    const nav_real_t d = (nav_real_t)m->pr_sigma_lsb * NAV_C(0.1);
    return d > floor_m ? d : floor_m;
}

__attribute__((noinline)) static nav_real_t rr_sigma_mps(const gnss_raw_sat_t *m)
{
    const nav_real_t d = (nav_real_t)m->rr_sigma_lsb * NAV_C(0.01);
    return d > APP_RAW_RR_SIGMA_MIN_MPS ? d : APP_RAW_RR_SIGMA_MIN_MPS;
}

typedef struct {
    const fusion_ctx_t *c;
    const gnss_raw_asm_t *g;
    geo_pos_t then;
    const nav_real_t *v_then;
    nav_real_t v2_then;       /* its horizontal speed squared, m^2/s^2 */
    int n;                    /* satellites */
    uint8_t slot[RAW_MAX];    /* their slots, highest first */
    int use_bias;             /* the ranges' correlated errors are the state db */
    ekf_antenna_t ant;        /* the antenna at the epoch */
} raw_epoch_t;

/* satellite i's row and innovation (rate = 0: its pseudorange, 1: its range rate) from its
 * geometry of this epoch (raw_geometry); 0 when it has none (refused geometry, a
 * measurement flagged invalid, not finite) */
static int raw_row(const fusion_t *fu, const raw_epoch_t *e, int i, int rate,
                   nav_real_t h[EKF_N], nav_real_t *z)
{
    const gnss_raw_sat_t *m = &e->g->sat[e->slot[i]];
    const uint8_t valid = rate != 0 ? m->rr_valid : m->pr_valid;
    if (fu->raw_geo_ok[i] == 0u || valid == 0u) {
        return 0;
    }
    if (rate != 0) {
        ekf_rows_range_rate(&fu->ekf, e->c->nav, e->v_then, fu->w_b_last_rps,
                            e->c->cfg->gnss_lever_b_m, &fu->raw_geo[i],
                            (nav_real_t)m->rr_lsb * NAV_C(0.01), h, z);
    } else {
        ekf_rows_pseudorange(&fu->ekf, &e->ant, &fu->raw_geo[i], m->pr_lsb, e->use_bias, h, z);
        if (fu->raw_corr_on[i] != 0u) {
            *z += fu->raw_corr_m[i]; /* computed minus (measured less its learnt bias) */
        }
    }
    return nav_isfinite(*z) ? 1 : 0;
}

/* every satellite's geometry from the epoch's antenna, once; a satellite whose position
 * is not a GNSS satellite's (gnss_geom_sat), whose declared elevation is not its geometry's
 * (APP_RAW_EL_SIN_MISMATCH), or whose pseudorange is not its range within
 * APP_RAW_PR_PLAUSIBLE_M (a receiver clock within 3 ms of GPS time; a range of 0 or a
 * corrupt one) is refused and counted in bad_value, in an epoch fused or only learnt from
 * (a client found the learnt-from epochs' refusals uncounted) */
static void raw_geometry(fusion_t *fu, const raw_epoch_t *e)
{
    for (int i = 0; i < e->n; i++) {
        const gnss_raw_sat_t *m = &e->g->sat[e->slot[i]];
        const int geo_ok =
            ekf_sat_geometry(&e->ant, m->pos_lsb, m->vel_lsb, &fu->raw_geo[i]) == NAV_OK &&
            nav_fabs(fu->raw_geo[i].los_enu[2] -
                     nav_sin((nav_real_t)m->elevation_deg * NAV_C(0.017453292519943295))) <=
                APP_RAW_EL_SIN_MISMATCH;
        const int pr_ok = geo_ok && (m->pr_valid == 0u ||
                                     nav_fabs(gnss_geom_pr_residual_m(m->pr_lsb, &fu->raw_geo[i].g,
                                                                      0)) <=
                                         APP_RAW_PR_PLAUSIBLE_M);
        fu->raw_geo_ok[i] = (uint8_t)(pr_ok ? 1u : 0u);
        if (!pr_ok) {
            app_diag_reject(e->c->diag, &e->c->diag->health->bad_value);
        }
    }
}

/* residuals (computed minus measured) of every satellite's pseudorange (rate = 0) or
 * range rate (rate = 1) against the filter's estimates, ok[i] = 0 where none (z[i] then 0,
 * or not finite) */
static void raw_residuals(const fusion_t *fu, const raw_epoch_t *e, int rate, nav_real_t *z,
                          uint8_t *ok)
{
    for (int i = 0; i < e->n; i++) {
        nav_real_t h[EKF_N];
        z[i] = NAV_C(0.0);
        ok[i] = (uint8_t)raw_row(fu, e, i, rate, h, &z[i]);
    }
}

/* the median of the usable residuals; 0 when there is none (n_ok = 0) */
static nav_real_t median_ok(const nav_real_t *z, const uint8_t *ok, int n, int *n_ok)
{
    nav_real_t v[RAW_MAX];
    int k = 0;
    for (int i = 0; i < n; i++) {
        if (ok[i] != 0u) {
            v[k] = z[i];
            k++;
        }
    }
    *n_ok = k;
    return k > 0 ? median_of(v, k) : NAV_C(0.0);
}

/* the filter's 1-sigma along any direction of the three states from i0 (position, velocity) */
static nav_real_t sigma3(const ekf_t *k, int i0)
{
    return nav_sqrt(k->P[i0][i0] + k->P[i0 + 1][i0 + 1] + k->P[i0 + 2][i0 + 2]);
}

/* The clock estimated afresh from the median residuals (the clock bias and drift that make
 * them zero), sigmas: the filter's position (velocity) sigma and the clock's floor. */
static void raw_clock_start(fusion_t *fu, const raw_epoch_t *e, nav_real_t med_pr,
                            nav_real_t med_rr, int n_rr)
{
    ekf_t *k = &fu->ekf;
    /* without a range rate the drift is not measured: kept, as unknown as a clock nobody
     * measured (the ranges' change from epoch to epoch then finds it) */
    const nav_real_t sd =
        n_rr > 0 ? sigma3(k, EKF_DV) + APP_RAW_DRIFT_SIGMA_MPS : k->cfg.clk_drift_mps;
    ekf_clock_start(k, med_pr, med_rr, sigma3(k, EKF_DR) + APP_RAW_CLOCK_SIGMA_M, sd);
    fu->clock_valid = 1u;
    app_count(&e->c->raw->clock_starts);
}

/* fault exclusion (step 3 above): ok[i] cleared for a residual too far from the median;
 * sigma(i) the measurement's, s_state the filter's sigma along any line of sight.
 * Returns the number excluded. */
static int raw_exclude(const raw_epoch_t *e, const nav_real_t *z, uint8_t *ok, int rate,
                       nav_real_t s_state)
{
    int n_ok;
    const nav_real_t med = median_ok(z, ok, e->n, &n_ok);
    int n_out = 0;
    if (n_ok < 2) {
        return 0;
    }
    for (int i = 0; i < e->n; i++) {
        if (ok[i] == 0u) {
            continue;
        }
        const gnss_raw_sat_t *m = &e->g->sat[e->slot[i]];
        const nav_real_t s = rate != 0 ? rr_sigma_mps(m) : pr_sigma_m(m);
        const nav_real_t lim = APP_RAW_FDE_SIGMAS * nav_sqrt(s * s + s_state * s_state);
        if (nav_fabs(z[i] - med) > lim) {
            ok[i] = 0u;
            n_out++;
        }
    }
    return n_out;
}

/* the scalar updates of the usable measurements (rate = 0 pseudoranges, 1 range rates);
 * returns the number applied, *gated the number the gate refused */
static int raw_updates(fusion_t *fu, const raw_epoch_t *e, const uint8_t *ok, int rate,
                       nav_real_t r_scale, int *gated, int *corrected)
{
    const app_config_t *cfg = e->c->cfg;
    int used = 0;
    for (int i = 0; i < e->n; i++) {
        if (ok[i] == 0u) {
            continue;
        }
        const gnss_raw_sat_t *m = &e->g->sat[e->slot[i]];
        nav_real_t h[EKF_N], z;
        if (raw_row(fu, e, i, rate, h, &z) == 0) {
            continue;
        }
        nav_real_t r;
        if (rate != 0) {
            const nav_real_t s = rr_sigma_mps(m);
            r = s * s;
        } else {
            /* with the state db the white part (gnss_white_ratio), else all of it,
             * its variance inflated by r_scale */
            const nav_real_t s = pr_sigma_m(m) * (e->use_bias != 0 ? cfg->gnss_white_ratio
                                                                    : NAV_C(1.0));
            r = s * s * r_scale;
        }
        const int rc = ekf_update(&fu->ekf, h, z, r, APP_GNSS_GATE_SIGMA);
        if (rc == 1) {
            used++;
            if (rate == 0 && fu->raw_corr_on[i] != 0u) {
                (*corrected)++;
            }
        } else if (rc == 0) {
            (*gated)++;
        } else {
            /* not finite: not counted as a measurement */
        }
    }
    return used;
}

/* the epoch's satellites with a complete set of frames, highest first */
static void raw_order(raw_epoch_t *e, const gnss_raw_close_t *closed)
{
    e->n = 0;
    uint32_t bit = 1u;
    for (int s = 0; s < RAW_MAX; s++, bit <<= 1u) {
        if ((closed->complete & bit) == 0u) {
            continue;
        }
        const uint8_t el = e->g->sat[s].elevation_deg;
        int j = e->n;
        while (j > 0 && e->g->sat[e->slot[j - 1]].elevation_deg < el) {
            e->slot[j] = e->slot[j - 1];
            j--;
        }
        e->slot[j] = (uint8_t)s;
        e->n++;
    }
}

/* The receiver's time since the last raw epoch fused (GPS time of week, ms, across the
 * week's end, gnss_tow_diff_ms): the clock moves on by its drift over that, not over the
 * arrival times. Beyond APP_RAW_CLOCK_KEEP_S when there is no such epoch, or it is older
 * than that by the IMU's sample count (no order to keep with it: a receiver restarted, a
 * new drive; the clock is estimated afresh). 0 for an epoch not after it (a replay). */
static int raw_interval(fusion_t *fu, const fusion_ctx_t *c, uint32_t tow_ms, nav_real_t *dt_s)
{
    const uint64_t n = c->diag->n_samples;
    *dt_s = APP_RAW_CLOCK_KEEP_S + NAV_C(1.0);
    const uint64_t since = n - fu->raw_sample;
    if (fu->raw_have_tow != 0u &&
        (nav_real_t)since > APP_RAW_CLOCK_KEEP_S * (nav_real_t)c->cfg->imu_rate_hz) {
        fu->raw_have_tow = 0u;
    }
    if (fu->raw_have_tow == 0u) {
        return 1;
    }
    const int64_t d_ms = gnss_tow_diff_ms(tow_ms, fu->raw_tow_ms);
    if (d_ms <= 0) {
        return 0;
    }
    *dt_s = (nav_real_t)d_ms * NAV_C(0.001);
    return 1;
}

/* gnss_input = both while the receiver gives fixes: the epoch's satellites' residuals
 * against the filter's position, which follows the fixes (with the correlated error state
 * db along each line of sight when it is one, as the fused ranges are), learnt as their
 * biases (raw_bias.h); nothing is fused, and only a satellite that is not one
 * (raw_geometry: its position, elevation or range implausible) is refused and counted; the
 * fault exclusion's and the gate's verdicts are not (the epoch's fix is fused). Learnt
 * only while the filter takes the fixes (one within gap_samples: APP_RAW_BOTH_GAP_EPOCHS of
 * their interval) with its horizontal sigma below APP_RAW_BIAS_POS_SIGMA_M and the car at
 * APP_RAW_BIAS_SPEED_MPS or more, from the satellites the fault exclusion keeps, when at
 * least APP_RAW_BIAS_MIN_SATS are left. */
static uint8_t raw_learning(const fusion_t *fu, uint64_t n_samples, nav_real_t v2_then,
                            nav_real_t gap_samples)
{
    /* as a positive test: a sigma or speed that is not a number learns nothing */
    return (app_stamp_within(&fu->fix, n_samples, (uint64_t)gap_samples) &&
            ekf_sigma_h_m(&fu->ekf) < APP_RAW_BIAS_POS_SIGMA_M &&
            v2_then >= APP_RAW_BIAS_SPEED_MPS * APP_RAW_BIAS_SPEED_MPS)
               ? 1u
               : 0u;
}

/* the learning of an epoch raw_learning lets learn (its geometry formed) */
static void raw_learn(fusion_t *fu, const raw_epoch_t *e, uint32_t tow_ms)
{
    nav_real_t z[RAW_MAX];
    uint8_t ok[RAW_MAX];
    raw_residuals(fu, e, 0, z, ok);
    (void)raw_exclude(e, z, ok, 0, sigma3(&fu->ekf, EKF_DR));
    int n_ok;
    const nav_real_t med = median_ok(z, ok, e->n, &n_ok);
    if (n_ok < APP_RAW_BIAS_MIN_SATS) {
        return;
    }
    for (int i = 0; i < e->n; i++) {
        z[i] = med - z[i]; /* measured minus computed, less the median */
    }
    raw_bias_learn(&fu->raw_bias, e->g->sat, e->slot, z, ok, e->n, tow_ms, fu->gnss_ep_typ_s);
}

/* A fused epoch's residuals (computed minus measured) and their usable flags, indexed by
 * rate: 0 the pseudoranges (m), 1 the range rates (m/s) */
typedef struct {
    nav_real_t z[2][RAW_MAX];
    uint8_t ok[2][RAW_MAX];
} raw_resid_t;

/* Steps 2 and 3 of a fused epoch: the clock moved on (or estimated afresh: counted in
 * clock_starts, and a receiver clock reset or jump in clock_jumps), the epoch recorded as
 * the last fused one (raw_tow_ms, raw_sample), then the fault exclusion; the residuals and
 * their usable flags in r. Returns the number excluded, or -1 when no pseudorange is
 * usable (nothing to measure with). */
static int raw_clock_exclude(fusion_t *fu, const raw_epoch_t *e, nav_real_t dt_s,
                             uint32_t tow_ms, int clock_reset, raw_resid_t *r)
{
    /* a reopened filter (here or by a fix) forgot the position the clock went with */
    if (fu->ekf.n_reopened != fu->raw_reopens) {
        fu->raw_reopens = fu->ekf.n_reopened;
        fu->clock_valid = 0u;
    }
    if (fu->clock_valid != 0u && dt_s <= APP_RAW_CLOCK_KEEP_S) {
        ekf_clock_advance(&fu->ekf, dt_s);
    } else {
        fu->clock_valid = 0u;
    }
    fu->raw_tow_ms = tow_ms;
    fu->raw_have_tow = 1u;
    fu->raw_sample = e->c->diag->n_samples;
    raw_residuals(fu, e, 0, r->z[0], r->ok[0]);
    raw_residuals(fu, e, 1, r->z[1], r->ok[1]);
    int n_pr, n_rr;
    const nav_real_t med_pr = median_ok(r->z[0], r->ok[0], e->n, &n_pr);
    const nav_real_t med_rr = median_ok(r->z[1], r->ok[1], e->n, &n_rr);
    if (n_pr == 0) {
        return -1;
    }
    const nav_real_t s_clk = ekf_state_sigma(&fu->ekf, EKF_CB);
    const int jumped = fu->clock_valid != 0u && n_pr >= 2 &&
                       nav_fabs(med_pr) > APP_RAW_CLOCK_JUMP_M &&
                       nav_fabs(med_pr) > APP_RAW_CLOCK_JUMP_SIGMAS * s_clk;
    if (clock_reset != 0 || jumped) {
        app_count(&e->c->raw->clock_jumps);
        fu->clock_valid = 0u;
    }
    if (fu->clock_valid == 0u) {
        raw_clock_start(fu, e, med_pr, med_rr, n_rr);
        raw_residuals(fu, e, 0, r->z[0], r->ok[0]);
        raw_residuals(fu, e, 1, r->z[1], r->ok[1]);
    }
    const int out = raw_exclude(e, r->z[0], r->ok[0], 0, sigma3(&fu->ekf, EKF_DR));
    return out + raw_exclude(e, r->z[1], r->ok[1], 1, sigma3(&fu->ekf, EKF_DV));
}

/* A fused epoch (gnss_input = raw, or both without fixes): steps 2 to 4 and the
 * supervision after them */
static fusion_action_t raw_fuse(fusion_t *fu, const raw_epoch_t *e, nav_real_t dt_s,
                                uint32_t tow_ms, int clock_reset, int *adopt)
{
    const fusion_ctx_t *c = e->c;
    const app_config_t *cfg = c->cfg;
    raw_resid_t r;
    const int out = raw_clock_exclude(fu, e, dt_s, tow_ms, clock_reset, &r);
    if (out < 0) {
        return FUSION_GO_ON;
    }
    /* 4. the updates: the pseudoranges' errors correlated over gnss_corr_s (longer while
     * the car stands: fusion_rx_corr_s), as the state db (its stationary sigma the correlated
     * part of the epoch's median range sigma) or by inflating their variance. A standing
     * antenna's multipath holds for its ranges as for its fixes: with the ranges left at
     * gnss_corr_s at a stop, gnss_input both with two satellites ended the Kingston drive's
     * first two 60-s outages (in its first standstill) 1.30 and 1.37 m off instead of 0.52
     * and 0.47 m, its ranges counting for more than the fixes before them. */
    const nav_real_t ep_s = dt_s > APP_GNSS_EPOCH_MIN_S ? dt_s : APP_GNSS_EPOCH_MIN_S;
    const nav_real_t corr_s = fusion_rx_corr_s(c->cfg, c->odo);
    nav_real_t r_scale = corr_spans(corr_s, ep_s);
    if (e->use_bias != 0) {
        nav_real_t sg[RAW_MAX];
        for (int i = 0; i < e->n; i++) {
            sg[i] = pr_sigma_m(&e->g->sat[e->slot[i]]);
        }
        /* the ranges see the height as the horizontal (taken as if the geometry's DOP were
         * 1 per axis, as the horizontal's): the same correlated part for both */
        const nav_real_t sc_raw = median_of(sg, e->n) * gnss_corr_part(cfg);
        bias_step(fu, cfg, c->diag->n_samples, sc_raw, corr_s, sc_raw);
        r_scale = NAV_C(1.0);
    }
    const nav_real_t v_min = APP_GNSS_HEADING_SPEED_SIGMAS * APP_RAW_RR_SIGMA_MIN_MPS;
    fu->ekf.hold_heading = e->v2_then < v_min * v_min ? 1u : 0u;
    int gated = 0;
    int corrected = 0;
    const int pr_used = raw_updates(fu, e, r.ok[0], 0, r_scale, &gated, &corrected);
    const int rr_used = raw_updates(fu, e, r.ok[1], 1, NAV_C(1.0), &gated, &corrected);
    fu->ekf.hold_heading = 0u;
    app_count_n(&c->raw->pr_used, (uint32_t)pr_used);
    app_count_n(&c->raw->rr_used, (uint32_t)rr_used);
    app_count_n(&c->raw->excluded, (uint32_t)out);
    app_count_n(&c->raw->gated, (uint32_t)gated);
    app_count_n(&c->raw->corrected, (uint32_t)corrected);
    if (pr_used > 0) {
        app_count(&c->raw->epochs_used);
    }
    if (out + gated > 0) {
        app_diag_reject(c->diag, &c->diag->health->gnss_rejected); /* once per epoch */
    }
    gate_run(fu, c, pr_used > 0, APP_RAW_PR_SIGMA_ZENITH_M);
    feed_back(fu, c);
    int was_reset;
    const fusion_action_t act = supervise(fu, c, &was_reset);
    *adopt = !was_reset;
    return act;
}

/* Out of line (noinline), as the helpers above: the link inlined it at its three calls
 * (a fix, a calibration at a fix, a commanded start), 48 bytes more of the ECU's flash. */
__attribute__((noinline)) nav_real_t fusion_fix_sigma_axis_m(nav_real_t hacc_m)
{
    return nav_clamp(hacc_m * APP_GNSS_HACC_PER_AXIS, APP_GNSS_SIGMA_FLOOR_M, APP_GNSS_SIGMA_MAX_M);
}

fusion_action_t fusion_raw(fusion_t *fu, const fusion_ctx_t *c, const gnss_raw_asm_t *g,
                           const gnss_raw_close_t *closed, uint32_t tow_ms, int clock_reset,
                           int *adopt)
{
    const app_config_t *cfg = c->cfg;
    *adopt = 0;
    if (!fu->on || cfg->gnss_input == GNSS_INPUT_FIX) {
        return FUSION_GO_ON;
    }
    /* gnss_input = both: the raw measurements only while the receiver gives no fixes (none
     * offered for APP_RAW_BOTH_GAP_EPOCHS of its usual intervals): an epoch's fix and its raw
     * measurements are the same information, whichever comes first on the bus */
    const nav_real_t gap_samples =
        APP_RAW_BOTH_GAP_EPOCHS * fu->gnss_ep_typ_s * (nav_real_t)cfg->imu_rate_hz;
    const int fixes_come = cfg->gnss_input == GNSS_INPUT_BOTH &&
                           fu->gnss_ep_typ_s > NAV_C(0.0) &&
                           (nav_real_t)(c->diag->n_samples - fu->prev_fix_sample) < gap_samples;
    const int fuse = !fixes_come;
    nav_real_t dt_s = NAV_C(0.0);
    if (fuse && !raw_interval(fu, c, tow_ms, &dt_s)) {
        app_diag_reject(c->diag, &c->diag->health->bad_counter);
        return FUSION_GO_ON;
    }
    /* 1. the epoch's time of validity: a fused epoch aligns the receiver's time, one only
     * learnt from peeks (the epoch's fix is the one that aligns it) */
    const nav_real_t latency_s = gnss_time_latency(c->time, cfg->gnss_latency_s);
    gnss_when_t when;
    if (fixes_come) {
        when = gnss_time_peek(c->time, c->diag->t_us, cfg->imu_rate_hz, tow_ms, latency_s);
    } else {
        when = gnss_time_align(c->time, c->diag->t_us, cfg->imu_rate_hz, tow_ms, latency_s);
        if (when.jumped) {
            app_count(&c->diag->health->time_jumps);
        }
    }
    raw_epoch_t e;
    nav_real_t d[3];
    /* an epoch only learnt from is not refused (its fix is the one that counts) */
    if ((fixes_come && !when.in_history) || !epoch_then(c, &when, d, &e.then)) {
        return FUSION_GO_ON;
    }
    e.c = c;
    e.g = g;
    e.v_then = gnss_time_velocity_then(c->time, &when);
    e.v2_then = e.v_then[0] * e.v_then[0] + e.v_then[1] * e.v_then[1];
    /* an epoch only learnt from: nothing to form when it would not be (a parked car) */
    if (fixes_come && raw_learning(fu, c->diag->n_samples, e.v2_then, gap_samples) == 0u) {
        return FUSION_GO_ON;
    }
    if (ekf_antenna(c->nav, &e.then, cfg->gnss_lever_b_m, &e.ant) != NAV_OK) {
        if (fuse) {
            app_diag_reject(c->diag, &c->diag->health->gnss_rejected);
        }
        return FUSION_GO_ON;
    }
    raw_order(&e, closed);
    raw_geometry(fu, &e);
    /* each satellite's learnt bias, removed from its range when fused (none learnt from) */
    for (int i = 0; i < e.n; i++) {
        const gnss_raw_sat_t *m = &g->sat[e.slot[i]];
        fu->raw_corr_on[i] = (fuse && raw_bias_of(&fu->raw_bias, m->system, m->sv_id, tow_ms,
                                                  &fu->raw_corr_m[i]) != 0)
                                 ? 1u
                                 : 0u;
    }
    /* the correlated errors as the fixes' state db when it is one */
    e.use_bias = bias_is_state(fu, cfg);
    if (fixes_come) {
        raw_learn(fu, &e, tow_ms);
        return FUSION_GO_ON;
    }
    return raw_fuse(fu, &e, dt_s, tow_ms, clock_reset, adopt);
}
