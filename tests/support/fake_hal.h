/*
 * fake_hal.h - an in-memory HAL for application tests: frames to receive are queued by the
 * test (a bounded queue, fake_hal_rx_push; empty, hal_can_receive returns rx_empty_rc,
 * HAL_ENODATA after fake_hal_reset, and it takes the HAL clock forward to each frame's
 * t_us as a bus would), transmitted frames are captured, NVM is a RAM array with the flash semantics of
 * hal.h that can be told to fail, lose power in the middle of a write or an erase, or have
 * a byte corrupted.
 *
 * Power loss: fake_hal_nvm_cut_after(hal, n, torn) lets the next n NVM "units" complete,
 * where one unit is one byte programmed by hal_nvm_write or one sector erase, and cuts the
 * power on the unit after them:
 * - a cut byte is programmed only on the bits of `torn` (0x00: not at all; the byte
 *   becomes old AND (new OR NOT torn)); the bytes after it in that write are untouched;
 * - a cut erase leaves the sector half erased: bytes at even offsets 0xFF, the others as
 *   they were (contents that are neither the old ones nor erased);
 * the call that was cut returns HAL_EIO, and so does every NVM call after it (the power
 * is off) until fake_hal_nvm_power_on(), the "reboot", which keeps the NVM contents.
 * Reads do not count as units. nvm_units counts the units done since fake_hal_reset, so
 * a test can measure an operation and then cut it at every unit. hal.h allows a write to
 * program its bytes in any order: nvm_program_backwards = 1 programs each write from its
 * last byte to its first, so a cut leaves a suffix programmed instead of a prefix.
 */
#ifndef NAVECU_TEST_FAKE_HAL_H
#define NAVECU_TEST_FAKE_HAL_H

#include "hal.h"

#define FAKE_TX_MAX 32768u
#define FAKE_RX_MAX 64u
#define FAKE_NVM_SECTOR_SIZE 512u
#define FAKE_NVM_SECTORS 2u
#define FAKE_NVM_SIZE (FAKE_NVM_SECTORS * FAKE_NVM_SECTOR_SIZE)

struct hal {
    hal_can_frame_t tx[FAKE_TX_MAX];
    uint32_t tx_n;
    uint32_t tx_dropped;   /* sends beyond FAKE_TX_MAX */
    uint64_t t_us;         /* what hal_time_us returns */
    uint32_t rx_lost;      /* what hal_can_rx_lost returns */
    uint32_t faults;       /* what hal_faults returns (HAL_FAULT_BUS_OFF cleared on read) */
    uint8_t nvm[FAKE_NVM_SIZE];
    int nvm_fail;          /* 1: NVM operations return HAL_EIO */
    int nvm_cut_armed;     /* 1: a power cut is pending (fake_hal_nvm_cut_after) */
    uint32_t nvm_cut_left; /* units that still complete before the cut */
    uint8_t nvm_cut_torn;  /* bits of the cut byte that do get programmed */
    int nvm_power_off;     /* 1: the cut happened: NVM calls return HAL_EIO */
    uint32_t nvm_units;    /* bytes programmed + sectors erased since fake_hal_reset */
    int nvm_program_backwards; /* 1: each write programs its last byte first */
    uint32_t kicks;
    hal_can_frame_t rx[FAKE_RX_MAX]; /* frames to receive, in order */
    uint32_t rx_head, rx_n;  /* next to receive, frames queued */
    int rx_empty_rc;         /* what hal_can_receive returns with the queue empty */
    uint32_t rx_calls;       /* hal_can_receive calls */
    int has_bootloader;      /* what hal_bootloader(hal, 0) says: 1 there is one */
    uint32_t bootloader_entered; /* hal_bootloader(hal, 1) calls */
};

void fake_hal_reset(hal_t *hal);

/* Queue a frame to receive. Returns 0, or -1 when the queue is full. */
int fake_hal_rx_push(hal_t *hal, const hal_can_frame_t *f);

/* Frames queued and not received yet. */
uint32_t fake_hal_rx_left(const hal_t *hal);

/* Arm a power cut after n_units more NVM units; torn = bits of the cut byte programmed. */
void fake_hal_nvm_cut_after(hal_t *hal, uint32_t n_units, uint8_t torn);

/* Power back on after a cut (disarms a cut not reached yet); NVM contents are kept. */
void fake_hal_nvm_power_on(hal_t *hal);

/* Flip the bits of xor_mask in NVM byte offset (< FAKE_NVM_SIZE), ignoring flash rules. */
void fake_hal_nvm_corrupt(hal_t *hal, size_t offset, uint8_t xor_mask);

#endif
