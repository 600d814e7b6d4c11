/*
 * test_nvstore.c - the parameters in NVM (firmware/app/nvstore.h) on the in-memory HAL:
 * a save and its load give the same parameters; a power cut at every unit (every byte
 * programmed, every sector erase) of a parameter save, both programming orders, loads
 * either the previous set or the new one, never a mix; a version 1 record (calibration
 * only) migrates; an extension of a newer version or corrupt is refused, never read;
 * entries with an unknown DID, a read-only DID, a wrong length or an out-of-range value
 * are refused and counted, that parameter at its default; a calibration save and a
 * calibration erase keep the stored parameters; the DTC status bytes.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app_uds.h"
#include "calstore.h"
#include "fake_hal.h"
#include "nvstore.h"
#include "test_util.h"

static hal_t hal;

static int setup(void **state)
{
    (void)state;
    fake_hal_reset(&hal);
    return 0;
}

/* the encoded parameters of *c (what the record stores): two configurations carry the
 * same parameters when these bytes are equal */
static size_t enc(const app_config_t *c, uint8_t *buf)
{
    const size_t n = nvstore_params_encode(c, buf, CALSTORE_PARAMS_MAX);
    assert_true(n > 0u);
    return n;
}

static int same_params(const app_config_t *x, const app_config_t *y)
{
    uint8_t a[CALSTORE_PARAMS_MAX], b[CALSTORE_PARAMS_MAX];
    const size_t na = enc(x, a), nb = enc(y, b);
    return na == nb && memcmp(a, b, na) == 0;
}

/* a configuration with parameters of every type away from their defaults */
static app_config_t set_a(void)
{
    app_config_t c = app_default_config();
    c.level_s = 30u;
    c.gnss_latency_s = 0.08f;
    c.odo_lever_b_m[0] = 1.25f;
    c.gyro_arw_rad_rts = 2.0e-4f;
    return c;
}

static app_config_t set_b(void)
{
    app_config_t c = app_default_config();
    c.level_s = 20u;
    c.gnss_latency_s = 0.12f;
    c.odo_lever_b_m[1] = -0.5f;
    c.accel_bias_mps2 = 0.05f;
    return c;
}

static const cal_record_t cal_x = {0.01f, 0.005f, 1200.0f, CAL_SRC_KNOWN_POSITION};
static const cal_record_t cal_none = {0.0f, 0.0f, 0.0f, CAL_SRC_NONE};

/* field by field (the struct has padding) */
static void expect_cal(const cal_record_t *got, const cal_record_t *want)
{
    assert_memory_equal(&got->dh_rad, &want->dh_rad, sizeof got->dh_rad);
    assert_memory_equal(&got->odo_scale_err, &want->odo_scale_err, sizeof got->odo_scale_err);
    assert_memory_equal(&got->base_m, &want->base_m, sizeof got->base_m);
    assert_int_equal(got->source, want->source);
}

/* every UDS-writable parameter fits the record, with room for more */
static void test_entries_fit(void **state)
{
    (void)state;
    const app_config_t d = app_default_config();
    uint8_t buf[CALSTORE_PARAMS_MAX];
    const size_t n = enc(&d, buf);
    size_t writable = 0u;
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        writable += app_params[k].uds_read_only ? 0u : 1u;
    }
    print_message("parameter entries: %u parameters, %u bytes of %u\n", (unsigned)writable,
                  (unsigned)n, (unsigned)CALSTORE_PARAMS_MAX);
    assert_true(n + 64u <= CALSTORE_PARAMS_MAX);
    assert_int_equal(nvstore_params_encode(&d, buf, n - 1u), 0u); /* too small: nothing */
}

/* GIVEN a save of set A with a calibration WHEN loaded THEN set A, every entry applied,
 * source NVM, version 2, and the calibration too */
static void test_round_trip(void **state)
{
    (void)state;
    calstore_t cs = {0u, -1};
    const app_config_t a = set_a(), d = app_default_config();
    assert_false(same_params(&a, &d));
    assert_int_equal(nvstore_save(&hal, &cs, &a, &cal_x), 0);
    app_config_t got;
    nvstore_status_t st;
    assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_OK);
    assert_true(same_params(&got, &a));
    assert_int_equal(st.source, NVSTORE_SRC_NVM);
    assert_int_equal(st.version, 2);
    assert_int_equal(st.refused, 0);
    assert_int_equal(st.seq, 1);
    size_t writable = 0u;
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        writable += app_params[k].uds_read_only ? 0u : 1u;
    }
    assert_int_equal(st.loaded, writable);
    cal_record_t rec;
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_OK);
    expect_cal(&rec, &cal_x);
}

/* the previous state of a cut save: set A saved (with no calibration) */
static void cut_one(const uint8_t *prior, uint32_t seq_old, uint32_t k, uint8_t torn,
                    unsigned *kept_old, unsigned *took_new)
{
    memcpy(hal.nvm, prior, FAKE_NVM_SIZE);
    fake_hal_nvm_cut_after(&hal, k, torn);
    calstore_t cs = {seq_old, 0};
    const app_config_t b = set_b();
    assert_int_equal(nvstore_save(&hal, &cs, &b, &cal_x), HAL_EIO);
    fake_hal_nvm_power_on(&hal);
    app_config_t got;
    nvstore_status_t st;
    assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_OK);
    assert_int_equal(st.refused, 0);
    cal_record_t rec;
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_OK);
    const app_config_t a = set_a();
    if (same_params(&got, &a)) {
        /* the previous record, whole: its (absent) calibration with it */
        assert_int_equal(st.seq, seq_old);
        expect_cal(&rec, &cal_none);
        (*kept_old)++;
    } else {
        assert_true(same_params(&got, &b)); /* else a mix: fails */
        assert_int_equal(st.seq, seq_old + 1u);
        expect_cal(&rec, &cal_x);
        (*took_new)++;
    }
}

/* GIVEN set A stored WHEN a save of set B (and a calibration) loses power at unit k, for
 * every k of the save, a cut byte programmed not at all, on half its bits or on all,
 * writes programmed forwards and backwards THEN the load gives set A with its calibration
 * or set B with its calibration, never anything else; and the next save works */
static void test_power_cut_every_byte(void **state)
{
    (void)state;
    static uint8_t prior[FAKE_NVM_SIZE];
    const app_config_t a = set_a(), b = set_b(), d = app_default_config();
    static const uint8_t torn[] = {0x00u, 0x0Fu, 0xF0u, 0xFFu};
    unsigned kept_old = 0u, took_new = 0u, cuts = 0u;
    uint32_t units = 0u;
    /* previous state: set A alone (the save's slot erased), or the defaults then set A
     * (the save erases the slot of the older record) */
    for (uint32_t n_prior = 1u; n_prior <= 2u; n_prior++) {
        fake_hal_reset(&hal);
        calstore_t cs = {0u, -1};
        if (n_prior == 2u) {
            assert_int_equal(nvstore_save(&hal, &cs, &d, &cal_none), 0);
        }
        assert_int_equal(nvstore_save(&hal, &cs, &a, &cal_none), 0);
        memcpy(prior, hal.nvm, sizeof prior);
        const uint32_t u0 = hal.nvm_units;
        assert_int_equal(nvstore_save(&hal, &cs, &b, &cal_x), 0);
        units = hal.nvm_units - u0;
        for (int backwards = 0; backwards < 2; backwards++) {
            hal.nvm_program_backwards = backwards;
            for (uint32_t k = 0; k < units; k++) {
                for (size_t t = 0; t < sizeof torn; t++) {
                    cut_one(prior, n_prior, k, torn[t], &kept_old, &took_new);
                    cuts++;
                }
            }
        }
        hal.nvm_program_backwards = 0;
        /* after a cut, the next save completes */
        memcpy(hal.nvm, prior, sizeof prior);
        fake_hal_nvm_cut_after(&hal, units / 2u, 0x00u);
        assert_int_equal(nvstore_save(&hal, &cs, &b, &cal_x), HAL_EIO);
        fake_hal_nvm_power_on(&hal);
        assert_int_equal(nvstore_save(&hal, &cs, &b, &cal_x), 0);
        app_config_t got;
        nvstore_status_t st;
        assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_OK);
        assert_true(same_params(&got, &b));
    }
    print_message("parameter save: %u NVM units (1 erase + bytes programmed); %u cuts: %u "
                  "loaded the previous set, %u the new set, 0 a mix\n",
                  (unsigned)units, cuts, kept_old, took_new);
    assert_int_equal(cuts, 2u * 2u * units * sizeof torn);
    assert_int_equal(kept_old + took_new, cuts);
    /* the new set only when the cut fell on the marker's last byte programmed with all its
     * zero bits (torn 0xFF): once per previous state and order */
    assert_int_equal(took_new, 2u * 2u);
}

/* GIVEN a version 1 record (the calibration only, as the previous firmware wrote it)
 * THEN the calibration loads, the parameters are the defaults, source Migrated, version
 * 1; a StoreParameters then writes a version 2 record with the calibration kept */
static void test_v1_migrates(void **state)
{
    (void)state;
    calstore_t cs = {0u, -1};
    assert_int_equal(calstore_save(&hal, &cs, &cal_x), 0);
    for (size_t i = CALSTORE_SLOT_BYTES; i < FAKE_NVM_SECTOR_SIZE; i++) {
        assert_int_equal(hal.nvm[i], 0xFF); /* exactly the 36-byte v1 slot */
    }
    app_config_t got;
    nvstore_status_t st;
    assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_OK);
    const app_config_t d = app_default_config();
    assert_true(same_params(&got, &d));
    assert_int_equal(st.source, NVSTORE_SRC_MIGRATED);
    assert_int_equal(st.version, 1);
    assert_int_equal(st.loaded, 0);
    cal_record_t rec;
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_OK);
    expect_cal(&rec, &cal_x);
    const app_config_t a = set_a();
    assert_int_equal(nvstore_save(&hal, &cs, &a, &rec), 0);
    assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_OK);
    assert_int_equal(st.source, NVSTORE_SRC_NVM);
    assert_true(same_params(&got, &a));
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_OK);
    expect_cal(&rec, &cal_x);
}

/* the extension of slot `slot` (its CRC recomputed after an edit at ext offset off) */
static void edit_ext(int slot, size_t off, uint8_t value, int fix_crc)
{
    uint8_t *e = &hal.nvm[(size_t)slot * FAKE_NVM_SECTOR_SIZE + CALSTORE_EXT_OFFSET];
    e[off] = value;
    if (fix_crc) {
        const size_t body = (size_t)e[6] | (size_t)e[7] << 8;
        const uint32_t crc = calstore_crc32(e, body);
        for (int i = 0; i < 4; i++) {
            e[body + (size_t)i] = (uint8_t)(crc >> (8 * i));
        }
    }
}

/* GIVEN an extension of version 3 (a newer firmware's) WHEN loaded THEN refused with its
 * version reported, the defaults, the calibration still loaded; GIVEN an extension with a
 * flipped bit THEN refused, the defaults */
static void test_newer_and_corrupt_refused(void **state)
{
    (void)state;
    calstore_t cs = {0u, -1};
    const app_config_t a = set_a(), d = app_default_config();
    assert_int_equal(nvstore_save(&hal, &cs, &a, &cal_x), 0);
    edit_ext(cs.slot, 4u, 3u, 1);
    app_config_t got;
    nvstore_status_t st;
    assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_OK);
    assert_int_equal(st.source, NVSTORE_SRC_REFUSED);
    assert_int_equal(st.version, 3);
    assert_true(same_params(&got, &d));
    cal_record_t rec;
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_OK);
    expect_cal(&rec, &cal_x);

    fake_hal_reset(&hal);
    cs.seq = 0u;
    cs.slot = -1;
    assert_int_equal(nvstore_save(&hal, &cs, &a, &cal_x), 0);
    fake_hal_nvm_corrupt(&hal, (size_t)cs.slot * FAKE_NVM_SECTOR_SIZE + CALSTORE_EXT_OFFSET +
                                   CALSTORE_EXT_HEAD + 5u, 0x10u);
    assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_OK);
    assert_int_equal(st.source, NVSTORE_SRC_REFUSED);
    assert_true(same_params(&got, &d));
    assert_int_equal(st.loaded, 0);
}

/* GIVEN entries: level_s 30 (good), an unknown DID, a read-only DID (the UDS request ID),
 * level_s with a wrong length, gnss_latency_s out of range, then a truncated entry WHEN
 * loaded THEN level_s 30, five refused, the rest at the defaults */
static void test_bad_entries_refused(void **state)
{
    (void)state;
    const app_config_t d = app_default_config();
    const float big = 1.0e6f;
    uint32_t u;
    memcpy(&u, &big, sizeof u);
    const uint16_t did_level = app_params[APP_PARAM_LEVEL_S].did;
    const uint16_t did_lat = app_params[APP_PARAM_GNSS_LATENCY_S].did;
    const uint16_t did_req = app_params[APP_PARAM_UDS_REQUEST_ID].did;
    const uint8_t blob[] = {
        (uint8_t)(did_level >> 8), (uint8_t)did_level, 2u, 0u, 30u,
        0x7Fu, 0xEEu, 2u, 0u, 1u,
        (uint8_t)(did_req >> 8), (uint8_t)did_req, 2u, 0x07u, 0x11u,
        (uint8_t)(did_level >> 8), (uint8_t)did_level, 1u, 30u,
        (uint8_t)(did_lat >> 8), (uint8_t)did_lat, 4u, (uint8_t)(u >> 24), (uint8_t)(u >> 16),
        (uint8_t)(u >> 8), (uint8_t)u,
        (uint8_t)(did_lat >> 8), (uint8_t)did_lat, 4u, 0x3Du,
    };
    assert_true(app_params[APP_PARAM_UDS_REQUEST_ID].uds_read_only);
    static calstore_ext_t ext;
    memset(&ext, 0, sizeof ext);
    memset(ext.dtc, 0xFF, sizeof ext.dtc);
    memcpy(ext.params, blob, sizeof blob);
    ext.params_len = (uint16_t)sizeof blob;
    calstore_t cs = {0u, -1};
    assert_int_equal(calstore_save_ext(&hal, &cs, &cal_none, &ext), 0);
    app_config_t got;
    nvstore_status_t st;
    assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_OK);
    assert_int_equal(st.source, NVSTORE_SRC_NVM);
    assert_int_equal(st.loaded, 1);
    assert_int_equal(st.refused, 5);
    assert_int_equal(got.level_s, 30);
    app_config_t want = d;
    want.level_s = 30u;
    assert_true(same_params(&got, &want));
    assert_int_equal(got.uds_request_id, d.uds_request_id);
}

/* A set valid as a whole loads back whatever its entries' order (the IMU rate's entry,
 * 20 Hz, comes before the output rates', 10 Hz, and breaks "an output rate at most the
 * IMU rate" against their defaults halfway through: it was refused and the ECU ran at
 * 100 Hz); a set that breaks the rule as a whole (the IMU rate alone) is refused whole:
 * the defaults, its one entry counted refused. */
static void test_low_imu_rate_loads_back(void **state)
{
    (void)state;
    calstore_t cs = {0u, -1};
    app_config_t a = app_default_config();
    a.nav_rate_hz = 10u;
    a.status_rate_hz = 10u;
    a.dyn_rate_hz = 10u;
    a.imu_rate_hz = 20u;
    assert_true(app_config_valid(&a));
    assert_true(app_params[APP_PARAM_IMU_RATE_HZ].did < app_params[APP_PARAM_NAV_RATE_HZ].did);
    assert_int_equal(nvstore_save(&hal, &cs, &a, &cal_x), 0);
    app_config_t got;
    nvstore_status_t st;
    assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_OK);
    assert_int_equal(st.refused, 0);
    assert_true(same_params(&got, &a));

    const app_config_t d = app_default_config();
    const uint16_t did = app_params[APP_PARAM_IMU_RATE_HZ].did;
    const uint8_t alone[] = {(uint8_t)(did >> 8), (uint8_t)did, 2u, 0u, 20u};
    app_config_t c = d;
    nvstore_status_t st2;
    memset(&st2, 0, sizeof st2);
    nvstore_params_decode(&c, alone, sizeof alone, &st2);
    assert_int_equal(st2.refused, 1);
    assert_int_equal(st2.loaded, 0);
    assert_true(same_params(&c, &d));
    assert_true(app_config_valid(&c));
}

/* the stored entries in (n bytes) but those of DID did, into out: their length */
static size_t drop_did(const uint8_t *in, size_t n, uint16_t did, uint8_t *out)
{
    size_t m = 0u;
    for (size_t k = 0u; k < n; k += NVSTORE_ENTRY_HEAD + in[k + 2u]) {
        if (((uint16_t)(in[k] << 8) | in[k + 1u]) != did) {
            memcpy(&out[m], &in[k], NVSTORE_ENTRY_HEAD + in[k + 2u]);
            m += NVSTORE_ENTRY_HEAD + in[k + 2u];
        }
    }
    assert_true(m < n);
    return m;
}

/* A record of the firmware before the forward accelerometer's own instability (DID 0x0239):
 * GIVEN an ECU configured for a navigation-grade IMU (the accelerometers' 0.0102 mg, the
 * automotive preset's default 2.04 mg) WHEN its record has no 0x0239 THEN the forward axis
 * takes the stored accelerometers' figure (B = the field / sqrt(2 / 300 s), to the float's
 * 1e-5), not the default; with 0x0239 stored its own value; a record with neither keeps
 * the default. */
static void test_forward_instability_of_an_older_record(void **state)
{
    (void)state;
    app_config_t nav = app_default_config();
    const double b_mps2 = 0.0101972 * 9.80665e-3;
    nav.accel_bias_rw_mps2_rts = (nav_real_t)(b_mps2 * sqrt(2.0 / 300.0));
    nav.accel_fwd_instability_mps2 = (nav_real_t)(3.0 * b_mps2);
    const uint16_t fwd = app_params[APP_PARAM_ACCEL_FWD_INSTABILITY_MPS2].did;
    uint8_t all[CALSTORE_PARAMS_MAX], buf[CALSTORE_PARAMS_MAX], neither[CALSTORE_PARAMS_MAX];
    const size_t n_all = enc(&nav, all);
    const size_t n_no_fwd = drop_did(all, n_all, fwd, buf);
    app_config_t got;
    nvstore_status_t st;
    memset(&st, 0, sizeof st);
    nvstore_params_decode(&got, buf, n_no_fwd, &st);
    assert_int_equal(st.refused, 0);
    print_message("older record: forward instability %.6g m/s^2 (the stored figure's B %.6g, "
                  "the default %.6g)\n", (double)got.accel_fwd_instability_mps2, b_mps2,
                  (double)app_default_config().accel_fwd_instability_mps2);
    assert_near((double)got.accel_fwd_instability_mps2, b_mps2, 1e-5 * b_mps2);
    memset(&st, 0, sizeof st);
    nvstore_params_decode(&got, all, n_all, &st);
    assert_near((double)got.accel_fwd_instability_mps2, 3.0 * b_mps2, 1e-6 * b_mps2);
    const size_t m =
        drop_did(buf, n_no_fwd, app_params[APP_PARAM_ACCEL_BIAS_RW_MPS2_RTS].did, neither);
    memset(&st, 0, sizeof st);
    nvstore_params_decode(&got, neither, m, &st);
    assert_near((double)got.accel_fwd_instability_mps2,
                (double)app_default_config().accel_fwd_instability_mps2, 0.0);
}

/* a calibration save (calib's policy) and a calibration erase keep the parameters; the
 * erase leaves no calibration; DTC status bytes round trip and survive both */
static void test_calibration_keeps_params_and_dtc(void **state)
{
    (void)state;
    calstore_t cs = {0u, -1};
    const app_config_t a = set_a();
    uint8_t dtc[CALSTORE_DTC_N];
    assert_int_equal(nvstore_dtc_status(&hal, dtc), 0);
    for (size_t i = 0; i < CALSTORE_DTC_N; i++) {
        assert_int_equal(dtc[i], 0xFF);
    }
    uint8_t put[CALSTORE_DTC_N];
    memset(put, 0xFF, sizeof put);
    put[3] = 0x09u;
    assert_int_equal(nvstore_put_dtc_status(&hal, &cs, put), 0); /* no record yet */
    /* StoreParameters keeps the stored DTC bytes */
    assert_int_equal(nvstore_save(&hal, &cs, &a, &cal_none), 0);
    assert_int_equal(nvstore_dtc_status(&hal, dtc), 0);
    assert_int_equal(dtc[3], 0x09);
    /* two bytes changed at once cost what one does: one record write, not one per byte */
    put[15] = 0x2Fu;
    put[0] = 0x50u;
    const uint32_t e0 = hal.nvm_units;
    assert_int_equal(nvstore_put_dtc_status(&hal, &cs, put), 0);
    const uint32_t two = hal.nvm_units - e0;
    put[1] = 0x50u;
    assert_int_equal(nvstore_put_dtc_status(&hal, &cs, put), 0);
    assert_int_equal(hal.nvm_units - e0 - two, two);
    put[1] = 0xFFu;
    assert_int_equal(nvstore_put_dtc_status(&hal, &cs, put), 0);
    assert_int_equal(nvstore_put_dtc_status(&hal, &cs, NULL), HAL_EINVAL);
    const uint32_t u0 = hal.nvm_units;
    assert_int_equal(nvstore_put_dtc_status(&hal, &cs, put), 0); /* unchanged: not written */
    assert_int_equal(hal.nvm_units, u0);
    assert_int_equal(calstore_save(&hal, &cs, &cal_x), 0);
    app_config_t got;
    nvstore_status_t st;
    assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_OK);
    assert_true(same_params(&got, &a));
    cal_record_t rec;
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_OK);
    expect_cal(&rec, &cal_x);
    assert_int_equal(nvstore_erase_calibration(&hal, &cs), 0);
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_OK);
    assert_int_equal(rec.source, CAL_SRC_NONE);
    assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_OK);
    assert_true(same_params(&got, &a));
    assert_int_equal(nvstore_dtc_status(&hal, dtc), 0);
    assert_int_equal(dtc[3], 0x09);
    assert_int_equal(dtc[15], 0x2F);
    assert_int_equal(dtc[0], 0x50);
    assert_int_equal(dtc[1], 0xFF);
    /* no stored parameters: the erase empties the store */
    fake_hal_reset(&hal);
    assert_int_equal(calstore_save(&hal, &cs, &cal_x), 0);
    assert_int_equal(nvstore_erase_calibration(&hal, &cs), 0);
    assert_int_equal(calstore_load(&hal, &cs, &rec), CALSTORE_EMPTY);
}

/* an interrupted first parameter save (only the extension written) is not taken for an
 * empty store: CORRUPT, the defaults */
static void test_interrupted_first_save(void **state)
{
    (void)state;
    calstore_t cs = {0u, -1};
    const app_config_t a = set_a();
    fake_hal_nvm_cut_after(&hal, 10u, 0x00u);
    assert_int_equal(nvstore_save(&hal, &cs, &a, &cal_x), HAL_EIO);
    fake_hal_nvm_power_on(&hal);
    app_config_t got;
    nvstore_status_t st;
    assert_int_equal(nvstore_layer(&hal, &got, &st), CALSTORE_CORRUPT);
    assert_int_equal(st.source, NVSTORE_SRC_DEFAULTS);
    const app_config_t d = app_default_config();
    assert_true(same_params(&got, &d));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_entries_fit, setup),
        cmocka_unit_test_setup(test_round_trip, setup),
        cmocka_unit_test_setup(test_power_cut_every_byte, setup),
        cmocka_unit_test_setup(test_v1_migrates, setup),
        cmocka_unit_test_setup(test_newer_and_corrupt_refused, setup),
        cmocka_unit_test_setup(test_bad_entries_refused, setup),
        cmocka_unit_test_setup(test_calibration_keeps_params_and_dtc, setup),
        cmocka_unit_test_setup(test_interrupted_first_save, setup),
        cmocka_unit_test_setup(test_low_imu_rate_loads_back, setup),
        cmocka_unit_test_setup(test_forward_instability_of_an_older_record, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
