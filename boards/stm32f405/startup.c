/*
 * startup.c - reset handler and vector table of the STM32F405 (Cortex-M4F) image, used by
 * the ECU build and the QEMU build alike (docs/porting.md).
 *
 * Reset: copy .data from flash, zero .bss, enable the FPU (CP10/CP11 full access in
 * CPACR, ARM DDI 0403 B3.2.20) before any float instruction, then board_main(), which
 * never returns. The C library's crt0 is not used (-nostartfiles): it has no vector
 * table and would pull in stdio and a heap.
 *
 * The vector table (RM0090 table 61, 82 peripheral interrupts) points every exception
 * that the board does not handle to default_handler, which resets the ECU (board_fault). Handlers are weak aliases, so a driver
 * overrides one by defining a function of that name.
 */
#include <stdint.h>

/* from the linker script (hal/cortex_m4f/stm32f405.ld) */
extern uint32_t _sidata[]; /* load address of .data in flash */
extern uint32_t _sdata[], _edata[], _sbss[], _ebss[];
extern uint32_t _estack[]; /* initial stack pointer: the end of RAM */

/* the board's entry point (boards/stm32f405/main.c or boards/qemu/main.c) */
void board_main(void) __attribute__((noreturn));

void Reset_Handler(void) __attribute__((noreturn));
void default_handler(void);

/* What an unexpected exception does: the ECU resets itself (SCB AIRCR SYSRESETREQ,
 * ARMv7-M B3.2.6), since the watchdog may not run yet this early; the QEMU image exits
 * with a failure status instead (boards/qemu/main.c). Weak: a board may define its own. */
void board_fault(void);
__attribute__((weak)) void board_fault(void)
{
    __asm__ volatile("dsb" ::: "memory");
    *(volatile uint32_t *)0xE000ED0Cu = 0x05FA0004u;
    __asm__ volatile("dsb" ::: "memory");
}

void default_handler(void)
{
    board_fault();
    for (;;) {
    }
}

#define WEAK_HANDLER(name) void name(void) __attribute__((weak, alias("default_handler")))
WEAK_HANDLER(NMI_Handler);
WEAK_HANDLER(HardFault_Handler);
WEAK_HANDLER(MemManage_Handler);
WEAK_HANDLER(BusFault_Handler);
WEAK_HANDLER(UsageFault_Handler);
WEAK_HANDLER(SVC_Handler);
WEAK_HANDLER(DebugMon_Handler);
WEAK_HANDLER(PendSV_Handler);
WEAK_HANDLER(SysTick_Handler);
WEAK_HANDLER(CAN1_TX_IRQHandler);   /* IRQ 19 */
WEAK_HANDLER(CAN1_RX0_IRQHandler);  /* IRQ 20 */
WEAK_HANDLER(CAN1_RX1_IRQHandler);  /* IRQ 21 */
WEAK_HANDLER(CAN1_SCE_IRQHandler);  /* IRQ 22 */

typedef union {
    void (*handler)(void);
    const void *stack_top;
} vector_t;

#define N_VECTORS (16u + 82u) /* Cortex-M4 exceptions + STM32F405 IRQ 0..81 */
extern const vector_t vector_table[N_VECTORS];

void Reset_Handler(void)
{
    /* this image's vector table, wherever it is linked: the bootloader's at 0x08000000,
     * the application's at 0x0800C000 (the bootloader set VTOR too; a debugger that
     * starts the application directly does not) */
    *(volatile uint32_t *)0xE000ED08u = (uint32_t)(uintptr_t)vector_table;
    /* volatile pointers: GCC would otherwise turn these loops into memcpy/memset calls */
    const volatile uint32_t *src = _sidata;
    volatile uint32_t *dst = _sdata;
    while (dst < _edata) {
        *dst++ = *src++;
    }
    dst = _sbss;
    while (dst < _ebss) {
        *dst++ = 0u;
    }
    /* CPACR (0xE000ED88): CP10 and CP11 full access, then DSB/ISB so that the next
     * instruction sees the FPU enabled */
    *(volatile uint32_t *)0xE000ED88u |= (0xFu << 20);
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    board_main();
}

#define H(fn) {.handler = fn}
#define D H(default_handler) /* an interrupt the board does not use */
#define R {.handler = 0}     /* reserved by the architecture */

__attribute__((section(".isr_vector"), used)) const vector_t vector_table[N_VECTORS] = {
    /* 0..15: stack, reset, NMI, HardFault, MemManage, BusFault, UsageFault, 4 reserved,
     * SVC, DebugMon, reserved, PendSV, SysTick */
    {.stack_top = _estack}, H(Reset_Handler), H(NMI_Handler), H(HardFault_Handler),
    H(MemManage_Handler), H(BusFault_Handler), H(UsageFault_Handler), R, R, R,
    R, H(SVC_Handler), H(DebugMon_Handler), R, H(PendSV_Handler), H(SysTick_Handler),
    /* IRQ 0..18 */
    D, D, D, D, D, D, D, D, D, D,
    D, D, D, D, D, D, D, D, D,
    /* IRQ 19..22: CAN1 TX, RX0, RX1, SCE */
    H(CAN1_TX_IRQHandler),
    H(CAN1_RX0_IRQHandler),
    H(CAN1_RX1_IRQHandler),
    H(CAN1_SCE_IRQHandler),
    /* IRQ 23..81 */
    D, D, D, D, D, D, D, D, D, D,
    D, D, D, D, D, D, D, D, D, D,
    D, D, D, D, D, D, D, D, D, D,
    D, D, D, D, D, D, D, D, D, D,
    D, D, D, D, D, D, D, D, D, D,
    D, D, D, D, D, D, D, D, D,
};
