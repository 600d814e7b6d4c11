/*
 * hal.h - the hardware abstraction layer: everything the application needs from a board.
 *
 * One implementation is linked per target (hal/linux/ for the host, hal/cortex_m4f/ for
 * the ECU). All functions take the HAL instance first, return 0 or a negative errno value
 * (values from <errno.h> of the implementation's C library; the application only compares
 * against the HAL_E* names below), never block unless stated, and never allocate.
 */
#ifndef NAVECU_HAL_H
#define NAVECU_HAL_H

#include <stddef.h>
#include <stdint.h>

#define HAL_EAGAIN (-11)  /* nothing available now (receive queue empty) */
#define HAL_EINVAL (-22)  /* bad argument */
#define HAL_EIO (-5)      /* device or file error */
#define HAL_ENODATA (-61) /* end of input: a log replay has no more frames */
#define HAL_ENOSPC (-28)  /* out of space (NVM region, TX queue) */

/* A classic CAN frame. */
typedef struct {
    uint32_t id;      /* 11-bit standard or 29-bit extended identifier */
    uint8_t extended; /* 1: 29-bit identifier */
    uint8_t dlc;      /* number of data bytes, 0..8 */
    uint8_t data[8];
    uint64_t t_us;    /* receive timestamp on the HAL clock (set by the HAL on receive) */
} hal_can_frame_t;

typedef struct hal hal_t; /* defined by the implementation */

/*
 * Receive one frame into *f. Returns 0; HAL_EAGAIN if none is waiting; HAL_ENODATA when
 * a finite source (a log replay) is exhausted; HAL_EIO on a device error. A malformed
 * frame from the source is not returned: it is counted (hal_can_rx_lost) and skipped.
 */
int hal_can_receive(hal_t *hal, hal_can_frame_t *f);

/* Queue one frame for transmission. Returns 0, HAL_EINVAL (dlc > 8), HAL_ENOSPC, HAL_EIO. */
int hal_can_send(hal_t *hal, const hal_can_frame_t *f);

/* Received frames the board lost before hal_can_receive could return them, since it
 * started: on a log replay the malformed lines skipped (garbage, truncated); on a CAN
 * controller the frames lost to a receive overrun (its hardware FIFO or the driver's ring
 * full: the main loop did not read them in time); on a live host socket its queue's drops,
 * its controller's receive overflows and the remote or FD frames it cannot deliver. Saturating or wrapping at 2^32, as the
 * implementation says; NAV_Status CntRxLost reports it (saturating at 255). */
uint32_t hal_can_rx_lost(const hal_t *hal);

/* The board's own faults (hal_faults), each a fault of the ECU the bus must hear of:
 *   HAL_FAULT_WATCHDOG  the watchdog is not supervising the ECU (it did not start): a hung
 *                       application is not reset; holds until the next power-on
 *   HAL_FAULT_BUS_OFF   the CAN controller went bus-off since the previous call (too many
 *                       errors of its own transmissions; it has recovered by itself once
 *                       the application can send again, ISO 11898-1's 128 x 11 recessive
 *                       bits) */
#define HAL_FAULT_WATCHDOG 0x1u
#define HAL_FAULT_BUS_OFF 0x2u

/* The HAL_FAULT_* bits that hold now; reading clears the events (HAL_FAULT_BUS_OFF:
 * several bus-offs between two calls are one). A board without a fault source returns 0
 * for its bit: the host has no watchdog, and a log replay no bus-off (a live SocketCAN
 * interface reports its controller's bus-off as an error frame, hal_socketcan.c). */
uint32_t hal_faults(hal_t *hal);

/* Time in microseconds since an arbitrary origin, monotonic on real hardware. On a log
 * replay: the timestamp of the last frame received, so replay runs as fast as it can; a
 * log whose timestamps go backwards makes it go backwards too (the application counts
 * that and does not depend on it: its time base is the IMU sample counter). */
uint64_t hal_time_us(const hal_t *hal);

/*
 * Non-volatile storage: one region of hal_nvm_size() bytes made of
 * hal_nvm_size() / hal_nvm_sector_size() equal sectors (at least 2); sector k holds bytes
 * [k * S, (k + 1) * S) with S = hal_nvm_sector_size(). The region behaves like NOR flash,
 * and the host and test HALs model it so that a caller which works there works on flash:
 * - erased bytes read 0xFF; only whole sectors can be erased;
 * - a write only clears bits: each byte becomes (old AND new). The write returns 0 when
 *   every byte then reads back as written; if some bit would have to go from 0 to 1 (a
 *   write over programmed bytes without an erase) it returns HAL_EIO and the bytes hold
 *   old AND new (a program-verify failure). Portable callers program each byte at most
 *   once between erases; any offset and length are allowed (no alignment rule);
 * - a reset or power loss during a write leaves each byte of the range anywhere between
 *   its old value and old AND new, in any order; during an erase, the sector's contents
 *   are unspecified. Only what was written before the interrupted call is certain
 *   (firmware/app/calstore.h builds its power-safe record on this).
 * - erase and write block until the flash is done: on a single-bank flash (STM32F405)
 *   a sector erase takes several hundred milliseconds, during which code fetches from
 *   flash stall (docs/porting.md). hal_nvm_read never blocks for long.
 * read, write and the erases return 0, HAL_EINVAL (a range past the end, a NULL buffer
 * with len > 0, a sector number >= the sector count, a NULL hal) or HAL_EIO (a flash or
 * file error).
 */
size_t hal_nvm_size(const hal_t *hal);
size_t hal_nvm_sector_size(const hal_t *hal);
int hal_nvm_read(hal_t *hal, size_t offset, void *buf, size_t len);
int hal_nvm_write(hal_t *hal, size_t offset, const void *buf, size_t len);
/* Erase one sector (every byte 0xFF). */
int hal_nvm_erase_sector(hal_t *hal, size_t sector);
/* Erase the whole region, sector by sector. */
int hal_nvm_erase(hal_t *hal);

/* Kick the watchdog. Must be called at least every 100 ms by the main loop. */
void hal_watchdog_kick(hal_t *hal);

/*
 * The bootloader (issue #19, docs/target.md): go 0 asks whether the board has one to
 * enter (0 yes, HAL_EIO no: the host, QEMU); go 1 enters it for a UDS programming
 * session: the board leaves the request where the bootloader finds it, lets the frames
 * already queued leave (bounded), and resets, so it does not return (HAL_EIO if it cannot).
 */
int hal_bootloader(hal_t *hal, int go);

#endif /* NAVECU_HAL_H */
