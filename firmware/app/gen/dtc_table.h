/* GENERATED FILE - DO NOT EDIT. Source: firmware/app/dtc.toml.
 * Regenerate with 'make dtc' (tools/gen_dtc.py); 'make test' fails if stale. */

#ifndef NAVECU_DTC_TABLE_H
#define NAVECU_DTC_TABLE_H

#include <stdint.h>

/* the DTCs: their index is the status byte's place in the NVM record */
typedef enum {
    DTC_IMU_STALE = 0, /* U1101-87 IMU_STALE */
    DTC_IMU_FAULT = 1, /* C1101-96 IMU_FAULT */
    DTC_NO_GNSS = 2, /* U1102-87 NO_GNSS */
    DTC_REJECTED = 3, /* U1103-81 REJECTED */
    DTC_NVM_ERROR = 4, /* C1104-46 NVM_ERROR */
    DTC_NO_HEADING = 5, /* C1105-00 NO_HEADING */
    DTC_IMU_GAP = 6, /* U1101-82 IMU_GAP */
    DTC_FILTER_RESET = 7, /* C1106-64 FILTER_RESET */
    DTC_IMU_SUSPECT = 8, /* C1101-29 IMU_SUSPECT */
    DTC_IMU_SATURATED = 9, /* C1101-22 IMU_SATURATED */
    DTC_ODO_REJECTED = 10, /* C1107-64 ODO_REJECTED */
    DTC_REACQUIRE = 11, /* C1106-00 REACQUIRE */
    DTC_IMU_RATE_MISMATCH = 12, /* C1101-38 IMU_RATE_MISMATCH */
    DTC_N = 13
} dtc_id_t;

#define DTC_MAX 16u /* status bytes the NVM record holds */

typedef struct {
    uint32_t number;      /* the 3-byte DTC: J2012 code (high, middle), FTB (low) */
    uint16_t health_mask; /* the NAV_Status HealthFlags bit it mirrors */
    uint32_t confirm_ms;  /* the condition persisting this long: confirmedDTC */
} dtc_def_t;

extern const dtc_def_t dtc_table[DTC_N];

#endif /* NAVECU_DTC_TABLE_H */
