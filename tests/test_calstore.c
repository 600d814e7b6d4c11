/*
 * test_calstore.c - the calibration store (firmware/app/calstore.c) against the in-memory
 * flash of tests/support/fake_hal.c: the documented byte layout and CRC, round trips,
 * slot alternation, a power loss at every byte of a save (once and twice in a row) and of
 * an erase, every byte of a slot corrupted, out-of-range payloads, seq wraparound, stale
 * caller state and HAL errors.
 *
 * Expectations are exact: a record read back must match the one saved bit for bit (floats
 * compared as bit patterns); "the previous record" means the newest committed one before
 * the interrupted operation, bit for bit, with its seq.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "calstore.h"
#include "fake_hal.h"

static hal_t hal;

/* bits of each torn (cut) byte that get programmed: none, halves, alternate, all */
static const uint8_t torn_masks[] = {0x00u, 0x0Fu, 0xF0u, 0x5Au, 0xFFu};
#define N_TORN (sizeof torn_masks / sizeof torn_masks[0])

/* units of one save: 1 sector erase + 28 record bytes + 4 commit bytes */
#define SAVE_UNITS 33u

/* ---- helpers ---- */

static uint32_t fbits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static float bitsf(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static cal_record_t mkrec(float dh_rad, float mu, float base_m, uint8_t source)
{
    cal_record_t r;
    memset(&r, 0, sizeof r);
    r.dh_rad = dh_rad;
    r.odo_scale_err = mu;
    r.base_m = base_m;
    r.source = source;
    return r;
}

static const cal_record_t rec_a = {0.01f, -0.005f, 1234.5f, CAL_SRC_GNSS};
static const cal_record_t rec_b = {-0.25f, 0.0125f, 87.25f, CAL_SRC_KNOWN_POSITION};
static const cal_record_t rec_c = {0.125f, -0.1875f, 20000.0f, CAL_SRC_FILTER};
static const cal_record_t rec_d = {-0.0625f, 0.03125f, 512.0f, CAL_SRC_GNSS};

static void assert_rec_equal(const cal_record_t *got, const cal_record_t *want)
{
    assert_int_equal(fbits(got->dh_rad), fbits(want->dh_rad));
    assert_int_equal(fbits(got->odo_scale_err), fbits(want->odo_scale_err));
    assert_int_equal(fbits(got->base_m), fbits(want->base_m));
    assert_int_equal(got->source, want->source);
}

static void assert_rec_default(const cal_record_t *got)
{
    const cal_record_t zero = mkrec(0.0f, 0.0f, 0.0f, CAL_SRC_NONE);
    assert_rec_equal(got, &zero);
}

static uint8_t *slot_ptr(unsigned k)
{
    return &hal.nvm[k * FAKE_NVM_SECTOR_SIZE];
}

static int slot_erased(unsigned k)
{
    for (unsigned i = 0; i < CALSTORE_SLOT_BYTES; i++) {
        if (slot_ptr(k)[i] != 0xFFu) {
            return 0;
        }
    }
    return 1;
}

/* load with a fresh calstore_t (a reboot) and check status, record, seq and slot */
static void expect_load(int status, const cal_record_t *want, uint32_t seq, int slot)
{
    calstore_t cs = {0xDEADBEEFu, 42};
    cal_record_t r = mkrec(9.0f, 9.0f, 9.0f, 9u);
    assert_int_equal(calstore_load(&hal, &cs, &r), status);
    if (status == CALSTORE_OK) {
        assert_rec_equal(&r, want);
        assert_int_equal(cs.seq, seq);
        assert_int_equal(cs.slot, slot);
    } else {
        assert_rec_default(&r);
        assert_int_equal(cs.seq, 0);
        assert_int_equal(cs.slot, -1);
    }
}

/* save through a freshly loaded calstore_t; returns the calstore_t after the save */
static calstore_t save_fresh(const cal_record_t *rec)
{
    calstore_t cs;
    cal_record_t r;
    (void)calstore_load(&hal, &cs, &r);
    assert_int_equal(calstore_save(&hal, &cs, rec), 0);
    return cs;
}

static void put_u32le(uint8_t *p, uint32_t v)
{
    for (unsigned i = 0; i < 4; i++) {
        p[i] = (uint8_t)(v >> (8u * i));
    }
}

/* A slot image built from calstore.h's layout table, independently of calstore.c
 * (only the CRC function is shared; test_crc32 and test_layout_golden pin it). */
static void build_slot(uint8_t img[CALSTORE_SLOT_BYTES], uint32_t seq, uint32_t dh_bits,
                       uint32_t mu_bits, uint32_t base_bits, uint8_t source)
{
    memset(img, 0xFF, CALSTORE_SLOT_BYTES);
    memcpy(img, "NCAL", 4);
    img[4] = 1u;
    img[5] = source;
    img[6] = 24u;
    img[7] = 0u;
    put_u32le(img + 8, seq);
    put_u32le(img + 12, dh_bits);
    put_u32le(img + 16, mu_bits);
    put_u32le(img + 20, base_bits);
    put_u32le(img + 24, calstore_crc32(img, 24));
    memcpy(img + 32, "DONE", 4);
}

static void build_rec_slot(uint8_t img[CALSTORE_SLOT_BYTES], uint32_t seq, const cal_record_t *r)
{
    build_slot(img, seq, fbits(r->dh_rad), fbits(r->odo_scale_err), fbits(r->base_m),
               r->source);
}

/* sector k := erased, then img at its start */
static void put_slot(unsigned k, const uint8_t img[CALSTORE_SLOT_BYTES])
{
    memset(slot_ptr(k), 0xFF, FAKE_NVM_SECTOR_SIZE);
    memcpy(slot_ptr(k), img, CALSTORE_SLOT_BYTES);
}

/* ---- the CRC and the byte layout ---- */

static void test_crc32(void **state)
{
    (void)state;
    assert_int_equal(calstore_crc32((const uint8_t *)"123456789", 9), 0xCBF43926u);
    assert_int_equal(calstore_crc32(NULL, 0), 0x00000000u);
    assert_int_equal(calstore_crc32((const uint8_t *)"a", 1), 0xE8B7BE43u);
}

/*
 * GIVEN an erased store WHEN rec_a is saved THEN slot 0 holds exactly the bytes of the
 * layout in calstore.h (CRC from zlib.crc32), everything else stays erased.
 */
static void test_layout_golden(void **state)
{
    (void)state;
    static const uint8_t golden[CALSTORE_SLOT_BYTES] = {
        0x4E, 0x43, 0x41, 0x4C, 0x01, 0x02, 0x18, 0x00, 0x01, 0x00, 0x00, 0x00, /* NCAL,v,src,len,seq */
        0x0A, 0xD7, 0x23, 0x3C, 0x0A, 0xD7, 0xA3, 0xBB, 0x00, 0x50, 0x9A, 0x44, /* 0.01 -0.005 1234.5 */
        0xDC, 0x0B, 0x63, 0x3D, 0xFF, 0xFF, 0xFF, 0xFF, 0x44, 0x4F, 0x4E, 0x45, /* CRC, gap, DONE */
    };
    fake_hal_reset(&hal);
    const calstore_t cs = save_fresh(&rec_a);
    assert_int_equal(cs.seq, 1);
    assert_int_equal(cs.slot, 0);
    assert_memory_equal(slot_ptr(0), golden, sizeof golden);
    for (size_t i = CALSTORE_SLOT_BYTES; i < FAKE_NVM_SIZE; i++) {
        assert_int_equal(hal.nvm[i], 0xFF);
    }
    uint8_t built[CALSTORE_SLOT_BYTES];
    build_rec_slot(built, 1u, &rec_a);
    assert_memory_equal(built, golden, sizeof golden);
}

/* the fake models flash, or the power-loss tests below would prove less */
static void test_fake_flash_semantics(void **state)
{
    (void)state;
    fake_hal_reset(&hal);
    assert_int_equal(hal_nvm_sector_size(&hal), FAKE_NVM_SECTOR_SIZE);
    assert_int_equal(hal_nvm_size(&hal) / hal_nvm_sector_size(&hal), 2);
    const uint8_t a = 0xF0u, b = 0x3Cu, c = 0x00u;
    assert_int_equal(hal_nvm_write(&hal, 5, &a, 1), 0);
    assert_int_equal(hal_nvm_write(&hal, 5, &b, 1), HAL_EIO); /* needs 0 -> 1 */
    assert_int_equal(hal.nvm[5], 0x30);                       /* old AND new */
    assert_int_equal(hal_nvm_write(&hal, 5, &c, 1), 0);       /* only clears: fine */
    assert_int_equal(hal_nvm_erase_sector(&hal, 2), HAL_EINVAL);
    hal.nvm[FAKE_NVM_SECTOR_SIZE] = 0x00u;
    assert_int_equal(hal_nvm_erase_sector(&hal, 0), 0);
    assert_int_equal(hal.nvm[5], 0xFF);
    assert_int_equal(hal.nvm[FAKE_NVM_SECTOR_SIZE], 0x00); /* the other sector is kept */
}

/* ---- normal operation ---- */

static void test_empty(void **state)
{
    (void)state;
    fake_hal_reset(&hal);
    expect_load(CALSTORE_EMPTY, NULL, 0, -1);
    for (size_t i = 0; i < FAKE_NVM_SIZE; i++) {
        assert_int_equal(hal.nvm[i], 0xFF); /* loading writes nothing */
    }
    assert_int_equal(hal.nvm_units, 0);
}

/* every record in range comes back bit for bit, including the range limits, -0, a
 * subnormal and the largest float */
static void test_round_trip(void **state)
{
    (void)state;
    const cal_record_t recs[] = {
        rec_a,
        rec_b,
        rec_c,
        mkrec(0.5f, 0.2f, 0.0f, CAL_SRC_KNOWN_POSITION),
        mkrec(-0.5f, -0.2f, 3.4028235e38f, CAL_SRC_FILTER),
        mkrec(-0.0f, bitsf(0x00000001u), -0.0f, CAL_SRC_GNSS),
        mkrec(1.0e-7f, -1.0e-30f, 1.0e-3f, CAL_SRC_GNSS),
    };
    fake_hal_reset(&hal);
    for (size_t k = 0; k < sizeof recs / sizeof recs[0]; k++) {
        const calstore_t cs = save_fresh(&recs[k]);
        expect_load(CALSTORE_OK, &recs[k], cs.seq, cs.slot);
    }
}

/*
 * GIVEN an erased store WHEN 6 records are saved THEN they go to slots 0, 1, 0, 1, ...
 * with seq 1..6, and the other slot still holds the record before (seq - 1).
 */
static void test_alternation(void **state)
{
    (void)state;
    const cal_record_t recs[] = {rec_a, rec_b, rec_c, rec_d, rec_a, rec_b};
    fake_hal_reset(&hal);
    calstore_t cs;
    cal_record_t r;
    assert_int_equal(calstore_load(&hal, &cs, &r), CALSTORE_EMPTY);
    for (uint32_t n = 0; n < 6; n++) {
        /* the same calstore_t across saves, as the application keeps it */
        assert_int_equal(calstore_save(&hal, &cs, &recs[n]), 0);
        assert_int_equal(cs.seq, n + 1u);
        assert_int_equal(cs.slot, (int)(n % 2u));
        expect_load(CALSTORE_OK, &recs[n], n + 1u, (int)(n % 2u));
        if (n > 0) {
            uint8_t want[CALSTORE_SLOT_BYTES];
            build_rec_slot(want, n, &recs[n - 1u]);
            assert_memory_equal(slot_ptr((n + 1u) % 2u), want, sizeof want);
        } else {
            assert_true(slot_erased(1));
        }
    }
}

static void test_erase(void **state)
{
    (void)state;
    fake_hal_reset(&hal);
    calstore_t cs = save_fresh(&rec_a);
    cs = save_fresh(&rec_b);
    cs = save_fresh(&rec_c);
    assert_int_equal(calstore_erase(&hal, &cs), 0);
    assert_int_equal(cs.seq, 0);
    assert_int_equal(cs.slot, -1);
    for (size_t i = 0; i < FAKE_NVM_SIZE; i++) {
        assert_int_equal(hal.nvm[i], 0xFF);
    }
    expect_load(CALSTORE_EMPTY, NULL, 0, -1);
    /* the next save starts again at seq 1 in slot 0 */
    assert_int_equal(calstore_save(&hal, &cs, &rec_d), 0);
    expect_load(CALSTORE_OK, &rec_d, 1, 0);

    /* the application's EraseCalibration (hal_nvm_erase of the whole region) too */
    assert_int_equal(hal_nvm_erase(&hal), 0);
    expect_load(CALSTORE_EMPTY, NULL, 0, -1);
    /* erasing an empty store is fine */
    assert_int_equal(calstore_erase(&hal, &cs), 0);
    expect_load(CALSTORE_EMPTY, NULL, 0, -1);
}

/* ---- power loss ---- */

typedef struct {
    uint32_t cuts;       /* interrupted saves */
    uint32_t kept_old;   /* the previous record (or nothing) loaded after the reboot */
    uint32_t took_new;   /* the new record loaded: its last marker byte was complete */
} cut_stats_t;

/*
 * GIVEN the store as in prior[] (newest: prior_newest with prior_seq, or none)
 * WHEN a save of rec_d loses power at unit k (k = 0: the erase; 1..28: record bytes;
 * 29..32: commit marker bytes; in address order, or backwards within each write if
 * hal.nvm_program_backwards), the cut byte programmed only on the bits of `torn`
 * THEN the save fails; after a reboot the load gives the previous record, bit for bit,
 * unless the new slot reads exactly as a complete commit (possible only when the cut hit
 * the last marker byte and `torn` happened to program all its zero bits): then the new
 * one. Never anything else. With no previous record: EMPTY if both slots read erased,
 * else CORRUPT, defaults either way.
 * AND a save after the reboot works and is loaded with the next seq.
 */
static void cut_one_save(const uint8_t *prior, const cal_record_t *prior_newest,
                         uint32_t prior_seq, uint32_t k, uint8_t torn, cut_stats_t *st)
{
    memcpy(hal.nvm, prior, FAKE_NVM_SIZE);
    fake_hal_nvm_power_on(&hal);
    calstore_t cs;
    cal_record_t r;
    (void)calstore_load(&hal, &cs, &r);
    const int target = cs.slot == 0 ? 1 : 0;
    const uint32_t new_seq = cs.seq + 1u;

    fake_hal_nvm_cut_after(&hal, k, torn);
    const calstore_t cs_before = cs;
    assert_true(calstore_save(&hal, &cs, &rec_d) < 0);
    assert_int_equal(cs.seq, cs_before.seq); /* unchanged on error */
    assert_int_equal(cs.slot, cs_before.slot);
    assert_int_equal(hal.nvm_power_off, 1);
    fake_hal_nvm_power_on(&hal); /* reboot */
    st->cuts++;

    uint8_t full[CALSTORE_SLOT_BYTES];
    build_rec_slot(full, new_seq, &rec_d);
    const int committed = memcmp(slot_ptr((unsigned)target), full, sizeof full) == 0;
    uint32_t next_seq;
    if (committed) {
        assert_int_equal(k, SAVE_UNITS - 1u);
        expect_load(CALSTORE_OK, &rec_d, new_seq, target);
        st->took_new++;
        next_seq = new_seq + 1u;
    } else if (prior_newest != NULL) {
        expect_load(CALSTORE_OK, prior_newest, prior_seq, 1 - target);
        st->kept_old++;
        next_seq = prior_seq + 1u;
    } else {
        expect_load(slot_erased(0) && slot_erased(1) ? CALSTORE_EMPTY : CALSTORE_CORRUPT,
                    NULL, 0, -1);
        st->kept_old++;
        next_seq = 1u;
    }
    /* a save after the torn one */
    const calstore_t after = save_fresh(&rec_b);
    assert_int_equal(after.seq, next_seq);
    expect_load(CALSTORE_OK, &rec_b, next_seq, after.slot);
}

static void test_power_loss_every_byte(void **state)
{
    (void)state;
    static uint8_t prior[FAKE_NVM_SIZE];
    const cal_record_t *history[] = {&rec_a, &rec_b, &rec_c};
    cut_stats_t st = {0, 0, 0};

    /* previous state: no record, one (slot 1 erased), two (target holds the older one:
     * the erase destroys a valid record), three (the newest in slot 0, target slot 1) */
    for (uint32_t n_prior = 0; n_prior <= 3; n_prior++) {
        fake_hal_reset(&hal);
        for (uint32_t j = 0; j < n_prior; j++) {
            (void)save_fresh(history[j]);
        }
        memcpy(prior, hal.nvm, sizeof prior);
        const cal_record_t *newest = n_prior > 0 ? history[n_prior - 1u] : NULL;

        /* a save costs SAVE_UNITS units, the reads in it none */
        const uint32_t u0 = hal.nvm_units;
        (void)save_fresh(&rec_d);
        assert_int_equal(hal.nvm_units - u0, SAVE_UNITS);

        for (int backwards = 0; backwards < 2; backwards++) {
            hal.nvm_program_backwards = backwards;
            for (uint32_t k = 0; k < SAVE_UNITS; k++) {
                for (size_t t = 0; t < N_TORN; t++) {
                    cut_one_save(prior, newest, n_prior, k, torn_masks[t], &st);
                }
            }
        }
        hal.nvm_program_backwards = 0;
        /* a cut armed after the last unit is never reached: the save completes */
        memcpy(hal.nvm, prior, sizeof prior);
        fake_hal_nvm_cut_after(&hal, SAVE_UNITS, 0x00u);
        const calstore_t cs = save_fresh(&rec_d);
        assert_int_equal(hal.nvm_power_off, 0);
        expect_load(CALSTORE_OK, &rec_d, n_prior + 1u, cs.slot);
        fake_hal_nvm_power_on(&hal);
    }
    assert_int_equal(st.cuts, 4u * 2u * SAVE_UNITS * N_TORN);
    /* the new record only when the cut hit the last marker byte programmed (forwards 'E'
     * = 0x45, backwards 'D' = 0x44) with all of its zero bits programmed: of the torn
     * masks only 0xFF does that, once per previous state and order */
    print_message("power loss: %u interrupted saves, %u loaded the previous record, %u the "
                  "new one (cut on its complete last marker byte)\n",
                  (unsigned)st.cuts, (unsigned)st.kept_old, (unsigned)st.took_new);
    assert_int_equal(st.took_new, 4u * 2u);
}

/*
 * GIVEN two records (newest rec_b, seq 2) WHEN a save loses power at unit k1, and after
 * the reboot the next save loses power at unit k2 THEN rec_b is still loaded; a third
 * save then works.
 */
static void test_power_loss_twice(void **state)
{
    (void)state;
    static uint8_t prior[FAKE_NVM_SIZE];
    fake_hal_reset(&hal);
    (void)save_fresh(&rec_a);
    (void)save_fresh(&rec_b);
    memcpy(prior, hal.nvm, sizeof prior);
    for (uint32_t k1 = 0; k1 < SAVE_UNITS; k1++) {
        for (uint32_t k2 = 0; k2 < SAVE_UNITS; k2++) {
            memcpy(hal.nvm, prior, sizeof prior);
            calstore_t cs;
            cal_record_t r;
            for (int round = 0; round < 2; round++) {
                assert_int_equal(calstore_load(&hal, &cs, &r), CALSTORE_OK);
                fake_hal_nvm_cut_after(&hal, round == 0 ? k1 : k2, 0x00u);
                assert_true(calstore_save(&hal, &cs, round == 0 ? &rec_c : &rec_d) < 0);
                fake_hal_nvm_power_on(&hal);
            }
            expect_load(CALSTORE_OK, &rec_b, 2, 1);
            const calstore_t after = save_fresh(&rec_a);
            assert_int_equal(after.seq, 3);
            expect_load(CALSTORE_OK, &rec_a, 3, 0);
        }
    }
}

/*
 * GIVEN rec_a (seq 1, slot 0) and rec_b (seq 2, slot 1) WHEN calstore_erase loses power
 * THEN on the first erase (slot 0, the older): rec_b is still there; on the second (slot 1,
 * half erased): no valid record, not erased -> CORRUPT; not cut: EMPTY.
 */
static void test_power_loss_erase(void **state)
{
    (void)state;
    static uint8_t prior[FAKE_NVM_SIZE];
    fake_hal_reset(&hal);
    (void)save_fresh(&rec_a);
    (void)save_fresh(&rec_b);
    memcpy(prior, hal.nvm, sizeof prior);
    static const int want[] = {CALSTORE_OK, CALSTORE_CORRUPT, CALSTORE_EMPTY};
    for (uint32_t k = 0; k < 3; k++) {
        memcpy(hal.nvm, prior, sizeof prior);
        calstore_t cs = {2u, 1};
        fake_hal_nvm_cut_after(&hal, k, 0x00u);
        assert_int_equal(calstore_erase(&hal, &cs), k < 2 ? HAL_EIO : 0);
        fake_hal_nvm_power_on(&hal);
        expect_load(want[k], &rec_b, 2, 1);
        (void)save_fresh(&rec_c);
        cal_record_t r;
        assert_int_equal(calstore_load(&hal, &cs, &r), CALSTORE_OK);
        assert_rec_equal(&r, &rec_c);
    }
}

/* ---- corruption ---- */

static const uint8_t flips[] = {0x01u, 0x02u, 0x04u, 0x08u, 0x10u, 0x20u, 0x40u, 0x80u, 0xFFu};

/*
 * GIVEN rec_a (seq 1, slot 0) and rec_b (seq 2, slot 1) WHEN any bit or all bits of any
 * byte of one slot's 36 bytes are flipped THEN load gives the other slot's record.
 */
static void test_corrupt_one_slot_of_two(void **state)
{
    (void)state;
    static uint8_t prior[FAKE_NVM_SIZE];
    static const cal_record_t *const recs[2] = {&rec_a, &rec_b};
    fake_hal_reset(&hal);
    (void)save_fresh(&rec_a);
    (void)save_fresh(&rec_b);
    memcpy(prior, hal.nvm, sizeof prior);
    for (unsigned s = 0; s < 2; s++) {
        for (unsigned i = 0; i < CALSTORE_SLOT_BYTES; i++) {
            for (size_t f = 0; f < sizeof flips; f++) {
                memcpy(hal.nvm, prior, sizeof prior);
                fake_hal_nvm_corrupt(&hal, s * FAKE_NVM_SECTOR_SIZE + i, flips[f]);
                const unsigned other = 1u - s;
                expect_load(CALSTORE_OK, recs[other], other + 1u, (int)other);
            }
        }
    }
}

/*
 * GIVEN one record, in slot 0 (slot 1 erased) or in slot 1 (slot 0 erased) WHEN any
 * byte of it is corrupted THEN CALSTORE_CORRUPT and the defaults, never its contents.
 */
static void test_corrupt_only_record(void **state)
{
    (void)state;
    static uint8_t prior[FAKE_NVM_SIZE];
    for (unsigned s = 0; s < 2; s++) {
        fake_hal_reset(&hal);
        (void)save_fresh(&rec_a);
        if (s == 1) {
            (void)save_fresh(&rec_b);
            assert_int_equal(hal_nvm_erase_sector(&hal, 0), 0);
        }
        memcpy(prior, hal.nvm, sizeof prior);
        expect_load(CALSTORE_OK, s == 0 ? &rec_a : &rec_b, s + 1u, (int)s);
        for (unsigned i = 0; i < CALSTORE_SLOT_BYTES; i++) {
            for (size_t f = 0; f < sizeof flips; f++) {
                memcpy(hal.nvm, prior, sizeof prior);
                fake_hal_nvm_corrupt(&hal, s * FAKE_NVM_SECTOR_SIZE + i, flips[f]);
                expect_load(CALSTORE_CORRUPT, NULL, 0, -1);
            }
        }
    }
}

static void test_corrupt_both(void **state)
{
    (void)state;
    fake_hal_reset(&hal);
    (void)save_fresh(&rec_a);
    (void)save_fresh(&rec_b);
    fake_hal_nvm_corrupt(&hal, 10, 0x01u);                        /* seq of slot 0 */
    fake_hal_nvm_corrupt(&hal, FAKE_NVM_SECTOR_SIZE + 14, 0x80u); /* dh of slot 1 */
    expect_load(CALSTORE_CORRUPT, NULL, 0, -1);
    /* all zeros (a programmed-over region), and a stray byte in an erased store */
    memset(hal.nvm, 0x00, FAKE_NVM_SIZE);
    expect_load(CALSTORE_CORRUPT, NULL, 0, -1);
    memset(hal.nvm, 0xFF, FAKE_NVM_SIZE);
    hal.nvm[FAKE_NVM_SECTOR_SIZE + CALSTORE_SLOT_BYTES - 1u] = 0xFEu;
    expect_load(CALSTORE_CORRUPT, NULL, 0, -1);
    /* bytes past a slot's 36 are not part of the store */
    memset(hal.nvm, 0xFF, FAKE_NVM_SIZE);
    hal.nvm[CALSTORE_SLOT_BYTES] = 0x00u;
    expect_load(CALSTORE_EMPTY, NULL, 0, -1);
    /* a save repairs the store */
    (void)save_fresh(&rec_c);
    expect_load(CALSTORE_OK, &rec_c, 1, 0);
}

/* ---- payload range ---- */

#define F_0P5 0x3F000000u  /* 0.5f */
#define F_0P2 0x3E4CCCCDu  /* 0.2f */
#define F_SIGN 0x80000000u

/*
 * GIVEN a slot with a correct CRC and commit marker but a payload outside the range of
 * calstore.h (or a wrong header field) WHEN loaded THEN it is rejected: CORRUPT alone, the
 * other slot's older record beside it; save refuses the same payload with HAL_EINVAL and
 * writes nothing. The limits themselves (|dh| = 0.5f, |mu| = 0.2f, base 0) are accepted.
 */
static void test_payload_rejected(void **state)
{
    (void)state;
    const uint32_t ok_dh = fbits(0.01f), ok_mu = fbits(-0.005f), ok_base = fbits(100.0f);
    static const uint32_t bad_float[] = {
        0x7FC00000u, 0xFFC00000u, 0x7F800001u, /* quiet NaN, negative NaN, signalling NaN */
        0x7F800000u, 0xFF800000u,              /* +inf, -inf */
    };
    struct {
        uint32_t dh, mu, base;
        uint8_t src;
    } bad[32];
    size_t n = 0;
    for (size_t i = 0; i < sizeof bad_float / sizeof bad_float[0]; i++) {
        bad[n].dh = bad_float[i], bad[n].mu = ok_mu, bad[n].base = ok_base, bad[n++].src = 1;
        bad[n].dh = ok_dh, bad[n].mu = bad_float[i], bad[n].base = ok_base, bad[n++].src = 1;
        bad[n].dh = ok_dh, bad[n].mu = ok_mu, bad[n].base = bad_float[i], bad[n++].src = 1;
    }
    /* one ulp past each limit, both signs; a negative base; sources 0 and 4 */
    bad[n].dh = F_0P5 + 1u, bad[n].mu = ok_mu, bad[n].base = ok_base, bad[n++].src = 2;
    bad[n].dh = (F_0P5 + 1u) | F_SIGN, bad[n].mu = ok_mu, bad[n].base = ok_base, bad[n++].src = 2;
    bad[n].dh = ok_dh, bad[n].mu = F_0P2 + 1u, bad[n].base = ok_base, bad[n++].src = 3;
    bad[n].dh = ok_dh, bad[n].mu = (F_0P2 + 1u) | F_SIGN, bad[n].base = ok_base, bad[n++].src = 3;
    bad[n].dh = ok_dh, bad[n].mu = ok_mu, bad[n].base = fbits(-1.0f), bad[n++].src = 1;
    bad[n].dh = ok_dh, bad[n].mu = ok_mu, bad[n].base = ok_base, bad[n++].src = 0;
    bad[n].dh = ok_dh, bad[n].mu = ok_mu, bad[n].base = ok_base, bad[n++].src = 4;
    assert_true(n <= sizeof bad / sizeof bad[0]);

    static uint8_t nvm_before[FAKE_NVM_SIZE];
    for (size_t i = 0; i < n; i++) {
        uint8_t img[CALSTORE_SLOT_BYTES], older[CALSTORE_SLOT_BYTES];
        fake_hal_reset(&hal);
        build_slot(img, 7u, bad[i].dh, bad[i].mu, bad[i].base, bad[i].src);
        put_slot(1, img);
        expect_load(CALSTORE_CORRUPT, NULL, 0, -1);
        build_rec_slot(older, 6u, &rec_a);
        put_slot(0, older);
        expect_load(CALSTORE_OK, &rec_a, 6, 0);

        const cal_record_t r = mkrec(bitsf(bad[i].dh), bitsf(bad[i].mu), bitsf(bad[i].base),
                                     bad[i].src);
        calstore_t cs = {6u, 0};
        memcpy(nvm_before, hal.nvm, sizeof nvm_before);
        const uint32_t u0 = hal.nvm_units;
        assert_int_equal(calstore_save(&hal, &cs, &r), HAL_EINVAL);
        assert_memory_equal(hal.nvm, nvm_before, sizeof nvm_before);
        assert_int_equal(hal.nvm_units, u0);
        assert_int_equal(cs.seq, 6);
    }

    /* header fields: version 2, body length 23, magic, a programmed gap byte, each with a
     * CRC recomputed so that only the field itself is wrong */
    for (int field = 0; field < 4; field++) {
        uint8_t img[CALSTORE_SLOT_BYTES];
        fake_hal_reset(&hal);
        build_rec_slot(img, 3u, &rec_a);
        switch (field) {
        case 0: img[4] = 2u; break;
        case 1: img[6] = 23u; break;
        case 2: img[0] = 'n'; break;
        default: img[29] = 0x00u; break;
        }
        put_u32le(img + 24, calstore_crc32(img, 24));
        put_slot(0, img);
        expect_load(CALSTORE_CORRUPT, NULL, 0, -1);
    }

    /* the limits are in range */
    const cal_record_t limits[] = {
        mkrec(0.5f, 0.2f, 0.0f, CAL_SRC_KNOWN_POSITION),
        mkrec(-0.5f, -0.2f, 0.0f, CAL_SRC_FILTER),
    };
    for (size_t i = 0; i < 2; i++) {
        uint8_t img[CALSTORE_SLOT_BYTES];
        fake_hal_reset(&hal);
        build_rec_slot(img, 5u, &limits[i]);
        put_slot(1, img);
        expect_load(CALSTORE_OK, &limits[i], 5, 1);
    }
}

/* ---- seq ---- */

/*
 * seq compares modulo 2^32: 0 is after 0xFFFFFFFF, whichever slot holds it; a save after
 * 0xFFFFFFFF writes 0, the next one 1.
 */
static void test_seq_wraparound(void **state)
{
    (void)state;
    static const uint32_t pairs[][2] = {
        {0xFFFFFFFFu, 0x00000000u},
        {0xFFFFFFFEu, 0xFFFFFFFFu},
        {0xFFFFFFF0u, 0x00000005u},
        {0x7FFFFFFFu, 0x80000000u},
        {5u, 6u},
    };
    for (size_t i = 0; i < sizeof pairs / sizeof pairs[0]; i++) {
        for (unsigned older_slot = 0; older_slot < 2; older_slot++) {
            uint8_t img[CALSTORE_SLOT_BYTES];
            fake_hal_reset(&hal);
            build_rec_slot(img, pairs[i][0], &rec_a);
            put_slot(older_slot, img);
            build_rec_slot(img, pairs[i][1], &rec_b);
            put_slot(1u - older_slot, img);
            expect_load(CALSTORE_OK, &rec_b, pairs[i][1], (int)(1u - older_slot));
        }
    }

    uint8_t img[CALSTORE_SLOT_BYTES];
    fake_hal_reset(&hal);
    build_rec_slot(img, 0xFFFFFFFFu, &rec_a);
    put_slot(0, img);
    calstore_t cs = save_fresh(&rec_b);
    assert_int_equal(cs.seq, 0);
    assert_int_equal(cs.slot, 1);
    expect_load(CALSTORE_OK, &rec_b, 0, 1);
    cs = save_fresh(&rec_c);
    assert_int_equal(cs.seq, 1);
    assert_int_equal(cs.slot, 0);
    expect_load(CALSTORE_OK, &rec_c, 1, 0);

    /* equal seqs (never written by calstore) or 2^31 apart: slot 0 wins, deterministically */
    fake_hal_reset(&hal);
    build_rec_slot(img, 9u, &rec_a);
    put_slot(0, img);
    build_rec_slot(img, 9u, &rec_b);
    put_slot(1, img);
    expect_load(CALSTORE_OK, &rec_a, 9, 0);
    build_rec_slot(img, 9u + 0x80000000u, &rec_b);
    put_slot(1, img);
    expect_load(CALSTORE_OK, &rec_a, 9, 0);
}

/* ---- caller state and HAL errors ---- */

/*
 * GIVEN rec_a (seq 1, slot 0), rec_b (seq 2, slot 1) WHEN saving with a calstore_t that
 * does not match (never loaded, or pointing at the wrong slot) THEN the newest record is
 * not overwritten: the save goes to slot 0 with seq 3.
 */
static void test_save_with_stale_state(void **state)
{
    (void)state;
    static const calstore_t stale[] = {{0u, -1}, {1u, 0}, {2u, 0}, {77u, 1}};
    static uint8_t prior[FAKE_NVM_SIZE];
    fake_hal_reset(&hal);
    (void)save_fresh(&rec_a);
    (void)save_fresh(&rec_b);
    memcpy(prior, hal.nvm, sizeof prior);
    for (size_t i = 0; i < sizeof stale / sizeof stale[0]; i++) {
        memcpy(hal.nvm, prior, sizeof prior);
        calstore_t cs = stale[i];
        assert_int_equal(calstore_save(&hal, &cs, &rec_c), 0);
        assert_int_equal(cs.seq, 3);
        assert_int_equal(cs.slot, 0);
        uint8_t want[CALSTORE_SLOT_BYTES];
        build_rec_slot(want, 2u, &rec_b);
        assert_memory_equal(slot_ptr(1), want, sizeof want);
        expect_load(CALSTORE_OK, &rec_c, 3, 0);
    }
    /* an erase behind the store's back (hal_nvm_erase): the next save starts over */
    calstore_t cs = {3u, 0};
    assert_int_equal(hal_nvm_erase(&hal), 0);
    assert_int_equal(calstore_save(&hal, &cs, &rec_d), 0);
    assert_int_equal(cs.seq, 4);
    assert_int_equal(cs.slot, 0);
    expect_load(CALSTORE_OK, &rec_d, 4, 0);
}

static void test_hal_errors(void **state)
{
    (void)state;
    fake_hal_reset(&hal);
    (void)save_fresh(&rec_a);
    calstore_t cs = {1u, 0};
    cal_record_t r = rec_b;

    hal.nvm_fail = 1;
    assert_int_equal(calstore_load(&hal, &cs, &r), HAL_EIO);
    assert_rec_default(&r); /* defaults even on an error */
    assert_int_equal(cs.slot, -1);
    cs.seq = 1u;
    cs.slot = 0;
    assert_int_equal(calstore_save(&hal, &cs, &rec_b), HAL_EIO);
    assert_int_equal(cs.seq, 1);
    assert_int_equal(cs.slot, 0);
    assert_int_equal(calstore_erase(&hal, &cs), HAL_EIO);
    assert_int_equal(cs.slot, 0);
    hal.nvm_fail = 0;
    expect_load(CALSTORE_OK, &rec_a, 1, 0);

    assert_int_equal(calstore_load(NULL, &cs, &r), HAL_EINVAL);
    assert_int_equal(calstore_load(&hal, NULL, &r), HAL_EINVAL);
    assert_int_equal(calstore_load(&hal, &cs, NULL), HAL_EINVAL);
    assert_int_equal(calstore_save(NULL, &cs, &rec_b), HAL_EINVAL);
    assert_int_equal(calstore_save(&hal, NULL, &rec_b), HAL_EINVAL);
    assert_int_equal(calstore_save(&hal, &cs, NULL), HAL_EINVAL);
    assert_int_equal(calstore_erase(NULL, &cs), HAL_EINVAL);
    assert_int_equal(calstore_erase(&hal, NULL), HAL_EINVAL);
    expect_load(CALSTORE_OK, &rec_a, 1, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc32),
        cmocka_unit_test(test_layout_golden),
        cmocka_unit_test(test_fake_flash_semantics),
        cmocka_unit_test(test_empty),
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_alternation),
        cmocka_unit_test(test_erase),
        cmocka_unit_test(test_power_loss_every_byte),
        cmocka_unit_test(test_power_loss_twice),
        cmocka_unit_test(test_power_loss_erase),
        cmocka_unit_test(test_corrupt_one_slot_of_two),
        cmocka_unit_test(test_corrupt_only_record),
        cmocka_unit_test(test_corrupt_both),
        cmocka_unit_test(test_payload_rejected),
        cmocka_unit_test(test_seq_wraparound),
        cmocka_unit_test(test_save_with_stale_state),
        cmocka_unit_test(test_hal_errors),
    };
    return cmocka_run_group_tests_name("calstore", tests, NULL, NULL);
}
