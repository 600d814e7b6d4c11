/*
 * dr_acc.c - the dead reckoning's error covariance (dr_acc.h).
 */
#include "dr_acc.h"

#include <stddef.h>

static void clear(dr_acc_t *a)
{
    for (int i = 0; i < DR_ACC_NX; i++) {
        for (int j = 0; j < DR_ACC_NX; j++) {
            a->P[i][j] = NAV_C(0.0);
        }
    }
}

void dr_acc_start(dr_acc_t *a, nav_real_t pos_sigma_m, nav_real_t mu_sigma,
                  nav_real_t psi_sigma_rad, nav_real_t b_sigma_rps, nav_real_t s_sigma)
{
    clear(a);
    a->P[DR_ACC_E][DR_ACC_E] = pos_sigma_m * pos_sigma_m;
    a->P[DR_ACC_N][DR_ACC_N] = pos_sigma_m * pos_sigma_m;
    a->P[DR_ACC_MU][DR_ACC_MU] = mu_sigma * mu_sigma;
    a->P[DR_ACC_PSI][DR_ACC_PSI] = psi_sigma_rad * psi_sigma_rad;
    a->P[DR_ACC_B][DR_ACC_B] = b_sigma_rps * b_sigma_rps;
    a->P[DR_ACC_S][DR_ACC_S] = s_sigma * s_sigma;
    a->psi_var_base = a->P[DR_ACC_PSI][DR_ACC_PSI];
    a->base_var_m2 = pos_sigma_m * pos_sigma_m;
    a->valid = 1u;
}

/* row dst += k row src (col 0) or column dst += k column src (col 1): F P F' for
 * F = I + G done in place, a row operation and a column operation per entry of G (no
 * temporaries on the stack) */
static void axpy(dr_acc_t *a, int dst, int src, nav_real_t k, int col)
{
    for (int i = 0; i < DR_ACC_NX; i++) {
        if (col != 0) {
            a->P[i][dst] += k * a->P[i][src];
        } else {
            a->P[dst][i] += k * a->P[src][i];
        }
    }
}

void dr_acc_move(dr_acc_t *a, nav_real_t de_m, nav_real_t dn_m, nav_real_t dtheta_rad,
                 nav_real_t dt_s, nav_real_t arw_rad_rts, nav_real_t b_rw_rps_rts)
{
    if (a->valid == 0u) {
        return;
    }
    if (!nav_isfinite(de_m) || !nav_isfinite(dn_m) || !nav_isfinite(dtheta_rad) ||
        !nav_isfinite(dt_s)) {
        a->valid = 0u;
        return;
    }
    /* G: seed 000 eq 5 (err_E += mu dE + psi dN), eq 6 (err_N += mu dN - psi dE), the
     * heading's drift (psi += b dt + s dtheta). The row and the column of psi change
     * last: the others read its value before the step. */
    for (int col = 0; col < 2; col++) {
        axpy(a, DR_ACC_E, DR_ACC_MU, de_m, col);
        axpy(a, DR_ACC_E, DR_ACC_PSI, dn_m, col);
        axpy(a, DR_ACC_N, DR_ACC_MU, dn_m, col);
        axpy(a, DR_ACC_N, DR_ACC_PSI, -de_m, col);
        axpy(a, DR_ACC_PSI, DR_ACC_B, dt_s, col);
        axpy(a, DR_ACC_PSI, DR_ACC_S, dtheta_rad, col);
    }
    for (int i = 0; i < DR_ACC_NX; i++) { /* symmetric to the last bit */
        for (int j = 0; j < i; j++) {
            a->P[i][j] = a->P[j][i];
        }
    }
    a->P[DR_ACC_B][DR_ACC_B] += b_rw_rps_rts * b_rw_rps_rts * dt_s;   /* its instability */
    a->P[DR_ACC_PSI][DR_ACC_PSI] += arw_rad_rts * arw_rad_rts * dt_s; /* the gyro's noise */
}

void dr_acc_hold(dr_acc_t *a, nav_real_t dt_s, nav_real_t b_rw_rps_rts, nav_real_t gain,
                 nav_real_t sample_var)
{
    if (a->valid == 0u) {
        return;
    }
    /* e_b' = (1 - K) e_b - K noise: b's row and column scale by 1 - K, its variance
     * gains K^2 times the sample's */
    const nav_real_t k1 = NAV_C(1.0) - gain;
    for (int i = 0; i < DR_ACC_NX; i++) {
        a->P[i][DR_ACC_B] *= k1;
        a->P[DR_ACC_B][i] = a->P[i][DR_ACC_B];
    }
    a->P[DR_ACC_B][DR_ACC_B] = a->P[DR_ACC_B][DR_ACC_B] * k1 + gain * gain * sample_var +
                               b_rw_rps_rts * b_rw_rps_rts * dt_s;
}

void dr_acc_calibrated(dr_acc_t *a, nav_real_t point_sigma_m, nav_real_t t_e_m,
                       nav_real_t t_n_m)
{
    if (a->valid == 0u) {
        return;
    }
    const nav_real_t var_pt = point_sigma_m * point_sigma_m;
    nav_real_t t2 = t_e_m * t_e_m + t_n_m * t_n_m;
    t2 = t2 > NAV_C(1.0) ? t2 : NAV_C(1.0);
    const nav_real_t var_geo = (var_pt + a->base_var_m2) / t2;
    nav_real_t drift = a->P[DR_ACC_PSI][DR_ACC_PSI] - a->psi_var_base;
    drift = drift > NAV_C(0.0) ? drift : NAV_C(0.0);
    const nav_real_t var_b = a->P[DR_ACC_B][DR_ACC_B];
    const nav_real_t var_s = a->P[DR_ACC_S][DR_ACC_S];
    clear(a);
    a->P[DR_ACC_E][DR_ACC_E] = var_pt;
    a->P[DR_ACC_N][DR_ACC_N] = var_pt;
    a->P[DR_ACC_MU][DR_ACC_MU] = var_geo;
    a->P[DR_ACC_PSI][DR_ACC_PSI] = var_geo + drift;
    /* the point's error in the position and in both estimates (dr_acc.h) */
    const nav_real_t ce = var_pt * t_e_m / t2, cn = var_pt * t_n_m / t2;
    a->P[DR_ACC_E][DR_ACC_MU] = ce;
    a->P[DR_ACC_N][DR_ACC_MU] = cn;
    a->P[DR_ACC_E][DR_ACC_PSI] = cn;
    a->P[DR_ACC_N][DR_ACC_PSI] = -ce;
    for (int i = DR_ACC_E; i <= DR_ACC_N; i++) {
        a->P[DR_ACC_MU][i] = a->P[i][DR_ACC_MU];
        a->P[DR_ACC_PSI][i] = a->P[i][DR_ACC_PSI];
    }
    a->P[DR_ACC_B][DR_ACC_B] = var_b;
    a->P[DR_ACC_S][DR_ACC_S] = var_s;
    a->psi_var_base = a->P[DR_ACC_PSI][DR_ACC_PSI];
    a->base_var_m2 = var_pt;
}

/* sqrt(v) of a valid model's variance v; -1 when not valid or v is not a variance. Out of
 * line (noinline): the link inlined it at both its callers, 16-24 bytes more. */
__attribute__((noinline)) static nav_real_t sigma_of(const dr_acc_t *a, nav_real_t v)
{
    return a->valid != 0u && v >= NAV_C(0.0) && nav_isfinite(v) ? nav_sqrt(v) : NAV_C(-1.0);
}

nav_real_t dr_acc_sigma_h_m(const dr_acc_t *a)
{
    return sigma_of(a, a->P[DR_ACC_E][DR_ACC_E] + a->P[DR_ACC_N][DR_ACC_N]);
}

nav_real_t dr_acc_sigma_heading_rad(const dr_acc_t *a)
{
    return sigma_of(a, a->P[DR_ACC_PSI][DR_ACC_PSI]);
}
