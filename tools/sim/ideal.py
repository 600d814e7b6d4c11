"""What the simulated receiver alone allows: the horizontal RMS error of a navigator whose
dead reckoning is perfect (issue #18, a reference for `make sim-seeds`).

    python -m tools.sim.ideal [--scenario default] [--seeds 1-8] [--above M]

A navigator that knows the car's motion exactly still has to place it on the Earth, and
only the GNSS fixes do that. Its position error is then one constant c (where its dead
reckoning started) and each fix measures y = b - c + w: b the receiver's correlated
error (a first-order Gauss-Markov process, sigma_gm per axis, correlation time tau), w its
white error (sigma_w). The best causal estimate of c from the fixes so far is the Kalman
filter on the states (c, b) with exactly the simulator's model (tools/sim/sensors.py,
gnss_epochs); its error is what no navigator fed those fixes can be sure to beat, whatever
its IMU and odometer. It is not a strict bound for each seed (another estimator can be
luckier on one realisation), but the model-matched estimator's error on that realisation:
over a drive of T s the receiver's slow error still averages to about sqrt(2 tau / T)
sigma_gm per axis, and on an unlucky seed much more. At the end of an outage its error is
the one it had at the start: what the firmware's error there has beyond it is its own
dead reckoning's.

The epochs and their errors are those tools.sim.run gives the firmware (the same
trajectory, preset and seed, 3 x seed + 2); the fixes the simulator marks as outliers are
left out (this navigator knows them), fixes in an outage do not exist. The error is taken
once per second from the first fix to the drive's end (in an outage the estimate is held:
a perfect dead reckoning does not drift), the same span as the firmware's RMS while it
navigates.
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
    """(GNSS preset, trajectory) of a scenario; no trajectory without GNSS."""
    scen = scenario.load(scen_name)
    _, gnss_name = scenario.preset_names(scen, None, None)
    spec = sensors.GNSS_PRESETS[gnss_name]
    return spec, (trajectory.generate(scen, IMU_RATE_HZ) if spec.enabled else None)


def receiver_limited(scen_name: str, seed: int) -> dict | None:
    """The perfect dead reckoning on one seed of a scenario (None without GNSS):
    rms_m, its horizontal RMS error; outage_end_m, its error at the end of the longest
    GNSS outage (by distance, the one tools.sim.seeds reports; that at its start, as the
    dead reckoning does not drift), None without an outage."""
    spec, truth = _drive(scen_name)
    if truth is None:
        return None
    g = sensors.gnss_epochs(truth, spec, 3 * seed + 2)
    use = np.asarray(g["valid"], dtype=bool) & ~np.asarray(g["outlier"], dtype=bool)
    t = np.asarray(g["t_s"], dtype=float)
    if not use.any():
        return None
    est = np.column_stack([offset_estimates(t, g["err_enu_m"][:, ax], use, spec.pos_white_h_m,
                                            spec.pos_gm_h_m, spec.pos_gm_corr_time_s)
                           for ax in (0, 1)])
    herr = np.hypot(est[:, 0], est[:, 1])

    def at(when_s):       # the estimate of the latest epoch at each time
        return herr[np.clip(np.searchsorted(t, when_s, side="right") - 1, 0, None)]

    first = t[np.argmax(use)]
    grid = np.arange(first, float(truth.t_s[-1]) + 1e-9, EVAL_STEP_S)
    out = {"rms_m": float(math.sqrt(np.mean(at(grid) ** 2))), "outage_end_m": None}
    outs = [(a, b) for (a, b, *_label) in truth.outages]
    if outs:
        dist = np.interp(np.array(outs), truth.t_s, truth.dist_m)
        a, b = outs[int(np.argmax(dist[:, 1] - dist[:, 0]))]
        out["outage_end_m"] = float(at(b))
    return out


def main(argv=None) -> int:
    from tools.sim.seeds import parse_seeds
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default="default")
    ap.add_argument("--seeds", nargs="+", default=["1-8"])
    ap.add_argument("--above", type=float, default=None, metavar="M",
                    help="also count the seeds whose RMS is above M m (a limit)")
    a = ap.parse_args(argv)
    vals = {}
    for seed in parse_seeds(a.seeds):
        r = receiver_limited(a.scenario, seed)
        if r is None:
            print(f"{a.scenario} seed {seed}: no GNSS")
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
