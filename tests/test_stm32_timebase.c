/*
 * test_stm32_timebase.c - the TIM2 microsecond time base (hal/cortex_m4f/stm32_timebase.c)
 * against a timer register block in RAM. The test is the timer: it sets CNT to the low
 * 32 bits of a reference 64-bit microsecond count and checks the driver's extension.
 *
 * Expected values follow RM0090 18.4: CR1.CEN bit 0, EGR.UG bit 0, SR.UIF bit 0;
 * f_CNT = f_TIM / (PSC + 1).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "stm32_timebase.h"

static stm32_tim_regs_t regs;
static stm32_timebase_t tb;

static int setup(void **state)
{
    (void)state;
    memset((void *)&regs, 0, sizeof regs);
    regs.ARR = 0xFFFFFFFFu; /* reset values of TIM2 */
    regs.CNT = 0x1234u;     /* running from an earlier life */
    regs.SR = 0x1Fu;
    regs.DIER = 0x1u;
    assert_int_equal(stm32_timebase_init(&tb, &regs, 84000000u), 0);
    return 0;
}

/* the time at reference t_us: CNT shows its low 32 bits */
static uint64_t at(uint64_t t_us)
{
    regs.CNT = (uint32_t)t_us;
    return stm32_timebase_us(&tb);
}

static void test_register_offsets(void **state)
{
    (void)state;
    assert_int_equal(offsetof(stm32_tim_regs_t, CR1), 0x00);
    assert_int_equal(offsetof(stm32_tim_regs_t, SR), 0x10);
    assert_int_equal(offsetof(stm32_tim_regs_t, EGR), 0x14);
    assert_int_equal(offsetof(stm32_tim_regs_t, CNT), 0x24);
    assert_int_equal(offsetof(stm32_tim_regs_t, PSC), 0x28);
    assert_int_equal(offsetof(stm32_tim_regs_t, ARR), 0x2C);
}

/* GIVEN an 84 MHz timer clock (APB1 42 MHz, x2) WHEN init runs THEN PSC 83 (84 MHz / 84 =
 * 1 MHz), ARR all ones, UG generated so PSC loads, UIF cleared, the counter running */
static void test_init_psc_arr_ug_cen(void **state)
{
    (void)state;
    assert_int_equal(regs.PSC, 83u);
    assert_int_equal(regs.ARR, 0xFFFFFFFFu);
    assert_int_equal(regs.EGR, 1u << 0);  /* UG */
    assert_int_equal(regs.CR1, 1u << 0);  /* CEN; up-counting, ARPE off */
    assert_int_equal(regs.SR, 0u);        /* UIF (and the rest) cleared */
    assert_int_equal(regs.DIER, 0u);      /* no interrupt */
    assert_int_equal(regs.CNT, 0u);
    assert_int_equal(stm32_timebase_us(&tb), 0u);

    /* the HSI fallback: 16 MHz -> PSC 15; a 1 MHz timer clock -> PSC 0 */
    assert_int_equal(stm32_timebase_init(&tb, &regs, 16000000u), 0);
    assert_int_equal(regs.PSC, 15u);
    assert_int_equal(stm32_timebase_init(&tb, &regs, 1000000u), 0);
    assert_int_equal(regs.PSC, 0u);
    assert_int_equal(stm32_timebase_init(&tb, &regs, 4000000000u), 0);
    assert_int_equal(regs.PSC, 3999u);
}

static void test_init_invalid_writes_nothing(void **state)
{
    (void)state;
    memset((void *)&regs, 0, sizeof regs);
    assert_int_equal(stm32_timebase_init(&tb, &regs, 0u), HAL_EINVAL);
    assert_int_equal(stm32_timebase_init(&tb, &regs, 84500000u), HAL_EINVAL);
    assert_int_equal(stm32_timebase_init(&tb, &regs, 999999u), HAL_EINVAL);
    assert_int_equal(stm32_timebase_init(NULL, &regs, 84000000u), HAL_EINVAL);
    assert_int_equal(stm32_timebase_init(&tb, NULL, 84000000u), HAL_EINVAL);
    assert_int_equal(regs.PSC, 0u);
    assert_int_equal(regs.CR1, 0u);
    assert_int_equal(regs.EGR, 0u);
}

/* GIVEN reads around the 32-bit wrap WHEN CNT goes 0xFFFFFFFF -> 0 THEN the 64-bit time
 * goes on: 2^32 - 1 -> 2^32 */
static void test_wrap_of_32_bit_counter_extends_to_64_bits(void **state)
{
    (void)state;
    assert_int_equal(at(5u), 5u);
    assert_int_equal(at(0x7FFFFFFFu), 0x7FFFFFFFu);
    assert_int_equal(at(0x80000000u), 0x80000000u);
    assert_int_equal(at(0xFFFFFFFFu), 0xFFFFFFFFu);
    assert_int_equal(at(UINT64_C(0x100000000)), UINT64_C(0x100000000));
    assert_int_equal(at(UINT64_C(0x100000007)), UINT64_C(0x100000007));
    /* reading the same CNT again changes nothing */
    assert_int_equal(at(UINT64_C(0x100000007)), UINT64_C(0x100000007));
    /* steps of exactly the allowed gap, 2^31 us, across several wraps */
    uint64_t t = UINT64_C(0x100000007);
    for (int i = 0; i < 8; i++) {
        t += STM32_TIMEBASE_MAX_GAP_US;
        assert_int_equal(at(t), t);
    }
    assert_int_equal(t, UINT64_C(0x500000007));
    /* a wrap seen only by its first microsecond */
    t = UINT64_C(0x5FFFFFFFF);
    assert_int_equal(at(t), t);
    assert_int_equal(at(t + 1u), UINT64_C(0x600000000));
}

/* GIVEN reads at pseudo-random gaps below 2^31 us, some short, over more than 1000 wraps
 * of the 32-bit counter (about 200 days) THEN every result equals the reference and never
 * goes backwards */
static void test_monotonic_over_many_wraps(void **state)
{
    (void)state;
    uint64_t t = 0;
    uint64_t prev = 0;
    uint32_t rng = 12345u;
    for (int i = 0; i < 20000; i++) {
        rng = rng * 1664525u + 1013904223u;
        uint32_t gap = rng >> 1; /* 0 .. 2^31 - 1 */
        if (i % 7 == 0) {
            gap = rng & 0xFFu; /* and some short gaps */
        }
        t += gap;
        uint64_t now = at(t);
        assert_int_equal(now, t);
        assert_true(now >= prev);
        prev = now;
    }
    assert_true(t > UINT64_C(1000) * UINT64_C(0x100000000));
}

/* the documented limit: GIVEN no read for more than 2^31 us WHEN the counter has passed
 * two half periods THEN 2^32 us are lost (the board must read more often) */
static void test_gap_above_bound_loses_a_wrap(void **state)
{
    (void)state;
    assert_int_equal(at(0x7FFFFFFFu), 0x7FFFFFFFu);
    uint64_t t = UINT64_C(0x7FFFFFFF) + STM32_TIMEBASE_MAX_GAP_US + 1u; /* 2^32: CNT 0 */
    assert_int_equal(at(t), t - UINT64_C(0x100000000));
}

/* GIVEN a call interrupted between its load and its store by a handler that saw a later
 * crossing (the state is one half period behind afterwards) WHEN the next call reads THEN
 * the state steps forward again and the time is right */
static void test_stale_store_after_preemption_heals(void **state)
{
    (void)state;
    /* the caller loads 0 half periods and reads CNT 0x80000010: it will store 1 */
    assert_int_equal(at(0x80000010u), 0x80000010u);
    assert_int_equal(tb.half_periods, 1u);
    /* a handler runs in between, after the wrap, and stores 2 */
    assert_int_equal(at(UINT64_C(0x100000010)), UINT64_C(0x100000010));
    assert_int_equal(tb.half_periods, 2u);
    tb.half_periods = 1u; /* the preempted caller's store lands now */
    assert_int_equal(at(UINT64_C(0x100000020)), UINT64_C(0x100000020));
    assert_int_equal(tb.half_periods, 2u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_register_offsets),
        cmocka_unit_test_setup(test_init_psc_arr_ug_cen, setup),
        cmocka_unit_test_setup(test_init_invalid_writes_nothing, setup),
        cmocka_unit_test_setup(test_wrap_of_32_bit_counter_extends_to_64_bits, setup),
        cmocka_unit_test_setup(test_monotonic_over_many_wraps, setup),
        cmocka_unit_test_setup(test_gap_above_bound_loses_a_wrap, setup),
        cmocka_unit_test_setup(test_stale_store_after_preemption_heals, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
