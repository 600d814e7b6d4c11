/*
 * test_stm32_flash.c - the STM32F405 embedded-flash driver (hal/cortex_m4f/stm32_flash.c)
 * against a FLASH register block and a flash array in RAM: two "sectors" of 1 KiB (the
 * sector size is a configuration value; the board uses 16 KiB), device sectors 1 and 2.
 *
 * The test plays the hardware from the driver's wait hook, which the driver calls before
 * every poll and once between the two key writes:
 * - KEYR is write-only (reads 0): the hook logs each key written and clears KEYR; KEY1
 *   then KEY2 while CR.LOCK is set clears LOCK, any other key write is a wrong sequence
 *   that keeps CR locked until reset (RM0090 3.6.1);
 * - CR.STRT with SER erases the sector SNB (cells and window to 0xFF), then STRT clears;
 * - the driver programs by writing bytes to the window, which is plain RAM: the hook
 *   finds each byte that differs from the flash cells and applies NOR semantics, cell =
 *   cell AND written (with CR.PG set and PSIZE x8; otherwise PGSERR / PGPERR and the
 *   write is dropped), then shows the cell in the window again;
 * - SR holds the hardware's status; a write by the driver is seen as a change of the
 *   value last shown and clears the written flags (rc_w1); BSY is shown while the test
 *   keeps the flash busy; error flags can be injected into the next operation.
 *
 * Expected register values are written from RM0090's bit positions (3.9.3..3.9.5), not
 * from the driver's macros: CR: PG bit 0, SER bit 1, SNB bits 6:3, PSIZE bits 9:8 (x8 = 0,
 * x32 = 2), STRT bit 16, LOCK bit 31; SR: EOP bit 0, OPERR bit 1, WRPERR bit 4, PGAERR
 * bit 5, PGPERR bit 6, PGSERR bit 7, BSY bit 16; ACR: LATENCY bits 2:0, PRFTEN bit 8,
 * ICEN bit 9, DCEN bit 10, ICRST bit 11, DCRST bit 12.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "stm32_flash.h"

#define SECTOR_BYTES 1024u
#define N_SECTORS 2u
#define REGION_BYTES (SECTOR_BYTES * N_SECTORS)
#define FIRST_SNB 1u /* region sector 0 is device sector 1 */
#define POLLS 50u

#define CR_PG (1u << 0)
#define CR_SER (1u << 1)
#define CR_STRT (1u << 16)
#define CR_LOCK (1u << 31)
#define SR_EOP (1u << 0)
#define SR_OPERR (1u << 1)
#define SR_WRPERR (1u << 4)
#define SR_PGAERR (1u << 5)
#define SR_PGPERR (1u << 6)
#define SR_PGSERR (1u << 7)
#define SR_BSY (1u << 16)
#define SR_RC_W1 0xF3u /* EOP, OPERR, WRPERR, PGAERR, PGPERR, PGSERR */
/* 5 wait states, prefetch, instruction and data caches: as stm32_clock leaves it */
#define ACR_168MHZ (5u | (1u << 8) | (1u << 9) | (1u << 10))

static stm32_flash_regs_t regs;
static uint8_t window[REGION_BYTES]; /* what the CPU reads at 0x08004000.. */
static uint8_t cells[REGION_BYTES];  /* the flash cells */
static stm32_flash_t dev;

static struct {
    uint32_t sr;        /* the hardware's status register */
    uint32_t sr_shown;  /* what the hook last put in regs.SR */
    uint32_t keys[8];   /* key writes seen, in order */
    unsigned n_keys;
    unsigned key_state; /* 1: KEY1 seen */
    int keys_broken;    /* wrong key sequence: locked until reset */
    uint32_t inject_sr; /* flags raised by the next operation instead of doing it */
    int busy_forever;   /* SR.BSY never clears */
    int stick_busy_on_op; /* the next operation hangs: BSY stays set */
    int stuck_byte;     /* index of a cell an erase leaves at 0x00, or -1 */
    unsigned hook_calls;
    unsigned erases;
    uint32_t erase_cr;  /* CR at the last erase start */
    unsigned programs;  /* bytes programmed */
    uint32_t program_cr; /* CR at the last byte program */
} hw;

static void hw_apply_key(void)
{
    uint32_t key = regs.KEYR;
    if (key == 0u) {
        return;
    }
    regs.KEYR = 0u;
    if (hw.n_keys < 8u) {
        hw.keys[hw.n_keys] = key;
    }
    hw.n_keys++;
    if ((regs.CR & CR_LOCK) == 0u) {
        hw.keys_broken = 1; /* a key to an unlocked flash is a wrong sequence */
    } else if (hw.key_state == 0u && key == 0x45670123u) {
        hw.key_state = 1u;
    } else if (hw.key_state == 1u && key == 0xCDEF89ABu && !hw.keys_broken) {
        hw.key_state = 0u;
        regs.CR &= ~CR_LOCK;
    } else {
        hw.keys_broken = 1;
    }
}

static int hw_raise_injected(void)
{
    if (hw.inject_sr == 0u) {
        return 0;
    }
    hw.sr |= hw.inject_sr;
    hw.inject_sr = 0u;
    return 1;
}

static void hw_apply_erase(void)
{
    uint32_t cr = regs.CR;
    if ((cr & CR_STRT) == 0u) {
        return;
    }
    if (hw.stick_busy_on_op) {
        hw.busy_forever = 1;
        return; /* STRT stays set: the erase never ends */
    }
    regs.CR = cr & ~CR_STRT;
    if ((cr & CR_LOCK) != 0u) {
        return; /* CR cannot have been written while locked: nothing happens */
    }
    hw.erase_cr = cr;
    if (hw_raise_injected()) {
        return;
    }
    uint32_t snb = (cr >> 3) & 0xFu;
    if ((cr & CR_SER) == 0u || snb < FIRST_SNB || snb >= FIRST_SNB + N_SECTORS) {
        hw.sr |= SR_PGSERR;
        return;
    }
    size_t base = (size_t)(snb - FIRST_SNB) * SECTOR_BYTES;
    memset(&cells[base], 0xFF, SECTOR_BYTES);
    if (hw.stuck_byte >= 0 && (size_t)hw.stuck_byte >= base &&
        (size_t)hw.stuck_byte < base + SECTOR_BYTES) {
        cells[hw.stuck_byte] = 0x00u;
    }
    memcpy(&window[base], &cells[base], SECTOR_BYTES);
    hw.erases++;
}

static void hw_apply_programs(void)
{
    for (size_t i = 0; i < REGION_BYTES; i++) {
        if (window[i] == cells[i]) {
            continue;
        }
        uint32_t cr = regs.CR;
        uint8_t written = window[i];
        window[i] = cells[i]; /* a dropped write leaves the cell as it was */
        if ((cr & CR_LOCK) != 0u || (cr & CR_PG) == 0u) {
            hw.sr |= SR_PGSERR;
        } else if (((cr >> 8) & 0x3u) != 0u) {
            hw.sr |= SR_PGPERR; /* a byte access needs PSIZE x8 */
        } else if (hw.stick_busy_on_op) {
            hw.busy_forever = 1;
        } else if (!hw_raise_injected()) {
            cells[i] &= written;
            window[i] = cells[i];
            hw.programs++;
            hw.program_cr = cr;
        }
    }
}

/* the hardware, run before every poll of the driver */
static void hw_hook(void *ctx)
{
    (void)ctx;
    hw.hook_calls++;
    if (regs.SR != hw.sr_shown) {
        hw.sr &= ~(regs.SR & SR_RC_W1); /* the driver cleared flags */
    }
    hw_apply_key();
    if (hw.keys_broken) {
        regs.CR |= CR_LOCK;
    }
    hw_apply_erase();
    hw_apply_programs();
    if (hw.busy_forever) {
        hw.sr |= SR_BSY;
    } else {
        hw.sr &= ~SR_BSY;
    }
    regs.SR = hw.sr;
    hw.sr_shown = hw.sr;
}

static stm32_flash_config_t config(void)
{
    stm32_flash_config_t cfg = {&regs, window, {FIRST_SNB, FIRST_SNB + 1u}, N_SECTORS,
                                SECTOR_BYTES, POLLS, hw_hook, NULL};
    return cfg;
}

static int setup(void **state)
{
    (void)state;
    memset((void *)&regs, 0, sizeof regs);
    regs.ACR = ACR_168MHZ;
    regs.CR = CR_LOCK;         /* reset value 0x80000000 */
    regs.OPTCR = 0x0FFFAAEDu;  /* reset value */
    memset(&hw, 0, sizeof hw);
    hw.stuck_byte = -1;
    for (size_t i = 0; i < REGION_BYTES; i++) {
        cells[i] = (uint8_t)(i * 7u + 3u); /* old contents, programmed */
    }
    memcpy(window, cells, sizeof window);
    stm32_flash_config_t cfg = config();
    assert_int_equal(stm32_flash_init(&dev, &cfg), 0);
    return 0;
}

static stm32_flash_stats_t stats(void)
{
    stm32_flash_stats_t s;
    assert_int_equal(stm32_flash_stats(&dev, &s), 0);
    return s;
}

static void assert_erased(size_t from, size_t len)
{
    for (size_t i = from; i < from + len; i++) {
        assert_int_equal(cells[i], 0xFF);
    }
}

/* ---- layout and configuration ---- */

static void test_register_offsets(void **state)
{
    (void)state;
    assert_int_equal(offsetof(stm32_flash_regs_t, ACR), 0x00);
    assert_int_equal(offsetof(stm32_flash_regs_t, KEYR), 0x04);
    assert_int_equal(offsetof(stm32_flash_regs_t, OPTKEYR), 0x08);
    assert_int_equal(offsetof(stm32_flash_regs_t, SR), 0x0C);
    assert_int_equal(offsetof(stm32_flash_regs_t, CR), 0x10);
    assert_int_equal(offsetof(stm32_flash_regs_t, OPTCR), 0x14);
}

static void test_init_rejects_bad_configs_and_locks(void **state)
{
    (void)state;
    stm32_flash_t d;
    stm32_flash_config_t cfg = config();
    assert_int_equal(stm32_flash_init(NULL, &cfg), HAL_EINVAL);
    assert_int_equal(stm32_flash_init(&d, NULL), HAL_EINVAL);
    cfg.regs = NULL;
    assert_int_equal(stm32_flash_init(&d, &cfg), HAL_EINVAL);
    cfg = config();
    cfg.window = NULL;
    assert_int_equal(stm32_flash_init(&d, &cfg), HAL_EINVAL);
    cfg = config();
    cfg.n_sectors = 0u;
    assert_int_equal(stm32_flash_init(&d, &cfg), HAL_EINVAL);
    cfg.n_sectors = STM32_FLASH_MAX_SECTORS + 1u;
    assert_int_equal(stm32_flash_init(&d, &cfg), HAL_EINVAL);
    cfg = config();
    cfg.sector_size_bytes = 0u;
    assert_int_equal(stm32_flash_init(&d, &cfg), HAL_EINVAL);
    cfg = config();
    cfg.timeout_polls = 0u;
    assert_int_equal(stm32_flash_init(&d, &cfg), HAL_EINVAL);
    cfg = config();
    cfg.sector_numbers[1] = 3u; /* sectors 1 and 3 are not adjacent */
    assert_int_equal(stm32_flash_init(&d, &cfg), HAL_EINVAL);
    cfg = config();
    cfg.sector_numbers[0] = 11u; /* the F405's last sector is 11 */
    cfg.sector_numbers[1] = 12u;
    assert_int_equal(stm32_flash_init(&d, &cfg), HAL_EINVAL);
    cfg = config();
    cfg.sector_size_bytes = 0x40000000u; /* 2 x 1 GiB: past the 2 GiB limit */
    cfg.n_sectors = 3u;
    cfg.sector_numbers[2] = FIRST_SNB + 2u;
    assert_int_equal(stm32_flash_init(&d, &cfg), HAL_EINVAL);

    /* a flash left unlocked (a debugger, an earlier crash) is locked by init */
    regs.CR = 0u;
    cfg = config();
    assert_int_equal(stm32_flash_init(&d, &cfg), 0);
    assert_int_equal(regs.CR, CR_LOCK);
    assert_int_equal(stm32_flash_size(&d), REGION_BYTES);
    assert_int_equal(stm32_flash_sector_size(&d), SECTOR_BYTES);
    assert_int_equal(stm32_flash_size(NULL), 0);
    assert_int_equal(hw.n_keys, 0);
}

/* ---- unlock and lock ---- */

static void test_unlock_writes_key1_then_key2(void **state)
{
    (void)state;
    assert_int_equal(stm32_flash_unlock(&dev), 0);
    assert_int_equal(hw.n_keys, 2);
    assert_int_equal(hw.keys[0], 0x45670123u);
    assert_int_equal(hw.keys[1], 0xCDEF89ABu);
    assert_int_equal(regs.CR & CR_LOCK, 0u);
    /* already unlocked: no key is written (it would lock CR until reset) */
    assert_int_equal(stm32_flash_unlock(&dev), 0);
    hw_hook(NULL);
    assert_int_equal(hw.n_keys, 2);
    assert_false(hw.keys_broken);
    stm32_flash_lock(&dev);
    assert_int_equal(regs.CR, CR_LOCK);
    assert_int_equal(stm32_flash_unlock(NULL), HAL_EINVAL);
}

/* GIVEN a flash whose CR stays locked after the keys (a wrong sequence earlier) WHEN an
 * erase runs THEN it fails with HAL_EIO, counted, and nothing is erased */
static void test_lock_staying_set_is_eio(void **state)
{
    (void)state;
    hw.keys_broken = 1;
    assert_int_equal(stm32_flash_unlock(&dev), HAL_EIO);
    assert_int_equal(stats().unlock_failures, 1);
    assert_int_equal(stm32_flash_erase_sector(&dev, 0), HAL_EIO);
    assert_int_equal(stats().unlock_failures, 2);
    assert_int_equal(hw.erases, 0);
    assert_int_equal(cells[0], 3u);
    assert_int_equal(regs.CR & (CR_SER | CR_STRT), 0u);
}

/* ---- erase ---- */

static void test_erase_sets_ser_snb_psize_strt_and_relocks(void **state)
{
    (void)state;
    assert_int_equal(stm32_flash_erase_sector(&dev, 1), 0);
    /* SER bit 1, SNB = device sector 2 in bits 6:3, PSIZE x32 = 2 in bits 9:8, STRT
     * bit 16, LOCK clear */
    assert_int_equal(hw.erase_cr, (1u << 1) | (2u << 3) | (2u << 8) | (1u << 16));
    assert_int_equal(hw.erases, 1);
    assert_erased(SECTOR_BYTES, SECTOR_BYTES);
    assert_int_equal(cells[0], 3u); /* sector 0 untouched */
    assert_int_equal(cells[SECTOR_BYTES - 1u], (uint8_t)((SECTOR_BYTES - 1u) * 7u + 3u));
    /* unlocked with KEY1, KEY2; afterwards locked with SER and SNB cleared */
    assert_int_equal(hw.n_keys, 2);
    assert_int_equal(hw.keys[0], 0x45670123u);
    assert_int_equal(hw.keys[1], 0xCDEF89ABu);
    assert_int_equal(regs.CR, CR_LOCK);
    /* caches flushed and restored: latency, PRFTEN, ICEN, DCEN kept; ICRST, DCRST clear */
    assert_int_equal(regs.ACR, ACR_168MHZ);
    /* the error flags were cleared before the start (rc_w1), then none was seen */
    assert_int_equal(regs.SR, 0u);
    stm32_flash_stats_t s = stats();
    assert_int_equal(s.erases, 1);
    assert_int_equal(s.timeouts + s.unlock_failures + s.verify_failures, 0);
    assert_int_equal(s.last_error_sr, 0);

    /* sector 0 is device sector 1 */
    assert_int_equal(stm32_flash_erase_sector(&dev, 0), 0);
    assert_int_equal(hw.erase_cr, (1u << 1) | (1u << 3) | (2u << 8) | (1u << 16));
    assert_erased(0, REGION_BYTES);
    assert_int_equal(stm32_flash_erase_sector(&dev, 2), HAL_EINVAL);
    assert_int_equal(stm32_flash_erase_sector(NULL, 0), HAL_EINVAL);
    assert_int_equal(hw.erases, 2);
}

/* GIVEN an erase that raises WRPERR WHEN it ends THEN HAL_EIO, the flag counted and
 * cleared by writing it back (rc_w1), the flash locked, nothing erased */
static void test_erase_error_flags_counted_and_cleared(void **state)
{
    (void)state;
    hw.inject_sr = SR_WRPERR;
    assert_int_equal(stm32_flash_erase_sector(&dev, 0), HAL_EIO);
    assert_int_equal(regs.SR, SR_WRPERR); /* written back: exactly that flag */
    assert_int_equal(regs.CR, CR_LOCK);
    assert_int_equal(regs.ACR, ACR_168MHZ);
    assert_int_equal(cells[0], 3u);
    stm32_flash_stats_t s = stats();
    assert_int_equal(s.wrperr, 1);
    assert_int_equal(s.last_error_sr, SR_WRPERR);
    assert_int_equal(s.erases, 0);

    /* several flags at once: each counted */
    hw.inject_sr = SR_PGSERR | SR_PGPERR | SR_PGAERR | SR_OPERR;
    assert_int_equal(stm32_flash_erase_sector(&dev, 1), HAL_EIO);
    assert_int_equal(regs.SR, SR_PGSERR | SR_PGPERR | SR_PGAERR | SR_OPERR);
    s = stats();
    assert_int_equal(s.pgserr, 1);
    assert_int_equal(s.pgperr, 1);
    assert_int_equal(s.pgaerr, 1);
    assert_int_equal(s.operr, 1);
    assert_int_equal(s.wrperr, 1);
    assert_int_equal(s.last_error_sr, 0xE2u);

    /* a flag left over from before (here PGPERR and EOP) is cleared before the next
     * operation and not taken for its result */
    hw_hook(NULL);
    hw.sr = SR_PGPERR | SR_EOP;
    hw_hook(NULL);
    assert_int_equal(stm32_flash_erase_sector(&dev, 0), 0);
    assert_erased(0, SECTOR_BYTES);
    assert_int_equal(regs.SR, 0u);
    assert_int_equal(stats().pgperr, 1);
    assert_int_equal(stats().erases, 1);
}

/* GIVEN a flash busy forever WHEN an erase starts THEN it gives up after timeout_polls
 * polls with HAL_EIO, before unlocking: no key written, CR untouched */
static void test_erase_busy_before_start_times_out(void **state)
{
    (void)state;
    hw.busy_forever = 1;
    hw_hook(NULL);
    hw.hook_calls = 0;
    assert_int_equal(stm32_flash_erase_sector(&dev, 0), HAL_EIO);
    assert_int_equal(hw.hook_calls, POLLS);
    assert_int_equal(hw.n_keys, 0);
    assert_int_equal(regs.CR, CR_LOCK);
    assert_int_equal(stats().timeouts, 1);
    assert_int_equal(hw.erases, 0);
}

/* GIVEN an erase whose BSY never clears WHEN the bound runs out THEN HAL_EIO, and CR is
 * not written (a write while BSY stalls the bus); once the flash recovers, the next
 * operation runs without new keys and locks again */
static void test_erase_busy_after_start_times_out(void **state)
{
    (void)state;
    hw.stick_busy_on_op = 1;
    assert_int_equal(stm32_flash_erase_sector(&dev, 0), HAL_EIO);
    assert_int_equal(stats().timeouts, 1);
    assert_int_equal(regs.CR, (1u << 1) | (1u << 3) | (2u << 8) | (1u << 16));
    assert_int_equal(hw.erases, 0);

    hw.stick_busy_on_op = 0;
    hw.busy_forever = 0;
    regs.CR &= ~CR_STRT; /* the hung operation ends at last */
    assert_int_equal(stm32_flash_erase_sector(&dev, 0), 0);
    assert_int_equal(hw.n_keys, 2); /* still unlocked: no second key sequence */
    assert_false(hw.keys_broken);
    assert_int_equal(regs.CR, CR_LOCK);
    assert_erased(0, SECTOR_BYTES);
}

/* GIVEN a sector with a byte the erase cannot reset WHEN it is erased THEN the read-back
 * finds it: HAL_EIO, counted as a verify failure */
static void test_erase_verified_by_read_back(void **state)
{
    (void)state;
    hw.stuck_byte = (int)SECTOR_BYTES + 17;
    assert_int_equal(stm32_flash_erase_sector(&dev, 1), HAL_EIO);
    assert_int_equal(stats().verify_failures, 1);
    assert_int_equal(stats().erases, 0);
    assert_int_equal(regs.CR, CR_LOCK);
    assert_int_equal(stm32_flash_erase_sector(&dev, 0), 0);
}

static void test_erase_all_sectors(void **state)
{
    (void)state;
    assert_int_equal(stm32_flash_erase(&dev), 0);
    assert_int_equal(hw.erases, 2);
    assert_erased(0, REGION_BYTES);
    assert_int_equal(stats().erases, 2);
    /* a failure stops it */
    hw.inject_sr = SR_WRPERR;
    assert_int_equal(stm32_flash_erase(&dev), HAL_EIO);
    assert_int_equal(hw.erases, 2);
    assert_int_equal(stm32_flash_erase(NULL), HAL_EINVAL);
}

/* ---- write and read ---- */

/* GIVEN an erased region WHEN 100 bytes are written across the sector boundary THEN they
 * read back, with PG and PSIZE x8 set while programming, 0xFF bytes not programmed, and
 * the flash locked afterwards */
static void test_write_read_round_trip(void **state)
{
    (void)state;
    assert_int_equal(stm32_flash_erase(&dev), 0);
    uint8_t data[100];
    size_t n_program = 0;
    for (size_t i = 0; i < sizeof data; i++) {
        data[i] = (uint8_t)(i % 17u == 0u ? 0xFFu : i * 13u + 1u);
        n_program += data[i] != 0xFFu ? 1u : 0u;
    }
    hw.n_keys = 0;
    const size_t off = SECTOR_BYTES - 40u;
    assert_int_equal(stm32_flash_write(&dev, off, data, sizeof data), 0);
    assert_int_equal(hw.program_cr, 1u << 0); /* PG, PSIZE x8 (0), LOCK clear */
    assert_int_equal(hw.programs, n_program);
    assert_int_equal(hw.n_keys, 2);
    assert_int_equal(regs.CR, CR_LOCK);
    assert_int_equal(regs.ACR, ACR_168MHZ);
    assert_memory_equal(&cells[off], data, sizeof data);
    assert_int_equal(cells[off - 1u], 0xFF);
    assert_int_equal(cells[off + sizeof data], 0xFF);

    uint8_t back[100];
    memset(back, 0, sizeof back);
    assert_int_equal(stm32_flash_read(&dev, off, back, sizeof back), 0);
    assert_memory_equal(back, data, sizeof data);
    uint8_t whole[REGION_BYTES];
    assert_int_equal(stm32_flash_read(&dev, 0, whole, sizeof whole), 0);
    assert_memory_equal(whole, cells, sizeof whole);
    stm32_flash_stats_t s = stats();
    assert_int_equal(s.verify_failures + s.timeouts + s.last_error_sr, 0);

    /* len 0: nothing touched */
    hw.n_keys = 0;
    assert_int_equal(stm32_flash_write(&dev, 5, data, 0), 0);
    assert_int_equal(stm32_flash_write(&dev, 5, NULL, 0), 0);
    assert_int_equal(hw.n_keys, 0);
}

/* GIVEN programmed bytes WHEN a write asks a bit to go from 0 to 1 THEN the byte holds
 * old AND new and the write returns HAL_EIO; clearing more bits is fine */
static void test_write_over_programmed_bytes_is_eio(void **state)
{
    (void)state;
    assert_int_equal(stm32_flash_erase_sector(&dev, 0), 0);
    const uint8_t a = 0x0F;
    const uint8_t b = 0xF0;
    const uint8_t c = 0x05;
    const uint8_t ff = 0xFF;
    assert_int_equal(stm32_flash_write(&dev, 5, &a, 1), 0);
    assert_int_equal(cells[5], 0x0F);
    assert_int_equal(stm32_flash_write(&dev, 5, &b, 1), HAL_EIO);
    assert_int_equal(cells[5], 0x00); /* 0x0F AND 0xF0, as the real flash */
    assert_int_equal(stats().verify_failures, 1);
    assert_int_equal(regs.CR, CR_LOCK);

    assert_int_equal(stm32_flash_write(&dev, 6, &a, 1), 0);
    assert_int_equal(stm32_flash_write(&dev, 6, &c, 1), 0); /* 0x0F -> 0x05 clears bits */
    assert_int_equal(cells[6], 0x05);
    unsigned programs = hw.programs;
    assert_int_equal(stm32_flash_write(&dev, 6, &c, 1), 0); /* the same value again */
    assert_int_equal(hw.programs, programs);                /* nothing to program */
    assert_int_equal(stm32_flash_write(&dev, 6, &ff, 1), HAL_EIO); /* 0x05 -> 0xFF */
    assert_int_equal(cells[6], 0x05);
    assert_int_equal(stats().verify_failures, 2);

    /* a multi-byte write: every byte programmed, one mismatch, one count */
    const uint8_t d[4] = {0x00, 0xFF, 0x11, 0x22};
    assert_int_equal(stm32_flash_write(&dev, 4, d, 4), HAL_EIO);
    assert_int_equal(cells[4], 0x00);
    assert_int_equal(cells[5], 0x00);
    assert_int_equal(cells[6], 0x01); /* 0x05 AND 0x11 */
    assert_int_equal(cells[7], 0x22);
    assert_int_equal(stats().verify_failures, 3);
}

/* GIVEN a byte program that raises PGPERR WHEN the write runs THEN it stops there with
 * HAL_EIO, the flag counted and cleared, PG cleared and the flash locked */
static void test_write_error_flag_stops_and_relocks(void **state)
{
    (void)state;
    assert_int_equal(stm32_flash_erase_sector(&dev, 0), 0);
    const uint8_t data[4] = {0x10, 0x20, 0x30, 0x40};
    hw.inject_sr = SR_PGPERR;
    assert_int_equal(stm32_flash_write(&dev, 100, data, 4), HAL_EIO);
    assert_int_equal(cells[100], 0xFF);
    assert_int_equal(cells[101], 0xFF); /* not attempted */
    assert_int_equal(hw.programs, 0);
    assert_int_equal(regs.SR, SR_PGPERR);
    assert_int_equal(regs.CR, CR_LOCK);
    stm32_flash_stats_t s = stats();
    assert_int_equal(s.pgperr, 1);
    assert_int_equal(s.last_error_sr, SR_PGPERR);
    assert_int_equal(s.verify_failures, 0);
    /* the next write succeeds */
    assert_int_equal(stm32_flash_write(&dev, 100, data, 4), 0);
    assert_memory_equal(&cells[100], data, 4);
}

static void test_write_busy_times_out(void **state)
{
    (void)state;
    assert_int_equal(stm32_flash_erase_sector(&dev, 0), 0);
    const uint8_t data[2] = {0x12, 0x34};
    hw.stick_busy_on_op = 1;
    hw.hook_calls = 0;
    assert_int_equal(stm32_flash_write(&dev, 0, data, 2), HAL_EIO);
    /* 1 poll before the start, 2 for the keys, then the bound for the first byte */
    assert_int_equal(hw.hook_calls, 1u + 2u + POLLS);
    assert_int_equal(stats().timeouts, 1);
    assert_int_equal(regs.CR & CR_PG, CR_PG); /* CR not written while busy */
}

static void test_range_checks(void **state)
{
    (void)state;
    uint8_t buf[4] = {0};
    hw.hook_calls = 0;
    assert_int_equal(stm32_flash_write(&dev, REGION_BYTES, buf, 1), HAL_EINVAL);
    assert_int_equal(stm32_flash_write(&dev, REGION_BYTES - 1u, buf, 2), HAL_EINVAL);
    assert_int_equal(stm32_flash_write(&dev, SIZE_MAX, buf, 2), HAL_EINVAL);
    assert_int_equal(stm32_flash_write(&dev, 1, buf, SIZE_MAX), HAL_EINVAL);
    assert_int_equal(stm32_flash_write(&dev, 0, NULL, 1), HAL_EINVAL);
    assert_int_equal(stm32_flash_write(NULL, 0, buf, 1), HAL_EINVAL);
    assert_int_equal(stm32_flash_read(&dev, REGION_BYTES, buf, 1), HAL_EINVAL);
    assert_int_equal(stm32_flash_read(&dev, REGION_BYTES - 3u, buf, 4), HAL_EINVAL);
    assert_int_equal(stm32_flash_read(&dev, 0, NULL, 1), HAL_EINVAL);
    assert_int_equal(stm32_flash_read(NULL, 0, buf, 1), HAL_EINVAL);
    assert_int_equal(hw.hook_calls, 0); /* nothing touched */
    assert_int_equal(hw.n_keys, 0);
    assert_int_equal(regs.CR, CR_LOCK);
    /* the last bytes and the empty range at the end are fine */
    assert_int_equal(stm32_flash_read(&dev, REGION_BYTES - 4u, buf, 4), 0);
    assert_int_equal(buf[3], (uint8_t)((REGION_BYTES - 1u) * 7u + 3u));
    assert_int_equal(stm32_flash_read(&dev, REGION_BYTES, buf, 0), 0);
    assert_int_equal(stm32_flash_read(&dev, 0, NULL, 0), 0);
    assert_int_equal(stm32_flash_stats(&dev, NULL), HAL_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_register_offsets),
        cmocka_unit_test_setup(test_init_rejects_bad_configs_and_locks, setup),
        cmocka_unit_test_setup(test_unlock_writes_key1_then_key2, setup),
        cmocka_unit_test_setup(test_lock_staying_set_is_eio, setup),
        cmocka_unit_test_setup(test_erase_sets_ser_snb_psize_strt_and_relocks, setup),
        cmocka_unit_test_setup(test_erase_error_flags_counted_and_cleared, setup),
        cmocka_unit_test_setup(test_erase_busy_before_start_times_out, setup),
        cmocka_unit_test_setup(test_erase_busy_after_start_times_out, setup),
        cmocka_unit_test_setup(test_erase_verified_by_read_back, setup),
        cmocka_unit_test_setup(test_erase_all_sectors, setup),
        cmocka_unit_test_setup(test_write_read_round_trip, setup),
        cmocka_unit_test_setup(test_write_over_programmed_bytes_is_eio, setup),
        cmocka_unit_test_setup(test_write_error_flag_stops_and_relocks, setup),
        cmocka_unit_test_setup(test_write_busy_times_out, setup),
        cmocka_unit_test_setup(test_range_checks, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
