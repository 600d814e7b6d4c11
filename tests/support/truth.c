/* truth.c - see truth.h. Compiled as the double variant (NAV_REAL_DOUBLE). */
#include "truth.h"

#include <math.h>

#include "earth.h"
#include "nav_math.h"

/* 5-point Gauss-Legendre on [-1, 1] */
static const double GL_X[5] = {-0.9061798459386640, -0.5384693101056831, 0.0,
                               0.5384693101056831, 0.9061798459386640};
static const double GL_W[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                               0.4786286704993665, 0.2369268850561891};

void truth_init(truth_gen_t *g, kin_fn kin, const void *ctx, double lat_rad, double lon_rad,
                double h_m)
{
    g->kin = kin;
    g->ctx = ctx;
    g->t_s = 0.0;
    g->lat_rad = lat_rad;
    g->lon_rad = lon_rad;
    g->h_m = h_m;
}

/* d(lat, lon, h)/dt at a position for velocity v_n (seed 001 eq. 6) */
static void pos_rate(double lat, double h, const double v[3], double out[3])
{
    double rm, rn;
    earth_radii_f64(sin(lat), &rm, &rn);
    out[0] = v[1] / (rm + h);
    out[1] = v[0] / ((rn + h) * cos(lat));
    out[2] = v[2];
}

/* Inertial rate and specific force in the body frame at time t, position (lat, h). */
static void sensed(const truth_gen_t *g, double t, double lat, double h, double w_ib_b[3],
                   double f_b[3])
{
    kin_t k;
    g->kin(g->ctx, t, &k);
    earth_t e;
    earth_eval_f64(lat, h, &e);
    double w_en[3], w_in[3], w_cor[3], a_cor[3], f_n[3];
    mat3_t C;
    earth_transport_rate_f64(&e, h, k.v_n_mps, w_en);
    for (int i = 0; i < 3; i++) {
        w_in[i] = e.w_ie_n_rps[i] + w_en[i];
        w_cor[i] = 2.0 * e.w_ie_n_rps[i] + w_en[i];
    }
    vec3_cross_f64(w_cor, k.v_n_mps, a_cor);
    for (int i = 0; i < 3; i++) {
        f_n[i] = k.a_n_mps2[i] + a_cor[i];
    }
    f_n[2] += e.g_mps2; /* f = dv/dt + (2 w_ie + w_en) x v - g, g_n = (0, 0, -g) */
    quat_to_dcm_f64(k.q_bn, &C);
    mat3t_mul_vec_f64(&C, f_n, f_b);
    mat3t_mul_vec_f64(&C, w_in, w_ib_b);
    for (int i = 0; i < 3; i++) {
        w_ib_b[i] += k.w_nb_b_rps[i];
    }
}

void truth_step(truth_gen_t *g, double dt, double dtheta_b_rad[3], double dv_b_mps[3])
{
    const double t0 = g->t_s;
    /* position rate at t0, used to place the quadrature nodes' positions: the sensed
     * quantities depend on position only through Earth rate, transport rate and gravity,
     * whose change over one interval is far below double rounding of the increments. */
    kin_t k0, km, k1;
    g->kin(g->ctx, t0, &k0);
    double p0[3];
    pos_rate(g->lat_rad, g->h_m, k0.v_n_mps, p0);

    for (int i = 0; i < 3; i++) {
        dtheta_b_rad[i] = 0.0;
        dv_b_mps[i] = 0.0;
    }
    for (int n = 0; n < 5; n++) {
        const double tau = 0.5 * dt * (GL_X[n] + 1.0);
        double w[3], f[3];
        sensed(g, t0 + tau, g->lat_rad + p0[0] * tau, g->h_m + p0[2] * tau, w, f);
        for (int i = 0; i < 3; i++) {
            dtheta_b_rad[i] += 0.5 * dt * GL_W[n] * w[i];
            dv_b_mps[i] += 0.5 * dt * GL_W[n] * f[i];
        }
    }

    /* RK4 of the position over the interval */
    g->kin(g->ctx, t0 + 0.5 * dt, &km);
    g->kin(g->ctx, t0 + dt, &k1);
    double r1[3], r2[3], r3[3], r4[3];
    r1[0] = p0[0]; r1[1] = p0[1]; r1[2] = p0[2];
    pos_rate(g->lat_rad + 0.5 * dt * r1[0], g->h_m + 0.5 * dt * r1[2], km.v_n_mps, r2);
    pos_rate(g->lat_rad + 0.5 * dt * r2[0], g->h_m + 0.5 * dt * r2[2], km.v_n_mps, r3);
    pos_rate(g->lat_rad + dt * r3[0], g->h_m + dt * r3[2], k1.v_n_mps, r4);
    g->lat_rad += dt / 6.0 * (r1[0] + 2.0 * r2[0] + 2.0 * r3[0] + r4[0]);
    g->lon_rad += dt / 6.0 * (r1[1] + 2.0 * r2[1] + 2.0 * r3[1] + r4[1]);
    g->h_m += dt / 6.0 * (r1[2] + 2.0 * r2[2] + 2.0 * r3[2] + r4[2]);
    g->t_s = t0 + dt;
}

void truth_q_from_euler(double roll, double pitch, double heading, double q_bn[4])
{
    quat_from_euler_f64(roll, pitch, heading, q_bn);
}

void truth_w_nb_from_euler_rates(double roll, double pitch, double roll_rate,
                                 double pitch_rate, double heading_rate, double w_nb_b[3])
{
    /* C_bn = Rz(-H) Rx(p) Ry(r)  =>  w_nb_b = Ry(r)^T [Rx(p)^T (0,0,-H') + (p',0,0)]
     * + (0,r',0) */
    const double cp = cos(pitch), sp = sin(pitch), cr = cos(roll), sr = sin(roll);
    /* Rx(p)^T (0,0,-H') = (0, -sp*(-H')... ) computed explicitly: */
    const double ax = pitch_rate;
    const double ay = -heading_rate * sp;
    const double az = -heading_rate * cp;
    /* Ry(r)^T (ax, ay, az) */
    w_nb_b[0] = cr * ax - sr * az;
    w_nb_b[1] = ay + roll_rate;
    w_nb_b[2] = sr * ax + cr * az;
}

double truth_att_err_rad(const double q_true[4], const double q_est[4])
{
    const double qc[4] = {q_true[0], -q_true[1], -q_true[2], -q_true[3]};
    double d[4];
    quat_mul_f64(qc, q_est, d);
    const double v = sqrt(d[1] * d[1] + d[2] * d[2] + d[3] * d[3]);
    return 2.0 * atan2(v, fabs(d[0]));
}

double truth_horiz_dist_m(double lat1, double lon1, double lat2, double lon2, double h_m)
{
    double rm, rn;
    earth_radii_f64(sin(0.5 * (lat1 + lat2)), &rm, &rn);
    double dlon = lon2 - lon1;
    const double pi = 3.14159265358979323846;
    if (dlon > pi) {
        dlon -= 2.0 * pi;
    } else if (dlon < -pi) {
        dlon += 2.0 * pi;
    }
    const double dn = (lat2 - lat1) * (rm + h_m);
    const double de = dlon * (rn + h_m) * cos(0.5 * (lat1 + lat2));
    return sqrt(dn * dn + de * de);
}

void truth_radii(double lat_rad, double *R_M_m, double *R_N_m)
{
    earth_radii_f64(sin(lat_rad), R_M_m, R_N_m);
}

double truth_gravity(double lat_rad, double h_m)
{
    return earth_gravity_f64(sin(lat_rad), h_m);
}
