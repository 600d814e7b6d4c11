/*
 * stm32_clock.c - STM32F405 clock setup (stm32_clock.h). Register and bit references are
 * to RM0090 sections 7 (RCC), 5 (PWR) and 3 (FLASH_ACR).
 */
#include "stm32_clock.h"

#define STM32_CLOCK_PLLCFGR                                                        \
    ((STM32_CLOCK_PLLM << STM32_RCC_PLLCFGR_PLLM_SHIFT) |                          \
     (STM32_CLOCK_PLLN << STM32_RCC_PLLCFGR_PLLN_SHIFT) |                          \
     ((STM32_CLOCK_PLLP / 2u - 1u) << STM32_RCC_PLLCFGR_PLLP_SHIFT) |              \
     STM32_RCC_PLLCFGR_PLLSRC_HSE | (STM32_CLOCK_PLLQ << STM32_RCC_PLLCFGR_PLLQ_SHIFT))
#define STM32_CLOCK_ACR                                                            \
    (STM32_CLOCK_FLASH_LATENCY | STM32_FLASH_ACR_PRFTEN | STM32_FLASH_ACR_ICEN |   \
     STM32_FLASH_ACR_DCEN)
#define STM32_CLOCK_PRESCALERS                                                     \
    ((STM32_RCC_PPRE_DIV4 << STM32_RCC_CFGR_PPRE1_SHIFT) |                         \
     (STM32_RCC_PPRE_DIV2 << STM32_RCC_CFGR_PPRE2_SHIFT)) /* HPRE 0: AHB /1 */
#define STM32_CLOCK_CFGR_PRESCALER_MASK                                            \
    (STM32_RCC_CFGR_HPRE_MASK | STM32_RCC_CFGR_PPRE1_MASK | STM32_RCC_CFGR_PPRE2_MASK)

static uint32_t sws(const stm32_rcc_regs_t *rcc)
{
    return (rcc->CFGR >> STM32_RCC_CFGR_SWS_SHIFT) & STM32_RCC_CFGR_SW_MASK;
}

/* Poll *reg until (*reg & mask) == want, at most timeout_polls times, the hook first. */
static int wait_reg(const stm32_clock_config_t *cfg, const volatile uint32_t *reg,
                    uint32_t mask, uint32_t want)
{
    for (uint32_t i = 0; i < cfg->timeout_polls; i++) {
        if (cfg->wait_hook != NULL) {
            cfg->wait_hook(cfg->hook_ctx);
        }
        if ((*reg & mask) == want) {
            return 0;
        }
    }
    return HAL_EIO;
}

/* Back to the HSI with all prescalers /1, then HSE and PLL off (they can only be turned
 * off once they no longer drive SYSCLK). */
static void fall_back_to_hsi(const stm32_clock_config_t *cfg)
{
    stm32_rcc_regs_t *rcc = cfg->rcc;
    rcc->CFGR = (rcc->CFGR & ~(STM32_RCC_CFGR_SW_MASK | STM32_CLOCK_CFGR_PRESCALER_MASK)) |
                STM32_RCC_CFGR_SW_HSI;
    if (wait_reg(cfg, &rcc->CFGR, STM32_RCC_CFGR_SW_MASK << STM32_RCC_CFGR_SWS_SHIFT,
                 STM32_RCC_CFGR_SW_HSI << STM32_RCC_CFGR_SWS_SHIFT) != 0) {
        return; /* still on the PLL: leave it running */
    }
    rcc->CR = rcc->CR & ~STM32_RCC_CR_PLLON;
    rcc->CR = rcc->CR & ~(STM32_RCC_CR_HSEON | STM32_RCC_CR_HSEBYP);
}

static int fail(const stm32_clock_config_t *cfg, stm32_clock_status_t *st,
                stm32_clock_fault_t fault)
{
    fall_back_to_hsi(cfg);
    if (st != NULL) {
        (void)stm32_clock_status(cfg->rcc, st);
        st->fault = fault;
    }
    return HAL_EIO;
}

int stm32_clock_init(const stm32_clock_config_t *cfg, stm32_clock_status_t *st)
{
    if (cfg == NULL || cfg->rcc == NULL || cfg->pwr == NULL || cfg->flash == NULL ||
        cfg->timeout_polls == 0u) {
        return HAL_EINVAL;
    }
    stm32_rcc_regs_t *rcc = cfg->rcc;
    /* PLLCFGR cannot change while the PLL runs, nor the PLL stop while it is SYSCLK */
    if (sws(rcc) != STM32_RCC_CFGR_SW_HSI || (rcc->CR & STM32_RCC_CR_PLLON) != 0u) {
        return HAL_EINVAL;
    }

    /* 1. the regulator at scale 1 (the PWR registers need the PWR clock) */
    rcc->APB1ENR = rcc->APB1ENR | STM32_RCC_APB1ENR_PWREN;
    (void)rcc->APB1ENR;
    cfg->pwr->CR = cfg->pwr->CR | STM32_PWR_CR_VOS;

    /* 2. HSE; HSEBYP may only change while the HSE is off */
    if (cfg->hse_bypass != 0u) {
        rcc->CR = rcc->CR | STM32_RCC_CR_HSEBYP;
    }
    rcc->CR = rcc->CR | STM32_RCC_CR_HSEON;
    if (wait_reg(cfg, &rcc->CR, STM32_RCC_CR_HSERDY, STM32_RCC_CR_HSERDY) != 0) {
        return fail(cfg, st, STM32_CLOCK_FAULT_HSE);
    }

    /* 3. the main PLL from the HSE */
    rcc->PLLCFGR = (rcc->PLLCFGR & ~STM32_RCC_PLLCFGR_FIELDS) | STM32_CLOCK_PLLCFGR;
    rcc->CR = rcc->CR | STM32_RCC_CR_PLLON;
    if (wait_reg(cfg, &rcc->CR, STM32_RCC_CR_PLLRDY, STM32_RCC_CR_PLLRDY) != 0) {
        return fail(cfg, st, STM32_CLOCK_FAULT_PLL);
    }

    /* 4. flash wait states before the clock rises */
    cfg->flash->ACR = STM32_CLOCK_ACR;
    if (wait_reg(cfg, &cfg->flash->ACR, STM32_FLASH_ACR_LATENCY_MASK,
                 STM32_CLOCK_FLASH_LATENCY) != 0) {
        return fail(cfg, st, STM32_CLOCK_FAULT_LATENCY);
    }

    /* 5. bus prescalers before the switch: APB1 never above 42 MHz, APB2 84 MHz */
    rcc->CFGR = (rcc->CFGR & ~STM32_CLOCK_CFGR_PRESCALER_MASK) | STM32_CLOCK_PRESCALERS;

    /* 6. the switch */
    rcc->CFGR = (rcc->CFGR & ~STM32_RCC_CFGR_SW_MASK) | STM32_RCC_CFGR_SW_PLL;
    if (wait_reg(cfg, &rcc->CFGR, STM32_RCC_CFGR_SW_MASK << STM32_RCC_CFGR_SWS_SHIFT,
                 STM32_RCC_CFGR_SW_PLL << STM32_RCC_CFGR_SWS_SHIFT) != 0) {
        return fail(cfg, st, STM32_CLOCK_FAULT_SWITCH);
    }
    if (st != NULL) {
        (void)stm32_clock_status(rcc, st);
    }
    return 0;
}

/* AHB divider from CFGR.HPRE: 0xxx /1, 1000 /2, 1001 /4, 1010 /8, 1011 /16, 1100 /64,
 * 1101 /128, 1110 /256, 1111 /512 (no /32) */
static uint32_t ahb_shift(uint32_t hpre)
{
    if (hpre < 8u) {
        return 0u;
    }
    uint32_t s = hpre - 7u;
    return s >= 5u ? s + 1u : s;
}

/* APB divider from CFGR.PPREx: 0xx /1, 100 /2, 101 /4, 110 /8, 111 /16 */
static uint32_t apb_shift(uint32_t ppre)
{
    return ppre < 4u ? 0u : ppre - 3u;
}

int stm32_clock_status(const stm32_rcc_regs_t *rcc, stm32_clock_status_t *st)
{
    if (rcc == NULL || st == NULL) {
        return HAL_EINVAL;
    }
    uint32_t src = sws(rcc);
    uint32_t sysclk;
    if (src == STM32_RCC_CFGR_SW_PLL) {
        uint32_t pll = rcc->PLLCFGR;
        uint32_t m = (pll >> STM32_RCC_PLLCFGR_PLLM_SHIFT) & 0x3Fu;
        uint32_t n = (pll >> STM32_RCC_PLLCFGR_PLLN_SHIFT) & 0x1FFu;
        uint32_t p = 2u * (((pll >> STM32_RCC_PLLCFGR_PLLP_SHIFT) & 0x3u) + 1u);
        uint32_t in = (pll & STM32_RCC_PLLCFGR_PLLSRC_HSE) != 0u ? STM32_CLOCK_HSE_HZ
                                                                  : STM32_CLOCK_HSI_HZ;
        if (m < 2u) {
            return HAL_EINVAL;
        }
        /* floor(in x N / M) in 32 bits: (in / M) x N <= 8 MHz x 511 < 2^32 for M >= 2,
         * and (in % M) x N < 63 x 511 */
        uint32_t vco = (in / m) * n + (in % m) * n / m;
        sysclk = vco / p;
        st->source = STM32_CLOCK_SRC_PLL;
    } else if (src == STM32_RCC_CFGR_SW_HSE) {
        sysclk = STM32_CLOCK_HSE_HZ;
        st->source = STM32_CLOCK_SRC_HSE;
    } else {
        sysclk = STM32_CLOCK_HSI_HZ; /* 3 is "not applicable": read as the HSI */
        st->source = STM32_CLOCK_SRC_HSI;
    }
    uint32_t cfgr = rcc->CFGR;
    uint32_t hpre = (cfgr & STM32_RCC_CFGR_HPRE_MASK) >> STM32_RCC_CFGR_HPRE_SHIFT;
    uint32_t ppre1 = (cfgr & STM32_RCC_CFGR_PPRE1_MASK) >> STM32_RCC_CFGR_PPRE1_SHIFT;
    uint32_t ppre2 = (cfgr & STM32_RCC_CFGR_PPRE2_MASK) >> STM32_RCC_CFGR_PPRE2_SHIFT;
    st->fault = STM32_CLOCK_FAULT_NONE;
    st->sysclk_hz = sysclk;
    st->hclk_hz = sysclk >> ahb_shift(hpre);
    st->pclk1_hz = st->hclk_hz >> apb_shift(ppre1);
    st->pclk2_hz = st->hclk_hz >> apb_shift(ppre2);
    /* a divided APB clocks its timers at twice its own rate (RM0090 7.2) */
    st->tim_apb1_hz = apb_shift(ppre1) == 0u ? st->pclk1_hz : 2u * st->pclk1_hz;
    st->tim_apb2_hz = apb_shift(ppre2) == 0u ? st->pclk2_hz : 2u * st->pclk2_hz;
    return 0;
}

int stm32_clock_enable_peripherals(stm32_rcc_regs_t *rcc)
{
    if (rcc == NULL) {
        return HAL_EINVAL;
    }
    rcc->AHB1ENR = rcc->AHB1ENR | STM32_RCC_AHB1ENR_GPIOAEN | STM32_RCC_AHB1ENR_GPIOBEN;
    (void)rcc->AHB1ENR;
    rcc->APB1ENR = rcc->APB1ENR | STM32_RCC_APB1ENR_TIM2EN | STM32_RCC_APB1ENR_CAN1EN |
                   STM32_RCC_APB1ENR_PWREN;
    (void)rcc->APB1ENR;
    return 0;
}
