"""Accuracy report: the firmware's NAV_* output log against the simulated truth.

    python -m tools.sim.report --truth out/sim/default/truth.npz --nav out/sim/default/nav.log \
        --out out/sim/default

Writes report.json and three PNG plots (track map, horizontal error, heading error); with
--scenario also the scenario's truths and its one-point calibration (calibration_report). The
statistics cover the time the firmware was navigating (NAV_Position present), from the first
NAV_Position frame to the end of the drive. Errors are horizontal distances on the WGS-84
ellipsoid (local radii of curvature), heading errors wrapped to [-180, 180) degrees.
"""
from __future__ import annotations

import argparse
import json
import math
import re
from pathlib import Path

import can
import numpy as np

from tools import navecu_can as nc

A_M = 6378137.0
E2 = 6.69437999014e-3


def radii_m(lat_rad):
    """Meridian and prime-vertical radii of curvature (WGS-84), m."""
    w2 = 1.0 - E2 * np.sin(lat_rad) ** 2
    return A_M * (1.0 - E2) / w2 ** 1.5, A_M / np.sqrt(w2)


def read_nav_log(path) -> dict:
    """Decode NAV_Position / NAV_Attitude / NAV_Velocity / NAV_Height / NAV_Status frames of
    a candump log into arrays keyed by message; each has 't_s' and the signal columns.

    't_s' is the firmware's own time of validity (NAV_Height TimeOfValidity, IMU time,
    unwrapped from its 65.536 s modulus), not the log's timestamps: a recording made over
    a live bus, at any replay speed, gives the same times as a --can-log run. Each
    NAV_Position opens a navigation set (Position, Height, Velocity, Attitude) that takes
    its NAV_Height's time; NAV_Status takes the time of the last set (NaN before one)."""
    db = nc.load_db()
    want = {db.get_message_by_name(n).frame_id: n
            for n in ("NAV_Position", "NAV_Attitude", "NAV_Velocity", "NAV_Height", "NAV_Status")}
    rows = {n: [] for n in want.values()}
    cycle_rows, t_cycle, last_ms, wraps = [], math.nan, None, 0
    with can.LogReader(str(path)) as reader:
        for msg in reader:
            name = want.get(msg.arbitration_id)
            if name is None:
                continue
            sig = db.decode_message(msg.arbitration_id, bytes(msg.data), decode_choices=False)
            if name == "NAV_Position":
                cycle_rows = []
            if name == "NAV_Height":
                ms = int(sig["TimeOfValidity"])
                if last_ms is not None and ms < last_ms:
                    wraps += 1
                last_ms = ms
                t_cycle = (wraps * 65536 + ms) / 1000.0
                for r in cycle_rows:
                    r["t_s"] = t_cycle
            sig["t_s"] = t_cycle
            if name != "NAV_Status":
                cycle_rows.append(sig)
            rows[name].append(sig)
    out = {}
    for name, lst in rows.items():
        if lst:
            keys = lst[0].keys() if name != "NAV_Status" else set().union(*lst)
            out[name] = {k: np.array([r.get(k, np.nan) for r in lst], dtype=float) for k in keys}
    return out


_CANDUMP_LINE = re.compile(
    r"^\(\d+\.\d+\)\s+\S+\s+([0-9A-Fa-f]{3,8})#([0-9A-Fa-f]*)(?:\s+[RT])?\s*$")


def _frames_with_ids(path, ids):
    """(frame_id, data) of the frames with these IDs, in log order. A candump -L text log
    (.log) is scanned line by line for them (a million-frame log in about a second); any
    other format goes through python-can's LogReader."""
    if str(path).endswith(".log"):
        keys = {f"{i:03X}#" for i in ids}
        with open(path) as fh:
            for line in fh:
                sp = line.find(" ", line.find(" ") + 1)
                if line[sp + 1:line.find("#", sp) + 1].upper() not in keys:
                    continue
                m = _CANDUMP_LINE.match(line)
                if m:
                    yield int(m.group(1), 16), bytes.fromhex(m.group(2))
        return
    with can.LogReader(str(path)) as reader:
        for msg in reader:
            if msg.arbitration_id in ids:
                yield msg.arbitration_id, bytes(msg.data)


def read_calibration_log(path) -> dict:
    """NAV_Calibration frames of a candump log as arrays: 't_s' and the signals (raw
    numbers, CalStatus/CalSource as their values). The frame is sent once a second on the
    sample clock and carries no time of its own: 't_s' is that of the last NAV_Height
    before it (its TimeOfValidity, unwrapped like read_nav_log's), NaN before the first."""
    db = nc.load_db()
    cal_id = db.get_message_by_name("NAV_Calibration").frame_id
    height = db.get_message_by_name("NAV_Height")
    tov = height.get_signal_by_name("TimeOfValidity")
    assert tov.byte_order == "little_endian" and tov.scale == 1 and tov.offset == 0
    tov_mask = (1 << tov.length) - 1
    rows, t_last, last_ms, wraps = [], math.nan, None, 0
    for frame_id, data in _frames_with_ids(path, {cal_id, height.frame_id}):
        if frame_id == height.frame_id:
            ms = (int.from_bytes(data, "little") >> tov.start) & tov_mask
            if last_ms is not None and ms < last_ms:
                wraps += 1
            last_ms = ms
            t_last = (wraps * (tov_mask + 1) + ms) / 1000.0
        else:
            sig = db.decode_message(cal_id, data, decode_choices=False)
            sig["t_s"] = t_last
            rows.append(sig)
    keys = rows[0].keys() if rows else ("t_s", "HeadingCorrection", "OdoScaleError", "CalValid",
                                        "CalStored", "CalStatus", "CalSource", "CalCount")
    return {k: np.array([r[k] for r in rows], dtype=float) for k in keys}


def _choice(signal: str, value) -> str | None:
    """The DBC's name of a NAV_Calibration enumeration value (VAL_ 785)."""
    if value is None or not np.isfinite(value):
        return None
    sig = nc.load_db().get_message_by_name("NAV_Calibration").get_signal_by_name(signal)
    return str((sig.choices or {}).get(int(value), int(value)))


def calibration_report(truth: dict, series: dict, cal_log: dict, cal: dict, truths: dict) -> dict:
    """report.json's "calibration": the one-point calibration requested at cal["at_s"]
    (a scenario's [calibration]) as the firmware did it, against the scenario's truths.

    performed: NAV_Calibration's CalCount rose above its first value; time_s, dH_deg, mu:
    that frame's time, HeadingCorrection and OdoScaleError. error_before_*: the horizontal
    error of the last NAV_Position at or before at_s over the distance travelled from the
    start of navigation to at_s; error_after_*: the largest error after the calibration
    over the distance travelled from it to the end of the drive (only if performed).
    dH_firmware_at_cal_deg: NAV_Attitude heading - true heading at at_s (the configured
    dH_true plus the gyros' drift since the start)."""
    at = float(cal["at_s"])
    rep = {"requested_at_s": at, "source": cal["source"], "performed": False, "time_s": None,
           "dH_deg": None, "mu": None, "dH_true_deg": truths["dH_deg"],
           "mu_true": truths["odometer_mu"], "dH_firmware_at_cal_deg": None,
           "cal_count": None, "cal_status": None, "cal_source": None,
           "distance_before_m": None, "error_before_m": None, "error_before_pct": None,
           "distance_after_m": None, "error_after_max_m": None, "error_after_final_m": None,
           "error_after_pct": None}
    n = len(cal_log.get("t_s", ()))
    if n:
        count = cal_log["CalCount"]
        done = np.nonzero(count > count[0])[0]
        i = int(done[0]) if len(done) else n - 1
        rep.update({"cal_count": int(count[i]),
                    "cal_status": _choice("CalStatus", cal_log["CalStatus"][i]),
                    "cal_source": _choice("CalSource", cal_log["CalSource"][i])})
        if len(done):
            t_c = float(cal_log["t_s"][i])
            rep.update({"performed": True, "time_s": t_c if np.isfinite(t_c) else None,
                        "dH_deg": float(cal_log["HeadingCorrection"][i]),
                        "mu": float(cal_log["OdoScaleError"][i])})
    if "heading" in series:
        th, dh = series["heading"]
        if len(th) and th[0] <= at:
            rep["dH_firmware_at_cal_deg"] = float(np.interp(at, th, dh))
    if "t" not in series:
        return rep
    t, herr = series["t"], series["herr"]
    dist = np.interp(t, truth["t_s"], truth["dist_m"])
    before = np.nonzero(t <= at)[0]
    if len(before):
        k = int(before[-1])
        d_b = float(np.interp(at, truth["t_s"], truth["dist_m"]) - dist[0])
        rep.update({"distance_before_m": d_b, "error_before_m": float(herr[k]),
                    "error_before_pct": float(100.0 * herr[k] / d_b) if d_b > 0 else None})
    if rep["performed"]:
        t_c = rep["time_s"] if rep["time_s"] is not None else at
        after = t > t_c
        d_a = float(truth["dist_m"][-1] - np.interp(t_c, truth["t_s"], truth["dist_m"]))
        if after.any():
            e_max = float(herr[after].max())
            rep.update({"distance_after_m": d_a, "error_after_max_m": e_max,
                        "error_after_final_m": float(herr[after][-1]),
                        "error_after_pct": float(100.0 * e_max / d_a) if d_a > 0 else None})
    return rep


def calibration_marks(cal_rep) -> list:
    """[(t_s, label)] for the plots: when the firmware calibrated, else when it was asked."""
    if not cal_rep:
        return []
    if cal_rep["performed"] and cal_rep["time_s"] is not None:
        return [(cal_rep["time_s"], "calibration")]
    return [(cal_rep["requested_at_s"], "calibration requested (not done)")]


def _interp_truth(truth, t_s):
    """Truth lat, lon, heading at times t_s (linear in time; headings unwrapped)."""
    lat = np.interp(t_s, truth["t_s"], truth["lat_rad"])
    lon = np.interp(t_s, truth["t_s"], np.unwrap(truth["lon_rad"]))
    hdg = np.interp(t_s, truth["t_s"], np.unwrap(truth["heading_rad"]))
    return lat, lon, hdg


def horizontal_error_m(lat_true, lon_true, lat_est, lon_est):
    rm, rn = radii_m(lat_true)
    dn = (lat_est - lat_true) * rm
    dlon = (lon_est - lon_true + math.pi) % (2 * math.pi) - math.pi
    de = dlon * rn * np.cos(lat_true)
    return np.hypot(de, dn), de, dn


def _stats(x):
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return {"rms": None, "p95": None, "max": None, "final": None}
    return {"rms": float(np.sqrt(np.mean(x ** 2))), "p95": float(np.percentile(x, 95)),
            "max": float(np.max(x)), "final": float(x[-1])}


def compute(truth: dict, nav: dict, outages) -> tuple[dict, dict]:
    """report.json content and the series for plotting."""
    pos = nav.get("NAV_Position")
    t_end = float(truth["t_s"][-1])
    dist_total = float(truth["dist_m"][-1])
    rep = {"duration_s": t_end, "distance_m": dist_total}
    series = {}
    if pos is None:
        rep.update({"navigating": False, "horizontal_error_m": _stats([]),
                    "heading_error_deg": {"rms": None, "max": None},
                    "final_error_pct_of_distance": None, "outages": []})
        return rep, series
    t = pos["t_s"]
    lat_e, lon_e = np.radians(pos["Latitude"]), np.radians(pos["Longitude"])
    lat_t, lon_t, _ = _interp_truth(truth, t)
    herr, _, _ = horizontal_error_m(lat_t, lon_t, lat_e, lon_e)
    dist_at = np.interp(t, truth["t_s"], truth["dist_m"])
    nav_dist = float(dist_at[-1] - dist_at[0])
    rep["navigating"] = True
    rep["navigation_start_s"] = float(t[0])
    rep["horizontal_error_m"] = _stats(herr)
    rep["final_error_pct_of_distance"] = (float(100.0 * herr[-1] / nav_dist)
                                          if nav_dist > 0 else None)
    att = nav.get("NAV_Attitude")
    if att is not None:
        _, _, hdg_t = _interp_truth(truth, att["t_s"])
        dh = (np.radians(att["Heading"]) - hdg_t + math.pi) % (2 * math.pi) - math.pi
        dh_deg = np.degrees(dh)
        rep["heading_error_deg"] = {"rms": float(np.sqrt(np.mean(dh_deg ** 2))),
                                    "max": float(np.max(np.abs(dh_deg)))}
        series["heading"] = (att["t_s"], dh_deg)
    else:
        rep["heading_error_deg"] = {"rms": None, "max": None}
    rep["outages"] = []
    for (t0, t1, *label) in outages:
        sel = (t >= t0) & (t <= t1)
        d0, d1 = np.interp([t0, t1], truth["t_s"], truth["dist_m"])
        entry = {"start_s": float(t0), "end_s": float(t1), "distance_m": float(d1 - d0),
                 "label": label[0] if label else "",
                 "max_error_m": float(herr[sel].max()) if sel.any() else None,
                 "end_error_m": float(herr[sel][-1]) if sel.any() else None}
        rep["outages"].append(entry)
    series.update({"t": t, "herr": herr, "lat_e": lat_e, "lon_e": lon_e})
    return rep, series


def plot(truth: dict, series: dict, gnss, outages, out_dir: Path, title: str,
         marks=()) -> list:
    """Track map, horizontal error and heading error PNGs; returns their paths. marks:
    [(t_s, label)] drawn as vertical lines over time and as points on the true track."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    lat0, lon0 = truth["lat_rad"][0], truth["lon_rad"][0]
    rm, rn = radii_m(lat0)

    def en(lat, lon):
        return (np.asarray(lon) - lon0) * rn * math.cos(lat0), (np.asarray(lat) - lat0) * rm

    paths = []
    fig, ax = plt.subplots(figsize=(8, 8))
    te, tn = en(truth["lat_rad"], truth["lon_rad"])
    ax.plot(te, tn, color="0.2", lw=2.0, label="truth")
    for k, (t0, t1, *label) in enumerate(outages):
        sel = (truth["t_s"] >= t0) & (truth["t_s"] <= t1)
        ax.plot(te[sel], tn[sel], color="tab:red", lw=5, alpha=0.45,
                label="GNSS outage" if k == 0 else None)
    if gnss is not None and len(gnss["t_s"]):
        ge, gn = en(gnss["lat_rad"], gnss["lon_rad"])
        ax.plot(ge, gn, ".", ms=2, color="tab:green", alpha=0.6, label="GNSS fixes")
    if "t" in series:
        ne, nn = en(series["lat_e"], series["lon_e"])
        ax.plot(ne, nn, color="tab:blue", lw=1.2, label="navecu")
    ax.plot(te[0], tn[0], "k^", ms=9, label="start")
    for t_m, label in marks:
        lat_m = np.interp(t_m, truth["t_s"], truth["lat_rad"])
        lon_m = np.interp(t_m, truth["t_s"], np.unwrap(truth["lon_rad"]))
        me, mn = en(lat_m, lon_m)
        ax.plot(me, mn, "*", color="tab:purple", ms=14, label=f"{label}, {t_m:.0f} s")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    ax.legend(loc="best")
    ax.set_title(f"{title}: track")
    p = out_dir / "track.png"
    fig.savefig(p, dpi=110, bbox_inches="tight")
    plt.close(fig)
    paths.append(p)

    for key, ylabel, fname in (("herr", "horizontal error (m)", "horizontal_error.png"),
                               ("heading", "heading error (deg)", "heading_error.png")):
        fig, ax = plt.subplots(figsize=(10, 4))
        if key == "herr" and "t" in series:
            ax.plot(series["t"] / 60.0, series["herr"], color="tab:blue")
        elif key == "heading" and "heading" in series:
            ax.plot(series["heading"][0] / 60.0, series["heading"][1], color="tab:blue")
        for k, (t0, t1, *label) in enumerate(outages):
            ax.axvspan(t0 / 60.0, t1 / 60.0, color="tab:red", alpha=0.15,
                       label="GNSS outage" if k == 0 else None)
        for t_m, label in marks:
            ax.axvline(t_m / 60.0, color="tab:purple", ls="--", lw=1.2, label=label)
        ax.set_xlabel("time (min)")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        if outages or marks:
            ax.legend(loc="upper left")
        ax.set_title(f"{title}: {ylabel}")
        p = out_dir / fname
        fig.savefig(p, dpi=110, bbox_inches="tight")
        plt.close(fig)
        paths.append(p)
    return paths


def summary_table(rep: dict) -> str:
    """A short human summary of report.json."""
    h = rep["horizontal_error_m"]
    lines = [f"drive: {rep['duration_s'] / 60:.1f} min, {rep['distance_m'] / 1000:.2f} km"]
    if not rep.get("navigating"):
        lines.append("navecu never started navigating (see its NAV_Status)")
        return "\n".join(lines)

    def f(x, unit="m"):
        return "n/a" if x is None else f"{x:.2f} {unit}"

    lines += [f"horizontal error: rms {f(h['rms'])}, p95 {f(h['p95'])}, max {f(h['max'])}, "
              f"final {f(h['final'])} ({f(rep['final_error_pct_of_distance'], '%')} of distance)",
              f"heading error:    rms {f(rep['heading_error_deg']['rms'], 'deg')}, "
              f"max {f(rep['heading_error_deg']['max'], 'deg')}"]
    for o in rep["outages"]:
        lines.append(f"outage {o['label'] or ''} {o['start_s']:.0f}-{o['end_s']:.0f} s "
                     f"({o['distance_m']:.0f} m): max error {f(o['max_error_m'])}, "
                     f"at its end {f(o['end_error_m'])}")
    c = rep.get("calibration")
    if c:
        if c["error_before_pct"] is not None:
            before = (f"{c['error_before_pct']:.2f} % of distance before it "
                      f"({c['error_before_m']:.0f} m after {c['distance_before_m'] / 1000:.2f} km)")
        else:
            before = "no error before it (not navigating)"
        truth = f"true dH {c['dH_true_deg']:+.3f} deg, mu {c['mu_true']:.5f}"
        if c["performed"]:
            after = ("n/a" if c["error_after_pct"] is None else
                     f"{c['error_after_pct']:.2f} % after (max {c['error_after_max_m']:.0f} m "
                     f"over {c['distance_after_m'] / 1000:.2f} km)")
            when = "n/a" if c["time_s"] is None else f"{c['time_s']:.1f} s"
            lines.append(f"calibration ({c['source']}, asked at {c['requested_at_s']:g} s) done at "
                         f"{when}: dH {c['dH_deg']:+.3f} deg, mu {c['mu']:.5f} ({truth})")
            lines.append(f"  error {before}, {after}")
        else:
            lines.append(f"calibration ({c['source']}) asked at {c['requested_at_s']:g} s: NOT "
                         f"performed by the firmware (CalCount {c['cal_count']}, CalStatus "
                         f"{c['cal_status']}); {truth}")
            lines.append(f"  error {before}")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--truth", required=True, help="truth.npz written by tools.sim.run")
    ap.add_argument("--nav", required=True, help="navecu output log (candump)")
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--scenario", default=None,
                    help="the run's scenario (name or .toml): adds its truths and calibration")
    args = ap.parse_args(argv)
    data = dict(np.load(args.truth, allow_pickle=False))
    outages = [tuple(o) for o in data.pop("outages", np.zeros((0, 2))).tolist()]
    nav = read_nav_log(args.nav)
    rep, series = compute(data, nav, outages)
    if args.scenario:
        from tools.sim import run, trajectory  # run imports this module
        scen = trajectory.load_scenario(run.scenario_path(args.scenario))
        imu, odo = run.sensor_specs(scen, scen.get("sim", {}).get("imu", "mid-grade"),
                                    scen["vehicle"])
        hdg = run.heading_command_deg(float(data["heading_rad"][0]), scen)
        rep["truth"] = run.scenario_truths(scen, float(data["heading_rad"][0]), imu, odo, hdg)
        cal = scen.get("calibration")
        rep["calibration"] = (calibration_report(data, series, read_calibration_log(args.nav),
                                                 cal, rep["truth"]) if cal else None)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "report.json").write_text(json.dumps(rep, indent=2))
    plot(data, series, None, outages, out, Path(args.out).name,
         marks=calibration_marks(rep.get("calibration")))
    print(summary_table(rep))


if __name__ == "__main__":
    main()
