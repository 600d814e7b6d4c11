/*
 * fake_hal.h - an in-memory HAL for application tests: frames to receive are queued by the
 * test, transmitted frames are captured, NVM is a RAM array that can be told to fail.
 */
#ifndef NAVECU_TEST_FAKE_HAL_H
#define NAVECU_TEST_FAKE_HAL_H

#include "hal.h"

#define FAKE_TX_MAX 8192u
#define FAKE_NVM_SIZE 256u

struct hal {
    hal_can_frame_t tx[FAKE_TX_MAX];
    uint32_t tx_n;
    uint32_t tx_dropped;   /* sends beyond FAKE_TX_MAX */
    uint64_t t_us;         /* what hal_time_us returns */
    uint32_t malformed;    /* what hal_can_rx_malformed returns */
    uint8_t nvm[FAKE_NVM_SIZE];
    int nvm_fail;          /* 1: NVM operations return HAL_EIO */
    uint32_t kicks;
};

void fake_hal_reset(hal_t *hal);

#endif
