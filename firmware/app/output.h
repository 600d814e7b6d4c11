/*
 * output.h - output encoding: the NAV_* frames from the application's state, at the
 * configured rates on the IMU time base, with their E2E protection; the HealthFlags and
 * the output mode of NAV_Status. The only place the outputs' codec structs are filled.
 */
#ifndef NAVECU_OUTPUT_H
#define NAVECU_OUTPUT_H

#include <stdint.h>

#include "hal.h"

/* E2E transmit state and what was sent: survives a navigation reset. */
typedef struct {
    uint8_t counter[11];        /* alive counters of the E2E-protected outputs */
    uint8_t status_page;        /* next counter page of NAV_Status */
    uint32_t frames_sent;
    uint32_t send_errors;
    uint64_t last_status_t_us;  /* HAL time of the last NAV_Status (app_poll) */
    uint8_t last_mode;          /* Mode of the last NAV_Status page 0 (0 WaitInit at boot) */
    /* NAV_Heartbeat, the one time-driven output (output_heartbeat): nothing of it is read
     * by the data-driven outputs */
    uint64_t boot_us;           /* HAL time of the first heartbeat: uptime 0 */
    uint32_t hb_uptime_s;       /* the uptime, whole seconds, of the last heartbeat */
    uint8_t hb_sent;            /* a heartbeat has been sent */
} tx_state_t;

typedef struct app app_t; /* app.h */

/* The outputs due after the current IMU sample (the application's time base): the
 * navigation frames at the NAV rate while navigating, NAV_Status at its rate and on a
 * change of Mode (before the navigation set of that sample, so a receiver never gets a
 * position after a status saying the ECU is not navigating, nor a WaitInit/Fault late),
 * NAV_Calibration at 1 Hz. */
void output_due(app_t *a, hal_t *hal);

/* NAV_Status now (app_poll: the heartbeat while no IMU data arrives). */
void output_status(app_t *a, hal_t *hal);

/* Before the first IMU sample, from app_poll at the status rate once the IMU is overdue
 * (APP_IMU_STALE_US after power-on): the DTCs of IMU_STALE (failing) and NVM_ERROR tested,
 * the others not (their flags count IMU samples), and nothing sent (the data-driven outputs wait for data, so a live run's
 * frames do not depend on how long the ECU waited for its input). */
void output_dtc_tests(app_t *a, hal_t *hal);

/* NAV_Heartbeat when due (app_poll, every main-loop pass): the first at the first call
 * (uptime 0, the boot), then one at each whole second of uptime on the HAL clock, whatever
 * the input. Mode as NAV_Status page 0; the inputs missing now (IMU_STALE or no IMU
 * sample since boot, NO_GNSS, the odometer not valid); the uptime; its own E2E counter.
 * The one output driven by time: every other frame is the same with or without it. */
void output_heartbeat(app_t *a, hal_t *hal);

#endif /* NAVECU_OUTPUT_H */
