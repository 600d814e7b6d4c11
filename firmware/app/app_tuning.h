/*
 * app_tuning.h - the application's tuning constants, in one place, each with its unit and
 * where its value comes from. Protocol facts (identifiers, signal ranges, value tables,
 * HealthFlags bits, status pages) are not here: they come from the DBC through the
 * generated codec (firmware/can/gen/). Configuration that an integrator sets per car or
 * per IMU is not here either: it is app_config_t (app_config.h).
 *
 * A few may be overridden on the compiler's command line for experiments (#ifndef);
 * the firmware is built and tested with the values below.
 */
#ifndef NAVECU_APP_TUNING_H
#define NAVECU_APP_TUNING_H

#include "nav_types.h"

/* ---- time base and input supervision (docs/can.md, docs/reliability.md) ---- */
/* NAV_Status flags IMU_STALE when no IMU sample came for this long on the HAL clock */
#define APP_IMU_STALE_US 500000u
/* IMU counter steps above this are held until successors confirm them (a corrupt
 * counter must not move time ahead): 4 = the lost frames the next sample may follow */
#define APP_IMU_MAX_DELTA 4
/* samples held for a counter jump, one following the other, before the next confirms the
 * jump: 2, so two wrong counters above 4 that happen to follow each other (a sender's
 * fault) are not a gap; with one, such a pair put a whole counter cycle (150 ms at 100 Hz)
 * into the IMU time for good (docs/reliability.md, bad counters; two wrong steps of +4 in a
 * row, taken at once, still can: docs/can.md) */
#define APP_IMU_JUMP_HELD 2u
/* a command's alive counter may step by at most this (CMD_MAX_DELTA - 1 lost frames) */
#define APP_CMD_MAX_DELTA 3
/* IMU gaps up to this are bridged by interpolation; longer ones re-acquire (docs/can.md) */
#define APP_MAX_BRIDGE_MS 200u
/* a receive-time gap counts as whole lost counter cycles (15 samples) only when it
 * exceeds the counter's step by more than this many periods: half a cycle, so a replay
 * up to ~7x slower than real time is never taken for a gap (docs/can.md, IMU) */
#define APP_IMU_GAP_SLACK_PERIODS 7u
/* imu_time = stamped (imu_stream.h): a sample's IMU_Time interval, over the samples it
 * covers, must lie within [1/APP_IMU_TIME_BAND_DIV, APP_IMU_TIME_BAND_MUL/APP_IMU_TIME_BAND_DIV]
 * = [0.5, 1.5] nominal periods (the IMU's clock cannot be 50 % off its rate; a rate that
 * far off is the rate check's, imu_rate.h); a sample outside it, or with a stamp not after
 * the previous one, is refused; APP_IMU_TIME_RESYNC refusals in a row, the last a stamp
 * behind the last one taken (the clock jumped back), restart the stamps' time base there,
 * as a gap too long to bridge (a jump forward is a gap the stamps see) */
#define APP_IMU_TIME_BAND_DIV 2u
#define APP_IMU_TIME_BAND_MUL 3u
#define APP_IMU_TIME_RESYNC 3u
/* IMU plausibility (imu_stream.c): an axis repeating its raw value this long while
 * another axis of the same sensor shows the sensor's noise is stuck. The noise shown: the
 * mean |second difference| of the raw increments over the last one to two half-windows
 * at least the preset's per-sample noise sigma (gyro: gyro_arw * sqrt(1/imu_rate), in
 * LSB; white noise gives 1.95 sigma), and never less than APP_IMU_NOISE_MIN_LSB: a
 * smooth motion quantized with its remainder carried gives at most 2 LSB (ideal data).
 * Saturation at 99.9 % of the configured range (the sensor clips there). */
#define APP_IMU_STUCK_S 2u
#define APP_IMU_NOISE_MIN_LSB 4u
#define APP_IMU_SAT_FRACTION NAV_C(0.999)

/* the IMU rate against the data (imu_rate.h): an interval between GNSS epochs is off-rate
 * beyond 1/APP_IMU_RATE_TOL_DIV (5 %) + APP_IMU_RATE_QUANT samples (each epoch's arrival
 * is known to one sample, and one more of latency jitter); a mismatch is APP_IMU_RATE_RUN
 * off-rate intervals in a row at one rate, together off by more than that plus a steady
 * change of the receiver's latency of APP_IMU_RATE_LATE_MS (2.5 times the 0.1 s latency
 * of a u-blox-class receiver; isolated late epochs of any size form no run); it ends
 * with APP_IMU_RATE_RUN on-rate intervals. Longer intervals (or going back in
 * TimeOfWeek: a clock jump) restart the measurement. */
#define APP_IMU_RATE_TOL_DIV 20
#define APP_IMU_RATE_QUANT 2
#define APP_IMU_RATE_LATE_MS 250
#define APP_IMU_RATE_RUN 2u
#define APP_IMU_RATE_MAX_MS 600000u

/* ---- how long NAV_Status flags an event (docs/can.md, HealthFlags) ---- */
#define APP_FLAG_HOLD_S 1u          /* REJECTED, IMU_GAP, IMU_SATURATED, ODO_REJECTED */
#define APP_FLAG_HOLD_LONG_S 10u    /* FILTER_RESET, IMU_SUSPECT */
#define APP_NO_GNSS_S 2u            /* NO_GNSS: no usable epoch for this long */
#define APP_GNSS_FIX_FRESH_S 2u     /* mode GnssIns while the last fix used is this recent */

/* ---- GNSS epochs ---- */
#define APP_GNSS_MIN_SATS 4u
/* GNSS course is a heading only when moving this fast (course noise ~ sigma_v / v) */
#define APP_GNSS_COURSE_MIN_MPS NAV_C(5.0)
/* a GNSS fix updates the heading only beyond this many speed sigmas (its course sigma is
 * speed sigma / speed: 0.1 rad here, the sigma of a commanded heading; 0.5 m/s at the
 * 0.05 m/s floor of the speed sigma) */
#define APP_GNSS_HEADING_SPEED_SIGMAS NAV_C(10.0)
/* below this GNSS speed the vehicle may be still (levelling, GNSS-only initialisation) */
#define APP_GNSS_STILL_MPS NAV_C(0.3)
/* the GNSS-only initialisation's course is the heading at the stop while the z gyro's
 * turn since it (its uncompensated bias included) stays within this: 2 deg, so that with
 * the course's own error the start stays within the filter's default 5 deg heading sigma
 * (the default automotive preset's turn-on bias, 0.001 rad/s, spends it in 35 s of driving
 * below 5 m/s: an older course is no heading) */
#define APP_GNSS_COURSE_TURN_RAD NAV_C(0.0349)
/* in-motion alignment (align.h): a window of at least this long between two driving
 * epochs (the along-track acceleration's error is ~ sqrt(2) sigma_v / window), restarted
 * beyond the longest; driving means a speed of this many sigmas (course sigma ~ 0.1 rad at
 * most); the heading sigma is sigma_v / v, not below the floor (the course's own lag and
 * the GNSS velocity's time of validity); the odometer's speed sigma for the acceleration */
/* a GNSS speed above this is motion for the commands (commands.h): 5 sigma of a poor
 * receiver's speed at rest (0.2 m/s); between APP_GNSS_STILL_MPS and this, levelling
 * restarts */
#define APP_CMD_MOVING_GNSS_MPS NAV_C(1.0)
#define APP_INMOTION_WINDOW_S NAV_C(1.0)
#define APP_INMOTION_WINDOW_MAX_S NAV_C(3.0)
#define APP_INMOTION_SPEED_SIGMAS NAV_C(10.0)
#define APP_INMOTION_HEADING_SIGMA_MIN_RAD NAV_C(0.008727) /* 0.5 deg */
#define APP_INMOTION_TILT_SIGMA_MIN_RAD NAV_C(0.008727)    /* 0.5 deg, the filter's default */
#define APP_INMOTION_ODO_SIGMA_MPS NAV_C(0.05)
/* the receiver's horizontal accuracy is a 2-D figure: per axis 1/sqrt(2) of it */
#define APP_GNSS_HACC_PER_AXIS NAV_C(0.7071)

/* The gyro's in-run bias instability (params.toml gyro_bias_rw_rps_rts) is the floor B of
 * its Allan deviation, stored as B sqrt(2 / 300 s): the z gyro's in-run state (ekf.h,
 * state 24) takes s = B / EKF_GM_ADEV_PEAK = the field x sqrt(150 s) / EKF_GM_ADEV_PEAK,
 * this factor (a literal: computed from EKF_GM_ADEV_PEAK in float32 it rounds differently
 * and changes the outputs; test_ekf checks the two agree) */
#define APP_GYRO_GM_SIGMA_PER_RW NAV_C(19.8383)
/* an instability's Allan floor B from its field stored as B sqrt(2 / 300 s) (params.toml
 * accel_bias_rw_mps2_rts): sqrt(150 s) (nvstore.c, a record without the forward
 * accelerometer's own figure) */
#define APP_INSTABILITY_PER_RW NAV_C(12.24745)
/* the speed sigma a fix's horizontal accuracy implies (1/s): range-rate noise over range
 * noise, both multiplied by the same DOP (0.05 m/s Doppler, 1.5 m code: 0.03) */
#define APP_GNSS_SACC_PER_HACC NAV_C(0.03)
#define APP_GNSS_SIGMA_MAX_M NAV_C(100.0)  /* larger declared sigmas are clamped */
#define APP_GNSS_SIGMA_V_MIN_M NAV_C(0.5)  /* vertical sigma floor */
#ifndef APP_GNSS_SIGMA_FLOOR_M
#define APP_GNSS_SIGMA_FLOOR_M NAV_C(1.0)  /* horizontal sigma floor per axis */
#endif
#define APP_GNSS_SACC_MIN_MPS NAV_C(0.05)  /* velocity sigma clamp */
#define APP_GNSS_SACC_MAX_MPS NAV_C(2.0)
#define APP_GNSS_VUP_SIGMA_RATIO NAV_C(1.5) /* vertical velocity sigma / horizontal */
#define APP_GNSS_EPOCH_MIN_S NAV_C(0.05)    /* shortest fix interval in the correlation model */
/* The receiver's correlated horizontal error is a state of the filter (fusion.c) when its
 * correlation time spans this many fix intervals: consecutive errors then agree within
 * exp(-1/10) (90 %), and the variance inflation, which treats the fixes as independent
 * and spreads one correlation time's information over them, no longer describes how the
 * error moves (the state does, and keeps the part no number of fixes averages away).
 * Below it the fixes are nearly independent and the inflation is kept. */
#define APP_GNSS_STATE_MIN_FIXES NAV_C(10.0)
/* GNSS time alignment (gnss_time.h): an epoch later than the running minimum offset by
 * more than 0.5 s three times in a row, earlier by more than 1 s or later by more than
 * 10 s is a receiver clock jump; the minimum may creep by 50 ppm of elapsed time */
#define APP_GNSS_LATE_US 500000
#define APP_GNSS_LATE_RUN 3u
#define APP_GNSS_JUMP_EARLY_US 1000000
#define APP_GNSS_JUMP_LATE_US 10000000
#define APP_GNSS_DRIFT_DIV 20000 /* 1 / 50 ppm */
/* velocity history for the GNSS time of validity: entries at most 10 ms apart, so 64
 * cover 0.64 s: the latency allowed (0.5 s) plus lateness */
#define APP_VHIST 64u
#define APP_VHIST_MAX_HZ 100u
/* the receiver's latency estimated from the data (gnss_time_learn): candidates 0..0.5 s
 * (the parameter's range) every 10 ms; each on-time epoch adds, per candidate, the squared
 * horizontal difference of its velocity from the navigator's that long before its
 * arrival, in units of the speed sigma, at most 25 (5 sigma: one bad epoch cannot decide);
 * the sums fade by 1/200 an epoch (40 s at 5 Hz: a changed receiver is learnt anew). A
 * candidate replaces the one in use (the parameter's at first) when its sum is lower by
 * 20: a log-likelihood ratio of 10, noise alone almost never reaches it */
#define APP_GNSS_LAT_BINS 51u
#define APP_GNSS_LAT_STEP_S NAV_C(0.01)
#define APP_GNSS_LAT_TERM_MAX NAV_C(25.0)
#define APP_GNSS_LAT_FADE NAV_C(0.995)
#define APP_GNSS_LAT_EVIDENCE NAV_C(20.0)

/* ---- Kalman filter scheduling and measurement noise (docs/kalman.md) ---- */
#define APP_EKF_PRED_HZ 10u /* covariance propagation and odometer updates */
#define APP_ZUPT_SIGMA_MPS NAV_C(0.01)
/* a slow wheel-speed source: its zero hides creeping below one step for a period */
#define APP_ZUPT_SIGMA_PER_PERIOD_MPS NAV_C(0.1)
#define APP_ODO_SIGMA_MPS NAV_C(0.05)    /* quantisation, latency and tyre slip */
#define APP_ODO_SIGMA_SPEED_FRAC NAV_C(0.01) /* plus 1 % of speed */
/* a slow source's speed is late and averaged: noise grows with acceleration x period */
#define APP_ODO_SIGMA_ACC_PERIOD NAV_C(0.5)
/* A source slower than the updates (each reading used once) is a quantised speed the car's
 * ECU has filtered: its error holds until the speed has moved by a step, over several
 * readings (the Kingston OBD speed's residual: 0.73 from one 1-s reading to the next, 0.36
 * three apart; tools/kingston/analyse.py). Its variance is multiplied by this correlation
 * time over the source's period, as the receiver's fixes' are (docs/kalman.md). */
#define APP_ODO_SLOW_CORR_S NAV_C(3.0)
/* the horizontal specific force beyond which zero wheels are not a standstill (fusion.c) */
#define APP_STILL_ACC_MPS2 NAV_C(0.3)
/* Zero wheels are a standstill only while the yaw rate stays below 0.5 deg/s
 * (odo_default_config), one IMU sample at a time; a sample's own noise is ARW x
 * sqrt(imu_rate), 0.33 deg/s for the simulator's automotive MEMS (2 deg/sqrt(h)) at
 * 100 Hz, so that test would end every standstill within 0.5 s. The threshold is at
 * least this many of those sigmas (app_init): a standing car leaves it once in 16 000
 * samples (Gaussian, 4 sigma), a turn beyond it is still seen in one sample. */
#define APP_STILL_RATE_SIGMAS NAV_C(4.0)
#define APP_NHC_SIGMA_MPS NAV_C(0.1)     /* side slip in turns, suspension motion */
/* a car body's pitch on its suspension per m/s^2 of acceleration along the track (dive
 * under braking, squat under acceleration): about 0.5 deg per m/s^2 for a passenger car
 * (1.5-3 deg at a 0.5 g stop; the simulator's default body 0.4 deg); the vertical
 * constraint's sigma grows by it times the speed and the acceleration (fusion.c) */
#define APP_DIVE_RAD_PER_MPS2 NAV_C(0.0087)
/* the longest time standing added to the receiver's error correlation time (fusion.c
 * fusion_rx_corr_s): the satellites' motion changes a standing antenna's multipath within
 * minutes (not measured beyond 20 s: the Kingston drive's stops) */
#define APP_GNSS_STAND_CORR_MAX_S NAV_C(300.0)
#define APP_ODO_MIN_SPEED_MPS NAV_C(0.5) /* below this the speed rows are not used */
/* odo_direction = navigator: reversing once the navigator moves backward faster than this
 * (half the slowest speed the rows use) */
#define APP_ODO_REVERSE_MPS NAV_C(0.25)
#define APP_ODO_GATE_SIGMA NAV_C(5.0)    /* odometer and standstill innovation gate */
#define APP_EKF_POS_SIGMA_MIN_M NAV_C(1.0) /* the filter's initial position sigma floor */
/* a commanded known position (CMD_KnownPosition: a map's or a surveyed point), 1 sigma per
 * axis: the dead reckoning's accuracy at its start and at a one-point calibration
 * (dr_acc.h, calib_sigmas) */
#define APP_KNOWN_POS_SIGMA_M NAV_C(1.0)
/* GNSS innovation gate (position and velocity), in sigmas: 3, for receivers' multipath
 * outliers that are far from Gaussian. Refusals in a row for longer than
 * APP_GNSS_REOPEN_S reopen the filter's position (3 x the fix's sigma) and velocity
 * (1 m/s): measured on the Kingston drive (docs/kalman.md), a 5-sigma gate lets
 * multipath in and a filter that trusts itself after one bad fix refuses the good ones
 * for half a minute. */
#ifndef APP_GNSS_GATE_SIGMA
#define APP_GNSS_GATE_SIGMA NAV_C(3.0)
#endif
#ifndef APP_GNSS_REOPEN_S
#define APP_GNSS_REOPEN_S 3u
#endif
#define APP_GNSS_REOPEN_POS_SIGMAS NAV_C(3.0)
#define APP_GNSS_REOPEN_VEL_MPS NAV_C(1.0)
#define APP_GNSS_REOPEN_AFTER 2u /* refused fixes in a row before a reopen may happen */

/* ---- tightly coupled GNSS (issue #20, fusion.c, docs/kalman.md) ----
 * A pseudorange is no better than a code receiver's range error: APP_RAW_PR_SIGMA_ZENITH_M
 * at the zenith over sin(elevation) (the atmosphere's residuals and multipath grow toward
 * the horizon; elevations below APP_RAW_EL_MIN_RAD count as that), whatever the receiver
 * declares (its tracking figure: the Kingston receiver says 0.05 m). Range rates: at least
 * APP_RAW_RR_SIGMA_MIN_MPS (a Doppler's noise and the satellites' velocity errors). */
#define APP_RAW_PR_SIGMA_ZENITH_M NAV_C(3.0)
#define APP_RAW_EL_MIN_RAD NAV_C(0.1745) /* 10 deg */
#define APP_RAW_RR_SIGMA_MIN_MPS NAV_C(0.2)
/* the clock estimated afresh: its sigma is the filter's position (velocity) sigma plus
 * these, for the satellites' errors in the median */
#define APP_RAW_CLOCK_SIGMA_M NAV_C(10.0)
#define APP_RAW_DRIFT_SIGMA_MPS NAV_C(0.5)
/* the clock carried over a gap of at most this (a TCXO's drift random walk grows the bias
 * sigma to ~50 m in 60 s) */
#define APP_RAW_CLOCK_KEEP_S NAV_C(60.0)
/* a receiver clock reset found: every residual (their median) beyond both */
#define APP_RAW_CLOCK_JUMP_M NAV_C(1000.0)
#define APP_RAW_CLOCK_JUMP_SIGMAS NAV_C(10.0)
/* gnss_input = both: raw epochs are fused when no fix came for this many of the
 * receiver's usual fix intervals (1.5: a fix late by half an interval is still coming) */
#define APP_RAW_BOTH_GAP_EPOCHS NAV_C(1.5)
/* GPS time of week: its length, ms */
#define APP_WEEK_MS 604800000u
/* a pseudorange farther than this from its satellite's range is no measurement (a
 * receiver's clock stays within 1 ms of GPS time: 3e5 m; 3 ms allowed) */
#define APP_RAW_PR_PLAUSIBLE_M NAV_C(1.0e6)
/* a satellite's declared elevation (GNSS_RawRange, whole degrees) against its geometry's
 * from the antenna: their sines more than this apart (6 deg at the horizon, 26 deg at
 * 60 deg; the rounding is 0.009 at most) is not this satellite's elevation, refused with
 * CntBadValue: it sets the satellite's sigma floor and its place in the fusion order */
#define APP_RAW_EL_SIN_MISMATCH NAV_C(0.1)
/* fault exclusion: a residual this many sigmas from the epoch's median */
#define APP_RAW_FDE_SIGMAS NAV_C(5.0)
/* each satellite's range bias learnt while fixes come (raw_bias.h, gnss_input = both):
 * averaged over APP_RAW_BIAS_TAU_S of driving, ten times the tens of seconds a moving car's
 * multipath lasts (Kingston: 27 s median) and short against the biases' tens of minutes
 * (orbit and clock 1 h, atmosphere 30 min); used once learnt for a minute (the average of
 * several multipath times), for up to 10 min after it was last learnt (a street canyon of
 * minutes; the slow errors still about 0.7 correlated); learnt from epochs of at least
 * APP_RAW_BIAS_MIN_SATS satellites (their median is the clock) at APP_RAW_BIAS_SPEED_MPS or
 * more (parked, a satellite's multipath is the spot's constant, not its bias) */
#define APP_RAW_BIAS_TAU_S NAV_C(300.0)
/* an epoch counts for the receiver's time since the satellite's last one, at most this: a
 * residual after a gap is one sample of a multipath that lasts tens of seconds */
#define APP_RAW_BIAS_STEP_MAX_S NAV_C(10.0)
#define APP_RAW_BIAS_MIN_S NAV_C(60.0)
#define APP_RAW_BIAS_KEEP_MS 600000u
#define APP_RAW_BIAS_MIN_SATS 4
#define APP_RAW_BIAS_SPEED_MPS NAV_C(2.0)
/* ... and while the filter takes the fixes with its horizontal position known better than
 * a zenith range (a position error along each line of sight would be learnt as the
 * satellites' biases: after a canyon, while the fixes pull the filter back) */
#define APP_RAW_BIAS_POS_SIGMA_M APP_RAW_PR_SIGMA_ZENITH_M

/* ---- filter supervision (docs/reliability.md) ---- */
#define APP_FILTER_REOPEN_LIMIT 3u /* covariance reopens without a fix taken: diverged */
/* ... and diverged whatever the odometer and the course say once the fixes have been
 * refused for this long, without a gap of APP_GNSS_REOPEN_S between them (fusion.c
 * gate_run, diverged; the fault drive's GNSS jumps last 26 s) */
#define APP_FILTER_LOCKOUT_S 60u
/* A stuck IMU axis's samples (app.c sample_noise): the motion's 1 sigma per sample is a
 * car's, not the sensor's range: a yaw rate of 30 deg/s (a roundabout 15-20 deg/s, a
 * parking turn up to 40 deg/s) and a specific force change of 3 m/s^2 (brisk braking or
 * cornering), each at most the sensor's range. With the range instead (300 deg/s), a z
 * gyro stuck for good grew the attitude errors to radians, beyond the error model's small
 * angles, and the filter learnt the mounting 5 deg and the odometer scale 4.6 % off
 * (a review, seed 1: 349 m RMS against 80 m without the noise). */
#define APP_STUCK_RATE_RPS NAV_C(0.5236)
#define APP_STUCK_ACCEL_MPS2 NAV_C(3.0)
/* A stuck yaw gyro's rate replaced by the car's own (landnav_car_yaw): the lateral
 * specific force over the forward speed (a car that does not slip sideways turns at
 * a_lat / v), from this speed; below it 0: what the force does not know, about 0.05 m/s^2
 * with the filter's accelerometer bias taken off (a roll error, the bias's residual), is
 * 1 deg/s at 3 m/s; without the filter the accelerometer's whole bias (docs/kalman.md) */
#define APP_STUCK_YAW_MIN_MPS NAV_C(3.0)
/* GNSS course vs the filter's heading: 10 deg */
#define APP_COURSE_MISMATCH_RAD NAV_C(0.17453)
/* angles beyond this are not the navigator's (a non-finite or runaway value) */
#define APP_ANGLE_SANE_RAD NAV_C(64.0)

/* ---- calibration and its storage (docs/odometry.md) ---- */
/* The filter's odometer scale and mounting yaw are adopted once what their errors would do to
 * a dead reckoning is within the 0.15 % of the distance driven that issue #18 holds a dead
 * reckoning after calibration to: a scale error s puts s of the distance along the track, a
 * mounting yaw error psi (rad) psi of it across, so the root sum square of the two sigmas
 * (sqrt(s^2 + psi^2), 0.0015; 1.5 mrad = 0.086 deg for the yaw alone). The scale's sigma is
 * that of k + o / v_mean (calib_filter_scale). Before this the bound was 0.1 % on each, a
 * box whose corner (0.141 %) a calibration good in one part and fair in the other could not
 * pass: on the Kingston drive (1 Hz whole-km/h OBD speed) the scale's sigma ends the hour at
 * 0.116 % with the mounting yaw's at 0.049 deg (0.144 % together), and nothing was ever
 * adopted there; now it is, at 3471 s (navecu's summary, `make kingston OUTAGES=none`;
 * docs/kingston.md). Stored when they moved by more than 2 sigma. */
#define APP_CAL_ADOPT_SIGMA NAV_C(0.0015)
#define APP_CAL_CHANGED_SIGMAS NAV_C(2.0)
#define APP_CAL_SAVE_MIN_S 600u /* filter calibration saves: flash wear, 10 k cycles */
#define APP_STORE_MIN_S 10u     /* StoreCalibration at most this often */

#endif /* NAVECU_APP_TUNING_H */
