/*
 * stm32_flash.h - register-level driver for the STM32F405 embedded flash (the FLASH
 * interface at 0x40023C00), used by the Cortex-M4F HAL (hal/cortex_m4f/) for the
 * non-volatile region of hal/hal.h (hal_nvm_*).
 *
 * The driver touches the flash interface only through a stm32_flash_regs_t pointer and
 * reads/programs the memory only through a window pointer (the first byte of the NVM
 * region), so the host tests (tests/test_stm32_flash.c) run it against a register block
 * and a byte array in RAM and play the hardware. It includes no OS header, never
 * allocates, and never waits without a bound.
 *
 * Typical use on the board (sectors 1 and 2: 16 KiB each at 0x08004000 and 0x08008000,
 * cut out of the linker script's FLASH region; docs/porting.md):
 *
 *     static stm32_flash_t nvm;
 *     stm32_flash_config_t cfg = {
 *         (stm32_flash_regs_t *)0x40023C00u, (volatile uint8_t *)0x08004000u,
 *         {1u, 2u}, 2u, 16384u, 10000000u, NULL, NULL};
 *     stm32_flash_init(&nvm, &cfg);
 *     hal_nvm_read/write/erase_sector -> stm32_flash_read/write/erase_sector
 *
 * Choices (RM0090 rev 19, section 3.6):
 *  - Programming uses PSIZE = x8: one byte per program operation, so any offset and
 *    length work with no alignment rule (as hal.h promises) and no write can cross a
 *    128-bit row (PGAERR). x8 is allowed at every supply voltage (1.8..3.6 V; RM0090
 *    3.6.2); wider parallelism would only save time (about 16 us per byte, datasheet
 *    tprog, against a 36-byte calibration record).
 *  - Sector erase uses PSIZE = x32 (allowed at VDD 2.7..3.6 V, which 168 MHz at 5 wait
 *    states already assumes, stm32_clock.h): a 16 KiB sector erases in 250 ms typical,
 *    500 ms maximum, against 400 / 800 ms at x8 (STM32F405 datasheet, tERASE16KB).
 *  - The flash is unlocked (FLASH_KEYR) at the start of each erase or write and locked
 *    again (CR.LOCK) at its end, also on errors; FLASH interrupts are not used.
 *  - The F4 flash does not refuse a program over programmed bytes: each byte becomes
 *    old AND new. A write therefore programs every byte whose value would change, then
 *    verifies the range; a byte that would need a bit to go from 0 to 1 reads back as
 *    old AND new and the write returns HAL_EIO (hal.h's program-verify failure). A byte
 *    whose old value already equals old AND new is not programmed (no program cycle
 *    that cannot change anything).
 *  - After an erase and after a write the ART accelerator's caches are flushed
 *    (ACR.DCRST / ICRST, each with its cache briefly disabled, as RM0090 3.5.2
 *    recommends after a flash change), so reads through the window never see stale
 *    cache lines. An erase is verified by reading the sector back (every byte 0xFF).
 *
 * Single-bank stall: the F405 has one flash bank. While a sector is erased (several
 * hundred milliseconds, above) or a byte is programmed, every instruction fetch and data
 * read from flash stalls the CPU, interrupt handlers included (the vector table is in
 * flash): no CAN frame is received and the watchdog is not kicked. The driver itself may
 * run from flash: the CPU simply stalls on its next fetch until the operation ends, then
 * reads BSY clear. The application therefore defers saves (erases) to standstill, and
 * the independent watchdog must be longer than the erase (stm32_iwdg.h:
 * stm32_iwdg_set_timeout around a save).
 *
 * Register layout and bit positions: RM0090 rev 19, section 3.9 (flash interface
 * registers). Return codes are those of hal/hal.h: 0 or a negative HAL_E* value.
 */
#ifndef NAVECU_STM32_FLASH_H
#define NAVECU_STM32_FLASH_H

#include <stddef.h>
#include <stdint.h>

#include "hal.h"

/* ---- register block (RM0090 3.9, offsets from 0x40023C00) ---- */

typedef struct {
    volatile uint32_t ACR;     /* 0x00 access control: latency, caches, prefetch */
    volatile uint32_t KEYR;    /* 0x04 key (write-only, reads 0) */
    volatile uint32_t OPTKEYR; /* 0x08 option key */
    volatile uint32_t SR;      /* 0x0C status */
    volatile uint32_t CR;      /* 0x10 control */
    volatile uint32_t OPTCR;   /* 0x14 option control */
} stm32_flash_regs_t;

_Static_assert(offsetof(stm32_flash_regs_t, ACR) == 0x00u, "FLASH_ACR offset");
_Static_assert(offsetof(stm32_flash_regs_t, KEYR) == 0x04u, "FLASH_KEYR offset");
_Static_assert(offsetof(stm32_flash_regs_t, OPTKEYR) == 0x08u, "FLASH_OPTKEYR offset");
_Static_assert(offsetof(stm32_flash_regs_t, SR) == 0x0Cu, "FLASH_SR offset");
_Static_assert(offsetof(stm32_flash_regs_t, CR) == 0x10u, "FLASH_CR offset");
_Static_assert(offsetof(stm32_flash_regs_t, OPTCR) == 0x14u, "FLASH_OPTCR offset");
_Static_assert(sizeof(stm32_flash_regs_t) == 0x18u, "FLASH register block size");

/* ---- bit positions (RM0090 3.9.1 .. 3.9.5) ---- */

/* FLASH_ACR */
#define STM32_FLASH_ACR_LATENCY_MASK 0x7u /* wait states, bits 2:0 (F405/407) */
#define STM32_FLASH_ACR_PRFTEN (1u << 8)  /* prefetch enable */
#define STM32_FLASH_ACR_ICEN (1u << 9)    /* instruction cache enable */
#define STM32_FLASH_ACR_DCEN (1u << 10)   /* data cache enable */
#define STM32_FLASH_ACR_ICRST (1u << 11)  /* instruction cache reset (ICEN = 0 only) */
#define STM32_FLASH_ACR_DCRST (1u << 12)  /* data cache reset (DCEN = 0 only) */
/* FLASH_KEYR: the unlock sequence of FLASH_CR */
#define STM32_FLASH_KEY1 0x45670123u
#define STM32_FLASH_KEY2 0xCDEF89ABu
/* FLASH_SR */
#define STM32_FLASH_SR_EOP (1u << 0)    /* end of operation (rc_w1; EOPIE only) */
#define STM32_FLASH_SR_OPERR (1u << 1)  /* operation error (rc_w1) */
#define STM32_FLASH_SR_WRPERR (1u << 4) /* write protection error (rc_w1) */
#define STM32_FLASH_SR_PGAERR (1u << 5) /* programming alignment error (rc_w1) */
#define STM32_FLASH_SR_PGPERR (1u << 6) /* programming parallelism error (rc_w1) */
#define STM32_FLASH_SR_PGSERR (1u << 7) /* programming sequence error (rc_w1) */
#define STM32_FLASH_SR_BSY (1u << 16)   /* operation in progress */
#define STM32_FLASH_SR_ERRORS                                                       \
    (STM32_FLASH_SR_OPERR | STM32_FLASH_SR_WRPERR | STM32_FLASH_SR_PGAERR |        \
     STM32_FLASH_SR_PGPERR | STM32_FLASH_SR_PGSERR)
/* FLASH_CR */
#define STM32_FLASH_CR_PG (1u << 0)  /* programming */
#define STM32_FLASH_CR_SER (1u << 1) /* sector erase */
#define STM32_FLASH_CR_MER (1u << 2) /* mass erase */
#define STM32_FLASH_CR_SNB_SHIFT 3u  /* sector number, bits 6:3 */
#define STM32_FLASH_CR_SNB_MASK (0xFu << STM32_FLASH_CR_SNB_SHIFT)
#define STM32_FLASH_CR_PSIZE_SHIFT 8u /* program/erase parallelism, bits 9:8 */
#define STM32_FLASH_CR_PSIZE_MASK (0x3u << STM32_FLASH_CR_PSIZE_SHIFT)
#define STM32_FLASH_CR_PSIZE_X8 (0x0u << STM32_FLASH_CR_PSIZE_SHIFT)
#define STM32_FLASH_CR_PSIZE_X32 (0x2u << STM32_FLASH_CR_PSIZE_SHIFT)
#define STM32_FLASH_CR_STRT (1u << 16)  /* start an erase */
#define STM32_FLASH_CR_EOPIE (1u << 24) /* end of operation interrupt enable */
#define STM32_FLASH_CR_ERRIE (1u << 25) /* error interrupt enable */
#define STM32_FLASH_CR_LOCK (1u << 31)  /* CR locked; cleared by the KEYR sequence */

/* the F405's sectors 0..11 (0..3: 16 KiB, 4: 64 KiB, 5..11: 128 KiB, RM0090 3.3) */
#define STM32_FLASH_LAST_SECTOR 11u
/* most sectors one NVM region may span */
#define STM32_FLASH_MAX_SECTORS 4u

/* ---- driver instance ---- */

typedef struct {
    stm32_flash_regs_t *regs;
    /* the first byte of the NVM region in the memory map (0x08004000 for sector 1) */
    volatile uint8_t *window;
    /* the device sector numbers of the region, in address order: region sector k is
     * device sector sector_numbers[k] and starts at window + k * sector_size_bytes. They
     * must be consecutive (on the F405, equal-size sectors that are adjacent in the
     * memory map have consecutive numbers), at most STM32_FLASH_LAST_SECTOR */
    uint8_t sector_numbers[STM32_FLASH_MAX_SECTORS];
    uint32_t n_sectors;          /* 1..STM32_FLASH_MAX_SECTORS (hal.h needs 2) */
    uint32_t sector_size_bytes;  /* size of each sector (16384 for sectors 1..3) */
    /* bound of each wait (BSY clear, CR.LOCK clear), in polls (> 0). A poll from flash
     * stalls during the operation, so few polls pass; from RAM or with a hook that
     * delays, size it for the longest operation (a 500 ms sector erase) */
    uint32_t timeout_polls;
    /* optional: called before every poll of a wait (so at least once per wait) and once
     * between the two key writes (a watchdog kick; the host tests play the hardware
     * here); NULL for none */
    void (*wait_hook)(void *ctx);
    void *hook_ctx;
} stm32_flash_config_t;

/* Counters since stm32_flash_init; wrap at 2^32. A failed operation counts each error
 * flag it saw in SR once. */
typedef struct {
    uint32_t erases;          /* sector erases completed and verified */
    uint32_t operr;           /* SR.OPERR seen */
    uint32_t wrperr;          /* SR.WRPERR seen (a write-protected sector) */
    uint32_t pgaerr;          /* SR.PGAERR seen */
    uint32_t pgperr;          /* SR.PGPERR seen */
    uint32_t pgserr;          /* SR.PGSERR seen */
    uint32_t timeouts;        /* BSY did not clear within timeout_polls */
    uint32_t unlock_failures; /* CR.LOCK stayed set after the key sequence */
    uint32_t verify_failures; /* write or erase that did not read back as intended */
    uint32_t last_error_sr;   /* SR error bits of the last operation that had any, else 0 */
} stm32_flash_stats_t;

/* One NVM region. Caller-owned (static on the board); all fields are private. */
typedef struct {
    stm32_flash_config_t cfg;
    stm32_flash_stats_t stats;
} stm32_flash_t;

/*
 * Check cfg and set up *dev (counters cleared); lock the flash (CR.LOCK) if it is not.
 * Nothing is erased or programmed.
 * Returns 0; HAL_EINVAL (NULL dev, cfg, regs or window; n_sectors 0 or above
 * STM32_FLASH_MAX_SECTORS; sector_size_bytes 0 or region above 2^31 bytes; a sector
 * number above STM32_FLASH_LAST_SECTOR or not consecutive; timeout_polls 0).
 */
int stm32_flash_init(stm32_flash_t *dev, const stm32_flash_config_t *cfg);

/* Region size in bytes (n_sectors x sector_size_bytes), sector size; 0 for NULL. */
size_t stm32_flash_size(const stm32_flash_t *dev);
size_t stm32_flash_sector_size(const stm32_flash_t *dev);

/*
 * Unlock FLASH_CR: when CR.LOCK is set, write KEY1 then KEY2 to KEYR and wait (bounded)
 * for CR.LOCK to clear; when it is already clear, write nothing (a key write to an
 * unlocked flash is a wrong sequence, which locks CR until the next reset). Erase and
 * write call it themselves; it is public for board bring-up.
 * Returns 0; HAL_EINVAL (NULL dev); HAL_EIO when CR.LOCK stays set (counted).
 */
int stm32_flash_unlock(stm32_flash_t *dev);

/* Set CR.LOCK. A write to CR while BSY is set stalls the bus until BSY clears. */
void stm32_flash_lock(stm32_flash_t *dev);

/*
 * Erase region sector `sector` (0..n_sectors-1; device sector sector_numbers[sector]):
 *  1. wait for SR.BSY clear; 2. unlock; 3. clear the SR error flags (rc_w1);
 *  4. CR = SER | SNB | PSIZE x32, then CR |= STRT; 5. wait for SR.BSY clear;
 *  6. read the SR error flags: count them, clear them, HAL_EIO;
 *  7. clear SER and SNB, lock, flush the caches, check every byte reads 0xFF.
 * Blocks for the erase (250..500 ms for 16 KiB; see the stall note above).
 * Returns 0; HAL_EINVAL (NULL dev, sector out of range; nothing touched); HAL_EIO on a
 * BSY timeout (before the erase: nothing touched; after STRT: CR is not written, since
 * a write would stall the bus until BSY clears, so the flash stays unlocked until the
 * next operation or stm32_flash_lock), an unlock failure, an error flag, or a byte that
 * does not read 0xFF afterwards.
 */
int stm32_flash_erase_sector(stm32_flash_t *dev, size_t sector);

/* Erase every sector of the region, in order; stops at the first failure (its code). */
int stm32_flash_erase(stm32_flash_t *dev);

/*
 * Program buf[0..len-1] at region offset `offset` with PSIZE x8: wait for BSY clear,
 * unlock, clear the SR error flags, CR = PG | PSIZE x8; then for each byte whose value
 * would change (old AND new != old): write it through the window, wait for BSY clear,
 * read the error flags (an error flag stops the write: count, clear, HAL_EIO). Then
 * clear PG, lock, flush the caches and verify the range: a byte that does not read back
 * as written (a 0 -> 1 bit was asked for: it holds old AND new) gives HAL_EIO (counted
 * once per call). len 0 touches nothing.
 * Returns 0; HAL_EINVAL (NULL dev, NULL buf with len > 0, a range past the end; nothing
 * touched); HAL_EIO (timeout, unlock failure, error flag, verify failure; bytes before
 * the failing one are programmed).
 */
int stm32_flash_write(stm32_flash_t *dev, size_t offset, const void *buf, size_t len);

/*
 * Copy len bytes at region offset `offset` into buf (byte reads through the window).
 * Never waits. Returns 0; HAL_EINVAL (NULL dev, NULL buf with len > 0, a range past the
 * end).
 */
int stm32_flash_read(const stm32_flash_t *dev, size_t offset, void *buf, size_t len);

/* The counters. Returns 0, HAL_EINVAL (NULL pointer). */
int stm32_flash_stats(const stm32_flash_t *dev, stm32_flash_stats_t *s);

#endif /* NAVECU_STM32_FLASH_H */
