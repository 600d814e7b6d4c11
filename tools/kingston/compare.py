"""Where two Kingston runs differ: their horizontal errors against the SPAN reference minute
by minute, and the reference's own consistency in a window.

    python -m tools.kingston.compare RUN_A RUN_B [--top 5] [--window 2255 2345]

RUN_A, RUN_B: output folders of tools.kingston.run (their nav.log). Per minute of the drive
(from the first reference epoch) each run's RMS error and the minute's share of the
difference of the two runs' mean squared errors over the drive, the minutes with the
largest shares first. With --window T0 T1 (s from the drive's start), every 5 s of it: the
reference's position less the integral of its own velocity since T0 (what the reference
cannot both be), and each run's position less that same integral, east and north.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from tools import geodesy
from tools.kingston import analyse, convert
from tools.sim import report


def errors(drive, run_dir: Path) -> tuple:
    """(t, horizontal error) of a run's NAV_Position against the reference, s and m."""
    ref = convert.reference_track(drive)
    pos = report.read_nav_log(run_dir / "nav.log")["NAV_Position"]
    t = pos["t_s"]
    sel = (t >= ref["t_s"][0]) & (t <= ref["t_s"][-1])
    t = t[sel]
    lat = np.interp(t, ref["t_s"], ref["lat_deg"])
    lon = np.interp(t, ref["t_s"], ref["lon_deg"])
    return t, geodesy.horizontal_distance_m(lat, lon, pos["Latitude"][sel],
                                            pos["Longitude"][sel]), pos


def by_minute(ta, ea, tb, eb) -> list:
    """(share of the mean-square difference, minute start s, RMS A, RMS B) per minute."""
    eb_at = np.interp(ta, tb, eb)
    minute = (ta // 60.0).astype(int)
    rows = []
    for m in np.unique(minute):
        k = minute == m
        share = float(np.sum(ea[k] ** 2 - eb_at[k] ** 2) / ta.size)
        rows.append((share, int(m) * 60, float(np.sqrt(np.mean(ea[k] ** 2))),
                     float(np.sqrt(np.mean(eb_at[k] ** 2)))))
    return rows


def window(drive, runs: dict, t0: float, t1: float) -> list:
    """Lines: every 5 s from t0 the reference's and each run's position less the
    reference velocity's integral since t0 (analyse.reference_track), east and north, m."""
    tr = analyse.reference_track(drive)
    t = tr["t_s"]
    tracks = {"reference": (tr["e_m"], tr["n_m"])}
    for name, pos in runs.items():
        e, n = analyse.local_en_m(drive, pos["Latitude"], pos["Longitude"])
        tracks[name] = (np.interp(t, pos["t_s"], e), np.interp(t, pos["t_s"], n))
    i0 = int(np.argmin(np.abs(t - t0)))
    i1 = int(np.argmin(np.abs(t - t1)))
    lines = []
    for i in range(i0, i1 + 1, 5):
        de, dn = tr["ie_m"][i] - tr["ie_m"][i0], tr["in_m"][i] - tr["in_m"][i0]
        parts = [f"{t[i]:6.0f} s"]
        for name, (e, n) in tracks.items():
            parts.append(f"{name} {e[i] - e[i0] - de:+6.2f} {n[i] - n[i0] - dn:+6.2f}")
        lines.append("   ".join(parts))
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run_a", type=Path)
    ap.add_argument("run_b", type=Path)
    ap.add_argument("--data", default=None)
    ap.add_argument("--top", type=int, default=5)
    ap.add_argument("--window", type=float, nargs=2, default=None, metavar=("T0", "T1"))
    a = ap.parse_args(argv)
    drive = convert.load(a.data)
    ta, ea, pa = errors(drive, a.run_a)
    tb, eb, pb = errors(drive, a.run_b)
    rows = sorted(by_minute(ta, ea, tb, eb), reverse=True)
    total = sum(r[0] for r in rows)
    print(f"A {a.run_a}: RMS {math.sqrt(float(np.mean(ea ** 2))):.2f} m; B {a.run_b}: RMS "
          f"{math.sqrt(float(np.mean(eb ** 2))):.2f} m; mean-square difference A - B "
          f"{total:+.4f} m^2")
    print("minutes where A is worse, largest first (share of that difference, RMS A, RMS B):")
    for share, m0, ra, rb in rows[:a.top]:
        print(f"  {m0:5d}-{m0 + 60:5d} s  {share:+.4f} m^2  {ra:.2f} m  {rb:.2f} m")
    if a.window:
        print(f"position less the reference velocity's integral from {a.window[0]:g} s "
              "(east, north, m):")
        for line in window(drive, {"A": pa, "B": pb}, a.window[0], a.window[1]):
            print("  " + line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
