"""tools/sim/gyro_floor.py: the position error a gyro's unpredictable errors leave through
an outage, against closed forms and a Monte Carlo of the process itself."""
import math

import numpy as np
import pytest

from tools.sim import gyro_floor


def straight(t_end_s, speed_mps, step_s=gyro_floor.STEP_S):
    t = np.arange(0.0, t_end_s + 1e-9, step_s)
    v = np.column_stack([np.zeros(t.size), np.full(t.size, speed_mps)])  # due north
    return t, v


def test_angle_random_walk_matches_its_closed_form():
    # white rate noise of psd q: psi is a random walk, the cross-track error of a straight
    # drive at speed v is v q^(1/2) t^(3/2) / sqrt(3) (the integral of a Wiener process)
    q_rts, v, t_end = 1e-4, 15.0, 300.0
    t, vel = straight(t_end, v)
    cov = gyro_floor.position_cov(t, vel, gyro_floor.heading_cov(t, q_rts, 0.0, 100.0))
    want = v * q_rts * t_end ** 1.5 / math.sqrt(3.0)
    assert math.sqrt(cov[0, 0]) == pytest.approx(want, rel=0.01)
    assert cov[1, 1] == pytest.approx(0.0, abs=1e-12)  # along the track: nothing


def test_bias_wander_matches_a_monte_carlo_of_the_process():
    # the Gauss-Markov bias drawn by its exact discretisation from a known start, integrated
    # twice along a straight drive: the spread of its cross-track error is the floor's
    # (4000 runs: the standard error of a standard deviation is 1.1 %, the bound 5 %)
    sigma, tau, v, t_end, dt = 1e-4, 100.0, 15.0, 300.0, gyro_floor.STEP_S
    t, vel = straight(t_end, v)
    cov = gyro_floor.position_cov(t, vel, gyro_floor.heading_cov(t, 0.0, sigma, tau))
    rng = np.random.default_rng(7)
    phi = math.exp(-dt / tau)
    n, runs = t.size, 4000
    b = np.zeros((runs, n))
    for i in range(1, n):
        b[:, i] = phi * b[:, i - 1] + sigma * math.sqrt(1.0 - phi * phi) * rng.standard_normal(runs)
    steps = 0.5 * (b[:, 1:] + b[:, :-1]) * dt
    psi = np.concatenate([np.zeros((runs, 1)), np.cumsum(steps, axis=1)], axis=1)
    w = np.full(n, dt)
    w[0] = w[-1] = 0.5 * dt
    y = v * (psi * w).sum(axis=1)
    assert math.sqrt(cov[0, 0]) == pytest.approx(float(np.std(y)), rel=0.05)


def test_a_known_start_leaves_less_than_an_unknown_one():
    # the unpredictable part of the wander is less than the whole process: what the floor
    # leaves out (the bias at the start) matters, and the floor is below the stationary
    # integral 2 sigma^2 T (t - T (1 - exp(-t/T))) of the heading variance
    sigma, tau, t_end = 1e-4, 100.0, 300.0
    t = np.arange(0.0, t_end + 1e-9, gyro_floor.STEP_S)
    c = gyro_floor.heading_cov(t, 0.0, sigma, tau)
    stationary = 2.0 * sigma ** 2 * tau * (t_end - tau * (1.0 - math.exp(-t_end / tau)))
    assert 0.1 * stationary < c[-1, -1] < 0.9 * stationary


def test_outage5_automotive_floor_is_a_share_of_its_distance():
    r = gyro_floor.outage_floor("outage5-automotive", (1.5,))
    assert r["imu"] == "automotive"
    assert r["distance_m"] == pytest.approx(4924.0, rel=0.01)
    assert 0.0 < r["median_m"] < r["rms_m"] * 1.5
    assert 0.0 < r["p_above"][1.5] < 1.0


def test_scale_factor_gain_matches_a_dead_reckoning_with_the_scale():
    # a car turning at a steady 0.02 rad/s (a slow circle) for 300 s at 15 m/s: its track
    # dead-reckoned with the heading a gyro of scale factor s makes (the heading turned
    # since the start, times 1 + s) ends s g away from the true one, to first order in s
    # (s = 1e-4, 6 rad turned: the second order, V T (s 6)^2 / 2 ~ 1e-4 m, is 3e-4 of the
    # error's size; the bound 0.1 % of it, on each component)
    t = np.arange(0.0, 300.0 + 1e-9, gyro_floor.STEP_S)
    heading = 0.3 + 0.02 * t
    speed, s = 15.0, 1e-4

    def track_end(h):
        v = np.column_stack([speed * np.sin(h), speed * np.cos(h)])
        wgt = np.full(t.size, gyro_floor.STEP_S)
        wgt[0] = wgt[-1] = 0.5 * gyro_floor.STEP_S
        return (v * wgt[:, None]).sum(axis=0)

    v_true = np.column_stack([speed * np.sin(heading), speed * np.cos(heading)])
    g = gyro_floor.scale_gain(t, v_true, np.mod(heading, 2.0 * math.pi))  # unwrapped inside
    err = track_end(heading + s * (heading - heading[0])) - track_end(heading)
    assert np.abs(err - s * g).max() < 1e-3 * np.hypot(*(s * g))
    assert np.hypot(*g) > 1e3  # 6 rad turned over 4.5 km: 4.7 km per unit, not 0


def test_heading_at_the_start_turns_the_whole_outage():
    # a heading error psi0 at the outage's start leaves psi0 times the outage's straight-line
    # displacement across it (to first order): outage5's 800-1100 s, displacement from the
    # truth's own positions
    from tools.sim import scenario, trajectory
    sigma_deg = 0.03
    r0 = gyro_floor.outage_floor("outage5")
    r = gyro_floor.outage_floor("outage5", heading_sigma_deg=sigma_deg)
    truth = trajectory.generate(scenario.load("outage5"), gyro_floor.RATE_HZ)
    i0, i1 = np.searchsorted(truth.t_s, [800.0, 1100.0])
    re = 6378137.0
    de = (truth.lon_rad[i1] - truth.lon_rad[i0]) * re * math.cos(truth.lat_rad[i0])
    dn = (truth.lat_rad[i1] - truth.lat_rad[i0]) * re
    want = math.radians(sigma_deg) * math.hypot(de, dn)
    assert r["heading_rms_m"] == pytest.approx(want, rel=0.01)
    assert r["rms_m"] ** 2 == pytest.approx(r0["rms_m"] ** 2 + want ** 2, rel=0.02)


def test_an_unknown_start_bias_makes_the_stationary_process():
    # the known-start wander plus an unknown start bias of the process's own sigma, decaying
    # as the navigator predicts it (bias_gain), is the stationary Gauss-Markov process: its
    # position covariance along a drive that turns (a slow circle) is the one integrated
    # from sigma^2 exp(-|t1 - t2| / T) directly (the same trapezoid rule: to rounding)
    sigma, tau = 1e-4, 100.0
    t = np.arange(0.0, 300.0 + 1e-9, gyro_floor.STEP_S)
    h = 0.3 + 0.02 * t
    vel = np.column_stack([15.0 * np.sin(h), 15.0 * np.cos(h)])
    known = gyro_floor.position_cov(t, vel, gyro_floor.heading_cov(t, 0.0, sigma, tau))
    g = gyro_floor.bias_gain(t, vel, tau) * sigma
    t1, t2 = np.meshgrid(t, t, indexing="ij")
    a = gyro_floor._integrator(t)
    stationary = gyro_floor.position_cov(
        t, vel, a @ (sigma ** 2 * np.exp(-np.abs(t1 - t2) / tau)) @ a.T)
    assert known + np.outer(g, g) == pytest.approx(stationary, rel=1e-9, abs=1e-12)
    # and the start bias is a real part of it: its gain is the closed form's to 1 %
    # (b0 T (1 - exp(-t/T)) integrated across the track of a straight drive north)
    ts, vs = straight(300.0, 15.0)
    want = 15.0 * (tau * 300.0 - tau ** 2 * (1.0 - math.exp(-300.0 / tau)))
    assert gyro_floor.bias_gain(ts, vs, tau)[0] == pytest.approx(want, rel=0.01)
    assert np.hypot(*g) > 0.1 * math.sqrt(np.trace(known))


def test_start_correlations_enter_once_each_way():
    # the start errors' cross terms are linear in each correlation: the mean square of
    # rho = +0.9 and -0.9 (heading with the in-run bias) is that of 0; outage5's gains point
    # alike (all integrate the across-track weight forward), so a positive correlation
    # raises the floor; a matrix that is not a correlation matrix's is refused
    kw = dict(heading_sigma_deg=0.02, turnon_sigma_dph=0.4, bias_sigma_dph=0.8)
    ms = {rho: gyro_floor.outage_floor("outage5", start_rho=(0.0, rho, 0.0), **kw)["rms_m"] ** 2
          for rho in (-0.9, 0.0, 0.9)}
    assert ms[0.9] + ms[-0.9] == pytest.approx(2.0 * ms[0.0], rel=1e-9)
    assert ms[-0.9] < ms[0.0] < ms[0.9]
    with pytest.raises(ValueError, match="correlation"):
        gyro_floor.outage_floor("outage5", start_rho=(0.9, 0.9, -0.9), **kw)
    # each correlation in its own slot: without the turn-on bias, its two correlations
    # change nothing and the heading's with the in-run bias does
    kw0 = dict(heading_sigma_deg=0.02, bias_sigma_dph=0.8)
    base = gyro_floor.outage_floor("outage5", **kw0)["rms_m"]
    assert gyro_floor.outage_floor("outage5", start_rho=(0.5, 0.0, 0.5), **kw0)["rms_m"] == base
    assert gyro_floor.outage_floor("outage5", start_rho=(0.0, 0.5, 0.0), **kw0)["rms_m"] > base


def test_turnon_bias_is_the_in_run_one_that_never_decays():
    # a constant bias error b0 turns the heading by b0 t: across the track of a straight
    # drive north v T^2 / 2 per unit (the trapezoid rule on t is exact to rounding); and the
    # in-run gain tends to it as the correlation time grows (T = 1e9 s: to 1e-6)
    t, v = straight(300.0, 15.0)
    g = gyro_floor.turnon_gain(t, v)
    assert g[0] == pytest.approx(15.0 * 300.0 ** 2 / 2.0, rel=1e-6)
    assert g[1] == pytest.approx(0.0, abs=1e-9)
    assert gyro_floor.bias_gain(t, v, 1e9) == pytest.approx(g, rel=1e-6)


def test_rounding_is_a_constant_error_at_a_constant_speed_unless_dithered():
    # a rear axle at a steady 18 m/s read 1.012 times (18.216 m/s) rounds to 18.22 m/s: a
    # navigator that knows mu finds 18.22 / 1.012 = 18.00395 m/s, 3.95 mm/s fast, for the
    # whole 300 s: 1.186 m ahead along the track (north), the same on every seed; white
    # noise of one step before the rounding dithers it away (rounded_mean's bound: 8.5e-10
    # of a step)
    t, v = straight(300.0, 18.0)
    rear = np.full((t.size, 2), 18.0)
    e = gyro_floor.rounding_error(t, v, rear, 0.012, 0.02, 0.0)
    assert e[1] == pytest.approx((18.22 / 1.012 - 18.0) * 300.0, rel=1e-9)
    assert e[0] == pytest.approx(0.0, abs=1e-12)
    # one step of noise: the mean error's bound (q / pi) exp(-2 pi^2), 8.5e-10 q, over 300 s
    bound1 = 0.02 / math.pi * math.exp(-2.0 * math.pi ** 2) * 300.0
    assert np.hypot(*gyro_floor.rounding_error(t, v, rear, 0.012, 0.02, 0.02)) < 1.01 * bound1
    x = np.linspace(10.0, 10.04, 41)
    assert np.array_equal(gyro_floor.rounded_mean(x, 0.02, 0.0), np.round(x / 0.02) * 0.02)
    # half a step of noise: the mean error's first Fourier term, (q / pi) exp(-pi^2 / 2)
    bound = 0.02 / math.pi * math.exp(-math.pi ** 2 / 2.0)
    assert 0.95 * bound < np.abs(gyro_floor.rounded_mean(x, 0.02, 0.01) - x).max() < 1.01 * bound


def test_outage5_rounding_is_the_simulators_own():
    # outage5's odometer (mu 0.012, 0.02 m/s steps, no noise) at its 18 and 11 m/s
    # stretches: the floor's rounding term against the simulator's own wheels
    # (sensors.wheel_speeds at 50 Hz, rounded less unrounded, the rear axle's mean over
    # 1 + mu, carried along the track): to 3 % (measured 1.8 %: the floor rounds the
    # truth's speed every 0.5 s, the simulator its 20-ms-late speed at 50 Hz, which differ
    # where the speed changes); every seed carries it, and it adds to the floor
    import dataclasses
    from tools.sim import scenario, sensors, trajectory
    r0 = gyro_floor.outage_floor("outage5")
    r = gyro_floor.outage_floor("outage5", odometer_rounding=True)
    scen = scenario.load("outage5")
    _, odo = scenario.sensor_specs(scen, "tactical", scen["vehicle"])
    truth = trajectory.generate(scen, gyro_floor.RATE_HZ)
    tw, rounded = sensors.wheel_speeds(truth, odo, seed=1)
    _, exact = sensors.wheel_speeds(truth, dataclasses.replace(odo, quant_mps=1e-9), seed=1)
    k = (tw >= r["outage_s"][0]) & (tw <= r["outage_s"][1])
    err = (rounded[k, 2:].mean(axis=1) - exact[k, 2:].mean(axis=1)) / (1.0 + odo.mu)
    v = np.column_stack([np.interp(tw[k], truth.t_s, truth.v_enu_mps[:, i]) for i in (0, 1)])
    u = v / np.hypot(v[:, 0], v[:, 1])[:, None]
    sim = (u * err[:, None]).sum(axis=0) / odo.rate_hz
    assert r["rounding_m"] == pytest.approx(float(np.hypot(*sim)), rel=0.03)
    assert r["rounding_m"] > 0.5
    assert r["rms_m"] ** 2 == pytest.approx(r0["rms_m"] ** 2 + r["rounding_m"] ** 2, rel=1e-9)


def test_help_prints_and_exits_0(capsys):
    # argparse formats every help text with %: a bare % in one (e.g. "% of the outage's
    # distance") made --help raise instead of printing
    with pytest.raises(SystemExit) as exc:
        gyro_floor.main(["--help"])
    assert exc.value.code == 0
    assert "--limit-pct" in capsys.readouterr().out
