/*
 * hal_semihost.c - the HAL of hal.h over semihosting files (contracts in hal_semihost.h).
 */
#include "hal_semihost.h"

#include "nvm_flash.h"
#include "semihost.h"

static uint32_t sat_inc_u32(uint32_t n)
{
    return n == UINT32_MAX ? n : n + 1u;
}

int hal_semihost_open(hal_t *hal, const char *rx_path, const char *tx_path)
{
    if (hal == NULL) {
        return HAL_EINVAL;
    }
    hal->rx = -1;
    hal->tx = -1;
    hal->rx_log.t_us = 0u;
    hal->watchdog_kicks = 0u;
    hal->rx_log.malformed = 0u;
    hal->rx_log.frames = 0u;
    hal->tx_frames = 0u;
    hal->rx_log.eof = 0u;
    hal->tx_error = 0u;
    hal->rx_pos = 0u;
    hal->rx_len = 0u;
    hal->tx_len = 0u;
    for (size_t k = 0u; k < HAL_SEMIHOST_NVM_SIZE; k++) {
        hal->nvm[k] = 0xFFu;
    }
    hal->nvm_path = NULL;
    if (rx_path != NULL) {
        hal->rx = semihost_open(rx_path, SEMIHOST_MODE_RB);
        if (hal->rx < 0) {
            return HAL_EIO;
        }
    }
    if (tx_path != NULL) {
        hal->tx = semihost_open(tx_path, SEMIHOST_MODE_WB);
        if (hal->tx < 0) {
            (void)hal_semihost_close(hal);
            return HAL_EIO;
        }
    }
    return 0;
}

static int tx_flush(hal_t *hal)
{
    if (hal->tx >= 0 && hal->tx_len > 0u) {
        if (semihost_write(hal->tx, hal->tx_buf, hal->tx_len) != 0) {
            hal->tx_error = 1u;
        }
    }
    hal->tx_len = 0u;
    return hal->tx_error != 0u ? HAL_EIO : 0;
}

int hal_semihost_nvm_file(hal_t *hal, const char *path)
{
    if (hal == NULL || path == NULL) {
        return HAL_EINVAL;
    }
    const int32_t h = semihost_open(path, SEMIHOST_MODE_RB);
    if (h >= 0) {
        size_t got = 0u;
        int32_t n = 1;
        while (n > 0 && got < HAL_SEMIHOST_NVM_SIZE) {
            n = semihost_read(h, &hal->nvm[got], HAL_SEMIHOST_NVM_SIZE - got);
            got += n > 0 ? (size_t)n : 0u;
        }
        uint8_t extra = 0u;
        const int32_t more = semihost_read(h, &extra, 1u);
        (void)semihost_close(h);
        if (got != HAL_SEMIHOST_NVM_SIZE || more != 0) {
            for (size_t k = 0u; k < HAL_SEMIHOST_NVM_SIZE; k++) {
                hal->nvm[k] = 0xFFu;
            }
            return HAL_EIO;
        }
    }
    hal->nvm_path = path;
    return 0;
}

int hal_semihost_close(hal_t *hal)
{
    int rc = tx_flush(hal);
    if (hal->nvm_path != NULL) {
        const int32_t h = semihost_open(hal->nvm_path, SEMIHOST_MODE_WB);
        if (h < 0 || semihost_write(h, hal->nvm, HAL_SEMIHOST_NVM_SIZE) != 0) {
            rc = HAL_EIO;
        }
        if (h >= 0) {
            (void)semihost_close(h);
        }
        hal->nvm_path = NULL;
    }
    if (hal->rx >= 0) {
        (void)semihost_close(hal->rx);
        hal->rx = -1;
    }
    if (hal->tx >= 0) {
        (void)semihost_close(hal->tx);
        hal->tx = -1;
    }
    return rc;
}

/* next byte of the RX log (candump_read's byte source) */
static int rx_byte(void *ctx)
{
    hal_t *hal = ctx;
    if (hal->rx_pos == hal->rx_len) {
        const int32_t n = semihost_read(hal->rx, hal->rx_buf, sizeof hal->rx_buf);
        if (n < 0) {
            return CANDUMP_SRC_ERROR;
        }
        if (n == 0) {
            return CANDUMP_SRC_END;
        }
        hal->rx_pos = 0u;
        hal->rx_len = (size_t)n;
    }
    return (int)(unsigned char)hal->rx_buf[hal->rx_pos++];
}

int hal_can_receive(hal_t *hal, hal_can_frame_t *f)
{
    if (hal == NULL || f == NULL) {
        return HAL_EINVAL;
    }
    if (hal->rx < 0) {
        return HAL_ENODATA;
    }
    return candump_replay(&hal->rx_log, rx_byte, hal, hal->line, HAL_SEMIHOST_LINE_MAX, f);
}

uint32_t hal_can_rx_lost(const hal_t *hal)
{
    return hal->rx_log.malformed;
}

uint32_t hal_faults(hal_t *hal)
{
    (void)hal;
    return 0u; /* QEMU's board: no watchdog, a log for a bus */
}

uint64_t hal_time_us(const hal_t *hal)
{
    return hal->rx_log.t_us;
}

int hal_can_send(hal_t *hal, const hal_can_frame_t *f)
{
    if (hal == NULL || f == NULL || f->dlc > 8u || f->extended > 1u ||
        f->id > (f->extended != 0u ? 0x1FFFFFFFu : 0x7FFu)) {
        return HAL_EINVAL;
    }
    if (hal->tx_error != 0u) {
        return HAL_EIO;
    }
    if (hal->tx >= 0) {
        if (HAL_SEMIHOST_TX_BUF - hal->tx_len < CANDUMP_FORMAT_MAX && tx_flush(hal) != 0) {
            return HAL_EIO;
        }
        const size_t len = candump_format_line(hal->tx_buf + hal->tx_len,
                                               HAL_SEMIHOST_TX_BUF - hal->tx_len, hal->rx_log.t_us,
                                               "can0", f);
        if (len == 0u) {
            return HAL_EIO; /* cannot happen: the frame was checked, the buffer has room */
        }
        hal->tx_len += len;
    }
    hal->tx_frames = sat_inc_u32(hal->tx_frames);
    return 0;
}

size_t hal_nvm_size(const hal_t *hal)
{
    (void)hal;
    return HAL_SEMIHOST_NVM_SIZE;
}

size_t hal_nvm_sector_size(const hal_t *hal)
{
    (void)hal;
    return HAL_SEMIHOST_NVM_SECTOR_SIZE;
}

int hal_nvm_read(hal_t *hal, size_t offset, void *buf, size_t len)
{
    if (hal == NULL || !nvm_flash_args_ok(HAL_SEMIHOST_NVM_SIZE, offset, buf, len)) {
        return HAL_EINVAL;
    }
    uint8_t *dst = buf;
    for (size_t k = 0u; k < len; k++) {
        dst[k] = hal->nvm[offset + k];
    }
    return 0;
}

int hal_nvm_write(hal_t *hal, size_t offset, const void *buf, size_t len)
{
    if (hal == NULL || !nvm_flash_args_ok(HAL_SEMIHOST_NVM_SIZE, offset, buf, len)) {
        return HAL_EINVAL;
    }
    /* flash programming only clears bits */
    const int verify_failed = nvm_flash_program(&hal->nvm[offset], &hal->nvm[offset], buf, len);
    return verify_failed ? HAL_EIO : 0;
}

int hal_nvm_erase_sector(hal_t *hal, size_t sector)
{
    if (hal == NULL || sector >= HAL_SEMIHOST_NVM_SIZE / HAL_SEMIHOST_NVM_SECTOR_SIZE) {
        return HAL_EINVAL;
    }
    for (size_t k = 0u; k < HAL_SEMIHOST_NVM_SECTOR_SIZE; k++) {
        hal->nvm[sector * HAL_SEMIHOST_NVM_SECTOR_SIZE + k] = 0xFFu;
    }
    return 0;
}

int hal_nvm_erase(hal_t *hal)
{
    for (size_t s = 0u; s < HAL_SEMIHOST_NVM_SIZE / HAL_SEMIHOST_NVM_SECTOR_SIZE; s++) {
        const int rc = hal_nvm_erase_sector(hal, s);
        if (rc != 0) {
            return rc;
        }
    }
    return 0;
}

void hal_watchdog_kick(hal_t *hal)
{
    hal->watchdog_kicks++;
}

int hal_bootloader(hal_t *hal, int go)
{
    (void)hal;
    (void)go;
    return HAL_EIO; /* the QEMU image replays one log: no reset into the bootloader */
}
