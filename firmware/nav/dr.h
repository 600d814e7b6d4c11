/*
 * dr.h - dead reckoning with the odometer along the SINS heading, and the one-point
 * calibration of heading error and odometer scale (seed 000, docs/odometry.md).
 *
 * Per odometer step ds (m) at SINS true heading H and pitch p (seed 000 eqs 1-4, with
 * the compensation of eqs 11-12 once a calibration (dH, mu) is known):
 *     ds_c = ds / (1 + mu)                              (eq 11-12, exact form; see below)
 *     dE = ds_c cos(p) sin(H - dH),  dN = ds_c cos(p) cos(H - dH),  dh = ds_c sin(p)
 *     lat += dN / (R_M + h),         lon += dE / ((R_N + h) cos(lat))     (eqs 1-2)
 * The paper writes (1 - mu) ds; 1/(1 + mu) is the exact inverse of its error model
 * "odometer distance = (1 + mu) x true" (eqs 5-6); the two differ by mu^2 (1.4e-4 of the
 * distance for mu = 0.012), which is larger than the 0.05 % this project aims at. cos(p)
 * takes the horizontal part of the distance on a slope (the paper neglects it: 0.4 % on
 * a 9 % grade).
 *
 * One-point calibration (eqs 7-10): at a point M whose true position is known, with the
 * base B (the start, or the previous calibration point) and the dead-reckoned position D,
 * the true displacement t = M - B and the dead-reckoned one d = D - B, both in metres east
 * and north, are related by a rotation through dH (clockwise, as the heading) and a scale
 * 1 + mu. Eqs 9-10 are the first-order solution; dr_calibrate uses the exact one:
 *     dH = atan2(d_E t_N - d_N t_E, d_E t_E + d_N t_N),   1 + mu = |d| / |t|
 * which agrees with eqs 9-10 to second order (onepoint_linear, for the tests). The
 * position is then reset to M, M becomes the base, and the estimates compose with the
 * ones in use (recalibration): dH += dH', (1 + mu) *= (1 + mu').
 */
#ifndef NAVECU_DR_H
#define NAVECU_DR_H

#include "earth.h"

/* The compensation's range: a heading correction or an odometer scale error beyond these
 * is not a calibration but a fault (the one place they are defined; calstore.h and the
 * application use them too). */
#define DR_DH_MAX_RAD NAV_C(0.5)
#define DR_MU_MAX NAV_C(0.2)

typedef struct {
    geo_pos_t pos;          /* dead-reckoned position */
    geo_pos_t base;         /* start, or the last calibration point (eqs 7-8) */
    nav_real_t dh_rad;      /* heading correction in use, dH (eqs 9, 11-12) */
    nav_real_t mu;          /* odometer scale error in use, mu (eqs 10, 11-12) */
    nav_real_t step_e_m;    /* the last step's compensated horizontal move, east */
    nav_real_t step_n_m;    /* and north (eqs 3-4; dr_acc.h's dE, dN) */
} dr_t;

/* Result of one calibration: the residual errors found (composed into dr_t's). */
typedef struct {
    nav_real_t dh_rad;      /* heading error found this time, dH' */
    nav_real_t mu;          /* scale error found this time, mu' */
    nav_real_t base_m;      /* |t|: straight-line distance from the base to the point */
    nav_real_t err_e_m;     /* dead-reckoning error at the point before the reset, east */
    nav_real_t err_n_m;     /* and north (eqs 7-8) */
    nav_real_t t_e_m;       /* t, the point less the base, east */
    nav_real_t t_n_m;       /* and north (eqs 7-8) */
} dr_cal_t;

#define dr_init NAV_SYM(dr_init)
#define dr_step NAV_SYM(dr_step)
#define dr_set_position NAV_SYM(dr_set_position)
#define dr_set_compensation NAV_SYM(dr_set_compensation)
#define dr_local_m NAV_SYM(dr_local_m)
#define dr_calibrate NAV_SYM(dr_calibrate)
#define onepoint_exact NAV_SYM(onepoint_exact)
#define onepoint_linear NAV_SYM(onepoint_linear)

/* Start at pos (also the base) with the compensation (dh_rad, mu) in use. NAV_EINVAL for
 * a non-finite value, |dh| > 0.5 rad or |mu| > 0.2. */
int dr_init(dr_t *d, const geo_pos_t *pos, nav_real_t dh_rad, nav_real_t mu);

/* One odometer step: ds_m (signed, reverse negative) along heading_rad with pitch_rad.
 * NAV_OK, NAV_EINVAL (non-finite, |ds| > 100 m), NAV_ERANGE (position out of range). */
int dr_step(dr_t *d, nav_real_t ds_m, nav_real_t heading_rad, nav_real_t pitch_rad);

/* Move the dead-reckoned position (and not the base): while the odometer is unusable the
 * application follows another source. */
void dr_set_position(dr_t *d, const geo_pos_t *pos);

/* Replace the compensation in use (dH rad, mu) by one from another source (the filter,
 * an erase). NAV_OK, or NAV_EINVAL (d unchanged) under dr_init's conditions. */
int dr_set_compensation(dr_t *d, nav_real_t dh_rad, nav_real_t mu);

/* East and north metres of p relative to ref (radii at ref's latitude and height, mid-
 * latitude for the east scale): the local frame of eqs 7-8. */
void dr_local_m(const geo_pos_t *ref, const geo_pos_t *p, nav_real_t *e_m, nav_real_t *n_m);

/*
 * One-point calibration at a point whose true latitude and longitude are those of
 * true_pos (its height is not used). Returns NAV_OK: the residuals in *out (if not NULL),
 * composed into d, position reset to the point (height kept), the point is the new base.
 * NAV_ERANGE if the point is closer than min_base_m to the base (not informative: the
 * estimates' errors scale as the point's position error over that distance); NAV_EINVAL
 * for a degenerate result (no distance travelled, non-finite, or |dH| or |mu| out of
 * dr_init's range). On an error d is unchanged.
 */
int dr_calibrate(dr_t *d, const geo_pos_t *true_pos, nav_real_t min_base_m, dr_cal_t *out);

/* Exact one-point solution from the dead-reckoned (d) and true (t) displacements (m):
 * NAV_OK, or NAV_EINVAL if |t| or |d| is zero or a value is not finite. */
int onepoint_exact(nav_real_t d_e_m, nav_real_t d_n_m, nav_real_t t_e_m, nav_real_t t_n_m,
                   nav_real_t *dh_rad, nav_real_t *mu);

/* Seed 000 eqs 9-10 as printed: from the true displacement (t) and the errors dE, dN of
 * eqs 7-8. NAV_EINVAL if |t| is zero. */
int onepoint_linear(nav_real_t t_e_m, nav_real_t t_n_m, nav_real_t err_e_m, nav_real_t err_n_m,
                    nav_real_t *dh_rad, nav_real_t *mu);

#endif /* NAVECU_DR_H */
