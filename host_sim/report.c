/* report.c - the host executable's --help and run summary; see report.h. */
#include "report.h"

#include "hal_linux.h"
#include "hal_socketcan.h"
#include "vehicle.h"

#include <math.h>
#include <string.h>

#include "params_cli.h"

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
            "  --imu-preset NAME    the IMU figures of a grade, together (below); the other\n"
            "                       options override them, wherever they are\n"
            "  --nvm FILE           file backing the non-volatile memory (default: none, in\n"
            "                       memory only); the parameters stored there are loaded,\n"
            "                       the options given here go over them\n"
            "  --iface NAME         interface name written in OUT.log (default can0)\n"
            "  --report-filter-at-s S  print what the filter knows of the heading and the z\n"
            "                       gyro once S seconds of IMU samples have been processed\n"
            "                       (the figures of tools/sim/gyro_floor.py)\n"
            "  --test-stall-poll-s S  test only: stop calling app_poll S seconds of bus time\n"
            "                       after the first frame (a stuck task: the watchdog expires,\n"
            "                       exit status 3)\n"
            "  --help               this text\n"
            "\n"
            "Exit status: 0 when the whole log was processed (or the live run was stopped\n"
            "by a signal), 1 on an I/O error or a missing interface, 2 on a usage error,\n"
            "3 when the watchdog expired (a task of the application was late).\n"
            "Rejected input is never fatal: it is counted in NAV_Status and in the summary\n"
            "printed to stderr.\n"
            "\n"
            "Parameters (firmware/app/params.toml, docs/configuration.md): --OPTION VALUE in\n"
            "the unit shown, within the range shown; a three-axis value is X,Y,Z (body axes\n"
            "x right, y forward, z up).\n");
    for (size_t k = 0u; k < (size_t)PARAMS_CLI_N; k++) {
        const params_cli_t *c = &params_cli[k];
        const app_param_t *p = &app_params[c->id];
        fprintf(out, "  %-22s ", c->option);
        if (p->type == APP_PARAM_ENUM) {
            fprintf(out, "%s", c->values);
        } else {
            fprintf(out, "%s%g..%g %s", p->min_exclusive ? ">" : "", c->min, c->max, c->unit);
        }
        if (p->vehicle_default) {
            const app_config_t d = app_default_config();
            nav_real_t v[3];
            app_param_get(&d, c->id, v);
            fprintf(out, ", default: the vehicle profile's (%s: %.6g)\n", vehicle_profile.name,
                    (double)v[0] / c->to_si);
        } else if (p->type == APP_PARAM_ENUM) {
            const char *v = c->values;
            for (int i = 0; i < (int)p->default_si && strchr(v, '|') != NULL; i++) {
                v = strchr(v, '|') + 1;
            }
            const char *bar = strchr(v, '|');
            fprintf(out, ", default %.*s\n", (int)(bar != NULL ? (size_t)(bar - v) : strlen(v)), v);
        } else {
            fprintf(out, ", default %g\n", (double)p->default_si / c->to_si);
        }
        fprintf(out, "                         %s\n", c->description);
    }
    fprintf(out, "\nIMU presets (--imu-preset NAME; default %s):\n",
            app_preset_names[APP_PRESET_DEFAULT]);
    for (int k = 0; k < (int)APP_PRESET_N; k++) {
        fprintf(out, "  %-12s %s\n", app_preset_names[k], params_cli_preset_about[k]);
    }
}

void host_filter_report(FILE *out, const app_t *app)
{
    const double t_s = (double)app_samples(app) / (double)app->cfg.imu_rate_hz;
    const ekf_t *k = app_filter(app);
    if (k == NULL) {
        fprintf(out, "navecu: filter at %.2f s: not running\n", t_s);
        return;
    }
    /* the car's heading: the IMU's psi_U less the mounting's yaw (output.c) */
    const int h = EKF_PSI + 2, m = EKF_MY, bt = EKF_BG + 2, bi = EKF_GZ;
    const double hh = (double)ekf_state_cov(k, h, h) + (double)ekf_state_cov(k, m, m) -
                      2.0 * (double)ekf_state_cov(k, h, m);
    const double tt = (double)ekf_state_cov(k, bt, bt), ii = (double)ekf_state_cov(k, bi, bi);
    const double ht = (double)ekf_state_cov(k, h, bt) - (double)ekf_state_cov(k, m, bt);
    const double hi = (double)ekf_state_cov(k, h, bi) - (double)ekf_state_cov(k, m, bi);
    const double ti = (double)ekf_state_cov(k, bt, bi);
    const double deg = 1.0 / RAD_PER_DEG, dph = deg * 3600.0;
    fprintf(out,
            "navecu: filter at %.2f s: car heading sigma %.4f deg; z gyro turn-on bias sigma "
            "%.3f deg/h, in-run %.3f deg/h; correlations heading/turn-on %+.3f, heading/in-run "
            "%+.3f, turn-on/in-run %+.3f (the filter's: its attitude error integrates minus "
            "the bias); z gyro scale factor sigma %.0f ppm\n",
            t_s, sqrt(hh) * deg, sqrt(tt) * dph, sqrt(ii) * dph, ht / sqrt(hh * tt),
            hi / sqrt(hh * ii), ti / sqrt(tt * ii),
            sqrt((double)ekf_state_cov(k, EKF_SG, EKF_SG)) * 1e6);
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
            frames_in, (unsigned long)hal_linux_rx_malformed(hal),
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
    if (app->keep.raw_epochs != 0u) {
        const fusion_raw_counts_t *r = &app->keep.raw_counts;
        fprintf(out, "navecu: raw GNSS epochs %lu, satellites %lu; fused epochs %lu: "
                "pseudoranges %lu, range rates %lu used, %lu excluded (fault exclusion), %lu "
                "gated; clock starts %lu, clock jumps %lu; pseudoranges with a learnt bias "
                "removed %lu\n",
                (unsigned long)app->keep.raw_epochs, (unsigned long)app->keep.raw_sats,
                (unsigned long)r->epochs_used, (unsigned long)r->pr_used,
                (unsigned long)r->rr_used, (unsigned long)r->excluded,
                (unsigned long)r->gated, (unsigned long)r->clock_starts,
                (unsigned long)r->clock_jumps, (unsigned long)r->corrected);
    }
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
                "scale %.5f (sigma %.5f), mounting yaw %.4f deg (sigma %.4f), pitch %.4f deg\n",
                (unsigned long)ekf->n_updates, (unsigned long)ekf->n_gated,
                (unsigned long)ekf->n_health_fixes, (double)ekf->k,
                (double)ekf_state_sigma(ekf, EKF_K), (double)ekf->mount_yaw_rad / RAD_PER_DEG,
                (double)ekf_state_sigma(ekf, EKF_MY) / RAD_PER_DEG,
                (double)ekf->mount_pitch_rad / RAD_PER_DEG);
        nav_real_t v_mean = NAV_C(0.0), mu = NAV_C(0.0), s_mu = NAV_C(0.0);
        (void)calib_filter_scale(&app->run.cal, ekf, &v_mean, &mu, &s_mu);
        fprintf(out,
                "navecu: odometer offset %.3f m/s (sigma %.3f); at the trip's mean speed "
                "%.2f m/s a scale of %.5f (sigma %.5f)\n",
                (double)ekf->odo_offset_mps, (double)ekf_state_sigma(ekf, EKF_OB),
                (double)v_mean, (double)mu, (double)s_mu);
        fprintf(out, "navecu: GNSS correlated error: E %.2f N %.2f m (sigma %.2f m)\n",
                (double)ekf->gnss_bias_m[0], (double)ekf->gnss_bias_m[1],
                (double)ekf_state_sigma(ekf, EKF_GB));
        fprintf(out, "navecu: z gyro scale factor %+.0f ppm (sigma %.0f ppm)\n",
                (double)ekf->gyro_scale_z * 1e6, (double)ekf_state_sigma(ekf, EKF_SG) * 1e6);
    }
    fprintf(out,
            "navecu: calibration: %s, %u adopted, dH %.4f deg, mu %.5f, stored %u; "
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
    fprintf(out, "navecu: of the bad values, IMU_Time stamps %lu; DTC bytes: %lu NVM writes, "
                 "%lu failed, %lu refused at start; UDS responsePending sent %lu\n",
            (unsigned long)h->imu_timing, (unsigned long)app->keep.dtc_persist_writes,
            (unsigned long)app->keep.dtc_persist_failed,
            (unsigned long)app->keep.dtc.load_rejected, (unsigned long)app->uds.pending_sent);
    if (live) {
        fprintf(out, "navecu: CAN error frames %lu, frames the socket dropped %lu, socket "
                     "errors %lu, send errors %lu\n",
                (unsigned long)hal_socketcan_error_frames(hal),
                (unsigned long)hal_socketcan_rx_dropped(hal),
                (unsigned long)hal_socketcan_io_errors(hal),
                (unsigned long)app->keep.tx.send_errors);
    }
}
