/*
 * test_stm32_clock.c - the STM32F405 clock setup (hal/cortex_m4f/stm32_clock.c) against
 * RCC, PWR and FLASH register blocks in RAM.
 *
 * The test plays the hardware from the driver's wait hook (called before every poll):
 * RCC_CR.HSERDY follows HSEON (unless the test has no crystal), PLLRDY follows PLLON once
 * the HSE is ready (unless the PLL is broken), CFGR.SWS follows CFGR.SW (unless the test
 * refuses the switch to the PLL); FLASH_ACR keeps what is written (unless the test makes
 * the latency field stick at 0). At the moment the PLL starts and the moment SW selects
 * the PLL it records the registers, so the test can check the order: PLLCFGR complete
 * before PLLON; wait states and bus prescalers set before the switch.
 *
 * Expected values are written from RM0090's bit positions (7.3.1..7.3.13, 5.4.1, 3.9.1),
 * not from the driver's macros: RCC_CR HSEON bit 16, HSERDY 17, HSEBYP 18, PLLON 24,
 * PLLRDY 25; PLLCFGR PLLM 5:0, PLLN 14:6, PLLP 17:16 (0 = /2), PLLSRC 22, PLLQ 27:24;
 * CFGR SW 1:0, SWS 3:2 (2 = PLL), HPRE 7:4, PPRE1 12:10, PPRE2 15:13 (100 = /2,
 * 101 = /4); AHB1ENR GPIOAEN 0, GPIOBEN 1; APB1ENR TIM2EN 0, CAN1EN 25, PWREN 28;
 * PWR_CR VOS 14; FLASH_ACR LATENCY 2:0, PRFTEN 8, ICEN 9, DCEN 10.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "stm32_clock.h"

#define POLLS 30u

#define CR_RESET 0x00000083u      /* HSION, HSIRDY, HSITRIM 16 */
#define PLLCFGR_RESET 0x24003010u /* bit 29 reserved at 1, Q 4, N 192, M 16 */
#define CR_HSEON (1u << 16)
#define CR_HSERDY (1u << 17)
#define CR_HSEBYP (1u << 18)
#define CR_PLLON (1u << 24)
#define CR_PLLRDY (1u << 25)
/* M 8 | N 336 << 6 | P /2 (0) << 16 | PLLSRC HSE bit 22 | Q 7 << 24, reserved bit 29 */
#define PLLCFGR_168 (8u | (336u << 6) | (0u << 16) | (1u << 22) | (7u << 24))
#define ACR_168 (5u | (1u << 8) | (1u << 9) | (1u << 10))
#define CFGR_PRESCALERS ((0x5u << 10) | (0x4u << 13)) /* APB1 /4, APB2 /2, AHB /1 */

static stm32_rcc_regs_t rcc;
static stm32_pwr_regs_t pwr;
static stm32_flash_regs_t flash;

static struct {
    int no_crystal;
    int pll_broken;
    int refuse_pll_switch;
    int latency_sticks;
    unsigned hook_calls;
    int pll_started;
    uint32_t pllcfgr_at_pllon;
    uint32_t cr_at_pllon;
    int switched;
    uint32_t acr_at_switch;
    uint32_t cfgr_at_switch;
    uint32_t pwr_cr_at_switch;
} hw;

static void hw_hook(void *ctx)
{
    (void)ctx;
    hw.hook_calls++;
    uint32_t cr = rcc.CR;
    if ((cr & CR_HSEON) != 0u && !hw.no_crystal) {
        cr |= CR_HSERDY;
    } else {
        cr &= ~CR_HSERDY;
    }
    if ((cr & CR_PLLON) != 0u && (cr & CR_HSERDY) != 0u && !hw.pll_broken) {
        if ((cr & CR_PLLRDY) == 0u) {
            hw.pll_started = 1;
            hw.pllcfgr_at_pllon = rcc.PLLCFGR;
            hw.cr_at_pllon = cr;
        }
        cr |= CR_PLLRDY;
    } else {
        cr &= ~CR_PLLRDY;
    }
    rcc.CR = cr;
    if (hw.latency_sticks) {
        flash.ACR &= ~0x7u;
    }
    uint32_t sw = rcc.CFGR & 0x3u;
    uint32_t sws = (rcc.CFGR >> 2) & 0x3u;
    if (sw == 2u && sws != 2u && !hw.refuse_pll_switch && (cr & CR_PLLRDY) != 0u) {
        hw.switched = 1;
        hw.acr_at_switch = flash.ACR;
        hw.cfgr_at_switch = rcc.CFGR;
        hw.pwr_cr_at_switch = pwr.CR;
        sws = 2u;
    } else if (sw == 0u) {
        sws = 0u;
    }
    rcc.CFGR = (rcc.CFGR & ~0xCu) | (sws << 2);
}

static stm32_clock_config_t config(void)
{
    stm32_clock_config_t cfg = {&rcc, &pwr, &flash, 0u, POLLS, hw_hook, NULL};
    return cfg;
}

static int setup(void **state)
{
    (void)state;
    memset((void *)&rcc, 0, sizeof rcc);
    memset((void *)&pwr, 0, sizeof pwr);
    memset((void *)&flash, 0, sizeof flash);
    rcc.CR = CR_RESET;
    rcc.PLLCFGR = PLLCFGR_RESET;
    rcc.AHB1ENR = 0x00100000u; /* CCMDATARAMEN at reset */
    pwr.CR = 0u; /* reset is VOS = 1; 0 here so that the test sees the driver set it */
    memset(&hw, 0, sizeof hw);
    return 0;
}

static void assert_on_hsi_16mhz(const stm32_clock_status_t *st)
{
    assert_int_equal(st->source, STM32_CLOCK_SRC_HSI);
    assert_int_equal(st->sysclk_hz, 16000000u);
    assert_int_equal(st->hclk_hz, 16000000u);
    assert_int_equal(st->pclk1_hz, 16000000u);
    assert_int_equal(st->pclk2_hz, 16000000u);
    assert_int_equal(st->tim_apb1_hz, 16000000u);
    assert_int_equal((rcc.CFGR >> 2) & 0x3u, 0u); /* SWS = HSI */
    assert_int_equal(rcc.CFGR & 0xFFF3u, 0u);     /* SW HSI, prescalers /1 */
    assert_int_equal(rcc.CR & (CR_HSEON | CR_HSEBYP | CR_PLLON), 0u);
}

static void test_register_offsets(void **state)
{
    (void)state;
    assert_int_equal(offsetof(stm32_rcc_regs_t, CR), 0x00);
    assert_int_equal(offsetof(stm32_rcc_regs_t, PLLCFGR), 0x04);
    assert_int_equal(offsetof(stm32_rcc_regs_t, CFGR), 0x08);
    assert_int_equal(offsetof(stm32_rcc_regs_t, AHB1ENR), 0x30);
    assert_int_equal(offsetof(stm32_rcc_regs_t, APB1ENR), 0x40);
    assert_int_equal(offsetof(stm32_rcc_regs_t, APB2ENR), 0x44);
    assert_int_equal(offsetof(stm32_rcc_regs_t, CSR), 0x74);
    assert_int_equal(offsetof(stm32_pwr_regs_t, CR), 0x00);
}

/* GIVEN the reset state and a working 8 MHz crystal WHEN init runs THEN 168 MHz from the
 * PLL with every register as RM0090 places the fields */
static void test_init_168mhz_register_values(void **state)
{
    (void)state;
    stm32_clock_config_t cfg = config();
    stm32_clock_status_t st;
    memset(&st, 0xA5, sizeof st);
    assert_int_equal(stm32_clock_init(&cfg, &st), 0);
    assert_int_equal(rcc.CR, CR_RESET | CR_HSEON | CR_HSERDY | CR_PLLON | CR_PLLRDY);
    assert_int_equal(rcc.PLLCFGR, 0x27405408u); /* reserved bit 29 kept */
    assert_int_equal(rcc.PLLCFGR, PLLCFGR_168 | (1u << 29));
    /* SW PLL (2), SWS PLL (2 << 2), APB1 /4, APB2 /2, AHB /1 */
    assert_int_equal(rcc.CFGR, 0x2u | (0x2u << 2) | CFGR_PRESCALERS);
    assert_int_equal(rcc.CFGR, 0x940Au);
    assert_int_equal(flash.ACR, ACR_168);
    assert_int_equal(flash.ACR, 0x705u);
    assert_int_equal(pwr.CR, 1u << 14);
    assert_int_equal(rcc.APB1ENR, 1u << 28);
    assert_int_equal(st.source, STM32_CLOCK_SRC_PLL);
    assert_int_equal(st.fault, STM32_CLOCK_FAULT_NONE);
    assert_int_equal(st.sysclk_hz, 168000000u);
    assert_int_equal(st.hclk_hz, 168000000u);
    assert_int_equal(st.pclk1_hz, 42000000u);
    assert_int_equal(st.pclk2_hz, 84000000u);
    assert_int_equal(st.tim_apb1_hz, 84000000u);
    assert_int_equal(st.tim_apb2_hz, 168000000u);
    /* each wait answered at its first poll: HSE, PLL, latency, switch */
    assert_int_equal(hw.hook_calls, 4);
    /* without a status and with an external clock (HSEBYP) */
    setup(NULL);
    cfg.hse_bypass = 1u;
    assert_int_equal(stm32_clock_init(&cfg, NULL), 0);
    assert_int_equal(rcc.CR & CR_HSEBYP, CR_HSEBYP);
    assert_int_equal(rcc.CFGR, 0x940Au);
}

/* the order: PLLCFGR complete and HSE ready before PLLON; 5 wait states, the bus
 * prescalers and VOS set before SW selects the PLL */
static void test_init_order_latency_before_switch(void **state)
{
    (void)state;
    stm32_clock_config_t cfg = config();
    assert_int_equal(stm32_clock_init(&cfg, NULL), 0);
    assert_true(hw.pll_started);
    assert_int_equal(hw.pllcfgr_at_pllon, 0x27405408u);
    assert_int_equal(hw.cr_at_pllon & CR_HSERDY, CR_HSERDY);
    assert_true(hw.switched);
    assert_int_equal(hw.acr_at_switch & 0x7u, 5u);
    assert_int_equal(hw.acr_at_switch, 0x705u);
    assert_int_equal(hw.cfgr_at_switch & 0xFCF0u, CFGR_PRESCALERS);
    assert_int_equal(hw.pwr_cr_at_switch, 1u << 14);
}

/* GIVEN no crystal WHEN init runs THEN HAL_EIO after the bound, still on the HSI at
 * 16 MHz with the HSE off, the PLL and the flash untouched, and the status says so */
static void test_hse_failure_stays_on_hsi(void **state)
{
    (void)state;
    hw.no_crystal = 1;
    stm32_clock_config_t cfg = config();
    cfg.hse_bypass = 1u;
    stm32_clock_status_t st;
    assert_int_equal(stm32_clock_init(&cfg, &st), HAL_EIO);
    assert_int_equal(st.fault, STM32_CLOCK_FAULT_HSE);
    assert_on_hsi_16mhz(&st);
    assert_int_equal(hw.hook_calls, POLLS + 1u); /* + 1: the check that SWS is HSI */
    assert_int_equal(rcc.PLLCFGR, PLLCFGR_RESET);
    assert_int_equal(flash.ACR, 0u);
    assert_false(hw.switched);
}

static void test_pll_failure_stays_on_hsi(void **state)
{
    (void)state;
    hw.pll_broken = 1;
    stm32_clock_config_t cfg = config();
    stm32_clock_status_t st;
    assert_int_equal(stm32_clock_init(&cfg, &st), HAL_EIO);
    assert_int_equal(st.fault, STM32_CLOCK_FAULT_PLL);
    assert_on_hsi_16mhz(&st);
    assert_int_equal(hw.hook_calls, 1u + POLLS + 1u);
    assert_int_equal(flash.ACR, 0u); /* never raised */
}

static void test_latency_not_taken_stays_on_hsi(void **state)
{
    (void)state;
    hw.latency_sticks = 1;
    stm32_clock_config_t cfg = config();
    stm32_clock_status_t st;
    assert_int_equal(stm32_clock_init(&cfg, &st), HAL_EIO);
    assert_int_equal(st.fault, STM32_CLOCK_FAULT_LATENCY);
    assert_on_hsi_16mhz(&st);
    assert_false(hw.switched);
}

/* GIVEN a switch that SWS never confirms WHEN init runs THEN HAL_EIO, SW back to the HSI
 * with prescalers /1, PLL and HSE off; the 5 wait states stay (fine at 16 MHz) */
static void test_switch_failure_goes_back_to_hsi(void **state)
{
    (void)state;
    hw.refuse_pll_switch = 1;
    stm32_clock_config_t cfg = config();
    stm32_clock_status_t st;
    assert_int_equal(stm32_clock_init(&cfg, &st), HAL_EIO);
    assert_int_equal(st.fault, STM32_CLOCK_FAULT_SWITCH);
    assert_on_hsi_16mhz(&st);
    assert_int_equal(flash.ACR, 0x705u);
    assert_int_equal(hw.hook_calls, 3u + POLLS + 1u);
}

static void test_init_invalid_or_not_from_reset(void **state)
{
    (void)state;
    stm32_clock_config_t cfg = config();
    stm32_clock_status_t st;
    assert_int_equal(stm32_clock_init(NULL, &st), HAL_EINVAL);
    cfg.timeout_polls = 0u;
    assert_int_equal(stm32_clock_init(&cfg, &st), HAL_EINVAL);
    cfg = config();
    cfg.flash = NULL;
    assert_int_equal(stm32_clock_init(&cfg, &st), HAL_EINVAL);
    /* already running from the PLL */
    cfg = config();
    rcc.CFGR = 0x2u | (0x2u << 2);
    rcc.CR |= CR_PLLON | CR_PLLRDY;
    assert_int_equal(stm32_clock_init(&cfg, &st), HAL_EINVAL);
    assert_int_equal(rcc.PLLCFGR, PLLCFGR_RESET);
    assert_int_equal(hw.hook_calls, 0);
}

/* the status decodes any register setting: the HSI PLL, odd prescalers */
static void test_status_decodes_registers(void **state)
{
    (void)state;
    stm32_clock_status_t st;
    assert_int_equal(stm32_clock_status(&rcc, &st), 0); /* reset: HSI */
    assert_int_equal(st.sysclk_hz, 16000000u);
    /* HSE direct, AHB /2 (1000), APB1 /16 (111), APB2 /1 */
    rcc.CFGR = (0x1u << 2) | (0x8u << 4) | (0x7u << 10);
    assert_int_equal(stm32_clock_status(&rcc, &st), 0);
    assert_int_equal(st.source, STM32_CLOCK_SRC_HSE);
    assert_int_equal(st.hclk_hz, 4000000u);
    assert_int_equal(st.pclk1_hz, 250000u);
    assert_int_equal(st.tim_apb1_hz, 500000u);
    assert_int_equal(st.pclk2_hz, 4000000u);
    assert_int_equal(st.tim_apb2_hz, 4000000u);
    /* PLL from the HSI: 16 MHz / 16 x 192 / 4 (P field 1) = 48 MHz; AHB /64 (1100) */
    rcc.PLLCFGR = 16u | (192u << 6) | (1u << 16);
    rcc.CFGR = (0x2u << 2) | (0xCu << 4);
    assert_int_equal(stm32_clock_status(&rcc, &st), 0);
    assert_int_equal(st.source, STM32_CLOCK_SRC_PLL);
    assert_int_equal(st.sysclk_hz, 48000000u);
    assert_int_equal(st.hclk_hz, 750000u);
    /* AHB /512 (1111) */
    rcc.CFGR = (0x2u << 2) | (0xFu << 4);
    assert_int_equal(stm32_clock_status(&rcc, &st), 0);
    assert_int_equal(st.hclk_hz, 93750u);
    /* M that does not divide the input: 8 MHz / 3 x 100 / 2 = 133.33 MHz, rounded down */
    rcc.PLLCFGR = 3u | (100u << 6) | (1u << 22);
    rcc.CFGR = 0x2u << 2;
    assert_int_equal(stm32_clock_status(&rcc, &st), 0);
    assert_int_equal(st.sysclk_hz, 133333333u);
    /* the largest field values: HSI 16 MHz / 2 x 511 / 8 = 511 MHz (out of spec, but
     * computed without overflow) */
    rcc.PLLCFGR = 2u | (511u << 6) | (3u << 16);
    assert_int_equal(stm32_clock_status(&rcc, &st), 0);
    assert_int_equal(st.sysclk_hz, 511000000u);
    /* PLLM 0 or 1 is not allowed */
    rcc.PLLCFGR = 1u | (192u << 6);
    assert_int_equal(stm32_clock_status(&rcc, &st), HAL_EINVAL);
    assert_int_equal(stm32_clock_status(NULL, &st), HAL_EINVAL);
    assert_int_equal(stm32_clock_status(&rcc, NULL), HAL_EINVAL);
}

static void test_enable_peripheral_clocks(void **state)
{
    (void)state;
    rcc.APB1ENR = 1u << 17; /* USART2, enabled by someone else: kept */
    assert_int_equal(stm32_clock_enable_peripherals(&rcc), 0);
    assert_int_equal(rcc.AHB1ENR, 0x00100000u | (1u << 0) | (1u << 1));
    assert_int_equal(rcc.APB1ENR, (1u << 17) | (1u << 0) | (1u << 25) | (1u << 28));
    assert_int_equal(rcc.APB2ENR, 0u);
    assert_int_equal(stm32_clock_enable_peripherals(NULL), HAL_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_register_offsets),
        cmocka_unit_test_setup(test_init_168mhz_register_values, setup),
        cmocka_unit_test_setup(test_init_order_latency_before_switch, setup),
        cmocka_unit_test_setup(test_hse_failure_stays_on_hsi, setup),
        cmocka_unit_test_setup(test_pll_failure_stays_on_hsi, setup),
        cmocka_unit_test_setup(test_latency_not_taken_stays_on_hsi, setup),
        cmocka_unit_test_setup(test_switch_failure_goes_back_to_hsi, setup),
        cmocka_unit_test_setup(test_init_invalid_or_not_from_reset, setup),
        cmocka_unit_test_setup(test_status_decodes_registers, setup),
        cmocka_unit_test_setup(test_enable_peripheral_clocks, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
