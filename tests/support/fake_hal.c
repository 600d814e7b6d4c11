/* fake_hal.c - see fake_hal.h. Tests of a single frame call app_handle_frame; the receive
 * queue is for the main loop's pass (app_loop.h). */
#include "fake_hal.h"

#include <string.h>

void fake_hal_reset(hal_t *hal)
{
    memset(hal, 0, sizeof *hal);
    memset(hal->nvm, 0xFF, sizeof hal->nvm);
    hal->rx_empty_rc = HAL_ENODATA;
}

int fake_hal_rx_push(hal_t *hal, const hal_can_frame_t *f)
{
    if (hal->rx_n >= FAKE_RX_MAX) {
        return -1;
    }
    hal->rx[hal->rx_n++] = *f;
    return 0;
}

uint32_t fake_hal_rx_left(const hal_t *hal)
{
    return hal->rx_n - hal->rx_head;
}

int hal_can_receive(hal_t *hal, hal_can_frame_t *f)
{
    hal->rx_calls++;
    if (hal->rx_head >= hal->rx_n) {
        return hal->rx_empty_rc;
    }
    *f = hal->rx[hal->rx_head++];
    if (f->t_us > hal->t_us) {
        hal->t_us = f->t_us; /* the HAL clock goes on with the bus */
    }
    return 0;
}

int hal_can_send(hal_t *hal, const hal_can_frame_t *f)
{
    if (f->dlc > 8u) {
        return HAL_EINVAL;
    }
    if (hal->tx_n >= FAKE_TX_MAX) {
        hal->tx_dropped++;
        return HAL_ENOSPC;
    }
    hal->tx[hal->tx_n] = *f;
    hal->tx[hal->tx_n].t_us = hal->t_us;
    hal->tx_n++;
    return 0;
}

uint32_t hal_can_rx_lost(const hal_t *hal)
{
    return hal->rx_lost;
}

uint32_t hal_faults(hal_t *hal)
{
    const uint32_t f = hal->faults;
    hal->faults &= ~HAL_FAULT_BUS_OFF; /* an event: reading clears it */
    return f;
}

uint64_t hal_time_us(const hal_t *hal)
{
    return hal->t_us;
}

size_t hal_nvm_size(const hal_t *hal)
{
    (void)hal;
    return FAKE_NVM_SIZE;
}

size_t hal_nvm_sector_size(const hal_t *hal)
{
    (void)hal;
    return FAKE_NVM_SECTOR_SIZE;
}

void fake_hal_nvm_cut_after(hal_t *hal, uint32_t n_units, uint8_t torn)
{
    hal->nvm_cut_armed = 1;
    hal->nvm_cut_left = n_units;
    hal->nvm_cut_torn = torn;
}

void fake_hal_nvm_power_on(hal_t *hal)
{
    hal->nvm_cut_armed = 0;
    hal->nvm_power_off = 0;
}

void fake_hal_nvm_corrupt(hal_t *hal, size_t offset, uint8_t xor_mask)
{
    if (offset < FAKE_NVM_SIZE) {
        hal->nvm[offset] ^= xor_mask;
    }
}

/* 1 if the next unit is the one the power is cut on (the power is then off) */
static int nvm_unit_cut(hal_t *hal)
{
    if (hal->nvm_cut_armed) {
        if (hal->nvm_cut_left == 0u) {
            hal->nvm_cut_armed = 0;
            hal->nvm_power_off = 1;
            return 1;
        }
        hal->nvm_cut_left--;
    }
    hal->nvm_units++;
    return 0;
}

static int nvm_range_ok(size_t offset, size_t len)
{
    return offset <= FAKE_NVM_SIZE && len <= FAKE_NVM_SIZE - offset;
}

int hal_nvm_read(hal_t *hal, size_t offset, void *buf, size_t len)
{
    if (hal->nvm_fail || hal->nvm_power_off) {
        return HAL_EIO;
    }
    if ((buf == NULL && len > 0u) || !nvm_range_ok(offset, len)) {
        return HAL_EINVAL;
    }
    if (len > 0u) {
        memcpy(buf, hal->nvm + offset, len);
    }
    return 0;
}

int hal_nvm_write(hal_t *hal, size_t offset, const void *buf, size_t len)
{
    if (hal->nvm_fail || hal->nvm_power_off) {
        return HAL_EIO;
    }
    if ((buf == NULL && len > 0u) || !nvm_range_ok(offset, len)) {
        return HAL_EINVAL;
    }
    const uint8_t *src = buf;
    int verify_failed = 0;
    for (size_t n = 0u; n < len; n++) {
        const size_t k = hal->nvm_program_backwards ? len - 1u - n : n;
        uint8_t *cell = &hal->nvm[offset + k];
        if (nvm_unit_cut(hal)) {
            *cell = (uint8_t)(*cell & (src[k] | (uint8_t)~hal->nvm_cut_torn));
            return HAL_EIO;
        }
        *cell = (uint8_t)(*cell & src[k]);
        if (*cell != src[k]) {
            verify_failed = 1;
        }
    }
    return verify_failed ? HAL_EIO : 0;
}

int hal_nvm_erase_sector(hal_t *hal, size_t sector)
{
    if (hal->nvm_fail || hal->nvm_power_off) {
        return HAL_EIO;
    }
    if (sector >= FAKE_NVM_SECTORS) {
        return HAL_EINVAL;
    }
    uint8_t *base = &hal->nvm[sector * FAKE_NVM_SECTOR_SIZE];
    if (nvm_unit_cut(hal)) {
        for (size_t k = 0u; k < FAKE_NVM_SECTOR_SIZE; k += 2u) {
            base[k] = 0xFFu;
        }
        return HAL_EIO;
    }
    memset(base, 0xFF, FAKE_NVM_SECTOR_SIZE);
    return 0;
}

int hal_nvm_erase(hal_t *hal)
{
    for (size_t k = 0u; k < FAKE_NVM_SECTORS; k++) {
        const int rc = hal_nvm_erase_sector(hal, k);
        if (rc != 0) {
            return rc;
        }
    }
    return 0;
}

void hal_watchdog_kick(hal_t *hal)
{
    hal->kicks++;
}

int hal_bootloader(hal_t *hal, int go)
{
    if (!hal->has_bootloader) {
        return HAL_EIO;
    }
    if (go) {
        hal->bootloader_entered++; /* a real board would not return */
    }
    return 0;
}
