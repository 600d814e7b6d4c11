/*
 * stm32_flash.c - register-level STM32F405 embedded-flash driver (stm32_flash.h).
 * Register and bit references are to RM0090 section 3; the erase and program sequences
 * are those of RM0090 3.6.3 and 3.6.4.
 */
#include "stm32_flash.h"

/* the largest region accepted: offsets and sizes stay far from size_t overflow */
#define STM32_FLASH_MAX_REGION_BYTES 0x80000000u

static void hook(const stm32_flash_t *dev)
{
    if (dev->cfg.wait_hook != NULL) {
        dev->cfg.wait_hook(dev->cfg.hook_ctx);
    }
}

/* Poll SR until BSY is clear, at most timeout_polls times, the hook before each poll.
 * A timeout is counted. */
static int wait_not_busy(stm32_flash_t *dev)
{
    for (uint32_t i = 0; i < dev->cfg.timeout_polls; i++) {
        hook(dev);
        if ((dev->cfg.regs->SR & STM32_FLASH_SR_BSY) == 0u) {
            return 0;
        }
    }
    dev->stats.timeouts++;
    return HAL_EIO;
}

/* Read the error flags after an operation: count each, clear exactly those (rc_w1).
 * Returns 0 or HAL_EIO. */
static int take_errors(stm32_flash_t *dev)
{
    uint32_t err = dev->cfg.regs->SR & STM32_FLASH_SR_ERRORS;
    if (err == 0u) {
        return 0;
    }
    stm32_flash_stats_t *s = &dev->stats;
    s->operr += (err & STM32_FLASH_SR_OPERR) != 0u ? 1u : 0u;
    s->wrperr += (err & STM32_FLASH_SR_WRPERR) != 0u ? 1u : 0u;
    s->pgaerr += (err & STM32_FLASH_SR_PGAERR) != 0u ? 1u : 0u;
    s->pgperr += (err & STM32_FLASH_SR_PGPERR) != 0u ? 1u : 0u;
    s->pgserr += (err & STM32_FLASH_SR_PGSERR) != 0u ? 1u : 0u;
    s->last_error_sr = err;
    dev->cfg.regs->SR = err;
    return HAL_EIO;
}

/* Reset a cache of the ART accelerator: disable it, pulse its reset bit, restore it.
 * The reset bit may only be written while the cache is disabled (RM0090 3.9.1). */
static void flush_cache(stm32_flash_regs_t *r, uint32_t en, uint32_t rst)
{
    uint32_t acr = r->ACR;
    if ((acr & en) == 0u) {
        return;
    }
    r->ACR = acr & ~en;
    r->ACR = (acr & ~en) | rst;
    r->ACR = acr & ~(en | rst);
    r->ACR = acr & ~rst;
}

static void flush_caches(stm32_flash_regs_t *r)
{
    flush_cache(r, STM32_FLASH_ACR_DCEN, STM32_FLASH_ACR_DCRST);
    flush_cache(r, STM32_FLASH_ACR_ICEN, STM32_FLASH_ACR_ICRST);
}

/* The CR bits an operation sets; cleared before the next and at its end. */
#define STM32_FLASH_CR_OP_BITS                                                    \
    (STM32_FLASH_CR_PG | STM32_FLASH_CR_SER | STM32_FLASH_CR_MER |                \
     STM32_FLASH_CR_SNB_MASK | STM32_FLASH_CR_PSIZE_MASK | STM32_FLASH_CR_STRT)

/* The common start of an erase or write: BSY clear, unlocked, error flags cleared. */
static int begin_op(stm32_flash_t *dev)
{
    if (wait_not_busy(dev) != 0) {
        return HAL_EIO;
    }
    if (stm32_flash_unlock(dev) != 0) {
        return HAL_EIO;
    }
    /* flags of an earlier operation (or a stray access) would be taken for ours */
    dev->cfg.regs->SR = STM32_FLASH_SR_ERRORS | STM32_FLASH_SR_EOP;
    return 0;
}

/* The common end: operation bits cleared, locked, caches flushed. */
static void end_op(stm32_flash_t *dev)
{
    stm32_flash_regs_t *r = dev->cfg.regs;
    r->CR = r->CR & ~STM32_FLASH_CR_OP_BITS;
    r->CR = r->CR | STM32_FLASH_CR_LOCK;
    flush_caches(r);
}

static int range_ok(const stm32_flash_t *dev, size_t offset, size_t len)
{
    size_t size = stm32_flash_size(dev);
    return offset <= size && len <= size - offset;
}

int stm32_flash_init(stm32_flash_t *dev, const stm32_flash_config_t *cfg)
{
    if (dev == NULL || cfg == NULL || cfg->regs == NULL || cfg->window == NULL ||
        cfg->n_sectors == 0u || cfg->n_sectors > STM32_FLASH_MAX_SECTORS ||
        cfg->sector_size_bytes == 0u || cfg->timeout_polls == 0u ||
        cfg->sector_size_bytes > STM32_FLASH_MAX_REGION_BYTES / cfg->n_sectors) {
        return HAL_EINVAL;
    }
    for (uint32_t k = 0; k < cfg->n_sectors; k++) {
        uint32_t snb = cfg->sector_numbers[k];
        if (snb > STM32_FLASH_LAST_SECTOR ||
            (k > 0u && snb != (uint32_t)cfg->sector_numbers[k - 1u] + 1u)) {
            return HAL_EINVAL;
        }
    }
    dev->cfg = *cfg;
    dev->stats = (stm32_flash_stats_t){0};
    if ((cfg->regs->CR & STM32_FLASH_CR_LOCK) == 0u) {
        stm32_flash_lock(dev);
    }
    return 0;
}

size_t stm32_flash_size(const stm32_flash_t *dev)
{
    if (dev == NULL) {
        return 0u;
    }
    return (size_t)dev->cfg.n_sectors * (size_t)dev->cfg.sector_size_bytes;
}

size_t stm32_flash_sector_size(const stm32_flash_t *dev)
{
    return dev == NULL ? 0u : (size_t)dev->cfg.sector_size_bytes;
}

int stm32_flash_unlock(stm32_flash_t *dev)
{
    if (dev == NULL) {
        return HAL_EINVAL;
    }
    stm32_flash_regs_t *r = dev->cfg.regs;
    if ((r->CR & STM32_FLASH_CR_LOCK) == 0u) {
        return 0;
    }
    r->KEYR = STM32_FLASH_KEY1;
    hook(dev);
    r->KEYR = STM32_FLASH_KEY2;
    for (uint32_t i = 0; i < dev->cfg.timeout_polls; i++) {
        hook(dev);
        if ((r->CR & STM32_FLASH_CR_LOCK) == 0u) {
            return 0;
        }
    }
    dev->stats.unlock_failures++;
    return HAL_EIO;
}

void stm32_flash_lock(stm32_flash_t *dev)
{
    if (dev == NULL) {
        return;
    }
    dev->cfg.regs->CR = dev->cfg.regs->CR | STM32_FLASH_CR_LOCK;
}

int stm32_flash_erase_sector(stm32_flash_t *dev, size_t sector)
{
    if (dev == NULL || sector >= dev->cfg.n_sectors) {
        return HAL_EINVAL;
    }
    stm32_flash_regs_t *r = dev->cfg.regs;
    if (begin_op(dev) != 0) {
        return HAL_EIO;
    }
    uint32_t snb = dev->cfg.sector_numbers[sector];
    r->CR = (r->CR & ~STM32_FLASH_CR_OP_BITS) | STM32_FLASH_CR_SER |
            (snb << STM32_FLASH_CR_SNB_SHIFT) | STM32_FLASH_CR_PSIZE_X32;
    r->CR = r->CR | STM32_FLASH_CR_STRT;
    if (wait_not_busy(dev) != 0) {
        return HAL_EIO; /* CR left alone: a write would stall until BSY clears */
    }
    int rc = take_errors(dev);
    end_op(dev);
    if (rc != 0) {
        return rc;
    }
    const volatile uint8_t *p = dev->cfg.window + sector * dev->cfg.sector_size_bytes;
    for (uint32_t i = 0; i < dev->cfg.sector_size_bytes; i++) {
        if (p[i] != 0xFFu) {
            dev->stats.verify_failures++;
            return HAL_EIO;
        }
    }
    dev->stats.erases++;
    return 0;
}

int stm32_flash_erase(stm32_flash_t *dev)
{
    if (dev == NULL) {
        return HAL_EINVAL;
    }
    for (size_t k = 0; k < dev->cfg.n_sectors; k++) {
        int rc = stm32_flash_erase_sector(dev, k);
        if (rc != 0) {
            return rc;
        }
    }
    return 0;
}

int stm32_flash_write(stm32_flash_t *dev, size_t offset, const void *buf, size_t len)
{
    if (dev == NULL || (buf == NULL && len > 0u) || !range_ok(dev, offset, len)) {
        return HAL_EINVAL;
    }
    if (len == 0u) {
        return 0;
    }
    stm32_flash_regs_t *r = dev->cfg.regs;
    const uint8_t *src = buf;
    volatile uint8_t *dst = dev->cfg.window + offset;
    if (begin_op(dev) != 0) {
        return HAL_EIO;
    }
    r->CR = (r->CR & ~STM32_FLASH_CR_OP_BITS) | STM32_FLASH_CR_PG | STM32_FLASH_CR_PSIZE_X8;
    for (size_t i = 0; i < len; i++) {
        uint8_t old = dst[i];
        if ((uint8_t)(old & src[i]) == old) {
            continue; /* programming could not change it */
        }
        dst[i] = src[i];
        if (wait_not_busy(dev) != 0) {
            return HAL_EIO; /* CR left alone: a write would stall until BSY clears */
        }
        if (take_errors(dev) != 0) {
            end_op(dev);
            return HAL_EIO;
        }
    }
    end_op(dev);
    for (size_t i = 0; i < len; i++) {
        if (dst[i] != src[i]) {
            dev->stats.verify_failures++;
            return HAL_EIO;
        }
    }
    return 0;
}

int stm32_flash_read(const stm32_flash_t *dev, size_t offset, void *buf, size_t len)
{
    if (dev == NULL || (buf == NULL && len > 0u) || !range_ok(dev, offset, len)) {
        return HAL_EINVAL;
    }
    uint8_t *out = buf;
    const volatile uint8_t *src = dev->cfg.window + offset;
    for (size_t i = 0; i < len; i++) {
        out[i] = src[i];
    }
    return 0;
}

int stm32_flash_stats(const stm32_flash_t *dev, stm32_flash_stats_t *s)
{
    if (dev == NULL || s == NULL) {
        return HAL_EINVAL;
    }
    *s = dev->stats;
    return 0;
}
