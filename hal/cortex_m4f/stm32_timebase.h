/*
 * stm32_timebase.h - the microsecond clock of the Cortex-M4F HAL (hal/cortex_m4f/):
 * TIM2 of the STM32F405 (a 32-bit timer at 0x40000000) counting at 1 MHz, extended by
 * software to the 64-bit monotonic count of hal_time_us.
 *
 * The driver touches the timer only through a stm32_tim_regs_t pointer, so the host
 * tests (tests/test_stm32_timebase.c) run it against a register block in RAM and set the
 * counter themselves. It includes no OS header, never allocates, and never waits.
 *
 * Typical use on the board (APB1 /4 = 42 MHz, so the APB1 timers run at 84 MHz;
 * stm32_clock.h):
 *
 *     static stm32_timebase_t tb;
 *     stm32_timebase_init(&tb, (stm32_tim_regs_t *)0x40000000u, clk.tim_apb1_hz);
 *     uint64_t hal_time_us(const hal_t *hal) { return stm32_timebase_us(&hal->tb); }
 *
 * Counting: PSC = timer clock / 1 MHz - 1 (83 at 84 MHz), ARR = 0xFFFFFFFF, up-counting,
 * free running; no interrupt. An update event (EGR.UG) loads PSC, which is otherwise
 * only taken at the next overflow (RM0090 18.3.1: the prescaler is buffered).
 *
 * Extension to 64 bits: the driver keeps the number of half periods of the 32-bit counter
 * (2^31 us each) seen so far. Its parity is the counter's top bit at the last read; a
 * read that finds the top bit changed has crossed into the next half period. The result
 * is (half periods / 2) x 2^32 + CNT. This is correct as long as stm32_timebase_us is
 * called at least once every 2^31 us = 2147 s = 35.8 minutes (a longer gap loses 2^32 us
 * per missed wrap); the board guarantees it by calling it from the main loop, e.g. with
 * every watchdog kick, not only when CAN frames arrive.
 * Why half periods rather than "last value and high word" (which would allow 71.6
 * minutes): the state is one word, updated by one plain store of a value computed from
 * one load, so stm32_timebase_us may be called both from the main loop and from
 * interrupt handlers (the CAN RX interrupt stamps frames with it) without masking
 * interrupts. The count is loaded before CNT is read, so a call never pairs a newer CNT
 * with an older count than it loaded. A handler that preempts a call between its load
 * and its store either stores the same value (same crossing seen) or, if it saw a later
 * crossing, the preempted call's store puts the count one half period back; its parity
 * then disagrees with CNT's top bit, so the next call steps it forward again, and every
 * result is right. Two words (last value, high word) could not be updated that way.
 *
 * Register layout and bit positions: RM0090 rev 19, section 18.4 (TIM2 to TIM5
 * registers). Return codes are those of hal/hal.h: 0 or a negative HAL_E* value.
 */
#ifndef NAVECU_STM32_TIMEBASE_H
#define NAVECU_STM32_TIMEBASE_H

#include <stddef.h>
#include <stdint.h>

#include "hal.h"

/* ---- register block (RM0090 18.4, offsets from the TIMx base; TIM2 at 0x40000000) ---- */

typedef struct {
    volatile uint32_t CR1;       /* 0x00 control 1 */
    volatile uint32_t CR2;       /* 0x04 control 2 */
    volatile uint32_t SMCR;      /* 0x08 slave mode control */
    volatile uint32_t DIER;      /* 0x0C DMA/interrupt enable */
    volatile uint32_t SR;        /* 0x10 status (rc_w0) */
    volatile uint32_t EGR;       /* 0x14 event generation */
    volatile uint32_t CCMR1;     /* 0x18 capture/compare mode 1 */
    volatile uint32_t CCMR2;     /* 0x1C capture/compare mode 2 */
    volatile uint32_t CCER;      /* 0x20 capture/compare enable */
    volatile uint32_t CNT;       /* 0x24 counter (32 bits on TIM2 and TIM5) */
    volatile uint32_t PSC;       /* 0x28 prescaler: f_CNT = f_TIM / (PSC + 1) */
    volatile uint32_t ARR;       /* 0x2C auto-reload */
    volatile uint32_t reserved0; /* 0x30 */
    volatile uint32_t CCR1;      /* 0x34 */
    volatile uint32_t CCR2;      /* 0x38 */
    volatile uint32_t CCR3;      /* 0x3C */
    volatile uint32_t CCR4;      /* 0x40 */
    volatile uint32_t reserved1; /* 0x44 */
    volatile uint32_t DCR;       /* 0x48 DMA control */
    volatile uint32_t DMAR;      /* 0x4C DMA address for full transfer */
    volatile uint32_t OR;        /* 0x50 option (TIM2: ITR1 remap) */
} stm32_tim_regs_t;

_Static_assert(offsetof(stm32_tim_regs_t, CR1) == 0x00u, "TIMx_CR1 offset");
_Static_assert(offsetof(stm32_tim_regs_t, DIER) == 0x0Cu, "TIMx_DIER offset");
_Static_assert(offsetof(stm32_tim_regs_t, SR) == 0x10u, "TIMx_SR offset");
_Static_assert(offsetof(stm32_tim_regs_t, EGR) == 0x14u, "TIMx_EGR offset");
_Static_assert(offsetof(stm32_tim_regs_t, CCER) == 0x20u, "TIMx_CCER offset");
_Static_assert(offsetof(stm32_tim_regs_t, CNT) == 0x24u, "TIMx_CNT offset");
_Static_assert(offsetof(stm32_tim_regs_t, PSC) == 0x28u, "TIMx_PSC offset");
_Static_assert(offsetof(stm32_tim_regs_t, ARR) == 0x2Cu, "TIMx_ARR offset");
_Static_assert(offsetof(stm32_tim_regs_t, CCR1) == 0x34u, "TIMx_CCR1 offset");
_Static_assert(offsetof(stm32_tim_regs_t, DCR) == 0x48u, "TIMx_DCR offset");
_Static_assert(offsetof(stm32_tim_regs_t, OR) == 0x50u, "TIMx_OR offset");
_Static_assert(sizeof(stm32_tim_regs_t) == 0x54u, "TIMx register block size");

/* ---- bit positions (RM0090 18.4.1 .. 18.4.6) ---- */

#define STM32_TIM_CR1_CEN (1u << 0) /* counter enable */
#define STM32_TIM_EGR_UG (1u << 0)  /* update generation: reload PSC, reset CNT */
#define STM32_TIM_SR_UIF (1u << 0)  /* update interrupt flag (rc_w0) */
#define STM32_TIM_PSC_MAX 0xFFFFu

#define STM32_TIMEBASE_TICK_HZ 1000000u
/* the longest gap between two calls of stm32_timebase_us that it survives: 2^31 us */
#define STM32_TIMEBASE_MAX_GAP_US 0x80000000u

/* One time base. Caller-owned (static on the board); all fields are private. */
typedef struct {
    stm32_tim_regs_t *regs;
    /* half periods of CNT (2^31 us) seen; its parity is CNT's top bit at the last read.
     * Written by stm32_timebase_us from any context (see the header note). */
    volatile uint32_t half_periods;
} stm32_timebase_t;

/*
 * Set the timer at regs to count microseconds from 0 and *tb to extend it:
 * CR1 = 0 (stop; up-counting, ARR not buffered), DIER = 0, PSC = timer_clock_hz /
 * 1 MHz - 1, ARR = 0xFFFFFFFF, CNT = 0, EGR = UG (PSC takes effect now), SR = 0 (the UIF
 * that UG sets), CR1 = CEN. timer_clock_hz is the timer's kernel clock: the APB1 timer
 * clock for TIM2 (stm32_clock_status_t.tim_apb1_hz, 84 MHz at 168 MHz).
 * Returns 0; HAL_EINVAL (NULL pointer, timer_clock_hz 0 or not a whole number of MHz;
 * nothing written).
 */
int stm32_timebase_init(stm32_timebase_t *tb, stm32_tim_regs_t *regs,
                        uint32_t timer_clock_hz);

/*
 * Microseconds since stm32_timebase_init: monotonic, 64 bits, provided calls are at most
 * STM32_TIMEBASE_MAX_GAP_US apart (35.8 minutes). Safe to call from the main loop and
 * from interrupt handlers alike. Never waits.
 */
uint64_t stm32_timebase_us(stm32_timebase_t *tb);

#endif /* NAVECU_STM32_TIMEBASE_H */
