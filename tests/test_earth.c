/*
 * test_earth.c - the WGS-84 Earth model against published values, and the fixed-point
 * position. Built for both numeric variants; float32 tolerances follow from its 24-bit
 * mantissa (relative 6e-8 per operation, a few operations per quantity).
 *
 * References: NIMA TR8350.2 (3rd ed.) Table 3.3 (derived geometric constants: polar radius
 * of curvature c = 6399593.6258 m), Table 3.4 (normal gravity at the equator 9.7803253359
 * and at the poles 9.8321849378 m/s^2), eq. 4-1 (Somigliana); the normal free-air gradient
 * -0.3086 mGal/m (Heiskanen & Moritz, Physical Geodesy, 1967, sec. 2-14).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "earth.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

#if defined(NAV_REAL_DOUBLE)
#define VARIANT "f64"
#define TOL_RADIUS_M 1e-6
#define TOL_G_MPS2 1e-12
#define TOL_REL 1e-10 /* reference values below carry 11 digits */
#else
#define VARIANT "f32"
#define TOL_RADIUS_M 2.0   /* 6.4e6 m * 3e-7: a few float32 roundings */
#define TOL_G_MPS2 3e-6    /* 9.8 * 3e-7 */
#define TOL_REL 3e-7
#endif

static void radii_at(double lat_deg, double *rm, double *rn)
{
    nav_real_t m, n;
    earth_radii((nav_real_t)sin(lat_deg * DEG), &m, &n);
    *rm = (double)m;
    *rn = (double)n;
}

static void test_radii_published(void **state)
{
    (void)state;
    double rm, rn;
    /* equator: R_N = a, R_M = a (1 - e^2) */
    radii_at(0.0, &rm, &rn);
    assert_near(rn, 6378137.0, TOL_RADIUS_M);
    assert_near(rm, 6335439.3273, TOL_RADIUS_M + 1e-4);
    /* pole: both equal the polar radius of curvature c = a^2/b (TR8350.2 Table 3.3) */
    radii_at(90.0, &rm, &rn);
    assert_near(rm, 6399593.6258, TOL_RADIUS_M + 1e-4);
    assert_near(rn, 6399593.6258, TOL_RADIUS_M + 1e-4);
    /* 45 deg: M = a(1-e^2)/W^3, N = a/W, W = sqrt(1 - e^2/2), evaluated in extended
     * precision from the defining constants a, 1/f */
    radii_at(45.0, &rm, &rn);
    assert_near(rm, 6367381.8156, TOL_RADIUS_M + 1e-4);
    assert_near(rn, 6388838.2901, TOL_RADIUS_M + 1e-4);
}

static double gravity_at(double lat_deg, double h_m)
{
    return (double)earth_gravity((nav_real_t)sin(lat_deg * DEG), (nav_real_t)h_m);
}

static void test_gravity_published(void **state)
{
    (void)state;
    assert_near(gravity_at(0.0, 0.0), 9.7803253359, TOL_G_MPS2 + 1e-10);
    assert_near(gravity_at(90.0, 0.0), 9.8321849378, TOL_G_MPS2 + 1e-10);
    /* eq. 4-1 at 45 deg with the published gamma_e, k, e^2 */
    assert_near(gravity_at(45.0, 0.0), 9.8061977694, TOL_G_MPS2 + 1e-10);
    /* height: the free-air gradient -0.3086 mGal/m, i.e. -3.086e-6 /s^2, to 0.2 %
     * (the published figure is rounded; it varies by 0.1 % with latitude) */
    for (int lat = 0; lat <= 90; lat += 45) {
        const double grad = (gravity_at(lat, 1000.0) - gravity_at(lat, 0.0)) / 1000.0;
        assert_near(grad, -3.086e-6, 0.002 * 3.086e-6 + TOL_G_MPS2 / 1000.0);
    }
    /* the second-order term 3 g h^2 / a^2 of eq. 4-3: at 10 km the series departs from the
     * chord through 0 and 1 km by 3 g (1e8 - 1e7) / a^2 = 6.5e-5 m/s^2 */
    const double chord = gravity_at(45.0, 0.0) + 10.0 * (gravity_at(45.0, 1e3) - gravity_at(45.0, 0.0));
    assert_near(gravity_at(45.0, 1e4) - chord, 3.0 * 9.806 * 9e7 / (6378137.0 * 6378137.0),
                1e-8 + 15.0 * TOL_G_MPS2);
}

static void test_earth_and_transport_rate(void **state)
{
    (void)state;
    earth_t e;
    earth_eval((nav_real_t)(45.0 * DEG), (nav_real_t)100.0, &e);
    const double U = 7.292115e-5;
    assert_near(e.w_ie_n_rps[0], 0.0, 0.0);
    assert_near(e.w_ie_n_rps[1], U * cos(45.0 * DEG), U * TOL_REL * 4.0);
    assert_near(e.w_ie_n_rps[2], U * sin(45.0 * DEG), U * TOL_REL * 4.0);
    /* seed 001 eq. 7: 10 m/s east and 5 m/s north at 100 m */
    const nav_real_t v[3] = {(nav_real_t)10.0, (nav_real_t)5.0, (nav_real_t)0.0};
    nav_real_t w_en[3];
    earth_transport_rate(&e, (nav_real_t)100.0, v, w_en);
    const double rm = 6367381.8156 + 100.0, rn = 6388838.2901 + 100.0;
    assert_near(w_en[0], -5.0 / rm, 5.0 / rm * TOL_REL * 8.0);
    assert_near(w_en[1], 10.0 / rn, 10.0 / rn * TOL_REL * 8.0);
    assert_near(w_en[2], 10.0 * 1.0 / rn, 10.0 / rn * TOL_REL * 40.0);
}

static void test_geo_pos_add(void **state)
{
    (void)state;
    const int64_t LSB_180 = GEO_LSB_180DEG;
    /* one 1e-7 degree north is exactly GEO_LSB_PER_DEG_E7 LSB (to the float rounding) */
    geo_pos_t p = {45 * 10000000LL * GEO_LSB_PER_DEG_E7, 0, 0};
    const int64_t lat0 = p.lat;
    assert_int_equal(geo_pos_add(&p, (nav_real_t)(1e-7 * DEG), (nav_real_t)0.0, (nav_real_t)1.0),
                     NAV_OK);
    assert_near((double)(p.lat - lat0), (double)GEO_LSB_PER_DEG_E7,
                (double)GEO_LSB_PER_DEG_E7 * TOL_REL * 2.0 + 1.0);
    assert_near((double)p.h, 1000.0 * (double)GEO_LSB_PER_MM, 1.0);
    assert_near(geo_lat_rad(&p), (45.0 + 1e-7) * DEG, 45.0 * DEG * TOL_REL);
    assert_near(geo_h_m(&p), 1.0, TOL_REL);

    /* longitude wraps east across 180 deg */
    geo_pos_t w = {0, LSB_180 - GEO_LSB_PER_DEG_E7, 0};
    assert_int_equal(geo_pos_add(&w, (nav_real_t)0.0, (nav_real_t)(3e-7 * DEG), (nav_real_t)0.0),
                     NAV_OK);
    assert_near((double)w.lon, (double)(-LSB_180 + 2 * GEO_LSB_PER_DEG_E7),
                (double)GEO_LSB_PER_DEG_E7 * 1e-6);
    /* and west across -180 deg */
    geo_pos_t v = {0, -LSB_180 + GEO_LSB_PER_DEG_E7, 0};
    assert_int_equal(geo_pos_add(&v, (nav_real_t)0.0, (nav_real_t)(-3e-7 * DEG), (nav_real_t)0.0),
                     NAV_OK);
    assert_true(v.lon > 0 && v.lon <= LSB_180);

    /* rejected without change: beyond the pole, NaN, absurd step */
    geo_pos_t q = {LSB_180 / 2 - GEO_LSB_PER_DEG_E7, 0, 0};
    const geo_pos_t q0 = q;
    assert_int_equal(geo_pos_add(&q, (nav_real_t)(2e-7 * DEG), (nav_real_t)0.0, (nav_real_t)0.0),
                     NAV_ERANGE);
    assert_int_equal(geo_pos_add(&q, (nav_real_t)NAN, (nav_real_t)0.0, (nav_real_t)0.0),
                     NAV_ERANGE);
    assert_int_equal(geo_pos_add(&q, (nav_real_t)0.0, (nav_real_t)0.0, (nav_real_t)INFINITY),
                     NAV_ERANGE);
    assert_int_equal(geo_pos_add(&q, (nav_real_t)0.5, (nav_real_t)0.0, (nav_real_t)0.0),
                     NAV_ERANGE);
    assert_memory_equal(&q, &q0, sizeof q);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_radii_published),
        cmocka_unit_test(test_gravity_published),
        cmocka_unit_test(test_earth_and_transport_rate),
        cmocka_unit_test(test_geo_pos_add),
    };
    return cmocka_run_group_tests_name("earth_" VARIANT, tests, NULL, NULL);
}
