/*
 * hal_linux.h - the HAL of hal.h on a Linux host: CAN from a candump log replay, CAN
 * transmission appended to a candump log, NVM in memory or backed by a file, and a
 * watchdog emulation on the HAL clock (hal_linux_watchdog_expired).
 *
 * The caller owns the struct hal (on the stack or static); nothing is allocated. One
 * instance per replay; the functions are not thread-safe.
 *
 * Log format: the candump line of hal/common/candump.h (parsed and written there). Any
 * interface name is accepted on receive (no filtering by interface). A line of only
 * blanks is skipped without counting. A malformed line is counted in
 * hal_can_rx_lost() and skipped, and so is a line longer than HAL_LINUX_LINE_MAX
 * characters before its newline (the rest of it is read and dropped; counted once). A
 * last line without a newline is parsed like any other.
 */
#ifndef NAVECU_HAL_LINUX_H
#define NAVECU_HAL_LINUX_H

#include <stdint.h>
#include <stdio.h>

#include "candump.h"
#include "hal.h"

#define HAL_LINUX_NVM_SIZE 4096u /* bytes in the NVM region */
#define HAL_LINUX_NVM_SECTOR_SIZE 2048u /* bytes per NVM sector: 2 sectors */
#define HAL_LINUX_LINE_MAX 128u  /* longest RX log line, characters before the newline */
#define HAL_LINUX_IFACE_MAX CANDUMP_IFACE_MAX /* longest interface name (IFNAMSIZ - 1) */

/* The file hal_linux_open could not use (hal_linux_open_failed). */
typedef enum {
    HAL_LINUX_FILE_NONE = 0,
    HAL_LINUX_FILE_RX,   /* the input log: cannot be opened (errno) */
    HAL_LINUX_FILE_TX,   /* the output log: cannot be created (errno) */
    HAL_LINUX_FILE_NVM,  /* the NVM file: cannot be opened or created (errno 0 < 0) */
    HAL_LINUX_FILE_NVM_SIZE, /* the NVM file: not HAL_LINUX_NVM_SIZE bytes, or unreadable */
} hal_linux_file_t;

/* One Linux host HAL. Fields are private to hal_linux.c; tests read them through the
 * accessor functions below. */
struct hal {
    FILE *rx;                 /* candump log replayed as CAN receive; NULL: none */
    FILE *tx;                 /* candump log transmitted frames go to; NULL: discarded */
    FILE *nvm_file;           /* file behind the NVM region; NULL: in memory only */
    candump_rx_t rx_log;      /* the replay's clock, malformed lines, frames, end; the
                                 live socket keeps its clock and counts here too */
    uint64_t watchdog_kicks;  /* hal_watchdog_kick calls since open */
    uint64_t last_kick_us;    /* HAL time of the last kick */
    uint32_t tx_frames;       /* frames accepted by hal_can_send (saturates) */
    char iface[HAL_LINUX_IFACE_MAX + 1u]; /* interface name written in the TX log */
    char line[HAL_LINUX_LINE_MAX];        /* RX line buffer, not NUL-terminated */
    uint8_t nvm[HAL_LINUX_NVM_SIZE];      /* the NVM region (mirror of nvm_file) */
    int can_fd;               /* live SocketCAN socket (hal_socketcan.c); -1: log replay */
    uint32_t can_error_frames; /* CAN error frames received on the socket */
    uint32_t can_bus_off;     /* of them, bus-off reports (CAN_ERR_BUSOFF); wraps */
    uint32_t can_bus_off_told; /* can_bus_off as hal_faults last reported it */
    uint32_t can_rx_dropped;  /* frames the socket's receive queue dropped (SO_RXQ_OVFL) */
    uint32_t can_rx_overflow; /* the controller's receive overflows (error frames) */
    uint32_t can_io_errors;   /* failed socket reads/writes (interface down, queue full) */
    hal_linux_file_t open_failed; /* the file a failed hal_linux_open could not use */
};

/*
 * Open a host HAL into caller-owned *hal (any previous contents are overwritten; a HAL
 * that is open must be closed first or its files leak).
 *   rx_log_path: candump log replayed by hal_can_receive; NULL: hal_can_receive returns
 *                HAL_ENODATA at once.
 *   tx_log_path: file hal_can_send appends candump lines to, created or truncated here;
 *                NULL: sent frames are checked and discarded.
 *   nvm_path:    file backing the NVM region, exactly HAL_LINUX_NVM_SIZE bytes; created
 *                filled with 0xFF if it does not exist; NULL: in memory only, erased.
 * The TX interface name is "can0" (hal_linux_set_iface changes it), the clock is 0.
 * Returns 0; HAL_EINVAL if hal is NULL; HAL_EIO if a file cannot be opened, created, or
 * read, or the NVM file has another size. On an error every file opened here is closed
 * again, hal_linux_close(hal) is harmless and hal_linux_open_failed says which file (for
 * the message: "cannot open" an input log is not "not an NVM image").
 */
int hal_linux_open(hal_t *hal, const char *rx_log_path, const char *tx_log_path,
                   const char *nvm_path);
hal_linux_file_t hal_linux_open_failed(const hal_t *hal);

/*
 * Flush the TX log and close every file. The NVM file is already up to date (writes go
 * through). A flush error here is not reported: hal_can_send returns HAL_EIO for errors
 * seen while sending. Safe to call twice, and after a failed hal_linux_open.
 */
void hal_linux_close(hal_t *hal);

/*
 * Set the interface name written in TX log lines (call after hal_linux_open, which sets
 * "can0"). At most HAL_LINUX_IFACE_MAX characters are kept; a character that is not
 * printable non-blank ASCII is written as '_', so the TX log stays a valid RX log.
 * NULL or "" restores "can0".
 */
void hal_linux_set_iface(hal_t *hal, const char *name);

/* hal_watchdog_kick calls since hal_linux_open. */
uint64_t hal_linux_watchdog_kicks(const hal_t *hal);

/*
 * The host's watchdog, emulated on the HAL clock (the log's time in a replay): 1 when the
 * last kick is more than HAL_LINUX_WATCHDOG_TIMEOUT_US behind hal_time_us, else 0 (also
 * before the first kick, which arms it). The ECU's independent watchdog resets the MCU in that case
 * (docs/target.md: 136..376 ms); the host executable reports it and exits non-zero. A
 * replay has no idle loop between frames, so the main loop asks only when it withholds a
 * kick (a late task); a gap in the log followed by a kick is not an expiry.
 */
#define HAL_LINUX_WATCHDOG_TIMEOUT_US 200000u
int hal_linux_watchdog_expired(const hal_t *hal);

/* Frames returned by hal_can_receive / accepted by hal_can_send since hal_linux_open
 * (saturating at UINT32_MAX). */
uint32_t hal_linux_rx_frames(const hal_t *hal);
uint32_t hal_linux_tx_frames(const hal_t *hal);

/* Of hal_can_rx_lost, the source's malformed frames alone: a log's unreadable lines, a live
 * socket's remote, FD or short frames (saturating at UINT32_MAX). */
uint32_t hal_linux_rx_malformed(const hal_t *hal);

/*
 * What hal.h leaves to the implementation, on this host:
 * - hal_can_receive: HAL_ENODATA at the end of the log and on every call after it;
 *   HAL_EIO on a read error; never HAL_EAGAIN (a replay has no idle time). The frame's
 *   t_us is its log timestamp, passed through even when it goes backwards.
 * - hal_time_us: the t_us of the last frame received (0 before any); not monotonic if
 *   the log is not.
 * - hal_can_send: writes "(SSSSSSSSSS.UUUUUU) IFACE ID#DATA\n" stamped hal_time_us(), so
 *   the TX log is a deterministic function of the RX log; ID as %03X or %08X, data as
 *   uppercase hex pairs. HAL_EINVAL if dlc > 8, extended is not 0 or 1, or the ID does not
 *   fit 11 (standard) or 29 (extended) bits; HAL_EIO on a write error (including one
 *   from an earlier buffered write); never HAL_ENOSPC.
 * - NVM: HAL_LINUX_NVM_SIZE bytes in sectors of HAL_LINUX_NVM_SECTOR_SIZE; HAL_EINVAL if
 *   offset + len > size, buf is NULL with len > 0, or the sector does not exist. Flash
 *   semantics as hal.h states them: a write stores old AND new and returns HAL_EIO when
 *   that differs from new (a write over programmed bytes is caught as on flash). Writes
 *   and erases go through to the file; HAL_EIO on a file error (the range's contents are
 *   then unspecified). A power loss is not modelled (tests/support/fake_hal.h does).
 */

#endif /* NAVECU_HAL_LINUX_H */
