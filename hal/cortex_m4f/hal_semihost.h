/*
 * hal_semihost.h - the HAL of hal.h for the Cortex-M4F under QEMU: CAN from a candump
 * log on the host, read through semihosting, and transmitted frames appended to another
 * host file in the same format (hal/common/candump.h), so the QEMU run is compared byte
 * for byte with the host's `navecu --can-log` (make target-test). QEMU emulates no CAN
 * controller; everything above the HAL is the ECU's firmware, compiled for the M4F.
 *
 * Same observable behaviour as the Linux log HAL (hal/linux/hal_linux.h): the clock is the
 * timestamp of the last frame received; malformed lines are counted and skipped (also a
 * line longer than HAL_SEMIHOST_LINE_MAX); TX lines are stamped hal_time_us() on
 * interface "can0"; the NVM is HAL_SEMIHOST_NVM_SIZE bytes of RAM in two sectors with
 * flash semantics (erased 0xFF, a write stores old AND new, HAL_EIO when that differs),
 * erased at open, or loaded from an NVM image file (hal_semihost_nvm_file) and written back
 * to it at close; the watchdog only counts kicks. Nothing is allocated.
 */
#ifndef NAVECU_HAL_SEMIHOST_H
#define NAVECU_HAL_SEMIHOST_H

#include <stddef.h>
#include <stdint.h>

#include "candump.h"
#include "hal.h"

#define HAL_SEMIHOST_NVM_SIZE 4096u
#define HAL_SEMIHOST_NVM_SECTOR_SIZE 2048u
#define HAL_SEMIHOST_LINE_MAX 128u   /* as HAL_LINUX_LINE_MAX */
#define HAL_SEMIHOST_RX_BUF 2048u    /* bytes read from the host per semihosting call */
#define HAL_SEMIHOST_TX_BUF 4096u    /* output bytes buffered before a semihosting write */

struct hal {
    int32_t rx;              /* semihosting handle of the RX log; -1: none */
    int32_t tx;              /* semihosting handle of the TX log; -1: discarded */
    candump_rx_t rx_log;     /* the replay's clock, malformed lines, frames, end */
    uint64_t watchdog_kicks;
    uint32_t tx_frames;
    uint8_t tx_error;        /* a host write failed: every later send returns HAL_EIO */
    size_t rx_pos;           /* next unread byte of rx_buf */
    size_t rx_len;           /* bytes in rx_buf */
    size_t tx_len;           /* bytes in tx_buf */
    char rx_buf[HAL_SEMIHOST_RX_BUF];
    char tx_buf[HAL_SEMIHOST_TX_BUF];
    char line[HAL_SEMIHOST_LINE_MAX];
    uint8_t nvm[HAL_SEMIHOST_NVM_SIZE];
    const char *nvm_path;    /* the NVM image file written at close; NULL: none */
};

/* Open the RX log (NULL: none) and create/truncate the TX log (NULL: discard). Returns 0,
 * HAL_EINVAL (hal NULL) or HAL_EIO (a file could not be opened). */
int hal_semihost_open(hal_t *hal, const char *rx_path, const char *tx_path);

/* After hal_semihost_open: the NVM backed by the image file at path (exactly
 * HAL_SEMIHOST_NVM_SIZE bytes, the host's --nvm file format: the region's bytes). A file
 * that does not exist leaves the NVM erased; it is created at close. Returns 0, HAL_EINVAL
 * (a NULL argument), HAL_EIO (the file has another size). The image is written back by
 * hal_semihost_close: the NVM as the run left it (a power cut is not modelled). */
int hal_semihost_nvm_file(hal_t *hal, const char *path);

/* Write out the buffered TX lines, the NVM image (if any), and close the files. Returns 0
 * or HAL_EIO. */
int hal_semihost_close(hal_t *hal);

#endif /* NAVECU_HAL_SEMIHOST_H */
