/*
 * app_loop.h - one pass of the main loop, the same on every board (host log and live,
 * the QEMU image, the STM32 ECU): frames in, each handled and followed by app_poll (so
 * NAV_Status goes on when the IMU is silent), app_poll once more if nothing arrived, and
 * the watchdog kicked only when every task ran in time (app_tasks_ok). A board calls it
 * in its loop and adds only what is its own: how to wait for the next frame, what to do
 * at the end of a finite input or on a device error, how to report.
 *
 * Bounded: at most max_frames frames per pass, so a flooded bus cannot starve the
 * watchdog kick.
 */
#ifndef NAVECU_APP_LOOP_H
#define NAVECU_APP_LOOP_H

#include <stdint.h>

#include "app.h"
#include "hal.h"

typedef struct {
    uint32_t max_frames; /* frames to take at most in this pass (>= 1) */
    uint8_t poll;        /* 1: call app_poll; 0 withholds it (a stuck task: the watchdog
                            test of the host, --test-stall-poll-s) */
} app_pass_cfg_t;

typedef struct {
    uint32_t frames;       /* frames handled in this pass */
    int rx_status;         /* the last hal_can_receive result: 0 or HAL_EAGAIN (go on),
                              HAL_ENODATA (a finite input ended), another HAL_E* (error) */
    uint8_t kicked;        /* the watchdog was kicked (every task in time) */
    hal_can_frame_t last;  /* the last frame handled (a board's trace) */
} app_pass_t;

/* One pass. At the end of a finite input or on a receive error it returns at once, with
 * no watchdog decision (rx_status says which). */
app_pass_t app_pass(app_t *a, hal_t *hal, const app_pass_cfg_t *cfg);

/* 1 while the board should go on calling app_pass. */
static inline int app_pass_go_on(const app_pass_t *p)
{
    return p->rx_status == 0 || p->rx_status == HAL_EAGAIN;
}

#endif /* NAVECU_APP_LOOP_H */
