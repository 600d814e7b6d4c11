/*
 * report.h - what the host executable prints: the --help text, and the summary of a run
 * (frames, rejections, the filter, the calibration, supervision, sensors) on stderr.
 */
#ifndef NAVECU_HOST_REPORT_H
#define NAVECU_HOST_REPORT_H

#include <stdio.h>

#include "app.h"

void host_usage(FILE *out);

/* The run's summary; live: it ran on a SocketCAN interface (its error counts follow). */
void host_summary(FILE *out, const app_t *app, const hal_t *hal, unsigned long frames_in,
                  int watchdog_expired, int live);

#endif /* NAVECU_HOST_REPORT_H */
