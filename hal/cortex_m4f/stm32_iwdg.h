/*
 * stm32_iwdg.h - register-level driver for the STM32F405 independent watchdog (IWDG at
 * 0x40003000, clocked by the LSI RC oscillator), used by the Cortex-M4F HAL
 * (hal/cortex_m4f/) for hal_watchdog_kick.
 *
 * The driver touches the watchdog only through a stm32_iwdg_regs_t pointer, so the host
 * tests (tests/test_stm32_iwdg.c) run it against a register block in RAM and play the
 * hardware. It includes no OS header, never allocates, and never waits without a bound.
 *
 * Typical use on the board:
 *
 *     static stm32_iwdg_t wdg;
 *     stm32_iwdg_config_t cfg = {(stm32_iwdg_regs_t *)0x40003000u,
 *                                STM32_IWDG_DEFAULT_TIMEOUT_MS, 100000u, NULL, NULL};
 *     stm32_iwdg_init(&wdg, &cfg);
 *     void hal_watchdog_kick(hal_t *hal) { stm32_iwdg_kick(&hal->wdg); }
 *
 * Timing: the counter counts LSI / (4 << PR) ticks (PR 0..6: /4../256) down from RLR
 * (12 bits); the timeout is (RLR + 1) x (4 << PR) / f_LSI (RM0090 21.3, timeout table:
 * /4 gives 0.125 ms .. 512 ms at 32 kHz). The driver computes PR and RLR from the
 * nominal LSI of 32 kHz: the smallest prescaler whose 4096 counts reach the timeout,
 * RLR = round(ticks / divider) - 1. Timeouts of 1 ms .. 32768 ms are possible.
 *
 * LSI tolerance: the STM32F405 datasheet gives f_LSI = 17 .. 47 kHz over temperature and
 * supply (32 kHz typical), and the driver cannot know it, so the real timeout is the
 * nominal one x 32 / f_LSI: from 0.68 x (47 kHz) to 1.88 x (17 kHz) the nominal.
 * STM32_IWDG_DEFAULT_TIMEOUT_MS = 200 ms nominal (PR 0, RLR 1599: 6400 LSI cycles) gives
 * 6400 / 47 kHz = 136 ms with the fastest LSI, still above the 100 ms kick period of
 * hal.h (36 ms margin), and 6400 / 17 kHz = 376 ms with the slowest.
 *
 * Flash erases: during a sector erase the CPU stalls (stm32_flash.h), so nothing kicks
 * the watchdog for up to 500 ms (16 KiB at PSIZE x32, datasheet maximum). Around a save
 * the board lengthens the timeout with stm32_iwdg_set_timeout(STM32_IWDG_ERASE_TIMEOUT_MS)
 * and restores the default afterwards: 2000 ms nominal is at least 2000 x 32 / 47 =
 * 1361 ms, enough for two erases (calstore_erase) at 500 ms each.
 *
 * The watchdog cannot be stopped once started (only a reset stops it). The IWDG keeps
 * counting while a debugger halts the core unless DBGMCU_APB1_FZ.DBG_IWDG_STOP is set
 * (the board's business, not this driver's).
 *
 * Register layout and bit positions: RM0090 rev 19, section 21.4 (IWDG registers).
 * Return codes are those of hal/hal.h: 0 or a negative HAL_E* value.
 */
#ifndef NAVECU_STM32_IWDG_H
#define NAVECU_STM32_IWDG_H

#include <stddef.h>
#include <stdint.h>

#include "hal.h"

/* ---- register block (RM0090 21.4, offsets from 0x40003000) ---- */

typedef struct {
    volatile uint32_t KR;  /* 0x00 key (write-only, reads 0) */
    volatile uint32_t PR;  /* 0x04 prescaler, bits 2:0 */
    volatile uint32_t RLR; /* 0x08 reload value, bits 11:0 */
    volatile uint32_t SR;  /* 0x0C status */
} stm32_iwdg_regs_t;

_Static_assert(offsetof(stm32_iwdg_regs_t, KR) == 0x00u, "IWDG_KR offset");
_Static_assert(offsetof(stm32_iwdg_regs_t, PR) == 0x04u, "IWDG_PR offset");
_Static_assert(offsetof(stm32_iwdg_regs_t, RLR) == 0x08u, "IWDG_RLR offset");
_Static_assert(offsetof(stm32_iwdg_regs_t, SR) == 0x0Cu, "IWDG_SR offset");
_Static_assert(sizeof(stm32_iwdg_regs_t) == 0x10u, "IWDG register block size");

/* ---- keys and bits (RM0090 21.4.1 .. 21.4.4) ---- */

#define STM32_IWDG_KEY_RELOAD 0xAAAAu /* reload the counter from RLR (the kick) */
#define STM32_IWDG_KEY_ACCESS 0x5555u /* allow writes to PR and RLR */
#define STM32_IWDG_KEY_START 0xCCCCu  /* start the watchdog (and the LSI) */
#define STM32_IWDG_PR_MAX 6u          /* /256 (7 is also /256) */
#define STM32_IWDG_RLR_MAX 0xFFFu
#define STM32_IWDG_SR_PVU (1u << 0) /* a prescaler update is in progress */
#define STM32_IWDG_SR_RVU (1u << 1) /* a reload value update is in progress */

#define STM32_IWDG_LSI_NOMINAL_HZ 32000u
#define STM32_IWDG_LSI_MIN_HZ 17000u /* STM32F405 datasheet, f_LSI */
#define STM32_IWDG_LSI_MAX_HZ 47000u
#define STM32_IWDG_TIMEOUT_MIN_MS 1u
#define STM32_IWDG_TIMEOUT_MAX_MS 32768u /* 4096 x 256 / 32 kHz */
/* the running timeout (see the tolerance note above) */
#define STM32_IWDG_DEFAULT_TIMEOUT_MS 200u
/* the timeout around a flash save (see the erase note above) */
#define STM32_IWDG_ERASE_TIMEOUT_MS 2000u

/*
 * The prescaler and reload for a nominal timeout of timeout_ms at 32 kHz: the smallest
 * PR (0..6, divider 4 << PR) with round(timeout_ms x 32 / divider) <= 4096, and
 * RLR = that count - 1. Returns 0 and *pr, *rlr; HAL_EINVAL (NULL pointer, timeout_ms
 * outside STM32_IWDG_TIMEOUT_MIN_MS..STM32_IWDG_TIMEOUT_MAX_MS).
 */
int stm32_iwdg_compute(uint32_t timeout_ms, uint32_t *pr, uint32_t *rlr);

/* The timeout in microseconds that PR and RLR give with an LSI of lsi_hz:
 * (RLR + 1) x (4 << PR) x 10^6 / lsi_hz, rounded down; 0 for PR > 6 or lsi_hz outside
 * 1 kHz .. 1 MHz. */
uint32_t stm32_iwdg_timeout_us(uint32_t pr, uint32_t rlr, uint32_t lsi_hz);

typedef struct {
    stm32_iwdg_regs_t *regs;
    uint32_t timeout_ms; /* nominal timeout, e.g. STM32_IWDG_DEFAULT_TIMEOUT_MS */
    /* bound of each wait for SR.PVU and SR.RVU to clear, in polls (> 0); an update takes
     * up to 5 LSI cycles (300 us at 17 kHz) */
    uint32_t timeout_polls;
    /* optional: called before every poll of SR (so at least once per wait; the host
     * tests play the hardware here); NULL for none */
    void (*wait_hook)(void *ctx);
    void *hook_ctx;
} stm32_iwdg_config_t;

/* One watchdog. Caller-owned; all fields are private. */
typedef struct {
    stm32_iwdg_config_t cfg;
    uint32_t pr;  /* as last programmed */
    uint32_t rlr;
} stm32_iwdg_t;

/*
 * Start the watchdog with cfg->timeout_ms (RM0090 21.3; the order of STM32CubeF4's
 * HAL_IWDG_Init):
 *  1. KR = 0xCCCC: start; this also turns the LSI on, which the PR/RLR updates need
 *     (the counter starts from 0xFFF at /4: 512 ms nominal, 348 ms at 47 kHz);
 *  2. wait for SR.PVU = SR.RVU = 0 (an earlier update finished);
 *  3. KR = 0x5555, PR, RLR; wait for SR.PVU = SR.RVU = 0;
 *  4. KR = 0xAAAA: load RLR into the counter (and protect PR/RLR again).
 * Each wait polls SR at most cfg->timeout_polls times, calling cfg->wait_hook before
 * each poll. Calling it again on a running watchdog is stm32_iwdg_set_timeout.
 * Returns 0; HAL_EINVAL (NULL pointer, timeout_polls 0, timeout_ms out of range: nothing
 * written, the watchdog not started); HAL_EIO when an update did not finish in time
 * (the watchdog then runs, with the old or new values; the counter was reloaded).
 */
int stm32_iwdg_init(stm32_iwdg_t *dev, const stm32_iwdg_config_t *cfg);

/*
 * Change the timeout of the running watchdog: wait for SR clear, KR = 0x5555, PR, RLR,
 * wait for SR clear, KR = 0xAAAA (the new reload takes effect with this kick).
 * Returns 0; HAL_EINVAL (NULL dev, timeout_ms out of range: nothing written); HAL_EIO
 * when an update did not finish in time (the counter was still reloaded).
 */
int stm32_iwdg_set_timeout(stm32_iwdg_t *dev, uint32_t timeout_ms);

/* Reload the counter: KR = 0xAAAA (nothing for a NULL dev). */
void stm32_iwdg_kick(stm32_iwdg_t *dev);

#endif /* NAVECU_STM32_IWDG_H */
