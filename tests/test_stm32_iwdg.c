/*
 * test_stm32_iwdg.c - the STM32F405 independent-watchdog driver
 * (hal/cortex_m4f/stm32_iwdg.c) against a register block in RAM.
 *
 * The test plays the hardware from the driver's wait hook (called before every poll of
 * SR): KR is write-only (reads 0), so the hook logs each key written and clears KR;
 * 0xCCCC starts the watchdog, 0x5555 opens PR and RLR for writing and any other key
 * closes them again (RM0090 21.3). A change of PR or RLR is an update that shows
 * SR.PVU / SR.RVU for two polls; a change while PR/RLR are closed, or while an update is
 * still in progress, is a protocol violation the test counts (the hardware would ignore
 * it). The last key of a call (the 0xAAAA reload) stays in KR for the test to read.
 *
 * Expected values follow RM0090 21.4: PR bits 2:0 (divider 4 << PR), RLR bits 11:0,
 * SR.PVU bit 0, SR.RVU bit 1; timeout = (RLR + 1) x (4 << PR) / f_LSI.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "stm32_iwdg.h"

#define POLLS 20u

static stm32_iwdg_regs_t regs;
static stm32_iwdg_t dev;

static struct {
    uint32_t keys[8]; /* keys seen, in order */
    unsigned n_keys;
    int started;
    int open;         /* PR/RLR writable (after 0x5555) */
    uint32_t pr, rlr; /* the values the hardware holds */
    unsigned busy;    /* polls an update stays in progress */
    int stuck;        /* SR.PVU never clears */
    unsigned violations;
    unsigned hook_calls;
} hw;

static void hw_hook(void *ctx)
{
    (void)ctx;
    hw.hook_calls++;
    uint32_t key = regs.KR;
    if (key != 0u) {
        regs.KR = 0u;
        if (hw.n_keys < 8u) {
            hw.keys[hw.n_keys] = key;
        }
        hw.n_keys++;
        hw.open = key == 0x5555u;
        if (key == 0xCCCCu) {
            hw.started = 1;
        }
    }
    if (regs.PR != hw.pr || regs.RLR != hw.rlr) {
        if (!hw.open || hw.busy > 0u || !hw.started) {
            hw.violations++;
        }
        hw.pr = regs.PR;
        hw.rlr = regs.RLR;
        hw.busy = 2u;
    }
    if (hw.stuck) {
        regs.SR = 0x3u;
    } else if (hw.busy > 0u) {
        regs.SR = 0x3u; /* PVU bit 0, RVU bit 1 */
        hw.busy--;
    } else {
        regs.SR = 0u;
    }
}

static stm32_iwdg_config_t config(uint32_t timeout_ms)
{
    stm32_iwdg_config_t cfg = {&regs, timeout_ms, POLLS, hw_hook, NULL};
    return cfg;
}

static int setup(void **state)
{
    (void)state;
    memset((void *)&regs, 0, sizeof regs);
    regs.RLR = 0xFFFu; /* reset values: PR 0, RLR 0xFFF */
    memset(&hw, 0, sizeof hw);
    hw.rlr = 0xFFFu;
    return 0;
}

static void assert_pr_rlr(uint32_t timeout_ms, uint32_t want_pr, uint32_t want_rlr)
{
    uint32_t pr = 99;
    uint32_t rlr = 99;
    assert_int_equal(stm32_iwdg_compute(timeout_ms, &pr, &rlr), 0);
    assert_int_equal(pr, want_pr);
    assert_int_equal(rlr, want_rlr);
}

static void test_register_offsets(void **state)
{
    (void)state;
    assert_int_equal(offsetof(stm32_iwdg_regs_t, KR), 0x0);
    assert_int_equal(offsetof(stm32_iwdg_regs_t, PR), 0x4);
    assert_int_equal(offsetof(stm32_iwdg_regs_t, RLR), 0x8);
    assert_int_equal(offsetof(stm32_iwdg_regs_t, SR), 0xC);
}

/* timeout x 32 kHz LSI cycles over the smallest divider 4 << PR that fits 4096 counts */
static void test_prescaler_and_reload_for_timeouts(void **state)
{
    (void)state;
    assert_pr_rlr(100u, 0u, 799u);    /* 3200 cycles / 4 = 800 */
    assert_pr_rlr(200u, 0u, 1599u);   /* 6400 / 4 = 1600 */
    assert_pr_rlr(512u, 0u, 4095u);   /* 16384 / 4 = 4096: the largest at /4 */
    assert_pr_rlr(513u, 1u, 2051u);   /* 16416 / 8 = 2052 */
    assert_pr_rlr(1000u, 1u, 3999u);  /* 32000 / 8 = 4000 */
    assert_pr_rlr(2000u, 2u, 3999u);  /* 64000 / 16 = 4000 */
    assert_pr_rlr(10000u, 5u, 2499u); /* 320000 / 128 = 2500 */
    assert_pr_rlr(1u, 0u, 7u);        /* 32 / 4 = 8 */
    assert_pr_rlr(32768u, 6u, 4095u); /* 1048576 / 256 = 4096: the longest */

    uint32_t pr = 7;
    uint32_t rlr = 7;
    assert_int_equal(stm32_iwdg_compute(0u, &pr, &rlr), HAL_EINVAL);
    assert_int_equal(stm32_iwdg_compute(32769u, &pr, &rlr), HAL_EINVAL);
    assert_int_equal(stm32_iwdg_compute(UINT32_MAX, &pr, &rlr), HAL_EINVAL);
    assert_int_equal(stm32_iwdg_compute(200u, NULL, &rlr), HAL_EINVAL);
    assert_int_equal(stm32_iwdg_compute(200u, &pr, NULL), HAL_EINVAL);
    assert_int_equal(pr, 7);
    assert_int_equal(rlr, 7);
}

/* GIVEN the default 200 ms nominal WHEN the LSI runs at its datasheet extremes THEN the
 * real timeout stays above the 100 ms kick period of hal.h */
static void test_default_timeout_with_lsi_tolerance(void **state)
{
    (void)state;
    uint32_t pr = 0;
    uint32_t rlr = 0;
    assert_int_equal(stm32_iwdg_compute(STM32_IWDG_DEFAULT_TIMEOUT_MS, &pr, &rlr), 0);
    assert_int_equal(stm32_iwdg_timeout_us(pr, rlr, 32000u), 200000u);
    /* 6400 cycles: 136.17 ms at 47 kHz, 376.47 ms at 17 kHz */
    assert_int_equal(stm32_iwdg_timeout_us(pr, rlr, STM32_IWDG_LSI_MAX_HZ), 136170u);
    assert_int_equal(stm32_iwdg_timeout_us(pr, rlr, STM32_IWDG_LSI_MIN_HZ), 376470u);
    assert_true(stm32_iwdg_timeout_us(pr, rlr, STM32_IWDG_LSI_MAX_HZ) > 100000u);
    /* the save timeout covers two 500 ms sector erases with the fastest LSI */
    assert_int_equal(stm32_iwdg_compute(STM32_IWDG_ERASE_TIMEOUT_MS, &pr, &rlr), 0);
    assert_int_equal(stm32_iwdg_timeout_us(pr, rlr, STM32_IWDG_LSI_MAX_HZ), 1361702u);
    assert_true(stm32_iwdg_timeout_us(pr, rlr, STM32_IWDG_LSI_MAX_HZ) > 2u * 500000u);
    /* RM0090 21.3, timeout table at 32 kHz: /4 0.125 .. 512 ms, /256 8 ms .. 32768 ms */
    assert_int_equal(stm32_iwdg_timeout_us(0u, 0u, 32000u), 125u);
    assert_int_equal(stm32_iwdg_timeout_us(0u, 0xFFFu, 32000u), 512000u);
    assert_int_equal(stm32_iwdg_timeout_us(6u, 0u, 32000u), 8000u);
    assert_int_equal(stm32_iwdg_timeout_us(6u, 0xFFFu, 32000u), 32768000u);
    assert_int_equal(stm32_iwdg_timeout_us(7u, 0u, 32000u), 0u);
    assert_int_equal(stm32_iwdg_timeout_us(0u, 0u, 0u), 0u);
    assert_int_equal(stm32_iwdg_timeout_us(0u, 0u, 999u), 0u);
    assert_int_equal(stm32_iwdg_timeout_us(0u, 0u, 1000001u), 0u);
    /* the extremes of the range: 2^20 cycles at 1 kHz, 4 cycles at 1 MHz */
    assert_int_equal(stm32_iwdg_timeout_us(6u, 0xFFFu, 1000u), 1048576000u);
    assert_int_equal(stm32_iwdg_timeout_us(0u, 0u, 1000000u), 4u);
    assert_int_equal(stm32_iwdg_timeout_us(6u, 0xFFFu, 999999u), 1048577u);
}

/* init: 0xCCCC (start, LSI on), 0x5555, PR/RLR once SR is clear, wait, 0xAAAA */
static void test_init_key_order_and_registers(void **state)
{
    (void)state;
    stm32_iwdg_config_t cfg = config(STM32_IWDG_DEFAULT_TIMEOUT_MS);
    assert_int_equal(stm32_iwdg_init(&dev, &cfg), 0);
    assert_int_equal(hw.n_keys, 2);
    assert_int_equal(hw.keys[0], 0xCCCCu);
    assert_int_equal(hw.keys[1], 0x5555u);
    assert_int_equal(regs.KR, 0xAAAAu); /* the last key: reload, PR/RLR closed */
    assert_true(hw.started);
    assert_int_equal(regs.PR, 0u);
    assert_int_equal(regs.RLR, 1599u);
    assert_int_equal(hw.violations, 0);
    /* 1 poll before writing (SR clear), 3 after: PVU/RVU shown for 2 polls */
    assert_int_equal(hw.hook_calls, 4);
    assert_int_equal(regs.SR, 0u);

    setup(NULL);
    cfg = config(10000u);
    assert_int_equal(stm32_iwdg_init(&dev, &cfg), 0);
    assert_int_equal(regs.PR, 5u);
    assert_int_equal(regs.RLR, 2499u);
    assert_int_equal(hw.violations, 0);
}

static void test_init_invalid_writes_nothing(void **state)
{
    (void)state;
    stm32_iwdg_config_t cfg = config(0u);
    assert_int_equal(stm32_iwdg_init(&dev, &cfg), HAL_EINVAL);
    cfg = config(40000u);
    assert_int_equal(stm32_iwdg_init(&dev, &cfg), HAL_EINVAL);
    cfg = config(200u);
    cfg.timeout_polls = 0u;
    assert_int_equal(stm32_iwdg_init(&dev, &cfg), HAL_EINVAL);
    cfg = config(200u);
    cfg.regs = NULL;
    assert_int_equal(stm32_iwdg_init(&dev, &cfg), HAL_EINVAL);
    assert_int_equal(stm32_iwdg_init(NULL, &cfg), HAL_EINVAL);
    assert_int_equal(stm32_iwdg_init(&dev, NULL), HAL_EINVAL);
    assert_int_equal(regs.KR, 0u);
    assert_int_equal(regs.PR, 0u);
    assert_int_equal(regs.RLR, 0xFFFu);
    assert_int_equal(hw.hook_calls, 0);
}

/* GIVEN an update still in progress from before WHEN init runs THEN PR/RLR are written
 * only once SR is clear (4 polls: SR shown busy 3 times), then 3 polls as usual */
static void test_init_waits_for_earlier_update(void **state)
{
    (void)state;
    hw.busy = 3u;
    hw.started = 1;
    stm32_iwdg_config_t cfg = config(1000u);
    assert_int_equal(stm32_iwdg_init(&dev, &cfg), 0);
    assert_int_equal(hw.violations, 0);
    assert_int_equal(regs.PR, 1u);
    assert_int_equal(regs.RLR, 3999u);
    assert_int_equal(hw.hook_calls, 4u + 3u);
}

/* GIVEN PVU/RVU that never clear WHEN init runs THEN HAL_EIO after the bound, with the
 * watchdog started and the counter reloaded */
static void test_update_timeout_is_eio(void **state)
{
    (void)state;
    hw.stuck = 1;
    stm32_iwdg_config_t cfg = config(200u);
    assert_int_equal(stm32_iwdg_init(&dev, &cfg), HAL_EIO);
    assert_int_equal(hw.hook_calls, POLLS);
    assert_int_equal(hw.n_keys, 1);
    assert_int_equal(hw.keys[0], 0xCCCCu);
    assert_int_equal(regs.KR, 0xAAAAu);
    assert_int_equal(regs.RLR, 0xFFFu); /* not written while an update was pending */

    /* a running watchdog whose update hangs */
    setup(NULL);
    hw.stuck = 0;
    assert_int_equal(stm32_iwdg_init(&dev, &cfg), 0);
    assert_int_equal(stm32_iwdg_set_timeout(&dev, 100u), 0);
    hw.stuck = 1;
    hw.hook_calls = 0;
    /* every poll sees SR set: no write at all, then a reload */
    assert_int_equal(stm32_iwdg_set_timeout(&dev, 1000u), HAL_EIO);
    assert_int_equal(hw.hook_calls, POLLS);
    assert_int_equal(regs.RLR, 799u);
    assert_int_equal(regs.KR, 0xAAAAu);
}

/* set_timeout on the running watchdog: no second start, 0x5555 then the new values */
static void test_set_timeout_for_a_flash_save(void **state)
{
    (void)state;
    stm32_iwdg_config_t cfg = config(STM32_IWDG_DEFAULT_TIMEOUT_MS);
    assert_int_equal(stm32_iwdg_init(&dev, &cfg), 0);
    hw.n_keys = 0;
    hw_hook(NULL); /* the hardware takes the 0xAAAA of init */
    hw.n_keys = 0;
    assert_int_equal(stm32_iwdg_set_timeout(&dev, STM32_IWDG_ERASE_TIMEOUT_MS), 0);
    assert_int_equal(hw.n_keys, 1);
    assert_int_equal(hw.keys[0], 0x5555u);
    assert_int_equal(regs.KR, 0xAAAAu);
    assert_int_equal(regs.PR, 2u);
    assert_int_equal(regs.RLR, 3999u);
    assert_int_equal(stm32_iwdg_set_timeout(&dev, STM32_IWDG_DEFAULT_TIMEOUT_MS), 0);
    assert_int_equal(regs.PR, 0u);
    assert_int_equal(regs.RLR, 1599u);
    assert_int_equal(hw.violations, 0);
    assert_int_equal(stm32_iwdg_set_timeout(&dev, 0u), HAL_EINVAL);
    assert_int_equal(stm32_iwdg_set_timeout(NULL, 200u), HAL_EINVAL);
    assert_int_equal(regs.RLR, 1599u);
}

static void test_kick_writes_reload_key(void **state)
{
    (void)state;
    stm32_iwdg_config_t cfg = config(STM32_IWDG_DEFAULT_TIMEOUT_MS);
    assert_int_equal(stm32_iwdg_init(&dev, &cfg), 0);
    hw_hook(NULL);
    assert_int_equal(regs.KR, 0u);
    hw.n_keys = 0;
    stm32_iwdg_kick(&dev);
    assert_int_equal(regs.KR, 0xAAAAu);
    hw_hook(NULL);
    stm32_iwdg_kick(&dev);
    hw_hook(NULL);
    assert_int_equal(hw.n_keys, 2);
    assert_int_equal(hw.keys[0], 0xAAAAu);
    assert_int_equal(hw.keys[1], 0xAAAAu);
    assert_int_equal(regs.PR, 0u); /* a kick changes nothing else */
    assert_int_equal(regs.RLR, 1599u);
    stm32_iwdg_kick(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_register_offsets),
        cmocka_unit_test(test_prescaler_and_reload_for_timeouts),
        cmocka_unit_test(test_default_timeout_with_lsi_tolerance),
        cmocka_unit_test_setup(test_init_key_order_and_registers, setup),
        cmocka_unit_test_setup(test_init_invalid_writes_nothing, setup),
        cmocka_unit_test_setup(test_init_waits_for_earlier_update, setup),
        cmocka_unit_test_setup(test_update_timeout_is_eio, setup),
        cmocka_unit_test_setup(test_set_timeout_for_a_flash_save, setup),
        cmocka_unit_test_setup(test_kick_writes_reload_key, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
