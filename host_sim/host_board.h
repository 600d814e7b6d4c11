/*
 * host_board.h - what the Linux host adds to the common main-loop pass as its board: the
 * HAL opened on a log or a live SocketCAN interface, stopping on SIGINT/SIGTERM, waiting
 * for frames, and the test-only stall of app_poll (--test-stall-poll-s).
 */
#ifndef NAVECU_HOST_BOARD_H
#define NAVECU_HOST_BOARD_H

#include "hal.h"
#include "options.h"

/* Open the log replay or the live interface (and catch SIGINT/SIGTERM when live);
 * 0, or 1 with the error printed. */
int host_open(hal_t *hal, const host_options_t *o);

/* 1 once SIGINT or SIGTERM arrived (live mode). */
int host_stop_requested(void);

/* Live mode: wait up to 20 ms for a frame; 0, or -1 with the error printed. */
int host_wait(hal_t *hal, const host_options_t *o);

/* 1 while app_poll may be called: always, but with --test-stall-poll-s S not from S
 * seconds of bus time after the first frame (t_first_us, UINT64_MAX before it). */
int host_poll_allowed(const hal_t *hal, const host_options_t *o, uint64_t t_first_us);

#endif /* NAVECU_HOST_BOARD_H */
