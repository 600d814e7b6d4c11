/*
 * bench_trace.h - the QEMU board's measurement (make target-bench): SysTick ticks spent
 * on every frame and at the application's profiling points (app_trace), written to a
 * trace file through semihosting, and the console it reports on. It reads SysTick only;
 * it does not change what the application computes.
 *
 * Trace file: "calibration INSTRUCTIONS TICKS" (a loop of known length), one line per
 * frame "ID TICKS UPDATES" (hex ID; ticks in app_handle_frame + app_poll; Kalman updates
 * it made), and at the end one line per profiling point "point NAME COUNT SUM MAX".
 * Under `-icount shift=0` QEMU advances its clock 1 ns per instruction and SysTick runs
 * from the 168 MHz core clock: one tick is about 5.95 instructions.
 */
#ifndef NAVECU_BENCH_TRACE_H
#define NAVECU_BENCH_TRACE_H

#include <stddef.h>
#include <stdint.h>

/* Open the trace file and calibrate; 0, or -1 if it cannot be opened. */
int bench_trace_open(const char *path);

/* One frame's line (after app_pass handled it; the ticks are the APP_TRACE_FRAME ones). */
void bench_trace_frame(uint32_t id, uint32_t updates);

/* The point lines; flush and close. */
void bench_trace_close(void);

/* Console output through semihosting. */
void bench_puts(const char *s);
void bench_put_u64(uint64_t v);

/* Split the semihosting command line at blanks; returns the number of words (<= max). */
size_t bench_args(const char **argv, size_t max);

#endif /* NAVECU_BENCH_TRACE_H */
