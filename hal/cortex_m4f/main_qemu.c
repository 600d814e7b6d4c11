/*
 * main_qemu.c - the navecu application on the Cortex-M4F under QEMU (netduinoplus2, an
 * STM32F405), replaying a candump log through semihosting (hal_semihost.h):
 *
 *   qemu-system-arm -M netduinoplus2 -nographic -monitor none -serial none \
 *       -semihosting-config enable=on,target=native,arg=navecu,arg=IN.log,arg=OUT.log \
 *       [-icount shift=0 ... arg=TRACE.txt] -kernel build/target/navecu-qemu.elf
 *
 * The loop is host_sim/main.c's log mode, frame for frame, with the default configuration,
 * so OUT.log must equal `build/host/navecu --can-log IN.log --out OUT.log` byte for byte
 * (make target-test). With a fourth argument it also writes one line per frame to TRACE:
 * "ID TICKS UPDATES" (hex ID; SysTick ticks spent in app_handle_frame + app_poll for it;
 * Kalman updates it made), which tools/target/qemu_run.py turns into instruction counts:
 * under `-icount shift=0` QEMU advances its virtual clock 1 ns per instruction, and the
 * SysTick runs from the 168 MHz core clock, so one tick is 1e9/168e6 = 5.95 instructions
 * (calibrated at start-up with a loop of known length, also written to TRACE), and at the
 * end one line per profiling point of app.h: "point NAME COUNT SUM_TICKS MAX_TICKS". The
 * measurement reads SysTick only; it does not change what the application computes.
 */
#include <stdint.h>

#include "app.h"
#include "hal_semihost.h"
#include "semihost.h"

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)
#define SYST_MASK 0x00FFFFFFu

#define CMDLINE_MAX 512u
#define N_ARGS_MAX 5u
#define TRACE_BUF 4096u

static hal_t hal;
static app_t app;
static char cmdline[CMDLINE_MAX];
static char trace_buf[TRACE_BUF];
static size_t trace_len;
static int32_t trace_fd = -1;

void board_main(void) __attribute__((noreturn));
void board_fault(void);

/* an unexpected exception (startup.c's default_handler): fail the run, exit status 3 */
void board_fault(void)
{
    semihost_puts("navecu-qemu: fault exception\n");
    semihost_exit(3u);
}

static void put_str(const char *s)
{
    semihost_puts(s);
}

/* decimal of v into buf (>= 21 bytes), NUL-terminated; returns the length */
static size_t fmt_u64(char *buf, uint64_t v)
{
    char rev[20];
    size_t n = 0u;
    do {
        rev[n++] = (char)('0' + (char)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    for (size_t k = 0u; k < n; k++) {
        buf[k] = rev[n - 1u - k];
    }
    buf[n] = '\0';
    return n;
}

static void put_u64(uint64_t v)
{
    char buf[21];
    (void)fmt_u64(buf, v);
    put_str(buf);
}

static void trace_flush(void)
{
    if (trace_fd >= 0 && trace_len > 0u) {
        (void)semihost_write(trace_fd, trace_buf, trace_len);
    }
    trace_len = 0u;
}

static void trace_text(const char *s)
{
    while (*s != '\0') {
        if (trace_len == TRACE_BUF) {
            trace_flush();
        }
        trace_buf[trace_len++] = *s++;
    }
}

static void trace_u64(uint64_t v, char sep)
{
    char buf[22];
    const size_t n = fmt_u64(buf, v);
    buf[n] = sep;
    buf[n + 1u] = '\0';
    trace_text(buf);
}

static void trace_hex(uint32_t v, char sep)
{
    static const char hex[] = "0123456789abcdef";
    char buf[10];
    size_t n = 0u;
    for (int shift = 28; shift >= 0; shift -= 4) {
        const uint32_t d = (v >> (unsigned)shift) & 0xFu;
        if (d != 0u || n > 0u || shift == 0) {
            buf[n++] = hex[d];
        }
    }
    buf[n++] = sep;
    buf[n] = '\0';
    trace_text(buf);
}

/* split the command line at blanks, in place; returns the number of words */
static size_t split_args(char *s, const char **argv, size_t max)
{
    size_t n = 0u;
    while (*s != '\0' && n < max) {
        while (*s == ' ') {
            *s++ = '\0';
        }
        if (*s == '\0') {
            break;
        }
        argv[n++] = s;
        while (*s != '\0' && *s != ' ') {
            s++;
        }
    }
    return n;
}

static uint32_t systick_now(void)
{
    return SYST_CVR & SYST_MASK;
}

/* ticks from a to b of the down-counting 24-bit SysTick */
static uint32_t ticks_between(uint32_t a, uint32_t b)
{
    return (a - b) & SYST_MASK;
}

/* the application's profiling points (app.h): ticks per occurrence */
typedef struct {
    uint32_t t_begin;
    uint32_t n;
    uint64_t sum;
    uint32_t max;
} point_stats_t;
static point_stats_t points[APP_TRACE_N];
static const char *const point_names[APP_TRACE_N] = {"mechanization", "prediction",
                                                     "odometer_update", "gnss_update"};

void app_trace(uint32_t point, uint32_t end)
{
    if (trace_fd < 0 || point >= (uint32_t)APP_TRACE_N) {
        return;
    }
    point_stats_t *p = &points[point];
    const uint32_t now = systick_now();
    if (end == 0u) {
        p->t_begin = now;
        return;
    }
    const uint32_t dt = ticks_between(p->t_begin, now);
    p->n++;
    p->sum += dt;
    p->max = dt > p->max ? dt : p->max;
}

/* SysTick ticks for a loop of 2 * n + a few instructions (subs + bne per iteration) */
static uint32_t calibration_ticks(uint32_t n)
{
    const uint32_t t0 = systick_now();
    __asm__ volatile("1:\n\tsubs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
    return ticks_between(t0, systick_now());
}

void board_main(void)
{
    const char *argv[N_ARGS_MAX];
    if (semihost_cmdline(cmdline, sizeof cmdline) != 0) {
        put_str("navecu-qemu: no semihosting command line\n");
        semihost_exit(2u);
    }
    const size_t argc = split_args(cmdline, argv, N_ARGS_MAX);
    if (argc < 3u) {
        put_str("usage: navecu-qemu IN.log OUT.log [TRACE.txt] (semihosting arguments)\n");
        semihost_exit(2u);
    }
    const app_config_t cfg = app_default_config();
    if (app_init(&app, &cfg) != 0) {
        put_str("navecu-qemu: bad configuration\n");
        semihost_exit(2u);
    }
    if (hal_semihost_open(&hal, argv[1], argv[2]) != 0) {
        put_str("navecu-qemu: cannot open the input or output log\n");
        semihost_exit(1u);
    }
    if (argc >= 4u) {
        trace_fd = semihost_open(argv[3], SEMIHOST_MODE_WB);
        if (trace_fd < 0) {
            put_str("navecu-qemu: cannot open the trace file\n");
            semihost_exit(1u);
        }
        SYST_RVR = SYST_MASK;
        SYST_CVR = 0u;
        SYST_CSR = 0x5u; /* CLKSOURCE = core clock, ENABLE, no interrupt */
        const uint32_t n_loop = 1000000u;
        trace_text("calibration ");
        trace_u64(2u * (uint64_t)n_loop, ' ');
        trace_u64(calibration_ticks(n_loop), '\n');
    }
    app_boot(&app, &hal);

    uint64_t frames_in = 0u;
    int rc;
    hal_can_frame_t f;
    while ((rc = hal_can_receive(&hal, &f)) != HAL_ENODATA) {
        if (rc == 0) {
            frames_in++;
            const uint32_t updates0 = app.ekf.n_updates;
            const uint32_t t0 = systick_now();
            app_handle_frame(&app, &hal, &f);
            app_poll(&app, &hal);
            const uint32_t t1 = systick_now();
            if (trace_fd >= 0) {
                trace_hex(f.id, ' ');
                trace_u64(ticks_between(t0, t1), ' ');
                trace_u64(app.ekf.n_updates - updates0, '\n');
            }
        } else if (rc != HAL_EAGAIN) {
            put_str("navecu-qemu: read error on the input log\n");
            (void)hal_semihost_close(&hal);
            semihost_exit(1u);
        }
        if (app_tasks_ok(&app, hal_time_us(&hal))) { /* as host_sim/main.c */
            hal_watchdog_kick(&hal);
        }
    }
    app.health.log_line_bad = hal_can_rx_malformed(&hal);
    const int close_rc = hal_semihost_close(&hal);
    for (uint32_t k = 0u; k < (uint32_t)APP_TRACE_N && trace_fd >= 0; k++) {
        trace_text("point ");
        trace_text(point_names[k]);
        trace_text(" ");
        trace_u64(points[k].n, ' ');
        trace_u64(points[k].sum, ' ');
        trace_u64(points[k].max, '\n');
    }
    trace_flush();
    if (trace_fd >= 0) {
        (void)semihost_close(trace_fd);
    }
    put_str("navecu-qemu: ");
    put_u64(frames_in);
    put_str(" frames in, ");
    put_u64(app.health.log_line_bad);
    put_str(" malformed lines skipped, ");
    put_u64(app.frames_sent);
    put_str(" frames out, ");
    put_u64(app.n_samples);
    put_str(" IMU samples\n");
    semihost_exit(app.send_errors != 0u || close_rc != 0 ? 1u : 0u);
}
