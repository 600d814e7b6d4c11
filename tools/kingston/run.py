"""The recorded Kingston 2008 drive through the firmware, against the SPAN reference.

    python -m tools.kingston.run --mode dr|full [--outages SPEC] [--calibrate-at-km 5|none]
                                 [--out out/kingston-dr] [--navecu build/host/navecu]

Stages: the CSVs converted to a candump log (tools/kingston/convert.py; `dr` sends no GNSS
frame at all, `full` sends GNSS with the outages, default "60 s every 240 s"); the host
firmware run over it (build/host/navecu --can-log, IMU, NAV and status at 10 Hz); the
report: report.json and PNG plots in the output folder, a summary on stdout.

The NAV outputs are read with tools/sim/report.py read_nav_log: their time is NAV_Height's
TimeOfValidity, the firmware's IMU time, i.e. seconds since the first IMU sample, the log's
time base. The reference (1 Hz) is interpolated linearly to those times; only NAV sets
within the reference's time span are compared. Horizontal errors use the local WGS-84
radii; heights are not compared (the GNSS and reference heights differ by a datum).
Travelled distances are the polyline of the reference positions.

report.json: horizontal_error_m {rms, p95, max, final}, distance_km, heading_error_deg,
outages (per outage: start, end, distance driven in it, error at its start, its largest,
error at its end and that as % of the distance), median_error_at_outage_end_m (over the
outages), calibration (the one-point
calibration at --calibrate-at-km: dH_deg and mu decoded from the firmware's
NAV_Calibration frames after the command, or performed = false with what the firmware
said; error_before_pct = horizontal error at the calibration point / distance travelled
until then, error_after_pct = max horizontal error after it / distance travelled since,
in %), gnss_only_horizontal_error_m (the receiver's fixes against the reference).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import shlex
import sys
import time
from pathlib import Path

import can
import numpy as np

from tools import geodesy, navecu_can as nc
from tools.kingston import convert
from tools.sim import report
from tools.sim.run import Stages

ROOT = Path(__file__).resolve().parents[2]
RATES = ["--imu-rate-hz", "10", "--nav-rate-hz", "10", "--status-rate-hz", "10"]
# This installation's sensors, as an ECU would be configured for them (docs/kingston.md):
# the IMU's noise and bias measured on the data at rest (tools/kingston/analyse.py: ARW
# 0.18..0.85 deg/sqrt(h), z bias about -2.4 deg/h; accelerometer bias of a low-grade MEMS
# unit, a few mg); its in-run instabilities a tenth of those turn-on figures (the usual
# datasheet relation of a MEMS unit's bias instability to its turn-on bias: 0.5 deg/h,
# 0.5 mg), chosen before they were measured and consistent with the measurement since
# (tools/kingston/analyse.py, "IMU Allan deviation at the first stop": the horizontal
# accelerometers' deviation largest at 100 s, 0.70 and 0.27 mg; the gyros' still falling
# at 170 s, z 0.28 deg/h), with the MEMS class's correlation time, the automotive
# preset's 100 s (not measured: a 529-s stop cannot place the accelerometers' Allan peak,
# flat and uncertain by tens of percent between 100 and 170 s); the forward (y)
# accelerometer's, which the filter takes as a Gauss-Markov state of its own (ekf.h,
# state 25), is that axis's measured 0.27 mg: its wander is what the odometer cannot tell
# from the pitch;
# ranges those of that preset (the default,
# firmware/app/params.toml); the receiver's fixes are stamped with their time of validity
# (latency 0) and their errors against the reference decorrelate in 3..5 s (measured). The
# speed is OBD-II's (PID 0x0D): a magnitude, the car reverses into its parking space at the
# end (3473-3498 s) with positive readings, so its direction is the navigator's; and it is
# whole km/h (0.2778 m/s steps: the filter's offset state's prior is half of one). The
# receiver's velocity errors are correlated over about 3 s as well (0.70 at 1 s, 0.37 at
# 3 s: tools/kingston/analyse.py).
SENSORS = ["--imu-preset", "automotive", "--gyro-arw-dpsh", "0.3", "--gyro-bias-dph", "5",
           "--gyro-instability-dph", "0.5", "--accel-bias-mg", "5",
           "--accel-instability-mg", "0.5", "--accel-fwd-instability-mg", "0.27",
           "--gnss-latency-ms", "0", "--gnss-corr-s", "4",
           "--gnss-vel-corr-s", "3", "--odo-direction", "navigator", "--odo-step-mps", "0.2778"]


def stats(x) -> dict:
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return {"rms": None, "p95": None, "max": None, "final": None}
    return {"rms": float(np.sqrt(np.mean(x ** 2))), "p95": float(np.percentile(x, 95)),
            "max": float(np.max(x)), "final": float(x[-1])}


def read_calibration_log(path) -> dict:
    """NAV_Calibration frames of a navecu output log, with the firmware's time (that of the
    last NAV_Height, TimeOfValidity unwrapped, as read_nav_log does; the log timestamp
    before any NAV_Height)."""
    db = nc.load_db()
    cal_id = db.get_message_by_name("NAV_Calibration").frame_id
    h_id = db.get_message_by_name("NAV_Height").frame_id
    rows, t_now, last_ms, wraps = [], None, None, 0
    with can.LogReader(str(path)) as reader:
        for msg in reader:
            if msg.arbitration_id == h_id:
                ms = int.from_bytes(bytes(msg.data[4:6]), "little")  # TimeOfValidity, bits 32..47
                if last_ms is not None and ms < last_ms:
                    wraps += 1
                last_ms = ms
                t_now = (wraps * 65536 + ms) / 1000.0
            elif msg.arbitration_id == cal_id:
                sig = db.decode_message(cal_id, bytes(msg.data), decode_choices=False)
                if sig.get("CalPage", 0) != 0:
                    continue  # the automatic mounting estimate's pages
                sig["t_s"] = t_now if t_now is not None else float(msg.timestamp)
                rows.append(sig)
    if not rows:
        return {}
    return {k: np.array([r[k] for r in rows], dtype=float) for k in rows[0]}


def _choice(db, message, signal, value) -> str:
    choices = db.get_message_by_name(message).get_signal_by_name(signal).choices or {}
    v = int(value)
    return str(choices.get(v, v))


def calibration_block(cal_meta, cal_log, status, t, herr, dist_at) -> dict:
    """The report's calibration entry (module docstring)."""
    if not cal_meta:
        return {"requested": False, "performed": False, "time_s": None, "dH_deg": None,
                "mu": None, "error_before_pct": None, "error_after_pct": None}
    db = nc.DEFAULT_DB
    t_cal = cal_meta["time_s"]
    out = {"requested": True, "time_s": t_cal, "at_km": cal_meta["at_km"],
           "lat_deg": cal_meta["lat_deg"], "lon_deg": cal_meta["lon_deg"],
           "performed": False, "dH_deg": None, "mu": None}
    # errors around the point, whatever the firmware made of the command
    before = t <= t_cal + 1e-9
    after = t > t_cal + 1e-9
    if before.any() and after.any():
        d_before = float(np.interp(t_cal, t, dist_at) - dist_at[0])
        d_after = float(dist_at[-1] - np.interp(t_cal, t, dist_at))
        e_cal = float(herr[before][-1])
        e_after = float(herr[after].max())
        out.update({"distance_before_m": d_before, "distance_after_m": d_after,
                    "error_at_point_m": e_cal, "max_error_after_m": e_after,
                    "error_before_pct": 100.0 * e_cal / d_before if d_before > 0 else None,
                    "error_after_pct": 100.0 * e_after / d_after if d_after > 0 else None})
    else:
        out.update({"error_before_pct": None, "error_after_pct": None})
    if not cal_log:
        out["status"] = "not performed: the firmware sent no NAV_Calibration frame"
        return out
    ct = cal_log["t_s"]
    prior = ct <= t_cal + 1e-9
    count_before = int(cal_log["CalCount"][prior][-1]) if prior.any() else 0
    later = np.flatnonzero(~prior)
    if not later.size:
        out["status"] = "not performed: no NAV_Calibration frame after the command"
        return out
    # a calibration by the command: CalCount up with a source other than the filter's
    # (the filter's own adoptions count too: filter_adoptions)
    done = [i for i in later if int(cal_log["CalCount"][i]) > count_before
            and int(cal_log["CalSource"][i]) != report.FILTER_CAL_SOURCE]
    # what the command counter page says right after the command
    rej = None
    if status is not None and "CntCmdRejected" in status:
        st_t, st_c = status["t_s"], status["CntCmdRejected"]
        ok = ~np.isnan(st_c)
        b = ok & (st_t <= t_cal + 1e-9)
        a = ok & (st_t > t_cal + 1e-9) & (st_t <= t_cal + 2.0)
        if b.any() and a.any():
            rej = int(st_c[a][-1] - st_c[b][-1])
    out["commands_rejected_within_2s"] = rej
    if done:
        i = done[0]
        out.update({"performed": True, "reported_at_s": float(ct[i]),
                    "dH_deg": float(cal_log["HeadingCorrection"][i]),
                    "mu": float(cal_log["OdoScaleError"][i]),
                    "cal_count": int(cal_log["CalCount"][i]),
                    "cal_status": _choice(db, "NAV_Calibration", "CalStatus",
                                          cal_log["CalStatus"][i]),
                    "cal_source": _choice(db, "NAV_Calibration", "CalSource",
                                          cal_log["CalSource"][i]),
                    "status": "performed"})
    else:
        i = later[0]
        st = _choice(db, "NAV_Calibration", "CalStatus", cal_log["CalStatus"][i])
        why = f"CalCount stayed {count_before}, CalStatus {st}"
        if rej:
            why += f", CntCmdRejected +{rej} (the firmware refused the command)"
        out["status"] = f"not performed: {why}"
        out["cal_status"] = st
    return out


def filter_adoptions(cal_log) -> list:
    """Each store of the filter's calibration (NAV_Calibration: CalCount up, CalSource
    Filter): time, odometer scale error and heading (mounting yaw) correction."""
    if not cal_log:
        return []
    out, prev = [], None
    for i, n in enumerate(cal_log["CalCount"]):
        filter_source = int(cal_log["CalSource"][i]) == report.FILTER_CAL_SOURCE
        if prev is not None and n > prev and filter_source:
            out.append({"t_s": float(cal_log["t_s"][i]), "mu": float(cal_log["OdoScaleError"][i]),
                        "dH_deg": float(cal_log["HeadingCorrection"][i])})
        prev = n
    return out


def gnss_errors(drive, sent_times=None) -> dict:
    """The receiver's fixes against the reference at the epochs both have (heights ignored).
    sent_times: only the epochs at these GPS times (the ones the log carries)."""
    g = drive.gnss
    common, gi, ri = np.intersect1d(np.rint(g["time_s"]), np.rint(drive.ref["time_s"]),
                                    return_indices=True)
    if sent_times is not None:
        keep = np.isin(common, np.rint(sent_times))
        gi, ri = gi[keep], ri[keep]
    e = geodesy.horizontal_distance_m(drive.ref["lat_deg"][ri], drive.ref["lon_deg"][ri],
                                      g["lat_deg"][gi], g["lon_deg"][gi])
    if not e.size:
        return {"n": 0, "rms": None, "p95": None, "median": None, "max": None}
    return {"n": int(e.size), "rms": float(np.sqrt(np.mean(e ** 2))),
            "p95": float(np.percentile(e, 95)), "median": float(np.median(e)),
            "max": float(e.max())}


def sent_gnss_times(can_log) -> np.ndarray:
    """GPS times of the GNSS epochs in the log that close with >= 4 satellites (the ones
    the firmware accepts), from their GNSS_Status TimeOfWeek."""
    db = nc.DEFAULT_DB
    sid = db.get_message_by_name("GNSS_Status").frame_id
    out = []
    with can.LogReader(str(can_log)) as reader:
        for msg in reader:
            if msg.arbitration_id == sid:
                s = db.decode_message(sid, bytes(msg.data), decode_choices=False)
                if s["NumSatellites"] >= 4 and s["FixType"] >= 3:
                    out.append(float(s["TimeOfWeek"]))
    return np.array(out)


AFTER_OUTAGE_S = 30.0  # the window after an outage's end checked for a transient


def outage_table(t, herr, ref_t, ref_dist, outages) -> list:
    """One row per GNSS outage [start_s, end_s): the distance driven in it (reference
    polyline), the horizontal error of the first and of the last NAV set inside it (its end
    error, also as % of that distance when the car moved more than 1 m) and the largest;
    after it, the largest error in the AFTER_OUTAGE_S that follow (GNSS back: the filter's
    transient) and whether it stays within the end error + 1 m."""
    rows = []
    for o in outages:
        a, b = o["start_s"], o["end_s"]
        s3 = (t >= a) & (t <= b)
        d0, d1 = np.interp([a, b], ref_t, ref_dist)
        end = float(herr[s3][-1]) if s3.any() else None
        s4 = (t > b) & (t <= b + AFTER_OUTAGE_S)
        after = float(herr[s4].max()) if s4.any() else None
        rows.append({"start_s": a, "end_s": b, "distance_m": float(d1 - d0),
                     "max_error_after_m": after,
                     "after_within_end_plus_1m": (after <= end + 1.0
                                                  if after is not None and end is not None
                                                  else None),
                     "start_error_m": float(herr[s3][0]) if s3.any() else None,
                     "max_error_m": float(herr[s3].max()) if s3.any() else None,
                     "end_error_m": end,
                     "end_error_pct_of_distance": (100.0 * end / float(d1 - d0)
                                                   if end is not None and d1 - d0 > 1.0
                                                   else None)})
    return rows


def median_outage_end_error(rows) -> float | None:
    """The median over the outages of the error at their end (None without outages)."""
    ends = [r["end_error_m"] for r in rows if r["end_error_m"] is not None]
    return float(np.median(ends)) if ends else None


def compute(drive, meta, nav, cal_log) -> tuple:
    """report.json content and the plot series."""
    ref = convert.reference_track(drive)
    rep = {"data": str(drive.data_dir), "t0_gps_s": drive.t0_gps,
           "duration_s": float(ref["t_s"][-1] - ref["t_s"][0]),
           "reference_distance_km": float(ref["dist_m"][-1] / 1000.0)}
    pos = nav.get("NAV_Position")
    if pos is None:
        rep.update({"navigating": False, "horizontal_error_m": stats([]), "distance_km": 0.0,
                    "calibration": calibration_block(meta["calibration"], cal_log, None,
                                                     np.array([]), np.array([]),
                                                     np.array([]))})
        return rep, {}
    t_all = pos["t_s"]
    sel = (t_all >= ref["t_s"][0]) & (t_all <= ref["t_s"][-1])
    t = t_all[sel]
    lat_e, lon_e = pos["Latitude"][sel], pos["Longitude"][sel]
    lat_r = np.interp(t, ref["t_s"], ref["lat_deg"])
    lon_r = np.interp(t, ref["t_s"], ref["lon_deg"])
    herr = geodesy.horizontal_distance_m(lat_r, lon_r, lat_e, lon_e)
    dist_at = np.interp(t, ref["t_s"], ref["dist_m"])
    dist = float(dist_at[-1] - dist_at[0])
    rep.update({"navigating": True, "navigation_start_s": float(t_all[0]),
                "compared_s": [float(t[0]), float(t[-1])], "nav_sets_compared": int(t.size),
                "horizontal_error_m": stats(herr), "distance_km": dist / 1000.0,
                "final_error_pct_of_distance": 100.0 * float(herr[-1]) / dist if dist else None})
    series = {"t": t, "herr": herr, "lat_e": lat_e, "lon_e": lon_e}
    att = nav.get("NAV_Attitude")
    if att is not None:
        ta = att["t_s"]
        s2 = (ta >= ref["t_s"][0]) & (ta <= ref["t_s"][-1])
        hr = np.interp(ta[s2], ref["t_s"], np.unwrap(np.radians(ref["heading_deg"])))
        dh = np.degrees((np.radians(att["Heading"][s2]) - hr + math.pi) % (2 * math.pi) - math.pi)
        rep["heading_error_deg"] = {"rms": float(np.sqrt(np.mean(dh ** 2))),
                                    "max": float(np.max(np.abs(dh))), "final": float(dh[-1])}
        series["heading"] = (ta[s2], dh)
    st = nav.get("NAV_Status")
    if st is not None and "Mode" in st:
        modes = st["Mode"][~np.isnan(st["Mode"])].astype(int)
        names = nc.DEFAULT_DB.get_message_by_name("NAV_Status").get_signal_by_name("Mode").choices
        rep["modes_seen"] = {str(names.get(m, m)): int(np.sum(modes == m))
                             for m in np.unique(modes)}
    rep["outages"] = outage_table(t, herr, ref["t_s"], ref["dist_m"],
                                  meta["gnss"]["outages"] if meta["gnss"]["enabled"] else [])
    rep["median_error_at_outage_end_m"] = median_outage_end_error(rep["outages"])
    rep["sigma_consistency"] = report.sigma_consistency(t, herr, st)
    rep["calibration"] = calibration_block(meta["calibration"], cal_log, st, t, herr, dist_at)
    rep["filter_calibration_adopted"] = filter_adoptions(cal_log)
    return rep, series


def plot(drive, meta, series, rep, out: Path, title: str) -> list:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ref = convert.reference_track(drive)
    lat0, lon0 = math.radians(ref["lat_deg"][0]), ref["lon_deg"][0]
    rm, rn = geodesy.radii_m(lat0)

    def en(lat_deg, lon_deg):
        return (np.radians(np.asarray(lon_deg) - lon0) * rn * math.cos(lat0),
                np.radians(np.asarray(lat_deg) - ref["lat_deg"][0]) * rm)

    outages = [(o["start_s"], o["end_s"]) for o in meta["gnss"]["outages"]] \
        if meta["gnss"]["enabled"] else []
    cal = meta["calibration"]
    paths = []
    re_, rn_ = en(ref["lat_deg"], ref["lon_deg"])
    for name, zoom in (("track.png", True), ("track_full.png", False)):
        fig, ax = plt.subplots(figsize=(8, 8))
        ax.plot(re_, rn_, color="0.2", lw=2.0, label="reference (SPAN)")
        for k, (a, b) in enumerate(outages):
            s = (ref["t_s"] >= a) & (ref["t_s"] < b)
            ax.plot(re_[s], rn_[s], color="tab:red", lw=5, alpha=0.4,
                    label="GNSS outage" if k == 0 else None)
        if meta["gnss"]["enabled"]:
            ge, gn = en(drive.gnss["lat_deg"], drive.gnss["lon_deg"])
            ax.plot(ge, gn, ".", ms=2, color="tab:green", alpha=0.5, label="GNSS fixes (all)")
        if "t" in series:
            ne, nn = en(series["lat_e"], series["lon_e"])
            ax.plot(ne, nn, color="tab:blue", lw=1.2, label="navecu")
        ax.plot(re_[0], rn_[0], "k^", ms=9, label="start")
        if cal:
            ce, cn = en(cal["lat_deg"], cal["lon_deg"])
            ax.plot(ce, cn, "*", color="tab:orange", ms=16, mec="k",
                    label=f"calibration point ({cal['at_km']:g} km)")
        if zoom:
            pad = 0.15 * max(np.ptp(re_), np.ptp(rn_))
            ax.set_xlim(re_.min() - pad, re_.max() + pad)
            ax.set_ylim(rn_.min() - pad, rn_.max() + pad)
            ax.set_aspect("equal", adjustable="box")
        else:
            ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("east (m)")
        ax.set_ylabel("north (m)")
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
        ax.set_title(f"{title}: track{'' if zoom else ' (whole navecu track)'}")
        p = out / name
        fig.savefig(p, dpi=110, bbox_inches="tight")
        plt.close(fig)
        paths.append(p)

    marks = [(cal["time_s"], f"CalibrateHere ({cal['at_km']:g} km)")] if cal else []
    paths += report.plot_error_series(series, outages, marks, title, out,
                                      "time since the first IMU sample (min)", log_above_m=1000.0)
    return paths


def binary_info(path) -> dict:
    """Which firmware build produced the result: the binary's SHA-256 and modification time
    (the firmware changes under active development)."""
    p = Path(path)
    return {"path": str(p), "sha256": hashlib.sha256(p.read_bytes()).hexdigest(),
            "modified_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(p.stat().st_mtime))}


def summary(rep: dict) -> str:
    def f(x, unit="m", nd=2):
        return "n/a" if x is None else f"{x:.{nd}f} {unit}"

    lines = [f"drive: {rep['duration_s'] / 60:.1f} min, "
             f"reference {rep['reference_distance_km']:.2f} km"]
    if not rep.get("navigating"):
        lines.append("navecu never started navigating (see its NAV_Status)")
        return "\n".join(lines)
    h = rep["horizontal_error_m"]
    lines.append(f"horizontal error: rms {f(h['rms'])}, p95 {f(h['p95'])}, max {f(h['max'])}, "
                 f"final {f(h['final'])} ({f(rep['final_error_pct_of_distance'], '%')} of "
                 f"{rep['distance_km']:.2f} km)")
    if "heading_error_deg" in rep:
        he = rep["heading_error_deg"]
        lines.append(f"heading error:    rms {f(he['rms'], 'deg')}, max {f(he['max'], 'deg')}, "
                     f"final {f(he['final'], 'deg')}")
    if rep.get("outages"):
        worst = max(rep["outages"], key=lambda o: o["max_error_m"] or 0.0)
        lines.append(f"GNSS outages: {len(rep['outages'])}, worst {worst['start_s']:.0f}-"
                     f"{worst['end_s']:.0f} s ({worst['distance_m']:.0f} m): max error "
                     f"{f(worst['max_error_m'])}; median error at an outage's end "
                     f"{f(rep.get('median_error_at_outage_end_m'))}")
        for o in rep["outages"]:
            pct = o.get("end_error_pct_of_distance")
            lines.append(f"  outage {o['start_s']:7.1f}-{o['end_s']:7.1f} s "
                         f"{o['distance_m']:7.0f} m: at its end {f(o['end_error_m'])}"
                         + (f" ({pct:.2f} %)" if pct is not None else "")
                         + f", max {f(o['max_error_m'])}; "
                         f"{AFTER_OUTAGE_S:.0f} s after: max {f(o['max_error_after_m'])}"
                         + ("" if o["after_within_end_plus_1m"] is not False
                            else " (above its end + 1 m)"))
        over = [o for o in rep["outages"] if o["after_within_end_plus_1m"] is False]
        lines.append(f"after the outages: {len(over)} of {len(rep['outages'])} with an error "
                     f"above their end's + 1 m within {AFTER_OUTAGE_S:.0f} s")
    sc = rep.get("sigma_consistency")
    if sc:
        lines.append("sigma consistency: " + (
            f"{sc['frac_within_2sigma'] * 100:.1f} % within 2 sigma, median error/sigma "
            f"{sc['median_error_over_sigma']:.2f} ({sc['epochs_used']} epochs)"
            if sc["status"] == "ok" else
            f"unknown (HorizAccuracy 655.35 at {sc['epochs_sigma_unknown']} of "
            f"{sc['epochs']} epochs)"))
    c = rep["calibration"]
    if c.get("requested"):
        lines.append(f"calibration at {c['at_km']:g} km (t = {c['time_s']:.1f} s): {c['status']}"
                     + (f", dH {c['dH_deg']:.3f} deg, mu {c['mu']:.5f}" if c["performed"] else ""))
        lines.append(f"  error at the point {f(c.get('error_at_point_m'))} = "
                     f"{f(c['error_before_pct'], '%', 3)} of the distance before; max after "
                     f"{f(c.get('max_error_after_m'))} = {f(c['error_after_pct'], '%', 3)} of "
                     "the distance since")
    ad = rep.get("filter_calibration_adopted", [])
    lines.append("filter's calibration adopted: " + (
        f"{len(ad)} time(s), first at {ad[0]['t_s']:.0f} s (mu {ad[0]['mu']:.5f}, dH "
        f"{ad[0]['dH_deg']:.3f} deg), last at {ad[-1]['t_s']:.0f} s (mu {ad[-1]['mu']:.5f}, "
        f"dH {ad[-1]['dH_deg']:.3f} deg)" if ad else "never (NAV_Calibration CalSource "
        "Filter not seen)"))
    g = rep["gnss_only_horizontal_error_m"]
    lines.append(f"GNSS fixes alone vs reference: rms {f(g['rms'])}, p95 {f(g['p95'])} "
                 f"({g['n']} epochs)")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mode", choices=("dr", "full"), default="full",
                    help="dr: no GNSS frames (dead reckoning); full: GNSS with outages")
    ap.add_argument("--outages", default="default",
                    help="full mode: 'a-b,c-d' s from the start, every:P:L[:O], default "
                         f"({convert.DEFAULT_OUTAGES}), none")
    ap.add_argument("--calibrate-at-km", default=str(convert.DEFAULT_CAL_KM),
                    type=convert.parse_km, help="CalibrateHere at this distance (km), or none")
    ap.add_argument("--imu-rule", choices=convert.IMU_RULES, default="rect",
                    help="IMU increment rule (tools/kingston/convert.py; default rect)")
    ap.add_argument("--level", action="store_true",
                    help="no CMD_InitialAttitude: the firmware levels on its own (30 s)")
    ap.add_argument("--no-odometer", action="store_true",
                    help="omit the WheelSpeeds frames (with --mode dr: free inertial)")
    ap.add_argument("--no-gnss-velocity", action="store_true",
                    help="omit the GNSS_Velocity frames (GNSS position only)")
    ap.add_argument("--gnss-raw", action="store_true",
                    help="also send gnss_raw.csv as raw epochs (GNSS_Raw*, docs/can.md; the "
                         "firmware assembles and counts them, and fuses them with "
                         "--navecu-args '--gnss-input raw' (or both))")
    ap.add_argument("--raw-keep", type=int, default=0, metavar="N",
                    help="with --gnss-raw: in the outages the N highest satellites' raw "
                         "measurements are kept (a partial outage)")
    ap.add_argument("--data", default=None, help=f"data folder (default {convert.DATA_DIR})")
    ap.add_argument("--out", default=None,
                    help="output folder (default out/kingston-dr or out/kingston)")
    ap.add_argument("--navecu", default=str(ROOT / "build" / "host" / "navecu"))
    ap.add_argument("--navecu-args", default="",
                    help="more navecu options, one string (e.g. \"--gyro-bias-dph 3\")")
    a = ap.parse_args(argv)
    out = Path(a.out) if a.out else ROOT / "out" / ("kingston-dr" if a.mode == "dr" else "kingston")
    out.mkdir(parents=True, exist_ok=True)
    st = Stages(4)

    st.start("convert the Kingston CSVs to CAN")
    drive = convert.load(a.data)
    t_end = float(drive.imu["time_s"][-1] - drive.t0_gps)
    gnss = a.mode == "full"
    try:
        outages = convert.parse_outages(a.outages, t_end) if gnss else []
    except ValueError as e:
        ap.error(str(e))
    can_in = out / "can_in.log"
    frames, meta = convert.build(drive, gnss=gnss, outages=outages,
                                 calibrate_at_km=a.calibrate_at_km, imu_rule=a.imu_rule,
                                 initial_attitude=not a.level, odometer=not a.no_odometer,
                                 gnss_velocity=not a.no_gnss_velocity, gnss_raw=a.gnss_raw,
                                 raw_keep_in_outages=a.raw_keep)
    nc.write_candump(can_in, (m for _, _, m in frames))
    meta["log"] = str(can_in)
    meta["mode"] = a.mode
    if not gnss and a.outages not in ("default", "none", ""):
        meta["note"] = f"--outages {a.outages} ignored: mode dr sends no GNSS"
    convert.sidecar_path(can_in).write_text(json.dumps(meta, indent=2))
    st.done(f"{meta['frames']} frames -> {can_in}")
    print(convert.summary(meta))

    st.start("firmware (build/host/navecu --can-log, 10 Hz)")
    nav_log = out / "nav.log"
    cmd = [a.navecu, "--can-log", str(can_in), "--out", str(nav_log)] + RATES + SENSORS + \
        shlex.split(a.navecu_args)
    res = st.firmware(cmd, out, " ".join(cmd) + "\n")
    if res.returncode != 0:
        return 1

    st.start("read NAV outputs")
    nav = report.read_nav_log(nav_log)
    cal_log = read_calibration_log(nav_log)
    st.done()

    st.start("report")
    rep, series = compute(drive, meta, nav, cal_log)
    rep["gnss_only_horizontal_error_m"] = gnss_errors(drive)
    rep["gnss_only_horizontal_error_m"]["epochs"] = "every gnss.csv fix at a reference epoch"
    if gnss:
        sent = gnss_errors(drive, sent_gnss_times(can_in))
        sent["epochs"] = "the fixes sent in this log with >= 4 satellites"
        rep["gnss_sent_horizontal_error_m"] = sent
    rep.update({"mode": a.mode, "outages_spec": a.outages if gnss else None,
                "odometer": not a.no_odometer,
                "imu_rule": a.imu_rule, "initial_attitude": "levelled by the firmware" if a.level
                else "CMD_InitialAttitude from the reference's first row",
                "navecu_command": cmd, "navecu_summary": res.stderr.strip().splitlines(),
                "navecu_binary": binary_info(a.navecu),
                "conversion": str(convert.sidecar_path(can_in))})
    (out / "report.json").write_text(json.dumps(rep, indent=2))
    what = "dead reckoning (no GNSS)" if a.mode == "dr" else "GNSS with outages"
    pngs = plot(drive, meta, series, rep, out, f"Kingston 2008, {what}")
    st.done(f"{out / 'report.json'} and {len(pngs)} plots")
    print()
    print(summary(rep))
    print(f"plots: {', '.join(str(p) for p in pngs)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
