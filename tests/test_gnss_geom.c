/*
 * test_gnss_geom.c - gnss_geom.h: the receiver's ECEF position in 0.1 mm from the core's
 * fixed-point geodetic position, a satellite's range and line of sight in the receive-time
 * axes, and the pseudorange residual, against double-precision references computed here
 * (libm's sin/cos to 1e-16, an ECEF of 6.4e6 m to 1e-9 m). Tolerances: the fixed point's
 * 0.1 mm unit (half of it from rounding, the rest of the Q62 arithmetic far below);
 * float32 only in the small corrections (the Earth-rotation term of up to 130 m, to 1e-7
 * of it; the range's correction of a few metres, to 1e-7 of it).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <cmocka.h>

#include "gnss_geom.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define A 6378137.0
#define E2 6.69437999014e-3
#define OMEGA 7.292115e-5
#define C_MPS 299792458.0

static geo_pos_t geo(double lat_deg, double lon_deg, double h_m)
{
    geo_pos_t p;
    p.lat = (int64_t)llround(lat_deg * 1e7 * (double)GEO_LSB_PER_DEG_E7);
    p.lon = (int64_t)llround(lon_deg * 1e7 * (double)GEO_LSB_PER_DEG_E7);
    p.h = (int64_t)llround(h_m * 1000.0 * (double)GEO_LSB_PER_MM);
    return p;
}

/* the same position's ECEF in double, from the position's exact fixed-point value */
static void ecef_ref(const geo_pos_t *p, double x[3])
{
    const double lat = (double)p->lat / (1e7 * (double)GEO_LSB_PER_DEG_E7) * PI / 180.0;
    const double lon = (double)p->lon / (1e7 * (double)GEO_LSB_PER_DEG_E7) * PI / 180.0;
    const double h = (double)p->h / (1000.0 * (double)GEO_LSB_PER_MM);
    const double n = A / sqrt(1.0 - E2 * sin(lat) * sin(lat));
    x[0] = (n + h) * cos(lat) * cos(lon);
    x[1] = (n + h) * cos(lat) * sin(lon);
    x[2] = (n * (1.0 - E2) + h) * sin(lat);
}

/* sin and cos in Q62 against libm over the whole turn, 1e-15 (libm's own error ~1e-16,
 * the Q62 unit 2e-19) */
static void test_sin_cos_q62(void **state)
{
    (void)state;
    double worst = 0.0;
    for (int k = -1000; k <= 1000; k++) {
        const double a = PI * (double)k / 1000.0 * 0.999999;
        const int64_t q61 = (int64_t)llround(a * 2305843009213693952.0); /* 2^61 */
        int64_t s, c;
        gnss_geom_sin_cos_q62(q61, &s, &c);
        const double exact = (double)q61 / 2305843009213693952.0;
        const double es = fabs((double)s / 4611686018427387904.0 - sin(exact));
        const double ec = fabs((double)c / 4611686018427387904.0 - cos(exact));
        worst = fmax(worst, fmax(es, ec));
    }
    printf("sin/cos Q62: worst error %.2e over the turn\n", worst);
    assert_true(worst < 1e-15);
}

/* ECEF over latitudes -89..89 deg, longitudes -180..180 deg, heights -500..9000 m: within
 * 0.06 mm of the double reference on every axis (the final rounding to 0.1 mm, 0.05 mm,
 * and the Q62 arithmetic carried in 0.1 mm / 2^16 before it) */
static void test_ecef(void **state)
{
    (void)state;
    double worst = 0.0;
    for (int i = -89; i <= 89; i += 7) {
        for (int j = -180; j <= 180; j += 13) {
            for (int k = 0; k < 3; k++) {
                const double h = k == 0 ? -500.0 : (k == 1 ? 123.456789 : 9000.0);
                const geo_pos_t p = geo((double)i + 0.123456789, (double)j + 0.987654321, h);
                int64_t got[3];
                double ref[3];
                geo_to_ecef_dmm(&p, got);
                ecef_ref(&p, ref);
                for (int a = 0; a < 3; a++) {
                    worst = fmax(worst, fabs((double)got[a] * 1e-4 - ref[a]));
                }
            }
        }
    }
    printf("ECEF in 0.1 mm: worst error %.3f mm\n", worst * 1e3);
    assert_true(worst < 6e-5);
}

/* a GPS-like satellite over Kingston (44.2 N, 76.5 W): the range in the receive-time axes
 * against the double reference (the satellite turned by omega x tau, tau iterated) within
 * 0.2 mm; the line of sight a unit vector along it; the pseudorange residual exact in
 * integers (a pseudorange of range + 120 km of clock + 3.21 m, the clock given: 3.21 m) */
static void test_satellite_range(void **state)
{
    (void)state;
    const geo_pos_t p = geo(44.2312345, -76.4987654, 95.0);
    int64_t rx[3];
    geo_to_ecef_dmm(&p, rx);
    const int32_t sat[3] = {550000000, -1000000000, 900000000}; /* x 0.02 m */
    const int16_t vel[3] = {-8000, 12000, 4000};                 /* x 0.125 m/s */
    gnss_geom_t g;
    assert_int_equal(gnss_geom_sat(rx, sat, vel, &g), NAV_OK);
    double r[3], s[3], d[3];
    for (int i = 0; i < 3; i++) {
        r[i] = (double)rx[i] * 1e-4;
        s[i] = (double)sat[i] * 0.02;
    }
    double tau = 0.07, range = 0.0;
    for (int it = 0; it < 5; it++) {
        const double th = OMEGA * tau;
        d[0] = cos(th) * s[0] + sin(th) * s[1] - r[0];
        d[1] = -sin(th) * s[0] + cos(th) * s[1] - r[1];
        d[2] = s[2] - r[2];
        range = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        tau = range / C_MPS;
    }
    const double got = ((double)g.range_dmm + (double)g.range_frac_dmm) * 1e-4;
    printf("range %.4f m, error %.3f mm; Earth-rotation term %.3f m\n", range,
           (got - range) * 1e3, hypot(s[0], s[1]) * OMEGA * tau);
    assert_true(fabs(got - range) < 2e-4);
    double n2 = 0.0;
    for (int i = 0; i < 3; i++) {
        n2 += (double)g.los_ecef[i] * (double)g.los_ecef[i];
        assert_true(fabs((double)g.los_ecef[i] - d[i] / range) < 1e-6);
    }
    assert_true(fabs(n2 - 1.0) < 1e-6);
    assert_true(fabs((double)g.tau_s - tau) < 1e-8); /* float32: 1e-7 of 0.08 s */
    /* the velocity turned by omega x tau too: within float32 of the double */
    const double th = OMEGA * tau;
    assert_true(fabs((double)g.sat_vel_mps[0] - (-1000.0 + th * 1500.0)) < 1e-3);
    assert_true(fabs((double)g.sat_vel_mps[1] - (1500.0 + th * 1000.0)) < 1e-3);
    /* the pseudorange: the range rounded to 0.02 m, plus 120 km of clock and 3.21 m */
    const int64_t clock_dmm = 1200000000; /* 120 km */
    const uint32_t pr = (uint32_t)llround((range + 120000.0 + 3.21) / 0.02);
    const double want = (double)pr * 0.02 - range - 120000.0;
    const nav_real_t z = gnss_geom_pr_residual_m(pr, &g, clock_dmm);
    printf("pseudorange residual %.5f m (exact %.5f m)\n", (double)z, want);
    assert_true(fabs((double)z - want) < 2e-4);
}

/* A satellite on GPS's orbit (26,560 km from the centre) seen at elevation el_deg from
 * rx (0.1 mm), towards the east: its position in 0.02 m */
static void sat_at_elevation(const int64_t rx[3], double el_deg, int32_t sat[3])
{
    double r[3], up[3];
    for (int i = 0; i < 3; i++) {
        r[i] = (double)rx[i] * 1e-4;
    }
    const double rn = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (int i = 0; i < 3; i++) {
        up[i] = r[i] / rn;
    }
    const double en = hypot(up[0], up[1]);
    const double east[3] = {-up[1] / en, up[0] / en, 0.0};
    const double e = el_deg * M_PI / 180.0, R = 26560e3;
    const double rho = -rn * sin(e) + sqrt(rn * rn * sin(e) * sin(e) - rn * rn + R * R);
    for (int i = 0; i < 3; i++) {
        sat[i] = (int32_t)llround((r[i] + rho * (cos(e) * east[i] + sin(e) * up[i])) / 0.02);
    }
}

/* Not a GNSS satellite, refused: 100 m from the receiver; at the Earth's centre (6,378 km
 * from the receiver, inside the 1,000-100,000 km that let it through before: a review's
 * finding); on GPS's orbit straight below the receiver (nadir) or 15 deg below its
 * horizon. On the orbit 5 deg below (a mountain's horizon), 5 and 90 deg above: taken. */
static void test_impossible_satellite(void **state)
{
    (void)state;
    const geo_pos_t p = geo(10.0, 20.0, 0.0);
    int64_t rx[3];
    geo_to_ecef_dmm(&p, rx);
    const int32_t near[3] = {(int32_t)(rx[0] / 200 + 5000), (int32_t)(rx[1] / 200),
                             (int32_t)(rx[2] / 200)};
    const int16_t v[3] = {0, 0, 0};
    gnss_geom_t g;
    assert_int_equal(gnss_geom_sat(rx, near, v, &g), NAV_EINVAL);
    const int32_t centre[3] = {0, 0, 0};
    assert_int_equal(gnss_geom_sat(rx, centre, v, &g), NAV_EINVAL);
    int32_t sat[3];
    sat_at_elevation(rx, -90.0, sat);
    assert_int_equal(gnss_geom_sat(rx, sat, v, &g), NAV_EINVAL);
    sat_at_elevation(rx, -15.0, sat);
    assert_int_equal(gnss_geom_sat(rx, sat, v, &g), NAV_EINVAL);
    sat_at_elevation(rx, -5.0, sat);
    assert_int_equal(gnss_geom_sat(rx, sat, v, &g), NAV_OK);
    sat_at_elevation(rx, 5.0, sat);
    assert_int_equal(gnss_geom_sat(rx, sat, v, &g), NAV_OK);
    sat_at_elevation(rx, 90.0, sat);
    assert_int_equal(gnss_geom_sat(rx, sat, v, &g), NAV_OK);
    /* along (1, 1, 1), above this receiver's horizon: 45,000 km from the centre (QZSS's
     * apogee, 45,330 km) is taken, 50,000 km (each axis 28,868 km, within the frame's
     * range) is not a GNSS orbit */
    int32_t far[3];
    for (int i = 0; i < 3; i++) {
        far[i] = (int32_t)llround(45000e3 / sqrt(3.0) / 0.02);
    }
    assert_int_equal(gnss_geom_sat(rx, far, v, &g), NAV_OK);
    for (int i = 0; i < 3; i++) {
        far[i] = (int32_t)llround(50000e3 / sqrt(3.0) / 0.02);
    }
    assert_int_equal(gnss_geom_sat(rx, far, v, &g), NAV_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sin_cos_q62),
        cmocka_unit_test(test_ecef),
        cmocka_unit_test(test_satellite_range),
        cmocka_unit_test(test_impossible_satellite),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
