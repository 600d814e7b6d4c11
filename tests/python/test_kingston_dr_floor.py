"""tools/kingston/dr_floor.py: the dead reckoning's floor after a one-point calibration,
against closed forms on made-up routes (the Kingston drive itself is not needed)."""
import math

import numpy as np
import pytest

from tools.kingston import dr_floor


def north(t_end_s, speed_mps, still_s=0.0):
    """1 Hz rows: standing for still_s, then due north at speed_mps (z = v_N + i v_E)."""
    t = np.arange(0.0, t_end_s + 1e-9, 1.0)
    still = t < still_s
    z = np.where(still, 0.0, speed_mps).astype(complex)
    return t, z, still


def test_a_noiseless_gyro_leaves_nothing():
    t, z, still = north(600.0, 10.0, still_s=10.0)
    err = dr_floor.draw_errors(t, z, still, 300, 0.0, 0.0, draws=3)
    assert np.max(np.abs(err)) < 1e-9  # rounding of the calibration's ratio 1


def test_a_bias_seen_standing_without_noise_is_removed_exactly():
    # a noiseless gyro's first standing second gives its bias: the heading never drifts
    t, z, still = north(600.0, 10.0, still_s=10.0)
    err = dr_floor.draw_errors(t, z, still, 300, 0.0, 5.0 * dr_floor.DPH, draws=50)
    assert np.max(np.abs(err)) == pytest.approx(0.0, abs=1e-9)


def test_a_bias_never_seen_is_a_heading_ramp():
    # no standstill: the bias b turns the heading by b t, the position across the track by
    # v b t^2 / 2 (east for a positive b on a northbound car), until the calibration
    t, z, still = north(400.0, 10.0)
    err = dr_floor.draw_errors(t, z, still, 400, 0.0, 1e-4, draws=200)
    # each draw's b from its own ramp: east error / (v t^2 / 2) is the same along the ramp
    k1, k2 = 100, 399
    r1 = err[:, k1].imag / (10.0 * (t[k1] - 1.0) * t[k1] / 2.0)
    r2 = err[:, k2].imag / (10.0 * (t[k2] - 1.0) * t[k2] / 2.0)
    assert np.allclose(r1, r2, rtol=3e-3)  # sin(psi) / psi: psi^2 / 6 at psi 0.1 rad
    assert np.std(r1) == pytest.approx(1e-4, rel=0.15)  # the bias sigma


def test_angle_random_walk_matches_its_closed_form():
    # white rate noise: psi a random walk of variance q^2 t, the cross-track error of a
    # straight drive at speed v has variance q^2 v^2 t^3 / 3 (before the calibration, here
    # at the last row); 4000 draws: the variance's sampling error is 2.2 % (1 sigma)
    q = 1e-4
    t, z, still = north(300.0, 15.0)
    err = dr_floor.draw_errors(t, z, still, t.size - 1, q, 0.0, draws=4000)
    k = 250
    want = q ** 2 * 15.0 ** 2 * t[k] ** 3 / 3.0
    assert np.var(err[:, k].imag) == pytest.approx(want, rel=0.08)
    assert np.max(np.abs(err[:, k].real)) < 1e-2 * math.sqrt(want)  # along: second order


def test_the_bias_estimate_is_the_posterior_of_the_standing_seconds_before_it():
    # 300 s standing, then moving: at row 300 the estimate has seen 300 s (the rows before
    # it), its error's variance 1 / (1 / sb^2 + T / q^2); it does not see the row itself
    # (changing that row's reading leaves it as it was); it stays the same while moving
    q, sb = 1e-4, 5e-5
    t, z, still = north(600.0, 10.0, still_s=300.0)
    dt = np.diff(t, append=t[-1])
    rng = np.random.default_rng(7)
    draws = 8000
    b = sb * rng.standard_normal((draws, 1))
    w = q * rng.standard_normal((draws, t.size))
    est = dr_floor.bias_estimates(b, w, still, dt, q, sb)
    want = 1.0 / (1.0 / sb ** 2 + 300.0 / q ** 2)
    assert np.var(est[:, 300] - b[:, 0]) == pytest.approx(want, rel=0.06)
    w2 = w.copy()
    w2[:, 299] += 1.0
    est2 = dr_floor.bias_estimates(b, w2, still, dt, q, sb)
    # (to rounding: the estimate before row k is the running sum less row k's term)
    assert np.allclose(est2[:, 299], est[:, 299], rtol=0.0, atol=1e-15)  # not yet seen
    assert np.min(np.abs(est2[:, 300] - est[:, 300])) > 1e-3             # seen at 300
    assert np.allclose(est[:, 300], est[:, 599], rtol=0.0, atol=1e-15)   # moving


def test_the_calibration_rotates_and_scales_as_seed_000_says():
    # the dead reckoning after the point, drawn independently here: the displacement from
    # the start to the point, true and dead-reckoned, gives (1 + mu) exp(-i a) = D / D_dr;
    # after it the velocity is that times exp(i psi) z. A bias never seen makes psi a ramp.
    t, z, still = north(600.0, 10.0)
    z = z * np.exp(1j * 0.3 * np.sin(t / 60.0))          # a winding road, not a straight
    k_cal = 300
    err = dr_floor.draw_errors(t, z, still, k_cal, 0.0, 2e-4, draws=4, seed=3)
    b = 2e-4 * np.random.default_rng(3).standard_normal((4, 1))
    dt = np.diff(t, append=t[-1])
    psi = np.concatenate([np.zeros((4, 1)), np.cumsum(b * np.ones_like(t) * dt, axis=1)[:, :-1]],
                         axis=1)
    d_true = np.sum((z * dt)[:k_cal])
    d_dr = np.sum((np.exp(1j * psi) * z * dt)[:, :k_cal], axis=1)
    ratio = d_true / d_dr
    v_after = ratio[:, None] * np.exp(1j * psi[:, k_cal:]) * z[k_cal:]
    want = np.cumsum((v_after - z[k_cal:]) * dt[k_cal:], axis=1)[:, :-1]
    assert np.allclose(err[:, k_cal + 1:], want, atol=1e-6)
    assert np.max(np.abs(want)) > 1.0                     # a test of something


def test_the_calibration_removes_the_rotation_it_measures():
    # a heading ramp before the point (bias never seen) makes the dead-reckoned displacement
    # turn; the calibration rotates and scales it onto the true one, so the error at the
    # point is zero and grows again only from what the heading does after it
    t, z, still = north(600.0, 10.0)
    err = dr_floor.draw_errors(t, z, still, 300, 0.0, 1e-4, draws=20)
    assert np.max(np.abs(err[:, 300])) == 0.0
    assert np.max(np.abs(err[:, 299])) > 1.0  # before it: the ramp's error
