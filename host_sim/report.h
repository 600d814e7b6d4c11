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

/* --report-filter-at-s: what the filter knows of the heading and the z gyro now, the
 * figures of tools/sim/gyro_floor.py (docs/kalman.md, "Over many seeds"): the car's
 * heading sigma (as NAV_Accuracy's), the z gyro's turn-on and in-run bias sigmas, their
 * three correlations as the filter has them, the z gyro's scale factor sigma. */
void host_filter_report(FILE *out, const app_t *app);

#endif /* NAVECU_HOST_REPORT_H */
