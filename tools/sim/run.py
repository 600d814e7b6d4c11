"""Simulate a drive, run the firmware on it, and report its accuracy (`make sim`).

    python -m tools.sim.run [--scenario default] [--imu mid-grade] [--gnss standalone]
                            [--seed 1] [--out out/sim/NAME] [--navecu build/host/navecu]

Stages: the scenario (tools/sim/scenario.py) and its exact trajectory
(tools/sim/trajectory.py); sensor data from the error models (tools/sim/sensors.py);
everything encoded through the project's DBC into a candump log (tools/navecu_can.py: E2E
counters and CRCs, IMU remainder carry); the host firmware run over it (build/host/navecu
--can-log); the report (tools/sim/report.py): report.json and PNG plots in the output
folder, a summary on stdout.

Initialization as a driver would do it: at t = 0 the vehicle stands still and receives
CMD_KnownPosition and CMD_Control SetInitialPosition (true position, height and heading);
the firmware levels for 30 s and navigates from then on. The heading sent is the car's, or
with the scenario's [initialization] that of the IMU's axes and/or with an error
(scenario.heading_command_deg). A scenario's [calibration] adds the one-point calibration
request of seed 000 at its at_s: CMD_KnownPosition with the true position and CMD_Control
CalibrateHere, or CalibrateAtGnss and the next GNSS epoch (calibration_frames).
"""
from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from tools import gnss_raw
from tools import navecu_can as nc
from tools.sim import report, scenario, sensors, trajectory

ROOT = Path(__file__).resolve().parents[2]
# the drive's GPS time (tools/sim/scenario.py), named here too for the run's users
GPS_TOW0_S = scenario.GPS_TOW0_S
GPS_WEEK = scenario.GPS_WEEK


class Stages:
    """Progress lines: '[2/5] sensor models ... 1.3 s'."""

    def __init__(self, n):
        self.n, self.k, self.t0 = n, 0, None

    def start(self, what):
        self.k += 1
        self.t0 = time.monotonic()
        print(f"[{self.k}/{self.n}] {what} ...", end="", flush=True)

    def done(self, extra=""):
        print(f" {time.monotonic() - self.t0:.1f} s{(' - ' + extra) if extra else ''}",
              flush=True)

    def firmware(self, cmd: list, out: Path, head: str = "") -> subprocess.CompletedProcess:
        """Run navecu (cmd) as this stage: its stderr into out/navecu.txt (after head),
        the summary's first line as the stage's result; on a failure (returncode not 0)
        its stderr printed."""
        res = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
        (out / "navecu.txt").write_text(head + res.stderr)
        if res.returncode != 0:
            print()
            print(res.stderr, file=sys.stderr)
        else:
            self.done(res.stderr.strip().splitlines()[0].replace("navecu: ", ""))
        return res


def _one_epoch(gnss: dict, i: int) -> dict:
    return {k: np.asarray(v)[i:i + 1] for k, v in gnss.items()}


def _merge_epochs(a: dict, b: dict) -> dict:
    """GNSS epoch dicts a and b as one, in time order."""
    if len(a.get("t_s", ())) == 0:
        return b
    order = np.argsort(np.concatenate([a["t_s"], b["t_s"]]), kind="stable")
    return {k: np.concatenate([np.asarray(a[k]), np.asarray(b[k])])[order] for k in b}


def calibration_epoch(truth, cal: dict, gnss: dict, seed: int) -> dict | None:
    """For a [calibration] with source "gnss" and a scenario without GNSS (no epoch after
    at_s): the one epoch of the calibration's own GNSS preset (cal["gnss"]) that follows
    the command, i.e. the first on its grid after at_s. None otherwise."""
    if cal is None or cal["source"] != "gnss":
        return None
    if np.any(np.asarray(gnss.get("t_s", ())) > cal["at_s"]):
        return None
    name = cal.get("gnss", "standalone")
    if name not in sensors.GNSS_PRESETS or not sensors.GNSS_PRESETS[name].enabled:
        raise SystemExit(f"[calibration] gnss: no GNSS preset '{name}' that has epochs")
    ep = sensors.gnss_epochs(truth, sensors.GNSS_PRESETS[name], seed)
    after = np.nonzero(ep["t_s"] > cal["at_s"])[0]
    if len(after) == 0:
        raise SystemExit(f"[calibration] at {cal['at_s']} s: no GNSS epoch after it")
    return _one_epoch(ep, int(after[0]))


def calibration_frames(sender, truth, cal: dict) -> list:
    """The one-point calibration request of a scenario's [calibration] as (t, order, msg):
    at at_s (after that instant's IMU sample and wheel speeds) CMD_KnownPosition with the
    true position at at_s, then CMD_Control CalibrateHere (5); or for source "gnss"
    CMD_Control CalibrateAtGnss (6) alone (the next GNSS epoch is the point)."""
    t = float(cal["at_s"])
    if not 0.0 < t <= float(truth.t_s[-1]):
        raise ValueError(f"[calibration] at_s {t} outside the drive (0, {truth.t_s[-1]:.1f}] s")
    lat = math.degrees(float(np.interp(t, truth.t_s, truth.lat_rad)))
    lon = math.degrees(float(np.interp(t, truth.t_s, np.unwrap(truth.lon_rad))))
    lon = (lon + 180.0) % 360.0 - 180.0
    h = float(np.interp(t, truth.t_s, truth.h_m))
    out = []
    if cal["source"] == "known_position":
        out.append((t, 9, sender.encode("CMD_KnownPosition", {"Latitude": lat, "Longitude": lon},
                                        t)))
        command = 5
    else:
        command = 6
    out.append((t, 10, sender.encode("CMD_Control", {"Command": command, "HeadingValid": 0,
                                                     "Heading": 0.0, "Height": h}, t)))
    return out


def frames(truth, dtheta, dv, wheels, gnss, db, initial_attitude=False, heading_deg=None,
           calibration=None, car=None, power_on_s=None, reset_s=(), heading_valid=True,
           raw=()):
    """Every input frame of the drive as (t_s, order, can.Message), unsorted. With
    initial_attitude, a CMD_InitialAttitude with the true roll and pitch follows the
    initialization commands: a perfect start, no levelling. heading_deg: the Heading of
    SetInitialPosition (default: the car's true heading; scenario.heading_command_deg).
    calibration: a scenario's [calibration] table (calibration_frames), with an optional
    "gnss_epoch" (calibration_epoch) sent among the GNSS epochs. car: a vehicle profile's
    tools.vehicle.CarEncoder: the wheel speeds (and gear) in the car's own messages instead
    of navecu's WheelSpeeds. power_on_s: the ECU powers on at this time of the drive (maybe
    driving): no frame before it and no initialization commands (the firmware starts on
    its own: the in-motion alignment, or GNSS alone). reset_s: times of the drive at which a
    CMD_Control Reset is sent (maybe driving; no command follows: the firmware starts again
    on its own). heading_valid False: the SetInitialPosition says HeadingValid 0 (the
    heading then comes from the in-motion alignment)."""
    sender = nc.E2ESender(db)
    out = []
    lat0, lon0 = math.degrees(truth.lat_rad[0]), math.degrees(truth.lon_rad[0])
    hdg0 = (scenario.heading_command_deg(truth.heading_rad[0]) if heading_deg is None
            else heading_deg)
    if power_on_s is None:
        out.append((0.0, 0, sender.encode("CMD_KnownPosition",
                                          {"Latitude": lat0, "Longitude": lon0}, 0.0)))
        out.append((0.0, 1, sender.encode("CMD_Control", {"Command": 2,
                                                          "HeadingValid": int(heading_valid),
                                                          "Heading": hdg0,
                                                          "Height": float(truth.h_m[0])}, 0.0)))
    if initial_attitude and power_on_s is None:
        out.append((0.0, 1, sender.encode("CMD_InitialAttitude", {
            "InitRoll": float(truth.roll_rad[0]), "InitPitch": float(truth.pitch_rad[0])}, 0.0)))
    quant = nc.ImuQuantizer()
    for k in range(1, len(truth.t_s)):
        t = float(truth.t_s[k])
        rate, accel = quant.signals(dtheta[k], dv[k])
        r, a = sender.encode_imu_pair(rate, accel, t)
        out.append((t, 2, r))
        out.append((t, 3, a))
    if calibration is not None:
        out.extend(calibration_frames(sender, truth, calibration))
        if calibration.get("gnss_epoch") is not None:
            gnss = _merge_epochs(gnss, calibration["gnss_epoch"])
    w_t, w_v = wheels
    for t, v in zip(w_t, np.clip(w_v, -81.9, 81.9)):
        if car is not None:
            out.extend((float(t), 4, m) for m in car.wheels(float(t), [float(x) for x in v]))
            continue
        out.append((float(t), 4, sender.encode("WheelSpeeds", {
            "WheelSpeedFL": float(v[0]), "WheelSpeedFR": float(v[1]),
            "WheelSpeedRL": float(v[2]), "WheelSpeedRR": float(v[3])}, float(t))))
    for i in range(len(gnss["t_s"])):
        t = float(gnss["t_s"][i])
        epoch = sender.next_counter("GNSS_Velocity")
        v = gnss["v_enu_mps"][i]
        out.append((t, 5, sender.encode("GNSS_Position", {
            "Latitude": math.degrees(gnss["lat_rad"][i]),
            "Longitude": math.degrees(gnss["lon_rad"][i])}, t)))
        out.append((t, 6, sender.encode("GNSS_Velocity", {
            "VelEast": float(v[0]), "VelNorth": float(v[1]), "VelUp": float(v[2]),
            "SpeedAccuracy": float(min(gnss["sacc_mps"][i], 1.5))}, t)))
        out.append((t, 7, sender.encode("GNSS_Height", {
            "Height": float(gnss["h_m"][i]), "GnssEpoch": epoch}, t)))
        out.append((t, 7, sender.encode("GNSS_Time", {"GpsWeek": GPS_WEEK, "GnssEpoch": epoch}, t)))
        out.append((t, 8, sender.encode("GNSS_Status", {
            "FixType": int(gnss["fix_type"][i]), "NumSatellites": int(gnss["num_sats"][i]),
            "HorizAccuracy": float(min(gnss["hacc_m"][i], 102.3)),
            "VertAccuracy": float(min(gnss["vacc_m"][i], 102.3)), "GnssEpoch": epoch,
            "TimeOfWeek": round((GPS_TOW0_S + float(gnss["t_meas_s"][i])) % 604800.0, 3)}, t)))
    for i, (t, ep) in enumerate(raw):
        out.extend((float(t), 9, m) for m in gnss_raw.encode_epoch(
            sender, ep, i % (nc.E2E_COUNTER_MAX + 1), float(t)))
    for t in reset_s:
        out.append((float(t), 1, sender.encode("CMD_Control", {"Command": 1, "HeadingValid": 0, "Heading": 0.0, "Height": 0.0}, float(t))))
    if power_on_s is not None:
        out = [x for x in out if x[0] >= power_on_s]
    return out


def firmware_args(imu: "sensors.ImuSpec", gnss: "sensors.GnssSpec",
                  odo: "sensors.OdoSpec | None" = None) -> list:
    """navecu options describing this drive's sensors, as an ECU is configured for the IMU
    and receiver it is installed with (docs/kalman.md): the IMU's noise, turn-on bias and
    in-run instability with its correlation time, the receiver's latency, error correlation
    time and white part. Mounting, odometer scale and the errors' realisation stay unknown
    to the firmware. With odo, the wheel speeds' latency (an ABS module's data sheet
    figure)."""
    rad_dph = math.pi / 180.0 / 3600.0
    g = sensors.G0_MPS2
    if imu.accel_bias_corr_time_s != imu.gyro_bias_corr_time_s:
        # the firmware has one correlation time for the z gyro's and the forward
        # accelerometer's in-run states (gyro_bias_corr_time_s, docs/kalman.md)
        raise ValueError(f"the IMU's accelerometer and gyro in-run correlation times differ "
                         f"({imu.accel_bias_corr_time_s:g} s, {imu.gyro_bias_corr_time_s:g} s): "
                         f"the firmware is configured with one")
    args = ["--gyro-arw-dpsh", f"{max(imu.gyro_arw_deg_per_rth, 1e-4):.6g}",
            "--gyro-bias-dph", f"{max(imu.gyro_bias_turnon_rps / rad_dph, 1e-3):.6g}",
            "--accel-bias-mg", f"{max(imu.accel_bias_turnon_mps2 / g * 1e3, 1e-3):.6g}",
            "--gyro-instability-dph", f"{max(imu.gyro_bias_instability_rps / rad_dph, 1e-4):.6g}",
            "--gyro-bias-corr-time-s", f"{imu.gyro_bias_corr_time_s:.6g}",
            "--accel-instability-mg",
            f"{max(imu.accel_bias_instability_mps2 / g * 1e3, 1e-4):.6g}",
            # the forward axis's own (the simulator draws every axis alike)
            "--accel-fwd-instability-mg",
            f"{max(imu.accel_bias_instability_mps2 / g * 1e3, 1e-4):.6g}",
            "--gyro-scale-ppm", f"{max(imu.gyro_scale_factor_ppm, 0.1):.6g}",
            # the simulated car measures its speed at the IMU (no lever arm), and the
            # installation is measured: to a tape measure's 0.1 m
            "--odo-lever-sigma-m", "0.1"]
    if odo is not None:
        args += ["--odo-latency-ms", f"{odo.latency_s * 1e3:.6g}"]
    if gnss.enabled:
        args += ["--gnss-latency-ms", f"{gnss.latency_s * 1e3:.6g}",
                 "--gnss-corr-s", f"{min(gnss.pos_gm_corr_time_s, 600.0):.6g}"]
        if gnss.pos_sigma_h_m > 0.0:
            # the receiver's white part of its per-axis sigma, as its spec would give it
            args += ["--gnss-white-ratio",
                     f"{min(max(gnss.pos_white_h_m / gnss.pos_sigma_h_m, 0.05), 1.0):.3g}"]
    return args


def save_truth(truth, out: Path):
    np.savez_compressed(out / "truth.npz", t_s=truth.t_s, lat_rad=truth.lat_rad,
                        lon_rad=truth.lon_rad, h_m=truth.h_m, heading_rad=truth.heading_rad,
                        dist_m=truth.dist_m,
                        outages=np.array([[o[0], o[1]] for o in truth.outages]).reshape(-1, 2))
    truth.to_csv(out / "truth.csv")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default="default", help="name in tools/sim/scenarios or a .toml")
    ap.add_argument("--imu", default=None, help="IMU preset (default: the scenario's, else mid-grade)")
    ap.add_argument("--gnss", default=None, help="GNSS preset (default: the scenario's, else standalone)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--mount", choices=("scenario", "configured", "automatic", "none"),
                    default="scenario",
                    help="the firmware's IMU mounting: as the scenario's [imu_mounting] says, "
                         "configured (--imu-mount-deg, the true angles), automatic "
                         "(--imu-mount-source automatic), none (told nothing)")
    ap.add_argument("--fw-arg", action="append", default=[], metavar="ARG",
                    help="one more firmware option (repeat), e.g. --fw-arg=--mount-est-sigma-deg --fw-arg=0.5")
    ap.add_argument("--imu-rate-hz", type=int, default=100)
    ap.add_argument("--out", default=None, help="output folder (default out/sim/NAME)")
    ap.add_argument("--navecu", default=None,
                    help="the firmware (default build/host/navecu, with --vehicle NAME "
                         "build/host/navecu-NAME)")
    ap.add_argument("--vehicle", default=None,
                    help="vehicle profile of the firmware build (vehicles/NAME.toml): its "
                         "identifiers, and its car's own wheel-speed and gear frames")
    ap.add_argument("--bus", default=None, metavar="IFACE",
                    help="run the firmware live on this SocketCAN bus (vcan0: inside "
                         "tools/vcan/with_vcan.sh), the log replayed with can_replay --fastest "
                         "and its output recorded to nav.log; also runs --can-log into "
                         "nav_file.log and checks that the two are identical "
                         "(tools/vcan/bus_run.py)")
    ap.add_argument("--power-on-s", type=float, default=None, metavar="T",
                    help="the ECU powers on at T s into the drive (maybe driving): no frame "
                         "before T and no initialization commands; report.json's power_on "
                         "gives the time to the first output and the errors 30 and 60 s on")
    ap.add_argument("--no-heading", action="store_true",
                    help="the SetInitialPosition at the start says HeadingValid 0")
    ap.add_argument("--reset-s", type=float, action="append", default=[], metavar="T",
                    help="send CMD_Control Reset at T s into the drive (repeat for more); "
                         "report.json's resets give, for each, the time to the first output "
                         "after it and the errors 30 and 60 s on")
    a = ap.parse_args(argv)
    car = None
    if a.vehicle not in (None, "native"):
        from tools import vehicle
        profile = vehicle.load(a.vehicle)
        car = None if profile.native_wheels else vehicle.CarEncoder(profile)
    nc.select_vehicle(a.vehicle)
    if a.navecu is None:
        suffix = "" if a.vehicle in (None, "native") else f"-{a.vehicle}"
        a.navecu = str(ROOT / "build" / "host" / f"navecu{suffix}")

    scen = scenario.load(a.scenario)
    name = scen.get("name", Path(a.scenario).stem)
    imu_name, gnss_name = scenario.preset_names(scen, a.imu, a.gnss)
    if imu_name not in sensors.PRESETS:
        raise SystemExit(f"no IMU preset '{imu_name}' (known: {', '.join(sensors.PRESETS)})")
    if gnss_name not in sensors.GNSS_PRESETS:
        raise SystemExit(f"no GNSS preset '{gnss_name}' (known: {', '.join(sensors.GNSS_PRESETS)})")
    out = Path(a.out) if a.out else ROOT / "out" / "sim" / name
    out.mkdir(parents=True, exist_ok=True)
    st = Stages(5)

    st.start(f"trajectory '{name}'")
    truth = trajectory.generate(scen, a.imu_rate_hz)
    st.done(f"{truth.t_s[-1] / 60:.1f} min, {truth.dist_m[-1] / 1000:.2f} km")

    st.start(f"sensors: IMU {imu_name}, GNSS {gnss_name}, odometer")
    # one seed per model, distinct across --seed values
    imu_spec, odo = scenario.sensor_specs(scen, imu_name, truth.vehicle)
    imu_seed, odo_seed, gnss_seed = sensors.drive_seeds(a.seed)
    dtheta, dv = sensors.apply_imu(truth, imu_spec, imu_seed)
    wheels = sensors.wheel_speeds(truth, odo, odo_seed)
    gnss = sensors.gnss_epochs(truth, sensors.GNSS_PRESETS[gnss_name], gnss_seed)
    fw_args = firmware_args(sensors.PRESETS[imu_name], sensors.GNSS_PRESETS[gnss_name], odo)
    mnt = scen["imu_mounting"]
    mount = a.mount
    if mount == "scenario":
        mount = ("configured" if mnt.get("configured") else
                 "automatic" if mnt.get("automatic") else "none")
    if mount == "configured":  # the installer configured the IMU's mounting
        fw_args += ["--imu-mount-deg",
                    f"{mnt['roll_deg']:.6g},{mnt['pitch_deg']:.6g},{mnt['yaw_deg']:.6g}"]
    elif mount == "automatic":  # navecu estimates it (firmware/app/mount_est.h)
        fw_args += ["--imu-mount-source", "automatic"]
    fw_args += list(a.fw_arg)
    fault_log = []
    if scen.get("gnss_faults"):
        gnss, fault_log = sensors.apply_gnss_faults(gnss, scen["gnss_faults"])
    cal = scen.get("calibration")
    if cal is not None:
        cal = dict(cal, gnss_epoch=calibration_epoch(truth, cal, gnss, gnss_seed))
    st.done(f"{len(gnss['t_s'])} GNSS epochs"
            + (f", {len(fault_log)} GNSS faults" if fault_log else "")
            + (f", calibration at {cal['at_s']:g} s ({cal['source']})" if cal else ""))

    st.start("CAN encoding")
    db = nc.load_db()
    hdg_cmd = scenario.heading_command_deg(truth.heading_rad[0], scen)
    raw = []
    if scen.get("gnss_raw", {}).get("enabled"):
        from tools.sim import receiver
        spec = receiver.spec_of(scen["gnss_raw"])
        dark = receiver.dark_outages(truth, spec)   # a tunnel has no raw epoch, a canyon has
        raw = [(t, ep) for t, ep, _ in receiver.simulate(truth, spec, receiver.raw_seed(a.seed),
                                                         t0_gps_s=GPS_TOW0_S, outages=dark)]
    fr = frames(truth, dtheta, dv, wheels, gnss, db, heading_deg=hdg_cmd, calibration=cal,
                car=car, power_on_s=a.power_on_s, reset_s=a.reset_s,
                heading_valid=not a.no_heading, raw=raw)
    fr.sort(key=lambda x: (x[0], x[1]))
    can_in = out / "can_in.log"
    n = nc.write_candump(can_in, (m for _, _, m in fr))
    save_truth(truth, out)
    st.done(f"{n} frames -> {can_in.relative_to(ROOT) if can_in.is_relative_to(ROOT) else can_in}")

    nav_log = out / "nav.log"
    if a.bus:
        from tools.vcan import bus_run
        st.start(f"firmware live on {a.bus} (navecu --can, can_replay --fastest) and --can-log")
        try:
            b = bus_run.run(a.navecu, can_in, out, a.bus, a.imu_rate_hz, fw_args)
        except bus_run.BusRunError as e:
            print()
            bar = "*" * 78
            print(f"{bar}\nFAILED: the firmware could not run on {a.bus}: {e}\n"
                  + ("  (no vcan possible here; Debian: apt-get install user-mode-linux kmod, "
                     "or make vcan)\n" if e.code == 2 else "") + bar, file=sys.stderr)
            return 1
        (out / "navecu.txt").write_text(f"{b['firmware_summary']}\n\n--can-log run "
                                        f"(nav_file.log):\n{b['file_summary']}\n")
        (out / "bus_run.json").write_text(json.dumps(b, indent=2))
        res = subprocess.CompletedProcess(a.navecu, 0, "", b["firmware_summary"])
        st.done(b["firmware_summary"].splitlines()[0].replace("navecu: ", ""))
        for line in bus_run.describe(b):
            print(f"      {line}")
        if not (b["identical"] and bus_run.lossless(b)):
            print(f"FAILED: the run on {a.bus} is not the --can-log run "
                  f"({out / 'bus_run.json'})", file=sys.stderr)
            return 1
    else:
        st.start(f"firmware ({Path(a.navecu).name} --can-log)")
        res = st.firmware([a.navecu, "--can-log", can_in, "--out", nav_log,
                           "--imu-rate-hz", str(a.imu_rate_hz)] + fw_args, out)
        if res.returncode != 0:
            return 1

    st.start("report")
    # the firmware's times count from its power-on: the log's timestamps are the drive's
    nav = report.read_nav_log(nav_log, wraps_from_log=not a.bus,
                              log_t0_s=a.power_on_s if a.power_on_s is not None else 0.0)
    if a.power_on_s is not None:
        for cols in nav.values():
            cols["t_s"] = cols["t_s"] + a.power_on_s
    truth_r = {"t_s": truth.t_s, "lat_rad": truth.lat_rad, "lon_rad": truth.lon_rad,
               "heading_rad": truth.heading_rad, "dist_m": truth.dist_m, "h_m": truth.h_m}
    rep, series = report.compute(truth_r, nav, truth.outages)
    rep.update({"scenario": name, "imu": imu_name, "gnss": gnss_name, "seed": a.seed,
                "imu_rate_hz": a.imu_rate_hz, "navecu_summary": res.stderr.strip().splitlines(),
                "navecu_binary": report.navecu_binary(a.navecu)})
    rep["truth"] = scenario.scenario_truths(scen, truth.heading_rad[0], imu_spec, odo, hdg_cmd)
    cal_log = report.read_calibration_log(nav_log)
    rep["calibration"] = (report.calibration_report(truth_r, series, cal_log, cal, rep["truth"])
                          if cal is not None else None)
    t_gnss = report.gnss_driving_reached(truth_r, report.FILTER_CAL_GNSS_DRIVING_S,
                                         rep.get("navigation_start_s", 0.0),
                                         gnss_t=gnss["t_s"][gnss["valid"]])
    rep["filter_calibration"] = report.filter_calibration(cal_log, rep["truth"], t_gnss)
    rep["gnss_faults"] = (report.gnss_fault_report(series, nav.get("NAV_Status"), fault_log,
                                                   truth.outages) if fault_log else None)
    if a.power_on_s is not None:
        rep["power_on"] = report.power_on_report(truth_r, series, a.power_on_s)
    rep["resets"] = [report.power_on_report(truth_r, series, t_r, restart=True)
                     for t_r in sorted(a.reset_s)]
    events = ([a.power_on_s] if a.power_on_s is not None
              else [rep.get("navigation_start_s", 0.0)]) + sorted(a.reset_s)
    rep["transitions"] = report.transition_check(series, nav, events)
    (out / "report.json").write_text(json.dumps(rep, indent=2))
    truth_d = {"t_s": truth.t_s, "lat_rad": truth.lat_rad, "lon_rad": truth.lon_rad}
    pngs = report.plot(truth_d, series, gnss, truth.outages, out, f"{name} ({imu_name} IMU)",
                       marks=report.calibration_marks(rep["calibration"])
                       + report.fault_marks(rep["gnss_faults"]))
    st.done(f"{out / 'report.json'} and {len(pngs)} plots")
    print()
    print(report.summary_table(rep))
    if rep.get("power_on"):
        print(f"power-on at {a.power_on_s:g} s: {json.dumps(rep['power_on'])}")
    for t_r, r in zip(sorted(a.reset_s), rep["resets"]):
        print(f"reset at {t_r:g} s: {json.dumps(r)}")
    print(report.transition_line(rep["transitions"]))
    if "GnssIns" not in (rep.get("modes_seen") or {}):
        print("note: the firmware never reported Mode GnssIns: no GNSS fusion in this run "
              "(the Kalman filter, #7).")
    print(f"plots: {', '.join(str(p) for p in pngs)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
