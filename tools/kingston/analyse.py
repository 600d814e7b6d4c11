"""Facts about the Kingston 2008 data that the conversion and the firmware depend on.

    python -m tools.kingston.analyse [--data DIR] [--json out/kingston/analysis.json]

- IMU time stamps: spacing, duplicates, gaps, phase against the GPS second.
- Standstills by the odometer (OBD speed exactly 0 on consecutive 1 Hz rows): their
  number and durations, the mean gyro z per stop (IMU samples from the first to the last
  zero row of the stop) and its spread, against the Earth rate's vertical component
  U sin(lat) that a level z-up gyro measures at rest: bias = mean wz - U sin(lat).
- Odometer against the reference: integrated OBD speed (trapezoid over the 1 Hz rows in the
  reference's time span) / the reference's travelled distance (polyline of its 1 Hz
  positions; also its integrated horizontal speed); median speed ratio above 3 m/s; the lag
  that best aligns the two speeds.
- The initial attitude: reference.csv's first row, and roll and pitch levelled from this
  IMU's own accelerometers over the initial standstill (docs/frames.md:
  roll = atan2(-fx, fz), pitch = atan2(fy, hypot(fx, fz))).
- Gyro z against the reference heading: the 1 s heading increments of the reference against
  -integral(wz) over the same second shifted by a lag tau, least squares over the seconds
  with turning (|d azimuth| > 2 deg/s): the lag and the scale factor (1 + s), for both
  increment rules (rect, trapezoid); and the integrated gyro heading (Earth rate removed)
  against the reference heading at some times.
- Gyro noise and means during the first (529 s) standstill, against the Earth rate a level
  IMU with the reference's heading measures on each axis.
- GNSS fixes against the reference, horizontal.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from tools import geodesy
from tools.kingston import convert

EARTH_RATE = geodesy.WGS84_OMEGA_IE_RPS  # rad/s
DEG_PER_H = 180.0 / math.pi * 3600.0


def imu_timing(drive) -> dict:
    t = drive.imu["time_s"]
    dt = np.diff(t)
    frac = np.round((t % 1.0) * 1000.0).astype(int) % 100
    tim = convert.imu_increments(drive.imu, drive.t0_gps).timing
    return {"rows": int(t.size), "first_gps_s": float(t[0]), "last_gps_s": float(t[-1]),
            "span_s": float(t[-1] - t[0]), "interval_min_s": float(dt.min()),
            "interval_max_s": float(dt.max()), "interval_mean_s": float(dt.mean()),
            "interval_max_dev_from_0.1_s": float(np.abs(dt - 0.1).max()),
            "duplicates": tim["duplicates_identical"] + tim["duplicates_conflicting"],
            "gaps": len(tim["gaps"]), "missing_samples": tim["missing_samples"],
            "phase_ms_after_gps_second_mod_100": sorted(set((frac).tolist()))}


def stops(drive, min_s: float = 10.0) -> dict:
    """Odometer standstills and the gyro z mean in each."""
    o = drive.odo
    z = (o["speed_mps"] == 0.0).astype(int)
    d = np.diff(np.concatenate(([0], z, [0])))
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1) - 1
    t_imu = drive.imu["time_s"]
    wz = drive.imu["wz_radps"]
    lat = math.radians(float(np.mean(drive.ref["lat_deg"])))
    earth_up = EARTH_RATE * math.sin(lat) * DEG_PER_H
    rows = []
    for a, b in zip(starts, ends):
        ta, tb = float(o["time_s"][a]), float(o["time_s"][b])
        sel = (t_imu >= ta) & (t_imu <= tb)
        w = wz[sel] * DEG_PER_H
        rows.append({"start_s": round(ta - drive.t0_gps, 2), "duration_s": tb - ta + 1.0,
                     "zero_rows": int(b - a + 1), "imu_samples": int(sel.sum()),
                     "mean_wz_deg_h": float(w.mean()) if w.size else None,
                     "sd_wz_deg_h": float(w.std(ddof=1)) if w.size > 1 else None,
                     "sem_wz_deg_h": float(w.std(ddof=1) / math.sqrt(w.size)) if w.size > 1
                     else None})
    long_ = [r for r in rows if r["duration_s"] >= min_s and r["imu_samples"] > 1]
    means = np.array([r["mean_wz_deg_h"] for r in long_])
    n = np.array([r["imu_samples"] for r in long_])
    dur = np.array([r["duration_s"] for r in rows])
    all_means = np.array([r["mean_wz_deg_h"] for r in rows if r["mean_wz_deg_h"] is not None])
    return {
        "definition": "runs of consecutive odometer rows with speed exactly 0; IMU samples "
                      "from the first to the last zero row",
        "count": len(rows), "total_s": float(dur.sum()),
        "duration_s": {"min": float(dur.min()), "median": float(np.median(dur)),
                       "max": float(dur.max())},
        "durations_s": [r["duration_s"] for r in rows],
        "earth_rate_up_deg_h": earth_up,
        "all_stops": {"n": len(rows), "mean_of_means_deg_h": float(all_means.mean()),
                      "sd_of_means_deg_h": float(all_means.std(ddof=1)),
                      "median_deg_h": float(np.median(all_means))},
        f"stops_ge_{min_s:g}s": {
            "n": len(long_), "mean_of_means_deg_h": float(means.mean()),
            "sd_of_means_deg_h": float(means.std(ddof=1)),
            "median_deg_h": float(np.median(means)),
            "min_deg_h": float(means.min()), "max_deg_h": float(means.max()),
            "sample_weighted_mean_deg_h": float(np.sum(means * n) / n.sum()),
            "bias_deg_h": float(np.sum(means * n) / n.sum() - earth_up),
            "bias_excluding_first_stop_deg_h": float(
                np.sum(means[1:] * n[1:]) / n[1:].sum() - earth_up) if len(long_) > 1 else None,
            "typical_sem_deg_h": float(np.median([r["sem_wz_deg_h"] for r in long_]))},
        "stops": rows,
    }


def odometer_vs_reference(drive) -> dict:
    ref = convert.reference_track(drive)
    r, o = drive.ref, drive.odo
    sel = (o["time_s"] >= r["time_s"][0]) & (o["time_s"] <= r["time_s"][-1])
    odo_m = float(np.trapezoid(o["speed_mps"][sel], o["time_s"][sel]))
    ref_speed = np.hypot(r["ve_mps"], r["vn_mps"])
    ref_speed_m = float(np.trapezoid(ref_speed, r["time_s"]))
    poly_m = float(ref["dist_m"][-1])
    rs = np.interp(o["time_s"], r["time_s"], ref_speed)
    m = sel & (rs > 3.0)
    lags = {}
    for lag in (-2, -1, 0, 1, 2):
        rr = np.interp(o["time_s"][sel] + lag, r["time_s"], ref_speed)
        lags[lag] = float(np.sqrt(np.mean((o["speed_mps"][sel] - rr) ** 2)))
    # distance the reference "travels" while the odometer says 0 (position noise at rest)
    still = np.interp(r["time_s"], o["time_s"], o["speed_mps"]) == 0.0
    jitter = float(np.sum(np.diff(ref["dist_m"])[still[1:] & still[:-1]]))
    return {"odometer_distance_m": odo_m, "reference_polyline_m": poly_m,
            "reference_speed_integral_m": ref_speed_m,
            "ratio_to_polyline": odo_m / poly_m, "ratio_to_speed_integral": odo_m / ref_speed_m,
            "median_speed_ratio_above_3mps": float(np.median(o["speed_mps"][m] / rs[m])),
            "rms_speed_difference_by_lag_s": lags,
            "reference_polyline_while_odometer_0_m": jitter}


def _acf(x: np.ndarray, lags=(1, 2, 3, 5, 10)) -> dict:
    """Autocorrelation of a 1 Hz series at these lags (NaN samples skipped pairwise)."""
    out = {}
    for k in lags:
        a, b = x[:-k], x[k:]
        ok = np.isfinite(a) & np.isfinite(b)
        out[k] = float(np.corrcoef(a[ok], b[ok])[0, 1])
    return out


SPEED_BINS_MPS = ((0.5, 2.0), (2.0, 4.0), (4.0, 6.0), (6.0, 8.0), (8.0, 10.0), (10.0, 12.0),
                  (12.0, 14.0), (14.0, 16.0))


def reference_speed_3d(ref) -> np.ndarray:
    """The reference's 3-D speed at its epochs, m/s (what an odometer measures)."""
    return np.sqrt(ref["ve_mps"] ** 2 + ref["vn_mps"] ** 2 + ref["vu_mps"] ** 2)


def odometer_error_model(drive) -> dict:
    """The OBD speed against the reference's 3-D speed at the same time stamp (issue #18):
    a least-squares reading = scale x true + offset over the moving epochs (reference above
    0.5 m/s), the mean reading - true per speed bin at low acceleration (|dv/dt| < 0.3
    m/s^2: no lag effect), the residual's RMS by acceleration and its autocorrelation from
    one 1-s reading to the next."""
    r, o = drive.ref, drive.odo
    vr = reference_speed_3d(r)
    v = np.interp(o["time_s"], r["time_s"], vr)
    acc = np.gradient(v, o["time_s"])
    m = (v > 0.5) & (o["speed_mps"] > 0.0)
    A = np.vstack([v[m], np.ones(int(m.sum()))]).T
    (scale, offset), *_ = np.linalg.lstsq(A, o["speed_mps"][m], rcond=None)
    res = np.full(v.size, np.nan)
    res[m] = o["speed_mps"][m] - (scale * v[m] + offset)
    bins = []
    for lo, hi in SPEED_BINS_MPS:
        b = m & (v > lo) & (v <= hi) & (np.abs(acc) < 0.3)
        if b.sum() >= 10:
            bins.append({"from_mps": lo, "to_mps": hi, "n": int(b.sum()),
                         "mean_difference_mps": float(np.mean(o["speed_mps"][b] - v[b])),
                         "as_scale_error": float(o["speed_mps"][b].sum() / v[b].sum() - 1.0)})
    by_acc = []
    for lo, hi in ((0.0, 0.2), (0.2, 0.5), (0.5, 1.0), (1.0, 3.0)):
        b = m & (np.abs(acc) >= lo) & (np.abs(acc) < hi)
        by_acc.append({"acc_from_mps2": lo, "acc_to_mps2": hi, "n": int(b.sum()),
                       "rms_mps": float(np.sqrt(np.mean(res[b] ** 2)))})
    return {"scale": float(scale), "offset_mps": float(offset), "speed_bins": bins,
            "residual_rms_by_acceleration": by_acc, "residual_acf": _acf(res),
            "residual_rms_by_shift_s": odometer_shift_fit(drive)}


SHIFTS_S = tuple(round(0.1 * k, 1) for k in range(-10, 11))


def odometer_shift_fit(drive, shifts_s=SHIFTS_S) -> dict:
    """The residual RMS (m/s) of reading = scale x reference speed + offset over the moving
    epochs (odometer_error_model's: reference above 0.5 m/s at the stamp, reading above 0;
    1 s inside the reference's span) with the reference's 3-D speed taken shift s after
    the reading's time stamp, for shifts in 0.1 s steps: where it is smallest the reading
    describes the car (a latency of -shift; docs/kalman.md, the odometer's latency)."""
    r, o = drive.ref, drive.odo
    vr = reference_speed_3d(r)
    sel = ((o["time_s"] >= r["time_s"][0] + 1.0) & (o["time_s"] <= r["time_s"][-1] - 1.0)
           & (np.interp(o["time_s"], r["time_s"], vr) > 0.5) & (o["speed_mps"] > 0.0))
    t, reading = o["time_s"][sel], o["speed_mps"][sel]
    out = {}
    for s in shifts_s:
        v = np.interp(t + s, r["time_s"], vr)
        A = np.column_stack([v, np.ones_like(v)])
        coef, *_ = np.linalg.lstsq(A, reading, rcond=None)
        out[float(s) + 0.0] = float(np.sqrt(np.mean((reading - A @ coef) ** 2)))
    return out


def gnss_velocity_errors(drive) -> dict:
    """The receiver's velocity against the reference's at its epochs: the horizontal error's
    median, p95 and RMS, and the east error's autocorrelation from epoch to epoch (1 Hz)."""
    g, r = drive.gnss, drive.ref
    de = g["ve_mps"] - np.interp(g["time_s"], r["time_s"], r["ve_mps"])
    dn = g["vn_mps"] - np.interp(g["time_s"], r["time_s"], r["vn_mps"])
    e = np.hypot(de, dn)
    return {"n": int(e.size), "median_mps": float(np.median(e)),
            "p95_mps": float(np.percentile(e, 95)), "rms_mps": float(np.sqrt(np.mean(e ** 2))),
            "east_acf": _acf(de - np.mean(de))}


def local_en_m(drive, lat_deg, lon_deg) -> tuple:
    """(east, north) in m of positions (deg) from the reference's first row, on the local
    radii there."""
    r = drive.ref
    _, e, n = geodesy.horizontal_error_m(math.radians(r["lat_deg"][0]),
                                         math.radians(r["lon_deg"][0]),
                                         np.radians(lat_deg), np.radians(lon_deg))
    return e, n


def reference_track(drive) -> dict:
    """The reference's rows in the local frame of local_en_m: t_s from the drive's start,
    its positions e_m, n_m, and the integrals of its own velocities from the first row,
    ie_m, in_m (trapezoid)."""
    r = drive.ref
    e, n = local_en_m(drive, r["lat_deg"], r["lon_deg"])
    dt = np.diff(r["time_s"])
    i_n = np.concatenate([[0.0], np.cumsum(0.5 * (r["vn_mps"][1:] + r["vn_mps"][:-1]) * dt)])
    i_e = np.concatenate([[0.0], np.cumsum(0.5 * (r["ve_mps"][1:] + r["ve_mps"][:-1]) * dt)])
    return {"t_s": r["time_s"] - drive.t0_gps, "e_m": e, "n_m": n, "ie_m": i_e, "in_m": i_n}


def reference_consistency(drive, window_s: int = 10) -> dict:
    """The SPAN reference against itself: over every window_s of its 1 Hz rows, the distance
    its positions move minus the integral of its own velocities (trapezoid), horizontal.
    What the reference's positions do that its velocities do not bounds what any solution
    can be measured to."""
    r = drive.ref
    tr = reference_track(drive)
    e, n, i_e, i_n = tr["e_m"], tr["n_m"], tr["ie_m"], tr["in_m"]
    w = window_s
    d = np.hypot((n[w:] - n[:-w]) - (i_n[w:] - i_n[:-w]), (e[w:] - e[:-w]) - (i_e[w:] - i_e[:-w]))
    k = int(np.argmax(d))
    return {"window_s": w, "median_m": float(np.median(d)), "p95_m": float(np.percentile(d, 95)),
            "max_m": float(d[k]), "max_at_s": float(r["time_s"][k] - r["time_s"][0])}


def initial_attitude(drive, still_s: float = 500.0) -> dict:
    r0 = drive.ref[0]
    t = drive.imu["time_s"]
    s = t < t[0] + still_s
    fx, fy, fz = (float(drive.imu[c][s].mean()) for c in ("fx_mps2", "fy_mps2", "fz_mps2"))
    roll = math.degrees(math.atan2(-fx, fz))
    pitch = math.degrees(math.atan2(fy, math.hypot(fx, fz)))
    rs = drive.ref["time_s"] < drive.ref["time_s"][0] + still_s
    return {"reference_first_row": {"gps_s": float(r0["time_s"]),
                                    "heading_deg": float(r0["azimuth_deg"]),
                                    "roll_deg": float(r0["roll_deg"]),
                                    "pitch_deg": float(r0["pitch_deg"]),
                                    "lat_deg": float(r0["lat_deg"]),
                                    "lon_deg": float(r0["lon_deg"]),
                                    "height_m": float(r0["height_m"])},
            f"reference_mean_first_{still_s:g}s": {
                "roll_deg": float(drive.ref["roll_deg"][rs].mean()),
                "pitch_deg": float(drive.ref["pitch_deg"][rs].mean()),
                "heading_min_deg": float(drive.ref["azimuth_deg"][rs].min()),
                "heading_max_deg": float(drive.ref["azimuth_deg"][rs].max())},
            f"imu_accel_levelled_first_{still_s:g}s": {
                "roll_deg": roll, "pitch_deg": pitch, "fz_mps2": fz}}


def gyro_z_timing(drive) -> dict:
    """Lag and scale of -wz against the reference's 1 s heading increments, for the
    increments of both rules of tools/kingston/convert.py."""
    return {rule: _gyro_z_timing(drive, rule) for rule in convert.IMU_RULES}


def _gyro_z_timing(drive, rule) -> dict:
    t = drive.imu["time_s"]
    wz = drive.imu["wz_radps"]
    inc = wz[1:] if rule == "rect" else 0.5 * (wz[1:] + wz[:-1])
    psi = np.concatenate(([0.0], np.cumsum(inc * np.diff(t))))
    r = drive.ref
    az = np.unwrap(np.radians(r["azimuth_deg"]))
    daz = np.diff(az)
    turning = np.abs(np.degrees(daz)) > 2.0
    best = None
    table = {}
    for tau_ms in range(-300, 301, 10):
        tau = tau_ms / 1000.0
        p = np.interp(r["time_s"] + tau, t, psi)
        dpsi = -np.diff(p)
        x, y = dpsi[turning], daz[turning]
        k = float(np.dot(x, y) / np.dot(x, x))
        res = float(np.sqrt(np.mean((y - k * x) ** 2)))
        table[tau_ms] = res
        if best is None or res < best[1]:
            best = (tau_ms, res, k)
    return {"turning_seconds": int(turning.sum()), "best_lag_ms": best[0],
            "scale_at_best": best[2], "rms_residual_deg_at_best": math.degrees(best[1]),
            "rms_residual_deg_at_0": math.degrees(table[0]),
            "meaning": "reference heading at t matches the IMU's integrated -wz at t + lag"}


def gyro_heading_vs_reference(drive, times=(520, 560, 800, 1195, 1500, 2000, 2500, 3000,
                                              3500)) -> dict:
    """The reference's azimuth against its first value minus the integrated gyro z, Earth
    rate removed (rule rect, no bias correction), at some times (s from the first IMU
    sample): where the two disagree, one of them moved."""
    t = drive.imu["time_s"] - drive.t0_gps
    lat = math.radians(float(drive.ref["lat_deg"][0]))
    wz = drive.imu["wz_radps"] - EARTH_RATE * math.sin(lat)
    psi = np.concatenate(([0.0], np.cumsum(wz[1:] * np.diff(t))))
    tr = drive.ref["time_s"] - drive.t0_gps
    az = np.unwrap(np.radians(drive.ref["azimuth_deg"]))
    err = np.degrees(az[0] - np.interp(tr, t, psi) - az)
    return {"definition": "gyro heading - reference heading, deg (no gyro bias removed)",
            "at_s": {str(T): float(err[int(np.argmin(np.abs(tr - T)))]) for T in times}}


def gyro_noise_at_first_stop(drive) -> dict:
    """Per-axis standard deviation of the 10 Hz rates during the initial standstill and the
    angle random walk it implies for interval-mean samples: sd * sqrt(dt)."""
    st = stops(drive)["stops"][0]
    t = drive.imu["time_s"] - drive.t0_gps
    sel = (t >= st["start_s"]) & (t <= st["start_s"] + st["duration_s"] - 1.0)
    out = {"stop_s": [st["start_s"], st["duration_s"]]}
    # the Earth rate a level IMU with this heading measures: north part on x (right) and y
    lat = math.radians(float(drive.ref["lat_deg"][0]))
    hdg = math.radians(float(drive.ref["azimuth_deg"][0]))
    north = EARTH_RATE * math.cos(lat) * DEG_PER_H
    earth = {"x": -math.sin(hdg) * north, "y": math.cos(hdg) * north,
             "z": EARTH_RATE * math.sin(lat) * DEG_PER_H}
    for ax in ("x", "y", "z"):
        w = drive.imu[f"w{ax}_radps"][sel] * DEG_PER_H
        sd = float(w.std(ddof=1))
        out[ax] = {"mean_deg_h": float(w.mean()), "earth_rate_deg_h": earth[ax],
                   "bias_deg_h": float(w.mean()) - earth[ax], "sd_deg_h": sd,
                   "arw_deg_sqrt_h": sd * math.sqrt(0.1) / 60.0}
    return out


ALLAN_TAUS_S = (1.0, 3.0, 10.0, 30.0, 100.0, 170.0)
MG = 9.80665e-3


def allan_axes(imu: dict, t0_s: float, t1_s: float, taus_s=ALLAN_TAUS_S) -> dict:
    """The overlapping Allan deviation (tools.sim.sensors.allan_deviation) of each IMU axis
    over the rows with t0_s <= time_s <= t1_s (10 Hz), accelerometers in mg and gyros in
    deg/h, at taus_s; and per axis the largest and the smallest from 10 s on with their
    taus: what an in-run instability (a data sheet's floor, a Gauss-Markov process's peak
    at 1.89 correlation times) can be read as from a stop this long: a rising deviation's
    largest, a falling one's smallest (an upper bound of its floor at the last tau). Where
    a peak lies is not determined by a stop a few correlation times long: the estimates at
    the last taus spread by tens of percent. ValueError for fewer than 2 rows."""
    from tools.sim.sensors import allan_deviation   # the simulator's one estimator
    t = np.asarray(imu["time_s"], dtype=float)
    sel = (t >= t0_s) & (t <= t1_s)
    if sel.sum() < 2:
        raise ValueError(f"allan_axes: {int(sel.sum())} IMU rows in {t0_s:g}..{t1_s:g} s")
    dt = float(np.median(np.diff(t[sel])))
    out = {"window_s": [t0_s, t1_s], "samples": int(sel.sum()), "taus_s": list(taus_s)}
    for name, unit, per in (("fx_mps2", "mg", 1.0 / MG), ("fy_mps2", "mg", 1.0 / MG),
                            ("fz_mps2", "mg", 1.0 / MG), ("wx_radps", "deg/h", DEG_PER_H),
                            ("wy_radps", "deg/h", DEG_PER_H), ("wz_radps", "deg/h", DEG_PER_H)):
        ad = np.asarray(allan_deviation(np.asarray(imu[name], dtype=float)[sel], dt,
                                        taus_s)).ravel() * per
        beyond = [(a, tau) for a, tau in zip(ad, taus_s) if tau >= 10.0 and np.isfinite(a)]
        big = max(beyond) if beyond else (None, None)
        small = min(beyond) if beyond else (None, None)
        out[name.split("_")[0]] = {
            "unit": unit, "adev": [None if not np.isfinite(a) else float(a) for a in ad],
            "largest_beyond_10s": None if big[0] is None else float(big[0]),
            "largest_at_s": big[1],
            "smallest_beyond_10s": None if small[0] is None else float(small[0]),
            "smallest_at_s": small[1]}
    return out


def imu_allan_at_first_stop(drive) -> dict:
    """allan_axes over the first stop (the 529 s before the drive), its last second left
    out as gyro_noise_at_first_stop does."""
    st = stops(drive)["stops"][0]
    t0 = drive.t0_gps + st["start_s"]
    return allan_axes(drive.imu, t0, t0 + st["duration_s"] - 1.0)


def gnss_vs_reference(drive) -> dict:
    g, r = drive.gnss, drive.ref
    common, gi, ri = np.intersect1d(np.rint(g["time_s"]), np.rint(r["time_s"]),
                                    return_indices=True)
    e = geodesy.horizontal_distance_m(r["lat_deg"][ri], r["lon_deg"][ri],
                                      g["lat_deg"][gi], g["lon_deg"][gi])
    dh = g["height_m"][gi] - r["height_m"][ri]
    return {"n": int(e.size), "rms_m": float(np.sqrt(np.mean(e ** 2))),
            "median_m": float(np.median(e)), "p95_m": float(np.percentile(e, 95)),
            "max_m": float(e.max()), "height_minus_reference_median_m": float(np.median(dh))}


def _pooled_axes_corr(a, b, min_pairs: int = 3):
    """How much of an error is still there k s later: sum(a b) / sqrt(sum(a^2) sum(b^2))
    over the pairs (a[i], b[i]), each an (east, north) error against the reference, the two
    axes pooled, about zero (the reference), which is what the filter's fixes are wrong by.
    Every bias is kept on purpose (a bias is an error the filter cannot average out):
    about the pairs' own means, one stop's constant error would have no variance and
    count as none; np.corrcoef of both axes pooled (as before) took out one mean common
    to both axes, and printed nan without variance. None with fewer than min_pairs pairs
    or no error at all."""
    if len(a) < min_pairs:
        return None
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    den = math.sqrt(float(np.sum(a * a)) * float(np.sum(b * b)))
    return float(np.sum(a * b)) / den if den > 0.0 else None


def gnss_error_correlation(drive, lags=(1, 2, 4, 10, 20)) -> dict:
    """The receiver's position error (fix less the reference, north and east pooled, about
    zero: _pooled_axes_corr) against
    itself lag seconds later, moving and standing apart: pairs of epochs k s apart of which
    every second in between is moving (the odometer above 0), or standing in one stop (the
    odometer at 0), the first stop (the drive's start) apart from the others. A moving
    antenna passes through its multipath; a standing one's changes only with the
    satellites' motion (firmware/app/fusion.c, fusion_rx_corr_s)."""
    g, r, o = drive.gnss, drive.ref, drive.odo
    common, gi, ri = np.intersect1d(np.rint(g["time_s"]), np.rint(r["time_s"]),
                                    return_indices=True)
    e, n = local_en_m(drive, g["lat_deg"][gi], g["lon_deg"][gi])
    er, nr = local_en_m(drive, r["lat_deg"][ri], r["lon_deg"][ri])
    err = {int(t): (a, b) for t, a, b in zip(common, e - er, n - nr)}
    zero = {int(t): v == 0.0 for t, v in zip(np.rint(o["time_s"]), o["speed_mps"])}
    # each second's class: 0 moving, 1 the first stop, 2 the other stops; a stop's number
    t_all = sorted(zero)
    stop_of, k_stop, prev = {}, 0, False
    for t in t_all:
        if zero[t] and not prev:
            k_stop += 1
        stop_of[t] = k_stop if zero[t] else 0
        prev = zero[t]
    out = {}
    for name, want in (("moving", lambda s: s == 0), ("first_stop", lambda s: s == 1),
                       ("other_stops", lambda s: s > 1)):
        acf = {}
        for k in lags:
            a, b = [], []
            for t in t_all:
                s0 = stop_of.get(t)
                if s0 is None or not want(s0) or t not in err or t + k not in err:
                    continue
                if any(stop_of.get(t + j) != s0 for j in range(1, k + 1)):
                    continue
                a.append(err[t])
                b.append(err[t + k])
            acf[k] = {"pairs": len(a), "r": _pooled_axes_corr(a, b)}
        out[name] = acf
    return out


def analyse(drive) -> dict:
    return {"imu_timing": imu_timing(drive), "stops": stops(drive),
            "odometer": odometer_vs_reference(drive), "initial_attitude": initial_attitude(drive),
            "gyro_z_vs_reference_heading": gyro_z_timing(drive),
            "gyro_heading_vs_reference": gyro_heading_vs_reference(drive),
            "gyro_noise_at_first_stop": gyro_noise_at_first_stop(drive),
            "imu_allan_at_first_stop": imu_allan_at_first_stop(drive),
            "gnss_vs_reference": gnss_vs_reference(drive),
            "odometer_error_model": odometer_error_model(drive),
            "gnss_velocity_errors": gnss_velocity_errors(drive),
            "reference_consistency": reference_consistency(drive),
            "gnss_error_correlation": gnss_error_correlation(drive)}


def _allan_extremes(a: dict) -> str:
    if a["largest_beyond_10s"] is None:
        return "no tau of 10 s or more in the window"
    return (f"from 10 s on largest {a['largest_beyond_10s']:.3g} at {a['largest_at_s']:g} s, "
            f"smallest {a['smallest_beyond_10s']:.3g} at {a['smallest_at_s']:g} s")


def _allan_line(al: dict) -> str:
    taus = "/".join(f"{t:g}" for t in al["taus_s"])
    return (f"IMU Allan deviation at the first stop ({al['samples']} samples), at {taus} s: "
            + "; ".join(
                f"{ax} " + " ".join("-" if v is None else f"{v:.3g}" for v in al[ax]["adev"])
                + f" {al[ax]['unit']} ({_allan_extremes(al[ax])})"
                for ax in ("fx", "fy", "fz", "wx", "wy", "wz")))


def text(a: dict) -> str:
    it, st, od, ia = a["imu_timing"], a["stops"], a["odometer"], a["initial_attitude"]
    lg = st["stops_ge_10s"]
    r0 = ia["reference_first_row"]
    lev = ia["imu_accel_levelled_first_500s"]
    gz = a["gyro_z_vs_reference_heading"]
    g = a["gnss_vs_reference"]
    lines = [
        f"IMU: {it['rows']} rows over {it['span_s']:.1f} s, interval {it['interval_min_s']:.6f}.."
        f"{it['interval_max_s']:.6f} s (max deviation from 0.1 s "
        f"{it['interval_max_dev_from_0.1_s']:.1e}),"
        f" {it['duplicates']} duplicates, {it['gaps']} gaps; samples at GPS second + "
        f"{it['phase_ms_after_gps_second_mod_100']} ms (mod 100)",
        f"stops (odometer 0): {st['count']}, {st['total_s']:.0f} s in all, durations "
        f"{st['duration_s']['min']:.0f}..{st['duration_s']['max']:.0f} s (median "
        f"{st['duration_s']['median']:.0f} s)",
        f"  gyro z at stops >= 10 s ({lg['n']}): mean of means {lg['mean_of_means_deg_h']:.2f} "
        f"deg/h, sd {lg['sd_of_means_deg_h']:.2f}, "
        f"range {lg['min_deg_h']:.2f}..{lg['max_deg_h']:.2f}, "
        f"sample-weighted {lg['sample_weighted_mean_deg_h']:.2f} deg/h; Earth rate up "
        f"{st['earth_rate_up_deg_h']:.2f} deg/h -> bias {lg['bias_deg_h']:.2f} deg/h "
        f"(without the first stop {lg['bias_excluding_first_stop_deg_h']:.2f}); typical "
        f"standard error per stop {lg['typical_sem_deg_h']:.1f} deg/h",
        f"  all {st['all_stops']['n']} stops: mean of means "
        f"{st['all_stops']['mean_of_means_deg_h']:.2f}"
        f" deg/h, sd {st['all_stops']['sd_of_means_deg_h']:.2f}, median "
        f"{st['all_stops']['median_deg_h']:.2f}",
        f"odometer: {od['odometer_distance_m']:.0f} m vs reference polyline "
        f"{od['reference_polyline_m']:.0f} m (ratio {od['ratio_to_polyline']:.4f}), reference "
        f"speed integral {od['reference_speed_integral_m']:.0f} m (ratio "
        f"{od['ratio_to_speed_integral']:.4f}); median speed ratio > 3 m/s "
        f"{od['median_speed_ratio_above_3mps']:.4f}; RMS speed difference by lag "
        + ", ".join(f"{k:+d} s {v:.2f}" for k, v in od["rms_speed_difference_by_lag_s"].items()),
        f"initial attitude (reference first row, GPS {r0['gps_s']:.0f}): heading "
        f"{r0['heading_deg']:.4f} deg, roll {r0['roll_deg']:.4f} deg, "
        f"pitch {r0['pitch_deg']:.4f} deg;"
        f" this IMU's accelerometers over the first 500 s: roll {lev['roll_deg']:.4f}, pitch "
        f"{lev['pitch_deg']:.4f} deg",
        f"gyro z vs reference heading ({gz['rect']['turning_seconds']} turning seconds): "
        + "; ".join(f"rule {r}: best lag {v['best_lag_ms']} ms, scale {v['scale_at_best']:.4f}, "
                    f"residual {v['rms_residual_deg_at_best']:.3f} deg/s (at lag 0: "
                    f"{v['rms_residual_deg_at_0']:.3f})" for r, v in gz.items()),
        "gyro heading - reference heading (deg) at t = " + ", ".join(
            f"{k} s {v:+.2f}" for k, v in a["gyro_heading_vs_reference"]["at_s"].items()),
        "gyro at the first stop: " + ", ".join(
            f"{ax} mean {a['gyro_noise_at_first_stop'][ax]['mean_deg_h']:+.2f} deg/h (Earth "
            f"{a['gyro_noise_at_first_stop'][ax]['earth_rate_deg_h']:+.2f}: bias "
            f"{a['gyro_noise_at_first_stop'][ax]['bias_deg_h']:+.2f}), sd "
            f"{a['gyro_noise_at_first_stop'][ax]['sd_deg_h']:.1f} deg/h (ARW "
            f"{a['gyro_noise_at_first_stop'][ax]['arw_deg_sqrt_h']:.3f} deg/sqrt(h))"
            for ax in ("x", "y", "z")),
        _allan_line(a["imu_allan_at_first_stop"]),
        f"GNSS vs reference: {g['n']} epochs, rms {g['rms_m']:.2f} m, "
        f"median {g['median_m']:.2f} m, "
        f"p95 {g['p95_m']:.2f} m, max {g['max_m']:.1f} m; height - reference median "
        f"{g['height_minus_reference_median_m']:.2f} m",
    ]
    om = a["odometer_error_model"]
    lines += [
        f"odometer error model (reading = scale x reference speed + offset, moving): scale "
        f"{om['scale']:.4f}, offset {om['offset_mps']:+.3f} m/s; reading - reference at "
        f"|acc| < 0.3 m/s^2 by speed: " + ", ".join(
            f"{b['from_mps']:g}-{b['to_mps']:g} m/s {b['mean_difference_mps']:+.3f} m/s "
            f"({100 * b['as_scale_error']:+.1f} %)" for b in om["speed_bins"]),
        "  residual RMS by |acceleration|: " + ", ".join(
            f"{b['acc_from_mps2']:g}-{b['acc_to_mps2']:g} m/s^2 {b['rms_mps']:.3f} m/s "
            f"(n {b['n']})" for b in om["residual_rms_by_acceleration"])
        + "; autocorrelation " + ", ".join(
            f"{k} s {v:.2f}" for k, v in om["residual_acf"].items()),
        "  residual RMS with the reference's speed taken s after the reading's stamp: "
        + ", ".join(f"{k:+.1f} s {v:.3f}" for k, v in om["residual_rms_by_shift_s"].items()
                    if abs(k) <= 0.5)
        + " m/s; smallest of -1..+1 s at "
        + f"{min(om['residual_rms_by_shift_s'], key=om['residual_rms_by_shift_s'].get):+.1f} s",
    ]
    gv, rc = a["gnss_velocity_errors"], a["reference_consistency"]
    lines += [
        f"GNSS velocity vs reference: {gv['n']} epochs, horizontal error median "
        f"{gv['median_mps']:.3f} m/s, p95 {gv['p95_mps']:.3f}, RMS {gv['rms_mps']:.3f}; east "
        "error autocorrelation " + ", ".join(f"{k} s {v:.2f}" for k, v in gv["east_acf"].items()),
        "GNSS position error (north and east) against itself k s later: " + "; ".join(
            f"{name.replace('_', ' ')} " + ", ".join(
                f"{k} s {v['r']:.2f} ({v['pairs']})" for k, v in acf.items()
                if v["r"] is not None)
            for name, acf in a["gnss_error_correlation"].items()),
        f"reference against itself (positions' motion - its velocities' integral over "
        f"{rc['window_s']} s): median {rc['median_m']:.2f} m, p95 {rc['p95_m']:.2f} m, max "
        f"{rc['max_m']:.2f} m (window from {rc['max_at_s']:.0f} s)",
    ]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=None)
    ap.add_argument("--json", default=None, help="also write the numbers here")
    a = ap.parse_args(argv)
    res = analyse(convert.load(a.data))
    print(text(res))
    if a.json:
        Path(a.json).parent.mkdir(parents=True, exist_ok=True)
        Path(a.json).write_text(json.dumps(res, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
