/*
 * ekf.h - the compact error-state Kalman filter: 26 states, float32, fixed-size storage,
 * closed loop (seed 001: "the INS solution is reconciled with the GNSS solution by a Kalman
 * filter with 18 parameters": those 18, the receiver's correlated horizontal error, the
 * receiver's clock for raw measurements (issue #20), the odometer's speed offset and the
 * yaw gyro's scale factor and its in-run bias, the forward accelerometer's in-run bias
 * (issue #18); docs/kalman.md).
 *
 * Error state x, all "computed minus true":
 *   0..2   dr    position error, ENU metres at the IMU
 *   3..5   dv    velocity error, ENU m/s
 *   6..8   psi   attitude error, rad: C_bn(computed) = (I - [psi x]) C_bn(true), so the
 *                heading error is +psi_U (Titterton & Weston, "Strapdown Inertial
 *                Navigation Technology", 2nd ed., sec. 12.3: the psi-angle form)
 *   9..11  bg    residual gyro bias, body, rad/s
 *   12..14 ba    residual accelerometer bias, body, m/s^2
 *   15     k     odometer scale error (reading = (1 + k) x true; seed 000's mu)
 *   16     mp    IMU-to-car mounting pitch (IMU nose up of the car's), rad
 *   17     my    IMU-to-car mounting yaw (IMU forward axis clockwise of the car's), rad
 *   18..19 db    the receiver's correlated horizontal position error, E and N, m: the
 *                filter's estimate gnss_bias_m minus the truth (a first-order Gauss-Markov
 *                process, ekf_gnss_bias_step; the fix's white part is the update's noise)
 *   20     dcb   the receiver clock bias, m (c times seconds): the estimate clock_dmm
 *                minus the truth
 *   21     dcd   the receiver clock drift, m/s: the estimate clock_drift_mps minus the truth
 *                (seed 001's test stand: the receiver's clock errors; Brown & Hwang,
 *                "Introduction to Random Signals and Applied Kalman Filtering", 4th ed.,
 *                sec. 9.3: the two-state clock model)
 *   22     ob    odometer speed offset, m/s (reading = (1 + k) x true + ob in the direction
 *                of travel; the estimate odo_offset_mps minus the truth): a speed signal
 *                of whole steps that the car's ECU truncates reads half a step low on
 *                average, whatever the speed (OBD-II's vehicle speed, PID 0x0D, is whole
 *                km/h: 0.14 m/s; the Kingston drive's reads 0.10..0.17 m/s low from 2 to
 *                16 m/s, a scale error from -14 % to -0.8 %: docs/odometry.md)
 *   23     sg    residual scale factor error of the body z gyro: the compensated rate is
 *                (1 + sg) x the true one (a residual, as bg, fed back into the estimate
 *                gyro_scale_z): a MEMS gyro's sensitivity is known to
 *                about 1 %, and each 90 deg turn then turns the heading 0.9 deg wrong;
 *                the GNSS course through the turns observes it (u-blox's automotive dead
 *                reckoning calibrates it likewise)
 *   24     gz    residual in-run bias of the body z gyro, rad/s, as bg (what the
 *                compensated rate still has: the truth minus the estimate gz_rps, fed back
 *                into it): a first-order Gauss-Markov process of steady-state sigma
 *                gz_sigma_rps and correlation time gz_tau_s. The data sheet's bias instability is
 *                the floor of the gyro's Allan deviation, a bias that wanders over about
 *                a minute and comes back (IEEE Std 952-1997 annex C; El-Sheimy, Hou & Niu,
 *                "Analysis and modeling of inertial sensors using Allan variance", IEEE
 *                Trans. Instrum. Meas. 57(1), 2008): a random walk in bg would hold a
 *                wandering learnt just before GNSS is lost for the whole outage and keep
 *                growing past what the gyro ever does; this state lets the estimate decay
 *                with the process and bounds its variance. State 11 (bg z) is then the
 *                turn-on bias, constant.
 *   25     af    residual in-run bias of the body y (forward) accelerometer, m/s^2, as ba
 *                (the truth minus the estimate af_mps2, fed back into it): a first-order
 *                Gauss-Markov process of steady-state sigma af_sigma_mps2 and correlation
 *                time af_tau_s, as state 24 for the z gyro. Through a GNSS outage the
 *                odometer sees the forward bias and the pitch only together (g dtheta -
 *                dba_y), so a bias that wanders is taken for a pitch and the height
 *                follows it at the speed times that pitch: a random walk cannot follow
 *                the wander (docs/kalman.md, "The forward accelerometer's in-run bias").
 *                State 13 (ba y) is then the turn-on bias, constant.
 * Dynamics (Titterton & Weston eqs 12.6, 12.8, 12.10, small terms of order v/R dropped):
 *   d(dr)/dt = dv
 *   d(dv)/dt = [f_n x] psi + C_bn ba - [(2 w_ie + w_en) x] dv + (0, 0, 2 g / R) dr_U
 *              + C_bn e_y af
 *   d(psi)/dt = -[w_in x] psi - C_bn bg - C_bn e_z w_z sg  (w_z the compensated body z
 *   rate, the interval's mean)
 *   d(psi)/dt also gets -C_bn e_z gz; d(gz)/dt = -gz / gz_tau_s + white (psd
 *   2 gz_sigma^2 / gz_tau_s), the estimate gz_rps decaying with it; af likewise with
 *   af_sigma_mps2 and af_tau_s, the estimate af_mps2.
 *   x and y gyro biases, x and z accelerometer biases, k, mounting, sg: random walks; the
 *   z gyro's and the y accelerometer's turn-on biases: constant.
 *   d(dcb)/dt = dcd + white (psd clk_b_psd), d(dcd)/dt = white (psd clk_d_psd): the clock
 *   states are coupled to nothing else until a raw measurement correlates them, so a filter
 *   fed only fixes computes the other states exactly as without them.
 *   ob: a random walk (odo_offset_rw_mps_rts).
 *   db: constant in ekf_predict (no coupling to the motion); its decay exp(-dt/tau) and
 *   driving noise are applied once per fix by ekf_gnss_bias_step, which is exact since
 *   the decay is a scaling of its own rows and columns only.
 * Prediction uses Phi = I + F dt over an interval of several IMU samples with the mean
 * specific force, and P = Phi P Phi^T + Q computed through F's 52 non-zero entries
 * (ekf_predict). Updates are scalar and sequential (no matrix inverse), in the symmetric
 * expansion of the Joseph form, each gated by its normalised innovation (chi-square).
 */
#ifndef NAVECU_EKF_H
#define NAVECU_EKF_H

#include "gnss_geom.h"
#include "sins.h"

#define EKF_N 26
/* The Allan deviation of a first-order Gauss-Markov process of sigma s peaks at
 * EKF_GM_ADEV_PEAK s (at 1.89 correlation times; IEEE Std 952-1997 annex C; computed by
 * tools/sim/sensors.py as GM_ADEV_PEAK_FACTOR): a data sheet's bias instability B, the
 * floor of that deviation, is the process of sigma B / EKF_GM_ADEV_PEAK (states 24, 25). */
#define EKF_GM_ADEV_PEAK NAV_C(0.61736)
enum {
    EKF_DR = 0,
    EKF_DV = 3,
    EKF_PSI = 6,
    EKF_BG = 9,
    EKF_BA = 12,
    EKF_K = 15,
    EKF_MP = 16,
    EKF_MY = 17,
    EKF_GB = 18, /* E, N */
    EKF_CB = 20, /* receiver clock bias, m */
    EKF_CD = 21, /* receiver clock drift, m/s */
    EKF_OB = 22, /* odometer speed offset, m/s */
    EKF_SG = 23, /* body z gyro scale factor error */
    EKF_GZ = 24, /* body z gyro in-run bias, first-order Gauss-Markov */
    EKF_AF = 25, /* body y (forward) accelerometer in-run bias, first-order Gauss-Markov */
};

typedef struct {
    /* initial 1-sigma */
    nav_real_t pos_m, vel_mps, tilt_rad, heading_rad, bg_rps, ba_mps2, k, mount_rad;
    nav_real_t gnss_bias_m;      /* the receiver's correlated error per axis (ekf_init) */
    nav_real_t clk_bias_m, clk_drift_mps; /* the receiver clock's, until ekf_clock_start */
    nav_real_t odo_offset_mps;   /* the odometer's speed offset */
    nav_real_t gyro_scale;       /* the body z gyro's scale factor error */
    /* noise densities */
    nav_real_t arw_rad_rts;      /* gyro angle random walk, rad/sqrt(s) */
    nav_real_t vrw_mps_rts;      /* accelerometer velocity random walk, m/s/sqrt(s) */
    nav_real_t bg_rw_rps_rts;    /* gyro bias random walk, rad/s/sqrt(s) */
    nav_real_t ba_rw_mps2_rts;   /* accelerometer bias random walk */
    nav_real_t k_rw_rts;         /* odometer scale random walk (tyre wear, pressure), 1/sqrt(s) */
    nav_real_t mount_rw_rad_rts; /* mounting random walk (load, suspension) */
    nav_real_t odo_offset_rw_mps_rts; /* odometer offset random walk, m/s/sqrt(s) */
    nav_real_t gyro_scale_rw_rts; /* z gyro scale factor random walk, 1/sqrt(s) */
    nav_real_t gz_sigma_rps;     /* the z gyro's in-run bias: its steady-state 1-sigma */
    nav_real_t gz_tau_s;         /* and its correlation time, s */
    nav_real_t af_sigma_mps2;    /* the forward accelerometer's in-run bias: its 1-sigma */
    nav_real_t af_tau_s;         /* and its correlation time, s */
    nav_real_t clk_b_psd_m2ps;   /* clock bias white noise psd, m^2/s (c^2 h0 / 2) */
    nav_real_t clk_d_psd_m2ps3;  /* clock drift white noise psd, m^2/s^3 (2 pi^2 c^2 h-2) */
    nav_real_t var_floor;        /* smallest variance allowed on the diagonal */
} ekf_config_t;

typedef struct {
    ekf_config_t cfg;
    nav_real_t x[EKF_N];
    nav_real_t P[EKF_N][EKF_N];
    /* estimates fed back (closed loop): the application subtracts the biases from the
     * IMU increments and uses k and the mounting for the odometer */
    nav_real_t bg_rps[3], ba_mps2[3], k, mount_pitch_rad, mount_yaw_rad;
    nav_real_t odo_offset_mps; /* the odometer's speed offset, m/s (state 22) */
    nav_real_t gz_rps;         /* the body z gyro's in-run bias (state 24), decaying
                                  with gz_tau_s between updates */
    nav_real_t af_mps2;        /* the body y accelerometer's in-run bias (state 25),
                                  decaying with af_tau_s between updates */
    nav_real_t gyro_scale_z;   /* the body z gyro's scale factor error (state 23): the
                                  application divides the z increment by 1 + it */
    /* the receiver's correlated horizontal position error (E, N, m) as estimated: what
     * the fixes are corrected by before their update (ekf_gnss_position) */
    nav_real_t gnss_bias_m[2];
    /* the fixes' correlated sigmas over about one correlation time, information-weighted:
     * their count and their sum of 1 / sigma_c^2, both decaying by phi at each
     * ekf_gnss_bias_step (ekf_gnss_sc_m) */
    nav_real_t gnss_sc_count;
    nav_real_t gnss_sc_info;
    /* the same of the fixes' correlated vertical sigmas (the fixes with a height; the
     * height's correlated error is not a state: ekf_gnss_scv_m) */
    nav_real_t gnss_scv_count;
    nav_real_t gnss_scv_info;
    /* the receiver clock as estimated: its bias in 0.1 mm units (c times seconds: a clock of
     * 1 ms is 3e5 m, beyond what float32 keeps to millimetres) and its drift, m/s */
    int64_t clock_dmm;
    nav_real_t clock_drift_mps;
    uint32_t n_updates;          /* accepted scalar updates */
    uint32_t n_gated;            /* measurements rejected by their innovation gate */
    uint32_t n_health_fixes;     /* last-resort covariance corrections */
    uint32_t n_nonfinite;        /* of which: a non-finite covariance, reset (divergence) */
    uint32_t n_negative_var;     /* of which: a negative variance (divergence) */
    uint32_t n_reopened;         /* ekf_reopen calls */
    uint8_t hold_heading;        /* updates leave the heading, the z gyro bias and the
                                    mounting yaw alone (a Schmidt "consider" update: their
                                    gains are 0, the Joseph form keeps P right): set while
                                    a measurement's heading information is below its noise */
    nav_real_t fp[EKF_N][EKF_N]; /* scratch for F P in ekf_predict: too large for an ECU's
                                    stack, and the core keeps no globals */
    nav_real_t q_inc[2];         /* process noise for the next prediction beyond the IMU's:
                                    angle (rad^2), velocity ((m/s)^2) per axis
                                    (ekf_add_increment_noise) */
} ekf_t;

#define ekf_default_config NAV_SYM(ekf_default_config)
#define ekf_init NAV_SYM(ekf_init)
#define ekf_predict NAV_SYM(ekf_predict)
#define ekf_update NAV_SYM(ekf_update)
#define ekf_feedback NAV_SYM(ekf_feedback)
#define ekf_health NAV_SYM(ekf_health)
#define ekf_sigma_h_m NAV_SYM(ekf_sigma_h_m)

/* initial sigmas and noise of a mid-grade IMU in a car (docs/kalman.md) */
ekf_config_t ekf_default_config(void);

/* Start with zero error state and the configured initial covariance (heading_sigma_rad
 * overrides cfg.heading_rad when > 0). NAV_EINVAL for a non-positive sigma. */
int ekf_init(ekf_t *k, const ekf_config_t *cfg, nav_real_t heading_sigma_rad);

/* Propagate over dt_s with the navigator's state, the mean specific force over the
 * interval in ENU (m/s^2) and the mean compensated body z rate (rad/s). */
void ekf_predict(ekf_t *k, const sins_t *s, const nav_real_t f_n_mps2[3],
                 nav_real_t w_bz_rps, nav_real_t dt_s);

/*
 * One scalar measurement z = h x + noise of variance r, with innovation z (measured
 * minus predicted from the current state: z = computed - measured for this filter's
 * sign) and the row h (EKF_N entries). Rejected without change when z^2 > gate^2 (h P h^T
 * + r) (gate in sigmas; <= 0: no gate). Returns 1 if applied, 0 if gated, -1 if invalid.
 */
int ekf_update(ekf_t *k, const nav_real_t h[EKF_N], nav_real_t z, nav_real_t r,
               nav_real_t gate_sigma);

/* Apply the error estimate to the navigator and the estimates, zero x (closed loop). */
int ekf_feedback(ekf_t *k, sins_t *s);

/* Symmetrise P, hold its diagonal at or above the floor, reset it if not finite; each
 * correction counted in n_health_fixes, a non-finite P also in n_nonfinite and a negative
 * variance (not just rounding below the floor) in n_negative_var: the signs of a diverged
 * filter, which the application resets (fusion.c, filter supervision). Returns the number of
 * corrections made. */
uint32_t ekf_health(ekf_t *k);

/* Forget what the filter believes about position and velocity: their rows and columns
 * of P cleared, the diagonals set to the given 1-sigma. For an innovation gate that keeps
 * refusing consistent fixes (the filter, not the receiver, is wrong); counted in
 * n_reopened. */
#define ekf_reopen NAV_SYM(ekf_reopen)
void ekf_reopen(ekf_t *k, nav_real_t pos_sigma_m, nav_real_t vel_sigma_mps);


/* 1-sigma horizontal position error (m): sqrt(P_EE + P_NN). */
nav_real_t ekf_sigma_h_m(const ekf_t *k);

/* ---------------------------------------------------------------- measurements ----
 * Each builds its rows h and innovations (computed minus measured) and applies them in
 * sequence. A vector measurement is gated as a whole: if any component's normalised
 * innovation exceeds gate_sigma (with P before the update), nothing is applied and
 * n_gated counts it once. Return: number of scalar updates applied (0 when gated), or -1
 * for invalid input. */
#define ekf_gnss_position NAV_SYM(ekf_gnss_position)
#define ekf_gnss_velocity NAV_SYM(ekf_gnss_velocity)
#define ekf_gnss_velocity_horizontal NAV_SYM(ekf_gnss_velocity_horizontal)
#define ekf_odometer NAV_SYM(ekf_odometer)
#define ekf_zero_velocity NAV_SYM(ekf_zero_velocity)
#define ekf_zero_rate NAV_SYM(ekf_zero_rate)

/* ---------------------------------------------------------- measurement rows ----
 * The row builders the updates below use, public so that tests/test_ekf_rows.c can check
 * every row against a numerical derivative of its measurement function (docs/kalman.md,
 * "How the measurement rows are checked"). Each fills rows h (EKF_N entries each, with the
 * error state x of this file: z ~ h x) and innovations z = predicted - measured, in the
 * units and frame of its name. They read the navigator and estimates and change nothing.
 * The rows follow from the psi-angle definition C_bn(computed) = (I - [psi x]) C_bn(true)
 * (Titterton & Weston sec. 12.3): for a body vector a and an ENU vector b,
 *   C(computed) a = C a + [(C a) x] psi,   C(computed)^T b = C^T b - C^T [b x] psi
 * to first order; the products of errors are dropped. */
#define EKF_GNSS_POS_ROWS 3
#define EKF_GNSS_VEL_ROWS 3
#define EKF_ODO_ROWS 3
#define EKF_ZUPT_ROWS 3
#define EKF_ZARU_ROWS 1
/* the odometer rows, in the order ekf_rows_odometer fills them (car frame axes) */
enum {
    EKF_ODO_LATERAL = 0,  /* non-holonomic: the car's lateral (x) velocity is zero */
    EKF_ODO_VERTICAL = 1, /* non-holonomic: the car's vertical (z) velocity is zero */
    EKF_ODO_FORWARD = 2,  /* the odometer's forward (y) speed */
};
#define ekf_rows_gnss_position NAV_SYM(ekf_rows_gnss_position)
#define ekf_rows_gnss_velocity NAV_SYM(ekf_rows_gnss_velocity)
#define ekf_rows_odometer NAV_SYM(ekf_rows_odometer)
#define ekf_rows_zero_velocity NAV_SYM(ekf_rows_zero_velocity)
#define ekf_rows_zero_rate NAV_SYM(ekf_rows_zero_rate)

/* GNSS antenna position. In: the navigator s (attitude C = C_bn), its position pos_then at
 * the fix's time of validity, the measured antenna position meas, the antenna at
 * lever_b_m (body axes, m) from the IMU. Out: z_enu_m = (pos_then - meas) in ENU metres
 * (dr_local_m, at meas) + C lever_b, and the rows (m per unit of each state)
 *   z = dr + [(C l_b) x] psi:  h[i] = e_i on dr,  h[.][psi] = [(C l_b) x]. */
void ekf_rows_gnss_position(const sins_t *s, const geo_pos_t *pos_then, const geo_pos_t *meas,
                            const nav_real_t lever_b_m[3], nav_real_t h[EKF_GNSS_POS_ROWS][EKF_N],
                            nav_real_t z_enu_m[EKF_GNSS_POS_ROWS]);

/* GNSS velocity. In: the navigator's velocity at the fix's time v_then_mps and the
 * measured velocity meas_mps (ENU, m/s). Out: z_enu_mps = v_then - meas and the rows
 *   z = dv:  h[i] = e_i on dv. */
void ekf_rows_gnss_velocity(const nav_real_t v_then_mps[3], const nav_real_t meas_mps[3],
                            nav_real_t h[EKF_GNSS_VEL_ROWS][EKF_N],
                            nav_real_t z_enu_mps[EKF_GNSS_VEL_ROWS]);

/* Odometer speed and non-holonomic constraints, rows EKF_ODO_*. In: the estimates of k
 * (k, mount_pitch_rad = mp, mount_yaw_rad = my), the navigator s (C = C_bn, v = v_n_mps,
 * ENU m/s), the body rate w_b_rps (body, rad/s), the reference point at lever_b_m (body,
 * m) from the IMU, the speed read speed_mps ((1 + k) x true, m/s). With the reference
 * point's velocity in IMU axes v_b = C^T v + w_b x l_b, out z_car_mps (m/s):
 *   lateral  = v_b,x + my v_b,y          (the car's x axis is the IMU's turned by my)
 *   vertical = v_b,z + mp v_b,y          (its z axis, turned by mp)
 *   forward  = (1 + k) v_b,y - speed_mps
 * and, with M = C^T and N = -C^T [v x] (the psi identity above), the rows
 *   lateral:  M_x dv + N_x psi + v_b,y d(my)
 *   vertical: M_z dv + N_z psi + v_b,y d(mp)
 *   forward:  (1 + k)(M_y dv + N_y psi) + v_b,y dk
 * (M_x: row x of M). Neglected: the gyro bias in w_b (entries e_j x l_b on bg: |bg| |l_b|,
 * 1e-4 m/s for a 10 deg/h bias and a 2 m arm), and the mounting angles' own part of the dv
 * and psi entries (lateral my (M_y dv + N_y psi), vertical mp (M_y dv + N_y psi), forward
 * -(1 + k)(my (M_x dv + N_x psi) + mp (M_z dv + N_z psi)): relative to the entries, of
 * the size of the mounting angle in rad). */
void ekf_rows_odometer(const ekf_t *k, const sins_t *s, const nav_real_t w_b_rps[3],
                       const nav_real_t lever_b_m[3], nav_real_t speed_mps,
                       nav_real_t h[EKF_ODO_ROWS][EKF_N], nav_real_t z_car_mps[EKF_ODO_ROWS]);

/* Zero velocity. In: the navigator s. Out: z_enu_mps = v_n (ENU, m/s: the truth is zero)
 * and the rows z = dv: h[i] = e_i on dv. */
void ekf_rows_zero_velocity(const sins_t *s, nav_real_t h[EKF_ZUPT_ROWS][EKF_N],
                            nav_real_t z_enu_mps[EKF_ZUPT_ROWS]);

/* Zero rate. In: the bias-compensated z gyro rate minus the Earth's rate on the body z
 * axis, residual_rate_z_rps (rad/s; the truth at a standstill is zero). Out: z_rps =
 * residual and the row z = bg_z + gz: h = 1 on bg_z and on the in-run state. Neglected: the
 * attitude and latitude errors of the Earth's rate removed, (C^T [w_ie x] psi)_z: below
 * |w_ie| |psi|, 7e-8 rad/s for a 1 mrad attitude error. */
void ekf_rows_zero_rate(nav_real_t residual_rate_z_rps, nav_real_t h[EKF_ZARU_ROWS][EKF_N],
                        nav_real_t z_rps[EKF_ZARU_ROWS]);

/* GNSS antenna position meas (lat/lon/height) for the navigator at pos_then (its position
 * at the fix's time of validity), antenna at lever_b (body, m) from the IMU. Horizontal:
 * the fix less the estimated correlated error gnss_bias_m, rows ekf_rows_gnss_position's
 * plus 1 on db, gated against the declared 1-sigma sigma_h_m per axis (h P h^T + sigma_h^2)
 * and applied with the fix's white part sigma_hw_m (0 < sigma_hw_m <= sigma_h_m, else -1).
 * Vertical: 1-sigma sigma_v_m, gated with it and applied with its variance times
 * r_scale_v (> 0; >= 1: errors correlated from fix to fix). The horizontal pair and the
 * height are gated apart (the height only if use_height): the return counts the rows
 * applied, 2 or 3 when the horizontal fix was taken. */
int ekf_gnss_position(ekf_t *k, const sins_t *s, const geo_pos_t *pos_then,
                      const geo_pos_t *meas, const nav_real_t lever_b[3], nav_real_t sigma_h_m,
                      nav_real_t sigma_hw_m, nav_real_t sigma_v_m, nav_real_t gate_sigma,
                      nav_real_t r_scale_v, int use_height, int use_bias);

/* The receiver's correlated horizontal error over dt_s since the previous fix: a
 * first-order Gauss-Markov process of correlation time tau_s (<= 0: none, white) and
 * stationary 1-sigma sigma_c_m per axis (the correlated part of the fix's declared
 * accuracy): the estimate and its covariance rows decay by phi = exp(-dt/tau), its
 * variance gains sigma_c^2 (1 - phi^2). A declared accuracy that grew since the previous
 * fix (prev_sigma_c_m) adds the difference of the variances (a new error source); one
 * that improved scales the estimate and its covariance rows by sigma_c / prev (the poorer
 * fixes' error went with them: an estimate kept whole with the better sigma would hold
 * the navigator off the good fixes; on the Kingston drive, gnss_corr_s 20 s, 33 m); the
 * variance is held at most sigma_c^2 (the receiver's error is not larger than it says;
 * the covariance rows scaled with it, so P stays a covariance). */
#define ekf_gnss_bias_step NAV_SYM(ekf_gnss_bias_step)
void ekf_gnss_bias_step(ekf_t *k, nav_real_t dt_s, nav_real_t tau_s, nav_real_t sigma_c_m,
                        nav_real_t prev_sigma_c_m, nav_real_t sigma_cv_m);

/* The filter started at a fix (its position is the fix's): the position error is the
 * fix's, white part and correlated part sigma_c_m: db = 0 (the estimate) minus the
 * receiver's error, variance sigma_c^2, and dr = -db + white: their covariance
 * -sigma_c^2. */
#define ekf_gnss_bias_start NAV_SYM(ekf_gnss_bias_start)
void ekf_gnss_bias_start(ekf_t *k, nav_real_t sigma_c_m, nav_real_t sigma_cv_m);

/* The correlated part's sigma of the recent fixes (m per axis): sqrt(count / sum of
 * 1 / sigma_c^2) over about one correlation time, so that one poorly declared fix among
 * many good ones weighs as little as it did in the updates; 0 before any. */
#define ekf_gnss_sc_m NAV_SYM(ekf_gnss_sc_m)
nav_real_t ekf_gnss_sc_m(const ekf_t *k);

/* The same of the fixes' correlated vertical sigmas (sigma_cv_m of ekf_gnss_bias_step and
 * ekf_gnss_bias_start, a fix with a height: above 0; 0 before any). A step without one
 * (0) decays both sums alike, so the sigma holds (the height unobserved, its last
 * correlated part still the best figure) until 14 correlation times without one forget
 * it (0). */
#define ekf_gnss_scv_m NAV_SYM(ekf_gnss_scv_m)
nav_real_t ekf_gnss_scv_m(const ekf_t *k);

/* GNSS velocity (ENU m/s) against the navigator's velocity at the fix's time v_then. */
int ekf_gnss_velocity(ekf_t *k, const nav_real_t v_then_mps[3], const nav_real_t meas_mps[3],
                      nav_real_t sigma_h_mps, nav_real_t sigma_v_mps, nav_real_t gate_sigma);

/* The same with the east and north rows only, for a receiver that measures no vertical
 * velocity (meas_mps[2] unused). */
int ekf_gnss_velocity_horizontal(ekf_t *k, const nav_real_t v_then_mps[3],
                                 const nav_real_t meas_mps[3], nav_real_t sigma_h_mps,
                                 nav_real_t gate_sigma);

/* Odometer speed of the car's reference point (m/s, as read: (1 + k) x true) along the
 * car's forward axis, and the non-holonomic constraints (no lateral, no vertical velocity
 * of the car): three scalar updates. The car's axes are the IMU's turned by the mounting
 * estimates. The reference point (the rear axle's middle) is at lever_b (body axes, m)
 * from the IMU; its velocity is the IMU's plus w_b x lever_b with the body rate w_b
 * (rad/s): in a turn a point ahead of the rear axle slides sideways. The lateral row's
 * 1-sigma is sigma_nhc_mps, the vertical's sigma_vert_mps. */
int ekf_odometer(ekf_t *k, const sins_t *s, const nav_real_t w_b_rps[3],
                 const nav_real_t lever_b_m[3], nav_real_t speed_mps, nav_real_t sigma_fwd_mps,
                 nav_real_t sigma_nhc_mps, nav_real_t sigma_vert_mps, nav_real_t gate_sigma);

/* Standstill: zero velocity (ENU) with 1-sigma sigma_mps; the horizontal pair refused as a
 * whole (and counted in n_gated) when a row's innovation is beyond gate_sigma standard
 * deviations (0: no gate): a wheel that locks while the car still moves reads "standing";
 * the vertical row, after a horizontal pair taken, is gated alone (a refused one counted
 * in n_gated too). Returns the rows used (0: the horizontal pair refused). */
int ekf_zero_velocity(ekf_t *k, const sins_t *s, nav_real_t sigma_mps, nav_real_t gate_sigma);

/* Standstill: the bias-compensated z gyro rate minus the Earth's rate seen by the body z
 * axis (rad/s) measures the residual z gyro bias; 1-sigma sigma_rps. */
int ekf_zero_rate(ekf_t *k, nav_real_t residual_rate_z_rps, nav_real_t sigma_rps);

/* ------------------------------------------------------- raw GNSS (issue #20) ----
 * Tightly coupled updates: one scalar per satellite and observable, formed against the
 * fixed-point geometry of gnss_geom.h so that float32 sees only the residual (ranges of
 * 2e7 m are reduced against the predicted range in 0.1 mm integers first:
 * docs/numeric-design.md, "Raw GNSS ranges"). */
#define EKF_RAW_ROWS 1
#define ekf_rows_pseudorange NAV_SYM(ekf_rows_pseudorange)
#define ekf_rows_range_rate NAV_SYM(ekf_rows_range_rate)
#define ekf_clock_start NAV_SYM(ekf_clock_start)
#define ekf_clock_advance NAV_SYM(ekf_clock_advance)

/* The antenna at the epoch's time of validity: at pos_then + C l_b, its ECEF in 0.1 mm
 * (gnss_geom.h), the lever arm in ENU (l_n = C l_b) and the navigator's ENU axes (those of
 * dr and of the velocity). Formed once per epoch. */
typedef struct {
    int64_t ecef_dmm[3];
    nav_real_t l_n[3];
    nav_real_t sin_lat, cos_lat, sin_lon, cos_lon;
} ekf_antenna_t;

/* One satellite as the rows need it: its geometry from the antenna (gnss_geom_sat) and the
 * line of sight in the navigator's ENU axes. */
typedef struct {
    gnss_geom_t g;
    nav_real_t los_enu[3]; /* unit vector antenna -> satellite, the navigator's ENU axes */
    nav_real_t sat_vel_enu_mps[3]; /* the satellite's velocity in the same axes */
} ekf_sat_t;

#define ekf_antenna NAV_SYM(ekf_antenna)
#define ekf_sat_geometry NAV_SYM(ekf_sat_geometry)

/* The antenna of the navigator s at lever_b_m (body, m) from the IMU, whose position at the
 * epoch's time of validity is pos_then. NAV_EINVAL when pos_then + C l_b cannot form. */
int ekf_antenna(const sins_t *s, const geo_pos_t *pos_then, const nav_real_t lever_b_m[3],
                ekf_antenna_t *a);

/* A satellite at sat_pos_lsb (0.02 m, ECEF axes of the transmit time) with velocity
 * sat_vel_lsb (0.125 m/s) seen from the antenna a: the geometric range (gnss_geom_sat: the
 * Earth's rotation during the signal's travel included), the line of sight and the
 * satellite's velocity in ENU. NAV_EINVAL for a satellite gnss_geom_sat refuses (a corrupt
 * position). Formed once per satellite and epoch, for both rows. */
int ekf_sat_geometry(const ekf_antenna_t *a, const int32_t sat_pos_lsb[3],
                     const int16_t sat_vel_lsb[3], ekf_sat_t *sat);

/* Pseudorange (corrected: satellite clock, ionosphere and troposphere removed by the
 * receiver, docs/can.md) pr_lsb (0.02 m) of the satellite sat seen from the antenna a: the
 * geometric range r and the clock estimate clock_dmm give the prediction; out
 * z_m = r + clock - pr (m, formed in integers first) and the row
 *   z = -u^T dr - u^T [(C l_b) x] psi + dcb = -u^T dr - (u x C l_b)^T psi + dcb
 * with u the unit line of sight in ENU (the antenna error dr + [(C l_b) x] psi of the
 * position rows, seen along u). Neglected: the Earth's rotation during the travel moves
 * with the range, by w_ie |r_sat| / c per metre (6.5e-6: 65 um for a 10 m error).
 * With use_bias, the ranges' errors correlated in time are the receiver's correlated
 * horizontal position error (the state db of the fixes, ekf_gnss_bias_step) seen along the
 * line of sight: the prediction is shortened by u_E b_E + u_N b_N (b = gnss_bias_m) and
 * the row has -u_E, -u_N on db. An approximation (independent per-satellite errors are not
 * a horizontal position error; a state per satellite would be), a model of the errors'
 * correlation like the fixes' (docs/kalman.md). */
void ekf_rows_pseudorange(const ekf_t *k, const ekf_antenna_t *a, const ekf_sat_t *sat,
                          uint32_t pr_lsb, int use_bias, nav_real_t h[EKF_N], nav_real_t *z_m);

/* Pseudorange rate (m/s, rr_mps: the rate of the range plus the clock drift; a Doppler
 * shift D at wavelength L is -D L) of the satellite sat (ekf_sat_geometry's), for the
 * navigator's velocity at the epoch v_then_mps (ENU) and body rate w_b_rps: the antenna
 * moves at v_a = v + C (w_b x l_b). Out z_mps = u . (v_sat - v_a) + clock_drift - rr and
 *   z = -u^T dv - (u x C (w_b x l_b))^T psi + ((C^T u) x l_b)^T bg + dcd
 * (the compensated rate w_b is the true one plus the residual gyro bias bg; its z part also
 * the in-run state and w_bz times the scale factor state, with bg_z's entry).
 * Neglected: the line of sight's change with the position error, |v_sat - v_a| / r per
 * metre (4e3 / 2e7: 2e-4 m/s per m). */
void ekf_rows_range_rate(const ekf_t *k, const sins_t *s, const nav_real_t v_then_mps[3],
                         const nav_real_t w_b_rps[3], const nav_real_t lever_b_m[3],
                         const ekf_sat_t *sat, nav_real_t rr_mps, nav_real_t h[EKF_N],
                         nav_real_t *z_mps);

/* The clock estimated afresh (the first raw epoch, a receiver clock reset, a long gap): the
 * estimates moved by -shift_m (rounded to the 0.1 mm units, held within +-1e8 m) and
 * -drift_shift_mps (the residuals' medians that the new estimates make zero), their errors
 * uncorrelated with the other states, 1-sigma sigma_b_m and sigma_d_mps. */
void ekf_clock_start(ekf_t *k, nav_real_t shift_m, nav_real_t drift_shift_mps,
                     nav_real_t sigma_b_m, nav_real_t sigma_d_mps);

/* The clock estimate moved on by its drift over dt_s (the errors' growth is ekf_predict's). */
void ekf_clock_advance(ekf_t *k, nav_real_t dt_s);

/* ---------------------------------------------------------------- access ----
 * The application reads the filter through these and changes its estimates only through
 * the setters, which refuse (NAV_EINVAL, k unchanged) a non-finite value or one outside
 * the stated range. */
#define ekf_state_sigma NAV_SYM(ekf_state_sigma)
#define ekf_state_ok NAV_SYM(ekf_state_ok)
#define ekf_state_cov NAV_SYM(ekf_state_cov)
#define ekf_set_gyro_bias NAV_SYM(ekf_set_gyro_bias)
#define ekf_set_odo_scale NAV_SYM(ekf_set_odo_scale)
#define ekf_set_mount_yaw NAV_SYM(ekf_set_mount_yaw)
#define ekf_widen_mount NAV_SYM(ekf_widen_mount)
#define ekf_add_increment_noise NAV_SYM(ekf_add_increment_noise)

/* 1-sigma of error state i (0 <= i < EKF_N): sqrt(P_ii), in that state's unit. */
nav_real_t ekf_state_sigma(const ekf_t *k, int i);

/* Covariance of error states i and j (0 <= i, j < EKF_N): P_ij. */
nav_real_t ekf_state_cov(const ekf_t *k, int i, int j);

/* 1 if the error state, the fed-back estimates and the covariance's diagonal are finite
 * and no variance is negative; 0 is a diverged filter (app: fusion supervision). */
int ekf_state_ok(const ekf_t *k);

/* The gyro bias estimate on body axis `axis` (0..2), rad/s, |b| < 1 rad/s: what the
 * standstill estimate already knows. */
int ekf_set_gyro_bias(ekf_t *k, int axis, nav_real_t b_rps);

/* The odometer scale error estimate (seed 000's mu), |k| <= DR_MU_MAX. */
int ekf_set_odo_scale(ekf_t *k, nav_real_t odo_scale);

/* The mounting yaw estimate (rad), |yaw| <= DR_DH_MAX_RAD. */
int ekf_set_mount_yaw(ekf_t *k, nav_real_t yaw_rad);

/* Widen the mounting pitch and yaw variances to at least sigma^2 (rad) each, for a
 * mounting in use that is only known to that sigma (the automatic coarse estimate's):
 * right after ekf_init, whose P is diagonal. A sigma of 0 leaves its state alone.
 * NAV_EINVAL for a sigma not finite or < 0. */
int ekf_widen_mount(ekf_t *k, nav_real_t pitch_sigma_rad, nav_real_t yaw_sigma_rad);

/* Process noise beyond the IMU's own for the next ekf_predict: var_angle_rad2 added to
 * each attitude error's variance, var_vel_m2ps2 to each velocity error's (isotropic, so
 * the same in any frame). For increments known less well than the IMU's noise says: the
 * bridged samples of an IMU gap and the saturated ones (app.c sample_noise). */
void ekf_add_increment_noise(ekf_t *k, nav_real_t var_angle_rad2, nav_real_t var_vel_m2ps2);

#endif /* NAVECU_EKF_H */
