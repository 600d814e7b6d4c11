/* report.c - the host executable's --help and run summary; see report.h. */
#include "report.h"

#include "hal_linux.h"
#include "hal_socketcan.h"
#include "vehicle.h"

#define RAD_PER_DEG (3.14159265358979323846 / 180.0)

void host_usage(FILE *out)
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
            "  --status-rate-hz N   NAV_Status and NAV_Accuracy rate (default 10)\n"
            "  --dyn-rate-hz N      NAV_Rates, NAV_AttitudeRates, NAV_Accel, NAV_AccelEnu rate\n"
            "                       (default 50, at most the IMU rate; 0: not sent)\n"
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

void host_summary(FILE *out, const app_t *app, const hal_t *hal, unsigned long frames_in,
                  int watchdog_expired, int live)
{
    const app_health_t *h = app_health(app);
    const calib_t *cal = app_calibration(app);
    const ekf_t *ekf = app_filter(app);
    const double rate = (double)app->cfg.imu_rate_hz;
    static const char *const mode_names[] = {"waiting for initial state", "levelling",
                                             "navigating", "fault"};
    static const char *const cal_names[] = {"none", "loaded from NVM", "one-point",
                                            "refused (too close)", "refused (not ready)",
                                            "NVM corrupt, defaults"};
    fprintf(out,
            "navecu: %lu frames in, %lu malformed lines skipped, %lu frames out, %llu IMU "
            "samples (%.1f s), mode: %s\n",
            frames_in, (unsigned long)hal_can_rx_malformed(hal),
            (unsigned long)app->keep.tx.frames_sent, (unsigned long long)app_samples(app),
            (double)app_samples(app) / rate,
            (unsigned)app_mode(app) < 4u ? mode_names[app_mode(app)] : "?");
    fprintf(out,
            "navecu: rejected: bad dlc %lu, bad crc %lu, bad counter %lu, "
            "imu pair broken %lu, imu lost %lu, bad value %lu, gnss %lu, command %lu, "
            "core %lu, time jumps %lu\n",
            (unsigned long)h->bad_dlc, (unsigned long)h->bad_crc,
            (unsigned long)h->bad_counter, (unsigned long)h->imu_pair_broken,
            (unsigned long)h->imu_lost, (unsigned long)h->bad_value,
            (unsigned long)h->gnss_rejected, (unsigned long)h->cmd_rejected,
            (unsigned long)h->nav_rejected, (unsigned long)h->time_jumps);
    fprintf(out, "navecu: foreign frames (not read, not refused): %lu\n",
            (unsigned long)h->foreign);
    if (h->imu_rate_mismatch != 0u) {
        fprintf(out,
                "navecu: IMU rate mismatch found %lu times: configured %u Hz, the data %s "
                "(measured %.2f Hz from the samples between GNSS epochs)\n",
                (unsigned long)h->imu_rate_mismatch, (unsigned)app->cfg.imu_rate_hz,
                imu_rate_mismatch(&app->keep.rate) ? "still disagree" : "match again",
                (double)app->keep.rate.measured_chz * 0.01);
    }
    if (!vehicle_profile.native_wheels) {
        const uint32_t *n = app->keep.rx.car_read;
        fprintf(out,
                "navecu: car messages read (profile %s): wheel speeds %lu, gear %lu, yaw rate "
                "%lu\n",
                vehicle_profile.name, (unsigned long)n[VEHICLE_MSG_WHEELS],
                (unsigned long)n[VEHICLE_MSG_GEAR], (unsigned long)n[VEHICLE_MSG_YAW_RATE]);
    }
    if (ekf != NULL) {
        fprintf(out,
                "navecu: filter: %lu updates, %lu gated, %lu covariance corrections; odometer "
                "scale %.5f, mounting yaw %.4f deg, pitch %.4f deg\n",
                (unsigned long)ekf->n_updates, (unsigned long)ekf->n_gated,
                (unsigned long)ekf->n_health_fixes, (double)ekf->k,
                (double)ekf->mount_yaw_rad / RAD_PER_DEG,
                (double)ekf->mount_pitch_rad / RAD_PER_DEG);
    }
    fprintf(out,
            "navecu: calibration: %s, %u one-point, dH %.4f deg, mu %.5f, stored %u; "
            "gyro z bias at standstill %.4f deg/h from %.0f s\n",
            cal->status < 6u ? cal_names[cal->status] : "?", (unsigned)cal->count,
            (double)cal->dh_rad / RAD_PER_DEG, (double)cal->mu, (unsigned)cal->stored,
            (double)app->keep.zbias.bias_rps / RAD_PER_DEG * 3600.0,
            (double)app->keep.zbias.n / rate);
    fprintf(out, "navecu: supervision: %lu filter resets, %lu late task passes, %llu "
                 "watchdog kicks%s\n",
            (unsigned long)h->filter_resets, (unsigned long)h->tasks_late,
            (unsigned long long)hal_linux_watchdog_kicks(hal),
            watchdog_expired ? ", WATCHDOG EXPIRED" : "");
    fprintf(out, "navecu: sensors: %lu IMU samples saturated, %lu IMU axes stuck, %lu "
                 "odometer updates refused; non-finite outputs %lu\n",
            (unsigned long)h->imu_saturated, (unsigned long)h->imu_stuck,
            (unsigned long)h->odo_rejected, (unsigned long)h->nonfinite_out);
    if (live) {
        fprintf(out, "navecu: CAN error frames %lu, socket errors %lu, send errors %lu\n",
                (unsigned long)hal_socketcan_error_frames(hal),
                (unsigned long)hal_socketcan_io_errors(hal),
                (unsigned long)app->keep.tx.send_errors);
    }
}
