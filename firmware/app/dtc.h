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
 *   debounced (DTC_DEBOUNCED in the table's confirm_ds; dtc.toml: a condition that is also
 *            a state of normal operation while short, such as the first GNSS fix after
 *            power-on or a refused frame now and then): the condition fails the test only once it has lasted the confirm
 *            time (then pending and confirmed at once); shorter, the test is not completed
 *            and the status byte unchanged, so a start's normal wait is no failure and no
 *            second start confirms it. A condition lasts while it is tested: a test not
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
#define DTC_NO_CONDITION UINT64_MAX /* fail_start_us: the condition is clear */
#define DTC_STORED_NONE 0xFFu       /* a stored byte never written (erased flash; the NVM
                                       record's "none stored") */

typedef struct {
    uint8_t status[DTC_N];       /* the Annex D status bytes */
    uint8_t stored[DTC_N];       /* what NVM holds (DTC_STORED_MASK bits) */
    uint8_t pending_at_start[DTC_N]; /* pendingDTC when this operation cycle started */
    uint64_t fail_start_us[DTC_N]; /* when the present condition started (its HealthFlags
                                      bit set), DTC_NO_CONDITION while it is clear */
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

/* One test of every DTC at now_us (a clock in us below 2^63, e.g. since power-on; going
 * backwards counts as no time; DTC_NO_CONDITION is not a time):
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
