/*
 * host_sim/main.c - navecu on a Linux host, replaying a candump-format CAN log.
 *
 *   build/host/navecu --can-log IN.log --out OUT.log [options]
 *   build/host/navecu --can vcan0 [--out OUT.log] [options]
 *
 * Log mode:
 * Runs the firmware application over every frame of IN.log as fast as it can and writes
 * every frame it transmits to OUT.log (candump format), then prints a summary of the
 * run and of the health counters to stderr. The output depends only on the input and the
 * options: the application's time base is the IMU sample counter.
 * Live mode: the same application on a SocketCAN interface until SIGINT or SIGTERM, then
 * the same summary.
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app.h"
#include "hal_linux.h"
#include "hal_socketcan.h"
#include "options.h"

static volatile sig_atomic_t stop_requested;

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static void usage(FILE *out)
{
    fprintf(out,
            "usage: navecu --can-log IN.log --out OUT.log [options]\n"
            "       navecu --can IFACE [--out OUT.log] [options]\n"
            "\n"
            "Replay a candump-format CAN log (lines '(t) iface ID#DATA') into the navecu\n"
            "firmware and write the frames it sends, in the same format, to OUT.log; or run\n"
            "the firmware live on a SocketCAN interface (e.g. vcan0) until SIGINT/SIGTERM.\n"
            "\n"
            "  --can-log FILE       input log\n"
            "  --can IFACE          live SocketCAN interface instead of a log\n"
            "  --out FILE           output log, created or truncated (required with\n"
            "                       --can-log; with --can it records what is sent)\n"
            "  --imu-rate-hz N      IMU sample rate of the log, 10..400 (default 100)\n"
            "  --nav-rate-hz N      NAV_Position/Height/Velocity/Attitude rate (default 50,\n"
            "                       at most the IMU rate)\n"
            "  --status-rate-hz N   NAV_Status rate (default 10)\n"
            "  --level-s N          accelerometer levelling time before navigating, 1..600 s\n"
            "                       (default 30)\n"
            "  --nvm FILE           file backing the non-volatile memory (default: none, in\n"
            "                       memory only)\n"
            "  --iface NAME         interface name written in OUT.log (default can0)\n"
            "  --odo-axle AXLE      wheels measuring the distance: rear (default) or front\n"
            "                       (docs/odometry.md)\n"
            "  --cal-min-base-m X   refuse a one-point calibration closer than X m to its\n"
            "                       base (default 2000)\n"
            "  --gyro-arw-dpsh X    gyro angle random walk, deg/sqrt(h) (default 0.003)\n"
            "  --gyro-range-dps X   the IMU's gyro range, deg/s (default 300): a rate at it is\n"
            "                       saturated (counted, flagged in NAV_Status)\n"
            "  --accel-range-mps2 X the IMU's accelerometer range, m/s^2 (default 78.45, 8 g)\n"
            "  --test-stall-poll-s S  test only: stop calling app_poll S seconds of bus time\n"
            "                       after the first frame (a stuck task: the watchdog expires,\n"
            "                       exit status 3)\n"
            "  --gyro-bias-dph X    gyro turn-on bias, 1 sigma, deg/h (default 0.015); both\n"
            "                       weigh the gyro bias estimate at standstill\n"
            "  --accel-bias-mg X    accelerometer bias, 1 sigma, mg (default 0.1)\n"
            "  --gyro-instability-dph X, --accel-instability-mg X\n"
            "                       in-run bias instability over 300 s (defaults 0.005\n"
            "                       deg/h, 0.01 mg): the filter's bias random walks\n"
            "  --gnss-latency-ms N  GNSS receiver latency, 0..500 ms (default 100)\n"
            "  --gnss-corr-s X      correlation time of the receiver's position errors, s\n"
            "                       (default 20; docs/kalman.md)\n"
            "  --gnss-lever-m X,Y,Z GNSS antenna from the IMU, body axes (x right, y\n"
            "                       forward, z up), m (default 0,0,0)\n"
            "  --odo-lever-m X,Y,Z  the odometer's reference point (middle of the measuring\n"
            "                       axle) from the IMU, body axes, m (default 0,0,0)\n"
            "  --help               this text\n"
            "\n"
            "Exit status: 0 when the whole log was processed (or the live run was stopped\n"
            "by a signal), 1 on an I/O error or a missing interface, 2 on a usage error,\n"
            "3 when the watchdog expired (a task of the application was late).\n"
            "Rejected input is never fatal: it is counted in NAV_Status and in the summary\n"
            "printed to stderr.\n");
}

#define RAD_PER_DEG (3.14159265358979323846 / 180.0)

/* The main loop's watchdog duty: kick only when every task ran in time (app_tasks_ok);
 * a withheld kick that leaves the watchdog expired ends the run, as the ECU's watchdog
 * would reset the MCU. Returns 0 on expiry. */
static int supervise(app_t *app, hal_t *hal)
{
    if (app_tasks_ok(app, hal_time_us(hal))) {
        hal_watchdog_kick(hal);
        return 1;
    }
    if (hal_linux_watchdog_expired(hal)) {
        fprintf(stderr,
                "navecu: WATCHDOG EXPIRED at %.3f s: no kick for more than %u ms, a task was "
                "late (%lu late passes)\n",
                (double)hal_time_us(hal) * 1e-6, HAL_LINUX_WATCHDOG_TIMEOUT_US / 1000u,
                (unsigned long)app->health.tasks_late);
        return 0;
    }
    return 1;
}

/* --test-stall-poll-s: 1 once the stall is due (app_poll is then never called again) */
static int stalled(const hal_t *hal, int enabled, uint64_t after_us, uint64_t *t_first)
{
    const uint64_t now = hal_time_us(hal);
    if (*t_first == UINT64_MAX) {
        *t_first = now;
    }
    return enabled && now >= *t_first && now - *t_first >= after_us;
}

int main(int argc, char **argv)
{
    host_options_t opt;
    char err[160];
    if (host_options_parse(argc, argv, &opt, err, sizeof err) != 0) {
        fprintf(stderr, "navecu: %s\n", err);
        if (strncmp(err, "unknown option", 14) == 0) {
            usage(stderr);
        }
        return 2;
    }
    if (opt.help) {
        usage(stdout);
        return 0;
    }
    const char *in_path = opt.in_path, *out_path = opt.out_path, *nvm_path = opt.nvm_path;
    const char *iface = opt.iface, *live_if = opt.live_if;
    const app_config_t cfg = opt.cfg;
    const int stall_poll = opt.stall_poll;
    const uint64_t stall_poll_us = opt.stall_poll_us;

    static hal_t hal;
    static app_t app;
    if (app_init(&app, &cfg) != 0) {
        fprintf(stderr, "navecu: invalid configuration\n");
        return 2;
    }
    if (live_if != NULL) {
        uint32_t ids[HAL_SOCKETCAN_MAX_FILTERS];
        const size_t n_ids = app_rx_ids(ids, HAL_SOCKETCAN_MAX_FILTERS);
        if (hal_socketcan_open(&hal, live_if, ids, n_ids, out_path, nvm_path) != 0) {
            fprintf(stderr, "navecu: cannot open CAN interface '%s': %s\n", live_if,
                    strerror(errno));
            return 1;
        }
    } else if (hal_linux_open(&hal, in_path, out_path, nvm_path) != 0) {
        fprintf(stderr, "navecu: cannot open '%s' or '%s': %s\n", in_path, out_path,
                strerror(errno));
        return 1;
    }
    if (iface != NULL) {
        hal_linux_set_iface(&hal, iface);
    }
    app_boot(&app, &hal);

    unsigned long frames_in = 0;
    int watchdog_expired = 0;
    uint64_t t_first = UINT64_MAX; /* HAL time of the first pass (--test-stall-poll-s) */
    int rc;
    hal_can_frame_t f;
    if (live_if != NULL) {
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigaction(SIGINT, &sa, NULL);
        sigaction(SIGTERM, &sa, NULL);
        fprintf(stderr, "navecu: running on %s until SIGINT/SIGTERM\n", live_if);
        while (!stop_requested) {
            if (hal_socketcan_wait(&hal, 20) < 0) {
                fprintf(stderr, "navecu: poll failed on %s: %s\n", live_if, strerror(errno));
                break;
            }
            while ((rc = hal_can_receive(&hal, &f)) == 0) {
                frames_in++;
                app_handle_frame(&app, &hal, &f);
            }
            if (!stalled(&hal, stall_poll, stall_poll_us, &t_first)) {
                app_poll(&app, &hal);
            }
            if (!supervise(&app, &hal)) {
                watchdog_expired = 1;
                break;
            }
        }
    } else {
        while ((rc = hal_can_receive(&hal, &f)) != HAL_ENODATA) {
            if (rc == 0) {
                frames_in++;
                app_handle_frame(&app, &hal, &f);
                if (!stalled(&hal, stall_poll, stall_poll_us, &t_first)) {
                    app_poll(&app, &hal);
                }
            } else if (rc != HAL_EAGAIN) {
                fprintf(stderr, "navecu: read error on '%s'\n", in_path);
                hal_linux_close(&hal);
                return 1;
            }
            if (!supervise(&app, &hal)) {
                watchdog_expired = 1;
                break;
            }
        }
    }
    app.health.log_line_bad = hal_can_rx_malformed(&hal); /* lines after the last frame */
    const unsigned long can_err = hal_socketcan_error_frames(&hal);
    const unsigned long can_io = hal_socketcan_io_errors(&hal);
    hal_linux_close(&hal);

    const app_health_t *h = &app.health;
    static const char *const mode_names[] = {"waiting for initial state", "levelling",
                                             "navigating", "fault", "dead reckoning"};
    static const char *const cal_names[] = {"none", "loaded from NVM", "one-point",
                                            "refused (too close)", "refused (not ready)",
                                            "NVM corrupt, defaults"};
    fprintf(stderr,
            "navecu: %lu frames in, %lu malformed lines skipped, %lu frames out, %llu IMU "
            "samples (%.1f s), mode: %s\n",
            frames_in, (unsigned long)h->log_line_bad, (unsigned long)app.frames_sent,
            (unsigned long long)app.n_samples,
            (double)app.n_samples / (double)cfg.imu_rate_hz,
            (unsigned)app.mode < 5u ? mode_names[app.mode] : "?");
    fprintf(stderr,
            "navecu: rejected: unknown id %lu, bad dlc %lu, bad crc %lu, bad counter %lu, "
            "imu pair broken %lu, imu lost %lu, bad value %lu, gnss %lu, command %lu, "
            "core %lu, time jumps %lu\n",
            (unsigned long)h->unknown_id, (unsigned long)h->bad_dlc, (unsigned long)h->bad_crc,
            (unsigned long)h->bad_counter, (unsigned long)h->imu_pair_broken,
            (unsigned long)h->imu_lost, (unsigned long)h->bad_value,
            (unsigned long)h->gnss_rejected, (unsigned long)h->cmd_rejected,
            (unsigned long)h->nav_rejected, (unsigned long)h->time_jumps);
    if (app.ekf_on) {
        fprintf(stderr,
                "navecu: filter: %lu updates, %lu gated, %lu covariance corrections; odometer "
                "scale %.5f, mounting yaw %.4f deg, pitch %.4f deg\n",
                (unsigned long)app.ekf.n_updates, (unsigned long)app.ekf.n_gated,
                (unsigned long)app.ekf.n_health_fixes, (double)app.ekf.k,
                (double)app.ekf.mount_yaw_rad / RAD_PER_DEG,
                (double)app.ekf.mount_pitch_rad / RAD_PER_DEG);
    }
    fprintf(stderr,
            "navecu: calibration: %s, %u one-point, dH %.4f deg, mu %.5f, stored %u; "
            "gyro z bias at standstill %.4f deg/h from %.0f s\n",
            app.cal_status < 6u ? cal_names[app.cal_status] : "?", (unsigned)app.cal_count,
            (double)app.cal_dh_rad / RAD_PER_DEG, (double)app.cal_mu, (unsigned)app.cal_stored,
            (double)app.gyro_bias_z_rps / RAD_PER_DEG * 3600.0,
            (double)app.gz_n / (double)cfg.imu_rate_hz);
    fprintf(stderr, "navecu: supervision: %lu filter resets, %lu late task passes, %llu "
                    "watchdog kicks%s\n",
            (unsigned long)h->filter_resets, (unsigned long)h->tasks_late,
            (unsigned long long)hal_linux_watchdog_kicks(&hal),
            watchdog_expired ? ", WATCHDOG EXPIRED" : "");
    fprintf(stderr, "navecu: sensors: %lu IMU samples saturated, %lu IMU axes stuck, %lu "
                    "odometer updates refused; non-finite outputs %lu\n",
            (unsigned long)h->imu_saturated, (unsigned long)h->imu_stuck,
            (unsigned long)h->odo_rejected, (unsigned long)h->nonfinite_out);
    if (watchdog_expired) {
        return 3;
    }
    if (live_if != NULL) {
        fprintf(stderr, "navecu: CAN error frames %lu, socket errors %lu, send errors %lu\n",
                can_err, can_io, (unsigned long)app.send_errors);
        return 0; /* a live bus may refuse frames (interface down): counted, not fatal */
    }
    return app.send_errors != 0 ? 1 : 0;
}
