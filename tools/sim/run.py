"""Simulate a drive, run the firmware on it, and report its accuracy (`make sim`).

    python -m tools.sim.run [--scenario default] [--imu mid-grade] [--gnss standalone]
                            [--seed 1] [--out out/sim/NAME] [--navecu build/host/navecu]

Stages: the scenario's exact trajectory (tools/sim/trajectory.py); sensor data from the
error models (tools/sim/sensors.py); everything encoded through the project's DBC into a
candump log (tools/navecu_can.py: E2E counters and CRCs, IMU remainder carry); the host
firmware run over it (build/host/navecu --can-log); the report (tools/sim/report.py):
report.json and PNG plots in the output folder, a summary on stdout.

Initialization as a driver would do it: at t = 0 the vehicle stands still and receives
CMD_KnownPosition and CMD_Control SetInitialPosition (true position, height and heading);
the firmware levels for 30 s and navigates from then on.
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

from tools import navecu_can as nc
from tools.sim import report, sensors, trajectory

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = Path(__file__).resolve().parent / "scenarios"
GPS_TOW0_S = 302400.0  # GNSS time of week at t = 0 (Wednesday noon)


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


def scenario_path(name: str) -> Path:
    p = Path(name)
    if p.suffix == ".toml" and p.exists():
        return p
    p = SCENARIOS / f"{name}.toml"
    if not p.exists():
        known = ", ".join(sorted(q.stem for q in SCENARIOS.glob("*.toml")))
        raise SystemExit(f"no scenario '{name}' (known: {known})")
    return p


def frames(truth, dtheta, dv, wheels, gnss, db, initial_attitude=False):
    """Every input frame of the drive as (t_s, order, can.Message), unsorted. With
    initial_attitude, a CMD_InitialAttitude with the true roll and pitch follows the
    initialization commands: a perfect start, no levelling."""
    sender = nc.E2ESender(db)
    out = []
    lat0, lon0 = math.degrees(truth.lat_rad[0]), math.degrees(truth.lon_rad[0])
    hdg0 = (round(math.degrees(truth.heading_rad[0]) % 360.0 * 100.0) % 36000) / 100.0
    out.append((0.0, 0, sender.encode("CMD_KnownPosition",
                                      {"Latitude": lat0, "Longitude": lon0}, 0.0)))
    out.append((0.0, 1, sender.encode("CMD_Control", {"Command": 2, "HeadingValid": 1,
                                                      "Heading": hdg0,
                                                      "Height": float(truth.h_m[0])}, 0.0)))
    if initial_attitude:
        out.append((0.0, 1, sender.encode("CMD_InitialAttitude", {
            "InitRoll": float(truth.roll_rad[0]), "InitPitch": float(truth.pitch_rad[0])}, 0.0)))
    quant = nc.ImuQuantizer()
    for k in range(1, len(truth.t_s)):
        t = float(truth.t_s[k])
        rate, accel = quant.signals(dtheta[k], dv[k])
        r, a = sender.encode_imu_pair(rate, accel, t)
        out.append((t, 2, r))
        out.append((t, 3, a))
    w_t, w_v = wheels
    for t, v in zip(w_t, np.clip(w_v, -81.9, 81.9)):
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
        out.append((t, 8, sender.encode("GNSS_Status", {
            "FixType": int(gnss["fix_type"][i]), "NumSatellites": int(gnss["num_sats"][i]),
            "HorizAccuracy": float(min(gnss["hacc_m"][i], 102.3)),
            "VertAccuracy": float(min(gnss["vacc_m"][i], 102.3)), "GnssEpoch": epoch,
            "TimeOfWeek": round((GPS_TOW0_S + float(gnss["t_meas_s"][i])) % 604800.0, 3)}, t)))
    return out


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
    ap.add_argument("--imu-rate-hz", type=int, default=100)
    ap.add_argument("--out", default=None, help="output folder (default out/sim/NAME)")
    ap.add_argument("--navecu", default=str(ROOT / "build" / "host" / "navecu"))
    a = ap.parse_args(argv)

    scen = trajectory.load_scenario(scenario_path(a.scenario))
    name = scen.get("name", Path(a.scenario).stem)
    sim_cfg = scen.get("sim", {})
    imu_name = a.imu or sim_cfg.get("imu", "mid-grade")
    gnss_name = a.gnss or sim_cfg.get("gnss", "standalone")
    if imu_name not in sensors.PRESETS:
        raise SystemExit(f"no IMU preset '{imu_name}' (known: {', '.join(sensors.PRESETS)})")
    out = Path(a.out) if a.out else ROOT / "out" / "sim" / name
    out.mkdir(parents=True, exist_ok=True)
    st = Stages(5)

    st.start(f"trajectory '{name}'")
    truth = trajectory.generate(scen, a.imu_rate_hz)
    st.done(f"{truth.t_s[-1] / 60:.1f} min, {truth.dist_m[-1] / 1000:.2f} km")

    st.start(f"sensors: IMU {imu_name}, GNSS {gnss_name}, odometer")
    # one seed per model, distinct across --seed values
    dtheta, dv = sensors.apply_imu(truth, sensors.PRESETS[imu_name], 3 * a.seed)
    odo = sensors.OdoSpec(track_m=truth.vehicle["track_m"],
                          wheelbase_m=truth.vehicle["wheelbase_m"])
    wheels = sensors.wheel_speeds(truth, odo, 3 * a.seed + 1)
    gnss = sensors.gnss_epochs(truth, sensors.GNSS_PRESETS[gnss_name], 3 * a.seed + 2)
    st.done(f"{len(gnss['t_s'])} GNSS epochs")

    st.start("CAN encoding")
    db = nc.load_db()
    fr = frames(truth, dtheta, dv, wheels, gnss, db)
    fr.sort(key=lambda x: (x[0], x[1]))
    can_in = out / "can_in.log"
    n = nc.write_candump(can_in, (m for _, _, m in fr))
    save_truth(truth, out)
    st.done(f"{n} frames -> {can_in.relative_to(ROOT) if can_in.is_relative_to(ROOT) else can_in}")

    st.start("firmware (build/host/navecu --can-log)")
    nav_log = out / "nav.log"
    res = subprocess.run([a.navecu, "--can-log", str(can_in), "--out", str(nav_log),
                          "--imu-rate-hz", str(a.imu_rate_hz)], capture_output=True, text=True)
    (out / "navecu.txt").write_text(res.stderr)
    if res.returncode != 0:
        print()
        print(res.stderr, file=sys.stderr)
        return 1
    st.done(res.stderr.strip().splitlines()[0].replace("navecu: ", ""))

    st.start("report")
    nav = report.read_nav_log(nav_log)
    rep, series = report.compute(
        {"t_s": truth.t_s, "lat_rad": truth.lat_rad, "lon_rad": truth.lon_rad,
         "heading_rad": truth.heading_rad, "dist_m": truth.dist_m}, nav, truth.outages)
    rep.update({"scenario": name, "imu": imu_name, "gnss": gnss_name, "seed": a.seed,
                "imu_rate_hz": a.imu_rate_hz, "navecu_summary": res.stderr.strip().splitlines()})
    (out / "report.json").write_text(json.dumps(rep, indent=2))
    truth_d = {"t_s": truth.t_s, "lat_rad": truth.lat_rad, "lon_rad": truth.lon_rad}
    pngs = report.plot(truth_d, series, gnss, truth.outages, out, f"{name} ({imu_name} IMU)")
    st.done(f"{out / 'report.json'} and {len(pngs)} plots")
    print()
    print(report.summary_table(rep))
    print("note: the firmware navigates free-inertially after initialization; GNSS and odometer")
    print("      fusion arrive with the odometer and Kalman-filter issues (#6, #7).")
    print(f"plots: {', '.join(str(p) for p in pngs)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
