/*
 * test_ekf_rows.c - every measurement row of the filter against a numerical derivative of
 * its measurement function (issue #14 point 5; docs/kalman.md, "How the measurement rows
 * are checked"). Built for both numeric variants.
 *
 * For each measurement the test writes its own measurement function from first principles,
 * in double: the innovation z(x) = (what a navigator with the error state x predicts) -
 * (what the sensor reads of the true state). The "computed" navigator and estimates for an
 * error x are built from the true ones the way ekf.h defines the errors (and ekf_feedback
 * undoes them): position + dr (ENU metres at the IMU), velocity + dv, C_bn(computed) =
 * (I - [psi x]) C_bn(true), body rate + bg, k, mounting pitch and yaw estimates = truth +
 * x. Each column j of the Jacobian is the central difference (z(+d_j) - z(-d_j)) / (2 d_j)
 * with d_j the step actually applied (read back from the stored, rounded navigator), and
 * it is compared with the row the filter builds (ekf_rows_*) at x = 0. The innovation the
 * filter builds is also compared with the test's, at x = 0 and at every perturbed state.
 *
 * Tolerance of an entry, for a row whose terms and sensitivities are at most S (in the
 * row's unit per unit of any state):
 *   16 eps S                 the filter's row in nav_real_t (a few roundings of terms <= S)
 * + (16 eps_d S + u_j S) / d_j  the two double evaluations of z, and the rounding u_j of the
 *                          stored perturbed attitude (eps rad; the other states' steps are
 *                          read back exactly, u_j = 0)
 * + d_j^2 S / 6            truncation of the central difference for the rotations (psi and
 *                          the mounting angles: the third derivative of a rotation of a
 *                          vector of size <= S is <= S); the other states enter linearly
 * + A                      where the filter's model knowingly simplifies: an explicit
 *                          bound of what it neglects (ekf.h), named at each use below
 * with eps the precision of nav_real_t, eps_d that of double. The steps trade rounding
 * against truncation per variant: d = 1e-5 rad (f64) and 5e-3 rad (f32, where the stored
 * quaternion's rounding eps / d dominates) for psi, 1e-5 / 1e-4 rad for the mounting,
 * and large steps for the linear states (1 m, 0.1 m/s, 0.01 rad/s, 0.01).
 *
 * The state is deliberately general: 45 deg N, roll 2, pitch -3, heading 130 deg, 15 m/s,
 * a 0.3 rad/s turn with roll and pitch rates, lever arms with three non-zero components,
 * odometer scale error 1.5 %, mounting 0.4 deg up and 0.7 deg left, so that no term of a
 * row hides behind a zero.
 */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "ekf.h"
#include "truth.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define RAD_PER_LSB (PI / (1.8e9 * (double)GEO_LSB_PER_DEG_E7))
#define M_PER_HLSB (1e-3 / (double)GEO_LSB_PER_MM)

#if defined(NAV_REAL_DOUBLE)
#define NAV_EPS DBL_EPSILON
#define STEP_PSI_RAD 1e-5
#define STEP_MOUNT_RAD 1e-5
#define VARIANT "f64"
#else
#define NAV_EPS ((double)FLT_EPSILON)
#define STEP_PSI_RAD 5e-3
#define STEP_MOUNT_RAD 1e-4
#define VARIANT "f32"
#endif
#define STEP_DR_M 1.0
#define STEP_DV_MPS 0.1
#define STEP_BG_RPS 0.01
#define STEP_BA_MPS2 1.0
#define STEP_K 0.01
#define STEP_OB_MPS 0.1
#define STEP_SG 0.01

static const char *const STATE_NAME[EKF_N] = {
    "dr_E", "dr_N", "dr_U", "dv_E", "dv_N", "dv_U", "psi_E", "psi_N", "psi_U",
    "bg_x", "bg_y", "bg_z", "ba_x", "ba_y", "ba_z", "k", "mount_pitch", "mount_yaw",
    "gnss_bias_E", "gnss_bias_N", "clock_bias", "clock_drift", "odo_offset", "gyro_scale_z",
    "gyro_bias_z_in_run", "accel_bias_y_in_run"};

/* A true state as the filter sees it at x = 0: the navigator, the estimates (k and the
 * mounting, in the ekf_t), the body rate the odometer rows get. */
typedef struct {
    sins_t nav;
    ekf_t kf;
    nav_real_t w_b_rps[3];
} state_t;

/* The same, read into double for the first-principles functions. */
typedef struct {
    double lat_rad, lon_rad, h_m;
    double v_n_mps[3];
    double C_bn[3][3];
    double k, mount_pitch_rad, mount_yaw_rad, odo_offset_mps;
    double w_b_rps[3];
} state_d_t;

/* ------------------------------------------------------- first principles ---- */

static void cross_d(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double norm_d(const double a[3])
{
    return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

/* C_bn of a Hamilton quaternion {w, x, y, z} (v_n = q v_b q*), normalised first */
static void dcm_of_quat(const nav_real_t qf[4], double C[3][3])
{
    const double n = sqrt((double)qf[0] * (double)qf[0] + (double)qf[1] * (double)qf[1] +
                          (double)qf[2] * (double)qf[2] + (double)qf[3] * (double)qf[3]);
    const double w = (double)qf[0] / n, x = (double)qf[1] / n, y = (double)qf[2] / n,
                 z = (double)qf[3] / n;
    C[0][0] = 1.0 - 2.0 * (y * y + z * z);
    C[0][1] = 2.0 * (x * y - w * z);
    C[0][2] = 2.0 * (x * z + w * y);
    C[1][0] = 2.0 * (x * y + w * z);
    C[1][1] = 1.0 - 2.0 * (x * x + z * z);
    C[1][2] = 2.0 * (y * z - w * x);
    C[2][0] = 2.0 * (x * z - w * y);
    C[2][1] = 2.0 * (y * z + w * x);
    C[2][2] = 1.0 - 2.0 * (x * x + y * y);
}

static state_d_t read_state(const state_t *st)
{
    state_d_t d;
    d.lat_rad = (double)st->nav.pos.lat * RAD_PER_LSB;
    d.lon_rad = (double)st->nav.pos.lon * RAD_PER_LSB;
    d.h_m = (double)st->nav.pos.h * M_PER_HLSB;
    dcm_of_quat(st->nav.q_bn, d.C_bn);
    for (int i = 0; i < 3; i++) {
        d.v_n_mps[i] = (double)st->nav.v_n_mps[i];
        d.w_b_rps[i] = (double)st->w_b_rps[i];
    }
    d.k = (double)st->kf.k;
    d.odo_offset_mps = (double)st->kf.odo_offset_mps;
    d.mount_pitch_rad = (double)st->kf.mount_pitch_rad;
    d.mount_yaw_rad = (double)st->kf.mount_yaw_rad;
    return d;
}

/* C_bn^T a */
static void to_body(const state_d_t *s, const double a_n[3], double a_b[3])
{
    for (int i = 0; i < 3; i++) {
        a_b[i] = s->C_bn[0][i] * a_n[0] + s->C_bn[1][i] * a_n[1] + s->C_bn[2][i] * a_n[2];
    }
}

/* Local east, north, up metres of a position from a reference point (the tangent plane at
 * the reference: exact for the differences of a few metres used here, to 1e-6). */
static void enu_from(const geo_pos_t *ref, const geo_pos_t *p, double enu_m[3])
{
    const double lat = (double)ref->lat * RAD_PER_LSB, h = (double)ref->h * M_PER_HLSB;
    double R_M, R_N;
    truth_radii(lat, &R_M, &R_N);
    enu_m[0] = (double)(p->lon - ref->lon) * RAD_PER_LSB * (R_N + h) * cos(lat);
    enu_m[1] = (double)(p->lat - ref->lat) * RAD_PER_LSB * (R_M + h);
    enu_m[2] = (double)(p->h - ref->h) * M_PER_HLSB;
}

/* a position moved by enu_m (tangent plane at p, as enu_from), to the nearest LSB */
static geo_pos_t geo_moved(const geo_pos_t *p, const double enu_m[3])
{
    const double lat = (double)p->lat * RAD_PER_LSB, h = (double)p->h * M_PER_HLSB;
    double R_M, R_N;
    truth_radii(lat, &R_M, &R_N);
    geo_pos_t q = *p;
    q.lon += (int64_t)llround(enu_m[0] / ((R_N + h) * cos(lat)) / RAD_PER_LSB);
    q.lat += (int64_t)llround(enu_m[1] / (R_M + h) / RAD_PER_LSB);
    q.h += (int64_t)llround(enu_m[2] / M_PER_HLSB);
    return q;
}

/* GNSS antenna: predicted antenna position (IMU + C l_b) minus the measured one, ENU metres
 * in the tangent plane at the true IMU position ref */
static void h_gnss_position(const state_t *st, const geo_pos_t *ref, const geo_pos_t *meas,
                            const nav_real_t lever_b_m[3], double z_m[3])
{
    const state_d_t s = read_state(st);
    double p_m[3], m_m[3];
    enu_from(ref, &st->nav.pos, p_m);
    enu_from(ref, meas, m_m);
    for (int i = 0; i < 3; i++) {
        double l_n = 0.0;
        for (int j = 0; j < 3; j++) {
            l_n += s.C_bn[i][j] * (double)lever_b_m[j];
        }
        z_m[i] = p_m[i] + l_n - m_m[i];
    }
}

/* GNSS velocity: the navigator's minus the measured */
static void h_velocity(const state_t *st, const double meas_mps[3], double z_mps[3])
{
    for (int i = 0; i < 3; i++) {
        z_mps[i] = (double)st->nav.v_n_mps[i] - meas_mps[i];
    }
}

/* The car's axes from the IMU's: v_car = R v_imu, R = Rz(-yaw) Rx(pitch) (the IMU's
 * forward axis turned clockwise by the mounting yaw and nose up by the mounting pitch of
 * the car's, the 3-1-2 convention of nav_math.h with the car as the reference frame). */
static void car_from_imu(double pitch_rad, double yaw_rad, double R[3][3])
{
    const double cp = cos(pitch_rad), sp = sin(pitch_rad), cy = cos(yaw_rad),
                 sy = sin(yaw_rad);
    const double Rz[3][3] = {{cy, sy, 0.0}, {-sy, cy, 0.0}, {0.0, 0.0, 1.0}};
    const double Rx[3][3] = {{1.0, 0.0, 0.0}, {0.0, cp, -sp}, {0.0, sp, cp}};
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            R[i][j] = Rz[i][0] * Rx[0][j] + Rz[i][1] * Rx[1][j] + Rz[i][2] * Rx[2][j];
        }
    }
}

/* the car's reference point at lever_b from the IMU: its velocity in IMU axes,
 * C^T v_n + w_b x l_b */
static void ref_point_velocity_b(const state_d_t *s, const nav_real_t lever_b_m[3],
                                 double v_b[3])
{
    const double l[3] = {(double)lever_b_m[0], (double)lever_b_m[1], (double)lever_b_m[2]};
    double wxl[3];
    to_body(s, s->v_n_mps, v_b);
    cross_d(s->w_b_rps, l, wxl);
    for (int i = 0; i < 3; i++) {
        v_b[i] += wxl[i];
    }
}

/* Odometer and non-holonomic constraints, in the EKF_ODO_* order: the reference point's
 * velocity in the car's axes (by the mounting estimates), lateral and vertical (true: 0),
 * and its forward speed as the odometer would read it with the estimated scale and offset
 * (in the direction of travel, the reading's sign), minus the reading. */
static void h_odometer(const state_t *st, const nav_real_t lever_b_m[3], double speed_read_mps,
                       double z_mps[EKF_ODO_ROWS])
{
    const state_d_t s = read_state(st);
    double v_b[3], R[3][3], v_c[3];
    ref_point_velocity_b(&s, lever_b_m, v_b);
    car_from_imu(s.mount_pitch_rad, s.mount_yaw_rad, R);
    for (int i = 0; i < 3; i++) {
        v_c[i] = R[i][0] * v_b[0] + R[i][1] * v_b[1] + R[i][2] * v_b[2];
    }
    z_mps[EKF_ODO_LATERAL] = v_c[0];
    z_mps[EKF_ODO_VERTICAL] = v_c[2];
    z_mps[EKF_ODO_FORWARD] = (1.0 + s.k) * v_c[1] +
                             (speed_read_mps < 0.0 ? -1.0 : 1.0) * s.odo_offset_mps -
                             speed_read_mps;
}

/* Earth rate in ENU at latitude lat */
static void earth_rate_n(double lat_rad, double w_ie_n[3])
{
    w_ie_n[0] = 0.0;
    w_ie_n[1] = WGS84_OMEGA_IE_RPS * cos(lat_rad);
    w_ie_n[2] = WGS84_OMEGA_IE_RPS * sin(lat_rad);
}

/* Zero rate at a standstill: the z gyro's rate as compensated (the true body rate, which
 * standing is the Earth's, plus the residual bias: the state's w_b) minus the Earth's
 * rate on the body z axis as the navigator computes it (its attitude and latitude). */
static double h_zero_rate(const state_t *st)
{
    const state_d_t s = read_state(st);
    double w_ie_n[3], w_ie_b[3];
    earth_rate_n(s.lat_rad, w_ie_n);
    to_body(&s, w_ie_n, w_ie_b);
    return s.w_b_rps[2] - w_ie_b[2];
}

/* ------------------------------------------------------ the error states ---- */

/* The "computed" state with error d in state j, built from the truth as ekf.h defines
 * the error (ekf_feedback undoes it). Returns the error actually applied, read back from
 * the stored (rounded) values; for psi, the rotation asked for (its rounding is in the
 * tolerance). */
static double perturb(const state_t *truth, int j, double d, state_t *comp)
{
    *comp = *truth;
    if (j < EKF_DV) {
        double enu[3] = {0.0, 0.0, 0.0}, back[3];
        enu[j - EKF_DR] = d;
        comp->nav.pos = geo_moved(&truth->nav.pos, enu);
        enu_from(&truth->nav.pos, &comp->nav.pos, back);
        return back[j - EKF_DR];
    }
    if (j < EKF_PSI) {
        nav_real_t *v = &comp->nav.v_n_mps[j - EKF_DV];
        *v = (nav_real_t)((double)*v + d);
        return (double)*v - (double)truth->nav.v_n_mps[j - EKF_DV];
    }
    if (j < EKF_BG) {
        /* C_comp = (I - [psi x]) C_true: q_comp = q(-psi) (x) q_true, the rotation of
         * angle d about the negative axis j, in double */
        const int a = j - EKF_PSI;
        const double c = cos(0.5 * d), s = sin(0.5 * d);
        double p[4] = {c, 0.0, 0.0, 0.0};
        p[1 + a] = -s;
        const nav_real_t *q = truth->nav.q_bn;
        const double qw = (double)q[0], qx = (double)q[1], qy = (double)q[2], qz = (double)q[3];
        const double r[4] = {p[0] * qw - p[1] * qx - p[2] * qy - p[3] * qz,
                             p[0] * qx + p[1] * qw + p[2] * qz - p[3] * qy,
                             p[0] * qy - p[1] * qz + p[2] * qw + p[3] * qx,
                             p[0] * qz + p[1] * qy - p[2] * qx + p[3] * qw};
        for (int i = 0; i < 4; i++) {
            comp->nav.q_bn[i] = (nav_real_t)r[i];
            comp->nav.q_bn_lo[i] = NAV_C(0.0);
        }
        return d;
    }
    nav_real_t *e = NULL;
    if (j < EKF_BA) {
        e = &comp->w_b_rps[j - EKF_BG]; /* the compensated rate = true + residual bias */
    } else if (j < EKF_K || j == EKF_AF) {
        return d; /* the accelerometer bias (turn-on or in-run) enters no measurement */
    } else if (j == EKF_K) {
        e = &comp->kf.k;
    } else if (j == EKF_MP) {
        e = &comp->kf.mount_pitch_rad;
    } else if (j == EKF_MY) {
        e = &comp->kf.mount_yaw_rad;
    } else if (j == EKF_CB) {
        /* the clock estimate in its 0.1 mm integers: the step is exact */
        const int64_t dd = (int64_t)llround(d * (double)GNSS_GEOM_DMM_PER_M);
        comp->kf.clock_dmm += dd;
        return (double)dd / (double)GNSS_GEOM_DMM_PER_M;
    } else if (j == EKF_CD) {
        e = &comp->kf.clock_drift_mps;
    } else if (j == EKF_OB) {
        e = &comp->kf.odo_offset_mps;
    } else if (j == EKF_GZ) {
        e = &comp->w_b_rps[2]; /* the in-run part of the z bias, as bg_z */
    } else if (j == EKF_SG) {
        /* the compensated z rate = (1 + sg) x the true one: the step actually stored is
         * the ratio's */
        nav_real_t *w = &comp->w_b_rps[2];
        const double w0 = (double)*w;
        *w = (nav_real_t)(w0 * (1.0 + d));
        return fabs(w0) > 0.0 ? (double)*w / w0 - 1.0 : d;
    } else {
        /* the receiver's correlated error: the row builders leave it to ekf_gnss_position
         * (its row is 1 on the state, the estimate subtracted from the fix) */
        e = &comp->kf.gnss_bias_m[j - EKF_GB];
    }
    const double before = (double)*e;
    *e = (nav_real_t)(before + d);
    return (double)*e - before;
}

static double step_of(int j)
{
    static const double step[EKF_N] = {
        STEP_DR_M,    STEP_DR_M,    STEP_DR_M,    STEP_DV_MPS,  STEP_DV_MPS,  STEP_DV_MPS,
        STEP_PSI_RAD, STEP_PSI_RAD, STEP_PSI_RAD, STEP_BG_RPS,  STEP_BG_RPS,  STEP_BG_RPS,
        STEP_BA_MPS2, STEP_BA_MPS2, STEP_BA_MPS2, STEP_K,       STEP_MOUNT_RAD,
        STEP_MOUNT_RAD, STEP_DR_M,    STEP_DR_M,    STEP_DR_M,    STEP_DV_MPS,  STEP_OB_MPS,
        STEP_SG,      STEP_BG_RPS,  STEP_BA_MPS2};
    return step[j];
}

static int is_rotation(int j)
{
    return (j >= EKF_PSI && j < EKF_BG) || j == EKF_MP || j == EKF_MY;
}

/* the numerical tolerance of an entry in column j of a row of scale S (file comment) */
static double tol_numeric(int j, double S)
{
    const double d = step_of(j);
    const double u = (j >= EKF_PSI && j < EKF_BG) ? NAV_EPS : 0.0;
    const double trunc = is_rotation(j) ? d * d * S / 6.0 : 0.0;
    return 16.0 * NAV_EPS * S + (16.0 * DBL_EPSILON * S + u * S) / d + trunc;
}

/* ------------------------------------------------------------ the check ---- */

/* One measurement under test: its name, rows, the first-principles innovation of a state
 * and the filter's rows and innovation of the same state. */
typedef struct {
    const char *name;
    int n_rows;
    const char *const *row_name;
    double scale; /* S of the file comment */
    void (*h)(const void *ctx, const state_t *st, double *z);
    void (*rows)(const void *ctx, const state_t *st, nav_real_t h[][EKF_N], nav_real_t *z);
    /* model allowance of (row, column) at the truth, and of the innovation at a state:
     * NULL where the filter's row is the exact derivative */
    double (*allow_h)(const void *ctx, const state_t *truth, int row, int col);
    double (*allow_z)(const void *ctx, const state_t *st, int row);
    const void *ctx;
} meas_t;

typedef struct {
    /* values beyond their tolerance, and the first of them, among the row entries [0] and
     * the innovations [1] */
    int n_bad[2];
    char first[2][320];
    /* entries the filter models exactly: count, max |filter - numerical| / tolerance */
    int n_exact;
    double worst_exact;
    char at_exact[160];
    /* entries within a model allowance: count, max |filter - numerical| / (tolerance +
     * allowance) */
    int n_model;
    double worst_model;
    char at_model[160];
} verdict_t;

enum { ROW_ENTRY = 0, INNOVATION = 1 };

static void judge(verdict_t *v, int kind, const char *what, double filter, double ref,
                  double tol_num, double allow)
{
    const double diff = fabs(filter - ref), tol = tol_num + allow;
    const double ratio = diff / tol;
    if (!(diff <= tol)) {
        if (v->n_bad[kind] == 0) {
            (void)snprintf(v->first[kind], sizeof v->first[kind],
                           "%s: filter %.10g, numerical %.10g, |difference| %.3g > tolerance "
                           "%.3g (numerical %.3g + model %.3g)",
                           what, filter, ref, diff, tol, tol_num, allow);
        }
        v->n_bad[kind]++;
    }
    int *n = allow > 0.0 ? &v->n_model : &v->n_exact;
    double *worst = allow > 0.0 ? &v->worst_model : &v->worst_exact;
    char *at = allow > 0.0 ? v->at_model : v->at_exact;
    (*n)++;
    if (ratio > *worst || isnan(ratio)) {
        *worst = ratio;
        (void)snprintf(at, sizeof v->at_exact, " at %s", what);
    }
}

/* every entry of every row against the central difference, and the innovation against the
 * first-principles one at the truth and at every perturbed state; the verdict returned */
static verdict_t check_meas(const meas_t *m, const state_t *truth)
{
    verdict_t v;
    memset(&v, 0, sizeof v);
    nav_real_t H[3][EKF_N], zf[3];
    double zr[3];
    char what[160];
    m->rows(m->ctx, truth, H, zf);
    m->h(m->ctx, truth, zr);
    for (int r = 0; r < m->n_rows; r++) {
        (void)snprintf(what, sizeof what, "%s %s innovation at the truth", m->name,
                       m->row_name[r]);
        judge(&v, INNOVATION, what, (double)zf[r], zr[r], 16.0 * (NAV_EPS + DBL_EPSILON) * m->scale,
              m->allow_z != NULL ? m->allow_z(m->ctx, truth, r) : 0.0);
    }
    for (int j = 0; j < EKF_N; j++) {
        static state_t plus, minus;
        const double d = step_of(j);
        const double a_plus = perturb(truth, j, d, &plus);
        const double a_minus = perturb(truth, j, -d, &minus);
        double zp[3], zm[3];
        m->h(m->ctx, &plus, zp);
        m->h(m->ctx, &minus, zm);
        for (int r = 0; r < m->n_rows; r++) {
            const double J = (zp[r] - zm[r]) / (a_plus - a_minus);
            (void)snprintf(what, sizeof what, "%s row %s, column %s", m->name, m->row_name[r],
                           STATE_NAME[j]);
            judge(&v, ROW_ENTRY, what, (double)H[r][j], J, tol_numeric(j, m->scale),
                  m->allow_h != NULL ? m->allow_h(m->ctx, truth, r, j) : 0.0);
        }
        /* the filter's innovation at the perturbed states */
        nav_real_t Hs[3][EKF_N], zs[3];
        for (int side = 0; side < 2; side++) {
            const state_t *st = side == 0 ? &plus : &minus;
            const double *zt = side == 0 ? zp : zm;
            m->rows(m->ctx, st, Hs, zs);
            for (int r = 0; r < m->n_rows; r++) {
                (void)snprintf(what, sizeof what, "%s %s innovation at %s %+g", m->name,
                               m->row_name[r], STATE_NAME[j], side == 0 ? d : -d);
                judge(&v, INNOVATION, what, (double)zs[r], zt[r], 16.0 * (NAV_EPS + DBL_EPSILON) * m->scale,
                      m->allow_z != NULL ? m->allow_z(m->ctx, st, r) : 0.0);
            }
        }
    }
    return v;
}

static void expect_rows_right(const meas_t *m, const state_t *truth)
{
    const verdict_t v = check_meas(m, truth);
    print_message("%s (%s): %d rows x %d columns, innovations at %d states: %d values exact "
                  "to the numerical tolerance (worst %.3f of it%s)",
                  m->name, VARIANT, m->n_rows, EKF_N, 1 + 2 * EKF_N, v.n_exact, v.worst_exact,
                  v.at_exact[0] != '\0' ? v.at_exact : ", every difference zero");
    if (v.n_model > 0) {
        print_message("; %d within a model allowance (worst %.3f of it%s)", v.n_model,
                      v.worst_model, v.at_model[0] != '\0' ? v.at_model : "");
    }
    print_message("\n");
    if (v.n_bad[ROW_ENTRY] + v.n_bad[INNOVATION] != 0) {
        fail_msg("%d row entries off%s%s; %d innovations off%s%s", v.n_bad[ROW_ENTRY],
                 v.n_bad[ROW_ENTRY] != 0 ? ", the first " : "", v.first[ROW_ENTRY],
                 v.n_bad[INNOVATION], v.n_bad[INNOVATION] != 0 ? ", the first " : "",
                 v.first[INNOVATION]);
    }
}

/* -------------------------------------------------------------- the state ---- */

static geo_pos_t geo_at(double lat_deg, double lon_deg, double h_m)
{
    const geo_pos_t p = {(int64_t)llround(lat_deg * DEG / RAD_PER_LSB),
                         (int64_t)llround(lon_deg * DEG / RAD_PER_LSB),
                         (int64_t)llround(h_m / M_PER_HLSB)};
    return p;
}

static const double W_TURN_B_RPS[3] = {0.02, -0.01, 0.3}; /* roll, pitch rates; left turn */
static const double SPEED_MPS = 15.0;
static const double K_TRUE = 0.015;
static const double OB_TRUE_MPS = -0.12; /* a truncating whole-km/h speed: half a step low */
/* the IMU 0.4 deg nose up and 0.7 deg anticlockwise (left) of the car */
#define MOUNT_PITCH_RAD (0.4 * DEG)
#define MOUNT_YAW_RAD (-0.7 * DEG)
static const double ODO_LEVER_B_M[3] = {0.35, -1.6, -0.3}; /* rear axle's middle */
static const double GNSS_LEVER_B_M[3] = {-0.3, 0.8, 1.3};

/* The true state: 45 deg N, roll 2, pitch -3, heading 130 deg, the IMU mounted mount_pitch
 * up and mount_yaw clockwise of the car, the car's reference point at ODO_LEVER_B_M moving
 * forward at speed along the car's axis (so the non-holonomic constraints hold exactly),
 * turning at W_TURN_B_RPS. speed 0: standing, the body rate the Earth's. */
static void true_state(state_t *st, double speed_mps, double mount_pitch_rad,
                       double mount_yaw_rad)
{
    double qd[4];
    truth_q_from_euler(2.0 * DEG, -3.0 * DEG, 130.0 * DEG, qd);
    nav_real_t q[4];
    for (int i = 0; i < 4; i++) {
        q[i] = (nav_real_t)qd[i];
    }
    const nav_real_t zero[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    const geo_pos_t p = geo_at(45.0, 10.0, 250.0);
    const sins_config_t scfg = sins_default_config();
    assert_int_equal(sins_init(&st->nav, &scfg, &p, zero, q), NAV_OK);
    const ekf_config_t kcfg = ekf_default_config();
    assert_int_equal(ekf_init(&st->kf, &kcfg, NAV_C(0.0)), NAV_OK);
    st->kf.k = (nav_real_t)K_TRUE;
    st->kf.odo_offset_mps = (nav_real_t)OB_TRUE_MPS;
    st->kf.mount_pitch_rad = (nav_real_t)mount_pitch_rad;
    st->kf.mount_yaw_rad = (nav_real_t)mount_yaw_rad;
    state_d_t s = read_state(st);
    if (speed_mps > 0.0) {
        for (int i = 0; i < 3; i++) {
            st->w_b_rps[i] = (nav_real_t)W_TURN_B_RPS[i];
        }
        /* the reference point: (0, speed, 0) in the car's axes, R^T of it in the IMU's;
         * the IMU's velocity is that less w x l */
        double R[3][3], v_ref_b[3], wxl[3], v_imu_b[3];
        car_from_imu((double)st->kf.mount_pitch_rad, (double)st->kf.mount_yaw_rad, R);
        const double l[3] = {(double)(nav_real_t)ODO_LEVER_B_M[0],
                             (double)(nav_real_t)ODO_LEVER_B_M[1],
                             (double)(nav_real_t)ODO_LEVER_B_M[2]};
        const double w[3] = {(double)st->w_b_rps[0], (double)st->w_b_rps[1],
                             (double)st->w_b_rps[2]};
        cross_d(w, l, wxl);
        for (int i = 0; i < 3; i++) {
            v_ref_b[i] = R[1][i] * speed_mps;
            v_imu_b[i] = v_ref_b[i] - wxl[i];
        }
        for (int i = 0; i < 3; i++) {
            st->nav.v_n_mps[i] = (nav_real_t)(s.C_bn[i][0] * v_imu_b[0] +
                                              s.C_bn[i][1] * v_imu_b[1] +
                                              s.C_bn[i][2] * v_imu_b[2]);
        }
    } else {
        double w_ie_n[3], w_ie_b[3];
        earth_rate_n(s.lat_rad, w_ie_n);
        to_body(&s, w_ie_n, w_ie_b);
        for (int i = 0; i < 3; i++) {
            st->w_b_rps[i] = (nav_real_t)w_ie_b[i];
        }
    }
}

static void lever_of(const double l[3], nav_real_t out[3])
{
    for (int i = 0; i < 3; i++) {
        out[i] = (nav_real_t)l[i];
    }
}

static const char *const ENU_ROW[3] = {"E", "N", "U"};
static const char *const ODO_ROW[EKF_ODO_ROWS] = {"lateral", "vertical", "forward"};

/* ------------------------------------------------------- GNSS position ---- */

typedef struct {
    geo_pos_t truth_pos; /* the tangent plane's origin: the true IMU position */
    geo_pos_t meas;      /* the antenna as measured */
    nav_real_t lever_b_m[3];
    double lever_norm_m;
} gnss_pos_ctx_t;

static void gnss_pos_h(const void *ctx, const state_t *st, double *z)
{
    const gnss_pos_ctx_t *c = ctx;
    h_gnss_position(st, &c->truth_pos, &c->meas, c->lever_b_m, z);
}

static void gnss_pos_rows(const void *ctx, const state_t *st, nav_real_t h[][EKF_N],
                          nav_real_t *z)
{
    const gnss_pos_ctx_t *c = ctx;
    ekf_rows_gnss_position(&st->nav, &st->nav.pos, &c->meas, c->lever_b_m, h, z);
}

/* The innovation: the filter turns (navigator - measurement) into metres with dr_local_m
 * at the measurement (cos(lat) at the middle), the test in the tangent plane at the true
 * IMU. The radii and cos(lat) change over the distance D between these points by less
 * than 3 D / R (R the Earth's radius, 45 deg N), on a difference of at most D metres:
 * 3 D^2 / R, with D = |innovation| + |l_b| + the 1 m step bounding every distance among
 * the navigator, the antenna, the measurement and the truth. */
static double gnss_pos_allow_z(const void *ctx, const state_t *st, int row)
{
    const gnss_pos_ctx_t *c = ctx;
    (void)row;
    double z[3];
    gnss_pos_h(ctx, st, z);
    const double D = norm_d(z) + c->lever_norm_m + STEP_DR_M;
    return 3.0 * D * D / 6.3e6;
}

static void test_rows_gnss_position(void **state)
{
    (void)state;
    static state_t truth;
    true_state(&truth, SPEED_MPS, MOUNT_PITCH_RAD, MOUNT_YAW_RAD);
    gnss_pos_ctx_t c;
    c.truth_pos = truth.nav.pos;
    lever_of(GNSS_LEVER_B_M, c.lever_b_m);
    c.lever_norm_m = norm_d(GNSS_LEVER_B_M);
    /* the true antenna (IMU + C l_b) measured with an error err, ENU metres */
    const double err[3] = {1.2, -1.9, 0.7};
    const state_d_t s = read_state(&truth);
    double ant[3];
    for (int i = 0; i < 3; i++) {
        ant[i] = s.C_bn[i][0] * (double)c.lever_b_m[0] + s.C_bn[i][1] * (double)c.lever_b_m[1] +
                 s.C_bn[i][2] * (double)c.lever_b_m[2] + err[i];
    }
    c.meas = geo_moved(&truth.nav.pos, ant);
    const meas_t m = {"GNSS position", 3, ENU_ROW,
                      1.0 + c.lever_norm_m + norm_d(err) + STEP_DR_M, gnss_pos_h, gnss_pos_rows,
                      NULL, gnss_pos_allow_z, &c};
    expect_rows_right(&m, &truth);
}

/* ------------------------------------------------------- GNSS velocity ---- */

typedef struct {
    double meas_mps[3];
} vel_ctx_t;

static void gnss_vel_h(const void *ctx, const state_t *st, double *z)
{
    h_velocity(st, ((const vel_ctx_t *)ctx)->meas_mps, z);
}

static void gnss_vel_rows(const void *ctx, const state_t *st, nav_real_t h[][EKF_N],
                          nav_real_t *z)
{
    const vel_ctx_t *c = ctx;
    const nav_real_t meas[3] = {(nav_real_t)c->meas_mps[0], (nav_real_t)c->meas_mps[1],
                                (nav_real_t)c->meas_mps[2]};
    ekf_rows_gnss_velocity(st->nav.v_n_mps, meas, h, z);
}

static void test_rows_gnss_velocity(void **state)
{
    (void)state;
    static state_t truth;
    true_state(&truth, SPEED_MPS, MOUNT_PITCH_RAD, MOUNT_YAW_RAD);
    /* measured with an error (0.05, -0.08, 0.02) m/s, as the filter receives it */
    const double err[3] = {0.05, -0.08, 0.02};
    vel_ctx_t c;
    for (int i = 0; i < 3; i++) {
        c.meas_mps[i] = (double)(nav_real_t)((double)truth.nav.v_n_mps[i] + err[i]);
    }
    const meas_t m = {"GNSS velocity", 3, ENU_ROW, 1.0 + SPEED_MPS, gnss_vel_h, gnss_vel_rows,
                      NULL, NULL, &c};
    expect_rows_right(&m, &truth);
}

/* ---------------------------------------------- odometer and non-holonomic ---- */

typedef struct {
    nav_real_t lever_b_m[3];
    nav_real_t speed_read_mps;
    double lever_norm_m;
    double speed_mps; /* the reference point's true speed */
} odo_ctx_t;

static void odo_h(const void *ctx, const state_t *st, double *z)
{
    const odo_ctx_t *c = ctx;
    h_odometer(st, c->lever_b_m, (double)c->speed_read_mps, z);
}

static void odo_rows(const void *ctx, const state_t *st, nav_real_t h[][EKF_N], nav_real_t *z)
{
    const odo_ctx_t *c = ctx;
    ekf_rows_odometer(&st->kf, &st->nav, st->w_b_rps, c->lever_b_m, c->speed_read_mps, h, z);
}

/* the car axis of each odometer row, and the filter's linear form of it (ekf.h): the
 * lateral axis (1, my, 0), the vertical (0, mp, 1), the forward (0, 1, 0) in IMU axes */
static const int ODO_AXIS[EKF_ODO_ROWS] = {0, 2, 1};

static void odo_linear_axis(const state_d_t *s, int row, double L[3])
{
    L[0] = row == EKF_ODO_LATERAL ? 1.0 : 0.0;
    L[1] = row == EKF_ODO_LATERAL    ? s->mount_yaw_rad
           : row == EKF_ODO_VERTICAL ? s->mount_pitch_rad
                                     : 1.0;
    L[2] = row == EKF_ODO_VERTICAL ? 1.0 : 0.0;
}

/* What the filter's odometer rows neglect (ekf.h), bounded at the truth (a state that
 * meets the constraints: the reference point's velocity along the car's forward axis):
 * - dv and psi: the rows take the car's axis as the IMU's unit axis e_a, the exact row
 *   is R_a (R = car_from_imu): off by g sum_i |R_ai - e_ai| times the largest entry of
 *   d(v_b)/d(dv) (1, a rotation's) or d(v_b)/d(psi) (|v_n|, C^T [v_n x]);
 * - bg: not modelled; the exact entries are g R_a (e_j x l_b), at most g |l_b|;
 * - k and the mounting: the rows take v_b,y (the IMU's forward velocity) for the car's
 *   forward speed: at the truth off by |v| (1 - cos(my) cos(mp)), below |v| (my^2 + mp^2)
 *   / 2 (the entries that are zero are exact there);
 * with g = 1 + k on the forward row, 1 on the others. */
static double odo_allow_h(const void *ctx, const state_t *truth, int row, int col)
{
    const odo_ctx_t *c = ctx;
    const state_d_t s = read_state(truth);
    const double g = row == EKF_ODO_FORWARD ? 1.0 + s.k : 1.0;
    if (col >= EKF_DV && col < EKF_BG) {
        double R[3][3];
        car_from_imu(s.mount_pitch_rad, s.mount_yaw_rad, R);
        const int a = ODO_AXIS[row];
        double rho = 0.0;
        for (int i = 0; i < 3; i++) {
            rho += fabs(R[a][i] - (i == a ? 1.0 : 0.0));
        }
        return g * rho * (col < EKF_PSI ? 1.0 : norm_d(s.v_n_mps));
    }
    if ((col >= EKF_BG && col < EKF_BA) || col == EKF_GZ) {
        return g * c->lever_norm_m;
    }
    if (col == EKF_SG) { /* as the bias: the rate's error in the lever arm, w_z per unit */
        return g * c->lever_norm_m * fabs((double)truth->w_b_rps[2]);
    }
    if (col >= EKF_K && col < EKF_GB) { /* the scale and the mounting; the offset's entry is exact */
        const double my = s.mount_yaw_rad, mp = s.mount_pitch_rad;
        return (1.0 + fabs(s.k)) * c->speed_mps * 0.5 * (my * my + mp * mp);
    }
    return 0.0;
}

/* The innovation: the filter's linear car axis L_a against the exact R_a, at any state:
 * off by g sum_i |L_ai - R_ai| |v_b,i| (v_b the reference point's velocity, IMU axes). */
static double odo_allow_z(const void *ctx, const state_t *st, int row)
{
    const odo_ctx_t *c = ctx;
    const state_d_t s = read_state(st);
    double v_b[3], R[3][3], L[3];
    ref_point_velocity_b(&s, c->lever_b_m, v_b);
    car_from_imu(s.mount_pitch_rad, s.mount_yaw_rad, R);
    odo_linear_axis(&s, row, L);
    double a = 0.0;
    for (int i = 0; i < 3; i++) {
        a += fabs(L[i] - R[ODO_AXIS[row]][i]) * fabs(v_b[i]);
    }
    return (row == EKF_ODO_FORWARD ? 1.0 + fabs(s.k) : 1.0) * a;
}

static void odo_case(state_t *truth, odo_ctx_t *c, meas_t *m, const char *name,
                     double mount_pitch_rad, double mount_yaw_rad)
{
    true_state(truth, SPEED_MPS, mount_pitch_rad, mount_yaw_rad);
    lever_of(ODO_LEVER_B_M, c->lever_b_m);
    c->lever_norm_m = norm_d(ODO_LEVER_B_M);
    c->speed_mps = SPEED_MPS;
    /* the odometer reads (1 + k) x the true speed plus its offset, and 0.04 m/s more */
    c->speed_read_mps = (nav_real_t)((1.0 + (double)truth->kf.k) * SPEED_MPS +
                                     (double)truth->kf.odo_offset_mps + 0.04);
    const meas_t mm = {name, EKF_ODO_ROWS, ODO_ROW,
                       1.0 + SPEED_MPS + norm_d(W_TURN_B_RPS) * c->lever_norm_m, odo_h,
                       odo_rows, odo_allow_h, odo_allow_z, c};
    *m = mm;
}

static void expect_odometer_rows_right(const char *name, double mount_pitch_rad,
                                       double mount_yaw_rad)
{
    static state_t truth;
    odo_ctx_t c;
    meas_t m;
    odo_case(&truth, &c, &m, name, mount_pitch_rad, mount_yaw_rad);
    expect_rows_right(&m, &truth);
}

/* The IMU aligned with the car: the rows must be the exact derivative but for the
 * unmodelled gyro bias. */
static void test_rows_odometer_aligned(void **state)
{
    (void)state;
    expect_odometer_rows_right("odometer + NHC, IMU aligned", 0.0, 0.0);
}

/* Mounted 0.4 deg nose up and 0.7 deg left (anticlockwise) of the car: the mounting's own
 * part of the dv and psi entries and the second-order terms of the k and mounting entries
 * are neglected (ekf.h), within the allowances of odo_allow_h. */
static void test_rows_odometer_mounted(void **state)
{
    (void)state;
    expect_odometer_rows_right("odometer + NHC, IMU mounted", MOUNT_PITCH_RAD, MOUNT_YAW_RAD);
}

/* The checker itself refuses a wrong row: the lateral row's mounting yaw entry halved,
 * and the lever arm's sign flipped (in the rows and the innovation of a copy). */
static void wrong_rows(const void *ctx, const state_t *st, nav_real_t h[][EKF_N], nav_real_t *z)
{
    odo_rows(ctx, st, h, z);
    h[EKF_ODO_LATERAL][EKF_MY] *= NAV_C(0.5);
}

static void flipped_lever_rows(const void *ctx, const state_t *st, nav_real_t h[][EKF_N],
                               nav_real_t *z)
{
    odo_ctx_t c = *(const odo_ctx_t *)ctx;
    for (int i = 0; i < 3; i++) {
        c.lever_b_m[i] = -c.lever_b_m[i];
    }
    odo_rows(&c, st, h, z);
}

static void test_check_refuses_wrong_rows(void **state)
{
    (void)state;
    static state_t truth;
    odo_ctx_t c;
    meas_t m;
    odo_case(&truth, &c, &m, "odometer (made wrong)", MOUNT_PITCH_RAD, MOUNT_YAW_RAD);
    m.rows = wrong_rows;
    verdict_t v = check_meas(&m, &truth);
    print_message("refused as it should be, the lateral row's mounting yaw entry halved: %d "
                  "row entries (%s)\n", v.n_bad[ROW_ENTRY], v.first[ROW_ENTRY]);
    assert_true(v.n_bad[ROW_ENTRY] >= 1);
    m.rows = flipped_lever_rows;
    v = check_meas(&m, &truth);
    print_message("refused as it should be, the lever arm's sign flipped: %d row entries, %d "
                  "innovations (%s)\n", v.n_bad[ROW_ENTRY], v.n_bad[INNOVATION],
                  v.first[ROW_ENTRY]);
    assert_true(v.n_bad[ROW_ENTRY] >= 1 && v.n_bad[INNOVATION] >= 1);
}

/* ------------------------------------------------------------ standstill ---- */

static void zupt_h(const void *ctx, const state_t *st, double *z)
{
    (void)ctx;
    const double zero[3] = {0.0, 0.0, 0.0};
    h_velocity(st, zero, z);
}

static void zupt_rows(const void *ctx, const state_t *st, nav_real_t h[][EKF_N], nav_real_t *z)
{
    (void)ctx;
    ekf_rows_zero_velocity(&st->nav, h, z);
}

static void test_rows_zero_velocity(void **state)
{
    (void)state;
    static state_t truth;
    true_state(&truth, 0.0, MOUNT_PITCH_RAD, MOUNT_YAW_RAD);
    const meas_t m = {"zero velocity", 3, ENU_ROW, 1.0, zupt_h, zupt_rows, NULL, NULL, NULL};
    expect_rows_right(&m, &truth);
}

static void zaru_h(const void *ctx, const state_t *st, double *z)
{
    (void)ctx;
    z[0] = h_zero_rate(st);
}

/* the residual rate is formed by the application (app.c: the compensated z rate minus
 * the Earth's rate on the body z axis); the test forms it as h_zero_rate does, in
 * nav_real_t as the application hands it over */
static void zaru_rows(const void *ctx, const state_t *st, nav_real_t h[][EKF_N], nav_real_t *z)
{
    (void)ctx;
    ekf_rows_zero_rate((nav_real_t)h_zero_rate(st), h, z);
}

/* What the zero-rate row neglects (ekf.h): the Earth's rate removed is the navigator's,
 * turned by its attitude error, (C^T [w_ie x] psi)_z, at most |w_ie| per rad; and taken
 * at its latitude, d(w_ie)/d(lat) = |w_ie| per rad, over the radius: |w_ie| / (R_M + h)
 * per metre. */
static double zaru_allow_h(const void *ctx, const state_t *truth, int row, int col)
{
    (void)ctx;
    (void)row;
    const double h = (double)truth->nav.pos.h * M_PER_HLSB;
    if (col >= EKF_PSI && col < EKF_BG) {
        return WGS84_OMEGA_IE_RPS;
    }
    if (col < EKF_DV) {
        return WGS84_OMEGA_IE_RPS / (6.3e6 + h);
    }
    if (col == EKF_SG) { /* the scale of a standing car's rate, the Earth's */
        return WGS84_OMEGA_IE_RPS;
    }
    return 0.0;
}

static void test_rows_zero_rate(void **state)
{
    (void)state;
    static state_t truth;
    true_state(&truth, 0.0, MOUNT_PITCH_RAD, MOUNT_YAW_RAD);
    static const char *const Z_ROW[1] = {"z rate"};
    const meas_t m = {"zero rate", 1, Z_ROW, 1.0, zaru_h, zaru_rows, zaru_allow_h, NULL, NULL};
    expect_rows_right(&m, &truth);
}


/* ------------------------------------------------ raw GNSS (issue #20) ---- */

/* WGS-84 ECEF of a geodetic position, double */
static void ecef_of(double lat, double lon, double h, double x[3])
{
    const double n = WGS84_A_M / sqrt(1.0 - WGS84_E2 * sin(lat) * sin(lat));
    x[0] = (n + h) * cos(lat) * cos(lon);
    x[1] = (n + h) * cos(lat) * sin(lon);
    x[2] = (n * (1.0 - WGS84_E2) + h) * sin(lat);
}

/* ENU axes at (lat, lon) as ECEF unit vectors: rows east, north, up */
static void enu_axes(double lat, double lon, double E[3][3])
{
    const double sl = sin(lat), cl = cos(lat), so = sin(lon), co = cos(lon);
    const double e[3][3] = {{-so, co, 0.0}, {-sl * co, -sl * so, cl}, {cl * co, cl * so, sl}};
    memcpy(E, e, sizeof e);
}

/* the satellite of the raw tests, in the protocol's units */
typedef struct {
    int32_t pos_lsb[3];
    int16_t vel_lsb[3];
    uint32_t pr_lsb;
    nav_real_t rr_mps;
    nav_real_t lever_b_m[3];
    double lever_norm_m;
    double rel_speed_mps; /* |v_sat| + |v_antenna|: for the line of sight's allowance */
} raw_ctx_t;

/* The truth for a state: the antenna (IMU + C l_b, exact in ECEF) and its velocity
 * (v + C (w_b x l_b)) in ECEF; the satellite turned from its transmit-time axes into the
 * receive-time ones by the Earth's rotation during the travel (IS-GPS-200
 * 20.3.3.4.3.3.2), the travel time iterated to convergence; the unit line of sight. */
typedef struct {
    double range_m, u[3], v_rel_los_mps, clock_m, drift_mps;
    double u_enu[3]; /* the line of sight in the navigator's ENU axes */
} raw_truth_t;

static raw_truth_t raw_geometry(const raw_ctx_t *c, const state_t *st)
{
    const state_d_t s = read_state(st);
    double E[3][3], imu[3], l_n[3], wl_b[3], wl_n[3], v_a_n[3], ant[3], v_a[3];
    enu_axes(s.lat_rad, s.lon_rad, E);
    ecef_of(s.lat_rad, s.lon_rad, s.h_m, imu);
    const double l[3] = {(double)c->lever_b_m[0], (double)c->lever_b_m[1],
                         (double)c->lever_b_m[2]};
    cross_d(s.w_b_rps, l, wl_b);
    for (int i = 0; i < 3; i++) {
        l_n[i] = s.C_bn[i][0] * l[0] + s.C_bn[i][1] * l[1] + s.C_bn[i][2] * l[2];
        wl_n[i] = s.C_bn[i][0] * wl_b[0] + s.C_bn[i][1] * wl_b[1] + s.C_bn[i][2] * wl_b[2];
        v_a_n[i] = s.v_n_mps[i] + wl_n[i];
    }
    for (int i = 0; i < 3; i++) {
        ant[i] = imu[i] + E[0][i] * l_n[0] + E[1][i] * l_n[1] + E[2][i] * l_n[2];
        v_a[i] = E[0][i] * v_a_n[0] + E[1][i] * v_a_n[1] + E[2][i] * v_a_n[2];
    }
    const double sp[3] = {c->pos_lsb[0] * 0.02, c->pos_lsb[1] * 0.02, c->pos_lsb[2] * 0.02};
    const double sv[3] = {c->vel_lsb[0] * 0.125, c->vel_lsb[1] * 0.125, c->vel_lsb[2] * 0.125};
    raw_truth_t t;
    double d[3], rs[3], rv[3], tau = 0.0;
    for (int it = 0; it < 5; it++) {
        const double th = WGS84_OMEGA_IE_RPS * tau;
        rs[0] = cos(th) * sp[0] + sin(th) * sp[1];
        rs[1] = -sin(th) * sp[0] + cos(th) * sp[1];
        rs[2] = sp[2];
        rv[0] = cos(th) * sv[0] + sin(th) * sv[1];
        rv[1] = -sin(th) * sv[0] + cos(th) * sv[1];
        rv[2] = sv[2];
        for (int i = 0; i < 3; i++) {
            d[i] = rs[i] - ant[i];
        }
        t.range_m = norm_d(d);
        tau = t.range_m / 299792458.0;
    }
    t.v_rel_los_mps = 0.0;
    for (int i = 0; i < 3; i++) {
        t.u[i] = d[i] / t.range_m;
        t.v_rel_los_mps += t.u[i] * (rv[i] - v_a[i]);
    }
    for (int i = 0; i < 3; i++) {
        t.u_enu[i] = E[i][0] * t.u[0] + E[i][1] * t.u[1] + E[i][2] * t.u[2];
    }
    t.clock_m = (double)st->kf.clock_dmm / (double)GNSS_GEOM_DMM_PER_M;
    t.drift_mps = (double)st->kf.clock_drift_mps;
    return t;
}

static void pr_h(const void *ctx, const state_t *st, double *z)
{
    const raw_ctx_t *c = ctx;
    const raw_truth_t t = raw_geometry(c, st);
    /* the correlated error estimate b shortens the predicted range by u . b */
    z[0] = t.range_m + t.clock_m - (double)c->pr_lsb * 0.02 -
           (t.u_enu[0] * (double)st->kf.gnss_bias_m[0] + t.u_enu[1] * (double)st->kf.gnss_bias_m[1]);
}

/* the antenna and the satellite's geometry, then the row, as fusion.c forms them */
static void raw_geometry_of(const raw_ctx_t *c, const state_t *st, ekf_antenna_t *a,
                            ekf_sat_t *sat)
{
    assert_int_equal(ekf_antenna(&st->nav, &st->nav.pos, c->lever_b_m, a), NAV_OK);
    assert_int_equal(ekf_sat_geometry(a, c->pos_lsb, c->vel_lsb, sat), NAV_OK);
}

static void pr_rows(const void *ctx, const state_t *st, nav_real_t h[][EKF_N], nav_real_t *z)
{
    const raw_ctx_t *c = ctx;
    ekf_antenna_t a;
    ekf_sat_t sat;
    raw_geometry_of(c, st, &a, &sat);
    ekf_rows_pseudorange(&st->kf, &a, &sat, c->pr_lsb, 1, h[0], z);
}

/* The innovation, formed in 0.1 mm integers (gnss_geom.h): the antenna's ECEF rounded to
 * 0.1 mm per axis (0.05 mm each, 0.087 mm along any line of sight), the Earth-rotation
 * correction rounded to 0.1 mm (0.07 mm), the range's refinement (0.01 mm,
 * test_gnss_geom), the antenna added to the position in its 1e-7 mm units, and the lever
 * arm turned in nav_real_t: |l| eps; 0.2 mm in all, and the float32 sum of a residual of
 * |z| m (eps |z|). */
static double pr_allow_z(const void *ctx, const state_t *st, int row)
{
    const raw_ctx_t *c = ctx;
    double z;
    (void)row;
    pr_h(ctx, st, &z);
    return 2.0e-4 + NAV_EPS * (fabs(z) + c->lever_norm_m);
}

static double sat_radius_m(const raw_ctx_t *c)
{
    return 0.02 * sqrt((double)c->pos_lsb[0] * c->pos_lsb[0] +
                       (double)c->pos_lsb[1] * c->pos_lsb[1] +
                       (double)c->pos_lsb[2] * c->pos_lsb[2]);
}

/* Allowances of the raw rows' entries. Model, what the pseudorange row neglects (ekf.h):
 * the Earth's rotation during the signal's travel changes with the range, w_ie |r_sat| / c
 * per metre of position. Numerical, beyond the file comment's: the first-principles range
 * is a difference of coordinates of |r_sat| = 2.7e7 m, each evaluation rounded to
 * 16 eps_d |r_sat| (4e-9 m) however small the step's effect, so the central difference is
 * off by that over the step; and the filter's line of sight comes from the 0.1 mm geometry,
 * 2e-4 m over the range in direction, on entries up to S. */
static double raw_allow_h(const raw_ctx_t *c, const state_t *truth, int col, double S,
                          double z_size)
{
    const raw_truth_t t = raw_geometry(c, truth);
    return 16.0 * DBL_EPSILON * z_size / step_of(col) + 2.0e-4 / t.range_m * S;
}

static double pr_allow_h(const void *ctx, const state_t *truth, int row, int col)
{
    const raw_ctx_t *c = ctx;
    (void)row;
    const double sagnac = col < EKF_DV ? WGS84_OMEGA_IE_RPS * sat_radius_m(c) / 299792458.0
                                       : 0.0;
    return sagnac + raw_allow_h(c, truth, col, 1.0 + c->lever_norm_m, sat_radius_m(c));
}

static void rr_h(const void *ctx, const state_t *st, double *z)
{
    const raw_ctx_t *c = ctx;
    const raw_truth_t t = raw_geometry(c, st);
    z[0] = t.v_rel_los_mps + t.drift_mps - (double)c->rr_mps;
}

static void rr_rows(const void *ctx, const state_t *st, nav_real_t h[][EKF_N], nav_real_t *z)
{
    const raw_ctx_t *c = ctx;
    ekf_antenna_t a;
    ekf_sat_t sat;
    raw_geometry_of(c, st, &a, &sat);
    ekf_rows_range_rate(&st->kf, &st->nav, st->nav.v_n_mps, st->w_b_rps, c->lever_b_m, &sat,
                        c->rr_mps, h[0], z);
}

/* What the range-rate row neglects (ekf.h): the line of sight turns with the position
 * error by 1/r per metre, changing u . (v_sat - v_a) by at most |v_sat - v_a| / r (the
 * antenna's error: dr, and psi through the lever arm, |l_b| per rad); and the
 * numerical allowances of raw_allow_h (the first-principles rate's rounding is on
 * velocities of the satellite's size). */
static double rr_allow_h(const void *ctx, const state_t *truth, int row, int col)
{
    const raw_ctx_t *c = ctx;
    (void)row;
    const raw_truth_t t = raw_geometry(c, truth);
    /* the antenna moves by 1 m per metre of dr, by |l_b| per rad of psi */
    const double los = col < EKF_DV                      ? c->rel_speed_mps / t.range_m
                       : (col >= EKF_PSI && col < EKF_BG) ? c->rel_speed_mps / t.range_m *
                                                                c->lever_norm_m
                                                          : 0.0;
    return los + raw_allow_h(c, truth, col, 1.0 + SPEED_MPS + c->lever_norm_m,
                             c->rel_speed_mps);
}

/* The innovation: nav_real_t sums of terms up to the satellite's speed (eps each), and
 * the line of sight from the 0.1 mm geometry (0.2 mm over the range) times the relative
 * speed. */
static double rr_allow_z(const void *ctx, const state_t *st, int row)
{
    const raw_ctx_t *c = ctx;
    (void)row;
    const raw_truth_t t = raw_geometry(c, st);
    return 8.0 * NAV_EPS * (c->rel_speed_mps + fabs((double)st->kf.clock_drift_mps) +
                            fabs((double)c->rr_mps)) +
           c->rel_speed_mps * 2.0e-4 / t.range_m;
}

/* A satellite 20,200 km up at elevation 35 deg, azimuth 60 deg of the true state, moving
 * at 3.1 km/s; the receiver clock 4,321.2345 m ahead, drifting 57.3 m/s; the pseudorange
 * 2.7 m long, the rate 0.06 m/s high. */
static void raw_case(state_t *truth, raw_ctx_t *c)
{
    true_state(truth, SPEED_MPS, MOUNT_PITCH_RAD, MOUNT_YAW_RAD);
    truth->kf.clock_dmm = 43212345;
    truth->kf.clock_drift_mps = NAV_C(57.3);
    truth->kf.gnss_bias_m[0] = NAV_C(0.8);
    truth->kf.gnss_bias_m[1] = NAV_C(-1.3);
    lever_of(GNSS_LEVER_B_M, c->lever_b_m);
    c->lever_norm_m = norm_d(GNSS_LEVER_B_M);
    const state_d_t s = read_state(truth);
    double E[3][3], rx[3];
    enu_axes(s.lat_rad, s.lon_rad, E);
    ecef_of(s.lat_rad, s.lon_rad, s.h_m, rx);
    const double el = 35.0 * DEG, az = 60.0 * DEG;
    const double los_n[3] = {cos(el) * sin(az), cos(el) * cos(az), sin(el)};
    /* the range to a satellite at 26,560 km from the centre along the line of sight */
    double los[3], b = 0.0, r2 = 0.0;
    for (int i = 0; i < 3; i++) {
        los[i] = E[0][i] * los_n[0] + E[1][i] * los_n[1] + E[2][i] * los_n[2];
        b += rx[i] * los[i];
        r2 += rx[i] * rx[i];
    }
    const double R = 26.56e6;
    const double rho = -b + sqrt(b * b - r2 + R * R);
    const double vs[3] = {-1850.0, 2290.0, 1125.0};
    for (int i = 0; i < 3; i++) {
        c->pos_lsb[i] = (int32_t)llround((rx[i] + rho * los[i]) / 0.02);
        c->vel_lsb[i] = (int16_t)lround(vs[i] / 0.125);
    }
    c->rel_speed_mps = norm_d(vs) + SPEED_MPS + 1.0;
    c->pr_lsb = 0u;
    c->rr_mps = NAV_C(0.0);
    const raw_truth_t t = raw_geometry(c, truth);
    c->pr_lsb = (uint32_t)llround((t.range_m + t.clock_m + 2.7) / 0.02);
    c->rr_mps = (nav_real_t)(t.v_rel_los_mps + t.drift_mps + 0.06);
}

static const char *const RAW_ROW[1] = {"satellite"};

static void test_rows_pseudorange(void **state)
{
    (void)state;
    static state_t truth;
    raw_ctx_t c;
    raw_case(&truth, &c);
    const meas_t m = {"pseudorange", 1, RAW_ROW, 1.0 + c.lever_norm_m + 2.7 + STEP_DR_M, pr_h,
                      pr_rows, pr_allow_h, pr_allow_z, &c};
    expect_rows_right(&m, &truth);
}

static void test_rows_range_rate(void **state)
{
    (void)state;
    static state_t truth;
    raw_ctx_t c;
    raw_case(&truth, &c);
    const meas_t m = {"pseudorange rate", 1, RAW_ROW,
                      1.0 + SPEED_MPS + norm_d(W_TURN_B_RPS) * c.lever_norm_m, rr_h, rr_rows,
                      rr_allow_h, rr_allow_z, &c};
    expect_rows_right(&m, &truth);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rows_gnss_position),
        cmocka_unit_test(test_rows_gnss_velocity),
        cmocka_unit_test(test_rows_odometer_aligned),
        cmocka_unit_test(test_rows_odometer_mounted),
        cmocka_unit_test(test_rows_zero_velocity),
        cmocka_unit_test(test_rows_zero_rate),
        cmocka_unit_test(test_rows_pseudorange),
        cmocka_unit_test(test_rows_range_rate),
        cmocka_unit_test(test_check_refuses_wrong_rows),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
