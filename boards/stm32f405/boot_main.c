/*
 * boards/stm32f405/boot_main.c - the bootloader of the navecu ECU (issue #19,
 * docs/target.md "The bootloader"), in sector 0 (boot.ld).
 *
 * At reset: unless the application asked to stay (BOOT_REQUEST_ADDR, written by the
 * application before its reset for a UDS programming session), check the application
 * (firmware/boot/boot.c boot_image_check: marker, CRC-32 over the flash, vectors) and start
 * it: VTOR, MSP, reset vector, with nothing initialised yet. Otherwise bring the board up
 * with the application's HAL (hal_stm32_init: clocks, time base, watchdog, CAN1 on PB8/PB9
 * with one filter for the request ID) and serve UDS on BOOT_RX_ID / BOOT_TX_ID until an
 * ECUReset, which resets the MCU (and so checks the image again).
 *
 * The application's sectors 3 (16 KiB) and 4 (64 KiB) go through the register-level
 * driver of the NVM (stm32_flash.c), one instance per sector size; the NVM sectors 1-2
 * are never part of them.
 */
#include <stdint.h>

#include "boot.h"
#include "hal_stm32.h"

/* the diagnostic IDs: the application's defaults (app_config.h uds_request_id /
 * uds_response_id, not stored in NVM), a build may define others */
#ifndef BOOT_RX_ID
#define BOOT_RX_ID 0x7A0u
#endif
#ifndef BOOT_TX_ID
#define BOOT_TX_ID 0x7A8u
#endif

_Static_assert(BOOT_REQUEST_ADDR == HAL_STM32_BOOT_REQUEST_ADDR &&
                   BOOT_REQUEST_MAGIC == HAL_STM32_BOOT_REQUEST_MAGIC,
               "the application's request (hal_stm32.h) is not where the bootloader looks");

#define SCB_VTOR (*(volatile uint32_t *)0xE000ED08u)
#define SCB_AIRCR (*(volatile uint32_t *)0xE000ED0Cu)
#define FLASH_IF_BASE 0x40023C00u
#define FLASH_POLLS 2000000u

static boot_t boot;
static stm32_flash_t sector3, sector4;
static hal_t *board_hal;

void board_main(void) __attribute__((noreturn));

static void kick(void *ctx)
{
    stm32_iwdg_kick((stm32_iwdg_t *)ctx);
}

#define IWDG_KR (*(volatile uint32_t *)0x40003000u)

static int fl_read(void *ctx, uint32_t addr, uint8_t *buf, size_t len)
{
    (void)ctx;
    /* the image check at reset runs before anything is set up, and a watchdog the
     * application started keeps running through a reset: kick it (harmless when off) */
    IWDG_KR = 0xAAAAu;
    for (size_t k = 0u; k < len; k++) {
        buf[k] = *(const volatile uint8_t *)(addr + (uint32_t)k);
    }
    return 0;
}

static int fl_write(void *ctx, uint32_t addr, const uint8_t *buf, size_t len)
{
    (void)ctx;
    const uint32_t s4 = BOOT_APP_START + BOOT_APP_SECTOR3_SIZE;
    size_t n3 = 0u;
    if (addr < s4) {
        n3 = (size_t)(s4 - addr) < len ? (size_t)(s4 - addr) : len;
        const int rc = stm32_flash_write(&sector3, addr - BOOT_APP_START, buf, n3);
        if (rc != 0) {
            return rc;
        }
    }
    if (n3 == len) {
        return 0;
    }
    return stm32_flash_write(&sector4, addr + (uint32_t)n3 - s4, &buf[n3], len - n3);
}

static int fl_erase(void *ctx, size_t sector)
{
    (void)ctx;
    /* up to 1.1 s for 64 KiB (x32), the CPU stalled on the flash meanwhile: the watchdog
     * runs with its erase timeout around it, as the application's NVM erase */
    if (stm32_iwdg_set_timeout(&board_hal->iwdg, STM32_IWDG_ERASE_TIMEOUT_MS) != 0) {
        return HAL_EIO;
    }
    const int rc = stm32_flash_erase_sector(sector == 0u ? &sector3 : &sector4, 0u);
    (void)stm32_iwdg_set_timeout(&board_hal->iwdg, STM32_IWDG_DEFAULT_TIMEOUT_MS);
    return rc;
}

static const boot_flash_t flash = {NULL, fl_read, fl_write, fl_erase};

static int tx(void *user, const hal_can_frame_t *f)
{
    return hal_can_send((hal_t *)user, f);
}

static void mcu_reset(void) __attribute__((noreturn));
static void mcu_reset(void)
{
    __asm__ volatile("dsb" ::: "memory");
    SCB_AIRCR = 0x05FA0004u; /* SYSRESETREQ */
    __asm__ volatile("dsb" ::: "memory");
    for (;;) {
    }
}

static void start_application(void) __attribute__((noreturn));
static void start_application(void)
{
    const volatile uint32_t *v = (const volatile uint32_t *)BOOT_APP_START;
    const uint32_t sp = v[0];
    const uint32_t pc = v[1];
    SCB_VTOR = BOOT_APP_START;
    __asm__ volatile("dsb\n\tisb\n\tmsr msp, %0\n\tbx %1" : : "r"(sp), "r"(pc) : "memory");
    for (;;) {
    }
}

static void init_sector(stm32_flash_t *dev, uint8_t number, uint32_t addr, uint32_t size)
{
    stm32_flash_config_t c = {0};
    c.regs = (stm32_flash_regs_t *)FLASH_IF_BASE;
    c.window = (volatile uint8_t *)addr;
    c.sector_numbers[0] = number;
    c.n_sectors = 1u;
    c.sector_size_bytes = size;
    c.timeout_polls = FLASH_POLLS;
    c.wait_hook = kick;
    c.hook_ctx = &board_hal->iwdg;
    (void)stm32_flash_init(dev, &c); /* constant, valid configuration */
}

void board_main(void)
{
    volatile uint32_t *request = (volatile uint32_t *)BOOT_REQUEST_ADDR;
    int stay = 0;
    if (request[0] == BOOT_REQUEST_MAGIC && request[1] == ~BOOT_REQUEST_MAGIC) {
        stay = 1;
    }
    request[0] = 0u;
    request[1] = 0u;
    if (!stay && boot_image_check(&flash) == BOOT_IMAGE_OK) {
        start_application();
    }
    static const uint32_t rx_ids[1] = {BOOT_RX_ID};
    board_hal = hal_stm32_init(rx_ids, 1u);
    init_sector(&sector3, 3u, BOOT_APP_START, BOOT_APP_SECTOR3_SIZE);
    init_sector(&sector4, 4u, BOOT_APP_START + BOOT_APP_SECTOR3_SIZE, BOOT_APP_SECTOR4_SIZE);
    (void)boot_init(&boot, &flash, BOOT_RX_ID, BOOT_TX_ID, tx, board_hal,
                    (uint32_t)hal_time_us(board_hal) ^ 0x5A5A1234u);
    if (stay) {
        boot_programming_requested(&boot, hal_time_us(board_hal)); /* 50 02: the pending answer */
    }
    for (;;) {
        hal_can_frame_t f;
        while (hal_can_receive(board_hal, &f) == 0) {
            boot_frame(&boot, &f, hal_time_us(board_hal));
        }
        if (boot_poll(&boot, hal_time_us(board_hal))) {
            mcu_reset(); /* the ECUReset's response left: check the image again */
        }
        hal_watchdog_kick(board_hal);
    }
}
