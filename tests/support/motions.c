/* motions.c - see motions.h. */
#include "motions.h"

#include "nav_run.h"

#include <math.h>

#define PI 3.14159265358979323846

void kin_still(const void *ctx, double t, kin_t *k)
{
    const still_t *s = ctx;
    (void)t;
    for (int i = 0; i < 3; i++) {
        k->v_n_mps[i] = 0.0;
        k->a_n_mps2[i] = 0.0;
        k->w_nb_b_rps[i] = 0.0;
    }
    truth_q_from_euler(s->roll, s->pitch, s->heading, k->q_bn);
}

void kin_circle(const void *ctx, double t, kin_t *k)
{
    const circle_t *c = ctx;
    const double w = 2.0 * PI / c->period_s;
    const double s = c->s0_mps * (1.0 - cos(w * t));
    const double sd = c->s0_mps * w * sin(w * t);
    const double dist = c->s0_mps * (t - sin(w * t) / w);
    const double H = c->heading0_rad + dist / c->radius_m;
    const double Hd = s / c->radius_m;
    k->v_n_mps[0] = s * sin(H);
    k->v_n_mps[1] = s * cos(H);
    k->v_n_mps[2] = 0.0;
    k->a_n_mps2[0] = sd * sin(H) + s * Hd * cos(H);
    k->a_n_mps2[1] = sd * cos(H) - s * Hd * sin(H);
    k->a_n_mps2[2] = 0.0;
    /* body roll: 0.008 rad per m/s^2 of lateral acceleration s^2/R, out of the turn
     * (right turn, left side down: negative roll), plus suspension motion */
    const double k_roll = 0.008, wr = 2.0 * PI / 3.1, wp = 2.0 * PI / 7.0;
    const double roll = -k_roll * s * s / c->radius_m + 0.005 * sin(wr * t);
    const double roll_rate = -k_roll * 2.0 * s * sd / c->radius_m + 0.005 * wr * cos(wr * t);
    const double pitch = 0.01 * sin(wp * t);
    const double pitch_rate = 0.01 * wp * cos(wp * t);
    truth_q_from_euler(roll, pitch, H, k->q_bn);
    truth_w_nb_from_euler_rates(roll, pitch, roll_rate, pitch_rate, Hd, k->w_nb_b_rps);
}

void kin_cone(const void *ctx, double t, kin_t *k)
{
    const cone_t *c = ctx;
    const double sa2 = sin(0.5 * c->alpha_rad), ca2 = cos(0.5 * c->alpha_rad);
    const double wt = c->omega_rps * t;
    /* q_cone = [cos(a/2), 0, sin(a/2) cos(wt), sin(a/2) sin(wt)]; its body rate follows from
     * w = 2 q* (x) dq/dt: (-2 W sin^2(a/2), -W sin(a) sin(wt), W sin(a) cos(wt)). */
    const double qc[4] = {ca2, 0.0, sa2 * cos(wt), sa2 * sin(wt)};
    for (int i = 0; i < 3; i++) {
        k->v_n_mps[i] = 0.0;
        k->a_n_mps2[i] = 0.0;
    }
    k->q_bn[0] = c->q0[0] * qc[0] - c->q0[1] * qc[1] - c->q0[2] * qc[2] - c->q0[3] * qc[3];
    k->q_bn[1] = c->q0[0] * qc[1] + c->q0[1] * qc[0] + c->q0[2] * qc[3] - c->q0[3] * qc[2];
    k->q_bn[2] = c->q0[0] * qc[2] - c->q0[1] * qc[3] + c->q0[2] * qc[0] + c->q0[3] * qc[1];
    k->q_bn[3] = c->q0[0] * qc[3] + c->q0[1] * qc[2] - c->q0[2] * qc[1] + c->q0[3] * qc[0];
    k->w_nb_b_rps[0] = -2.0 * c->omega_rps * sa2 * sa2;
    k->w_nb_b_rps[1] = -c->omega_rps * sin(c->alpha_rad) * sin(wt);
    k->w_nb_b_rps[2] = c->omega_rps * sin(c->alpha_rad) * cos(wt);
}

void kin_scull(const void *ctx, double t, kin_t *k)
{
    const scull_t *c = ctx;
    const double wt = c->omega_rps * t;
    k->v_n_mps[0] = 0.0;
    k->v_n_mps[1] = c->a0_mps2 / c->omega_rps * (1.0 - cos(wt));
    k->v_n_mps[2] = 0.0;
    k->a_n_mps2[0] = 0.0;
    k->a_n_mps2[1] = c->a0_mps2 * sin(wt);
    k->a_n_mps2[2] = 0.0;
    const double psi = c->psi0_rad * sin(wt);
    truth_q_from_euler(0.0, 0.0, psi, k->q_bn);
    truth_w_nb_from_euler_rates(0.0, 0.0, 0.0, 0.0, c->psi0_rad * c->omega_rps * cos(wt),
                                k->w_nb_b_rps);
}

run_spec_t run_spec_default(kin_fn kin, const void *ctx, double duration_s, double rate_hz)
{
    run_spec_t spec = {0};
    spec.kin = kin;
    spec.ctx = ctx;
    spec.lat0_rad = 45.0 * PI / 180.0;
    spec.lon0_rad = 10.0 * PI / 180.0;
    spec.h0_m = 100.0;
    spec.rate_hz = rate_hz;
    spec.duration_s = duration_s;
    spec.coning_sculling = 1;
    spec.vdamp = 1;
    return spec;
}
