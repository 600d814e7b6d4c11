/* mounting.c - the IMU's configured rotation into the vehicle's axes; see mounting.h. */
#include "mounting.h"

#include <string.h>

void mounting_init(mounting_t *m, const nav_real_t rpy_rad[3])
{
    memset(m, 0, sizeof *m);
    m->rotate = (rpy_rad[0] > NAV_C(0.0) || rpy_rad[0] < NAV_C(0.0) || rpy_rad[1] > NAV_C(0.0) ||
                 rpy_rad[1] < NAV_C(0.0) || rpy_rad[2] > NAV_C(0.0) || rpy_rad[2] < NAV_C(0.0))
                    ? 1u
                    : 0u;
    nav_real_t q[4];
    quat_from_euler(rpy_rad[0], rpy_rad[1], rpy_rad[2], q);
    quat_to_dcm(q, &m->C_vi);
    m->yaw_axis = 2u;
    for (uint8_t j = 0u; j < 2u; j++) {
        if (nav_fabs(m->C_vi.m[2][j]) > nav_fabs(m->C_vi.m[2][m->yaw_axis])) {
            m->yaw_axis = j;
        }
    }
}

void mounting_to_vehicle(const mounting_t *m, const nav_real_t imu[3], nav_real_t veh[3])
{
    if (m->rotate) {
        mat3_mul_vec(&m->C_vi, imu, veh);
    } else {
        veh[0] = imu[0];
        veh[1] = imu[1];
        veh[2] = imu[2];
    }
}

void mounting_apply(const mounting_t *m, imu_inc_t *inc)
{
    if (!m->rotate) {
        return;
    }
    nav_real_t w[3], v[3];
    mat3_mul_vec(&m->C_vi, inc->dtheta_b_rad, w);
    mat3_mul_vec(&m->C_vi, inc->dv_b_mps, v);
    for (int i = 0; i < 3; i++) {
        inc->dtheta_b_rad[i] = w[i];
        inc->dv_b_mps[i] = v[i];
    }
}
