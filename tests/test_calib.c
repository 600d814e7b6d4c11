/*
 * test_calib.c - calib.h: the car's calibration (dH, mu) and its NVM policy over the
 * power-safe store (calstore.h) in the in-memory HAL: boot from an empty, corrupt or valid
 * store, StoreCalibration's rate limit, erase, the one-point calibration and its refusals,
 * the filter's estimates adopted only below APP_CAL_ADOPT_SIGMA and stored only at a
 * standstill, when moved by more than 2 sigma, at most every 600 s.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "calib.h"
#include "fake_hal.h"
#include "navecu_can.h"
#include "test_util.h"

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define RATE_HZ 100u
#define RM_45 6367381.8 /* WGS-84 meridian radius at 45 deg */
#define RN_45 6388838.3 /* and the prime vertical's */

static hal_t hal;
static calib_t c;
static calib_trip_t trip;
static dr_t dr;
static sins_t nav;
static ekf_t ekf;
static geo_pos_t base;

static int setup(void **state)
{
    (void)state;
    fake_hal_reset(&hal);
    calib_init(&c);
    memset(&trip, 0, sizeof trip);
    base.lat = 450000000LL * 16777216LL;
    base.lon = 100000000LL * 16777216LL;
    base.h = 0;
    assert_int_equal(dr_init(&dr, &base, 0.0f, 0.0f), NAV_OK);
    return 0;
}

/* what the store holds now */
static int stored(cal_record_t *rec)
{
    calstore_t cs;
    return calstore_load(&hal, &cs, rec);
}

static void save_record(float dh, float mu, float base_m, uint8_t source)
{
    calstore_t cs = {0u, -1};
    const cal_record_t rec = {dh, mu, base_m, source};
    assert_int_equal(calstore_save(&hal, &cs, &rec), 0);
}

/* ---- boot ---- */

static void test_boot_empty(void **state)
{
    (void)state;
    calib_boot(&c, &hal);
    assert_int_equal(c.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NONE_CHOICE);
    assert_int_equal(c.source, CAL_SRC_NONE);
    assert_int_equal(c.nvm_error, 0);
    assert_int_equal(c.stored, 0);
    assert_near(c.dh_rad, 0.0, 0.0);
    assert_near(c.mu, 0.0, 0.0);
}

static void test_boot_valid(void **state)
{
    (void)state;
    save_record(0.01f, -0.02f, 2500.0f, CAL_SRC_KNOWN_POSITION);
    calib_boot(&c, &hal);
    assert_int_equal(c.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_FROM_NVM_CHOICE);
    assert_int_equal(c.source, CAL_SRC_KNOWN_POSITION);
    assert_int_equal(c.stored, 1);
    assert_int_equal(c.nvm_error, 0);
    assert_near(c.dh_rad, 0.01f, 0.0);
    assert_near(c.mu, -0.02f, 0.0);
    assert_near(c.base_m, 2500.0, 0.0);
}

/* A bit flipped in the record (both slots touched: one held it, the other was erased):
 * the defaults, CalStatus NvmCorrupt, the NVM flag raised. */
static void test_boot_corrupt(void **state)
{
    (void)state;
    save_record(0.01f, -0.02f, 2500.0f, CAL_SRC_GNSS);
    fake_hal_nvm_corrupt(&hal, 12u, 0x01u);
    fake_hal_nvm_corrupt(&hal, FAKE_NVM_SECTOR_SIZE + 12u, 0x01u);
    calib_boot(&c, &hal);
    assert_int_equal(c.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NVM_CORRUPT_CHOICE);
    assert_int_equal(c.nvm_error, 1);
    assert_int_equal(c.source, CAL_SRC_NONE);
    assert_int_equal(c.stored, 0);
    assert_near(c.dh_rad, 0.0, 0.0);
    assert_near(c.mu, 0.0, 0.0);
}

/* An NVM read error: the defaults and the NVM flag, CalStatus still None. */
static void test_boot_read_error(void **state)
{
    (void)state;
    save_record(0.01f, -0.02f, 2500.0f, CAL_SRC_GNSS);
    hal.nvm_fail = 1;
    calib_boot(&c, &hal);
    assert_int_equal(c.nvm_error, 1);
    assert_int_equal(c.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NONE_CHOICE);
    assert_near(c.mu, 0.0, 0.0);
}

/* ---- storing and erasing ---- */

/* StoreCalibration: refused with nothing calibrated; GIVEN a calibration THEN stored at
 * sample 500, refused at 500 + 999 (within 10 s at 100 Hz), taken again at 500 + 1000. */
static void test_store_rate_limit(void **state)
{
    (void)state;
    assert_int_equal(calib_store_command(&c, &trip, &hal, 500u, RATE_HZ), -1);
    c.dh_rad = 0.01f;
    c.mu = 0.03f;
    c.source = CAL_SRC_KNOWN_POSITION;
    assert_int_equal(calib_store_command(&c, &trip, &hal, 500u, RATE_HZ), 0);
    assert_int_equal(c.stored, 1);
    cal_record_t rec;
    assert_int_equal(stored(&rec), CALSTORE_OK);
    assert_near(rec.dh_rad, 0.01f, 0.0);
    assert_near(rec.odo_scale_err, 0.03f, 0.0);
    assert_int_equal(rec.source, CAL_SRC_KNOWN_POSITION);
    c.mu = 0.04f;
    assert_int_equal(calib_store_command(&c, &trip, &hal, 1499u, RATE_HZ), -1);
    assert_int_equal(stored(&rec), CALSTORE_OK);
    assert_near(rec.odo_scale_err, 0.03f, 0.0);
    assert_int_equal(calib_store_command(&c, &trip, &hal, 1500u, RATE_HZ), 0);
    assert_int_equal(stored(&rec), CALSTORE_OK);
    assert_near(rec.odo_scale_err, 0.04f, 0.0);
}

/* A failing NVM: not stored, the NVM flag; the next good save clears it. */
static void test_store_failure_flagged(void **state)
{
    (void)state;
    c.source = CAL_SRC_GNSS;
    hal.nvm_fail = 1;
    calib_store(&c, &trip, &hal, 100u);
    assert_int_equal(c.stored, 0);
    assert_int_equal(c.nvm_error, 1);
    hal.nvm_fail = 0;
    calib_store(&c, &trip, &hal, 2000u);
    assert_int_equal(c.stored, 1);
    assert_int_equal(c.nvm_error, 0);
}

/* EraseCalibration: the store empty, the values in use and the dead reckoning's back to
 * zero; an NVM failure leaves everything as it was. */
static void test_erase(void **state)
{
    (void)state;
    c.dh_rad = 0.01f;
    c.mu = 0.03f;
    c.source = CAL_SRC_KNOWN_POSITION;
    c.status = NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_ONE_POINT_CHOICE;
    calib_store(&c, &trip, &hal, 100u);
    assert_int_equal(dr_set_compensation(&dr, 0.01f, 0.03f), NAV_OK);
    hal.nvm_fail = 1;
    calib_erase(&c, &hal, &dr);
    assert_int_equal(c.nvm_error, 1);
    assert_near(c.mu, 0.03f, 0.0);
    assert_int_equal(c.source, CAL_SRC_KNOWN_POSITION);
    assert_near(dr.mu, 0.03f, 0.0);
    hal.nvm_fail = 0;
    calib_erase(&c, &hal, &dr);
    assert_int_equal(c.nvm_error, 0);
    assert_near(c.mu, 0.0, 0.0);
    assert_near(c.dh_rad, 0.0, 0.0);
    assert_int_equal(c.source, CAL_SRC_NONE);
    assert_int_equal(c.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_NONE_CHOICE);
    assert_int_equal(c.stored, 0);
    assert_near(dr.mu, 0.0, 0.0);
    assert_near(dr.dh_rad, 0.0, 0.0);
    cal_record_t rec;
    assert_int_equal(stored(&rec), CALSTORE_EMPTY);
    /* not navigating: no dead reckoning to reset */
    c.mu = 0.05f;
    calib_erase(&c, &hal, NULL);
    assert_near(c.mu, 0.0, 0.0);
}

/* ---- one-point calibration ---- */

/* the dead reckoning driven 3000 m north from base, and a navigator beside it */
static void drive_north_3000(void)
{
    for (int k = 0; k < 300; k++) {
        assert_int_equal(dr_step(&dr, 10.0f, 0.0f, 0.0f), NAV_OK);
    }
    const sins_config_t cfg = sins_default_config();
    nav_real_t q[4];
    quat_from_euler(0.0f, 0.0f, 0.0f, q);
    const nav_real_t v0[3] = {0.0f, 0.0f, 0.0f};
    assert_int_equal(sins_init(&nav, &cfg, &dr.pos, v0, q), NAV_OK);
}

/* a point at bearing b_deg from base, at d_m, flat Earth at 45 N */
static geo_pos_t point_at(double b_deg, double d_m)
{
    geo_pos_t p;
    const double lat = 45.0 + d_m * cos(b_deg * DEG) / RM_45 / DEG;
    const double lon = 10.0 + d_m * sin(b_deg * DEG) / (RN_45 * cos(45.0 * DEG)) / DEG;
    p.lat = (int64_t)llround(lat * 1e7 * 16777216.0);
    p.lon = (int64_t)llround(lon * 1e7 * 16777216.0);
    p.h = 0;
    return p;
}

/* GIVEN 3000 m dead-reckoned north WHEN the true point lies 1 deg west of that bearing at
 * 3000 / 1.02 m (the heading reads 1 deg too far clockwise, the odometer 2 % long) THEN
 * dH = +1 deg and mu = 0.02, CalStatus OnePoint, counted, stored with its source and base,
 * and the dead reckoning and the navigator are at the point. */
static void test_one_point(void **state)
{
    (void)state;
    drive_north_3000();
    const geo_pos_t p = point_at(-1.0, 3000.0 / 1.02);
    assert_int_equal(calib_one_point(&c, &trip, &hal, 5000u, 1, &dr, &nav, &p,
                                     CAL_SRC_KNOWN_POSITION, 2000.0f, NULL),
                     0);
    assert_near(c.dh_rad, 1.0 * DEG, 2e-5);
    assert_near(c.mu, 0.02, 2e-5);
    assert_near(c.base_m, 3000.0 / 1.02, 0.05);
    assert_int_equal(c.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_ONE_POINT_CHOICE);
    assert_int_equal(c.source, CAL_SRC_KNOWN_POSITION);
    assert_int_equal(c.count, 1);
    assert_int_equal(c.stored, 1);
    assert_near(dr.dh_rad, c.dh_rad, 0.0);
    assert_near(dr.mu, c.mu, 0.0);
    assert_true(dr.pos.lat == p.lat && dr.pos.lon == p.lon);
    assert_true(nav.pos.lat == p.lat && nav.pos.lon == p.lon);
    cal_record_t rec;
    assert_int_equal(stored(&rec), CALSTORE_OK);
    assert_near(rec.dh_rad, c.dh_rad, 0.0);
    assert_near(rec.odo_scale_err, c.mu, 0.0);
    assert_int_equal(rec.source, CAL_SRC_KNOWN_POSITION);
}

/* Refusals: not ready (RefusedNotReady), the point closer than the minimum base
 * (RefusedTooClose), the point at the base itself (degenerate: RefusedNotReady); nothing
 * changes, nothing is stored. */
static void test_one_point_refusals(void **state)
{
    (void)state;
    drive_north_3000();
    const geo_pos_t p = point_at(-1.0, 3000.0 / 1.02);
    const geo_pos_t before = dr.pos;
    assert_int_equal(calib_one_point(&c, &trip, &hal, 5000u, 0, &dr, &nav, &p, CAL_SRC_GNSS,
                                     2000.0f, NULL),
                     -1);
    assert_int_equal(c.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE);
    assert_int_equal(calib_one_point(&c, &trip, &hal, 5000u, 1, &dr, &nav, &p, CAL_SRC_GNSS,
                                     3000.0f, NULL),
                     -1);
    assert_int_equal(c.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_TOO_CLOSE_CHOICE);
    assert_int_equal(calib_one_point(&c, &trip, &hal, 5000u, 1, &dr, &nav, &base, CAL_SRC_GNSS,
                                     0.0f, NULL),
                     -1);
    assert_int_equal(c.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE);
    assert_int_equal(c.count, 0);
    assert_int_equal(c.source, CAL_SRC_NONE);
    assert_true(dr.pos.lat == before.lat && dr.pos.lon == before.lon);
    cal_record_t rec;
    assert_int_equal(stored(&rec), CALSTORE_EMPTY);
    calib_not_ready(&c);
    assert_int_equal(c.status, NAVECU_CAN_NAV_CALIBRATION_CAL_STATUS_REFUSED_NOT_READY_CHOICE);
}

/* ---- the filter's estimates ---- */

/* the filter's odometer scale k and mounting yaw with their 1-sigmas, its speed offset 0
 * known to 1 mm/s, after 100 s more of the trip at 10 m/s */
static void filter_says(float k, float sk, float yaw, float sy)
{
    ekf.k = k;
    ekf.mount_yaw_rad = yaw;
    ekf.P[EKF_K][EKF_K] = sk * sk;
    ekf.P[EKF_MY][EKF_MY] = sy * sy;
    ekf.odo_offset_mps = 0.0f;
    ekf.P[EKF_OB][EKF_OB] = 1e-6f;
    ekf.P[EKF_K][EKF_OB] = ekf.P[EKF_OB][EKF_K] = 0.0f;
    for (int i = 0; i < 100 * (int)RATE_HZ; i++) {
        calib_trip_odo(&trip, 1, 10.0f, 1.0f / (float)RATE_HZ);
    }
}

/* GIVEN the filter's scale k 0.001 (sigma 0.0019) and speed offset -0.12 m/s (sigma 0.019
 * m/s) correlated -0.94 (the kind of figures a drive with an offset-type odometer gives:
 * Kingston's ends at k sigma 0.0026 and offset sigma 0.026 m/s, navecu's summary of `make
 * kingston OUTAGES=none`), and a trip at 10 m/s
 * mean (and 0.3 m/s of creeping, which is not counted) THEN the calibration adopted is the
 * scale the trip's distance implies, k + o / 10 = -0.011, its sigma 0.00066 (the two
 * estimates' errors cancel: below APP_CAL_ADOPT_SIGMA); uncorrelated its sigma would be
 * 0.0027 and nothing is adopted. */
static void test_filter_adoption_with_offset(void **state)
{
    (void)state;
    const ekf_config_t ec = ekf_default_config();
    for (int correlated = 0; correlated < 2; correlated++) {
        assert_int_equal(ekf_init(&ekf, &ec, 0.0f), NAV_OK);
        memset(&trip, 0, sizeof trip);
        calib_init(&c);
        filter_says(0.001f, 0.0019f, 0.02f, 0.0004f);
        for (int i = 0; i < 10 * (int)RATE_HZ; i++) {
            calib_trip_odo(&trip, 1, 0.3f, 1.0f / (float)RATE_HZ);
        }
        ekf.odo_offset_mps = -0.12f;
        ekf.P[EKF_OB][EKF_OB] = 0.019f * 0.019f;
        ekf.P[EKF_K][EKF_OB] = ekf.P[EKF_OB][EKF_K] =
            correlated ? -0.94f * 0.0019f * 0.019f : 0.0f;
        calib_adopt_filter(&c, &trip, &hal, 1000u, RATE_HZ, &ekf, &dr, 1);
        if (correlated) {
            assert_int_equal(c.source, CAL_SRC_FILTER);
            /* float32: 1e-6 (the mean speed exact in the integer sums) */
            assert_near(c.mu, 0.001 - 0.012, 1e-6);
            assert_near(dr.mu, 0.001 - 0.012, 1e-6);
        } else {
            assert_int_equal(c.source, CAL_SRC_NONE);
        }
    }
}

static float stored_mu(void)
{
    cal_record_t rec;
    return stored(&rec) == CALSTORE_OK ? rec.odo_scale_err : -1.0f;
}

/* GIVEN sigma(k) 0.0013 and sigma(yaw) 0.0008 (root sum square 0.00153, above
 * APP_CAL_ADOPT_SIGMA, 0.15 % of distance), or the yaw's alone 0.0016, THEN nothing is
 * adopted; GIVEN 0.0012 and 0.0008 (0.00144: the scale's above 0.1 %, as Kingston's ends)
 * THEN k and the mounting yaw are the calibration in use (CalSource Filter) and the dead
 * reckoning's, but stored only at a standstill, and the store counts (CalCount); its
 * sigmas for the dead reckoning's accuracy are 0.15 % each (each part at most the sum). */
static void test_filter_adoption(void **state)
{
    (void)state;
    const ekf_config_t ec = ekf_default_config();
    assert_int_equal(ekf_init(&ekf, &ec, 0.0f), NAV_OK);
    filter_says(0.01f, 0.0013f, 0.02f, 0.0008f);
    calib_adopt_filter(&c, &trip, &hal, 1000u, RATE_HZ, &ekf, &dr, 1);
    assert_int_equal(c.source, CAL_SRC_NONE);
    assert_near(c.mu, 0.0, 0.0);
    filter_says(0.01f, 0.0001f, 0.02f, 0.0016f);
    calib_adopt_filter(&c, &trip, &hal, 1000u, RATE_HZ, &ekf, &dr, 1);
    assert_int_equal(c.source, CAL_SRC_NONE);

    filter_says(0.01f, 0.0012f, 0.02f, 0.0008f);
    calib_adopt_filter(&c, &trip, &hal, 1000u, RATE_HZ, &ekf, &dr, 0);
    assert_int_equal(c.source, CAL_SRC_FILTER);
    assert_near(c.mu, 0.01f, 0.0);
    assert_near(c.dh_rad, 0.02f, 0.0);
    assert_near(dr.mu, 0.01f, 0.0);
    assert_near(dr.dh_rad, 0.02f, 0.0);
    assert_int_equal(c.stored, 0);
    assert_near(stored_mu(), -1.0, 0.0); /* moving: not written */
    assert_int_equal(c.count, 0);
    calib_adopt_filter(&c, &trip, &hal, 1100u, RATE_HZ, &ekf, &dr, 1);
    assert_int_equal(c.stored, 1);
    assert_int_equal(c.count, 1);
    assert_near(stored_mu(), 0.01f, 0.0);
    cal_record_t rec;
    (void)stored(&rec);
    assert_int_equal(rec.source, CAL_SRC_FILTER);
    assert_near(rec.dh_rad, 0.02f, 0.0);
    nav_real_t s_mu, s_yaw;
    calib_sigmas(&c, &ec, 1.0f, &s_mu, &s_yaw);
    assert_near(s_mu, 0.0015, 1e-7);
    assert_near(s_yaw, 0.0015, 1e-7);
    /* an estimate beyond what the dead reckoning takes (|k| > 0.2) is not adopted */
    filter_says(0.3f, 0.0001f, 0.02f, 0.0001f);
    calib_adopt_filter(&c, &trip, &hal, 200000u, RATE_HZ, &ekf, &dr, 1);
    assert_near(c.mu, 0.01f, 0.0);
}

/* GIVEN k 0.01 stored at sample 1100 with sigma 0.0004 (2 sigma = 0.0008) WHEN k is 0.0107
 * THEN it is in use but not worth a save; WHEN 0.0109 within 600 s of the save THEN not
 * yet (flash wear); at 600 s it is stored. The mounting yaw likewise. */
static void test_filter_store_policy(void **state)
{
    (void)state;
    const ekf_config_t ec = ekf_default_config();
    assert_int_equal(ekf_init(&ekf, &ec, 0.0f), NAV_OK);
    filter_says(0.01f, 0.0004f, 0.02f, 0.0004f);
    calib_adopt_filter(&c, &trip, &hal, 1100u, RATE_HZ, &ekf, &dr, 1);
    assert_near(stored_mu(), 0.01f, 0.0);
    const uint64_t gap = 600u * RATE_HZ;
    filter_says(0.0107f, 0.0004f, 0.02f, 0.0004f);
    calib_adopt_filter(&c, &trip, &hal, 1100u + gap + 1u, RATE_HZ, &ekf, &dr, 1);
    assert_near(c.mu, 0.0107f, 0.0);
    assert_near(stored_mu(), 0.01f, 0.0);
    filter_says(0.0109f, 0.0004f, 0.02f, 0.0004f);
    calib_adopt_filter(&c, &trip, &hal, 1100u + gap - 1u, RATE_HZ, &ekf, &dr, 1);
    assert_near(stored_mu(), 0.01f, 0.0);
    assert_int_equal(c.stored, 0);
    calib_adopt_filter(&c, &trip, &hal, 1100u + gap, RATE_HZ, &ekf, &dr, 1);
    assert_near(stored_mu(), 0.0109f, 0.0);
    assert_int_equal(c.stored, 1);
    /* the yaw moved by 0.001 > 0.0008, 600 s later: stored */
    filter_says(0.0109f, 0.0004f, 0.021f, 0.0004f);
    calib_adopt_filter(&c, &trip, &hal, 1100u + 2u * gap, RATE_HZ, &ekf, &dr, 1);
    cal_record_t rec;
    assert_int_equal(stored(&rec), CALSTORE_OK);
    assert_near(rec.dh_rad, 0.021f, 0.0);
}

/* The dead reckoning starts with the calibration in use; one out of range is refused. */
static void test_start_dr(void **state)
{
    (void)state;
    c.dh_rad = -0.1f;
    c.mu = 0.05f;
    dr_t d;
    assert_int_equal(calib_start_dr(&c, &d, &base), NAV_OK);
    assert_near(d.dh_rad, -0.1f, 0.0);
    assert_near(d.mu, 0.05f, 0.0);
    assert_true(d.pos.lat == base.lat && d.base.lon == base.lon);
    c.dh_rad = 0.6f; /* beyond DR_DH_MAX_RAD */
    assert_int_not_equal(calib_start_dr(&c, &d, &base), NAV_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_boot_empty, setup),
        cmocka_unit_test_setup(test_boot_valid, setup),
        cmocka_unit_test_setup(test_boot_corrupt, setup),
        cmocka_unit_test_setup(test_boot_read_error, setup),
        cmocka_unit_test_setup(test_store_rate_limit, setup),
        cmocka_unit_test_setup(test_store_failure_flagged, setup),
        cmocka_unit_test_setup(test_erase, setup),
        cmocka_unit_test_setup(test_one_point, setup),
        cmocka_unit_test_setup(test_one_point_refusals, setup),
        cmocka_unit_test_setup(test_filter_adoption, setup),
        cmocka_unit_test_setup(test_filter_adoption_with_offset, setup),
        cmocka_unit_test_setup(test_filter_store_policy, setup),
        cmocka_unit_test_setup(test_start_dr, setup),
    };
    return cmocka_run_group_tests_name("calib", tests, NULL, NULL);
}
