/*
 * stm32_timebase.c - the 64-bit microsecond clock from TIM2 (stm32_timebase.h). Register
 * and bit references are to RM0090 section 18.
 */
#include "stm32_timebase.h"

int stm32_timebase_init(stm32_timebase_t *tb, stm32_tim_regs_t *regs,
                        uint32_t timer_clock_hz)
{
    if (tb == NULL || regs == NULL || timer_clock_hz == 0u ||
        timer_clock_hz % STM32_TIMEBASE_TICK_HZ != 0u) {
        return HAL_EINVAL;
    }
    /* at most 4294 MHz / 1 MHz - 1: always within the 16-bit PSC */
    uint32_t psc = timer_clock_hz / STM32_TIMEBASE_TICK_HZ - 1u;
    tb->regs = regs;
    tb->half_periods = 0u;
    regs->CR1 = 0u;
    regs->DIER = 0u;
    regs->PSC = psc;
    regs->ARR = 0xFFFFFFFFu;
    regs->CNT = 0u;
    regs->EGR = STM32_TIM_EGR_UG;
    regs->SR = 0u;
    regs->CR1 = STM32_TIM_CR1_CEN;
    return 0;
}

uint64_t stm32_timebase_us(stm32_timebase_t *tb)
{
    if (tb == NULL || tb->regs == NULL) {
        return 0u; /* not initialised: a constant clock (the board records the fault) */
    }
    /* the count first, then CNT (both volatile: the compiler keeps the order), so CNT
     * is never older than the count it is paired with (the header's note) */
    uint32_t h = tb->half_periods;
    uint32_t cnt = tb->regs->CNT;
    if ((cnt >> 31) != (h & 1u)) {
        h++;
        tb->half_periods = h;
    }
    return ((uint64_t)(h >> 1) << 32) | cnt;
}
