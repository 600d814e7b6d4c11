"""tools/kingston/analyse.py's GNSS error correlation (gnss_error_correlation) on a
synthetic drive: a receiver whose error is white while the car moves and one constant
offset per stop must come out uncorrelated moving and fully correlated standing, with the
first stop apart and no pair spanning a stop's start or end."""
import types

import numpy as np
import pytest

from tools.kingston import analyse

LAT0, LON0 = 44.23, -76.47
M_PER_DEG_LAT = 111_100.0


def _drive(seed=1):
    """600 s at 1 Hz, standing 0-99 s and 300-359 s (zero odometer), moving otherwise; the
    reference at a fixed point, the fixes off it by white noise moving and by one offset per
    stop (2 m and 3 m north, 1 m and -1 m east) standing."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 600.0) + 1000.0
    standing = ((t - 1000.0) < 100.0) | (((t - 1000.0) >= 300.0) & ((t - 1000.0) < 360.0))
    de = rng.normal(0.0, 1.0, t.size)
    dn = rng.normal(0.0, 1.0, t.size)
    first = (t - 1000.0) < 100.0
    second = standing & ~first
    de[first], dn[first] = 1.0, 2.0
    de[second], dn[second] = -1.0, 3.0
    coslat = np.cos(np.radians(LAT0))
    gnss = {"time_s": t, "lat_deg": LAT0 + dn / M_PER_DEG_LAT,
            "lon_deg": LON0 + de / (M_PER_DEG_LAT * coslat)}
    ref = {"time_s": t, "lat_deg": np.full(t.size, LAT0), "lon_deg": np.full(t.size, LON0)}
    odo = {"time_s": t, "speed_mps": np.where(standing, 0.0, 10.0)}
    return types.SimpleNamespace(gnss=gnss, ref=ref, odo=odo)


def test_moving_white_standing_one_offset():
    acf = analyse.gnss_error_correlation(_drive(), lags=(1, 4, 10))
    for k in (1, 4, 10):
        assert abs(acf["moving"][k]["r"]) < 0.1  # white: |r| ~ 1/sqrt(2 x ~440 pairs)
    # within a stop the error is one constant: pairs (t, t + k) in the first stop are
    # 100 - k, each giving its (east, north) pair; the two offsets differ, so pooled over
    # the second stop alone the correlation is 1 too
    assert acf["first_stop"][4]["pairs"] == 96
    assert acf["first_stop"][4]["r"] > 0.999
    assert acf["other_stops"][10]["pairs"] == 50
    assert acf["other_stops"][10]["r"] > 0.999
    # no moving pair spans a stop: 100..299 and 360..599 give 200 - k and 240 - k
    assert acf["moving"][10]["pairs"] == (200 - 10) + (240 - 10)


def test_correlation_about_zero_none_without_error():
    """_pooled_axes_corr: about zero, not the pairs' own means (a constant error persists:
    1); no error at all or too few pairs: None, not a nan."""
    const = [(1.0, -2.0)] * 10
    assert analyse._pooled_axes_corr(const, const) == 1.0
    zero = [(0.0, 0.0)] * 10
    assert analyse._pooled_axes_corr(zero, zero) is None
    assert analyse._pooled_axes_corr(const[:2], const[:2]) is None
    flip = [(-1.0, 2.0)] * 10
    assert analyse._pooled_axes_corr(const, flip) == -1.0


def test_allan_axes_white_noise_and_a_wandering_bias():
    """allan_axes on 530 s of 10 Hz samples: white noise of sd s per sample has the Allan
    deviation s sqrt(dt / tau) (IEEE Std 952 annex C), within three of the overlapping
    estimator's relative spreads (about 0.75 / sqrt(2 (n / m - 1)): 2.3 % at 1 s, 4 % at
    3 s, 7.4 % at 10 s); a Gauss-Markov bias (1 mg, 50 s) on another axis gives a
    deviation rising beyond 10 s (where its peak lies, a 530-s record does not tell), well
    above the white axis's there; accelerometers in mg, gyros in deg/h. A window of no
    tau of 10 s prints without one; one of fewer than 2 rows is refused."""
    rng = np.random.default_rng(7)
    dt, n = 0.1, 5300
    t = 1000.0 + dt * np.arange(n)
    s_f, s_w = analyse.MG, 1e-5      # 1 mg and 1e-5 rad/s per sample
    gm = np.zeros(n)
    a = np.exp(-dt / 50.0)
    for k in range(1, n):
        gm[k] = a * gm[k - 1] + analyse.MG * np.sqrt(1.0 - a * a) * rng.normal()
    imu = {"time_s": t, "fx_mps2": s_f * rng.normal(size=n),
           "fy_mps2": s_f * rng.normal(size=n) + gm, "fz_mps2": s_f * rng.normal(size=n),
           "wx_radps": s_w * rng.normal(size=n), "wy_radps": s_w * rng.normal(size=n),
           "wz_radps": s_w * rng.normal(size=n)}
    al = analyse.allan_axes(imu, t[0], t[-1])
    assert al["samples"] == n and al["taus_s"] == list(analyse.ALLAN_TAUS_S)
    for i, (tau, tol) in enumerate(((1.0, 0.07), (3.0, 0.12), (10.0, 0.22))):
        assert al["fx"]["adev"][i] == pytest.approx(1.0 * np.sqrt(dt / tau), rel=tol)
        assert al["wz"]["adev"][i] == pytest.approx(
            s_w * analyse.DEG_PER_H * np.sqrt(dt / tau), rel=tol)
    assert al["fx"]["unit"] == "mg" and al["wz"]["unit"] == "deg/h"
    assert al["fy"]["largest_at_s"] >= 30.0
    assert al["fy"]["largest_beyond_10s"] > 3.0 * al["fx"]["largest_beyond_10s"]
    # the white axis falls beyond 10 s: its largest there is at 10 s
    assert al["fx"]["largest_at_s"] == 10.0
    assert al["fx"]["smallest_at_s"] >= 100.0
    line = analyse._allan_line(al)
    assert line.count("from 10 s on largest") == 6
    # 15 s: taus of 10 s and more need 20 s; the line says so instead of failing
    short = analyse.allan_axes(imu, t[0], t[0] + 15.0)
    assert short["fx"]["largest_beyond_10s"] is None and short["fx"]["adev"][3] is None
    assert "no tau of 10 s or more" in analyse._allan_line(short)
    with pytest.raises(ValueError):
        analyse.allan_axes(imu, t[0] - 10.0, t[0] - 5.0)
