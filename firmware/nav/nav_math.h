/*
 * nav_math.h - small fixed-size vector, matrix and quaternion algebra.
 *
 * Conventions (stated once for the whole core, see docs/frames.md):
 *   - vectors are nav_real_t[3]; matrices mat3_t (row-major m[row][col]);
 *   - quaternions are nav_real_t[4] = {w, x, y, z}, Hamilton product;
 *   - q_bn / C_bn map body to navigation frame: v_n = C_bn * v_b = q_bn (x) v_b (x) q_bn*;
 *   - Euler angles are the 3-1-2 sequence of seed 001's frames (ENU navigation frame,
 *     body x right, y forward, z up): C_bn = Rz(-heading) * Rx(pitch) * Ry(roll),
 *     heading clockwise from north, pitch nose-up positive, roll right-side-down positive.
 *
 * All functions are pure, take outputs last, and allow no aliasing between an output
 * and an input unless stated.
 */
#ifndef NAVECU_NAV_MATH_H
#define NAVECU_NAV_MATH_H

#include "nav_types.h"

/* A 3x3 matrix; a struct so that const-qualified matrices pass without casts. */
typedef struct {
    nav_real_t m[3][3];
} mat3_t;

#define vec3_cross NAV_SYM(vec3_cross)
#define vec3_dot NAV_SYM(vec3_dot)
#define vec3_norm NAV_SYM(vec3_norm)
#define mat3_mul_vec NAV_SYM(mat3_mul_vec)
#define mat3t_mul_vec NAV_SYM(mat3t_mul_vec)
#define quat_mul NAV_SYM(quat_mul)
#define quat_to_dcm NAV_SYM(quat_to_dcm)
#define dcm_to_quat NAV_SYM(dcm_to_quat)
#define quat_from_euler NAV_SYM(quat_from_euler)
#define dcm_to_euler NAV_SYM(dcm_to_euler)
#define rotvec_to_dquat NAV_SYM(rotvec_to_dquat)
#define nav_acc_add NAV_SYM(nav_acc_add)
#define nav_clamp NAV_SYM(nav_clamp)

/* out = a x b. out may not alias a or b. */
void vec3_cross(const nav_real_t a[3], const nav_real_t b[3], nav_real_t out[3]);
/* returns a . b */
nav_real_t vec3_dot(const nav_real_t a[3], const nav_real_t b[3]);
/* returns |a| */
nav_real_t vec3_norm(const nav_real_t a[3]);
/* out = M v; out may not alias v. */
void mat3_mul_vec(const mat3_t *M, const nav_real_t v[3], nav_real_t out[3]);
/* out = M^T v; out may not alias v. */
void mat3t_mul_vec(const mat3_t *M, const nav_real_t v[3], nav_real_t out[3]);

/* out = p (x) q (Hamilton). out may not alias p or q. */
void quat_mul(const nav_real_t p[4], const nav_real_t q[4], nav_real_t out[4]);
/* C = DCM of the unit quaternion q (same mapping: v' = C v = q (x) v (x) q*). */
void quat_to_dcm(const nav_real_t q[4], mat3_t *C);
/* q = unit quaternion of the rotation matrix C, w >= 0 (Shepperd's method). */
void dcm_to_quat(const mat3_t *C, nav_real_t q[4]);
/* q_bn from roll, pitch, heading (rad), 3-1-2 sequence above. */
void quat_from_euler(nav_real_t roll_rad, nav_real_t pitch_rad, nav_real_t heading_rad,
                     nav_real_t q_bn[4]);
/* roll (-pi..pi], pitch [-pi/2..pi/2], heading [0..2pi) from C_bn, 3-1-2 sequence above. */
void dcm_to_euler(const mat3_t *C_bn, nav_real_t *roll_rad, nav_real_t *pitch_rad,
                  nav_real_t *heading_rad);

/*
 * dq = q(phi) - {1,0,0,0}, the quaternion of the rotation vector phi (rad) minus identity.
 * Returning the difference from identity keeps small rotations exact in float32 (the scalar
 * part cos(|phi|/2) - 1 would otherwise round to zero). Evaluated by fixed-degree series,
 * no libm, so results are bit-identical on every target.
 * Returns NAV_OK, or NAV_EINVAL if |phi| > pi or phi is not finite (dq then zero).
 */
int rotvec_to_dquat(const nav_real_t phi_rad[3], nav_real_t dq[4]);

/*
 * Compensated accumulation: (*hi + *lo) += inc (Knuth's TwoSum of hi and inc + lo).
 * *lo carries what float rounding drops from *hi; hi alone is the value to use. The only
 * rounding left is that of inc + lo, relative to the increment, not to hi: after N steps
 * the sum is exact within N eps^2 |hi| / 2 (test_compensated_accumulation).
 * Needs strict IEEE evaluation: the build forbids -ffast-math and uses -ffp-contract=off.
 */
void nav_acc_add(nav_real_t *hi, nav_real_t *lo, nav_real_t inc);

/* x limited to [lo, hi] (lo <= hi); a NaN x is returned as it is. */
nav_real_t nav_clamp(nav_real_t x, nav_real_t lo, nav_real_t hi);

#endif /* NAVECU_NAV_MATH_H */
