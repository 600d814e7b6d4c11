/*
 * test_dtc.c - the fault memory (firmware/app/dtc.c): the ISO 14229-1 Annex D status byte
 * of a DTC through failed and passed tests, the confirm time, the second operation cycle,
 * the pendingDTC kept for the next cycle, ClearDiagnosticInformation, the stored bytes
 * (what goes to NVM, and when) and the refusal of impossible stored bytes.
 *
 * The expected bytes are written from Annex D's bit definitions (bit 0 testFailed, 1
 * testFailedThisOperationCycle, 2 pendingDTC, 3 confirmedDTC, 4
 * testNotCompletedSinceLastClear, 5 testFailedSinceLastClear, 6
 * testNotCompletedThisOperationCycle), not produced by the code under test. The DTCs are
 * the generated table's (firmware/app/dtc.toml): IMU_STALE confirms after 2 s, NVM_ERROR at
 * the first failure.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "dtc.h"
#include "navecu_protocol.h"

#define MS 1000u /* us */
#define STALE NAVECU_HEALTH_IMU_STALE
#define BIT(i) ((uint32_t)1u << (i))

static dtc_t d;

static int setup(void **state)
{
    (void)state;
    dtc_init(&d);
    return 0;
}

/* every status byte within the availability mask: bit 7 never set */
static void assert_bit7_clear(void)
{
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        assert_int_equal(dtc_status(&d, i) & 0x80u, 0u);
    }
}

static void test_table_from_dtc_toml(void **state)
{
    (void)state;
    assert_true(DTC_N <= DTC_MAX);
    assert_int_equal(dtc_table[DTC_IMU_STALE].number, 0xD10187u); /* U1101-87 */
    assert_int_equal(dtc_table[DTC_IMU_STALE].health_mask, NAVECU_HEALTH_IMU_STALE);
    assert_int_equal(dtc_table[DTC_IMU_STALE].confirm_ds, 20u); /* 2 s */
    assert_int_equal(dtc_table[DTC_NVM_ERROR].confirm_ds, 0u);
    assert_int_equal(dtc_table[DTC_NO_GNSS].confirm_ds, 600u | DTC_DEBOUNCED); /* 60 s */
    assert_int_equal(dtc_table[DTC_NO_HEADING].confirm_ds, 3000u | DTC_DEBOUNCED);
    uint32_t all = 0u;
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        assert_int_equal(all & dtc_table[i].health_mask, 0u); /* one DTC per flag */
        all |= dtc_table[i].health_mask;
        assert_true(dtc_table[i].number <= 0xFFFFFFu);
    }
    assert_int_equal(all, 0x7FFFu); /* every HealthFlags bit of the DBC has one */
    assert_int_equal(dtc_table[DTC_WATCHDOG_OFF].number, 0x510847u); /* C1108-47 */
    assert_int_equal(dtc_table[DTC_BUS_OFF].number, 0xC00188u);      /* U0001-88 */
    assert_int_equal(dtc_table[DTC_BUS_OFF].confirm_ds, 10u); /* 1 s, not debounced */
}

/* a fresh ECU: never tested since the clear (nothing in NVM) */
static void test_fresh_is_not_tested(void **state)
{
    (void)state;
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        assert_int_equal(dtc_status(&d, i), 0x50u);
        assert_int_equal(dtc_stored(&d, i), 0x10u);
    }
    assert_int_equal(dtc_status(&d, DTC_N), 0u); /* beyond the table: nothing */
}

/* a passed test: TF, TNCTOC, TNCSLC clear -> 0x00, stored 0x00 (each DTC once) */
static void test_passed_test(void **state)
{
    (void)state;
    assert_int_equal(dtc_update(&d, 0u, 0u), (uint32_t)(BIT(DTC_N) - 1u));
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        assert_int_equal(dtc_status(&d, i), 0x00u);
        assert_int_equal(dtc_stored(&d, i), 0x00u);
    }
    assert_int_equal(dtc_update(&d, 0u, 100u * MS), 0u); /* nothing changes: no write */
}

/* IMU_STALE failing: 0x27 (TF TFTOC PDTC TFSLC) at once, confirmed (0x2F) after 2 s of
 * failures, not before; then passing: 0x2E (pending and confirmed stay) */
static void test_confirm_time(void **state)
{
    (void)state;
    (void)dtc_update(&d, 0u, 0u);
    assert_int_equal(dtc_update(&d, STALE, 1000u * MS), BIT(DTC_IMU_STALE));
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x27u);
    assert_int_equal(dtc_stored(&d, DTC_IMU_STALE), 0x24u);
    assert_int_equal(dtc_status(&d, DTC_IMU_FAULT), 0x00u); /* the others untouched */
    for (uint64_t t = 1100u; t < 3000u; t += 100u) {
        assert_int_equal(dtc_update(&d, STALE, t * MS), 0u); /* not yet: no write */
        assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x27u);
    }
    assert_int_equal(dtc_update(&d, STALE, 2999999u), 0u); /* 1 us short of 2 s */
    assert_int_equal(dtc_update(&d, STALE, 3000u * MS), BIT(DTC_IMU_STALE));
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x2Fu);
    assert_int_equal(dtc_stored(&d, DTC_IMU_STALE), 0x2Cu);
    assert_int_equal(dtc_update(&d, 0u, 3100u * MS), 0u); /* passes: only TF, in RAM */
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x2Eu);
    assert_bit7_clear();
}

/* a pass restarts the confirm time: 1.5 s + 1.5 s of failure with a pass between */
static void test_confirm_time_restarts_after_a_pass(void **state)
{
    (void)state;
    (void)dtc_update(&d, STALE, 0u);
    (void)dtc_update(&d, STALE, 1500u * MS);
    (void)dtc_update(&d, 0u, 1600u * MS);
    (void)dtc_update(&d, STALE, 1700u * MS);
    (void)dtc_update(&d, STALE, 3200u * MS);
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE) & DTC_CDTC, 0u);
    (void)dtc_update(&d, STALE, 3700u * MS); /* 2 s after the second start */
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE) & DTC_CDTC, DTC_CDTC);
    /* time going backwards counts as no time: no confirmation from it */
    dtc_init(&d);
    (void)dtc_update(&d, STALE, 5000u * MS);
    (void)dtc_update(&d, STALE, 1000u * MS);
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x27u);
    /* a condition's time is taken on the clock's low 32 bits (dtc.h): 2 s across their
     * wrap (71.6 min after power-on) confirms as anywhere else, 1.9 s does not */
    dtc_init(&d);
    const uint64_t wrap = UINT64_C(1) << 32;
    (void)dtc_update(&d, STALE, wrap - 1000u * MS);
    (void)dtc_update(&d, STALE, wrap + 900u * MS);
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE) & DTC_CDTC, 0u);
    (void)dtc_update(&d, STALE, wrap + 1000u * MS);
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE) & DTC_CDTC, DTC_CDTC);
}

/* confirm time 0: confirmed at the first failure (NVM_ERROR) */
static void test_confirm_at_first_failure(void **state)
{
    (void)state;
    assert_int_equal(dtc_update(&d, NAVECU_HEALTH_NVM_ERROR, 0u),
                     (uint32_t)(BIT(DTC_N) - 1u)); /* every DTC tested for the first time */
    assert_int_equal(dtc_status(&d, DTC_NVM_ERROR), 0x2Fu);
    assert_int_equal(dtc_stored(&d, DTC_NVM_ERROR), 0x2Cu);
}

/* the next operation cycle from the stored bytes */
static void load_from(const dtc_t *prev)
{
    uint8_t nvm[DTC_MAX];
    memset(nvm, 0, sizeof nvm);
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        nvm[i] = dtc_stored(prev, i);
    }
    dtc_init(&d);
    assert_int_equal(dtc_load(&d, nvm, sizeof nvm), 0u);
}

/* failed in two operation cycles: confirmed at the first failure of the second, though
 * neither failure lasted the confirm time */
static void test_two_cycle_confirm(void **state)
{
    (void)state;
    (void)dtc_update(&d, STALE, 0u);
    (void)dtc_update(&d, 0u, 1000u * MS); /* 1 s < 2 s: pending only */
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x26u);
    assert_int_equal(dtc_stored(&d, DTC_IMU_STALE), 0x24u);
    const dtc_t prev = d;
    load_from(&prev);
    /* the new cycle: TF, TFTOC clear, TNCTOC set; pending and TFSLC kept */
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x64u);
    assert_int_equal(dtc_status(&d, DTC_IMU_FAULT), 0x40u); /* passed before: 0x00 + TNCTOC */
    assert_int_equal(dtc_update(&d, STALE, 0u), BIT(DTC_IMU_STALE));
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x2Fu);
    assert_int_equal(dtc_stored(&d, DTC_IMU_STALE), 0x2Cu);
}

/* a cycle that tested the DTC and never failed it clears pendingDTC for the next one (the
 * stored byte changes at its first pass: one write), so a failure in the cycle after is
 * not a second consecutive one; a cycle without the test keeps pendingDTC */
static void test_pending_across_cycles(void **state)
{
    (void)state;
    (void)dtc_update(&d, STALE, 0u);
    (void)dtc_update(&d, 0u, 500u * MS);
    dtc_t prev = d;
    load_from(&prev); /* cycle 2: not tested at all */
    assert_int_equal(dtc_stored(&d, DTC_IMU_STALE), 0x24u);
    prev = d;
    load_from(&prev); /* cycle 3: passes only */
    assert_int_equal(dtc_update(&d, 0u, 0u) & BIT(DTC_IMU_STALE), BIT(DTC_IMU_STALE));
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x24u); /* pending in this cycle still */
    assert_int_equal(dtc_stored(&d, DTC_IMU_STALE), 0x20u); /* not in the next */
    assert_int_equal(dtc_update(&d, 0u, 100u * MS), 0u);    /* one write, not one a pass */
    prev = d;
    load_from(&prev); /* cycle 4: fails briefly: pending again, not confirmed */
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x60u);
    (void)dtc_update(&d, STALE, 0u);
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x27u);
    /* a failure after a pass in the same cycle puts pending back in the stored byte */
    prev = d;
    load_from(&prev);
    (void)dtc_update(&d, 0u, 0u);
    assert_int_equal(dtc_stored(&d, DTC_IMU_STALE), 0x20u);
    assert_int_equal(dtc_update(&d, STALE, 100u * MS) & BIT(DTC_IMU_STALE), BIT(DTC_IMU_STALE));
    assert_int_equal(dtc_stored(&d, DTC_IMU_STALE) & DTC_PDTC, DTC_PDTC);
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE) & DTC_CDTC, DTC_CDTC); /* 2 cycles */
}

/* ClearDiagnosticInformation: every DTC 0x50, stored 0x10; the confirm timer stopped */
static void test_clear(void **state)
{
    (void)state;
    (void)dtc_update(&d, STALE | NAVECU_HEALTH_NVM_ERROR, 0u);
    (void)dtc_update(&d, STALE | NAVECU_HEALTH_NVM_ERROR, 2000u * MS);
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x2Fu);
    /* every stored byte changed (all were tested): all written */
    assert_int_equal(dtc_clear_all(&d), (uint32_t)(BIT(DTC_N) - 1u));
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        assert_int_equal(dtc_status(&d, i), 0x50u);
        assert_int_equal(dtc_stored(&d, i), 0x10u);
    }
    assert_int_equal(d.clears, 1u);
    assert_int_equal(dtc_clear_all(&d), 0u); /* a second clear writes nothing */
    /* still failing after the clear: a new failure, its confirm time from now */
    (void)dtc_update(&d, STALE, 2100u * MS);
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x27u);
    (void)dtc_update(&d, STALE, 4099u * MS);
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x27u);
    (void)dtc_update(&d, STALE, 4100u * MS);
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x2Fu);
    /* a clear also forgets a pending of the previous cycle */
    const dtc_t prev = d;
    load_from(&prev);
    (void)dtc_clear_all(&d);
    (void)dtc_update(&d, STALE, 0u);
    assert_int_equal(dtc_status(&d, DTC_IMU_STALE), 0x27u);
}

/* stored bytes that cannot be: refused, the DTC as after a clear, counted */
static void test_load_refuses_impossible_bytes(void **state)
{
    (void)state;
    uint8_t nvm[DTC_MAX];
    memset(nvm, 0, sizeof nvm);
    nvm[0] = 0x80u; /* bit 7 is never stored */
    nvm[1] = 0x08u; /* confirmed, never failed since the clear */
    nvm[2] = 0x04u; /* pending, never failed since the clear */
    nvm[3] = 0x30u; /* failed since the clear and never tested since it */
    nvm[4] = 0x2Du; /* bit 0 is not stored */
    nvm[5] = 0x2Cu; /* a good one: confirmed and pending */
    nvm[6] = 0x10u; /* a good one: not tested since the clear */
    assert_int_equal(dtc_load(&d, nvm, sizeof nvm), 5u);
    assert_int_equal(d.load_rejected, 5u);
    for (size_t i = 0u; i < 5u; i++) {
        assert_int_equal(dtc_status(&d, i), 0x50u);
    }
    assert_int_equal(dtc_status(&d, 5), 0x6Cu);
    assert_int_equal(dtc_status(&d, 6), 0x50u);
    assert_int_equal(dtc_status(&d, 7), 0x40u);
    /* 0xFF: never stored (erased flash, the record's "none"): as after a clear, not refused */
    memset(nvm, 0xFF, sizeof nvm);
    nvm[2] = 0x2Cu;
    assert_int_equal(dtc_load(&d, nvm, sizeof nvm), 0u);
    assert_int_equal(d.load_rejected, 5u);
    assert_int_equal(dtc_status(&d, 0), 0x50u);
    assert_int_equal(dtc_status(&d, 2), 0x6Cu);
    nvm[5] = 0x2Cu;
    /* a shorter record (an older table): the DTCs beyond it as after a clear */
    assert_int_equal(dtc_load(&d, nvm + 5, 1u), 0u);
    assert_int_equal(dtc_status(&d, 0), 0x6Cu);
    assert_int_equal(dtc_status(&d, 1), 0x50u);
    /* none at all */
    assert_int_equal(dtc_load(&d, NULL, 0u), 0u);
    assert_int_equal(dtc_status(&d, 0), 0x50u);
    assert_bit7_clear();
}

/* NO_GNSS, debounced for 60 s: a start's wait for the first fix (59.9 s of the condition
 * from 0.1 s) is no test result, in this operation cycle and the next (the docs-only client
 * found U1102-87 confirmed on the second fault-free start, before debouncing); a pass
 * between restarts the time; 60 s of it fails the test: 0x2F (TF TFTOC PDTC CDTC TFSLC)
 * at once, stored 0x2C */
static void test_debounced(void **state)
{
    (void)state;
    const uint32_t no_gnss = NAVECU_HEALTH_NO_GNSS;
    for (int cycle = 0; cycle < 2; cycle++) {
        for (uint64_t t = 100u; t < 60000u; t += 100u) {
            assert_int_equal(dtc_update(&d, no_gnss, t * MS) & BIT(DTC_NO_GNSS), 0u);
            assert_int_equal(dtc_status(&d, DTC_NO_GNSS), cycle == 0 ? 0x50u : 0x40u);
        }
        assert_int_equal(dtc_update(&d, 0u, 60000u * MS) & BIT(DTC_NO_GNSS),
                         cycle == 0 ? BIT(DTC_NO_GNSS) : 0u); /* passed: 0x00 */
        assert_int_equal(dtc_status(&d, DTC_NO_GNSS), 0x00u);
        const uint8_t stored = dtc_stored(&d, DTC_NO_GNSS);
        assert_int_equal(stored, 0x00u);
        (void)dtc_load(&d, (const uint8_t[DTC_N]){[DTC_NO_GNSS] = 0x00u}, (size_t)DTC_N);
    }
    (void)dtc_update(&d, no_gnss, 0u);
    (void)dtc_update(&d, no_gnss, 40000u * MS);
    (void)dtc_update(&d, 0u, 41000u * MS);                /* a fix: the time restarts */
    (void)dtc_update(&d, no_gnss, 42000u * MS);
    assert_int_equal(dtc_update(&d, no_gnss, 101999u * MS) & BIT(DTC_NO_GNSS), 0u);
    assert_int_equal(dtc_status(&d, DTC_NO_GNSS), 0x00u); /* 59.999 s: nothing yet */
    assert_int_equal(dtc_update(&d, no_gnss, 102000u * MS) & BIT(DTC_NO_GNSS),
                     BIT(DTC_NO_GNSS));
    assert_int_equal(dtc_status(&d, DTC_NO_GNSS), 0x2Fu);
    assert_int_equal(dtc_stored(&d, DTC_NO_GNSS), 0x2Cu);
    assert_bit7_clear();
}

/* A debounced condition lasts only while it is tested: NO_GNSS untested for 100 s (the
 * car stands, output.c) restarts its time, as does a new operation cycle (dtc_load) */
static void test_debounce_time_while_tested(void **state)
{
    (void)state;
    const uint32_t no_gnss = NAVECU_HEALTH_NO_GNSS;
    const uint32_t not_it = ~no_gnss;
    (void)dtc_update(&d, no_gnss, 0u);
    (void)dtc_update_tested(&d, no_gnss, not_it, 50000u * MS);
    (void)dtc_update(&d, no_gnss, 100000u * MS);
    assert_int_equal(dtc_status(&d, DTC_NO_GNSS), 0x50u); /* 0 s of it since 100 s */
    (void)dtc_update(&d, no_gnss, 159999u * MS);
    assert_int_equal(dtc_status(&d, DTC_NO_GNSS), 0x50u);
    (void)dtc_update(&d, no_gnss, 160000u * MS);
    assert_int_equal(dtc_status(&d, DTC_NO_GNSS), 0x2Fu);
    /* a new cycle with the condition running from before it: its time starts again */
    setup(NULL);
    (void)dtc_update(&d, no_gnss, 0u);
    (void)dtc_load(&d, (const uint8_t[DTC_N]){0}, (size_t)DTC_N);
    (void)dtc_update(&d, no_gnss, 61000u * MS);
    assert_int_equal(dtc_status(&d, DTC_NO_GNSS), 0x40u); /* not completed this cycle */
    (void)dtc_update(&d, no_gnss, 121000u * MS);
    assert_int_equal(dtc_status(&d, DTC_NO_GNSS), 0x2Fu);
}

/* Refusals are debounced and tested at a standstill too (dtc.toml; the mask of output.c):
 * a refused frame or a gated GNSS fix flags REJECTED for a second, in two drives in a row
 * (the review found that confirming U1103-81 on fault-free drives: the simulator's clean
 * drive gates 2 fixes); a wheel locking for 2 s under braking, in two drives, confirms no
 * C1107-64 either. A sender whose every frame fails for 10 s confirms U1103-81, the car
 * standing or not; NO_GNSS meanwhile, the car standing, is not tested (while_moving). */
static void test_refusals_now_and_then_are_no_fault(void **state)
{
    (void)state;
    const uint32_t standing = ~((uint32_t)DTC_WHILE_MOVING_FLAGS * 1u);
    const uint32_t moving = ~((uint32_t)DTC_WHILE_MOVING_FLAGS * 0u);
    for (int cycle = 0; cycle < 2; cycle++) {
        for (uint64_t t = 0u; t < 120000u; t += 100u) {
            /* a refusal flagged for 1 s of every 20 (REJECTED), a wheel lock for 2 s of
             * every 60 (ODO_REJECTED): each condition short, then passed */
            const uint32_t f = (t % 20000u < 1000u ? NAVECU_HEALTH_REJECTED : 0u) |
                               (t % 60000u < 2000u ? NAVECU_HEALTH_ODO_REJECTED : 0u);
            (void)dtc_update_tested(&d, f, t < 60000u ? moving : standing, t * MS);
        }
        assert_int_equal(dtc_status(&d, DTC_REJECTED), 0x00u); /* tested, passed */
        assert_int_equal(dtc_status(&d, DTC_ODO_REJECTED), 0x00u);
        (void)dtc_load(&d, (const uint8_t[DTC_N]){0}, (size_t)DTC_N); /* the next drive */
    }
    const uint32_t bad = NAVECU_HEALTH_REJECTED | NAVECU_HEALTH_NO_GNSS;
    (void)dtc_update_tested(&d, bad, standing, 0u);
    assert_int_equal(dtc_update_tested(&d, bad, standing, 9900u * MS) & BIT(DTC_REJECTED), 0u);
    assert_int_equal(dtc_update_tested(&d, bad, standing, 10000u * MS) & BIT(DTC_REJECTED),
                     BIT(DTC_REJECTED));
    assert_int_equal(dtc_status(&d, DTC_REJECTED), 0x2Fu); /* pending and confirmed at once */
    assert_int_equal(dtc_status(&d, DTC_NO_GNSS), 0x40u);  /* not tested while standing */
    /* and the wheel speeds refused for 30 s of driving */
    (void)dtc_update_tested(&d, NAVECU_HEALTH_ODO_REJECTED, moving, 20000u * MS);
    (void)dtc_update_tested(&d, NAVECU_HEALTH_ODO_REJECTED, moving, 49900u * MS);
    assert_int_equal(dtc_status(&d, DTC_ODO_REJECTED), 0x00u);
    (void)dtc_update_tested(&d, NAVECU_HEALTH_ODO_REJECTED, moving, 50000u * MS);
    assert_int_equal(dtc_status(&d, DTC_ODO_REJECTED), 0x2Fu);
    assert_bit7_clear();
}

/* A 1 Hz sender whose every frame is refused: REJECTED held 1 s after each refusal, seen
 * at the 10 Hz NAV_Status ticks with the refusals' jitter leaving one or two ticks clear
 * between them (a review's finding: such a fault never confirmed when any pass ended the
 * condition). One condition: confirmed 10 s after the first refusal. Refusals 3.5 s apart
 * (passes of 2.5 s, over DTC_PASS_HOLD_US): no condition, in two drives. */
static void test_slow_refusals_are_one_condition(void **state)
{
    (void)state;
    for (uint64_t t = 0u; t <= 10000u; t += 100u) {
        const uint64_t in_s = t % 1000u; /* the flag clear for the last tick or two */
        const uint32_t f = in_s < ((t / 1000u) % 2u == 0u ? 900u : 800u) ? NAVECU_HEALTH_REJECTED
                                                                       : 0u;
        (void)dtc_update(&d, f, t * MS);
        if (t < 10000u) {
            assert_int_equal(dtc_status(&d, DTC_REJECTED) & DTC_PDTC, 0u);
        }
    }
    assert_int_equal(dtc_status(&d, DTC_REJECTED), 0x2Fu); /* at 10 s */
    setup(NULL);
    for (int cycle = 0; cycle < 2; cycle++) {
        for (uint64_t t = 0u; t < 60000u; t += 100u) {
            const uint32_t f = t % 3500u < 1000u ? NAVECU_HEALTH_REJECTED : 0u;
            (void)dtc_update(&d, f, t * MS);
        }
        assert_int_equal(dtc_status(&d, DTC_REJECTED), 0x00u);
        (void)dtc_load(&d, (const uint8_t[DTC_N]){0}, (size_t)DTC_N);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_table_from_dtc_toml, setup),
        cmocka_unit_test_setup(test_fresh_is_not_tested, setup),
        cmocka_unit_test_setup(test_passed_test, setup),
        cmocka_unit_test_setup(test_confirm_time, setup),
        cmocka_unit_test_setup(test_confirm_time_restarts_after_a_pass, setup),
        cmocka_unit_test_setup(test_confirm_at_first_failure, setup),
        cmocka_unit_test_setup(test_two_cycle_confirm, setup),
        cmocka_unit_test_setup(test_pending_across_cycles, setup),
        cmocka_unit_test_setup(test_clear, setup),
        cmocka_unit_test_setup(test_load_refuses_impossible_bytes, setup),
        cmocka_unit_test_setup(test_debounced, setup),
        cmocka_unit_test_setup(test_debounce_time_while_tested, setup),
        cmocka_unit_test_setup(test_refusals_now_and_then_are_no_fault, setup),
        cmocka_unit_test_setup(test_slow_refusals_are_one_condition, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
