/* GENERATED FILE - DO NOT EDIT. Source: firmware/app/params.toml.
 * Regenerate with 'make params' (tools/gen_params.py); 'make test' fails if stale. */

#ifndef NAVECU_PARAMS_CLI_H
#define NAVECU_PARAMS_CLI_H

#include "app_params.h"

/* a parameter's command-line option: its value in `unit`, range [min, max] (min
 * excluded with min_exclusive), times to_si gives the field's SI value; an enum's
 * value is one of `values` (names separated by '|') */
typedef struct {
    const char *option;
    app_param_id_t id;
    const char *unit;
    double min, max, to_si;
    const char *values;
    const char *description;
} params_cli_t;

#define PARAMS_CLI_N 42

static const params_cli_t params_cli[PARAMS_CLI_N] = {
    {"--imu-rate-hz", APP_PARAM_IMU_RATE_HZ, "Hz", 10.0, 400.0, 1.0, "", "IMU sample rate: one IMU_Rate + IMU_Accel pair per sample"},
    {"--nav-rate-hz", APP_PARAM_NAV_RATE_HZ, "Hz", 1.0, 400.0, 1.0, "", "NAV_Position, NAV_Height, NAV_Velocity, NAV_Attitude and NAV_Time rate (at most the IMU rate; the host lowers the default to it); sent every round(IMU rate / rate) IMU samples: a rate that does not divide the IMU rate goes out at the IMU rate over that whole number (60 Hz at 100 Hz: every 2nd sample, 50 Hz; 67 Hz: every sample, 100 Hz)"},
    {"--status-rate-hz", APP_PARAM_STATUS_RATE_HZ, "Hz", 1.0, 400.0, 1.0, "", "NAV_Status page 0 (and NAV_Accuracy) rate, at most the IMU rate; sent every round(IMU rate / rate) IMU samples, as nav_rate_hz"},
    {"--dyn-rate-hz", APP_PARAM_DYN_RATE_HZ, "Hz", 0.0, 400.0, 1.0, "", "NAV_Rates, NAV_AttitudeRates, NAV_Accel, NAV_AccelEnu rate (at most the IMU rate; 0: not sent); sent every round(IMU rate / rate) IMU samples, as nav_rate_hz"},
    {"--level-s", APP_PARAM_LEVEL_S, "s", 1.0, 600.0, 1.0, "", "accelerometer levelling time at rest before navigation starts"},
    {"--odo-axle", APP_PARAM_ODO_AXLE, "", 0.0, 1.0, 1.0, "rear|front", "the wheels that measure the distance (docs/odometry.md)"},
    {"--odo-track-m", APP_PARAM_ODO_TRACK_M, "m", 0.5, 3.0, 1.0, "", "track of the measuring axle: the turn's inner/outer wheel difference"},
    {"--odo-wheelbase-m", APP_PARAM_ODO_WHEELBASE_M, "m", 1.0, 6.0, 1.0, "", "wheelbase, for the front axle's steering correction"},
    {"--odo-lever-m", APP_PARAM_ODO_LEVER_B_M, "m", -10.0, 10.0, 1.0, "", "the odometer's reference point (middle of the measuring axle) from the IMU, body axes x right, y forward, z up"},
    {"--odo-lever-sigma-m", APP_PARAM_ODO_LEVER_SIGMA_M, "m", 0.0, 5.0, 1.0, "", "1-sigma uncertainty of odo_lever_b_m: the default 1 m is an ECU somewhere between the axles with its lever arm not measured; in a turn the no-side-slip constraint allows the yaw rate times it"},
    {"--odo-step-mps", APP_PARAM_ODO_STEP_MPS, "m/s", 0.001, 1.0, 1.0, "", "the wheel-speed source's resolution, one step of its speed signal: half a step is the 1-sigma of the filter's speed offset state (a signal the car's ECU truncates reads half a step low; docs/kalman.md); by default the vehicle profile's wheel speed signal's DBC scale (navecu's WheelSpeeds 0.02 m/s, the RAV4's 0.01 km/h); an OBD-II speed (PID 0x0D) forwarded into WheelSpeeds is whole km/h, 0.2778 m/s"},
    {"--odo-direction", APP_PARAM_ODO_DIRECTION, "", 0.0, 1.0, 1.0, "as_read|navigator", "where the wheel speeds' direction of travel comes from: as read (navecu's signed WheelSpeeds, or the vehicle profile's gear); navigator, for a source of magnitudes that cannot tell reversing (an OBD-II vehicle speed, PID 0x0D, forwarded into WheelSpeeds): the sign of the navigator's forward velocity (docs/odometry.md)"},
    {"--odo-latency-ms", APP_PARAM_ODO_LATENCY_S, "ms", 0.0, 500.0, 0.001, "", "wheel-speed latency: the moment a reading describes to its arrival among the IMU samples (the ABS module's filtering and the bus, less the IMU data's own latency); each reading is moved on to the moment the filter uses it, this plus its age, with the navigator's along-track acceleration (docs/kalman.md, the odometer's latency)"},
    {"--cal-min-base-m", APP_PARAM_CAL_MIN_BASE_M, "m", 0.0, 100000.0, 1.0, "", "a one-point calibration closer than this to its base is refused: a point's error e gives about e / base in dH (rad) and in mu"},
    {"--imu-mount-deg", APP_PARAM_IMU_MOUNT_RAD, "deg", -180.0, 180.0, 0.017453292519943295, "", "the IMU's attitude in the vehicle, roll, pitch, yaw (firmware/app/mounting.h: 3-1-2 as the navigation attitude; yaw clockwise, pitch nose up, roll right side down): any rotation, e.g. 0,0,90 turned right, 180,0,0 upside down; the filter estimates the small residual yaw and pitch"},
    {"--imu-mount-source", APP_PARAM_IMU_MOUNT_SOURCE, "", 0.0, 1.0, 1.0, "fixed|automatic", "fixed: imu_mount_deg is the mounting; automatic: navecu estimates it from the data (firmware/app/mount_est.h: gravity at rest, the accelerations and turns against the wheel speeds) and holds navigation (mode Fault, NAV_Calibration MountState estimating) until the estimate converges, then starts from GNSS while driving with it; app_adopt_mounting (RoutineControl 0x0204) copies it into imu_mount_deg"},
    {"--mount-est-sigma-deg", APP_PARAM_MOUNT_EST_SIGMA_RAD, "deg", 0.01, 10.0, 0.017453292519943295, "", "the automatic mounting estimate is converged when its roll/pitch and its yaw 1-sigma are below this (and the excitation reached mount_est_excite_m2ps3)"},
    {"--mount-est-excite-m2ps3", APP_PARAM_MOUNT_EST_EXCITE_M2PS3, "m^2/s^3", 0.0, 100000.0, 1.0, "", "the excitation the automatic mounting estimate needs before it converges: the sum of (forward acceleration^2 + lateral acceleration^2) x time of the drive (50: about 50 s of 1 m/s^2, a few minutes of ordinary driving)"},
    {"--gyro-arw-dpsh", APP_PARAM_GYRO_ARW_RAD_RTS, "deg/sqrt(h)", 1e-06, 100.0, 0.0002908882086657216, "", "gyro angle random walk (app_init copies it into the IMU link's stuck-axis test and the standstill's yaw-rate threshold: after ECUReset)"},
    {"--gyro-bias-dph", APP_PARAM_GYRO_BIAS_RPS, "deg/h", 1e-06, 10000.0, 4.84813681109536e-06, "", "gyro turn-on bias, 1 sigma: weighs the bias estimate at standstill and in the filter"},
    {"--accel-bias-mg", APP_PARAM_ACCEL_BIAS_MPS2, "mg", 0.0001, 1000.0, 0.00980665, "", "accelerometer turn-on bias, 1 sigma"},
    {"--gyro-instability-dph", APP_PARAM_GYRO_BIAS_RW_RPS_RTS, "deg/h", 1e-06, 10000.0, 3.9584871301292104e-07, "", "gyro in-run bias instability, the floor of its Allan deviation (the data sheet's figure): the filter takes the z gyro's as a first-order Gauss-Markov process whose Allan peak is this floor (sigma = it / 0.6174, IEEE Std 952 annex C) with the correlation time gyro_bias_corr_time_s, and the x and y gyros' as a random walk of sigma sqrt(2 / 300 s); the dead reckoning without GNSS takes it as that walk for its own accuracy (docs/odometry.md)"},
    {"--gyro-bias-corr-time-s", APP_PARAM_GYRO_BIAS_CORR_TIME_S, "s", 10.0, 100000.0, 1.0, "", "the correlation time of the z gyro's in-run bias (the Gauss-Markov process of gyro_bias_rw_rps_rts; its Allan deviation peaks at 1.89 times it), and of the forward accelerometer's (accel_fwd_instability_mps2): how long the filter holds what it learnt of that bias once GNSS is lost (at least 10 s: a hundred of the filter's prediction intervals, 0.1 s, so that its step I + F dt follows the decay to 5e-5 per step)"},
    {"--accel-instability-mg", APP_PARAM_ACCEL_BIAS_RW_MPS2_RTS, "mg", 1e-05, 1000.0, 0.0008007096195354885, "", "accelerometer in-run bias instability over 300 s, taken as a random walk as the x and y gyros' is (the x and z accelerometers'; the forward one's is accel_fwd_instability_mps2)"},
    {"--accel-fwd-instability-mg", APP_PARAM_ACCEL_FWD_INSTABILITY_MPS2, "mg", 1e-05, 1000.0, 0.00980665, "", "the forward (body y) accelerometer's in-run bias instability, the floor of its Allan deviation (the data sheet's figure, or the axis's own measured at rest): the filter takes it as a first-order Gauss-Markov process whose Allan peak is this floor (sigma = it / 0.6174) with the correlation time gyro_bias_corr_time_s, as the z gyro's; through a GNSS outage the odometer sees this bias and the pitch only together, so its wander is what the height's accuracy must follow (docs/kalman.md)"},
    {"--gyro-range-dps", APP_PARAM_GYRO_RANGE_RPS, "deg/s", 1.0, 5000.0, 0.017453292519943295, "", "the gyro's measurement range: a rate at or beyond it is saturated (counted, flagged, and the filter takes the sample as uncertain by the range: docs/kalman.md)"},
    {"--accel-range-mps2", APP_PARAM_ACCEL_RANGE_MPS2, "m/s^2", 9.80665, 2000.0, 1.0, "", "the accelerometer's measurement range (default 8 g): as the gyro's. At least 1 g (9.80665): below it gravity alone saturates the vertical axis of a car at rest, and every sample would be flagged; no accelerometer of a car has such a range"},
    {"--gyro-scale-ppm", APP_PARAM_GYRO_SCALE, "ppm", 0.1, 100000.0, 1e-06, "", "the z gyro's scale factor error, 1 sigma (its data sheet's sensitivity tolerance): the prior of the filter's scale state (docs/kalman.md), which the turns with GNSS calibrate; a 1 % error turns the heading 0.9 deg wrong in each 90 deg turn"},
    {"--gnss-latency-ms", APP_PARAM_GNSS_LATENCY_S, "ms", 0.0, 500.0, 0.001, "", "receiver latency: a fix's time of validity to its arrival (more when TimeOfWeek shows a late epoch)"},
    {"--gnss-corr-s", APP_PARAM_GNSS_CORR_S, "s", 0.0, 600.0, 1.0, "", "correlation time of the receiver's position errors, and of its pseudoranges' when raw measurements are fused (docs/can.md, raw GNSS; docs/kalman.md): 0 for white errors"},
    {"--gnss-vel-corr-s", APP_PARAM_GNSS_VEL_CORR_S, "s", 0.0, 60.0, 1.0, "", "correlation time of the receiver's velocity errors (its tracking loops' and navigation filter's smoothing; docs/kalman.md): fixes closer than it carry less than independent ones, and the velocity's variance is multiplied by it over the fix interval; 0: independent from epoch to epoch"},
    {"--gnss-white-ratio", APP_PARAM_GNSS_WHITE_RATIO, "", 0.05, 1.0, 1.0, "", "the white part of the receiver's declared per-axis accuracy, as a ratio of the sigmas (tracking noise, fast multipath; the rest, atmosphere, orbits and clocks, is correlated over gnss_corr_s and a state of the filter when that spans 10 fix intervals, docs/kalman.md; the same split of a fused pseudorange's sigma): a code receiver's about 1/3 (0.7 of 2.1 m per axis), a differential one's about 1/2"},
    {"--gnss-accuracy", APP_PARAM_GNSS_ACCURACY, "", 0.0, 1.0, 1.0, "reported|declared", "where the fixes' accuracies come from: the receiver's GNSS_Status/GNSS_Velocity fields, or declared here for a receiver that reports none (gnss_hacc_m, gnss_vacc_m, gnss_sacc_mps: its datasheet's figures)"},
    {"--gnss-hacc-m", APP_PARAM_GNSS_HACC_M, "m", 0.1, 102.3, 1.0, "", "declared horizontal accuracy (68 % radius, as HorizAccuracy), used with gnss_accuracy = declared"},
    {"--gnss-vacc-m", APP_PARAM_GNSS_VACC_M, "m", 0.1, 102.3, 1.0, "", "declared vertical accuracy (1 sigma, as VertAccuracy), used with gnss_accuracy = declared"},
    {"--gnss-sacc-mps", APP_PARAM_GNSS_SACC_MPS, "m/s", 0.01, 1.5, 1.0, "", "declared speed accuracy (as SpeedAccuracy), used with gnss_accuracy = declared"},
    {"--gnss-vel-up", APP_PARAM_GNSS_VEL_UP, "", 0.0, 1.0, 1.0, "measured|none", "whether the receiver measures the vertical velocity: with none, GNSS_Velocity's VelUp is not fused (its east and north are)"},
    {"--gnss-input", APP_PARAM_GNSS_INPUT, "", 0.0, 2.0, 1.0, "fix|raw|both", "what the filter fuses of the receiver (issue #20, docs/kalman.md): its fixes (loosely coupled); its raw pseudoranges and range rates (tightly coupled; fixes only start the navigation); or both, the fixes while the receiver gives them and the raw measurements while it gives none (fewer than four satellites: an urban canyon), each satellite's range with its bias removed, learnt from the raw epochs that came with the fixes (firmware/app/raw_bias.h)"},
    {"--gnss-lever-m", APP_PARAM_GNSS_LEVER_B_M, "m", -10.0, 10.0, 1.0, "", "the GNSS antenna from the IMU, body axes x right, y forward, z up"},
    {"--uds-request-id", APP_PARAM_UDS_REQUEST_ID, "", 1.0, 2047.0, 1.0, "", "the UDS server's physical request ID (11-bit; docs/can.md, Diagnostics (UDS)): frames on it go to ISO-TP, never to navigation; read-only over UDS (the boards set their receive filters at start)"},
    {"--uds-response-id", APP_PARAM_UDS_RESPONSE_ID, "", 1.0, 2047.0, 1.0, "", "the UDS server's response ID (11-bit, by convention request + 8); read-only over UDS"},
    {"--imu-time", APP_PARAM_IMU_TIME, "", 0.0, 1.0, 1.0, "grid|stamped", "the IMU's sample time: grid, every sample 1/imu_rate_hz long; or stamped, each sample as long as its IMU_Time stamps say (an IMU not on an exact grid, integrated without resampling; imu_rate_hz is then its nominal rate, docs/configuration.md)"},
};

/* --imu-preset NAME: the presets' descriptions, in app_presets' order */
static const char *const params_cli_preset_about[APP_PRESET_N] = {
    "consumer / phone MEMS (a windshield phone or dashcam IMU)",
    "automotive MEMS: the ESP/airbag-class IMU a car's navigation ECU usually carries (the default)",
    "tactical grade (fibre-optic or high-end MEMS)",
    "navigation grade (ring-laser class), seed 000's IMU",
};

#endif /* NAVECU_PARAMS_CLI_H */
