/*
 * test_mounting.c - the IMU's configured mounting (firmware/app/mounting.c): a vector of
 * the IMU's axes lands on the vehicle's axis the mounting's definition says, for the
 * installs the issue names (turned 90 deg, upside down, pitched 30 deg) and a general one
 * (the rotation keeps lengths and is proper); the identity passes samples bit for bit;
 * levelling an upside-down IMU gives the vehicle's level attitude.
 * Tolerance: float32 rounding of a 3x3 rotation of unit vectors, 1e-6.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "align.h"
#include "mounting.h"

#define TOL 1e-6
#define DEG (3.14159265358979323846 / 180.0)

static mounting_t make(double roll_deg, double pitch_deg, double yaw_deg)
{
    const nav_real_t rpy[3] = {(nav_real_t)(roll_deg * DEG), (nav_real_t)(pitch_deg * DEG),
                               (nav_real_t)(yaw_deg * DEG)};
    mounting_t m;
    mounting_init(&m, rpy);
    return m;
}

static void expect(const mounting_t *m, double x, double y, double z, double ex, double ey,
                   double ez)
{
    const nav_real_t in[3] = {(nav_real_t)x, (nav_real_t)y, (nav_real_t)z};
    nav_real_t out[3];
    mounting_to_vehicle(m, in, out);
    if (fabs((double)out[0] - ex) > TOL || fabs((double)out[1] - ey) > TOL ||
        fabs((double)out[2] - ez) > TOL) {
        fail_msg("(%g, %g, %g) -> (%g, %g, %g), expected (%g, %g, %g)", x, y, z,
                 (double)out[0], (double)out[1], (double)out[2], ex, ey, ez);
    }
}

/* turned 90 deg to the right (yaw +90, clockwise): the IMU's forward axis points along the
 * vehicle's right, its right axis along the vehicle's back */
static void test_turned_right(void **state)
{
    (void)state;
    const mounting_t m = make(0.0, 0.0, 90.0);
    expect(&m, 0, 1, 0, 1, 0, 0);
    expect(&m, 1, 0, 0, 0, -1, 0);
    expect(&m, 0, 0, 1, 0, 0, 1);
}

/* upside down about the forward axis (roll 180): up is down, right is left */
static void test_upside_down(void **state)
{
    (void)state;
    const mounting_t m = make(180.0, 0.0, 0.0);
    expect(&m, 0, 0, 1, 0, 0, -1);
    expect(&m, 1, 0, 0, -1, 0, 0);
    expect(&m, 0, 1, 0, 0, 1, 0);
}

/* pitched 30 deg nose up: the IMU's forward axis points forward and up */
static void test_pitched(void **state)
{
    (void)state;
    const mounting_t m = make(0.0, 30.0, 0.0);
    expect(&m, 0, 1, 0, 0, cos(30 * DEG), sin(30 * DEG));
    expect(&m, 0, 0, 1, 0, -sin(30 * DEG), cos(30 * DEG));
}

/* the IMU axis nearest the vehicle's z (the gyro whose stuck value is the yaw's): z for
 * the installs above, upside down too; y for an IMU on its back edge (pitched 90 deg: its
 * forward axis points up); x for one on its side (rolled 90 deg) */
static void test_yaw_axis(void **state)
{
    (void)state;
    assert_int_equal(make(0.0, 0.0, 0.0).yaw_axis, 2);
    assert_int_equal(make(0.0, 0.0, 90.0).yaw_axis, 2);
    assert_int_equal(make(180.0, 0.0, 0.0).yaw_axis, 2);
    assert_int_equal(make(0.0, 30.0, 0.0).yaw_axis, 2);
    assert_int_equal(make(0.0, 90.0, 0.0).yaw_axis, 1);
    assert_int_equal(make(90.0, 0.0, 0.0).yaw_axis, 0);
}

/* any angles: a rotation (lengths kept, determinant +1) */
static void test_general_is_a_rotation(void **state)
{
    (void)state;
    const mounting_t m = make(37.0, -61.0, 143.0);
    double det = 0.0;
    const mat3_t *C = &m.C_vi;
    for (int i = 0; i < 3; i++) {
        double n = 0.0;
        for (int j = 0; j < 3; j++) {
            n += (double)C->m[i][j] * (double)C->m[i][j];
        }
        assert_true(fabs(n - 1.0) < TOL);
    }
    double c[3][3];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            c[i][j] = (double)C->m[i][j];
        }
    }
    det = c[0][0] * (c[1][1] * c[2][2] - c[1][2] * c[2][1]) -
          c[0][1] * (c[1][0] * c[2][2] - c[1][2] * c[2][0]) +
          c[0][2] * (c[1][0] * c[2][1] - c[1][1] * c[2][0]);
    assert_true(fabs(det - 1.0) < TOL);
}

/* the identity: nothing touched, bit for bit */
static void test_identity_untouched(void **state)
{
    (void)state;
    const mounting_t m = make(0.0, 0.0, 0.0);
    assert_int_equal(m.rotate, 0);
    imu_inc_t inc = {{NAV_C(1e-3), NAV_C(-2e-4), NAV_C(3.3e-5)}, {NAV_C(0.01), NAV_C(0.02),
                                                                 NAV_C(0.0981)}, NAV_C(0.01)};
    const imu_inc_t before = inc;
    mounting_apply(&m, &inc);
    assert_memory_equal(&inc, &before, sizeof inc);
}

/* levelling an upside-down IMU in a level car: its specific force reads (0, 0, -g) in its
 * own axes; the vehicle is level */
static void test_levelling_upside_down(void **state)
{
    (void)state;
    const mounting_t m = make(180.0, 0.0, 0.0);
    align_t al;
    memset(&al, 0, sizeof al);
    const int32_t v_raw[3] = {0, 0, -1000};
    for (uint32_t k = 0u; k < 100u; k++) {
        (void)align_level_sample(&al, v_raw, 100u);
    }
    nav_real_t roll, pitch;
    align_level_attitude(&al, &m, &roll, &pitch);
    assert_true(fabs((double)roll) < TOL && fabs((double)pitch) < TOL);
    /* without the mounting the car would seem on its roof */
    const mounting_t none = make(0.0, 0.0, 0.0);
    align_level_attitude(&al, &none, &roll, &pitch);
    assert_true(fabs(fabs((double)roll) - 3.14159265358979) < 1e-5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_turned_right),
        cmocka_unit_test(test_upside_down),
        cmocka_unit_test(test_pitched),
        cmocka_unit_test(test_yaw_axis),
        cmocka_unit_test(test_general_is_a_rotation),
        cmocka_unit_test(test_identity_untouched),
        cmocka_unit_test(test_levelling_upside_down),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
