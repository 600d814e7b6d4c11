/* fake_hal.c - see fake_hal.h. Receiving is not faked: tests call app_handle_frame. */
#include "fake_hal.h"

#include <string.h>

void fake_hal_reset(hal_t *hal)
{
    memset(hal, 0, sizeof *hal);
    memset(hal->nvm, 0xFF, sizeof hal->nvm);
}

int hal_can_receive(hal_t *hal, hal_can_frame_t *f)
{
    (void)hal;
    (void)f;
    return HAL_ENODATA;
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

uint32_t hal_can_rx_malformed(const hal_t *hal)
{
    return hal->malformed;
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

int hal_nvm_read(hal_t *hal, size_t offset, void *buf, size_t len)
{
    if (hal->nvm_fail) {
        return HAL_EIO;
    }
    if (offset > FAKE_NVM_SIZE || len > FAKE_NVM_SIZE - offset) {
        return HAL_EINVAL;
    }
    memcpy(buf, hal->nvm + offset, len);
    return 0;
}

int hal_nvm_write(hal_t *hal, size_t offset, const void *buf, size_t len)
{
    if (hal->nvm_fail) {
        return HAL_EIO;
    }
    if (offset > FAKE_NVM_SIZE || len > FAKE_NVM_SIZE - offset) {
        return HAL_EINVAL;
    }
    memcpy(hal->nvm + offset, buf, len);
    return 0;
}

int hal_nvm_erase(hal_t *hal)
{
    if (hal->nvm_fail) {
        return HAL_EIO;
    }
    memset(hal->nvm, 0xFF, sizeof hal->nvm);
    return 0;
}

void hal_watchdog_kick(hal_t *hal)
{
    hal->kicks++;
}
