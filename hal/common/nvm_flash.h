/*
 * nvm_flash.h - the NOR-flash rules of hal.h's NVM for HALs that keep the region in RAM
 * (the Linux host, the QEMU semihosting image): the argument check every NVM call makes,
 * and what a write leaves behind. The ECU's flash does this in hardware
 * (hal/cortex_m4f/stm32_flash.c); tests/support/fake_hal.c adds power cuts.
 */
#ifndef NAVECU_NVM_FLASH_H
#define NAVECU_NVM_FLASH_H

#include <stddef.h>
#include <stdint.h>

/* 1 when hal.h's NVM arguments are valid for a region of `size` bytes: buf is not NULL
 * unless len is 0, and [offset, offset + len) lies inside it (no overflow). */
int nvm_flash_args_ok(size_t size, size_t offset, const void *buf, size_t len);

/* Program len bytes: out[k] = old[k] AND src[k] (a write only clears bits; out may be
 * old). Returns 1 when some byte then differs from src (hal.h's program-verify failure,
 * HAL_EIO), else 0. */
int nvm_flash_program(uint8_t *out, const uint8_t *old, const uint8_t *src, size_t len);

#endif /* NAVECU_NVM_FLASH_H */
