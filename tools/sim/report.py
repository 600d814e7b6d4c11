"""Accuracy report: the firmware's NAV_* output log against the simulated truth.

    python -m tools.sim.report --truth out/sim/default/truth.npz --nav out/sim/default/nav.log \
        --out out/sim/default

Writes report.json and three PNG plots (track map, horizontal error, heading error). The
statistics cover the time the firmware was navigating (NAV_Position present), from the first
NAV_Position frame to the end of the drive. Errors are horizontal distances on the WGS-84
ellipsoid (local radii of curvature), heading errors wrapped to [-180, 180) degrees.
"""
from __future__ import annotations

import argparse
import json
import math
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


def plot(truth: dict, series: dict, gnss, outages, out_dir: Path, title: str) -> list:
    """Track map, horizontal error and heading error PNGs; returns their paths."""
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
        ax.set_xlabel("time (min)")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        if outages:
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
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--truth", required=True, help="truth.npz written by tools.sim.run")
    ap.add_argument("--nav", required=True, help="navecu output log (candump)")
    ap.add_argument("--out", required=True, help="output folder")
    args = ap.parse_args(argv)
    data = dict(np.load(args.truth, allow_pickle=False))
    outages = [tuple(o) for o in data.pop("outages", np.zeros((0, 2))).tolist()]
    nav = read_nav_log(args.nav)
    rep, series = compute(data, nav, outages)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "report.json").write_text(json.dumps(rep, indent=2))
    plot(data, series, None, outages, out, Path(args.out).name)
    print(summary_table(rep))


if __name__ == "__main__":
    main()
