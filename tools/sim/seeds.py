"""The simulator over many seeds, not one (issue #18, `make sim-seeds`).

    python -m tools.sim.seeds [--seeds 1-8] [--scenarios default dgnss outage5 outage5-automotive]
                              [--jobs 2] [--out out/sim/seeds] [--md FILE]
    python -m tools.sim.seeds --merge A/seeds.json B/seeds.json ... [--md FILE]

Each scenario runs once per seed through tools.sim.run (a subprocess: `python -m
tools.sim.run --scenario S --seed N --out OUT/S/seedN`, its stdout in OUT/S/seedN/run.txt),
at most --jobs at a time. run.py's default seed is 1, so the default seeds 1-8 include the
one every single-run figure of the docs was measured with, plus seven others.

The figures of merit, from each run's report.json (tools/sim/report.py):
  rms_m         horizontal_error_m.rms: RMS horizontal error while navigating
  outage_pct    outages[longest].end_error_pct_of_distance: the error at the end of the
                (longest) GNSS outage as % of the distance driven in it
  within_2sigma_pct  sigma_consistency.frac_within_2sigma x 100: share of the epochs whose
                error <= 2 x NAV_Status HorizAccuracy
  height_rms_m  height.error_m.rms: RMS of NAV_Height's Height against the truth's
  height_within_2sigma_pct  height.frac_within_2sigma x 100: share of the NAV_Height epochs
                with a known VertAccuracy whose |error| <= 2 x VertAccuracy (no limit in
                issue #18; the vertical claim checked as the horizontal one is)
and, per seed, whether the reported accuracy follows the error (recomputed from nav.log and
truth.npz over the same epochs as the sigma consistency):
  hacc_spearman Spearman rank correlation of HorizAccuracy and the horizontal error over the
                epochs (1: the sigma rises and falls with the error; a constant sigma has
                none: None)
  hacc_cv_ratio the sigma's coefficient of variation over the error's (std/mean of each):
                0 for a constant sigma whatever the error
and across the seeds of a scenario (across_seeds): the range of the seeds' mean
HorizAccuracy beside that of their RMS errors, and the ratio of the two coefficients of
variation over the seeds: 0 when every seed reports the same sigma whatever its error.
  ideal_rms_m   the model-matched expectation from the seed's fixes: the RMS horizontal
                error of a navigator with a perfect dead reckoning that has only the fixes
                and knows the simulator's receiver model (tools/sim/ideal.py; from the
                navigation's start), beside rms_m. Not a strict bound (the firmware beats
                it on some seeds), but a limit well below it is not one to expect on that
                seed
  ideal_outage_m  that navigator's error at the longest outage's end (the one it had at
                its start), beside outage_m: what the fixes before it left
Rows keep the scenario as given (scenario_arg) and navigation_start_s for them.
For each scenario the median and the worst (largest error, smallest share or correlation)
over the seeds, beside issue #18's limits with PASS / FAIL. Writes OUT/seeds.json and prints
the tables (also to --md). It is a benchmark: the exit status is 0 when a limit is not met,
1 only when a run crashed or gave no report.

--merge runs nothing: it joins the seeds of earlier sweeps (each scenario's rows of every
file, a seed given twice taken from the last file), computes the perfect dead reckoning
afresh for every row (from the row's scenario_arg, else the scenario's name, and its
navigation_start_s, else its report.json's; None where that fails), prints the same tables
(also to --md) and the summary line, and writes no seeds.json; --seeds, --scenarios,
--jobs and --out do not apply. Its exit status is 1 when a joined row is a failed run.
"""
from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from tools.sim import ideal

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ["default", "dgnss", "outage5", "outage5-automotive"]
DEFAULT_SEEDS = "1-8"

# figure -> (how the worst is taken: max or min, unit, label)
FIGURES = {
    "rms_m": (max, "m", "RMS horizontal error"),
    "ideal_rms_m": (max, "m", "RMS of a perfect dead reckoning from the fixes (model-matched)"),
    "outage_pct": (max, "%", "error at the outage's end, % of its distance"),
    "within_2sigma_pct": (min, "%", "epochs within 2 x HorizAccuracy"),
    "height_rms_m": (max, "m", "RMS height error"),
    "height_within_2sigma_pct": (min, "%", "epochs within 2 x VertAccuracy"),
    "hacc_spearman": (min, "", "Spearman(HorizAccuracy, error)"),
    "hacc_cv_ratio": (min, "", "CV(HorizAccuracy) / CV(error)"),
}
# issue #18's limits: scenario -> figure -> {"median"|"worst": (op, value)}
SIGMA_EVERY_SEED = {"worst": (">=", 90.0)}
LIMITS = {
    "default": {"rms_m": {"median": ("<=", 1.5), "worst": ("<=", 2.5)},
                "within_2sigma_pct": SIGMA_EVERY_SEED},
    "dgnss": {"rms_m": {"median": ("<=", 0.5)}, "within_2sigma_pct": SIGMA_EVERY_SEED},
    "outage5": {"outage_pct": {"worst": ("<=", 0.05)}, "within_2sigma_pct": SIGMA_EVERY_SEED},
    "outage5-automotive": {"outage_pct": {"median": ("<=", 1.0), "worst": ("<=", 1.5)},
                           "within_2sigma_pct": SIGMA_EVERY_SEED},
}


def parse_seeds(items) -> list:
    """'1-8', '1,3,5', '1-4,9' or several such words -> sorted distinct seeds."""
    out = set()
    for item in items:
        for part in str(item).replace(" ", ",").split(","):
            if not part:
                continue
            if "-" in part:
                lo, hi = (int(x) for x in part.split("-", 1))
                if hi < lo:
                    raise ValueError(f"seed range {part}: end before start")
                out.update(range(lo, hi + 1))
            else:
                out.add(int(part))
    if not out:
        raise ValueError("no seeds")
    return sorted(out)


def rankdata(x) -> np.ndarray:
    """Ranks 1..n of x, ties given their average rank (scipy.stats.rankdata's default)."""
    x = np.asarray(x, dtype=float)
    order = np.argsort(x, kind="stable")
    ranks = np.empty(x.size)
    ranks[order] = np.arange(1, x.size + 1)
    _, inv, counts = np.unique(x, return_inverse=True, return_counts=True)
    sums = np.bincount(inv, weights=ranks)
    return (sums / counts)[inv]


def spearman(a, b) -> float | None:
    """Spearman rank correlation of a and b; None when either is constant or n < 3."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.size < 3 or np.ptp(a) == 0.0 or np.ptp(b) == 0.0:
        return None
    return float(np.corrcoef(rankdata(a), rankdata(b))[0, 1])


def _cv(x) -> float:
    m = float(np.mean(x))
    return float(np.std(x)) / m if m > 0 else math.nan


def sigma_follows_error(sigma, herr) -> dict:
    """Does the reported accuracy follow the actual error: Spearman rank correlation of the
    two over the epochs, and the ratio of their coefficients of variation."""
    sigma, herr = np.asarray(sigma, dtype=float), np.asarray(herr, dtype=float)
    cv_s, cv_e = (_cv(sigma), _cv(herr)) if sigma.size else (math.nan, math.nan)
    ratio = cv_s / cv_e if np.isfinite(cv_s) and np.isfinite(cv_e) and cv_e > 0 else None
    return {"epochs": int(sigma.size), "hacc_spearman": spearman(sigma, herr),
            "hacc_cv_ratio": ratio,
            "sigma_mean_m": float(sigma.mean()) if sigma.size else None,
            "sigma_min_m": float(sigma.min()) if sigma.size else None,
            "sigma_max_m": float(sigma.max()) if sigma.size else None,
            "error_min_m": float(herr.min()) if herr.size else None,
            "error_max_m": float(herr.max()) if herr.size else None}


def epoch_sigma_and_error(out: Path) -> tuple:
    """(HorizAccuracy, horizontal error) at each NAV_Position of a run's nav.log, the epochs
    report.sigma_consistency uses (a page-0 sigma at most 1 s old, not 'unknown', not 0)."""
    from tools.sim import report
    tr = np.load(out / "truth.npz")
    truth = {k: tr[k] for k in ("t_s", "lat_rad", "lon_rad", "heading_rad", "dist_m")}
    nav = report.read_nav_log(out / "nav.log", wraps_from_log=True)
    _, series = report.compute(truth, nav, [tuple(o) for o in tr["outages"]])
    if "t" not in series:
        return np.zeros(0), np.zeros(0)
    ts, sg = report.status_page(nav.get("NAV_Status"), 0, "HorizAccuracy")
    sig = report.latest_at(ts, sg, series["t"], report.SIGMA_MAX_AGE_S)
    ok = (np.isfinite(sig) & (sig < report.HORIZ_ACCURACY_UNKNOWN_M - 0.005) & (sig > 0.0))
    return sig[ok], np.asarray(series["herr"])[ok]


def figures_of(rep: dict) -> dict:
    """The figures of merit of one report.json."""
    sc = rep.get("sigma_consistency") or {}
    outs = [o for o in rep.get("outages") or [] if o.get("distance_m")]
    longest = max(outs, key=lambda o: o["distance_m"]) if outs else None
    frac = sc.get("frac_within_2sigma")
    hgt = rep.get("height") or {}
    hfrac = hgt.get("frac_within_2sigma")
    return {"rms_m": (rep.get("horizontal_error_m") or {}).get("rms"),
            "height_rms_m": (hgt.get("error_m") or {}).get("rms"),
            "height_within_2sigma_pct": None if hfrac is None else 100.0 * hfrac,
            "outage_pct": longest.get("end_error_pct_of_distance") if longest else None,
            "outage_m": longest.get("end_error_m") if longest else None,
            "outage_distance_m": longest.get("distance_m") if longest else None,
            "within_2sigma_pct": None if frac is None else 100.0 * frac,
            "median_error_over_sigma": sc.get("median_error_over_sigma"),
            "sigma_median_m": sc.get("sigma_median_m")}


def reference(scen: str, seed: int, start_s) -> dict:
    """ideal_rms_m and ideal_outage_m of one seed (None: no reference for the scenario)."""
    ref = ideal.receiver_limited(scen, seed, start_s) or {}
    return {"ideal_rms_m": ref.get("rms_m"), "ideal_outage_m": ref.get("outage_end_m")}


def run_one(scen: str, seed: int, out: Path, navecu: str) -> dict:
    """One seed of one scenario: tools.sim.run as a subprocess into out, then its figures."""
    out.mkdir(parents=True, exist_ok=True)
    argv = ["--scenario", scen, "--seed", str(seed)]
    row = {"seed": seed, "command": "python -m tools.sim.run " + " ".join(argv),
           "out": str(out), "error": None, "scenario_arg": scen}
    t0 = time.monotonic()
    with open(out / "run.txt", "w") as log:
        res = subprocess.run([sys.executable, "-m", "tools.sim.run", *argv, "--out", str(out),
                              "--navecu", navecu], cwd=ROOT, stdout=log,
                             stderr=subprocess.STDOUT)
    row["run_s"] = round(time.monotonic() - t0, 1)
    row["rc"] = res.returncode
    if res.returncode != 0 or not (out / "report.json").exists():
        row["error"] = f"tools.sim.run exit status {res.returncode} (see {out / 'run.txt'})"
        return row
    try:
        rep = json.loads((out / "report.json").read_text())
        row.update(figures_of(rep))
        row.update(sigma_follows_error(*epoch_sigma_and_error(out)))
        row["navigation_start_s"] = rep.get("navigation_start_s")
        row.update(reference(scen, seed, row["navigation_start_s"]))
    except Exception as e:   # noqa: BLE001 - a crash of the analysis is reported, exit 1
        row["error"] = f"analysis: {type(e).__name__}: {e}"
    return row


def across_seeds(rows: list) -> dict:
    """Does the reported accuracy differ between seeds as their errors do: the range of each
    seed's mean HorizAccuracy and of its RMS error, and the ratio of their coefficients of
    variation over the seeds (0: the same sigma whatever the seed's error)."""
    ok = [r for r in rows if r.get("sigma_mean_m") is not None and r.get("rms_m") is not None]
    sig = np.array([r["sigma_mean_m"] for r in ok])
    rms = np.array([r["rms_m"] for r in ok])
    out = {"seeds": len(ok), "sigma_mean_m": None, "rms_m": None, "cv_ratio": None}
    if len(ok) >= 2:
        out.update({"sigma_mean_m": [float(sig.min()), float(sig.max())],
                    "rms_m": [float(rms.min()), float(rms.max())]})
        if _cv(rms) > 0:
            out["cv_ratio"] = _cv(sig) / _cv(rms)
    return out


def _check(op: str, v, lim: float) -> bool:
    return v is not None and (v <= lim if op == "<=" else v >= lim)


def summarise(rows: list, limits: dict) -> dict:
    """Per figure: median and worst over the seeds that have it, the limits and PASS/FAIL."""
    out = {}
    for fig, (worst_of, unit, label) in FIGURES.items():
        vals = [r[fig] for r in rows if r.get(fig) is not None]
        lim = limits.get(fig, {})
        if not vals and not lim:
            continue
        s = {"label": label, "unit": unit, "seeds": len(vals),
             "median": float(np.median(vals)) if vals else None,
             "worst": float(worst_of(vals)) if vals else None,
             "worst_seed": None, "limits": {}, "result": None}
        if vals:
            s["worst_seed"] = next(r["seed"] for r in rows if r.get(fig) == s["worst"])
        for stat, (op, value) in lim.items():
            # a seed without the figure (no report) fails its limit
            ok = _check(op, s[stat], value) and len(vals) == len(rows)
            s["limits"][stat] = {"op": op, "value": value, "result": "PASS" if ok else "FAIL"}
        if s["limits"]:
            s["result"] = ("PASS" if all(v["result"] == "PASS" for v in s["limits"].values())
                           else "FAIL")
        out[fig] = s
    return out


def _f(v, fmt=".2f"):
    return "-" if v is None else format(v, fmt)


def _lim(s, stat):
    lim = s["limits"].get(stat)
    return "" if lim is None else f" ({lim['op']} {lim['value']:g} {lim['result']})"


def _height(r: dict) -> str:
    """A seed's height cell: its RMS and share within 2 VertAccuracy, '-' for either
    missing (a seeds.json of before the height, merged)."""
    rms, frac = r.get("height_rms_m"), r.get("height_within_2sigma_pct")
    return ("-" if rms is None else f"{rms:.2f} m") + ", " + ("-" if frac is None else
                                                                f"{frac:.2f} %")


def tables(result: dict) -> str:
    """The summary table (median, worst, limits) and the per-seed table, as markdown."""
    lines = ["| scenario | figure | seeds | median | worst (seed) | result |",
             "|---|---|---|---|---|---|"]
    for name, sc in result["scenarios"].items():
        for fig, s in sc["summary"].items():
            u = f" {s['unit']}" if s["unit"] else ""
            fmt = ".3f" if fig == "outage_pct" else ".2f"
            lines.append(f"| {name} | {s['label']} | {s['seeds']} "
                         f"| {_f(s['median'], fmt)}{u}{_lim(s, 'median')} "
                         f"| {_f(s['worst'], fmt)}{u} (seed {s['worst_seed']}){_lim(s, 'worst')} "
                         f"| {s['result'] or '-'} |")
    lines += ["", "| scenario | mean HorizAccuracy over the seeds | RMS error over the seeds "
              "| CV(sigma) / CV(RMS) across seeds |", "|---|---|---|---|"]
    for name, sc in result["scenarios"].items():
        a = sc["across_seeds"]
        if a["sigma_mean_m"] is None:
            continue
        lines.append(f"| {name} | {a['sigma_mean_m'][0]:.3f}-{a['sigma_mean_m'][1]:.3f} m "
                     f"| {a['rms_m'][0]:.2f}-{a['rms_m'][1]:.2f} m | {_f(a['cv_ratio'], '.4f')} |")
    lines += ["", "| scenario | seed | RMS | perfect DR's RMS | outage end | within 2 sigma "
              "| Spearman(sigma, error) | CV ratio | sigma min-max | error min-max "
              "| height: RMS, within 2 VertAccuracy | run |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, sc in result["scenarios"].items():
        for r in sc["seeds"]:
            if r.get("error"):
                lines.append(f"| {name} | {r['seed']} | ERROR: {r['error']} |||||||||| ")
                continue
            outage = ("-" if r.get("outage_pct") is None else
                      f"{r['outage_m']:.2f} m, {r['outage_pct']:.3f} %"
                      + ("" if r.get("ideal_outage_m") is None else
                         f" (perfect DR {r['ideal_outage_m']:.2f} m)"))
            lines.append(
                f"| {name} | {r['seed']} | {_f(r['rms_m'])} m "
                f"| {_f(r.get('ideal_rms_m'))}{'' if r.get('ideal_rms_m') is None else ' m'} "
                f"| {outage} "
                f"| {_f(r['within_2sigma_pct'], '.1f')} % | {_f(r['hacc_spearman'])} "
                f"| {_f(r['hacc_cv_ratio'])} | {_f(r['sigma_min_m'])}-{_f(r['sigma_max_m'])} m "
                f"| {_f(r['error_min_m'])}-{_f(r['error_max_m'])} m "
                f"| {_height(r)} "
                f"| {r['run_s']:.0f} s |")
    return "\n".join(lines)


def _merged_reference(name: str, r: dict) -> dict:
    """The perfect dead reckoning of a joined row, computed afresh; None where that fails."""
    start = r.get("navigation_start_s")
    try:
        if start is None and r.get("out") and (Path(r["out"]) / "report.json").exists():
            start = json.loads((Path(r["out"]) / "report.json").read_text()).get(
                "navigation_start_s")
        return reference(r.get("scenario_arg", name), r["seed"], start)
    except (Exception, SystemExit) as e:   # noqa: BLE001 - one row's reference, not the merge
        print(f"  {name} seed {r['seed']}: no perfect dead reckoning ({type(e).__name__}: "
              f"{e})", file=sys.stderr)
        return {"ideal_rms_m": None, "ideal_outage_m": None}


def merged(paths) -> dict:
    """The seeds.json of several sweeps as one result: per scenario the rows of every file
    by seed (a later file's row replaces an earlier one's), summaries recomputed."""
    rows, commands = {}, []
    for path in paths:
        res = json.loads(Path(path).read_text())
        commands.append(res.get("command", str(path)))
        for name, sc in res["scenarios"].items():
            for r in sc["seeds"]:
                rows.setdefault(name, {})[r["seed"]] = r
    result = {"issue": 18, "merged": [str(p) for p in paths], "commands": commands,
              "scenarios": {}}
    for name, by_seed in rows.items():
        srows = [by_seed[k] for k in sorted(by_seed)]
        for r in srows:
            if not r.get("error"):
                r.update(_merged_reference(name, r))
        result["scenarios"][name] = {"seeds": srows,
                                     "summary": summarise(srows, LIMITS.get(name, {})),
                                     "across_seeds": across_seeds(srows)}
    result["seeds"] = sorted({r["seed"] for sc in result["scenarios"].values()
                              for r in sc["seeds"]})
    return result


def _summary_line(result: dict, what: str, where: str) -> int:
    """Print the limits not met and the failed runs; the exit status (1: a run failed)."""
    fails = [f"{n} {f}" for n, sc in result["scenarios"].items()
             for f, s in sc["summary"].items() if s["result"] == "FAIL"]
    crashed = [f"{n} seed {r['seed']}" for n, sc in result["scenarios"].items()
               for r in sc["seeds"] if r.get("error")]
    print(f"\nsim seeds: {what}; limits not met: {', '.join(fails) or 'none'}; crashed: "
          f"{', '.join(crashed) or 'none'}{where}")
    return 1 if crashed else 0


def _scenario_name(scen: str) -> str:
    from tools.sim import scenario
    return scenario.load(scen).get("name", Path(scen).stem)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", nargs="+", default=[DEFAULT_SEEDS],
                    help=f"seeds: 1-10, 1,3,5 or a list (default {DEFAULT_SEEDS}: run.py's "
                         "default seed 1 and seven others)")
    ap.add_argument("--scenarios", nargs="+", default=SCENARIOS,
                    help="names in tools/sim/scenarios or .toml files (default: "
                         + " ".join(SCENARIOS) + ")")
    ap.add_argument("--jobs", type=int, default=2, help="runs at a time (default 2)")
    ap.add_argument("--out", default=str(ROOT / "out" / "sim" / "seeds"))
    ap.add_argument("--navecu", default=str(ROOT / "build" / "host" / "navecu"))
    ap.add_argument("--md", default=None, help="also write the tables to this markdown file")
    ap.add_argument("--merge", nargs="+", default=None, metavar="SEEDS_JSON",
                    help="run nothing: the tables over the seeds of these seeds.json files")
    a = ap.parse_args(argv)
    if a.merge:
        result = merged(a.merge)
        md = tables(result)
        print(md)
        if a.md:
            Path(a.md).parent.mkdir(parents=True, exist_ok=True)
            Path(a.md).write_text(md + "\n")
        return _summary_line(result, f"{len(a.merge)} sweeps joined", "")
    try:
        seeds = parse_seeds(a.seeds)
    except ValueError as e:
        ap.error(str(e))
    if a.jobs < 1:
        ap.error("--jobs must be at least 1")
    out = Path(a.out)
    names = [_scenario_name(s) for s in a.scenarios]
    t0 = time.monotonic()
    jobs = [(name, scen, seed) for name, scen in zip(names, a.scenarios) for seed in seeds]
    print(f"sim seeds: {len(a.scenarios)} scenario(s) x {len(seeds)} seed(s) "
          f"({', '.join(map(str, seeds))}), {a.jobs} at a time, into {out}", flush=True)
    rows = {}
    with ProcessPoolExecutor(max_workers=a.jobs) as pool:
        futs = {pool.submit(run_one, scen, seed, out / name / f"seed{seed}", a.navecu):
                (name, seed) for name, scen, seed in jobs}
        for fut in futs:
            name, seed = futs[fut]
            try:
                r = fut.result()
            except Exception as e:   # noqa: BLE001 - the worker itself crashed
                r = {"seed": seed, "error": f"{type(e).__name__}: {e}", "run_s": None}
            rows[(name, seed)] = r
            state = ("ERROR " + r["error"]) if r.get("error") else (
                f"rms {_f(r.get('rms_m'))} m, within 2 sigma "
                f"{_f(r.get('within_2sigma_pct'), '.1f')} %, Spearman "
                f"{_f(r.get('hacc_spearman'))}")
            print(f"  {name} seed {seed}: {state} ({r.get('run_s')} s)", flush=True)
    result = {"issue": 18, "seeds": seeds, "jobs": a.jobs, "navecu": a.navecu,
              "command": "python -m tools.sim.seeds --seeds " + " ".join(a.seeds)
                         + " --scenarios " + " ".join(a.scenarios),
              "scenarios": {}}
    for name in names:
        srows = [rows[(name, s)] for s in seeds]
        result["scenarios"][name] = {"seeds": srows,
                                     "summary": summarise(srows, LIMITS.get(name, {})),
                                     "across_seeds": across_seeds(srows)}
    result["wall_s"] = round(time.monotonic() - t0, 1)
    out.mkdir(parents=True, exist_ok=True)
    (out / "seeds.json").write_text(json.dumps(result, indent=2))
    md = tables(result)
    print()
    print(md)
    if a.md:
        Path(a.md).parent.mkdir(parents=True, exist_ok=True)
        Path(a.md).write_text(md + "\n")
    return _summary_line(result, f"{len(jobs)} runs in {result['wall_s']:.0f} s",
                         f" ({out / 'seeds.json'})")


if __name__ == "__main__":
    sys.exit(main())
