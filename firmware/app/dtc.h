/*
 * dtc.h - the fault memory: one DTC per health condition of NAV_Status (the generated
 * table firmware/app/gen/dtc_table.h, from firmware/app/dtc.toml), each with its ISO
 * 14229-1 Annex D status byte. Pure: no HAL, no clock of its own, fixed size.
 *
 * The test of every DTC runs with each NAV_Status (dtc_update): its HealthFlags bit set is
 * a failed test, clear a passed one. Per Annex D:
 *   failed:  testFailed, testFailedThisOperationCycle, pendingDTC, testFailedSinceLastClear
 *            set; testNotCompletedThisOperationCycle, testNotCompletedSinceLastClear clear;
 *            confirmedDTC set once the failure has lasted confirm_ms without a passed test
 *            between (the table's confirm time; 0 confirms at the first failure), or at
 *            once when the DTC was pending at the start of this operation cycle (it failed
 *            in the previous one: two operation cycles);
 *   debounced (DTC_DEBOUNCED in the table's confirm_ds, and DTC_EVENTS for the flags of
 *            events (dtc.toml `events`); dtc.toml: a condition that is also
 *            a state of normal operation while short, such as the first GNSS fix after
 *            power-on or a refused frame now and then): the condition fails the test only once it has lasted the confirm
 *            time (then pending and confirmed at once); shorter, the test is not completed
 *            and the status byte unchanged, so a start's normal wait is no failure and no
 *            second start confirms it. With DTC_EVENTS too, a pass shorter than
 *            DTC_PASS_HOLD_US does not end the condition (the test is then not completed,
 *            the status byte unchanged: a slow source's refusals, one a second, are one
 *            condition). A condition lasts
 *            while it is tested: a test not
 *            run (dtc_update_tested; the application runs the while_moving ones of
 *            dtc.toml only while the car moves), a passed test and a new operation cycle start its time again;
 *   passed:  testFailed, testNotCompletedThisOperationCycle, testNotCompletedSinceLastClear
 *            clear;
 *   the start of an operation cycle (dtc_load): testFailed, testFailedThisOperationCycle
 *            clear, testNotCompletedThisOperationCycle set; pendingDTC clear where the last
 *            cycle tested and never failed the DTC;
 *   ClearDiagnosticInformation (dtc_clear_all): every DTC 0x50 (testNotCompletedSinceLastClear,
 *            testNotCompletedThisOperationCycle), the confirm timers stopped.
 * confirmedDTC stays until a clear (no aging). Bit 7 (warningIndicatorRequested) is not
 * supported: DTC_AVAILABILITY_MASK.
 *
 * NVM: the stored byte of a DTC is its bits 2..5 (DTC_STORED_MASK) as the next operation
 * cycle will start from them: pendingDTC as it will be at the end of this cycle if nothing
 * else happens (set if it failed in this cycle, clear if it was tested and never failed,
 * unchanged if not tested yet). dtc_update and dtc_clear_all return which stored bytes
 * changed, for the caller to write to NVM (firmware/app/app_dtc.c); so the pendingDTC of
 * the previous cycle is known at the next start without an end-of-cycle write (power is
 * cut without warning). At most a few writes per DTC and operation cycle.
 */
#ifndef NAVECU_DTC_H
#define NAVECU_DTC_H

#include <stddef.h>
#include <stdint.h>

#include "dtc_table.h"

/* ISO 14229-1 D.2 DTC status bits */
#define DTC_TF 0x01u     /* testFailed */
#define DTC_TFTOC 0x02u  /* testFailedThisOperationCycle */
#define DTC_PDTC 0x04u   /* pendingDTC */
#define DTC_CDTC 0x08u   /* confirmedDTC */
#define DTC_TNCSLC 0x10u /* testNotCompletedSinceLastClear */
#define DTC_TFSLC 0x20u  /* testFailedSinceLastClear */
#define DTC_TNCTOC 0x40u /* testNotCompletedThisOperationCycle */
#define DTC_AVAILABILITY_MASK 0x7Fu /* bits 0..6 supported */
#define DTC_STORED_MASK 0x3Cu       /* bits kept in NVM: pending, confirmed, the two SLC */
#define DTC_STATUS_CLEARED 0x50u    /* after a clear: TNCSLC | TNCTOC */
#define DTC_NO_CONDITION UINT32_MAX /* fail_start_us: the condition is clear (a condition
                                       starting at that very microsecond of the clock's
                                       low 32 bits starts one test later) */
/* DTC_PASS_HOLD_US (dtc_table.h, tools/gen_dtc.py): an events DTC's condition goes on
 * through a pass shorter than it. Its flag marks events and is held for a second after each
 * (REJECTED, ODO_REJECTED), so a 1 Hz or 0.5 Hz sender whose every frame is refused leaves
 * passes of up to a second between them (a review's finding: with the condition ended by
 * any pass, such a fault never confirmed). 2 s: the flag's 1 s hold plus a period of up to
 * 2 s, with margin for jitter; refusals further apart than 3 s (a GNSS fix gated now and
 * then, a wheel locking once under braking) are no condition. */
#define DTC_STORED_NONE 0xFFu       /* a stored byte never written (erased flash; the NVM
                                       record's "none stored") */

typedef struct {
    uint8_t status[DTC_N];       /* the Annex D status bytes */
    uint8_t stored[DTC_N];       /* what NVM holds (DTC_STORED_MASK bits) */
    uint8_t pending_at_start[DTC_N]; /* pendingDTC when this operation cycle started */
    uint32_t fail_start_us[DTC_N]; /* when the present condition started (its HealthFlags
                                      bit set; the clock's low 32 bits), DTC_NO_CONDITION
                                      while it is clear */
    uint32_t last_fail_us[DTC_N]; /* the condition's last failed test, the clock's low 32
                                     bits (DTC_EVENTS: DTC_PASS_HOLD_US) */
    uint32_t load_rejected;      /* stored bytes refused at dtc_load (bits outside
                                    DTC_STORED_MASK, an impossible combination): 0x50 */
    uint32_t clears;             /* ClearDiagnosticInformation done */
} dtc_t;

/* A fresh ECU's fault memory (nothing in NVM): every DTC 0x50, stored 0x10. */
void dtc_init(dtc_t *d);

/*
 * The start of an operation cycle from the stored bytes of NVM (n of them, the record's;
 * DTCs beyond n and those stored as DTC_STORED_NONE start as after a clear, bytes beyond
 * DTC_N are ignored). Any other byte with bits outside DTC_STORED_MASK, pendingDTC or
 * confirmedDTC without testFailedSinceLastClear, or both "since last clear" bits (a
 * corrupt record) is refused: that DTC starts as after a clear, counted in load_rejected.
 * Returns the number refused.
 */
size_t dtc_load(dtc_t *d, const uint8_t *stored, size_t n);

/* One test of every DTC at now_us (a clock in us, e.g. since power-on; a condition's time
 * is taken on its low 32 bits, modulo 71.6 min: a difference of 2^31 us or more, time gone
 * backwards, counts as no time; a condition confirms within its confirm time, at most
 * 1,638.3 s, so the wrap never decides):
 * health_flags the NAV_Status HealthFlags. Returns the DTCs whose stored byte changed (bit
 * i for DTC i), to be written to NVM. */
uint32_t dtc_update(dtc_t *d, uint32_t health_flags, uint64_t now_us);

/* dtc_update for the DTCs whose HealthFlags bits are in tested only; the others keep their
 * status (not tested this time). */
uint32_t dtc_update_tested(dtc_t *d, uint32_t health_flags, uint32_t tested, uint64_t now_us);

/* ClearDiagnosticInformation of every DTC. Returns the DTCs whose stored byte changed. */
uint32_t dtc_clear_all(dtc_t *d);

/* DTC i's status byte (0 for i >= DTC_N) and its stored byte. */
uint8_t dtc_status(const dtc_t *d, size_t i);
uint8_t dtc_stored(const dtc_t *d, size_t i);

#endif /* NAVECU_DTC_H */
