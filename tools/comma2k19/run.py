"""The 2017 RAV4's real bus through navecu built for that car, against the reference pose.

    python -m tools.comma2k19.run [--data data/comma2k19-rav4] [--vehicle toyota_rav4_2017]
        [--outage 28-58] [--out out/drive-rav4] [--navecu build/host/navecu-toyota_rav4_2017]
        [--imu-time grid|stamped]

--imu-time stamped sends the device's own samples with their IMU_Time stamps (no
resampling, convert.py) and runs the firmware with --imu-time stamped at the device's
nominal rate (convert.STAMPED_RATE_HZ); grid (the default) resamples to IMU_RATE_HZ.

Four runs of the same firmware on the same IMU and GNSS frames (tools/comma2k19/convert.py
says what they carry and what the run is given besides the recording):

- **bus**: with every frame of the car's recorded buses (car_bus.log, 2,258 frames/s);
- **quiet**: with only the car frames the profile reads (WHEEL_SPEEDS, GEAR_PACKET,
  KINEMATICS): the bus run's outputs must equal it, NAV_Status page 1's CntForeign aside,
  and its HealthFlags too: the car's traffic raises nothing;
- **bus-outage** and **no-car-outage**: a GNSS outage (--outage, default the last 30 s of
  fixes), with the car's bus and without any car frame: what the odometer from 0x0AA
  brings.

The outputs are decoded with the DBC the build generated for the profile
(build/vehicle/NAME/navecu.dbc); their time is NAV_Height's TimeOfValidity (IMU time since
the first sample), the reference (20 Hz, device pose; comma's post-processed INS/GNSS/vision
solution) interpolated to it. report.json and plots in --out, a summary on stdout:
horizontal error (rms, p95, max) of each run, the outage's end and largest errors, the
u-blox fixes' own error against the reference, the car messages the firmware read (its
summary), the odometer scale the filter estimated beside the wheels' distance over the
reference's (cantools on 0x0AA), the foreign-frame count, the HealthFlags each run raised,
and NAV_Time against the GNSS time of each output set.
"""
from __future__ import annotations

import argparse
import json
import math
import re
import shlex
import sys
from pathlib import Path

import can
import numpy as np

from tools import navecu_can as nc
from tools import vehicle
from tools.comma2k19 import convert
from tools.data_csv import read_csv
from tools.geodesy import horizontal_distance_m, horizontal_error_m
from tools.sim import report
from tools.sim.run import Stages

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_OUTAGE = "28-58"
NAV_TIME_SETTLED_S = 10.0
# The device's IMU, configured as an ECU is for a consumer MEMS part: the consumer preset
# (firmware/app/params.toml: BMI160-datasheet class figures, not fitted to this drive)
IMU_OPTIONS = ["--imu-preset", "consumer"]
# The u-blox fixes of the log carry no accuracy and no vertical velocity: declared, with the
# receiver class's datasheet figures (u-blox NEO-M8, UBX-15031086: horizontal 2.5 m CEP =
# 1.1774 sigma per axis, given as the 68.27 % radius, 1.5152 sigma: 3.2 m; vertical about
# twice the horizontal sigma: 4.2 m; velocity 0.05 m/s, 0.2 m/s taken for a car's antenna)
GNSS_OPTIONS = ["--gnss-accuracy", "declared", "--gnss-hacc-m", "3.2", "--gnss-vacc-m", "4.2",
                "--gnss-sacc-mps", "0.2", "--gnss-vel-up", "none"]
RATES = ["--imu-rate-hz", str(convert.IMU_RATE_HZ), "--nav-rate-hz", "10",
         "--status-rate-hz", "10", "--dyn-rate-hz", "10"]


def rate_options(imu_time: str) -> list:
    """The firmware's rate options for the IMU input variant (grid: RATES)."""
    if imu_time == "grid":
        return list(RATES)
    return ["--imu-time", "stamped", "--imu-rate-hz", str(convert.STAMPED_RATE_HZ),
            *RATES[2:]]


def firmware_options(meta: dict, imu_time: str = "grid", mount: str = "configured") -> list:
    """The firmware's options for a converted segment (meta: convert.build's): its rates,
    the fixes' latency, the IMU's and receiver's declared figures, and the mounting,
    configured from the reference (mount configured) or estimated (automatic)."""
    opts = [*rate_options(imu_time), "--gnss-latency-ms", str(meta["gnss_latency_ms"]),
            *IMU_OPTIONS, *GNSS_OPTIONS]
    if mount == "configured":
        return opts + ["--imu-mount-deg",
                       ",".join(f"{x:g}" for x in meta["imu"]["imu_mount_deg_312"])]
    return opts + ["--imu-mount-source", "automatic"]


def reference_truth(data: Path, t0: float) -> dict:
    """reference.csv on the run's time base in the simulator's truth layout (report.compute):
    t_s, lat/lon in rad, the car's heading (direction of travel), distance along it."""
    r = read_csv(data / "reference.csv")
    ds = horizontal_distance_m(r["lat_deg"][:-1], r["lon_deg"][:-1], r["lat_deg"][1:],
                               r["lon_deg"][1:])
    return {"t_s": r["t_s"] - t0, "lat_rad": np.radians(r["lat_deg"]),
            "lon_rad": np.radians(r["lon_deg"]),
            "heading_rad": np.radians(r["car_heading_deg"]),
            "gps_tow_s": r["gps_tow_s"], "dist_m": np.concatenate(([0.0], np.cumsum(ds)))}


def wheel_distance_ratio(data: Path, prof, t0: float, t1: float, truth: dict) -> dict:
    """The rear wheels' distance (cantools on the car's WHEEL_SPEEDS, rectangle rule) over
    the reference's in [t0, t1] (segment clock): the odometer scale the filter should find."""
    wheels = next(r for r in prof.reads if r.role == "wheels")
    rl, rr = wheels.signals[2].name, wheels.signals[3].name
    t, v = [], []
    with can.LogReader(str(data / "car_bus.log")) as reader:
        for msg in reader:
            if msg.arbitration_id == wheels.message.frame_id and msg.channel == "can0":
                d = wheels.message.decode(bytes(msg.data), decode_choices=False)
                t.append(float(msg.timestamp))
                v.append(0.5 * (d[rl] + d[rr]) * prof.speed_factor)
    t, v = np.asarray(t), np.asarray(v)
    sel = (t >= t0) & (t <= t1)
    dist_w = float(np.sum(v[sel][1:] * np.diff(t[sel])))
    a, b = np.interp([t[sel][0] - t0, t[sel][-1] - t0], truth["t_s"], truth["dist_m"])
    return {"wheels_m": dist_w, "reference_m": float(b - a),
            "scale_error": dist_w / float(b - a) - 1.0}


def gnss_error(data: Path, truth: dict, t0: float) -> dict:
    """The u-blox fixes against the reference at their own time of validity."""
    g = read_csv(data / "gnss_ublox.csv")
    t = g["t_fix_s"] - t0
    sel = (t >= truth["t_s"][0]) & (t <= truth["t_s"][-1])
    lat, lon, _ = report._interp_truth(truth, t[sel])
    e, _, _ = horizontal_error_m(lat, lon, np.radians(g["lat_deg"][sel]),
                                 np.radians(g["lon_deg"][sel]))
    return report._stats(e)


_SUMMARY = {
    "car_read": re.compile(r"wheel speeds (\d+), gear (\d+), yaw rate (\d+)"),
    "foreign": re.compile(r"foreign frames \(not read, not refused\): (\d+)"),
    "odo_scale": re.compile(r"odometer scale (-?\d+\.\d+)"),  # navecu's "filter:" line
    "rejected": re.compile(r"rejected: (.*)$", re.M),
}


def parse_summary(text: str) -> dict:
    out = {}
    m = _SUMMARY["car_read"].search(text)
    if m:
        out["car_messages_read"] = dict(zip(("wheel_speeds", "gear", "yaw_rate"),
                                            map(int, m.groups())))
    m = _SUMMARY["foreign"].search(text)
    out["foreign_frames"] = int(m.group(1)) if m else None
    m = _SUMMARY["odo_scale"].search(text)
    out["filter_odometer_scale_error"] = float(m.group(1)) if m else None
    m = _SUMMARY["rejected"].search(text)
    out["rejected"] = m.group(1) if m else None
    return out


def health_flags_raised(status, db) -> list:
    """Names of the HealthFlags bits set in any NAV_Status page-0 frame."""
    _, flags = report.status_page(status, 0, "HealthFlags")
    seen = 0
    for f in flags.astype(int):
        seen |= int(f)
    return [name for bit, (name, _) in sorted(nc.health_bits(db).items()) if seen >> bit & 1]


def nav_time_check(nav: dict, meta: dict) -> dict:
    """NAV_Time (TimeOfWeek, us) of each output set against the GNSS time of its
    TimeOfValidity (t0's GPS time + the IMU time)."""
    nt = nav.get("NAV_Time")
    if nt is None or not len(nt["t_s"]):
        return {"frames": 0}
    ok = np.isfinite(nt["t_s"])
    expect = (meta["t0_gps_tow_s"] + nt["t_s"][ok]) % 604800.0
    d_us = (nt["TimeOfWeek"][ok] - expect) * 1e6
    weeks = sorted({int(w) for w in nt["GpsWeek"][ok]})
    late = nt["t_s"][ok] >= NAV_TIME_SETTLED_S

    def st(x):
        return {"median": float(np.median(x)), "min": float(x.min()), "max": float(x.max())}
    return {"frames": int(ok.sum()), "gps_weeks": weeks, "offset_us": st(d_us),
            "offset_us_after_settling": st(d_us[late]) if late.any() else None,
            "settled_from_s": NAV_TIME_SETTLED_S,
            "note": "TimeOfWeek - (t0 GPS time + TimeOfValidity); the firmware's GNSS time is "
                    "the IMU time less the smallest (IMU time - TimeOfWeek) of the epochs so "
                    "far plus the configured latency: until the earliest-logged epoch has "
                    "come, it is early by that epoch's extra delay"}


def _c312(roll_deg, pitch_deg, yaw_deg) -> np.ndarray:
    """C = Rz(-yaw) Rx(pitch) Ry(roll) (vehicle <- IMU, firmware/app/mounting.h)."""
    r, p, y = map(math.radians, (roll_deg, pitch_deg, yaw_deg))
    rz = np.array([[math.cos(y), math.sin(y), 0.0], [-math.sin(y), math.cos(y), 0.0],
                   [0.0, 0.0, 1.0]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(p), -math.sin(p)],
                   [0.0, math.sin(p), math.cos(p)]])
    ry = np.array([[math.cos(r), 0.0, math.sin(r)], [0.0, 1.0, 0.0],
                   [-math.sin(r), 0.0, math.cos(r)]])
    return rz @ rx @ ry


def device_angles_deg(rpy_312) -> dict:
    """The README's mounting angles (the device's Z-Y-X roll, pitch, yaw against the car,
    convert.device_mount_deg) of a firmware mounting (3-1-2, the device's FRD axes)."""
    z = convert.P_SWAP @ _c312(*rpy_312)
    return {"roll": math.degrees(math.atan2(z[2, 1], z[2, 2])),
            "pitch": math.degrees(-math.asin(max(-1.0, min(1.0, z[2, 0])))),
            "yaw": math.degrees(math.atan2(z[1, 0], z[0, 0]))}


def mount_estimate(path, db, imu_meta: dict) -> dict | None:
    """The automatic mounting estimate (NAV_Calibration pages 1 and 2) of a run: when it
    converged (log time), the last estimate in the firmware's 3-1-2 angles and as the
    README's device angles against the reference's (imu_meta: the converter's meta "imu",
    its mounting_deg and imu_mount_deg_312); None when the run sent no page 1 (a
    configured mounting)."""
    ref_deg = imu_meta["mounting_deg"]
    cal_id = db.get_message_by_name("NAV_Calibration").frame_id
    last1 = last2 = at_conv = None
    conv_t = None
    for m in nc.read_log(path):
        if m.arbitration_id != cal_id:
            continue
        sig = db.decode_message(cal_id, bytes(m.data), decode_choices=False)
        if sig["CalPage"] == 1:
            last1 = sig
        elif sig["CalPage"] == 2:
            last2 = sig
            if conv_t is None and sig["MountState"] >= 2:
                conv_t = float(m.timestamp)
                at_conv = (last1, sig)
    if last1 is None or last2 is None:
        return None
    rpy = (last1["MountRoll"], last1["MountPitch"], last1["MountYaw"])
    dev = device_angles_deg(rpy)
    conv = None
    if at_conv is not None:  # the mounting navigation ran with
        c1, c2 = at_conv
        crpy = (c1["MountRoll"], c1["MountPitch"], c1["MountYaw"])
        cdev = device_angles_deg(crpy)
        conv = {"estimate_device_deg": {k: round(v, 3) for k, v in cdev.items()},
                "error_device_deg": {k: round(cdev[k] - ref_deg[k], 3) for k in cdev},
                "sigma_roll_pitch_deg": c2["MountSigmaRollPitch"],
                "sigma_yaw_deg": c2["MountSigmaYaw"]}
    return {"converged_at_log_s": conv_t, "state": int(last2["MountState"]),
            "at_convergence": conv,
            "estimate_312_deg": rpy, "reference_312_deg": list(imu_meta["imu_mount_deg_312"]),
            "estimate_device_deg": {k: round(v, 3) for k, v in dev.items()},
            "reference_device_deg": ref_deg,
            "error_device_deg": {k: round(dev[k] - ref_deg[k], 3) for k in dev},
            "sigma_roll_pitch_deg": last2["MountSigmaRollPitch"],
            "sigma_yaw_deg": last2["MountSigmaYaw"],
            "excitation_m2ps3": last2["MountExcitation"]}


def _output_frames(path, exclude_status_page1: bool, status_id: int) -> list:
    """The data-driven output frames (all but the time-driven NAV_Heartbeat: the car's
    traffic adds main-loop passes, so it may go out at another frame) as (id, data)."""
    out = []
    for m in nc.data_driven(nc.read_log(path)):
        if exclude_status_page1 and m.arbitration_id == status_id and (m.data[0] & 0x7) == 1:
            continue
        out.append((m.arbitration_id, bytes(m.data)))
    return out


def run_one(stages, navecu, name, frames, meta, out: Path, opts, db, truth, outage):
    d = out / name
    d.mkdir(parents=True, exist_ok=True)
    convert.write(d / "input.log", frames, meta)
    cmd = [navecu, "--can-log", d / "input.log", "--out", d / "nav.log", *opts]
    stages.start(f"firmware: {name}")
    res = stages.firmware(cmd, d, "$ " + shlex.join(map(str, cmd)) + "\n")
    if res.returncode != 0:
        raise RuntimeError(f"navecu failed on {name} (exit {res.returncode})")
    nav = report.read_nav_log(d / "nav.log", db)
    outages = [] if outage is None else [(outage[0], outage[1], "GNSS outage")]
    rep, series = report.compute(truth, nav, outages)
    rep.update(parse_summary(res.stderr))
    rep["health_flags_raised"] = health_flags_raised(nav.get("NAV_Status"), db)
    _, cnt = report.status_page(nav.get("NAV_Status"), 1, "CntForeign")
    rep["cnt_foreign_last"] = int(cnt[-1]) if cnt.size else None
    rep["nav_time"] = nav_time_check(nav, meta)
    rep["mount_estimate"] = mount_estimate(d / "nav.log", db, meta["imu"])
    rep["input_frames"] = meta["frames"]
    rep["car_frames"] = meta["car_bus"]["frames"]
    return rep, series, d


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default=str(convert.DATA_DIR))
    ap.add_argument("--vehicle", default="toyota_rav4_2017")
    ap.add_argument("--outage", default=DEFAULT_OUTAGE, help="GNSS outage A-B s, or none")
    ap.add_argument("--out", default="out/drive-rav4")
    ap.add_argument("--navecu", default=None)
    ap.add_argument("--mount", choices=("configured", "automatic"), default="configured",
                    help="configured: --imu-mount-deg, the device's axes and the angles "
                         "measured against the reference; automatic: --imu-mount-source "
                         "automatic, no angle given (firmware/app/mount_est.h), the estimate "
                         "reported against the reference's")
    ap.add_argument("--fw-arg", action="append", default=[], metavar="ARG",
                    help="one more firmware option (repeat), e.g. --fw-arg=--mount-est-sigma-deg --fw-arg=2")
    ap.add_argument("--imu-time", default="grid", choices=("grid", "stamped"))
    ap.add_argument("--init", default="reference", choices=("reference", "none"),
                    help="reference: the reference pose at t0 in the initialization "
                         "commands; none: no command, the firmware self-starts (in-motion "
                         "alignment from GNSS)")
    a = ap.parse_args(argv)
    data, out = Path(a.data), Path(a.out)
    navecu = Path(a.navecu or ROOT / "build" / "host" / f"navecu-{a.vehicle}")
    gen_dbc = ROOT / "build" / "vehicle" / a.vehicle / "navecu.dbc"
    for p in (navecu, gen_dbc):
        if not p.exists():
            print(f"drive: {p} missing: make VEHICLE={a.vehicle} first", file=sys.stderr)
            return 2
    try:
        outage = convert.parse_outage(a.outage)
        prof = vehicle.load(a.vehicle)
    except (ValueError, vehicle.ProfileError) as e:
        print(f"drive: {e}", file=sys.stderr)
        return 2
    if prof.native_wheels:
        print(f"drive: profile {a.vehicle} reads no car message: the recording's wheel speeds "
              f"would all be foreign; use VEHICLE=toyota_rav4_2017", file=sys.stderr)
        return 2
    db = nc.load_db(gen_dbc)     # the outputs, decoded with the build's generated DBC
    if {m.name: m.frame_id for m in db.messages} != {
            m.name: m.frame_id for m in nc.select_vehicle(a.vehicle).messages}:
        print(f"drive: {gen_dbc} is not profile {a.vehicle}'s: rebuild", file=sys.stderr)
        return 2
    stages = Stages(6 if outage is not None else 4)
    stages.start("convert the recording")
    read_ids = {r.message.frame_id for r in prof.reads}
    variants = {
        "bus": dict(car_bus=True, outage=None),
        "quiet": dict(car_bus=True, outage=None, car_ids=read_ids),
        "bus-outage": dict(car_bus=True, outage=outage),
        "no-car-outage": dict(car_bus=False, outage=outage),
    }
    if outage is None:
        del variants["bus-outage"], variants["no-car-outage"]
    built = {k: convert.build(data, a.vehicle, imu_time=a.imu_time, init_state=a.init, **kw)
             for k, kw in variants.items()}
    meta = built["bus"][1]
    stages.done(f"{meta['frames']} frames, {meta['car_bus']['frames']} of the car's bus")
    truth = reference_truth(data, meta["t0_segment_s"])
    opts = firmware_options(meta, a.imu_time, a.mount) + list(a.fw_arg)
    reps, series = {}, {}
    for k, (frames, m) in built.items():
        reps[k], series[k], _ = run_one(stages, navecu, k, frames, m, out, opts, db, truth,
                                        variants[k]["outage"])
    stages.start("compare and report")
    status_id = db.get_message_by_name("NAV_Status").frame_id
    same = (_output_frames(out / "bus" / "nav.log", True, status_id)
            == _output_frames(out / "quiet" / "nav.log", True, status_id))
    t_last = meta["last_imu_sample_s"]
    rep = {
        "vehicle": a.vehicle, "navecu": str(navecu), "generated_dbc": str(gen_dbc),
        "firmware_options": opts, "given": {
            "init": meta["init"], "imu": meta["imu"], "gnss": meta["gnss"],
            "gnss_latency_ms": meta["gnss_latency_ms"]},
        "car_bus": meta["car_bus"],
        "runs": reps,
        "bus_outputs_equal_quiet_outputs": same,
        "health_flags_raised_by_car_traffic": sorted(
            set(reps["bus"]["health_flags_raised"]) - set(reps["quiet"]["health_flags_raised"])),
        "wheel_distance": wheel_distance_ratio(data, prof, meta["t0_segment_s"],
                                               meta["t0_segment_s"] + t_last, truth),
        "gnss_only_horizontal_error_m": gnss_error(data, truth, meta["t0_segment_s"]),
    }
    out.mkdir(parents=True, exist_ok=True)
    (out / "report.json").write_text(json.dumps(rep, indent=2, default=float) + "\n")
    plot(series, outage, out)
    stages.done()
    print(summary(rep))
    return 0 if same and not rep["health_flags_raised_by_car_traffic"] else 1


def plot(series, outage, out: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(10, 4))
    for k, s in series.items():
        if "t" in s:
            ax.plot(s["t"], s["herr"], label=k, lw=1.2)
    if outage is not None:
        ax.axvspan(outage[0], outage[1], color="tab:red", alpha=0.12, label="GNSS outage")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("horizontal error (m)")
    ax.set_yscale("log")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("2017 RAV4 (comma2k19): navecu against the reference")
    fig.savefig(out / "horizontal_error.png", dpi=110, bbox_inches="tight")
    plt.close(fig)


def summary(rep: dict) -> str:
    r = rep["runs"]
    b = r["bus"]
    L = [f"vehicle {rep['vehicle']}: {rep['car_bus']['frames']} car frames "
         f"({rep['car_bus']['frames_per_s']:.0f}/s, all channels of car_bus.log)"]
    cr = b.get("car_messages_read", {})
    L.append(f"car messages read: {cr}; foreign frames {b['foreign_frames']} "
             f"(NAV_Status CntForeign {b['cnt_foreign_last']})")
    wd = rep["wheel_distance"]
    fse = b["filter_odometer_scale_error"]
    L.append(f"odometer: filter's scale error {'none' if fse is None else format(fse, '+.4f')}, "
             f"wheels/reference {wd['scale_error']:+.4f} ({wd['wheels_m']:.1f} m / "
             f"{wd['reference_m']:.1f} m)")
    L.append(f"health flags: bus {b['health_flags_raised'] or 'none'}, quiet "
             f"{r['quiet']['health_flags_raised'] or 'none'}; raised by the car's traffic: "
             f"{rep['health_flags_raised_by_car_traffic'] or 'none'}; outputs with and "
             f"without the car's other traffic {'identical' if rep['bus_outputs_equal_quiet_outputs'] else 'DIFFERENT'}"
             " (NAV_Status page 1 aside)")
    L.append(f"rejected (firmware): {b['rejected']}")
    g = rep["gnss_only_horizontal_error_m"]
    L.append(f"u-blox fixes alone: rms {g['rms']:.2f} m, max {g['max']:.2f} m")
    for k, x in r.items():
        h = x["horizontal_error_m"]
        if h["rms"] is None:
            L.append(f"{k:>14}: not navigating")
            continue
        line = f"{k:>14}: horizontal error rms {h['rms']:.2f} m, p95 {h['p95']:.2f} m, " \
               f"max {h['max']:.2f} m"
        if not rep["given"]["init"].get("sent", True):
            line += f" (self-started: first output at {x['navigation_start_s']:.2f} s)"
        for o in x.get("outages", []):
            line += (f"; outage {o['start_s']:.0f}-{o['end_s']:.0f} s ({o['distance_m']:.0f} m):"
                     f" end {o['end_error_m']:.2f} m, max {o['max_error_m']:.2f} m")
        L.append(line)
        me = x.get("mount_estimate")
        if me:
            e, ref = me["estimate_device_deg"], me["reference_device_deg"]
            L.append(f"{'':>14}  mounting estimate (state {me['state']}, converged at "
                     f"{me['converged_at_log_s']} s): roll {e['roll']:+.2f} pitch "
                     f"{e['pitch']:+.2f} yaw {e['yaw']:+.2f} deg vs the reference's "
                     f"{ref['roll']:+.2f} {ref['pitch']:+.2f} {ref['yaw']:+.2f}; sigma "
                     f"{me['sigma_roll_pitch_deg']:.3f}/{me['sigma_yaw_deg']:.3f} deg, "
                     f"excitation {me['excitation_m2ps3']:.0f} m^2/s^3")
            ac = me.get("at_convergence")
            if ac:
                ce = ac["error_device_deg"]
                L.append(f"{'':>14}  at convergence (the mounting in use): error roll "
                         f"{ce['roll']:+.2f} pitch {ce['pitch']:+.2f} yaw {ce['yaw']:+.2f} deg, "
                         f"sigma {ac['sigma_roll_pitch_deg']:.3f}/{ac['sigma_yaw_deg']:.3f}")
    nt = b["nav_time"]
    if nt.get("frames"):
        o, s = nt["offset_us"], nt["offset_us_after_settling"] or nt["offset_us"]
        L.append(f"NAV_Time: {nt['frames']} frames, week {nt['gps_weeks']}, TimeOfWeek - GNSS "
                 f"time of the set: median {o['median']:.0f} us [{o['min']:.0f}, "
                 f"{o['max']:.0f}]; from {nt['settled_from_s']:.0f} s on [{s['min']:.0f}, "
                 f"{s['max']:.0f}] us")
    return "\n".join(L)


if __name__ == "__main__":
    sys.exit(main())
