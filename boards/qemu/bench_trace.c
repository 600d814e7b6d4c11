/* bench_trace.c - SysTick tracing and console of the QEMU board; see bench_trace.h. */
#include "bench_trace.h"

#include "app.h"
#include "semihost.h"

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)
#define SYST_MASK 0x00FFFFFFu
#define CMDLINE_MAX 512u
#define TRACE_BUF 4096u

static char cmdline[CMDLINE_MAX];
static char trace_buf[TRACE_BUF];
static size_t trace_len;
static int32_t trace_fd = -1;

/* the application's profiling points (app.h): ticks per occurrence */
typedef struct {
    uint32_t t_begin;
    uint32_t last;
    uint32_t n;
    uint64_t sum;
    uint32_t max;
} point_stats_t;
static point_stats_t points[APP_TRACE_N];
static const char *const point_names[APP_TRACE_N] = {"mechanization", "prediction",
                                                     "odometer_update", "gnss_update", "frame"};

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

void bench_puts(const char *s)
{
    semihost_puts(s);
}

void bench_put_u64(uint64_t v)
{
    char buf[21];
    (void)fmt_u64(buf, v);
    semihost_puts(buf);
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

size_t bench_args(const char **argv, size_t max)
{
    if (semihost_cmdline(cmdline, sizeof cmdline) != 0) {
        return 0u;
    }
    char *s = cmdline;
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
    p->last = dt;
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

int bench_trace_open(const char *path)
{
    trace_fd = semihost_open(path, SEMIHOST_MODE_WB);
    if (trace_fd < 0) {
        return -1;
    }
    SYST_RVR = SYST_MASK;
    SYST_CVR = 0u;
    SYST_CSR = 0x5u; /* CLKSOURCE = core clock, ENABLE, no interrupt */
    const uint32_t n_loop = 1000000u;
    trace_text("calibration ");
    trace_u64(2u * (uint64_t)n_loop, ' ');
    trace_u64(calibration_ticks(n_loop), '\n');
    return 0;
}

void bench_trace_frame(uint32_t id, uint32_t updates)
{
    if (trace_fd < 0) {
        return;
    }
    trace_hex(id, ' ');
    trace_u64(points[APP_TRACE_FRAME].last, ' ');
    trace_u64(updates, '\n');
}

void bench_trace_close(void)
{
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
}
