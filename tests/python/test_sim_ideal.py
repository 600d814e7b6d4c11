"""tools/sim/ideal.py: the perfect dead reckoning's error, the reference beside the seeds'
RMS (issue #18). The estimator against closed forms: with white errors only it is the
running mean of the fixes; a receiver error constant over the drive is never removed; the
filter is the generalised least squares estimate of the receiver model. And the drive's epochs are the ones
tools.sim.run gives the firmware."""
import math

import numpy as np
import pytest

from tools.sim import ideal, scenario, sensors, trajectory


def test_white_errors_only_give_the_running_mean():
    rng = np.random.default_rng(1)
    t = np.arange(200) * 0.2
    y = 3.0 + 0.7 * rng.standard_normal(t.size)
    use = np.ones(t.size, dtype=bool)
    use[50:80] = False                      # an outage: the estimate is carried
    est = ideal.offset_estimates(t, y, use, 0.7, 0.0, 120.0)
    # y = b - c + w with b = 0: c's estimate is minus the mean of the fixes so far; the
    # diffuse prior (1e4 m) leaves a relative 0.7^2 / 1e8 of it
    n = np.cumsum(use)
    mean = -np.cumsum(np.where(use, y, 0.0)) / n
    assert est == pytest.approx(mean, abs=1e-6)
    assert est[79] == est[49]


def test_a_constant_receiver_error_stays_in_the_position():
    # tau far beyond the drive: b is one constant no fix can tell from c
    t = np.arange(3000) * 0.2
    y = np.full(t.size, 2.5)
    est = ideal.offset_estimates(t, y, np.ones(t.size, dtype=bool), 0.5, 2.0, 1e9)
    # the estimator splits y between b and c by their priors (c diffuse): c takes all but
    # a 2^2 / 1e8 part of it, the error of the position is the whole 2.5 m
    assert est[-1] == pytest.approx(-2.5, abs=1e-4)


def test_the_estimate_is_the_generalised_least_squares_one():
    # y = b - c + w over uneven epochs with a gap: with c diffuse, the best estimate of c
    # from all fixes so far is GLS with the fixes' covariance sigma_gm^2 exp(-|ti - tj| /
    # tau) + sigma_w^2 I; the filter's estimate after each fix must be it (a filter that
    # dropped the decay, the process noise or the white part gives another)
    rng = np.random.default_rng(3)
    tau, sg, sw = 30.0, 2.0, 0.5
    t = np.concatenate([np.arange(0, 40, 0.5), np.arange(70, 100, 1.0)])
    cov = sg ** 2 * np.exp(-np.abs(t[:, None] - t[None, :]) / tau) + sw ** 2 * np.eye(t.size)
    y = np.linalg.cholesky(cov) @ rng.standard_normal(t.size) + 4.0
    est = ideal.offset_estimates(t, y, np.ones(t.size, dtype=bool), sw, sg, tau)
    for n in (1, 10, 80, t.size):
        ci = np.linalg.inv(cov[:n, :n])
        one = np.ones(n)
        gls = -(one @ ci @ y[:n]) / (one @ ci @ one)
        assert est[n - 1] == pytest.approx(gls, abs=1e-5), n


def test_the_drive_is_the_firmware_s():
    scen = scenario.load("default")
    _, gname = scenario.preset_names(scen)
    spec = sensors.GNSS_PRESETS[gname]
    truth = trajectory.generate(scen, ideal.IMU_RATE_HZ)
    g = sensors.gnss_epochs(truth, spec, sensors.drive_seeds(5)[2])
    r = ideal.receiver_limited("default", 5)
    # between the white part averaged away and the raw fixes' error
    raw = math.sqrt(np.mean(np.sum(g["err_enu_m"][g["valid"], :2] ** 2, axis=1)))
    assert 0.0 < r["rms_m"] < raw
    assert ideal.receiver_limited("default", 5) == r      # deterministic
    assert ideal.receiver_limited("default", 6) != r      # per seed
    # the longest outage is the tunnel (625-715 s); the error at its end is that of the
    # last fix's estimate before it, a fix whose [measure, report] touches it not made
    t, ok = g["t_s"], g["valid"] & ~g["outlier"]
    assert not np.any((t > 625.0) & (t - spec.latency_s < 715.0))
    est = np.column_stack([ideal.offset_estimates(t, g["err_enu_m"][:, ax], ok,
                                                  spec.pos_white_h_m, spec.pos_gm_h_m,
                                                  spec.pos_gm_corr_time_s) for ax in (0, 1)])
    k = np.searchsorted(t, 715.0, side="right") - 1
    assert r["outage_end_m"] == pytest.approx(math.hypot(*est[k]))
    # from the navigation's start: the first 30 s (the estimate still settling) left out
    later = ideal.receiver_limited("default", 5, 30.0)
    assert later["rms_m"] != r["rms_m"] and later["outage_end_m"] == r["outage_end_m"]


def test_no_reference_where_the_fixes_are_more_than_the_preset_s():
    # gnss-faults puts jumps and a frozen fix into the fixes, canyon5-raw adds raw epochs:
    # the reference would not be from the firmware's fixes
    assert ideal.receiver_limited("gnss-faults", 1) is None
    assert ideal.receiver_limited("canyon5-raw", 1) is None

