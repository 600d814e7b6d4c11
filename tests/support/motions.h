/*
 * motions.h - analytic vehicle motions for the truth generator (test support).
 */
#ifndef NAVECU_TEST_MOTIONS_H
#define NAVECU_TEST_MOTIONS_H

#include "truth.h"

/* A vehicle standing still at fixed Euler angles (rad). */
typedef struct {
    double roll, pitch, heading;
} still_t;
void kin_still(const void *ctx, double t, kin_t *k);

/*
 * Stop-and-go driving on a circle: speed s(t) = S0 (1 - cos(2 pi t / T)) (a stop every
 * period T), constant path curvature 1/radius so the heading advances by s/radius; the body
 * rolls out of the turn with lateral acceleration and pitches and rolls on its suspension,
 * so all three gyro and accelerometer axes work.
 */
typedef struct {
    double s0_mps;      /* mean speed */
    double period_s;    /* stop-and-go period */
    double radius_m;    /* circle radius */
    double heading0_rad;
} circle_t;
void kin_circle(const void *ctx, double t, kin_t *k);

/* Classical coning: body axis x sweeps a cone of half-angle alpha at rate omega, on top of
 * a fixed attitude q0 (ENU). */
typedef struct {
    double alpha_rad, omega_rps;
    double q0[4];
} cone_t;
void kin_cone(const void *ctx, double t, kin_t *k);

/* Classical sculling: the body yaws back and forth (heading psi0 sin(w t)) while it
 * accelerates along north in phase (a_N = a0 sin(w t), from rest): a rotation about z and
 * an acceleration along y oscillating together, which rectify into a spurious horizontal
 * acceleration along x unless the sculling term corrects it. */
typedef struct {
    double a0_mps2, omega_rps, psi0_rad;
} scull_t;
void kin_scull(const void *ctx, double t, kin_t *k);

#endif
