/* GENERATED FILE - DO NOT EDIT. Source: firmware/app/dtc.toml.
 * Regenerate with 'make dtc' (tools/gen_dtc.py); 'make test' fails if stale. */

#ifndef NAVECU_DTC_TABLE_H
#define NAVECU_DTC_TABLE_H

#include <stdint.h>

/* the DTCs: their index is the status byte's place in the NVM record */
#define DTC_IMU_STALE 0u /* U1101-87 IMU_STALE */
#define DTC_IMU_FAULT 1u /* C1101-96 IMU_FAULT */
#define DTC_NO_GNSS 2u /* U1102-87 NO_GNSS */
#define DTC_REJECTED 3u /* U1103-81 REJECTED */
#define DTC_NVM_ERROR 4u /* C1104-46 NVM_ERROR */
#define DTC_NO_HEADING 5u /* C1105-00 NO_HEADING */
#define DTC_IMU_GAP 6u /* U1101-82 IMU_GAP */
#define DTC_FILTER_RESET 7u /* C1106-64 FILTER_RESET */
#define DTC_IMU_SUSPECT 8u /* C1101-29 IMU_SUSPECT */
#define DTC_IMU_SATURATED 9u /* C1101-22 IMU_SATURATED */
#define DTC_ODO_REJECTED 10u /* C1107-64 ODO_REJECTED */
#define DTC_REACQUIRE 11u /* C1106-00 REACQUIRE */
#define DTC_IMU_RATE_MISMATCH 12u /* C1101-38 IMU_RATE_MISMATCH */
#define DTC_WATCHDOG_OFF 13u /* C1108-47 WATCHDOG_OFF */
#define DTC_BUS_OFF 14u /* U0001-88 BUS_OFF */
#define DTC_N 15u /* DTCs in the table */

#define DTC_MAX 16u /* status bytes the NVM record holds */

typedef struct {
    uint32_t number;      /* the 3-byte DTC: J2012 code (high, middle), FTB (low) */
    uint16_t health_mask; /* the NAV_Status HealthFlags bit it mirrors */
    uint16_t confirm_ds;  /* the condition persisting this long, 0.1 s: confirmedDTC
                             (8 bytes a row; 12 with milliseconds in 32 bits); with
                             DTC_DEBOUNCED the test fails only then (dtc.h) */
} dtc_def_t;

#define DTC_DEBOUNCED 0x8000u     /* in confirm_ds: a debounced DTC (dtc.toml) */
#define DTC_EVENTS 0x4000u        /* in confirm_ds: its flag marks events, held for a
                                     second (dtc.toml events; DTC_PASS_HOLD_US) */
#define DTC_PASS_HOLD_US 2000000u /* an events DTC's condition goes on through shorter passes (dtc.h) */
#define DTC_WHILE_MOVING_FLAGS 0x0824u /* tested only while the car moves: NO_GNSS | NO_HEADING | REACQUIRE */
#define DTC_CONFIRM_DS_MASK 0x3FFFu /* in confirm_ds: the confirm time */

extern const dtc_def_t dtc_table[DTC_N];

#endif /* NAVECU_DTC_TABLE_H */
