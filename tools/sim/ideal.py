"""What the simulated receiver's fixes alone allow: the horizontal RMS error of a
navigator whose dead reckoning is perfect (issue #18, a reference for `make sim-seeds`).

    python -m tools.sim.ideal [--scenario default] [--seeds 1-8] [--start-s 30] [--above M]

A navigator that knows the car's motion exactly still has to place it on the Earth. If
only the GNSS fixes do that, its position error is one constant c (where its dead
reckoning started) and each fix measures y = b - c + w: b the receiver's correlated error
(a first-order Gauss-Markov process, sigma_gm per axis, correlation time tau), w its white
error (sigma_w). The Kalman filter on the states (c, b) with exactly the simulator's model
(tools/sim/sensors.py, gnss_epochs) is the best causal estimate of c from the fixes so far
(it equals generalised least squares over them: tests/python/test_sim_ideal.py). Its error
on a seed is the model-matched expectation for that seed's fixes, not a strict bound:
another estimator can be luckier on one realisation, and the firmware gets more than the
fixes (tools.sim.run commands its start at the true position). The end of a drive of T s
leaves sigma_gm sqrt(2 tau / (T + 2 tau)) per axis (the best estimate of the process's
mean); the RMS over the drive of the estimates as they come is larger, about sigma_gm
sqrt((2 tau / T) ln(1 + T / (2 tau))) per axis. At the end of an outage the perfect dead
reckoning's error is the one it had at the start: what the firmware's error there has
beyond it is its own dead reckoning's.

The epochs and their errors are those tools.sim.run gives the firmware: the same
trajectory at IMU_RATE_HZ (run.py's default), the scenario's GNSS preset and the fixes'
seed (sensors.drive_seeds); the fixes the simulator marks as outliers are left out (this
navigator knows them), fixes in an outage do not exist. Scenarios whose fixes are more
than the preset's ([gnss_faults], a [calibration] epoch, [gnss_raw]) have no reference
(None). The error is taken once per second from the navigation's start (report.json's
navigation_start_s, or the first fix) to the drive's end (in an outage the estimate is
held: a perfect dead reckoning does not drift), the span of the firmware's RMS.
"""
from __future__ import annotations

import argparse
import functools
import math

import numpy as np

from tools.sim import scenario, sensors, trajectory

IMU_RATE_HZ = 100     # tools.sim.run's default; the GNSS errors do not depend on it
EVAL_STEP_S = 1.0
PRIOR_C_M = 1e4       # the start's offset: nothing known before the first fix


def offset_estimates(t_s, y_m, use, sigma_w_m: float, sigma_gm_m: float,
                     tau_s: float) -> np.ndarray:
    """Per epoch, the estimate of the constant offset c after the fixes up to it, from
    y = b - c + w on one axis (b a Gauss-Markov process of sigma_gm_m and tau_s, w white of
    sigma_w_m); epochs with use False are not measured (the estimate is carried)."""
    t_s, y_m = np.asarray(t_s, dtype=float), np.asarray(y_m, dtype=float)
    x = np.zeros(2)                                   # (c, b)
    p = np.diag([PRIOR_C_M ** 2, sigma_gm_m ** 2])
    h = np.array([-1.0, 1.0])
    out = np.zeros(t_s.size)
    prev = t_s[0] if t_s.size else 0.0
    for i in range(t_s.size):
        phi = math.exp(-(t_s[i] - prev) / tau_s) if tau_s > 0.0 else 0.0
        prev = t_s[i]
        x[1] *= phi
        p[1, :] *= phi
        p[:, 1] *= phi
        p[1, 1] += sigma_gm_m ** 2 * (1.0 - phi * phi)
        if use[i]:
            s = h @ p @ h + sigma_w_m ** 2
            k = p @ h / s
            x = x + k * (y_m[i] - h @ x)
            p = p - np.outer(k, h @ p)
        out[i] = x[0]
    return out


@functools.lru_cache(maxsize=4)
def _drive(scen_name: str) -> tuple:
    """(GNSS preset, trajectory) of a scenario; no trajectory without a reference (no GNSS,
    or fixes that are not only the preset's)."""
    scen = scenario.load(scen_name)
    _, gnss_name = scenario.preset_names(scen, None, None)
    spec = sensors.GNSS_PRESETS[gnss_name]
    more = (scen.get("gnss_faults") or scen.get("calibration")
            or scen.get("gnss_raw", {}).get("enabled"))
    if not spec.enabled or more:
        return spec, None
    return spec, trajectory.generate(scen, IMU_RATE_HZ)


def receiver_limited(scen_name: str, seed: int, start_s: float | None = None) -> dict | None:
    """The perfect dead reckoning on one seed of a scenario (None without a reference):
    rms_m, its horizontal RMS error from start_s (the navigation's start; None: the first
    usable fix) to the end; outage_end_m, its error at the end of the longest GNSS outage
    (by distance, the one tools.sim.seeds reports; that at its start, as the dead reckoning
    does not drift), None without an outage or when no fix came before its end."""
    spec, truth = _drive(scen_name)
    if truth is None:
        return None
    g = sensors.gnss_epochs(truth, spec, sensors.drive_seeds(seed)[2])
    use = np.asarray(g["valid"], dtype=bool) & ~np.asarray(g["outlier"], dtype=bool)
    t = np.asarray(g["t_s"], dtype=float)
    if not use.any():
        return None
    est = np.column_stack([offset_estimates(t, g["err_enu_m"][:, ax], use, spec.pos_white_h_m,
                                            spec.pos_gm_h_m, spec.pos_gm_corr_time_s)
                           for ax in (0, 1)])
    herr = np.hypot(est[:, 0], est[:, 1])
    first = float(t[np.argmax(use)])

    def at(when_s):       # the estimate of the latest epoch at each time
        return herr[np.clip(np.searchsorted(t, when_s, side="right") - 1, 0, None)]

    t0 = first if start_s is None else max(first, float(start_s))
    grid = np.arange(t0, float(truth.t_s[-1]) + 1e-9, EVAL_STEP_S)
    out = {"rms_m": float(math.sqrt(np.mean(at(grid) ** 2))), "outage_end_m": None}
    longest = truth.longest_outage()
    if longest is not None and longest[1] >= first:
        out["outage_end_m"] = float(at(longest[1]))
    return out


def main(argv=None) -> int:
    from tools.sim.seeds import parse_seeds
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default="default")
    ap.add_argument("--seeds", nargs="+", default=["1-8"])
    ap.add_argument("--start-s", type=float, default=30.0,
                    help="the navigation's start (s): the RMS from then on (default 30, "
                         "tools.sim.run's levelling on the scenarios of make sim-seeds)")
    ap.add_argument("--above", type=float, default=None, metavar="M",
                    help="also count the seeds whose RMS is above M m (a limit)")
    a = ap.parse_args(argv)
    vals = {}
    for seed in parse_seeds(a.seeds):
        r = receiver_limited(a.scenario, seed, a.start_s)
        if r is None:
            print(f"{a.scenario} seed {seed}: no reference (no GNSS, or fixes beyond the "
                  "preset's)")
            continue
        end = "" if r["outage_end_m"] is None else \
            f", at the longest outage's end {r['outage_end_m']:.2f} m"
        print(f"{a.scenario} seed {seed}: perfect dead reckoning's RMS {r['rms_m']:.2f} m{end}",
              flush=True)
        vals[seed] = r["rms_m"]
    if vals:
        v = np.array(list(vals.values()))
        worst = max(vals, key=vals.get)
        line = (f"{a.scenario}, {v.size} seeds: median {np.median(v):.2f} m, 90th percentile "
                f"{np.percentile(v, 90):.2f} m, worst {v.max():.2f} m (seed {worst})")
        if a.above is not None:
            line += f", {int(np.sum(v > a.above))} above {a.above:g} m"
        print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
