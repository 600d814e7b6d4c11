/*
 * boards/stm32f405/main.c - the navecu ECU: board bring-up, then the application's main
 * loop pass (app_loop.h, the same as every other board's) and a sleep until the next
 * interrupt (a received frame, or the 100 Hz SysTick that keeps app_poll and the time
 * base running on a silent bus).
 */
#include <stdint.h>

#include "app.h"
#include "app_loop.h"
#include "hal_stm32.h"

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)
#define SYSTICK_HZ 100u
#define RX_IDS_MAX 32u
#define BATCH_MAX 64u /* the RX ring's length */

static app_t app;
static uint32_t rx_ids[RX_IDS_MAX]; /* static: off the 2 KiB stack */

void board_main(void) __attribute__((noreturn));
void SysTick_Handler(void);

void SysTick_Handler(void)
{
    /* only wakes the main loop from WFI */
}

void board_main(void)
{
    (void)app_init_defaults(&app); /* the defaults are valid (test_app) */
    const size_t n_ids = app_uds_rx_ids(&app.cfg, rx_ids, RX_IDS_MAX);
    hal_t *hal = hal_stm32_init(rx_ids, n_ids);
    /* the layers: defaults, then the NVM's parameters (the receive list above is the
     * defaults': the CAN and UDS identifiers are not stored) */
    (void)app_start(&app, hal); /* NVM entries are checked one by one */

    const uint32_t hclk = hal->clock.hclk_hz != 0u ? hal->clock.hclk_hz : 16000000u;
    SYST_RVR = hclk / SYSTICK_HZ - 1u;
    SYST_CVR = 0u;
    SYST_CSR = 0x7u; /* core clock, interrupt, enable */

    const app_pass_cfg_t pass = {BATCH_MAX, 1u};
    for (;;) {
        /* the watchdog is kicked inside only when every task ran in time: a stuck or
         * starved task ends in a watchdog reset (136..376 ms), not in a stale ECU */
        (void)app_pass(&app, hal, &pass);
        /* sleep only if nothing arrived meanwhile: with interrupts masked, a frame that
         * comes in after the check still ends WFI (a pending interrupt wakes it), and is
         * handled once they are unmasked */
        __asm__ volatile("cpsid i" ::: "memory");
        if (!hal_stm32_rx_pending(hal)) {
            __asm__ volatile("wfi");
        }
        __asm__ volatile("cpsie i" ::: "memory");
    }
}
