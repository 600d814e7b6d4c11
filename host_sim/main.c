/*
 * host_sim/main.c - navecu on a Linux host: a candump-format CAN log replayed as fast as
 * it can be read (--can-log IN --out OUT), or a live SocketCAN interface (--can vcan0)
 * until SIGINT/SIGTERM; the same application and main-loop pass as the ECU (app_loop.h),
 * then a summary on stderr (report.h). The output depends only on the input and the
 * options: the application's time base is the IMU sample counter.
 */
#include <stdio.h>
#include <string.h>

#include "app.h"
#include "app_loop.h"
#include "hal_linux.h"
#include "host_board.h"
#include "options.h"
#include "report.h"

/* the command line, the board's configuration layer over the defaults and the NVM
 * (app_start, app.h), at the start and at every ECUReset */
static int cmd_argc;
static char **cmd_argv;

int app_board_layer(app_config_t *cfg)
{
    static host_options_t over;
    if (cmd_argv == NULL) {
        return 0;
    }
    if (host_options_parse_over(cmd_argc, cmd_argv, cfg, &over, NULL, 0u) != 0) {
        return -1;
    }
    *cfg = over.cfg;
    return 0;
}

int main(int argc, char **argv)
{
    static host_options_t o;
    static hal_t hal;
    static app_t app;
    char err[160];
    if (host_options_parse(argc, argv, &o, err, sizeof err) != 0) {
        fprintf(stderr, "navecu: %s\n", err);
        if (strncmp(err, "unknown option", 14) == 0) {
            host_usage(stderr);
        }
        return 2;
    }
    if (o.help) {
        host_usage(stdout);
        return 0;
    }
    if (app_init(&app, &o.cfg) != 0) {
        fprintf(stderr, "navecu: invalid configuration\n");
        return 2;
    }
    if (host_open(&hal, &o) != 0) {
        return 1;
    }
    /* the layers: defaults, the NVM (--nvm), the command line over both */
    cmd_argc = argc;
    cmd_argv = argv;
    if (app_start(&app, &hal) != 0) {
        fprintf(stderr, "navecu: invalid configuration over the NVM's parameters\n");
        hal_linux_close(&hal);
        return 2;
    }
    const int live = o.live_if != NULL;
    unsigned long frames_in = 0;
    uint64_t t_first = UINT64_MAX; /* the first frame's time (--test-stall-poll-s) */
    int expired = 0, read_error = 0, filter_reported = 0;
    /* --report-filter-at-s: at an IMU sample count, not a time of arrival */
    const uint64_t report_at = o.report_filter_ms * app.cfg.imu_rate_hz / 1000u;
    while (!host_stop_requested() && !expired && !(live && host_wait(&hal, &o) != 0)) {
        const app_pass_cfg_t pass = {live ? 64u : 1u, (uint8_t)host_poll_allowed(&hal, &o, t_first)};
        const app_pass_t p = app_pass(&app, &hal, &pass);
        frames_in += p.frames;
        t_first = p.frames != 0u && t_first == UINT64_MAX ? p.last.t_us : t_first;
        if (p.rx_status == HAL_ENODATA || (!live && !app_pass_go_on(&p))) {
            read_error = p.rx_status != HAL_ENODATA;
            break; /* the end of the log, or a read error */
        }
        expired = !p.kicked && hal_linux_watchdog_expired(&hal);
        if (o.report_filter && !filter_reported && app_samples(&app) >= report_at) {
            host_filter_report(stderr, &app);
            filter_reported = 1;
        }
    }
    if (expired) {
        fprintf(stderr, "navecu: WATCHDOG EXPIRED at %.3f s: no kick for more than %u ms, a "
                "task was late (%lu late passes)\n", (double)hal_time_us(&hal) * 1e-6,
                HAL_LINUX_WATCHDOG_TIMEOUT_US / 1000u, (unsigned long)app_health(&app)->tasks_late);
    }
    if (read_error) {
        fprintf(stderr, "navecu: read error on '%s'\n", o.in_path);
    }
    if (o.report_filter && !filter_reported) {
        fprintf(stderr, "navecu: filter at %.2f s: not reached (%.2f s of IMU samples)\n",
                (double)o.report_filter_ms * 1e-3,
                (double)app_samples(&app) / (double)app.cfg.imu_rate_hz);
    }
    host_summary(stderr, &app, &hal, frames_in, expired, live);
    hal_linux_close(&hal);
    /* a live bus may refuse frames (interface down): counted, not fatal */
    return expired ? 3 : (read_error || (!live && app.keep.tx.send_errors != 0u) ? 1 : 0);
}
