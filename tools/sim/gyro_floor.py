"""What the z gyro's own noise allows through a GNSS outage: the horizontal error at the
outage's end that no navigator can remove (issue #18, a reference for outage5 and
outage5-automotive).

    python -m tools.sim.gyro_floor [--scenario outage5-automotive] [--limit-pct 1.0 1.5]
                                   [--seeds 24] [--heading-sigma-deg D] [--scale-ppm P]
                                   [--turnon-sigma-dph T] [--bias-sigma-dph B]
                                   [--start-rho HT HI TI] [--odometer-rounding]

Through an outage nothing observes the heading: the odometer and the car's constraints
measure speed, not direction, and gravity says nothing of yaw. Whatever the z gyro's error
does after the outage's start that cannot be predicted from before it turns into heading
error, and the heading error into position error across the track. Two parts of the
simulator's gyro (tools/sim/sensors.py) are such:

* the angle random walk, white rate noise of psd q = ARW^2;
* the in-run bias's wander, a first-order Gauss-Markov process of sigma_gm and correlation
  time T: even a navigator that knew its value b0 at the outage's start exactly can only
  predict b0 exp(-t/T); the rest has the covariance
  sigma_gm^2 (exp(-|t1 - t2| / T) - exp(-(t1 + t2) / T)).

A third part is added on request (--scale-ppm): the residual of the z gyro's scale factor
left at the outage's start, a constant s of the given sigma. The rate it reads is (1 + s)
times the true one, so its heading error is s times the heading turned since the start
(the unwrapped heading change, signed: a left and a right turn cancel, a roundabout's
full circle does not), and its position error at the end s g, g the integral of that
heading change times w below: a rank-one term sigma_s^2 g g^T of the covariance,
independent of the other two. A navigator knows it only as well as the turns before the
outage showed it. Likewise on request (--heading-sigma-deg) the heading error at the
outage's start, a constant psi0 of the given sigma: psi0 g0, g0 the integral of w (the
outage's displacement turned by 90 degrees), another rank-one term. And (--bias-sigma-dph)
the error b0 of the navigator's estimate of the in-run bias at the outage's start: the
navigator predicts the bias's mean b exp(-t/T), so that error decays the same way and turns
the heading by b0 T (1 - exp(-t/T)) (bias_gain); with the process's own sigma (nothing
learnt) it makes the known-start wander the stationary process. And (--turnon-sigma-dph)
the error of its estimate of the turn-on bias, constant: b0 t (turnon_gain). The heading
and the two biases at the start may be correlated (--start-rho, the navigator's own
covariance there; outage_floor says in which sense). With any of them, the figure is no
longer the gyro's alone but what any navigator that starts the outage with that knowledge
is left with.

With psi(t) the heading error they make (their integral from the outage's start), the
position error at its end is the integral of psi(s) (v_N(s), -v_E(s)) ds along the
scenario's own trajectory (a heading error turns the velocity: dv = psi x v), so its
covariance is the double integral of w(s1) w(s2)^T C_psi(s1, s2) with w = (v_N, -v_E).
Everything else (the odometer; the scale factor, the heading and the biases at the start
unless asked for) is taken as known exactly, so this is a floor under the expected squared
error of any navigator with this IMU, not a typical figure; per seed it is a distribution: the error at
the outage's end is at least this Gaussian's draw on average, and its median and the chance
of exceeding a limit are printed. The firmware's own error adds everything the floor takes
as known. No seed enters: the covariance is that of the model.
"""
from __future__ import annotations

import argparse
import math

import numpy as np

from tools.sim import scenario, sensors, trajectory

STEP_S = 0.5          # the integrals' step: 600 points over a 5-min outage
DRAWS = 200_000       # draws of the 2-D Gaussian for its median and tail (fixed seed)
RATE_HZ = 100         # tools.sim.run's default IMU rate; the trajectory does not depend on it


def heading_cov(t_s: np.ndarray, arw_rad_rts: float, sigma_gm_rps: float,
                corr_time_s: float) -> np.ndarray:
    """Covariance of the heading error psi(t_i) (rad^2) from the outage's start t = 0 at
    the times t_s (from 0, uniform step): the angle random walk plus the integral of the
    Gauss-Markov bias's unpredictable part (its value at t = 0 known)."""
    t = np.asarray(t_s, dtype=float)
    t1, t2 = np.meshgrid(t, t, indexing="ij")
    c = arw_rad_rts ** 2 * np.minimum(t1, t2)
    if sigma_gm_rps > 0.0 and corr_time_s > 0.0:
        ce = sigma_gm_rps ** 2 * (np.exp(-np.abs(t1 - t2) / corr_time_s)
                                  - np.exp(-(t1 + t2) / corr_time_s))
        a = _integrator(t)
        c = c + a @ ce @ a.T
    return c


def _trapezoid(t_s: np.ndarray) -> np.ndarray:
    """The trapezoid rule's weights over the uniform t_s: the integral is their dot
    product with the samples."""
    t = np.asarray(t_s, dtype=float)
    dt = t[1] - t[0] if t.size > 1 else 0.0
    wgt = np.full(t.size, dt)
    wgt[0] = wgt[-1] = 0.5 * dt
    return wgt


def _integrator(t_s: np.ndarray) -> np.ndarray:
    """A (N x N): psi = A rate, psi_i the integral of a rate sampled at the uniform t_s from
    t_s[0] to t_s[i] (trapezoid rule)."""
    t = np.asarray(t_s, dtype=float)
    dt = t[1] - t[0] if t.size > 1 else 0.0
    a = np.tril(np.ones((t.size, t.size)), 0) * dt
    a[:, 0] *= 0.5
    a[np.arange(t.size), np.arange(t.size)] *= 0.5
    a[0, :] = 0.0
    return a


def bias_gain(t_s: np.ndarray, v_en_mps: np.ndarray, corr_time_s: float) -> np.ndarray:
    """g (m per rad/s, E and N): the position error at the last time that an error b0 in
    the navigator's estimate of the in-run bias at t_s[0] makes, b0 g. The navigator
    predicts the bias's mean, b exp(-t/T), so that error decays the same way: the heading
    error is b0 T (1 - exp(-t/T)), here the integral of b0 exp(-t/T) by the rule
    heading_cov uses (the known-start covariance plus sigma^2 g g^T is then the stationary
    process's, exactly)."""
    t = np.asarray(t_s, dtype=float)
    psi = _integrator(t) @ np.exp(-(t - t[0]) / corr_time_s)
    return _weights(t, v_en_mps).T @ psi


def turnon_gain(t_s: np.ndarray, v_en_mps: np.ndarray) -> np.ndarray:
    """g (m per rad/s, E and N): the position error at the last time that a constant error
    b0 of the navigator's turn-on bias estimate makes, b0 g: the heading error b0 t."""
    t = np.asarray(t_s, dtype=float)
    return _weights(t, v_en_mps).T @ (t - t[0])


def _weights(t_s: np.ndarray, v_en_mps: np.ndarray) -> np.ndarray:
    """w (N x 2): the position error at the last time is the sum of psi_i w_i (a heading
    error turns the velocity; trapezoid rule over the uniform t_s)."""
    return np.column_stack([v_en_mps[:, 1], -v_en_mps[:, 0]]) * _trapezoid(t_s)[:, None]


def position_cov(t_s: np.ndarray, v_en_mps: np.ndarray, c_psi: np.ndarray) -> np.ndarray:
    """2x2 covariance (m^2, E and N) of the position error at the last time from the heading
    error covariance c_psi over t_s and the velocities v_en_mps (N x 2, E and N)."""
    w = _weights(t_s, v_en_mps)
    return w.T @ c_psi @ w


def scale_gain(t_s: np.ndarray, v_en_mps: np.ndarray, heading_rad: np.ndarray) -> np.ndarray:
    """g (m per unit of scale factor, E and N): the position error at the last time that a
    z gyro scale factor residual s makes, s g, from the heading over t_s (rad, clockwise
    from north, any wrapping) and the velocities v_en_mps (N x 2): the heading error is s
    times the heading turned since t_s[0], weighted as position_cov weights psi."""
    turned = np.unwrap(np.asarray(heading_rad, dtype=float))
    return _weights(t_s, v_en_mps).T @ (turned - turned[0])


def rounded_mean(x, q: float, sigma: float) -> np.ndarray:
    """E[round((x + n) / q) q] for n ~ N(0, sigma^2): a reading rounded to the step q after
    white noise of sigma (exactly the rounding when sigma is 0). Noise dithers the rounding:
    its mean error is at most (q / pi) exp(-2 pi^2 sigma^2 / q^2), its Fourier series's
    first term: 0.23 % of a step at half a step of noise, 8.5e-10 of it at one step."""
    x = np.asarray(x, dtype=float)
    if sigma <= 0.0:
        return np.round(x / q) * q
    erf = np.vectorize(math.erf)
    half = 8.0 * sigma + q  # the Gaussian beyond 8 sigma: 1e-15
    j0 = np.floor((x - half) / q)
    out = np.zeros_like(x)
    for i in range(int(2.0 * half / q) + 2):
        j = j0 + i
        hi = erf(((j + 0.5) * q - x) / (sigma * math.sqrt(2.0)))
        lo = erf(((j - 0.5) * q - x) / (sigma * math.sqrt(2.0)))
        out += j * q * 0.5 * (hi - lo)
    return out


def rounding_error(t_s: np.ndarray, v_en_mps: np.ndarray, rear_mps: np.ndarray,
                   mu: float, q: float, noise_mps: float) -> np.ndarray:
    """(E, N) m: the position error at the last time that the wheel speeds' rounding leaves
    a navigator that knows their scale error mu exactly: each rear wheel (rear_mps, N x 2,
    the truth's) read (1 + mu) times, rounded to q after noise_mps of white noise (its mean,
    rounded_mean), the axle's mean compensated by 1 + mu, less the truth's speed, carried
    along the track (v_en_mps's direction) over the uniform t_s. While the speed is constant
    the rounding's error is too: no filter can tell it from the speed."""
    read = rounded_mean((1.0 + mu) * np.asarray(rear_mps, dtype=float), q, noise_mps)
    err = read.mean(axis=1) / (1.0 + mu) - np.asarray(rear_mps, dtype=float).mean(axis=1)
    speed = np.hypot(v_en_mps[:, 0], v_en_mps[:, 1])
    u = np.where(speed[:, None] > 0.0, v_en_mps / np.maximum(speed, 1e-9)[:, None], 0.0)
    return (u * (err * _trapezoid(t_s))[:, None]).sum(axis=0)


def outage_floor(scen_name: str, limits_pct=(), outage: tuple | None = None,
                 scale_ppm: float = 0.0, heading_sigma_deg: float = 0.0,
                 bias_sigma_dph: float = 0.0, turnon_sigma_dph: float = 0.0,
                 start_rho=(0.0, 0.0, 0.0), odometer_rounding: bool = False) -> dict | None:
    """The floor at the end of a scenario's longest outage (by distance; or outage = (a, b)
    s): rms_m, rms_pct of its distance, median_m / median_pct of the 2-D error's size and,
    for each limit in limits_pct, the chance p_above[limit] that it exceeds it; with
    scale_ppm > 0 the z gyro's scale factor residual of that sigma included (scale_rms_m:
    its part alone); with heading_sigma_deg > 0 the heading error at the start of that sigma
    (heading_rms_m: its part alone); with bias_sigma_dph > 0 the in-run bias estimate's
    error at the start of that sigma (bias_rms_m, bias_gain); with turnon_sigma_dph > 0 the
    turn-on bias estimate's (turnon_rms_m, turnon_gain); start_rho: the correlations of
    those three at the start, (heading, turn-on), (heading, in-run), (turn-on, in-run), in
    the floor's sense: the heading error clockwise and each bias the rate that turns it
    (psi' = +b). A filter whose attitude error integrates minus the z gyro's bias (this
    firmware's psi_U, docs/kalman.md) has the heading's correlations with the biases of the
    other sign, the biases' with each other the same. With odometer_rounding the wheel
    speeds' rounding at the scenario's odometer (rounding_error, rounding_m: its size, the
    same on every seed: the draws' mean). None for a scenario without an outage."""
    rht, rhi, rti = (float(x) for x in start_rho)
    corr = np.array([[1.0, rht, rhi], [rht, 1.0, rti], [rhi, rti, 1.0]])
    if not np.all(np.abs(corr) <= 1.0) or np.linalg.eigvalsh(corr).min() < -1e-12:
        raise ValueError(f"start_rho {tuple(start_rho)} is not a correlation matrix's")
    scen = scenario.load(scen_name)
    imu_name, _ = scenario.preset_names(scen, None, None)
    imu = sensors.PRESETS[imu_name]
    _, odo = scenario.sensor_specs(scen, imu_name, scen["vehicle"])
    truth = trajectory.generate(scen, RATE_HZ)
    if outage is not None:
        a, b = (float(x) for x in outage)
        d_m = float(np.diff(np.interp([a, b], truth.t_s, truth.dist_m))[0])
    else:
        longest = truth.longest_outage()
        if longest is None:
            return None
        a, b, d_m = longest
    t = np.arange(0.0, b - a + 1e-9, STEP_S)
    v = np.column_stack([np.interp(a + t, truth.t_s, truth.v_enu_mps[:, i]) for i in (0, 1)])
    c_psi = heading_cov(t, imu.gyro_arw_rad_per_rts, imu.gyro_gm_sigma_rps,
                        imu.gyro_bias_corr_time_s)
    cov = position_cov(t, v, c_psi)
    # the errors at the start asked for, each sigma times its gain g (position error per
    # unit of the error): the scale factor's a rank-one term g g^T independent of the rest;
    # the heading's and the two biases' G S R S G^T with their correlations R
    h = np.interp(a + t, truth.t_s, np.unwrap(truth.heading_rad))  # unwrapped: no seam
    g_scale = scale_gain(t, v, h) * scale_ppm * 1e-6
    cov = cov + np.outer(g_scale, g_scale)
    dph = math.radians(1.0) / 3600.0
    g_start = np.column_stack([
        _weights(t, v).sum(axis=0) * math.radians(heading_sigma_deg),
        turnon_gain(t, v) * turnon_sigma_dph * dph,
        bias_gain(t, v, imu.gyro_bias_corr_time_s) * bias_sigma_dph * dph])
    cov = cov + g_start @ corr @ g_start.T
    parts = {key: float(np.hypot(*g)) for key, g in (
        ("scale_rms_m", g_scale), ("heading_rms_m", g_start[:, 0]),
        ("turnon_rms_m", g_start[:, 1]), ("bias_rms_m", g_start[:, 2]))}
    mean = np.zeros(2)
    if odometer_rounding:
        # the rear axle's wheels (the firmware's default odo_axle) as the simulator makes them
        # (sensors._ideal_wheels), at the floor's times
        s_t = np.interp(a + t, truth.t_s, truth.speed_mps)
        r_t = np.interp(a + t, truth.t_s, truth.yaw_rate_rps)
        rear = sensors._ideal_wheels(s_t, r_t, odo.track_m, odo.wheelbase_m)[:, 2:]
        mean = rounding_error(t, v, rear, odo.mu, odo.quant_mps, odo.noise_mps)
    draws = np.random.default_rng(0).multivariate_normal(mean, cov, size=DRAWS)
    size = np.hypot(draws[:, 0], draws[:, 1])
    rms = math.sqrt(float(np.trace(cov)) + float(mean @ mean))
    med = float(np.median(size))
    return {"imu": imu_name, "outage_s": (float(a), float(b)), "distance_m": d_m,
            "rms_m": rms, "rms_pct": 100.0 * rms / d_m, "median_m": med,
            "median_pct": 100.0 * med / d_m, "scale_ppm": float(scale_ppm),
            "heading_sigma_deg": float(heading_sigma_deg),
            "bias_sigma_dph": float(bias_sigma_dph), "turnon_sigma_dph": float(turnon_sigma_dph),
            "start_rho": (rht, rhi, rti),
            "rounding_m": float(np.hypot(mean[0], mean[1])) if odometer_rounding else None,
            **parts,
            "p_above": {float(lim): float(np.mean(size > lim / 100.0 * d_m))
                        for lim in limits_pct}}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default="outage5-automotive")
    ap.add_argument("--limit-pct", type=float, nargs="*", default=[],
                    help="limits (%% of the outage's distance): the chance of exceeding each")
    ap.add_argument("--seeds", type=int, default=None,
                    help="with --limit-pct: the chance that at least one of this many seeds "
                         "exceeds each limit")
    ap.add_argument("--scale-ppm", type=float, default=0.0,
                    help="include the z gyro's scale factor residual at the outage's start, "
                         "1-sigma in ppm (the IMU preset's figure if nothing was learnt)")
    ap.add_argument("--heading-sigma-deg", type=float, default=0.0,
                    help="include the heading error at the outage's start, 1-sigma in degrees "
                         "(the filter's own, NAV_Accuracy's HeadingAccuracy there)")
    ap.add_argument("--bias-sigma-dph", type=float, default=0.0,
                    help="include the error of the z gyro's in-run bias estimate at the "
                         "outage's start, 1-sigma in deg/h (the filter's own; the process's "
                         "sigma, the IMU's bias instability / 0.617, if nothing was learnt)")
    ap.add_argument("--turnon-sigma-dph", type=float, default=0.0,
                    help="include the error of the z gyro's turn-on (constant) bias estimate "
                         "at the outage's start, 1-sigma in deg/h (the filter's own)")
    ap.add_argument("--start-rho", type=float, nargs=3, default=(0.0, 0.0, 0.0),
                    metavar=("HT", "HI", "TI"),
                    help="the correlations at the outage's start of the heading with the "
                         "turn-on bias, of the heading with the in-run bias and of the two "
                         "biases, in the floor's sense (outage_floor: a filter whose attitude "
                         "error integrates minus the bias gives the first two of the other "
                         "sign)")
    ap.add_argument("--odometer-rounding", action="store_true",
                    help="include the wheel speeds' rounding to their step at the scenario's "
                         "speeds (its odometer's mu, step and noise): the same on every seed")
    a = ap.parse_args(argv)
    r = outage_floor(a.scenario, a.limit_pct, scale_ppm=a.scale_ppm,
                     heading_sigma_deg=a.heading_sigma_deg, bias_sigma_dph=a.bias_sigma_dph,
                     turnon_sigma_dph=a.turnon_sigma_dph, start_rho=a.start_rho,
                     odometer_rounding=a.odometer_rounding)
    if r is None:
        print(f"{a.scenario}: no outage")
        return 1
    s0, s1 = r["outage_s"]
    print(f"{a.scenario} ({r['imu']} IMU), outage {s0:g}-{s1:g} s, {r['distance_m']:.0f} m: "
          f"the z gyro's noise and bias wander"
          + (f" and a {r['scale_ppm']:g} ppm scale factor ({r['scale_rms_m']:.1f} m of it alone)"
             if r["scale_ppm"] > 0.0 else " alone")
          + (f", with a heading {r['heading_sigma_deg']:g} deg off at the start "
             f"({r['heading_rms_m']:.1f} m of it alone)," if r["heading_sigma_deg"] > 0.0 else "")
          + (f" with the turn-on bias {r['turnon_sigma_dph']:g} deg/h off at the start "
             f"({r['turnon_rms_m']:.1f} m of it alone)," if r["turnon_sigma_dph"] > 0.0 else "")
          + (f" with the in-run bias {r['bias_sigma_dph']:g} deg/h off at the start "
             f"({r['bias_rms_m']:.1f} m of it alone)," if r["bias_sigma_dph"] > 0.0 else "")
          + (" correlated {:+g} {:+g} {:+g},".format(*r["start_rho"])
             if any(r["start_rho"]) else "")
          + (f" with the wheel speeds' rounding ({r['rounding_m']:.2f} m, on every seed),"
             if r["rounding_m"] is not None else "")
          + f" leave {r['rms_m']:.1f} m RMS "
          f"({r['rms_pct']:.3f} %), median {r['median_m']:.1f} m ({r['median_pct']:.3f} %)")
    for lim, p in r["p_above"].items():
        line = f"  above {lim:g} %: {100.0 * p:.1f} % of seeds"
        if a.seeds:
            any_p = 1.0 - (1.0 - p) ** a.seeds
            line += f"; at least one of {a.seeds} seeds: {100.0 * any_p:.1f} %"
        print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
