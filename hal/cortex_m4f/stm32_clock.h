/*
 * stm32_clock.h - clock setup of the STM32F405 (RCC at 0x40023800, PWR at 0x40007000,
 * flash wait states in FLASH_ACR at 0x40023C00): 168 MHz from an 8 MHz HSE through the
 * main PLL, used by the Cortex-M4F HAL (hal/cortex_m4f/) at board start.
 *
 * The driver touches the hardware only through register-block pointers, so the host
 * tests (tests/test_stm32_clock.c) run it against register blocks in RAM and play the
 * hardware. It includes no OS header, never allocates, and never waits without a bound.
 *
 * The clock tree (RM0090 rev 19, section 7.2; limits from the STM32F405
 * datasheet: VCO input 1..2 MHz, VCO output 100..432 MHz, SYSCLK <= 168 MHz, APB1 <= 42
 * MHz, APB2 <= 84 MHz, USB/SDIO clock 48 MHz):
 *   HSE 8 MHz / PLLM 8 = 1 MHz VCO input, x PLLN 336 = 336 MHz VCO,
 *   / PLLP 2 = 168 MHz SYSCLK, / PLLQ 7 = 48 MHz;
 *   AHB /1 = 168 MHz HCLK; APB1 /4 = 42 MHz (bxCAN: BXCAN_BTR_42MHZ_500K), APB1 timers
 *   x2 = 84 MHz (TIM2: stm32_timebase.h); APB2 /2 = 84 MHz, APB2 timers 168 MHz.
 *   FLASH_ACR: 5 wait states (RM0090 3.5.1: 150 < HCLK <= 168 MHz at VDD 2.7..3.6 V),
 *   prefetch, instruction and data caches on. PWR_CR.VOS = scale 1 (needed above
 *   144 MHz).
 *
 * Typical use on the board, first thing after reset:
 *
 *     stm32_clock_config_t cfg = {(stm32_rcc_regs_t *)0x40023800u,
 *                                 (stm32_pwr_regs_t *)0x40007000u,
 *                                 (stm32_flash_regs_t *)0x40023C00u, 0u, 1000000u,
 *                                 NULL, NULL};
 *     stm32_clock_status_t clk;
 *     if (stm32_clock_init(&cfg, &clk) != 0) { ... HSI 16 MHz: clk says so; compute the
 *         CAN bit timing and the timer prescaler from clk.pclk1_hz / clk.tim_apb1_hz }
 *     stm32_clock_enable_peripherals(cfg.rcc);
 *
 * Register layout and bit positions: RM0090 rev 19, section 7.3 (RCC registers), 5.4
 * (PWR registers) and 3.9 (FLASH_ACR, stm32_flash.h). Return codes are those of
 * hal/hal.h: 0 or a negative HAL_E* value.
 */
#ifndef NAVECU_STM32_CLOCK_H
#define NAVECU_STM32_CLOCK_H

#include <stddef.h>
#include <stdint.h>

#include "hal.h"
#include "stm32_flash.h" /* stm32_flash_regs_t: FLASH_ACR */

/* ---- register blocks (RM0090 7.3, offsets from 0x40023800; 5.4, from 0x40007000) ---- */

typedef struct {
    volatile uint32_t CR;         /* 0x00 clock control */
    volatile uint32_t PLLCFGR;    /* 0x04 PLL configuration */
    volatile uint32_t CFGR;       /* 0x08 clock configuration */
    volatile uint32_t CIR;        /* 0x0C clock interrupt */
    volatile uint32_t AHB1RSTR;   /* 0x10 */
    volatile uint32_t AHB2RSTR;   /* 0x14 */
    volatile uint32_t AHB3RSTR;   /* 0x18 */
    volatile uint32_t reserved0;  /* 0x1C */
    volatile uint32_t APB1RSTR;   /* 0x20 */
    volatile uint32_t APB2RSTR;   /* 0x24 */
    volatile uint32_t reserved1[2]; /* 0x28..0x2F */
    volatile uint32_t AHB1ENR;    /* 0x30 AHB1 peripheral clock enable (GPIOx) */
    volatile uint32_t AHB2ENR;    /* 0x34 */
    volatile uint32_t AHB3ENR;    /* 0x38 */
    volatile uint32_t reserved2;  /* 0x3C */
    volatile uint32_t APB1ENR;    /* 0x40 APB1 peripheral clock enable (TIM2, CAN1, PWR) */
    volatile uint32_t APB2ENR;    /* 0x44 APB2 peripheral clock enable */
    volatile uint32_t reserved3[2]; /* 0x48..0x4F */
    volatile uint32_t AHB1LPENR;  /* 0x50 */
    volatile uint32_t AHB2LPENR;  /* 0x54 */
    volatile uint32_t AHB3LPENR;  /* 0x58 */
    volatile uint32_t reserved4;  /* 0x5C */
    volatile uint32_t APB1LPENR;  /* 0x60 */
    volatile uint32_t APB2LPENR;  /* 0x64 */
    volatile uint32_t reserved5[2]; /* 0x68..0x6F */
    volatile uint32_t BDCR;       /* 0x70 backup domain control */
    volatile uint32_t CSR;        /* 0x74 control/status (LSI, reset flags) */
    volatile uint32_t reserved6[2]; /* 0x78..0x7F */
    volatile uint32_t SSCGR;      /* 0x80 spread spectrum */
    volatile uint32_t PLLI2SCFGR; /* 0x84 PLLI2S configuration */
} stm32_rcc_regs_t;

_Static_assert(offsetof(stm32_rcc_regs_t, CR) == 0x00u, "RCC_CR offset");
_Static_assert(offsetof(stm32_rcc_regs_t, PLLCFGR) == 0x04u, "RCC_PLLCFGR offset");
_Static_assert(offsetof(stm32_rcc_regs_t, CFGR) == 0x08u, "RCC_CFGR offset");
_Static_assert(offsetof(stm32_rcc_regs_t, APB1RSTR) == 0x20u, "RCC_APB1RSTR offset");
_Static_assert(offsetof(stm32_rcc_regs_t, AHB1ENR) == 0x30u, "RCC_AHB1ENR offset");
_Static_assert(offsetof(stm32_rcc_regs_t, APB1ENR) == 0x40u, "RCC_APB1ENR offset");
_Static_assert(offsetof(stm32_rcc_regs_t, APB2ENR) == 0x44u, "RCC_APB2ENR offset");
_Static_assert(offsetof(stm32_rcc_regs_t, AHB1LPENR) == 0x50u, "RCC_AHB1LPENR offset");
_Static_assert(offsetof(stm32_rcc_regs_t, BDCR) == 0x70u, "RCC_BDCR offset");
_Static_assert(offsetof(stm32_rcc_regs_t, CSR) == 0x74u, "RCC_CSR offset");
_Static_assert(offsetof(stm32_rcc_regs_t, PLLI2SCFGR) == 0x84u, "RCC_PLLI2SCFGR offset");
_Static_assert(sizeof(stm32_rcc_regs_t) == 0x88u, "RCC register block size");

typedef struct {
    volatile uint32_t CR;  /* 0x00 power control (VOS) */
    volatile uint32_t CSR; /* 0x04 power control/status */
} stm32_pwr_regs_t;

_Static_assert(offsetof(stm32_pwr_regs_t, CR) == 0x00u, "PWR_CR offset");
_Static_assert(offsetof(stm32_pwr_regs_t, CSR) == 0x04u, "PWR_CSR offset");

/* ---- bit positions (RM0090 7.3.1 .. 7.3.14, 5.4.1) ---- */

/* RCC_CR */
#define STM32_RCC_CR_HSION (1u << 0)
#define STM32_RCC_CR_HSIRDY (1u << 1)
#define STM32_RCC_CR_HSEON (1u << 16)
#define STM32_RCC_CR_HSERDY (1u << 17)
#define STM32_RCC_CR_HSEBYP (1u << 18) /* HSE from an external clock, not a crystal */
#define STM32_RCC_CR_CSSON (1u << 19)
#define STM32_RCC_CR_PLLON (1u << 24)
#define STM32_RCC_CR_PLLRDY (1u << 25)
/* RCC_PLLCFGR */
#define STM32_RCC_PLLCFGR_PLLM_SHIFT 0u   /* bits 5:0, 2..63 */
#define STM32_RCC_PLLCFGR_PLLN_SHIFT 6u   /* bits 14:6, 50..432 */
#define STM32_RCC_PLLCFGR_PLLP_SHIFT 16u  /* bits 17:16: P = 2 x (field + 1) */
#define STM32_RCC_PLLCFGR_PLLSRC_HSE (1u << 22)
#define STM32_RCC_PLLCFGR_PLLQ_SHIFT 24u  /* bits 27:24, 2..15 */
#define STM32_RCC_PLLCFGR_FIELDS 0x0F437FFFu /* the rest is reserved: kept at reset */
/* RCC_CFGR */
#define STM32_RCC_CFGR_SW_MASK 0x3u /* system clock switch, bits 1:0 */
#define STM32_RCC_CFGR_SW_HSI 0x0u
#define STM32_RCC_CFGR_SW_HSE 0x1u
#define STM32_RCC_CFGR_SW_PLL 0x2u
#define STM32_RCC_CFGR_SWS_SHIFT 2u /* switch status, bits 3:2, same codes */
#define STM32_RCC_CFGR_HPRE_SHIFT 4u  /* AHB prescaler, bits 7:4: 0xxx = /1 */
#define STM32_RCC_CFGR_HPRE_MASK (0xFu << STM32_RCC_CFGR_HPRE_SHIFT)
#define STM32_RCC_CFGR_PPRE1_SHIFT 10u /* APB1 prescaler, bits 12:10: 0xx /1, 100 /2, */
#define STM32_RCC_CFGR_PPRE1_MASK (0x7u << STM32_RCC_CFGR_PPRE1_SHIFT) /* 101 /4 ... */
#define STM32_RCC_CFGR_PPRE2_SHIFT 13u /* APB2 prescaler, bits 15:13 */
#define STM32_RCC_CFGR_PPRE2_MASK (0x7u << STM32_RCC_CFGR_PPRE2_SHIFT)
#define STM32_RCC_PPRE_DIV2 0x4u
#define STM32_RCC_PPRE_DIV4 0x5u
/* RCC_AHB1ENR */
#define STM32_RCC_AHB1ENR_GPIOAEN (1u << 0)
#define STM32_RCC_AHB1ENR_GPIOBEN (1u << 1)
/* RCC_APB1ENR */
#define STM32_RCC_APB1ENR_TIM2EN (1u << 0)
#define STM32_RCC_APB1ENR_CAN1EN (1u << 25)
#define STM32_RCC_APB1ENR_PWREN (1u << 28)
/* PWR_CR */
#define STM32_PWR_CR_VOS (1u << 14) /* regulator scale 1 (F405: one bit; 1 at reset) */

/* ---- the clock plan ---- */

#define STM32_CLOCK_HSI_HZ 16000000u
#define STM32_CLOCK_HSE_HZ 8000000u
#define STM32_CLOCK_PLLM 8u
#define STM32_CLOCK_PLLN 336u
#define STM32_CLOCK_PLLP 2u
#define STM32_CLOCK_PLLQ 7u
#define STM32_CLOCK_SYSCLK_HZ 168000000u
#define STM32_CLOCK_FLASH_LATENCY 5u /* wait states at 168 MHz, 2.7..3.6 V */

typedef enum {
    STM32_CLOCK_SRC_HSI = 0, /* the 16 MHz RC oscillator (after reset, or a fallback) */
    STM32_CLOCK_SRC_HSE = 1,
    STM32_CLOCK_SRC_PLL = 2,
} stm32_clock_source_t;

/* The step stm32_clock_init gave up on. */
typedef enum {
    STM32_CLOCK_FAULT_NONE = 0,
    STM32_CLOCK_FAULT_HSE = 1,     /* HSERDY did not come: no crystal / oscillator */
    STM32_CLOCK_FAULT_PLL = 2,     /* PLLRDY did not come */
    STM32_CLOCK_FAULT_LATENCY = 3, /* FLASH_ACR did not take 5 wait states */
    STM32_CLOCK_FAULT_SWITCH = 4,  /* CFGR.SWS did not report the PLL */
} stm32_clock_fault_t;

/* The clocks as the registers set them. */
typedef struct {
    stm32_clock_source_t source; /* SYSCLK source as CFGR.SWS reports it */
    stm32_clock_fault_t fault;   /* stm32_clock_init's failed step, or NONE */
    uint32_t sysclk_hz;
    uint32_t hclk_hz;            /* AHB: core, DMA, GPIO */
    uint32_t pclk1_hz;           /* APB1: bxCAN kernel clock */
    uint32_t pclk2_hz;           /* APB2 */
    uint32_t tim_apb1_hz;        /* APB1 timers (TIM2): pclk1, x2 when APB1 is divided */
    uint32_t tim_apb2_hz;
} stm32_clock_status_t;

typedef struct {
    stm32_rcc_regs_t *rcc;
    stm32_pwr_regs_t *pwr;
    stm32_flash_regs_t *flash;
    uint32_t hse_bypass;   /* 1: an external 8 MHz clock on OSC_IN (HSEBYP); 0: crystal */
    /* bound of each wait (HSERDY, PLLRDY, the latency, SWS), in polls (> 0); a crystal
     * needs up to 2 ms to start (datasheet tSU(HSE)), the PLL about 100 us */
    uint32_t timeout_polls;
    /* optional: called before every poll of a wait (so at least once per wait; the host
     * tests play the hardware here); NULL for none */
    void (*wait_hook)(void *ctx);
    void *hook_ctx;
} stm32_clock_config_t;

/*
 * Run the system from the PLL at 168 MHz. Precondition: the reset state (SYSCLK = HSI,
 * PLL off). Steps (RM0090 7.2, 3.5.1 "increasing the CPU frequency"):
 *  1. APB1ENR.PWREN, PWR_CR.VOS = scale 1;
 *  2. HSEBYP if configured, HSEON; wait for HSERDY;
 *  3. PLLCFGR = M 8, N 336, P 2, Q 7, source HSE (reserved bits kept); PLLON; wait for
 *     PLLRDY;
 *  4. FLASH_ACR = 5 wait states | PRFTEN | ICEN | DCEN; wait until ACR reads 5 wait
 *     states - before the switch, so the flash is never read too fast;
 *  5. CFGR prescalers AHB /1, APB1 /4, APB2 /2 - before the switch, so APB1 never runs
 *     above 42 MHz;
 *  6. CFGR.SW = PLL; wait for CFGR.SWS = PLL.
 * Each wait polls at most cfg->timeout_polls times, calling cfg->wait_hook before each
 * poll. On a failure the system stays on (or goes back to) the HSI at 16 MHz with all
 * prescalers /1: HSE and PLL switched off, FLASH_ACR left at 5 wait states when it was
 * already set (correct at any lower clock). *st (optional) receives the resulting clocks
 * and the failed step.
 * Returns 0; HAL_EINVAL (NULL cfg or register pointer, timeout_polls 0, not in the reset
 * state: nothing written); HAL_EIO on a timeout (st->fault says which).
 */
int stm32_clock_init(const stm32_clock_config_t *cfg, stm32_clock_status_t *st);

/*
 * The clocks as the RCC registers define them now: source from CFGR.SWS, the PLL output
 * from PLLCFGR (source / M x N / P), the AHB and APB prescalers from CFGR; fault NONE.
 * Returns 0; HAL_EINVAL (NULL pointer; a PLL source with PLLM < 2).
 */
int stm32_clock_status(const stm32_rcc_regs_t *rcc, stm32_clock_status_t *st);

/*
 * Enable the clocks of the peripherals the ECU uses: GPIOA and GPIOB (AHB1ENR bits 0, 1;
 * CAN1 pins), TIM2 (APB1ENR bit 0; the microsecond time base), CAN1 (bit 25), PWR (bit
 * 28). Other enable bits are kept. Each register is read back after the write (the
 * STM32F40x errata's delay before the first access to a newly clocked peripheral).
 * Returns 0; HAL_EINVAL (NULL rcc).
 */
int stm32_clock_enable_peripherals(stm32_rcc_regs_t *rcc);

#endif /* NAVECU_STM32_CLOCK_H */
