/* nav_math.c - see nav_math.h for the contracts and conventions. */
#include "nav_math.h"

void vec3_cross(const nav_real_t a[3], const nav_real_t b[3], nav_real_t out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

nav_real_t vec3_dot(const nav_real_t a[3], const nav_real_t b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

nav_real_t vec3_norm(const nav_real_t a[3])
{
    return nav_sqrt(vec3_dot(a, a));
}

void mat3_mul_vec(const mat3_t *M, const nav_real_t v[3], nav_real_t out[3])
{
    for (int i = 0; i < 3; i++) {
        out[i] = M->m[i][0] * v[0] + M->m[i][1] * v[1] + M->m[i][2] * v[2];
    }
}

void mat3t_mul_vec(const mat3_t *M, const nav_real_t v[3], nav_real_t out[3])
{
    for (int i = 0; i < 3; i++) {
        out[i] = M->m[0][i] * v[0] + M->m[1][i] * v[1] + M->m[2][i] * v[2];
    }
}

void quat_mul(const nav_real_t p[4], const nav_real_t q[4], nav_real_t out[4])
{
    out[0] = p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3];
    out[1] = p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2];
    out[2] = p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1];
    out[3] = p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0];
}

void quat_to_dcm(const nav_real_t q[4], mat3_t *Cm)
{
    nav_real_t (*C)[3] = Cm->m;
    const nav_real_t w = q[0], x = q[1], y = q[2], z = q[3];
    const nav_real_t two = NAV_C(2.0);
    C[0][0] = w * w + x * x - y * y - z * z;
    C[0][1] = two * (x * y - w * z);
    C[0][2] = two * (x * z + w * y);
    C[1][0] = two * (x * y + w * z);
    C[1][1] = w * w - x * x + y * y - z * z;
    C[1][2] = two * (y * z - w * x);
    C[2][0] = two * (x * z - w * y);
    C[2][1] = two * (y * z + w * x);
    C[2][2] = w * w - x * x - y * y + z * z;
}

void dcm_to_quat(const mat3_t *Cm, nav_real_t q[4])
{
    const nav_real_t (*C)[3] = Cm->m;
    /* Shepperd: take the square root of the largest of 4w^2, 4x^2, 4y^2, 4z^2 so that
     * no division is by a small number. */
    const nav_real_t tr = C[0][0] + C[1][1] + C[2][2];
    const nav_real_t one = NAV_C(1.0), quarter = NAV_C(0.25);
    if (tr >= C[0][0] && tr >= C[1][1] && tr >= C[2][2]) {
        const nav_real_t s = NAV_C(2.0) * nav_sqrt(one + tr); /* s = 4w */
        q[0] = quarter * s;
        q[1] = (C[2][1] - C[1][2]) / s;
        q[2] = (C[0][2] - C[2][0]) / s;
        q[3] = (C[1][0] - C[0][1]) / s;
    } else if (C[0][0] >= C[1][1] && C[0][0] >= C[2][2]) {
        const nav_real_t s = NAV_C(2.0) * nav_sqrt(one + C[0][0] - C[1][1] - C[2][2]);
        q[0] = (C[2][1] - C[1][2]) / s;
        q[1] = quarter * s;
        q[2] = (C[0][1] + C[1][0]) / s;
        q[3] = (C[0][2] + C[2][0]) / s;
    } else if (C[1][1] >= C[2][2]) {
        const nav_real_t s = NAV_C(2.0) * nav_sqrt(one + C[1][1] - C[0][0] - C[2][2]);
        q[0] = (C[0][2] - C[2][0]) / s;
        q[1] = (C[0][1] + C[1][0]) / s;
        q[2] = quarter * s;
        q[3] = (C[1][2] + C[2][1]) / s;
    } else {
        const nav_real_t s = NAV_C(2.0) * nav_sqrt(one + C[2][2] - C[0][0] - C[1][1]);
        q[0] = (C[1][0] - C[0][1]) / s;
        q[1] = (C[0][2] + C[2][0]) / s;
        q[2] = (C[1][2] + C[2][1]) / s;
        q[3] = quarter * s;
    }
    if (q[0] < NAV_C(0.0)) {
        for (int i = 0; i < 4; i++) {
            q[i] = -q[i];
        }
    }
}

void quat_from_euler(nav_real_t roll_rad, nav_real_t pitch_rad, nav_real_t heading_rad,
                     nav_real_t q_bn[4])
{
    const nav_real_t h = NAV_C(0.5);
    /* C_bn = Rz(-heading) Rx(pitch) Ry(roll): the same product of elementary quaternions. */
    const nav_real_t qz[4] = {nav_cos(h * heading_rad), NAV_C(0.0), NAV_C(0.0),
                              -nav_sin(h * heading_rad)};
    const nav_real_t qx[4] = {nav_cos(h * pitch_rad), nav_sin(h * pitch_rad), NAV_C(0.0),
                              NAV_C(0.0)};
    const nav_real_t qy[4] = {nav_cos(h * roll_rad), NAV_C(0.0), nav_sin(h * roll_rad),
                              NAV_C(0.0)};
    nav_real_t qzx[4];
    quat_mul(qz, qx, qzx);
    quat_mul(qzx, qy, q_bn);
    if (q_bn[0] < NAV_C(0.0)) {
        for (int i = 0; i < 4; i++) {
            q_bn[i] = -q_bn[i];
        }
    }
}

void dcm_to_euler(const mat3_t *Cm, nav_real_t *roll_rad, nav_real_t *pitch_rad,
                  nav_real_t *heading_rad)
{
    const nav_real_t (*C)[3] = Cm->m;
    /* Row U of C_bn is (-cos(p) sin(r), sin(p), cos(p) cos(r)); column y (the forward axis)
     * is (sin(H) cos(p), cos(H) cos(p), sin(p)). */
    nav_real_t sp = C[2][1];
    if (sp > NAV_C(1.0)) {
        sp = NAV_C(1.0);
    } else if (sp < NAV_C(-1.0)) {
        sp = NAV_C(-1.0);
    }
    *pitch_rad = nav_asin(sp);
    *roll_rad = nav_atan2(-C[2][0], C[2][2]);
    nav_real_t hdg = nav_atan2(C[0][1], C[1][1]);
    if (hdg < NAV_C(0.0)) {
        hdg += NAV_C(6.283185307179586);
        if (hdg >= NAV_C(6.283185307179586)) {
            hdg = NAV_C(0.0); /* -tiny + 2 pi rounds up to 2 pi itself */
        }
    }
    *heading_rad = hdg;
}

int rotvec_to_dquat(const nav_real_t phi_rad[3], nav_real_t dq[4])
{
    const nav_real_t y4 = vec3_dot(phi_rad, phi_rad); /* |phi|^2 = 4 x^2, x = |phi|/2 */
    if (!nav_isfinite(y4) || y4 > NAV_C(9.869604401089358)) {
        dq[0] = dq[1] = dq[2] = dq[3] = NAV_C(0.0);
        return NAV_EINVAL;
    }
    const nav_real_t y = NAV_C(0.25) * y4; /* x^2 <= pi^2/4: truncation error < 1e-12 */
    /* cos(x) - 1 and sin(x)/x by their Taylor series in y = x^2, Horner form. */
    const nav_real_t cm1 =
        y * (NAV_C(-0.5) +
        y * (NAV_C(4.1666666666666664e-2) +
        y * (NAV_C(-1.3888888888888889e-3) +
        y * (NAV_C(2.4801587301587302e-5) +
        y * (NAV_C(-2.7557319223985888e-7) +
        y * (NAV_C(2.0876756987868099e-9) +
        y * (NAV_C(-1.1470745597729725e-11) +
        y * NAV_C(4.7794773323873853e-14))))))));
    const nav_real_t sinc =
        NAV_C(1.0) +
        y * (NAV_C(-1.6666666666666666e-1) +
        y * (NAV_C(8.3333333333333332e-3) +
        y * (NAV_C(-1.9841269841269841e-4) +
        y * (NAV_C(2.7557319223985893e-6) +
        y * (NAV_C(-2.5052108385441720e-8) +
        y * (NAV_C(1.6059043836821613e-10) +
        y * (NAV_C(-7.6471637318198164e-13) +
        y * NAV_C(2.8114572543455206e-15))))))));
    const nav_real_t k = NAV_C(0.5) * sinc; /* sin(x)/|phi| */
    dq[0] = cm1;
    dq[1] = k * phi_rad[0];
    dq[2] = k * phi_rad[1];
    dq[3] = k * phi_rad[2];
    return NAV_OK;
}

void nav_acc_add(nav_real_t *hi, nav_real_t *lo, nav_real_t inc)
{
#if defined(NAV_ACC_PLAIN)
    /* numerics study only (make numerics): what plain accumulation would cost */
    *hi += inc;
    *lo = NAV_C(0.0);
    return;
#endif
    const nav_real_t y = inc + *lo;
    const nav_real_t s = *hi + y;
    const nav_real_t yv = s - *hi;
    const nav_real_t hv = s - yv;
    *lo = (*hi - hv) + (y - yv);
    *hi = s;
}

/* Out of line (noinline): GCC inlined it at each of its 30 calls (the output frames' signals,
 * GNSS accuracies), two float compares and their branches each time; one copy is 640 bytes
 * less of the ECU's flash (docs/target.md). None of the calls is per IMU sample. */
__attribute__((noinline)) nav_real_t nav_clamp(nav_real_t x, nav_real_t lo, nav_real_t hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}
