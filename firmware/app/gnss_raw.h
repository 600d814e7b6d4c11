/*
 * gnss_raw.h - raw GNSS epoch assembly (issue #20, docs/can.md "Raw GNSS measurements"):
 * the five frames of each satellite (GNSS_RawSatX/Y/Z, GNSS_RawRange, GNSS_RawRate, in any
 * order) collected by their RawSlot until the GNSS_RawEpoch with the same GnssEpoch closes
 * the epoch. A closed epoch lists the satellites whose five frames all came; the values stay
 * in the protocol's integer units (a satellite position of 2.6e7 m at 0.02 m needs 31 bits:
 * the range to it is formed in fixed point before anything goes to float32).
 *
 * What is dropped, and counted by the caller:
 * - a frame of another epoch number while an epoch is in assembly: the assembly so far is
 *   dropped (its epoch never closed) and this frame starts the next (GNSS_RAW_DROPPED);
 * - a second frame of the same part and slot in one epoch: the repeat is dropped, the
 *   first stays (GNSS_RAW_REPEAT);
 * - at the close: slots with a frame missing, frames of slots at or beyond NumMeas, a close
 *   whose epoch number is not the assembly's, a satellite in two slots (both dropped:
 *   gnss_raw_close_t);
 * - an epoch with the TimeOfWeek of the previous one (a repeat of the whole epoch).
 * The assembly is fixed size: GNSS_RAW_MAX_SATS slots.
 */
#ifndef NAVECU_GNSS_RAW_H
#define NAVECU_GNSS_RAW_H

#include <stdint.h>

#include "app_rx.h"

#define GNSS_RAW_MAX_SATS 16u

/* One satellite's measurements, in the protocol's units (the DBC's scales). */
typedef struct {
    int32_t pos_lsb[3];     /* ECEF at the transmit time, axes of that time, 0.02 m */
    int16_t vel_lsb[3];     /* ECEF velocity, 0.125 m/s */
    uint32_t pr_lsb;        /* corrected pseudorange, 0.02 m */
    int32_t rr_lsb;         /* pseudorange rate, 0.01 m/s */
    uint8_t pr_sigma_lsb;   /* 0.1 m; 0 no estimate */
    uint8_t rr_sigma_lsb;   /* 0.01 m/s; 0 no estimate */
    uint8_t system, sv_id, elevation_deg, cn0_dbhz;
    uint8_t pr_valid, rr_valid;
} gnss_raw_sat_t;

typedef struct {
    gnss_raw_sat_t sat[GNSS_RAW_MAX_SATS];
    uint8_t parts[GNSS_RAW_MAX_SATS]; /* RX_RAW_PART_* received per slot */
    uint8_t epoch;                    /* the epoch number in assembly */
    uint8_t open;                     /* a frame is in assembly */
    uint8_t have_tow;
    uint32_t last_tow_ms;             /* the previous closed epoch's TimeOfWeek */
} gnss_raw_asm_t;

/* What one frame did to the assembly. */
typedef enum {
    GNSS_RAW_TAKEN = 0,
    GNSS_RAW_REPEAT,  /* the same part of the slot again in this epoch: dropped */
    GNSS_RAW_DROPPED, /* an unclosed epoch of another number was dropped for this frame */
} gnss_raw_frame_t;

/* What closing an epoch found. n_sats satellites are complete, in slots of `complete`
 * (bit i: slot i), readable in the assembly until its next frame. */
typedef struct {
    uint8_t mismatch;   /* the close's epoch number is not the assembly's: all dropped */
    uint8_t repeat;     /* the previous epoch's TimeOfWeek again: all dropped */
    uint8_t incomplete; /* slots below NumMeas with a frame missing (dropped) */
    uint8_t extra;      /* slots at or beyond NumMeas that had frames (dropped) */
    uint8_t duplicate;  /* complete slots of a satellite (System, SvId) another complete
                           slot also has: every one of them dropped */
    uint8_t n_sats;     /* complete satellites */
    uint16_t complete;  /* their slots */
    uint8_t usable;     /* at least one complete satellite, not a repeat or mismatch */
} gnss_raw_close_t;

void gnss_raw_init(gnss_raw_asm_t *g);

/* One satellite frame (in->kind RX_GNSS_RAW_SAT, decoded by app_rx). */
gnss_raw_frame_t gnss_raw_frame(gnss_raw_asm_t *g, const rx_input_t *in);

/* Close the epoch with its GNSS_RawEpoch (in->kind RX_GNSS_RAW_EPOCH). The slots are
 * cleared for the next epoch at its first frame; the complete ones stay readable till then. */
gnss_raw_close_t gnss_raw_close(gnss_raw_asm_t *g, const rx_input_t *in);

#endif /* NAVECU_GNSS_RAW_H */
