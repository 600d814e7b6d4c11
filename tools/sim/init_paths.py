"""Every initialisation path of issue #17, measured on the simulator (`make init-paths`).

Each path is one tools.sim.run invocation (its command is printed in the table) with an
automotive-MEMS and a mid-grade IMU, standalone GNSS, on the inmotion drives (a 5-s stop,
15 m/s or 30 m/s straight, a 90 deg turn, straight: tools/sim/scenarios/inmotion*.toml).
For each: the time from the event (power-on, the start command, a Reset) to the first
NAV_Position after it, the horizontal error 30 s and 60 s after the event and its largest
value from 30 s on, the largest heading error from 60 s on, and the transition check of
tools/sim/report.py (each position's error against 3 x the HorizAccuracy of the last
NAV_Status before it; positions after a status that says the ECU is not navigating).

The limits are the issue's: output within 15 s while driving (from rest: the levelling,
or the drive-off plus 15 s), error <= 3 m from 30 s on, heading <= 1
deg from 60 s on, error <= 3 sigma throughout, no position while not navigating. A path
that breaks one is marked FAIL (the exit status is 1).

    python -m tools.sim.init_paths [--imu automotive mid-grade] [--out out/sim/init_paths]
    [--md FILE] (writes the table as markdown too)
"""
import argparse
import json
import sys
from pathlib import Path

from tools.sim import run

ROOT = Path(__file__).resolve().parents[2]

# (path, scenario, the event's time in the drive (s), run.py options beyond --scenario/--imu,
# the limit of the time to the first output (s): 15 s while driving (the issue's); from
# rest, the 30-s levelling, or the drive-off at 40 s plus the 15 s of an in-motion start)
PATHS = [
    ("power-on at rest, GNSS only (no command), drive-off at 40 s", "rest-start", 0.0,
     ["--power-on-s", "0"], 55.0),
    ("SetInitialPosition with heading, at rest", "rest-start", 0.0, [], 31.0),
    ("SetInitialPosition, HeadingValid 0, at rest, drive-off at 40 s", "rest-start", 0.0,
     ["--no-heading"], 55.0),
    ("SetInitialPosition with heading, drive-off at 5 s during levelling", "inmotion", 0.0,
     [], 20.0),
    ("power-on at 15 m/s, straight", "inmotion", 30.0, ["--power-on-s", "30"], 15.0),
    ("power-on at 15 m/s, in the 90 deg turn", "inmotion", 80.0, ["--power-on-s", "80"], 15.0),
    ("power-on at 30 m/s, straight", "inmotion30", 40.0, ["--power-on-s", "40"], 15.0),
    ("Reset at 15 m/s, straight", "inmotion", 30.0, ["--reset-s", "30"], 15.0),
    ("Reset at 15 m/s, in the turn", "inmotion", 80.0, ["--reset-s", "80"], 15.0),
    ("Reset at 30 m/s, straight", "inmotion30", 50.0, ["--reset-s", "50"], 15.0),
    ("Reset at 30 m/s, in the turn", "inmotion30", 95.0, ["--reset-s", "95"], 15.0),
]
LIMITS = {"max_error_from_30s_m": 3.0,
          "max_heading_error_from_60s_deg": 1.0, "max_error_over_sigma": 3.0,
          "positions_not_navigating": 0}


def measure(path, scen, t_event, opts, first_limit_s, imu, out: Path, navecu: str) -> dict:
    """One path with one IMU: run.main into out, the figures of its report.json."""
    argv = ["--scenario", scen, "--imu", imu, "--gnss", "standalone", *opts,
            "--out", str(out), "--navecu", navecu]
    rc = run.main(argv)
    cmd = "python -m tools.sim.run " + " ".join(a for a in argv[:-4])
    row = {"path": path, "imu": imu, "command": cmd, "event_s": t_event, "rc": rc}
    if rc != 0:
        row["fail"] = ["run failed"]
        return row
    rep = json.loads((out / "report.json").read_text())
    if rep.get("power_on"):
        ev = rep["power_on"]
    elif rep.get("resets"):
        ev = rep["resets"][0]
    else:   # a start command at 0: the first navigation from it
        from tools.sim import report
        truth = run.trajectory.generate(run.scenario.load(scen), 100)
        nav = report.read_nav_log(out / "nav.log", wraps_from_log=True)
        truth_r = {"t_s": truth.t_s, "lat_rad": truth.lat_rad, "lon_rad": truth.lon_rad,
                   "heading_rad": truth.heading_rad, "dist_m": truth.dist_m}
        _, series = report.compute(truth_r, nav, truth.outages)
        ev = report.power_on_report(truth_r, series, t_event)
    tr = rep["transitions"]
    row.update({k: ev.get(k) for k in ("speed_mps", "first_output_s", "error_at_30s_m",
                                       "error_at_60s_m", "max_error_from_30s_m",
                                       "max_heading_error_from_60s_deg", "output_stopped")})
    row.update({"max_error_over_sigma": tr["max_error_over_sigma"],
                "positions_not_navigating": tr["positions_not_navigating"],
                "positions_without_status": tr["positions_without_status"]})
    fails = []
    for k, lim in dict(LIMITS, first_output_s=first_limit_s).items():
        v = row.get(k)
        if v is None or v > lim:
            fails.append(f"{k} {v} (limit {lim})")
    if row.get("output_stopped") is False:
        fails.append("the output did not stop at the Reset")
    row["fail"] = fails
    return row


def _f(v, fmt):
    return "-" if v is None else format(v, fmt)


def table(rows) -> str:
    lines = ["| path | IMU | speed | first output | error at 30 s / 60 s | max error from 30 s "
             "| heading from 60 s | max error / sigma | positions not navigating | result "
             "| command |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['path']} | {r['imu']} | {_f(r.get('speed_mps'), '.1f')} m/s "
            f"| {_f(r.get('first_output_s'), '.2f')} s "
            f"| {_f(r.get('error_at_30s_m'), '.2f')} / {_f(r.get('error_at_60s_m'), '.2f')} m "
            f"| {_f(r.get('max_error_from_30s_m'), '.2f')} m "
            f"| {_f(r.get('max_heading_error_from_60s_deg'), '.2f')} deg "
            f"| {_f(r.get('max_error_over_sigma'), '.2f')} "
            f"| {r.get('positions_not_navigating', '-')} "
            f"| {'PASS' if not r['fail'] else 'FAIL: ' + '; '.join(r['fail'])} "
            f"| `{r['command']}` |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--imu", nargs="+", default=["automotive", "mid-grade"])
    ap.add_argument("--out", default=str(ROOT / "out" / "sim" / "init_paths"))
    ap.add_argument("--navecu", default=str(ROOT / "build" / "host" / "navecu"))
    ap.add_argument("--md", default=None, help="also write the table to this markdown file")
    a = ap.parse_args(argv)
    out = Path(a.out)
    rows = []
    for k, (path, scen, t_ev, opts, first_s) in enumerate(PATHS):
        for imu in a.imu:
            rows.append(measure(path, scen, t_ev, opts, first_s, imu, out / f"{k:02d}-{imu}",
                                a.navecu))
    (out / "init_paths.json").write_text(json.dumps(rows, indent=2))
    md = table(rows)
    print()
    print(md)
    if a.md:
        Path(a.md).write_text(md + "\n")
    bad = [r for r in rows if r["fail"]]
    print(f"\ninit paths: {len(rows) - len(bad)} of {len(rows)} within the limits "
          f"({out / 'init_paths.json'})")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
