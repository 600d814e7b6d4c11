"""What the z gyro's own noise allows the Kingston dead reckoning after its one-point
calibration (issue #18's `make kingston MODE=dr` <= 0.15 % of distance): a floor drawn by
Monte Carlo on the drive's own route and standstills.

    python -m tools.kingston.dr_floor [--arw-dpsh 0.3] [--bias-dph 5] [--draws 4000]
                                      [--calibrate-at-s 1195] [--limit-pct 0.15]

Without GNSS nothing observes the heading while the car moves; at a standstill the z
gyro's reading is its bias (the Earth's rate known), which the dead reckoning learns as
the posterior mean of a constant with a zero-mean prior (docs/odometry.md, "Standstill":
prior sigma the turn-on bias, each standing second an observation of the bias with the
angle random walk's noise). What that leaves is modelled here, per draw:

* a constant bias b ~ N(0, bias^2) (the configured turn-on sigma, `--bias-dph`);
* the gyro's white rate noise, ARW^2 / dt per second's mean (`--arw-dpsh`), the same
  sequence the standstills observe and the moving seconds integrate;
* the bias estimate at each second: every standing second before it, weighted as above;
* the heading error psi: held at a standstill, grown by (b - estimate) + noise while moving;
* the position error: the reference's own velocity turned by psi, less itself
  (complex north + i east, exp(i psi) z - z), the odometer exact;
* the one-point calibration at --calibrate-at-s (seed 000 eqs 9-10, docs/odometry.md):
  the rotation a and scale 1 + mu that map the dead-reckoned displacement since the start
  onto the true one, the point's position exact; after it the velocity is
  (1 + mu) exp(i (psi - a)) z.

The figure is the report's (tools/kingston/run.py): the largest error after the point over
the distance driven after it. Everything else is exact (the odometer and its scale, the
initial heading up to a constant the calibration removes, the gyro's scale, the in-run
wander, the reference), so this is a floor under any dead reckoning with this gyro, these
standstills and this calibration, not a typical figure. Its defaults are the installation
figures tools/kingston/run.py configures (`SENSORS`: 0.3 deg/sqrt(h), 5 deg/h); the z
gyro's noise measured at the first stop is 0.22 deg/sqrt(h) (`python -m
tools.kingston.analyse`), which `--arw-dpsh 0.22` gives.
"""
from __future__ import annotations

import argparse
import math

import numpy as np

from tools.kingston import convert

DEG = math.pi / 180.0
DPH = DEG / 3600.0                 # deg/h -> rad/s
DPSH = DEG / 60.0                  # deg/sqrt(h) -> rad/sqrt(s)
SEED = 20081  # fixed: the floor is a property of the model, not of a draw
CHUNK = 500   # draws at a time


def route(drive) -> dict:
    """The reference's 1 Hz rows on the log's time base: t_s, z = v_N + i v_E (m/s), the
    travelled distance dist_m, and still (the odometer's reading exactly 0 at that second:
    the dead reckoning's standstill)."""
    ref = convert.reference_track(drive)
    t = ref["t_s"]
    z = drive.ref["vn_mps"] + 1j * drive.ref["ve_mps"]
    o = drive.odo
    t_odo = o["time_s"] - drive.t0_gps
    k = np.clip(np.searchsorted(t_odo, t, side="right") - 1, 0, t_odo.size - 1)
    still = o["speed_mps"][k] == 0.0
    return {"t_s": t, "z": z, "dist_m": ref["dist_m"], "still": still}


def bias_estimates(b, w, still, dt, arw_rad_rts: float, bias_rps: float) -> np.ndarray:
    """The standstill estimate of the bias at each row (draws, n), rad/s: the posterior
    mean of a constant with a zero-mean prior of sigma bias_rps from the standing steps
    *before* the row, each step's reading b + w of variance ARW^2 / dt (docs/odometry.md)."""
    n = np.asarray(dt).size
    obs = np.asarray(still).astype(float) * dt         # seconds of bias seen at each step
    info = np.cumsum(obs) - obs                        # before row k
    s_info = np.cumsum((b + w) * obs, axis=1) - (b + w) * obs
    prior_info = 1.0 / bias_rps ** 2 if bias_rps > 0.0 else math.inf
    if arw_rad_rts > 0.0:
        return (s_info / arw_rad_rts ** 2) / (prior_info + info / arw_rad_rts ** 2)
    # a noiseless gyro: its first standing second gives the bias exactly
    return np.where(info > 0.0, b, 0.0) * np.ones((1, n))


def draw_errors(t_s, z, still, i_cal: int, arw_rad_rts: float, bias_rps: float,
                draws: int, seed: int = SEED) -> np.ndarray:
    """Position errors (draws, n) as complex north + i east, m, of the model in the module
    docstring; i_cal the row of the calibration (its error 0 there and the correction from
    it on)."""
    t = np.asarray(t_s, dtype=float)
    n = t.size
    dt = np.diff(t, append=t[-1])           # row k's step to k + 1 (last: 0)
    dtc = np.where(dt > 0.0, dt, 1.0)
    rng = np.random.default_rng(seed)
    b = bias_rps * rng.standard_normal((draws, 1))
    w = arw_rad_rts / np.sqrt(dtc) * rng.standard_normal((draws, n))   # each step's mean noise
    est = bias_estimates(b, w, still, dt, arw_rad_rts, bias_rps)
    rate = np.where(still, 0.0, (b - est) + w)         # the heading is held at a standstill
    psi = np.concatenate([np.zeros((draws, 1)), np.cumsum(rate * dt, axis=1)[:, :-1]], axis=1)
    dz = (np.exp(1j * psi) - 1.0) * z                  # velocity error before the point
    err = np.concatenate([np.zeros((draws, 1)), np.cumsum(dz * dt, axis=1)[:, :-1]], axis=1)
    d_true = np.sum((z * dt)[:i_cal])                  # the displacement start -> point
    d_dr = d_true + err[:, i_cal]
    ratio = d_true / d_dr                              # (1 + mu) exp(-i a)
    after = (ratio[:, None] * np.exp(1j * psi[:, i_cal:]) - 1.0) * z[i_cal:]
    err_after = np.concatenate([np.zeros((draws, 1)),
                                np.cumsum(after * dt[i_cal:], axis=1)[:, :-1]], axis=1)
    return np.concatenate([err[:, :i_cal], err_after], axis=1)


def floor(drive=None, arw_dpsh: float = 0.3, bias_dph: float = 5.0, draws: int = 4000,
          calibrate_at_s: float = 1195.0, limits_pct=(0.15,)) -> dict:
    """The floor's figures: per draw the largest error after the point over the distance
    after it (%); their median, percentiles and the share above each limit."""
    if drive is None:
        drive = convert.load(None)
    r = route(drive)
    i_cal = int(np.searchsorted(r["t_s"], calibrate_at_s))
    if not 0 < i_cal < r["t_s"].size - 1:
        raise ValueError(f"--calibrate-at-s {calibrate_at_s} is not inside the drive")
    d_after = float(r["dist_m"][-1] - r["dist_m"][i_cal])
    pct = []
    for c, k in enumerate(range(0, draws, CHUNK)):   # in chunks: memory, not the figure
        err = draw_errors(r["t_s"], r["z"], r["still"], i_cal, arw_dpsh * DPSH,
                          bias_dph * DPH, min(CHUNK, draws - k), seed=SEED + c)
        pct.append(100.0 * np.max(np.abs(err[:, i_cal:]), axis=1) / d_after)
    pct = np.concatenate(pct)
    standing = np.diff(r["t_s"], append=r["t_s"][-1]) * r["still"]  # s standing per row
    still_before = float(np.sum(standing[:i_cal]))
    still_all = float(np.sum(standing))
    return {"arw_dpsh": arw_dpsh, "bias_dph": bias_dph, "draws": draws,
            "calibrate_at_s": float(r["t_s"][i_cal]), "distance_after_m": d_after,
            "standing_before_s": still_before, "standing_s": still_all,
            "median_pct": float(np.median(pct)),
            "p16_pct": float(np.percentile(pct, 16)), "p84_pct": float(np.percentile(pct, 84)),
            "above": {float(x): float(np.mean(pct > x)) for x in limits_pct}}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=None, help="the drive's folder (default data/kingston-2008)")
    ap.add_argument("--arw-dpsh", type=float, default=0.3, help="z gyro angle random walk")
    ap.add_argument("--bias-dph", type=float, default=5.0, help="z gyro turn-on bias sigma")
    ap.add_argument("--draws", type=int, default=4000)
    ap.add_argument("--calibrate-at-s", type=float, default=1195.0,
                    help="the one-point calibration's time (tools.kingston.run's at 5 km)")
    ap.add_argument("--limit-pct", type=float, nargs="*", default=[0.15])
    a = ap.parse_args(argv)
    if a.draws < 1 or a.arw_dpsh < 0.0 or a.bias_dph < 0.0:
        ap.error("--draws must be >= 1, --arw-dpsh and --bias-dph >= 0")
    f = floor(convert.load(a.data), a.arw_dpsh, a.bias_dph, a.draws, a.calibrate_at_s,
              a.limit_pct)
    print(f"z gyro ARW {f['arw_dpsh']:g} deg/sqrt(h), turn-on bias sigma {f['bias_dph']:g} deg/h; "
          f"{f['standing_before_s']:.0f} s standing before the point at "
          f"{f['calibrate_at_s']:.0f} s, {f['standing_s']:.0f} s in the drive; {f['draws']} draws")
    print(f"largest error after the point / {f['distance_after_m'] / 1000:.2f} km driven after "
          f"it: median {f['median_pct']:.3f} %, 16-84 % of draws {f['p16_pct']:.3f}-"
          f"{f['p84_pct']:.3f} %")
    for x, share in f["above"].items():
        print(f"  above {x:g} %: {100 * share:.1f} % of draws")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
