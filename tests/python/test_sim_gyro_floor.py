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
