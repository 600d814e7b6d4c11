/*
 * hal_stm32.c - the HAL of hal.h on the STM32F405 ECU (contracts in hal_stm32.h and hal.h).
 */
#include "hal_stm32.h"

/* peripheral base addresses (RM0090 table 1) */
#define RCC_BASE 0x40023800u
#define PWR_BASE 0x40007000u
#define FLASH_IF_BASE 0x40023C00u
#define CAN1_BASE 0x40006400u
#define TIM2_BASE 0x40000000u
#define IWDG_BASE 0x40003000u
#define GPIOB_BASE 0x40020400u
#define NVM_WINDOW 0x08004000u /* sectors 1 and 2 (stm32f405.ld) */
#define NVM_SECTOR_BYTES 16384u

/* GPIO port registers (RM0090 8.4): MODER 0x00, OSPEEDR 0x08, AFRH 0x24 */
#define GPIOB_MODER (*(volatile uint32_t *)(GPIOB_BASE + 0x00u))
#define GPIOB_OSPEEDR (*(volatile uint32_t *)(GPIOB_BASE + 0x08u))
#define GPIOB_AFRH (*(volatile uint32_t *)(GPIOB_BASE + 0x24u))
#define GPIO_AF9_CAN1 9u

/* NVIC (ARMv7-M B3.4): interrupt set-enable and priority registers */
#define NVIC_ISER0 (*(volatile uint32_t *)0xE000E100u)
#define NVIC_IPR_BYTE(irq) (*(volatile uint8_t *)(0xE000E400u + (irq)))
#define IRQ_CAN1_RX0 20u
#define IRQ_CAN1_SCE 22u

/* polls of each hardware wait: generous bounds, the loops poll registers (a few cycles
 * each at 168 MHz); a flash erase stalls the poll itself, so few polls pass there */
#define CLOCK_POLLS 200000u
#define CAN_POLLS 200000u
#define FLASH_POLLS 2000000u
#define IWDG_POLLS 100000u

static hal_t board;

static void watchdog_hook(void *ctx)
{
    stm32_iwdg_kick((stm32_iwdg_t *)ctx);
}

/* PB8 = CAN1_RX, PB9 = CAN1_TX: alternate function 9, fast speed */
static void can_pins(void)
{
    GPIOB_MODER = (GPIOB_MODER & ~(0xFu << 16)) | (0xAu << 16);      /* pins 8, 9: AF */
    GPIOB_OSPEEDR = (GPIOB_OSPEEDR & ~(0xFu << 16)) | (0xAu << 16);  /* 0b10: fast speed */
    GPIOB_AFRH = (GPIOB_AFRH & ~0xFFu) | (GPIO_AF9_CAN1 << 0) | (GPIO_AF9_CAN1 << 4);
}

hal_t *hal_stm32_init(const uint32_t *rx_ids, size_t n_ids)
{
    hal_t *h = &board;
    const stm32_clock_config_t clk = {(stm32_rcc_regs_t *)RCC_BASE, (stm32_pwr_regs_t *)PWR_BASE,
                                      (stm32_flash_regs_t *)FLASH_IF_BASE, 0u, CLOCK_POLLS,
                                      NULL, NULL};
    const int clk_rc = stm32_clock_init(&clk, &h->clock);
    if (clk_rc == HAL_EINVAL) {
        /* not from the reset state (a bootloader set the clocks up): take them as they are */
        (void)stm32_clock_status(clk.rcc, &h->clock);
        if (h->clock.pclk1_hz != 42000000u) {
            h->init_faults |= HAL_STM32_FAULT_CLOCK; /* the CAN bit timing needs 42 MHz */
        }
    } else if (clk_rc != 0) {
        h->init_faults |= HAL_STM32_FAULT_CLOCK;
    }
    (void)stm32_clock_enable_peripherals(clk.rcc);
    if (stm32_timebase_init(&h->time, (stm32_tim_regs_t *)TIM2_BASE, h->clock.tim_apb1_hz) != 0) {
        h->init_faults |= HAL_STM32_FAULT_CLOCK; /* hal_time_us then stays 0 */
    }

    const stm32_iwdg_config_t wd = {(stm32_iwdg_regs_t *)IWDG_BASE,
                                    STM32_IWDG_DEFAULT_TIMEOUT_MS, IWDG_POLLS, NULL, NULL};
    if (stm32_iwdg_init(&h->iwdg, &wd) != 0) {
        h->init_faults |= HAL_STM32_FAULT_WATCHDOG;
    }

    stm32_flash_config_t fl = {0};
    fl.regs = (stm32_flash_regs_t *)FLASH_IF_BASE;
    fl.window = (volatile uint8_t *)NVM_WINDOW;
    fl.sector_numbers[0] = 1u;
    fl.sector_numbers[1] = 2u;
    fl.n_sectors = 2u;
    fl.sector_size_bytes = NVM_SECTOR_BYTES;
    fl.timeout_polls = FLASH_POLLS;
    fl.wait_hook = watchdog_hook;
    fl.hook_ctx = &h->iwdg;
    if (stm32_flash_init(&h->flash, &fl) != 0) {
        h->init_faults |= HAL_STM32_FAULT_NVM;
    }

    if ((h->init_faults & HAL_STM32_FAULT_CLOCK) == 0u) {
        can_pins();
        const bxcan_config_t cc = {BXCAN_BTR_42MHZ_500K, CAN_POLLS, watchdog_hook, &h->iwdg};
        if (bxcan_init(&h->can, (bxcan_regs_t *)CAN1_BASE, &cc) != 0 ||
            bxcan_set_filters(&h->can, rx_ids, n_ids) != 0) {
            h->init_faults |= HAL_STM32_FAULT_CAN;
        } else {
            /* RX above SCE: a bus-off report may wait, a frame may not */
            NVIC_IPR_BYTE(IRQ_CAN1_RX0) = 0x40u;
            NVIC_IPR_BYTE(IRQ_CAN1_SCE) = 0x80u;
            NVIC_ISER0 = (1u << IRQ_CAN1_RX0) | (1u << IRQ_CAN1_SCE);
        }
    } else {
        h->init_faults |= HAL_STM32_FAULT_CAN;
    }
    return h;
}

void CAN1_RX0_IRQHandler(void);
void CAN1_SCE_IRQHandler(void);

void CAN1_RX0_IRQHandler(void)
{
    bxcan_rx0_irq(&board.can, stm32_timebase_us(&board.time));
}

void CAN1_SCE_IRQHandler(void)
{
    bxcan_sce_irq(&board.can);
}

int hal_can_receive(hal_t *hal, hal_can_frame_t *f)
{
    if (hal == NULL) {
        return HAL_EINVAL;
    }
    return bxcan_receive(&hal->can, f);
}

int hal_can_send(hal_t *hal, const hal_can_frame_t *f)
{
    if (hal == NULL) {
        return HAL_EINVAL;
    }
    if ((hal->init_faults & HAL_STM32_FAULT_CAN) != 0u) {
        return HAL_EIO;
    }
    const int rc = bxcan_send(&hal->can, f);
    if (rc == HAL_ENOSPC && hal->can_tx_full != UINT32_MAX) {
        hal->can_tx_full++;
    }
    return rc;
}

uint32_t hal_can_rx_lost(const hal_t *hal)
{
    /* a controller delivers only well-formed frames: what it loses is overruns, the ring's
     * frames and the FIFO's events (at least one frame each); wraps, as the driver's counts */
    bxcan_stats_t s;
    (void)bxcan_stats(&hal->can, &s);
    return s.rx_ring_overruns + s.rx_fifo_overruns;
}

uint32_t hal_faults(hal_t *hal)
{
    bxcan_stats_t s;
    (void)bxcan_stats(&hal->can, &s);
    uint32_t f = 0u;
    if ((hal->init_faults & HAL_STM32_FAULT_WATCHDOG) != 0u) {
        f = HAL_FAULT_WATCHDOG;
    }
    if (s.bus_off_events != hal->bus_off_told) {
        hal->bus_off_told = s.bus_off_events;
        f |= HAL_FAULT_BUS_OFF;
    }
    return f;
}

uint64_t hal_time_us(const hal_t *hal)
{
    /* the timebase's state is written on read (volatile, interrupt-safe by design) */
    return stm32_timebase_us((stm32_timebase_t *)&hal->time);
}

size_t hal_nvm_size(const hal_t *hal)
{
    return hal == NULL ? 0u : stm32_flash_size(&hal->flash);
}

size_t hal_nvm_sector_size(const hal_t *hal)
{
    return hal == NULL ? 0u : stm32_flash_sector_size(&hal->flash);
}

int hal_nvm_read(hal_t *hal, size_t offset, void *buf, size_t len)
{
    if (hal == NULL) {
        return HAL_EINVAL;
    }
    return stm32_flash_read(&hal->flash, offset, buf, len);
}

int hal_nvm_write(hal_t *hal, size_t offset, const void *buf, size_t len)
{
    if (hal == NULL) {
        return HAL_EINVAL;
    }
    return stm32_flash_write(&hal->flash, offset, buf, len);
}

int hal_nvm_erase_sector(hal_t *hal, size_t sector)
{
    if (hal == NULL) {
        return HAL_EINVAL;
    }
    /* a 16 KiB erase takes up to 500 ms, longer than the watchdog's 136 ms worst case,
     * and the CPU stalls on flash meanwhile: the timeout is raised around it */
    if (stm32_iwdg_set_timeout(&hal->iwdg, STM32_IWDG_ERASE_TIMEOUT_MS) != 0) {
        return HAL_EIO; /* erasing under the short timeout would reset the ECU mid-erase */
    }
    const int rc = stm32_flash_erase_sector(&hal->flash, sector);
    (void)stm32_iwdg_set_timeout(&hal->iwdg, STM32_IWDG_DEFAULT_TIMEOUT_MS);
    return rc;
}

int hal_nvm_erase(hal_t *hal)
{
    if (hal == NULL) {
        return HAL_EINVAL;
    }
    const size_t sector_bytes = hal_nvm_sector_size(hal);
    if (sector_bytes == 0u) {
        return HAL_EIO; /* the flash driver did not initialise (HAL_STM32_FAULT_NVM) */
    }
    for (size_t s = 0u; s < hal_nvm_size(hal) / sector_bytes; s++) {
        const int rc = hal_nvm_erase_sector(hal, s);
        if (rc != 0) {
            return rc;
        }
    }
    return 0;
}

int hal_stm32_rx_pending(const hal_t *hal)
{
    return bxcan_rx_pending(&hal->can);
}

void hal_watchdog_kick(hal_t *hal)
{
    stm32_iwdg_kick(&hal->iwdg);
}

#define TX_DRAIN_POLLS 200000u /* about 10 ms at 168 MHz: 3 frames take 0.7 ms at 500 kbit/s */

int hal_bootloader(hal_t *hal, int go)
{
    if (hal == NULL) {
        return HAL_EINVAL;
    }
    if (!go) {
        return 0; /* the application is linked behind the bootloader (stm32f405.ld) */
    }
    const uint32_t empty = BXCAN_TSR_TME0 | BXCAN_TSR_TME1 | BXCAN_TSR_TME2;
    uint32_t polls = (hal->init_faults & HAL_STM32_FAULT_CAN) == 0u ? TX_DRAIN_POLLS : 0u;
    while (polls > 0u && (hal->can.regs->TSR & empty) != empty) {
        polls--;
    }
    volatile uint32_t *request = (volatile uint32_t *)HAL_STM32_BOOT_REQUEST_ADDR;
    request[0] = HAL_STM32_BOOT_REQUEST_MAGIC;
    request[1] = ~HAL_STM32_BOOT_REQUEST_MAGIC;
    __asm__ volatile("dsb" ::: "memory");
    *(volatile uint32_t *)0xE000ED0Cu = 0x05FA0004u; /* AIRCR SYSRESETREQ */
    __asm__ volatile("dsb" ::: "memory");
    for (;;) {
    }
}
