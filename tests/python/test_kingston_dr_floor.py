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


def test_the_calibration_removes_the_rotation_it_measures():
    # a heading ramp before the point (bias never seen) makes the dead-reckoned displacement
    # turn; the calibration rotates and scales it onto the true one, so the error at the
    # point is zero and grows again only from what the heading does after it
    t, z, still = north(600.0, 10.0)
    err = dr_floor.draw_errors(t, z, still, 300, 0.0, 1e-4, draws=20)
    assert np.max(np.abs(err[:, 300])) == 0.0
    assert np.max(np.abs(err[:, 299])) > 1.0  # before it: the ramp's error
