/*
 * stm32_iwdg.c - register-level STM32F405 independent-watchdog driver (stm32_iwdg.h).
 * Register and bit references are to RM0090 section 21.
 */
#include "stm32_iwdg.h"

#define STM32_IWDG_COUNTS 4096u /* RLR + 1 at most */
#define STM32_IWDG_SR_BUSY (STM32_IWDG_SR_PVU | STM32_IWDG_SR_RVU)

int stm32_iwdg_compute(uint32_t timeout_ms, uint32_t *pr, uint32_t *rlr)
{
    if (pr == NULL || rlr == NULL || timeout_ms < STM32_IWDG_TIMEOUT_MIN_MS ||
        timeout_ms > STM32_IWDG_TIMEOUT_MAX_MS) {
        return HAL_EINVAL;
    }
    /* LSI cycles: at most 32768 ms x 32 = 1 048 576, no overflow */
    uint32_t ticks = timeout_ms * (STM32_IWDG_LSI_NOMINAL_HZ / 1000u);
    for (uint32_t p = 0; p <= STM32_IWDG_PR_MAX; p++) {
        uint32_t div = 4u << p;
        uint32_t counts = (ticks + div / 2u) / div;
        if (counts <= STM32_IWDG_COUNTS) {
            *pr = p;
            *rlr = counts - 1u; /* counts >= 1: ticks >= 32 and div <= 256 */
            return 0;
        }
    }
    return HAL_EINVAL; /* not reached: 32768 ms fits /256 */
}

uint32_t stm32_iwdg_timeout_us(uint32_t pr, uint32_t rlr, uint32_t lsi_hz)
{
    if (lsi_hz < 1000u || lsi_hz > 1000000u || pr > STM32_IWDG_PR_MAX) {
        return 0u;
    }
    /* cycles x 10^6 / f in 32 bits: cycles <= 2^20, so cycles x 1000 < 2^30; with
     * cycles x 1000 = q f + r, the result is 1000 q + floor(1000 r / f) exactly, and
     * q <= 2^30 / 1000, r < f <= 10^6 keep both products below 2^32 */
    uint32_t cycles = ((rlr & STM32_IWDG_RLR_MAX) + 1u) * (4u << pr);
    uint32_t q = cycles * 1000u / lsi_hz;
    uint32_t r = cycles * 1000u % lsi_hz;
    return q * 1000u + r * 1000u / lsi_hz;
}

/* Poll SR until PVU and RVU are clear, at most timeout_polls times, the hook first. */
static int wait_updates(const stm32_iwdg_t *dev)
{
    for (uint32_t i = 0; i < dev->cfg.timeout_polls; i++) {
        if (dev->cfg.wait_hook != NULL) {
            dev->cfg.wait_hook(dev->cfg.hook_ctx);
        }
        if ((dev->cfg.regs->SR & STM32_IWDG_SR_BUSY) == 0u) {
            return 0;
        }
    }
    return HAL_EIO;
}

/* Write PR and RLR (the watchdog running), then kick. */
static int program(stm32_iwdg_t *dev, uint32_t pr, uint32_t rlr)
{
    stm32_iwdg_regs_t *r = dev->cfg.regs;
    int rc = wait_updates(dev);
    if (rc == 0) {
        r->KR = STM32_IWDG_KEY_ACCESS;
        r->PR = pr;
        r->RLR = rlr;
        dev->pr = pr;
        dev->rlr = rlr;
        rc = wait_updates(dev);
    }
    r->KR = STM32_IWDG_KEY_RELOAD;
    return rc;
}

int stm32_iwdg_init(stm32_iwdg_t *dev, const stm32_iwdg_config_t *cfg)
{
    uint32_t pr = 0;
    uint32_t rlr = 0;
    if (dev == NULL || cfg == NULL || cfg->regs == NULL || cfg->timeout_polls == 0u ||
        stm32_iwdg_compute(cfg->timeout_ms, &pr, &rlr) != 0) {
        return HAL_EINVAL;
    }
    dev->cfg = *cfg;
    dev->pr = 0u;                   /* reset values until programmed */
    dev->rlr = STM32_IWDG_RLR_MAX;
    cfg->regs->KR = STM32_IWDG_KEY_START;
    return program(dev, pr, rlr);
}

int stm32_iwdg_set_timeout(stm32_iwdg_t *dev, uint32_t timeout_ms)
{
    uint32_t pr = 0;
    uint32_t rlr = 0;
    if (dev == NULL || dev->cfg.regs == NULL ||
        stm32_iwdg_compute(timeout_ms, &pr, &rlr) != 0) {
        return HAL_EINVAL;
    }
    dev->cfg.timeout_ms = timeout_ms;
    return program(dev, pr, rlr);
}

void stm32_iwdg_kick(stm32_iwdg_t *dev)
{
    if (dev != NULL && dev->cfg.regs != NULL) {
        dev->cfg.regs->KR = STM32_IWDG_KEY_RELOAD;
    }
}
