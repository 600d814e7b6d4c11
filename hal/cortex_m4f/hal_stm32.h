/*
 * hal_stm32.h - the HAL of hal.h on the ECU: an STM32F405/F407 at 168 MHz (docs/target.md,
 * docs/porting.md). It ties the register-level drivers together:
 *   clocks        stm32_clock.[ch]     8 MHz HSE -> PLL 168 MHz, APB1 42 MHz, flash 5 WS
 *   CAN           bxcan.[ch]           CAN1 on PB8 (RX) / PB9 (TX), 500 kbit/s, ID-list
 *                                      filters from the application's receive IDs, RX by
 *                                      interrupt into a 64-frame ring
 *   time          stm32_timebase.[ch]  TIM2 at 1 MHz extended to 64 bits
 *   NVM           stm32_flash.[ch]     flash sectors 1 and 2 (2 x 16 KiB at 0x08004000;
 *                                      kept out of the image by stm32f405.ld)
 *   watchdog      stm32_iwdg.[ch]      200 ms nominal (136..376 ms over the LSI's spread),
 *                                      raised to 2 s around a sector erase
 * One instance, owned here (the interrupt handlers need it); nothing is allocated.
 */
#ifndef NAVECU_HAL_STM32_H
#define NAVECU_HAL_STM32_H

#include <stddef.h>
#include <stdint.h>

#include "bxcan.h"
#include "hal.h"
#include "stm32_clock.h"
#include "stm32_flash.h"
#include "stm32_iwdg.h"
#include "stm32_timebase.h"

struct hal {
    bxcan_t can;
    stm32_flash_t flash;
    stm32_iwdg_t iwdg;
    stm32_timebase_t time;
    stm32_clock_status_t clock; /* what stm32_clock_init reached */
    uint32_t init_faults;       /* bit 0 clock (running on HSI), 1 CAN, 2 NVM, 3 watchdog */
    uint32_t can_tx_full;       /* sends refused: every mailbox pending */
    uint32_t bus_off_told;      /* the driver's bus-off count hal_faults last reported */
};

#define HAL_STM32_FAULT_CLOCK 0x1u
#define HAL_STM32_FAULT_CAN 0x2u
#define HAL_STM32_FAULT_NVM 0x4u
#define HAL_STM32_FAULT_WATCHDOG 0x8u

/* hal_bootloader's request to the bootloader: this word and its complement in the last
 * 16 bytes of SRAM, above the stack (the values of firmware/boot/boot_image.h
 * BOOT_REQUEST_ADDR / BOOT_REQUEST_MAGIC, which hal/ does not include:
 * boards/stm32f405/boot_main.c asserts that they are equal) */
#define HAL_STM32_BOOT_REQUEST_ADDR 0x2001FFF0u
#define HAL_STM32_BOOT_REQUEST_MAGIC 0xB007F1A5u

/*
 * Bring the board up: clocks, peripheral clocks, CAN pins, TIM2, bxCAN with filters for
 * rx_ids[0..n_ids), its interrupts in the NVIC, the flash NVM driver, and the watchdog
 * (started: from here on hal_watchdog_kick must be called at least every 100 ms). A
 * step that fails is recorded in init_faults and the board goes on with what works (a
 * clock fault leaves the CPU on the 16 MHz HSI: CAN timing is then wrong and CAN is not
 * started). Returns the HAL instance.
 */
hal_t *hal_stm32_init(const uint32_t *rx_ids, size_t n_ids);

/* 1 when a received frame waits in the CAN ring (checked with interrupts masked before the
 * main loop sleeps, so a frame that arrived after the last receive is not left waiting). */
int hal_stm32_rx_pending(const hal_t *hal);

#endif /* NAVECU_HAL_STM32_H */
