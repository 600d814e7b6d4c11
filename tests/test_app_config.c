/*
 * test_app_config.c - app_config.h: the defaults the ECU runs with, and the range check
 * every configuration goes through, field by field at its limits (NaN refused).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app_config.h"
#include "test_util.h"

/* The documented defaults (firmware/app/params.toml, docs/configuration.md): IMU 100 Hz,
 * outputs 50 Hz, status 10 Hz, levelling 30 s, rear axle, 2 km minimum base, the automotive
 * MEMS preset (ARW 2 deg/sqrt(h) = 5.82e-4 rad/sqrt(s), turn-on bias 1e-3 rad/s, 0.2 m/s^2,
 * instabilities 20 deg/h and 2 mg over 300 s; 300 deg/s and 8 g), latency 0.1 s, 20 s
 * correlation, no lever arms. */
static void test_defaults(void **state)
{
    (void)state;
    const app_config_t c = app_default_config();
    assert_int_equal(c.imu_rate_hz, 100u);
    assert_int_equal(c.nav_rate_hz, 50u);
    assert_int_equal(c.status_rate_hz, 10u);
    assert_int_equal(c.level_s, 30u);
    assert_int_equal(c.odo_axle, ODO_AXLE_REAR);
    assert_near(c.cal_min_base_m, 2000.0, 0.0);
    assert_near(c.gyro_arw_rad_rts, 2.0 * 3.14159265358979 / 180.0 / 60.0, 1e-9);
    assert_near(c.gyro_bias_rps, 1e-3, 1e-9);
    assert_near(c.accel_bias_mps2, 0.2, 1e-6);
    assert_near(c.gyro_bias_rw_rps_rts, 20.0 * 3.14159265358979 / 180.0 / 3600.0 * sqrt(2.0 / 300.0),
                1e-10);
    assert_near(c.accel_bias_rw_mps2_rts, 0.02 * sqrt(2.0 / 300.0), 1e-8);
    assert_near(c.gnss_latency_s, 0.1, 1e-8);
    assert_near(c.gnss_corr_s, 20.0, 0.0);
    assert_near(c.gnss_white_ratio, 0.33, 1e-6);
    for (int i = 0; i < 3; i++) {
        assert_near(c.gnss_lever_b_m[i], 0.0, 0.0);
        assert_near(c.odo_lever_b_m[i], 0.0, 0.0);
    }
    assert_near(c.gyro_range_rps, 300.0 * 3.14159265358979 / 180.0, 1e-5);
    assert_near(c.accel_range_mps2, 8.0 * 9.80665, 1e-4);
    assert_int_equal(app_config_valid(&c), 1);
}

typedef struct {
    const char *what;
    void (*set)(app_config_t *c);
    int valid;
} edge_t;

#define EDGE(name, stmt, ok) \
    static void set_##name(app_config_t *c) { stmt; }
#define EDGES(X) \
    X(imu_10, c->imu_rate_hz = 10u; c->nav_rate_hz = 10u; c->status_rate_hz = 10u; \
          c->dyn_rate_hz = 10u, 1) \
    X(imu_9, c->imu_rate_hz = 9u; c->nav_rate_hz = 9u; c->status_rate_hz = 9u; \
          c->dyn_rate_hz = 9u, 0) \
    X(imu_400, c->imu_rate_hz = 400u, 1) \
    X(imu_401, c->imu_rate_hz = 401u, 0) \
    X(nav_0, c->nav_rate_hz = 0u, 0) \
    X(nav_eq_imu, c->nav_rate_hz = 100u, 1) \
    X(nav_above_imu, c->nav_rate_hz = 101u, 0) \
    X(status_0, c->status_rate_hz = 0u, 0) \
    X(dyn_0, c->dyn_rate_hz = 0u, 1) \
    X(dyn_eq_imu, c->dyn_rate_hz = 100u, 1) \
    X(dyn_above_imu, c->dyn_rate_hz = 101u, 0) \
    X(track_05, c->odo_track_m = 0.5f, 0) \
    X(wheelbase_6, c->odo_wheelbase_m = 6.0f, 1) \
    X(wheelbase_601, c->odo_wheelbase_m = 6.01f, 0) \
    X(track_0, c->odo_track_m = 0.0f, 0) \
    X(can_id_11bit, c->can_ids[NAVECU_MSG_NAV_TIME] = 0x7FFu, 1) \
    X(can_id_12bit, c->can_ids[NAVECU_MSG_NAV_TIME] = 0x800u, 0) \
    X(can_id_twice, c->can_ids[NAVECU_MSG_NAV_TIME] = c->can_ids[NAVECU_MSG_IMU_RATE], 0) \
    X(status_above_imu, c->status_rate_hz = 101u, 0) \
    X(level_0, c->level_s = 0u, 0) \
    X(level_600, c->level_s = 600u, 1) \
    X(level_601, c->level_s = 601u, 0) \
    X(base_0, c->cal_min_base_m = 0.0f, 1) \
    X(base_neg, c->cal_min_base_m = -1.0f, 0) \
    X(base_1e6, c->cal_min_base_m = 1e6f, 0) \
    X(arw_0, c->gyro_arw_rad_rts = 0.0f, 0) \
    X(arw_nan, c->gyro_arw_rad_rts = NAN, 0) \
    X(arw_1, c->gyro_arw_rad_rts = 1.0f, 0) \
    X(bias_0, c->gyro_bias_rps = 0.0f, 0) \
    X(accel_bias_10, c->accel_bias_mps2 = 10.0f, 0) \
    X(gyro_rw_nan, c->gyro_bias_rw_rps_rts = NAN, 0) \
    X(accel_rw_0, c->accel_bias_rw_mps2_rts = 0.0f, 0) \
    X(latency_0, c->gnss_latency_s = 0.0f, 1) \
    X(latency_05, c->gnss_latency_s = 0.5f, 1) \
    X(latency_051, c->gnss_latency_s = 0.51f, 0) \
    X(latency_neg, c->gnss_latency_s = -0.01f, 0) \
    X(corr_600, c->gnss_corr_s = 600.0f, 1) \
    X(corr_601, c->gnss_corr_s = 601.0f, 0) \
    X(corr_nan, c->gnss_corr_s = NAN, 0) \
    X(white_1, c->gnss_white_ratio = 1.0f, 1) \
    X(white_005, c->gnss_white_ratio = 0.05f, 1) \
    X(white_0, c->gnss_white_ratio = 0.0f, 0) \
    X(white_nan, c->gnss_white_ratio = NAN, 0) \
    X(lever_10, c->gnss_lever_b_m[2] = -10.0f, 1) \
    X(lever_1001, c->gnss_lever_b_m[1] = 10.01f, 0) \
    X(odo_lever_nan, c->odo_lever_b_m[0] = NAN, 0) \
    X(gyro_range_0, c->gyro_range_rps = 0.0f, 0) \
    X(gyro_range_5000dps, c->gyro_range_rps = 87.2664f, 1) \
    X(gyro_range_5001dps, c->gyro_range_rps = 87.28f, 0) \
    X(accel_range_1g, c->accel_range_mps2 = 9.80665f, 1) \
    X(accel_range_below_1g, c->accel_range_mps2 = 9.8f, 0) \
    X(accel_range_2000, c->accel_range_mps2 = 2000.0f, 1) \
    X(accel_range_2001, c->accel_range_mps2 = 2001.0f, 0) \
    X(accel_range_nan, c->accel_range_mps2 = NAN, 0)
EDGES(EDGE)
#define EDGE_ROW(name, stmt, ok) {#name, set_##name, ok},

/* GIVEN the defaults with one field changed THEN valid exactly when that field is within
 * its documented range. */
static void test_ranges(void **state)
{
    (void)state;
    static const edge_t edges[] = {EDGES(EDGE_ROW)};
    for (size_t i = 0u; i < sizeof edges / sizeof edges[0]; i++) {
        app_config_t c = app_default_config();
        edges[i].set(&c);
        if (app_config_valid(&c) != edges[i].valid) {
            fail_msg("%s: valid %d, expected %d", edges[i].what, app_config_valid(&c),
                     edges[i].valid);
        }
    }
}

/* GIVEN the defaults with one parameter of the table at its minimum, its maximum, just
 * below and just above (1e-4 of the span), or NaN THEN valid exactly within the table's
 * range (min excluded where the table says so); the cross-field rules kept (the output
 * rates raised with the IMU rate). */
static void test_every_table_range(void **state)
{
    (void)state;
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        const app_param_t *p = &app_params[k];
        const app_param_id_t id = (app_param_id_t)k;
        const nav_real_t span = p->max_si - p->min_si;
        const nav_real_t d = p->type == APP_PARAM_U16 || p->type == APP_PARAM_ENUM
                                 ? NAV_C(1.0)
                                 : span * NAV_C(1e-4);
        const struct {
            nav_real_t x;
            int valid;
        } cases[] = {{p->min_si, !p->min_exclusive}, {p->max_si, 1},
                     {p->min_si - d, 0},            {p->max_si + d, 0},
                     {(p->min_si + p->max_si) * NAV_C(0.5), p->type != APP_PARAM_U16 &&
                                                              p->type != APP_PARAM_ENUM},
                     {(nav_real_t)NAN, 0}};
        for (size_t i = 0u; i < sizeof cases / sizeof cases[0]; i++) {
            app_config_t c = app_default_config();
            c.imu_rate_hz = 400u; /* the output rates' rule out of the way */
            c.nav_rate_hz = c.status_rate_hz = c.dyn_rate_hz = 1u;
            const nav_real_t v[3] = {cases[i].x, cases[i].x, cases[i].x};
            int want = cases[i].valid;
            if ((p->type == APP_PARAM_U16 || p->type == APP_PARAM_ENUM) && i == 4u) {
                want = floor((double)v[0]) >= (double)v[0]; /* a whole midpoint */
            }
            const int set = app_param_set(&c, id, v);
            const int valid = set == 0 && app_config_valid(&c);
            if (valid != want || (set != 0) != !app_param_in_range(id, v)) {
                fail_msg("%s = %g: valid %d (set %d), expected %d", app_param_names[k],
                         (double)v[0], valid, set, want);
            }
        }
    }
}

/* GIVEN a configuration WHEN each parameter is read and written back THEN nothing changes
 * (app_param_get and app_param_set are each other's inverse). */
static void test_get_set_round_trip(void **state)
{
    (void)state;
    const app_config_t a = app_default_config();
    app_config_t b = a;
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        nav_real_t v[3];
        app_param_get(&a, (app_param_id_t)k, v);
        assert_int_equal(app_param_set(&b, (app_param_id_t)k, v), 0);
    }
    assert_memory_equal(&a, &b, sizeof a);
}

/* GIVEN each preset WHEN applied to the defaults THEN it sets its IMU parameters to its
 * values and nothing else; an unknown preset changes nothing. */
static void test_presets(void **state)
{
    (void)state;
    for (int k = 0; k < (int)APP_PRESET_N; k++) {
        const app_config_t d = app_default_config();
        app_config_t c = d;
        assert_int_equal(app_config_preset(&c, (app_preset_id_t)k), 0);
        assert_int_equal(app_config_valid(&c), 1);
        for (int j = 0; j < (int)APP_PARAM_N; j++) {
            nav_real_t vc[3], vd[3];
            app_param_get(&c, (app_param_id_t)j, vc);
            app_param_get(&d, (app_param_id_t)j, vd);
            int in_preset = -1;
            for (int m = 0; m < APP_PRESET_PARAMS; m++) {
                in_preset = app_preset_params[m] == (app_param_id_t)j ? m : in_preset;
            }
            const double want = in_preset >= 0 ? (double)app_presets[k].value_si[in_preset]
                                               : (double)vd[0];
            assert_near(vc[0], want, 0.0);
        }
    }
    const app_config_t d = app_default_config();
    app_config_t c = d;
    assert_int_equal(app_config_preset(&c, APP_PRESET_N), -1);
    assert_memory_equal(&c, &d, sizeof c);
    /* the default configuration is the default preset's */
    app_config_t e = d;
    assert_int_equal(app_config_preset(&e, APP_PRESET_DEFAULT), 0);
    assert_memory_equal(&e, &d, sizeof e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_ranges),
        cmocka_unit_test(test_every_table_range),
        cmocka_unit_test(test_get_set_round_trip),
        cmocka_unit_test(test_presets),
    };
    return cmocka_run_group_tests_name("app_config", tests, NULL, NULL);
}
