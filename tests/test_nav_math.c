/*
 * test_nav_math.c - vector, quaternion and attitude conventions, series rotation, and
 * compensated accumulation. Built for both numeric variants.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "nav_math.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

#if defined(NAV_REAL_DOUBLE)
#define VARIANT "f64"
#define EPS 1e-15
#else
#define VARIANT "f32"
#define EPS 1.2e-7 /* float32 machine epsilon */
#endif

static void body_to_nav(const nav_real_t q[4], double x, double y, double z, double out[3])
{
    mat3_t C;
    const nav_real_t v[3] = {(nav_real_t)x, (nav_real_t)y, (nav_real_t)z};
    nav_real_t r[3];
    quat_to_dcm(q, &C);
    mat3_mul_vec(&C, v, r);
    for (int i = 0; i < 3; i++) {
        out[i] = (double)r[i];
    }
}

/* docs/frames.md: ENU navigation frame, body x right, y forward, z up; heading clockwise
 * from north, pitch nose-up positive, roll right-side-down positive. */
static void test_euler_conventions(void **state)
{
    (void)state;
    nav_real_t q[4];
    double v[3];
    /* heading 90 deg: forward points east */
    quat_from_euler((nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)(90.0 * DEG), q);
    body_to_nav(q, 0, 1, 0, v);
    assert_near(v[0], 1.0, 4 * EPS);
    assert_near(v[1], 0.0, 4 * EPS);
    /* heading 30 deg: forward = (sin 30, cos 30, 0) */
    quat_from_euler((nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)(30.0 * DEG), q);
    body_to_nav(q, 0, 1, 0, v);
    assert_near(v[0], 0.5, 4 * EPS);
    assert_near(v[1], sqrt(0.75), 4 * EPS);
    /* pitch +10 deg: forward rises */
    quat_from_euler((nav_real_t)0.0, (nav_real_t)(10.0 * DEG), (nav_real_t)0.0, q);
    body_to_nav(q, 0, 1, 0, v);
    assert_near(v[2], sin(10.0 * DEG), 4 * EPS);
    /* roll +10 deg: the right side goes down */
    quat_from_euler((nav_real_t)(10.0 * DEG), (nav_real_t)0.0, (nav_real_t)0.0, q);
    body_to_nav(q, 1, 0, 0, v);
    assert_near(v[2], -sin(10.0 * DEG), 4 * EPS);
}

static void test_euler_round_trip(void **state)
{
    (void)state;
    const double rolls[] = {-170.0, -45.0, 0.0, 3.0, 120.0};
    const double pitches[] = {-80.0, -10.0, 0.0, 25.0, 85.0};
    const double headings[] = {0.0, 1.0, 89.0, 181.0, 359.5};
    for (int i = 0; i < 5; i++) {
        for (int j = 0; j < 5; j++) {
            for (int k = 0; k < 5; k++) {
                nav_real_t q[4], q2[4], r, p, h;
                mat3_t C;
                quat_from_euler((nav_real_t)(rolls[i] * DEG), (nav_real_t)(pitches[j] * DEG),
                                (nav_real_t)(headings[k] * DEG), q);
                quat_to_dcm(q, &C);
                dcm_to_euler(&C, &r, &p, &h);
                /* near pitch 85 deg roll and heading are ill-conditioned: 1/cos(85) = 11 */
                const double tol = 200.0 * EPS;
                assert_near(r, rolls[i] * DEG, tol);
                assert_near(p, pitches[j] * DEG, tol);
                /* heading is in [0, 2 pi): compare the wrapped difference */
                double dh = (double)h - headings[k] * DEG;
                dh -= 2.0 * PI * floor(dh / (2.0 * PI) + 0.5);
                assert_near(dh, 0.0, tol);
                assert_true(h >= (nav_real_t)0.0 && h < (nav_real_t)(2.0 * PI));
                dcm_to_quat(&C, q2);
                for (int n = 0; n < 4; n++) {
                    assert_near(q2[n], q[n], 8 * EPS);
                }
            }
        }
    }
}

/* every branch of Shepperd's method: rotations by 180 deg about x, y, z and identity */
static void test_dcm_to_quat_branches(void **state)
{
    (void)state;
    const nav_real_t qs[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    for (int b = 0; b < 4; b++) {
        mat3_t C;
        nav_real_t q[4];
        quat_to_dcm(qs[b], &C);
        dcm_to_quat(&C, q);
        for (int n = 0; n < 4; n++) {
            assert_near(fabs((double)q[n]), (double)qs[b][n], 4 * EPS);
        }
    }
}

static void test_rotvec_series(void **state)
{
    (void)state;
    const double angles[] = {0.0, 1e-9, 1e-4, 0.01, 0.3, 1.0, 2.5, 3.14};
    const double axis[3] = {0.48, -0.6, 0.64}; /* unit */
    for (size_t i = 0; i < sizeof angles / sizeof angles[0]; i++) {
        const double a = angles[i];
        const nav_real_t phi[3] = {(nav_real_t)(a * axis[0]), (nav_real_t)(a * axis[1]),
                                   (nav_real_t)(a * axis[2])};
        nav_real_t dq[4];
        assert_int_equal(rotvec_to_dquat(phi, dq), NAV_OK);
        /* cos(a/2) - 1 = -2 sin^2(a/4), free of cancellation: relative accuracy expected,
         * plus the series truncation bound 1e-12 (nav_math.c) */
        const double cm1 = -2.0 * sin(0.25 * a) * sin(0.25 * a);
        assert_near(dq[0], cm1, fabs(cm1) * 8 * EPS + 1e-12);
        for (int n = 0; n < 3; n++) {
            const double want = sin(0.5 * a) * axis[n];
            assert_near(dq[n + 1], want, fabs(want) * 8 * EPS + 1e-12);
        }
    }
    const nav_real_t too_big[3] = {(nav_real_t)3.2, (nav_real_t)0.0, (nav_real_t)0.0};
    const nav_real_t nan3[3] = {(nav_real_t)NAN, (nav_real_t)0.0, (nav_real_t)0.0};
    nav_real_t dq[4];
    assert_int_equal(rotvec_to_dquat(too_big, dq), NAV_EINVAL);
    assert_int_equal(rotvec_to_dquat(nan3, dq), NAV_EINVAL);
}

/*
 * GIVEN 1e6 increments of 1e-9 added to 1.0
 * WHEN accumulated with nav_acc_add
 * THEN hi + lo equals the exact sum within N eps^2 / 2 (each step rounds only the sum of
 *      the increment and the carried remainder, |lo| <= eps/2): 7e-9 in float32 although
 *      each increment is far below the float32 ULP of 1.0 (1.2e-7), where a plain float sum
 *      does not move at all.
 */
static void test_compensated_accumulation(void **state)
{
    (void)state;
    const nav_real_t inc = (nav_real_t)1e-9;
    nav_real_t hi = (nav_real_t)1.0, lo = (nav_real_t)0.0, plain = (nav_real_t)1.0;
    for (int i = 0; i < 1000000; i++) {
        nav_acc_add(&hi, &lo, inc);
        plain += inc;
    }
    const double exact = 1.0 + 1e6 * (double)inc;
    assert_near((double)hi + (double)lo, exact, 1e6 * EPS * EPS * 0.5 + 1e-15);
#if !defined(NAV_REAL_DOUBLE)
    assert_near((double)plain, 1.0, 0.0); /* shows what the compensation is for */
#endif
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_euler_conventions),
        cmocka_unit_test(test_euler_round_trip),
        cmocka_unit_test(test_dcm_to_quat_branches),
        cmocka_unit_test(test_rotvec_series),
        cmocka_unit_test(test_compensated_accumulation),
    };
    return cmocka_run_group_tests_name("nav_math_" VARIANT, tests, NULL, NULL);
}
