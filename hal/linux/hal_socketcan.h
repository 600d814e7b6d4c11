/*
 * hal_socketcan.h - the live CAN backend of the Linux host HAL: a raw SocketCAN socket
 * (vcan0 or a real interface). The socket code lives in hal_socketcan.c only; hal_linux.c
 * dispatches to it when the HAL was opened with hal_socketcan_open.
 */
#ifndef NAVECU_HAL_SOCKETCAN_H
#define NAVECU_HAL_SOCKETCAN_H

#include <stddef.h>
#include <stdint.h>

#include "hal_linux.h"

#define HAL_SOCKETCAN_MAX_FILTERS 32u

/*
 * Open the host HAL on a live interface: a raw CAN socket bound to ifname, non-blocking,
 * kernel receive timestamps (SO_TIMESTAMP), a receive filter passing only the standard
 * IDs in rx_ids[0..n_ids) (n_ids <= HAL_SOCKETCAN_MAX_FILTERS; 0: everything), and error
 * frames (counted, never returned). tx_log_path (may be NULL) also records every frame
 * sent, in candump format, timestamped on the HAL clock. nvm_path as for hal_linux_open.
 * Returns 0; HAL_EINVAL for bad arguments; HAL_EIO when the interface does not exist or
 * the socket cannot be set up (errno tells why; the HAL is then closed).
 */
int hal_socketcan_open(hal_t *hal, const char *ifname, const uint32_t *rx_ids, size_t n_ids,
                       const char *tx_log_path, const char *nvm_path);

/* Wait up to timeout_ms for a frame to be readable. Returns 1 (readable), 0 (timeout or
 * a signal), HAL_EIO (poll failed). */
int hal_socketcan_wait(hal_t *hal, int timeout_ms);

/* Called by hal_linux.c for an open socket. */
int hal_socketcan_receive(hal_t *hal, hal_can_frame_t *f);
int hal_socketcan_send(hal_t *hal, const hal_can_frame_t *f);
uint64_t hal_socketcan_time_us(void);
void hal_socketcan_close(hal_t *hal);

/* Counters of the live backend. */
uint32_t hal_socketcan_error_frames(const hal_t *hal);  /* CAN error frames received */
uint32_t hal_socketcan_io_errors(const hal_t *hal);     /* failed reads/writes (down, full) */
uint32_t hal_socketcan_rx_dropped(const hal_t *hal);    /* frames the socket's queue dropped */

#endif
