"""Accuracy report: the firmware's NAV_* output log against the simulated truth.

    python -m tools.sim.report --truth out/sim/default/truth.npz --nav out/sim/default/nav.log \
        --out out/sim/default

Writes report.json and three PNG plots (track map, horizontal error, heading error); with
--scenario also the scenario's truths, its one-point calibration (calibration_report), the
Kalman filter's calibration (filter_calibration) and its GNSS faults (gnss_fault_report, at
the nominal times of its [gnss_faults]). The
statistics cover the time the firmware was navigating (NAV_Position present), from the first
NAV_Position frame to the end of the drive. Errors are horizontal distances on the WGS-84
ellipsoid (local radii of curvature), heading errors wrapped to [-180, 180) degrees.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import can
import numpy as np

from tools import navecu_can as nc
from tools.geodesy import horizontal_error_m, radii_m
from tools.sim import scenario, sensors

def read_nav_log(path, db=None, wraps_from_log: bool = False, log_t0_s: float = 0.0,
                 skipped: list | None = None) -> dict:
    """Decode the NAV_* frames of a candump log (every message navecu sends) into arrays
    keyed by message; each has 't_s' and the signal columns.

    't_s' is the firmware's own time of validity (NAV_Height TimeOfValidity, IMU time,
    unwrapped from its 65.536 s modulus), not the log's timestamps: a recording made over
    a live bus, at any replay speed, gives the same times as a --can-log run. Each
    NAV_Position opens a navigation set (Position, Height, Velocity, Attitude) that takes
    its NAV_Height's time; the others take the time of the last set (NaN before one): at
    the default rates every output of a sample follows its set (docs/can.md). db: the
    protocol to decode with (default nc.load_db(), the selected vehicle's).
    wraps_from_log: the log's timestamps are the IMU time plus log_t0_s (a --can-log run
    of the simulator's log; log_t0_s its power-on time): every NAV_Height's modulus is
    resolved with them, so that neither a start held beyond 65.536 s (the automatic
    mounting estimate) nor a longer time without navigation (a re-acquisition waiting for
    the GNSS course) loses a wrap; without it a wrap is counted when TimeOfValidity goes
    back, which misses a gap of more than 65.536 s.
    Each row also has 'seq', the frame's index in the log: what a receiver had seen before
    it (transition_check). A candump log's malformed lines are skipped and counted
    (nc.LogFile): skipped, a list, gets the LogFile; without one a count above 0 is said
    on stderr; so are frames of a NAV_* identifier that are not that message (an extended
    ID, another length) or that fail its E2E check (the CRC in byte 7, a counter of 15;
    nc.check_e2e, docs/can.md): rejected, not decoded."""
    db = db if db is not None else nc.load_db()
    want = {m.frame_id: m.name for m in db.messages if "NAVECU" in m.senders}
    rows = {n: [] for n in want.values()}
    cycle_rows, t_cycle, last_ms, wraps = [], math.nan, None, 0
    length = {m.frame_id: m.length for m in db.messages}
    with nc.LogFile(path) as reader:
        for seq, msg in enumerate(reader):
            name = want.get(msg.arbitration_id)
            if name is None:
                continue
            if msg.is_extended_id or msg.is_remote_frame or len(msg.data) != length[
                    msg.arbitration_id]:
                reader.reject(msg, f"{name} with {len(msg.data)} bytes"
                              + (", extended ID" if msg.is_extended_id else ""))
                continue
            if not nc.check_e2e(msg, db):
                reader.reject(msg, f"{name} failing its E2E check")
                continue
            sig = db.decode_message(msg.arbitration_id, bytes(msg.data), decode_choices=False)
            sig["seq"] = seq
            if name == "NAV_Position":
                cycle_rows = []
            if name == "NAV_Height":
                ms = int(sig["TimeOfValidity"])
                if wraps_from_log:
                    wraps = max(0, round((float(msg.timestamp) - log_t0_s - ms / 1000.0)
                                         / 65.536))
                elif last_ms is not None and ms < last_ms:
                    wraps += 1
                last_ms = ms
                t_cycle = (wraps * 65536 + ms) / 1000.0
                for r in cycle_rows:
                    r["t_s"] = t_cycle
            sig["t_s"] = t_cycle
            if name != "NAV_Status":
                cycle_rows.append(sig)
            rows[name].append(sig)
    if skipped is not None:
        skipped.append(reader)
    elif reader.skipped:
        print(f"read_nav_log: {reader.note()}", file=sys.stderr)
    out = {}
    for name, lst in rows.items():
        if lst:
            keys = lst[0].keys() if name != "NAV_Status" else set().union(*lst)
            out[name] = {k: np.array([r.get(k, np.nan) for r in lst], dtype=float) for k in keys}
    return out


def _frames_with_ids(path, ids):
    """(frame_id, data) of the frames with these IDs, in log order. A candump -L text log
    (.log) is scanned line by line for them (a million-frame log in about a second), its
    malformed lines (nc.CANDUMP_LINE) left out as read_nav_log leaves them out and counts
    them; any other format goes through python-can's LogReader."""
    if str(path).endswith(".log"):
        keys = {f"{i:03{c}}#" for i in ids for c in "Xx"}
        with open(path, encoding="utf-8", errors="replace") as fh:
            for line in fh:
                if not any(k in line for k in keys):
                    continue
                if nc.CANDUMP_LINE.fullmatch(line.rstrip("\n")):
                    ident, data = line.split()[2].split("#")
                    if int(ident, 16) in ids:
                        yield int(ident, 16), bytes.fromhex(data)
        return
    with can.LogReader(str(path)) as reader:
        for msg in reader:
            if msg.arbitration_id in ids:
                yield msg.arbitration_id, bytes(msg.data)


def read_calibration_log(path, page: int = 0) -> dict:
    """NAV_Calibration frames of a candump log as arrays: 't_s' and the signals (raw
    numbers, CalStatus/CalSource as their values). The frame is sent once a second on the
    sample clock and carries no time of its own: 't_s' is that of the last NAV_Height
    before it (its TimeOfValidity, unwrapped like read_nav_log's), NaN before the first.
    page: CalPage, 0 the calibration, 1 and 2 the automatic mounting estimate."""
    db = nc.load_db()
    cal_id = db.get_message_by_name("NAV_Calibration").frame_id
    height = db.get_message_by_name("NAV_Height")
    tov = height.get_signal_by_name("TimeOfValidity")
    assert tov.byte_order == "little_endian" and tov.scale == 1 and tov.offset == 0
    tov_mask = (1 << tov.length) - 1
    rows, t_last, last_ms, wraps = [], math.nan, None, 0
    for frame_id, data in _frames_with_ids(path, {cal_id, height.frame_id}):
        if frame_id == height.frame_id:
            ms = (int.from_bytes(data, "little") >> tov.start) & tov_mask
            if last_ms is not None and ms < last_ms:
                wraps += 1
            last_ms = ms
            t_last = (wraps * (tov_mask + 1) + ms) / 1000.0
        else:
            sig = db.decode_message(cal_id, data, decode_choices=False)
            if sig.get("CalPage", 0) != page:
                continue
            sig["t_s"] = t_last
            rows.append(sig)
    keys = rows[0].keys() if rows else ("t_s", "HeadingCorrection", "OdoScaleError", "CalValid",
                                        "CalStored", "CalStatus", "CalSource", "CalCount")
    return {k: np.array([r[k] for r in rows], dtype=float) for k in keys}


def _choice(signal: str, value) -> str | None:
    """The DBC's name of a NAV_Calibration enumeration value (VAL_ 785)."""
    if value is None or not np.isfinite(value):
        return None
    sig = nc.load_db().get_message_by_name("NAV_Calibration").get_signal_by_name(signal)
    return str((sig.choices or {}).get(int(value), int(value)))


def calibration_report(truth: dict, series: dict, cal_log: dict, cal: dict, truths: dict) -> dict:
    """report.json's "calibration": the one-point calibration requested at cal["at_s"]
    (a scenario's [calibration]) as the firmware did it, against the scenario's truths.

    performed: NAV_Calibration's CalCount rose above its first value with a source other
    than Filter (the filter's adoptions count too); time_s, dH_deg, mu:
    that frame's time, HeadingCorrection and OdoScaleError. error_before_*: the horizontal
    error of the last NAV_Position at or before at_s over the distance travelled from the
    start of navigation to at_s; error_after_*: the largest error after the calibration
    over the distance travelled from it to the end of the drive (only if performed).
    dH_firmware_at_cal_deg: NAV_Attitude heading - true heading at at_s (the configured
    dH_true plus the gyros' drift since the start)."""
    at = float(cal["at_s"])
    rep = {"requested_at_s": at, "source": cal["source"], "performed": False, "time_s": None,
           "dH_deg": None, "mu": None, "dH_true_deg": truths["dH_deg"],
           "mu_true": truths["odometer_mu"], "dH_firmware_at_cal_deg": None,
           "cal_count": None, "cal_status": None, "cal_source": None,
           "distance_before_m": None, "error_before_m": None, "error_before_pct": None,
           "distance_after_m": None, "error_after_max_m": None, "error_after_final_m": None,
           "error_after_pct": None}
    n = len(cal_log.get("t_s", ()))
    if n:
        count = cal_log["CalCount"]
        # the one-point calibration: CalCount up from another source than the filter's
        # own adoptions (CalSource Filter), which count too
        src = np.asarray(cal_log["CalSource"], dtype=float)
        done = np.nonzero((count > count[0]) & (src != FILTER_CAL_SOURCE))[0]
        i = int(done[0]) if len(done) else n - 1
        rep.update({"cal_count": int(count[i]),
                    "cal_status": _choice("CalStatus", cal_log["CalStatus"][i]),
                    "cal_source": _choice("CalSource", cal_log["CalSource"][i])})
        if len(done):
            t_c = float(cal_log["t_s"][i])
            rep.update({"performed": True, "time_s": t_c if np.isfinite(t_c) else None,
                        "dH_deg": float(cal_log["HeadingCorrection"][i]),
                        "mu": float(cal_log["OdoScaleError"][i])})
    if "heading" in series:
        th, dh = series["heading"]
        if len(th) and th[0] <= at:
            rep["dH_firmware_at_cal_deg"] = float(np.interp(at, th, dh))
    if "t" not in series:
        return rep
    t, herr = series["t"], series["herr"]
    dist = np.interp(t, truth["t_s"], truth["dist_m"])
    before = np.nonzero(t <= at)[0]
    if len(before):
        k = int(before[-1])
        d_b = float(np.interp(at, truth["t_s"], truth["dist_m"]) - dist[0])
        rep.update({"distance_before_m": d_b, "error_before_m": float(herr[k]),
                    "error_before_pct": float(100.0 * herr[k] / d_b) if d_b > 0 else None})
    if rep["performed"]:
        t_c = rep["time_s"] if rep["time_s"] is not None else at
        after = t > t_c
        d_a = float(truth["dist_m"][-1] - np.interp(t_c, truth["t_s"], truth["dist_m"]))
        if after.any():
            e_max = float(herr[after].max())
            rep.update({"distance_after_m": d_a, "error_after_max_m": e_max,
                        "error_after_final_m": float(herr[after][-1]),
                        "error_after_pct": float(100.0 * e_max / d_a) if d_a > 0 else None})
    return rep


def calibration_marks(cal_rep) -> list:
    """[(t_s, label)] for the plots: when the firmware calibrated, else when it was asked."""
    if not cal_rep:
        return []
    if cal_rep["performed"] and cal_rep["time_s"] is not None:
        return [(cal_rep["time_s"], "calibration")]
    return [(cal_rep["requested_at_s"], "calibration requested (not done)")]


def _interp_truth(truth, t_s):
    """Truth lat, lon, heading at times t_s (linear in time; headings unwrapped)."""
    lat = np.interp(t_s, truth["t_s"], truth["lat_rad"])
    lon = np.interp(t_s, truth["t_s"], np.unwrap(truth["lon_rad"]))
    hdg = np.interp(t_s, truth["t_s"], np.unwrap(truth["heading_rad"]))
    return lat, lon, hdg


def _stats(x):
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return {"rms": None, "p95": None, "max": None, "final": None}
    return {"rms": float(np.sqrt(np.mean(x ** 2))), "p95": float(np.percentile(x, 95)),
            "max": float(np.max(x)), "final": float(x[-1])}


HORIZ_ACCURACY_UNKNOWN_M = 655.35   # NAV_Status HorizAccuracy saturated: "unknown"
SIGMA_MAX_AGE_S = 1.0               # a page-0 sigma older than this does not count
# a consistent filter, if HorizAccuracy is sqrt(sigma_E^2 + sigma_N^2) (DRMS) of a circular
# Gaussian error: P(r <= 2 DRMS) = 1 - exp(-4), median r = sqrt(ln 2) DRMS; if it is the
# per-axis sigma: 1 - exp(-2) and sqrt(2 ln 2)
SIGMA_CONSISTENT_DRMS = {"frac_within_2sigma": 1.0 - math.exp(-4.0),
                         "median_error_over_sigma": math.sqrt(math.log(2.0))}
SIGMA_CONSISTENT_PER_AXIS = {"frac_within_2sigma": 1.0 - math.exp(-2.0),
                             "median_error_over_sigma": math.sqrt(2.0 * math.log(2.0))}


def status_page(status, page: int, signal: str):
    """(t_s, values) of one NAV_Status page's signal, rows with a time and a value only."""
    if status is None or signal not in status or "StatusPage" not in status:
        return np.zeros(0), np.zeros(0)
    sel = ((status["StatusPage"] == page) & np.isfinite(status["t_s"])
           & np.isfinite(status[signal]))
    t, v = status["t_s"][sel], status[signal][sel]
    order = np.argsort(t, kind="stable")
    return t[order], v[order]


def latest_at(t_src, v_src, t, max_age_s=math.inf):
    """The latest v_src at or before each t (NaN where none, or older than max_age_s)."""
    t = np.asarray(t, dtype=float)
    k = np.searchsorted(t_src, t, side="right") - 1
    ok = k >= 0
    kk = np.clip(k, 0, None)
    out = np.full(t.shape, np.nan)
    if len(t_src):
        ok &= (t - t_src[kk]) <= max_age_s
        out[ok] = v_src[kk[ok]]
    return out


def sigma_consistency(t, herr, status) -> dict:
    """The firmware's own accuracy claim against its error: at each NAV_Position time the
    latest NAV_Status page-0 HorizAccuracy (the firmware's horizontal accuracy claim,
    docs/can.md; at most SIGMA_MAX_AGE_S old; NAV_Status takes the time of the NAV_Height
    before it, read_nav_log), epochs whose sigma is 655.35 ("unknown") or 0 skipped.
    frac_within_2sigma: share of the epochs with error <= 2 sigma; median_error_over_sigma:
    median of error / sigma. status "unknown" when no epoch has a sigma. The values a
    consistent filter gives are beside them (if_consistent_*)."""
    t, herr = np.asarray(t, dtype=float), np.asarray(herr, dtype=float)
    out = {"status": "unknown", "epochs": int(t.size), "epochs_used": 0,
           "epochs_sigma_unknown": 0, "epochs_sigma_zero": 0, "epochs_without_status": 0,
           "frac_within_2sigma": None, "median_error_over_sigma": None,
           "sigma_median_m": None, "error_median_m": None,
           "source": "NAV_Status page 0 HorizAccuracy, latest at or before each NAV_Position",
           "if_consistent_drms": SIGMA_CONSISTENT_DRMS,
           "if_consistent_per_axis_sigma": SIGMA_CONSISTENT_PER_AXIS}
    ts, sg = status_page(status, 0, "HorizAccuracy")
    sig = latest_at(ts, sg, t, SIGMA_MAX_AGE_S)
    none = ~np.isfinite(sig)
    unknown = ~none & (sig >= HORIZ_ACCURACY_UNKNOWN_M - 0.005)
    zero = ~none & ~unknown & (sig <= 0.0)
    ok = ~none & ~unknown & ~zero
    out.update({"epochs_used": int(ok.sum()), "epochs_sigma_unknown": int(unknown.sum()),
                "epochs_sigma_zero": int(zero.sum()), "epochs_without_status": int(none.sum())})
    if ok.any():
        r = herr[ok] / sig[ok]
        out.update({"status": "ok", "frac_within_2sigma": float(np.mean(r <= 2.0)),
                    "median_error_over_sigma": float(np.median(r)),
                    "sigma_median_m": float(np.median(sig[ok])),
                    "error_median_m": float(np.median(herr[ok]))})
    return out


VERT_ACCURACY_UNKNOWN_M = 25.5   # NAV_Height VertAccuracy raw 255: the filter not running
# a consistent per-axis sigma: P(|e| <= 2 sigma) of a Gaussian, median |e| / sigma
VERT_CONSISTENT = {"frac_within_2sigma": math.erf(2.0 / math.sqrt(2.0)),
                   "median_error_over_sigma": 0.6744897501960817}


def height_report(truth: dict, nav: dict) -> dict:
    """The height against the truth's (truth.npz h_m, the same ellipsoid): NAV_Height's
    Height at its time of validity, |error| statistics, and the share within 2
    VertAccuracy (NAV_Height's own 1-sigma; 25.5 "unknown" skipped, a saturated 25.4 taken
    as it is, a claim no larger than the firmware's). status "unknown" without a truth
    height (an older truth.npz) or a NAV_Height."""
    out = {"status": "unknown", "error_m": _stats([]), "epochs": 0, "epochs_used": 0,
           "frac_within_2sigma": None, "median_error_over_sigma": None,
           "if_consistent": VERT_CONSISTENT}
    hgt = nav.get("NAV_Height")
    if "h_m" not in truth or hgt is None:
        return out
    ok_t = np.isfinite(hgt["t_s"])
    t, h, sv = hgt["t_s"][ok_t], hgt["Height"][ok_t], hgt["VertAccuracy"][ok_t]
    if not t.size:
        return out
    err = h - np.interp(t, truth["t_s"], truth["h_m"])
    st = _stats(np.abs(err))
    st["final"] = float(err[-1])
    st["mean"] = float(np.mean(err))
    out.update({"status": "ok", "error_m": st, "epochs": int(t.size)})
    known = (sv < VERT_ACCURACY_UNKNOWN_M - 0.05) & (sv > 0.0)
    if known.any():
        r = np.abs(err[known]) / sv[known]
        out.update({"epochs_used": int(known.sum()),
                    "frac_within_2sigma": float(np.mean(r <= 2.0)),
                    "median_error_over_sigma": float(np.median(r))})
    return out


def last_counter(status, page: int, signal: str):
    """The last value of a NAV_Status counter page's signal, None when never sent."""
    _, v = status_page(status, page, signal)
    return int(v[-1]) if v.size else None


def modes_seen(status) -> dict:
    """NAV_Status page-0 Mode by its DBC name (VAL_ 784): number of frames and share."""
    _, mode = status_page(status, 0, "Mode")
    if not mode.size:
        return {}
    names = nc.load_db().get_message_by_name("NAV_Status").get_signal_by_name("Mode").choices or {}
    return {str(names.get(int(m), int(m))): {"frames": int(np.sum(mode == m)),
                                             "share": float(np.mean(mode == m))}
            for m in np.unique(mode)}


# NAV_Status's multiplexed page that carries CntOdoRejected (the DBC's multiplexer id)
ODO_REJECTED_PAGE = nc.load_db().get_message_by_name("NAV_Status").get_signal_by_name(
    "CntOdoRejected").multiplexer_ids[0]
FILTER_CAL_SOURCE = nc.choice_value("NAV_Calibration", "CalSource", "Filter")  # VAL_ 785
FILTER_CAL_GNSS_DRIVING_S = 600.0
MOVING_MPS = 0.1
GNSS_FRESH_S = 1.0


def gnss_driving_reached(truth: dict, seconds: float, t_from: float = 0.0, gnss_t=None,
                         outages=()):
    """The drive time at which the car has driven `seconds` with GNSS since t_from, None if
    never. Driving: truth speed (d dist/dt) above MOVING_MPS; with GNSS: a valid epoch in
    the last GNSS_FRESH_S (gnss_t: their times), or without gnss_t outside the outages."""
    t = np.asarray(truth["t_s"], dtype=float)
    if t.size < 2:
        return None
    moving = np.gradient(np.asarray(truth["dist_m"], dtype=float), t) > MOVING_MPS
    if gnss_t is not None:
        gt = np.sort(np.asarray(gnss_t, dtype=float))
        have = np.isfinite(latest_at(gt, gt, t, GNSS_FRESH_S))
    else:
        have = np.ones(t.size, dtype=bool)
        for (a, b, *_l) in outages:
            have &= ~((t >= a) & (t <= b))
    use = (moving & have & (t >= t_from))[1:]
    cum = np.concatenate([[0.0], np.cumsum(use * np.diff(t))])
    k = int(np.searchsorted(cum, seconds - 1e-9))
    return float(t[k]) if k < t.size else None


def filter_calibration(cal_log: dict, truths: dict | None, t_gnss: float | None) -> dict:
    """report.json's "filter_calibration": the Kalman filter's odometer scale error
    (NAV_Calibration OdoScaleError) and IMU mounting yaw (HeadingCorrection, deg) from the
    frames with CalSource 3 "Filter": the last one at or before t_gnss (the time the car had
    driven FILTER_CAL_GNSS_DRIVING_S with GNSS, gnss_driving_reached) as odo_scale,
    mount_yaw_deg, at_s, and the last of the drive as "last"; the truths beside (mu_true;
    mount_yaw_true_deg: [imu_mounting] yaw, the IMU's forward axis clockwise of the car's,
    the convention of firmware/nav/ekf.h's mounting state) and the differences."""
    truths = truths or {}
    mu = truths.get("odometer_mu")
    yaw = (truths.get("imu_mounting_deg") or {}).get("yaw")
    t = np.asarray(cal_log.get("t_s", ()), dtype=float)
    src = np.asarray(cal_log.get("CalSource", np.full(t.size, np.nan)), dtype=float)
    idx = np.nonzero((src == FILTER_CAL_SOURCE) & np.isfinite(t))[0]

    def entry(i):
        k, y = float(cal_log["OdoScaleError"][i]), float(cal_log["HeadingCorrection"][i])
        return {"at_s": float(t[i]), "odo_scale": k, "mount_yaw_deg": y,
                "odo_scale_error": k - mu if mu is not None else None,
                "mount_yaw_error_deg": y - yaw if yaw is not None else None}

    rep = {"at_s": None, "odo_scale": None, "mount_yaw_deg": None, "odo_scale_error": None,
           "mount_yaw_error_deg": None, "mu_true": mu, "mount_yaw_true_deg": yaw,
           "gnss_driving_s": FILTER_CAL_GNSS_DRIVING_S, "gnss_driving_reached_at_s": t_gnss,
           "frames": int(idx.size), "last": None}
    if idx.size:
        rep["last"] = entry(int(idx[-1]))
        if t_gnss is not None:
            upto = idx[t[idx] <= t_gnss + 1e-9]
            if upto.size:
                rep.update(entry(int(upto[-1])))
    return rep


FAULT_WINDOW_S = 10.0      # the fault's neighbourhood: its first to last frame +- this
FAULT_CLEAN_S = 60.0       # the clean neighbourhood: this much more on either side
FAULT_OUTAGE_SETTLE_S = 30.0


def fault_windows_from_table(faults: dict) -> list:
    """Nominal fault log entries (kind, t_start_s, t_end_s, parameters) from a scenario's
    validated [gnss_faults], for report.main (the run's own log has the epoch times)."""
    out = [dict(f, kind="freeze", t_start_s=f["t0_s"], t_end_s=f["t1_s"])
           for f in faults.get("freeze", [])]
    out += [dict(f, kind="jump", t_start_s=f["t_s"], t_end_s=f["t_s"] + f["duration_s"])
            for f in faults.get("jumps", [])]
    out += [dict(f, kind="latency_spike", t_start_s=f["t_s"], t_end_s=f["t_s"] + f["extra_s"])
            for f in faults.get("latency_spike", [])]
    return out


def gnss_fault_report(series: dict, status, fault_log: list, outages=()) -> list:
    """report.json's "gnss_faults": per injected fault (sensors.apply_gnss_faults' log), the
    largest horizontal error and the largest step of the error vector between consecutive
    NAV_Positions (a jump of the solution) within FAULT_WINDOW_S of the fault's frames,
    against the same in its clean neighbourhood (FAULT_CLEAN_S further on either side,
    without the other faults' windows, the GNSS outages and FAULT_OUTAGE_SETTLE_S after
    them); and NAV_Status page 3 CntGnssRejected, the last value before the fault's first
    frame and the last within FAULT_WINDOW_S after its last."""
    t = series.get("t", np.zeros(0))
    herr = series.get("herr", np.zeros(0))
    if t.size:
        step = np.concatenate([[0.0], np.hypot(np.diff(series["de"]), np.diff(series["dn"]))])
    else:
        step = np.zeros(0)
    tr, rej = status_page(status, 3, "CntGnssRejected")
    out = []
    fault_log = sorted(fault_log, key=lambda f: f["t_start_s"])
    for j, f in enumerate(fault_log):
        a, b = f["t_start_s"], f["t_end_s"]
        win = (t >= a - FAULT_WINDOW_S) & (t <= b + FAULT_WINDOW_S)
        clean = (t >= a - FAULT_WINDOW_S - FAULT_CLEAN_S) & (t <= b + FAULT_WINDOW_S
                                                               + FAULT_CLEAN_S) & ~win
        for k, g in enumerate(fault_log):
            if k != j:
                clean &= ~((t >= g["t_start_s"] - FAULT_WINDOW_S)
                           & (t <= g["t_end_s"] + FAULT_WINDOW_S))
        for (o0, o1, *_l) in outages:
            clean &= ~((t >= o0) & (t <= o1 + FAULT_OUTAGE_SETTLE_S))
        before = tr < a
        after = tr <= b + FAULT_WINDOW_S
        r0 = int(rej[before][-1]) if before.any() else None
        r1 = int(rej[after][-1]) if after.any() else None
        e = {k: v for k, v in f.items() if k != "epoch_t_s"}
        e.update({
            "window_s": [a - FAULT_WINDOW_S, b + FAULT_WINDOW_S],
            "max_error_m": float(herr[win].max()) if win.any() else None,
            "clean_max_error_m": float(herr[clean].max()) if clean.any() else None,
            "clean_rms_error_m": float(np.sqrt(np.mean(herr[clean] ** 2))) if clean.any()
            else None,
            "max_step_m": float(step[win].max()) if win.any() else None,
            "clean_max_step_m": float(step[clean].max()) if clean.any() else None,
            "cnt_gnss_rejected_before": r0, "cnt_gnss_rejected_after": r1,
            "gnss_rejected": r1 - r0 if r0 is not None and r1 is not None else None})
        out.append(e)
    return out


def navecu_binary(path) -> dict:
    """Which firmware build produced a result (it changes under active development): the
    binary's path, SHA-256 and modification time."""
    import hashlib
    import time
    p = Path(path)
    return {"path": str(p), "sha256": hashlib.sha256(p.read_bytes()).hexdigest(),
            "modified_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(p.stat().st_mtime))}


def fault_marks(fault_rep) -> list:
    """[(t_s, label)] for the plots: each injected GNSS fault's first frame."""
    return [(f["t_start_s"], f"GNSS {f['kind'].replace('_', ' ')}") for f in fault_rep or []]


def compute(truth: dict, nav: dict, outages) -> tuple[dict, dict]:
    """report.json content and the series for plotting."""
    pos = nav.get("NAV_Position")
    t_end = float(truth["t_s"][-1])
    dist_total = float(truth["dist_m"][-1])
    rep = {"duration_s": t_end, "distance_m": dist_total}
    series = {}
    if pos is None:
        rep.update({"navigating": False, "horizontal_error_m": _stats([]),
                    "heading_error_deg": {"rms": None, "max": None},
                    "final_error_pct_of_distance": None, "outages": [],
                    "sigma_consistency": sigma_consistency(np.zeros(0), np.zeros(0), None),
                    "modes_seen": modes_seen(nav.get("NAV_Status"))})
        return rep, series
    t = pos["t_s"]
    lat_e, lon_e = np.radians(pos["Latitude"]), np.radians(pos["Longitude"])
    lat_t, lon_t, _ = _interp_truth(truth, t)
    herr, de, dn = horizontal_error_m(lat_t, lon_t, lat_e, lon_e)
    dist_at = np.interp(t, truth["t_s"], truth["dist_m"])
    nav_dist = float(dist_at[-1] - dist_at[0])
    rep["navigating"] = True
    rep["navigation_start_s"] = float(t[0])
    rep["horizontal_error_m"] = _stats(herr)
    rep["final_error_pct_of_distance"] = (float(100.0 * herr[-1] / nav_dist)
                                          if nav_dist > 0 else None)
    att = nav.get("NAV_Attitude")
    if att is not None:
        _, _, hdg_t = _interp_truth(truth, att["t_s"])
        dh = (np.radians(att["Heading"]) - hdg_t + math.pi) % (2 * math.pi) - math.pi
        dh_deg = np.degrees(dh)
        rep["heading_error_deg"] = {"rms": float(np.sqrt(np.mean(dh_deg ** 2))),
                                    "max": float(np.max(np.abs(dh_deg)))}
        series["heading"] = (att["t_s"], dh_deg)
    else:
        rep["heading_error_deg"] = {"rms": None, "max": None}
    rep["outages"] = []
    for (t0, t1, *label) in outages:
        sel = (t >= t0) & (t <= t1)
        d0, d1 = np.interp([t0, t1], truth["t_s"], truth["dist_m"])
        end = float(herr[sel][-1]) if sel.any() else None
        entry = {"start_s": float(t0), "end_s": float(t1), "distance_m": float(d1 - d0),
                 "label": label[0] if label else "",
                 "start_error_m": float(herr[sel][0]) if sel.any() else None,
                 "max_error_m": float(herr[sel].max()) if sel.any() else None,
                 "end_error_m": end,
                 "end_error_pct_of_distance": (float(100.0 * end / (d1 - d0))
                                               if end is not None and d1 - d0 > 1.0 else None)}
        rep["outages"].append(entry)
    status = nav.get("NAV_Status")
    rep["sigma_consistency"] = sigma_consistency(t, herr, status)
    rep["height"] = height_report(truth, nav)
    rep["odo_rejected"] = last_counter(status, ODO_REJECTED_PAGE, "CntOdoRejected")
    rep["modes_seen"] = modes_seen(status)
    series.update({"t": t, "herr": herr, "de": de, "dn": dn, "lat_e": lat_e, "lon_e": lon_e})
    return rep, series


def power_on_report(truth: dict, series: dict, t_on_s: float, restart: bool = False) -> dict:
    """A start at t_on_s (run.py --power-on-s; with restart, a CMD_Control Reset at t_on_s,
    run.py --reset-s): the time from it to the first NAV_Position after it, the largest
    horizontal error from 30 s after it to the end (m), the error 30 s and 60 s after it
    (None if not navigating then),
    the largest heading error from 60 s on (deg), and the truth's speed at t_on_s (m/s). With restart, output_stopped says
    whether the output paused after the reset (no NAV_Position within 0.5 s of it), as it
    must when navigation starts again."""
    speed = float(np.interp(t_on_s, truth["t_s"][1:], np.diff(truth["dist_m"])
                            / np.diff(truth["t_s"])))
    rep = {"speed_mps": speed, "first_output_s": None, "max_error_from_30s_m": None,
           "max_heading_error_from_60s_deg": None, "error_at_30s_m": None,
           "error_at_60s_m": None}
    if restart:
        rep["output_stopped"] = None
    if "t" not in series or len(series["t"]) == 0:
        return rep
    t, herr = series["t"], series["herr"]
    after = t > t_on_s
    if not after.any():
        return rep
    t, herr = t[after], herr[after]
    rep["first_output_s"] = float(t[0] - t_on_s)
    if restart:
        rep["output_stopped"] = bool(t[0] - t_on_s > 0.5)
    sel = t >= t_on_s + 30.0
    rep["max_error_from_30s_m"] = float(herr[sel].max()) if sel.any() else None
    for at in (30.0, 60.0):   # the epoch then (None: not navigating then)
        k = int(np.searchsorted(t, t_on_s + at))
        ok = k < t.size and t[k] - (t_on_s + at) <= 0.5
        rep[f"error_at_{at:.0f}s_m"] = float(herr[k]) if ok else None
    if "heading" in series:
        th, dh = series["heading"]
        sel = th >= t_on_s + 60.0
        rep["max_heading_error_from_60s_deg"] = float(np.abs(dh[sel]).max()) if sel.any() else None
    return rep


NAVIGATING_MODES = ("Inertial", "DeadReckoning", "GnssIns")   # VAL_ 784 Mode
TRANSITION_WINDOW_S = 60.0


def transition_check(series: dict, nav: dict, events, window_s=TRANSITION_WINDOW_S) -> dict:
    """Issue #17's rule for every transition, as a receiver of the output sees it: for each
    NAV_Position, the NAV_Status page 0 received last before it in the log (read_nav_log's
    'seq'): the position's horizontal error against 3 x that status's HorizAccuracy, and
    whether its Mode is a navigating one (no position may follow a status that says
    WaitInit, Levelling or Fault). Over the whole run and in the window_s after each event
    (power-on, the first navigation, a reset). max_error_over_sigma must stay <= 3 and
    positions_not_navigating at 0. A sigma of 655.35 m ("unknown") passes any error; such
    epochs are counted."""
    out = {"rule": "error <= 3 x NAV_Status HorizAccuracy; no NAV_Position unless the last "
                   "NAV_Status before it says " + "/".join(NAVIGATING_MODES),
           "window_s": window_s, "events_s": [float(e) for e in events], "epochs": 0,
           "epochs_in_windows": 0, "max_error_over_sigma": None,
           "max_error_over_sigma_in_windows": None, "worst_epoch_s": None,
           "epochs_over_3_sigma": 0, "epochs_sigma_unknown": 0,
           "positions_not_navigating": 0, "positions_without_status": 0}
    pos, status = nav.get("NAV_Position"), nav.get("NAV_Status")
    if "t" not in series or len(series["t"]) == 0 or pos is None:
        return out
    t, herr = series["t"], series["herr"]
    p_seq = pos["seq"]
    if status is not None:
        sel = status["StatusPage"] == 0
        s_seq, s_sig, s_mode = status["seq"][sel], status["HorizAccuracy"][sel], status["Mode"][sel]
    else:
        s_seq = s_sig = s_mode = np.zeros(0)
    k = np.searchsorted(s_seq, p_seq, side="left") - 1
    have = k >= 0
    kk = np.clip(k, 0, None)
    sig = np.where(have, s_sig[kk] if s_sig.size else np.nan, np.nan)
    md = np.where(have, s_mode[kk] if s_mode.size else np.nan, np.nan)
    names = nc.load_db().get_message_by_name("NAV_Status").get_signal_by_name("Mode").choices or {}
    nav_codes = [int(c) for c, v in names.items() if str(v) in NAVIGATING_MODES]
    not_nav = have & ~np.isin(np.nan_to_num(md, nan=-1.0), nav_codes)
    unknown = have & (sig >= HORIZ_ACCURACY_UNKNOWN_M - 0.005)
    ok = have & ~unknown & (sig > 0.0)
    ratio = np.full(t.shape, np.nan)
    ratio[ok] = herr[ok] / sig[ok]
    ratio[have & (sig <= 0.0)] = np.inf   # a zero sigma claims exactness
    win = np.zeros(t.shape, dtype=bool)
    for e in events:
        win |= (t >= e) & (t <= e + window_s)
    fin = ~np.isnan(ratio)
    out.update({"epochs": int(t.size), "epochs_in_windows": int(win.sum()),
                "epochs_over_3_sigma": int(np.sum(fin & (ratio > 3.0))),
                "epochs_sigma_unknown": int(unknown.sum()),
                "positions_not_navigating": int(not_nav.sum()),
                "positions_without_status": int((~have).sum())})
    if fin.any():
        j = int(np.argmax(np.where(fin, ratio, -1.0)))
        out["max_error_over_sigma"] = float(ratio[j])
        out["worst_epoch_s"] = float(t[j])
    if (fin & win).any():
        out["max_error_over_sigma_in_windows"] = float(np.max(ratio[fin & win]))
    if not_nav.any():
        out["first_not_navigating_s"] = float(t[not_nav][0])
    return out


def transition_line(tr: dict) -> str:
    """One line for a run's summary: transition_check's result."""
    m = tr.get("max_error_over_sigma")
    mw = tr.get("max_error_over_sigma_in_windows")
    return (f"transitions (error vs 3 x HorizAccuracy, {tr['window_s']:g} s after "
            f"{', '.join(f'{e:g}' for e in tr['events_s'])} s): max error/sigma "
            f"{'-' if mw is None else f'{mw:.2f}'} in the windows, "
            f"{'-' if m is None else f'{m:.2f}'} over the run (at {tr['worst_epoch_s']} s), "
            f"{tr['epochs_over_3_sigma']} epochs over 3 sigma; "
            f"{tr['positions_not_navigating']} positions output while not navigating, "
            f"{tr['positions_without_status']} without a status")


def plot(truth: dict, series: dict, gnss, outages, out_dir: Path, title: str,
         marks=()) -> list:
    """Track map, horizontal error and heading error PNGs; returns their paths. marks:
    [(t_s, label)] drawn as vertical lines over time and as points on the true track."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    lat0, lon0 = truth["lat_rad"][0], truth["lon_rad"][0]
    rm, rn = radii_m(lat0)

    def en(lat, lon):
        return (np.asarray(lon) - lon0) * rn * math.cos(lat0), (np.asarray(lat) - lat0) * rm

    paths = []
    fig, ax = plt.subplots(figsize=(8, 8))
    te, tn = en(truth["lat_rad"], truth["lon_rad"])
    ax.plot(te, tn, color="0.2", lw=2.0, label="truth")
    for k, (t0, t1, *label) in enumerate(outages):
        sel = (truth["t_s"] >= t0) & (truth["t_s"] <= t1)
        ax.plot(te[sel], tn[sel], color="tab:red", lw=5, alpha=0.45,
                label="GNSS outage" if k == 0 else None)
    if gnss is not None and len(gnss["t_s"]):
        ge, gn = en(gnss["lat_rad"], gnss["lon_rad"])
        ax.plot(ge, gn, ".", ms=2, color="tab:green", alpha=0.6, label="GNSS fixes")
    if "t" in series:
        ne, nn = en(series["lat_e"], series["lon_e"])
        ax.plot(ne, nn, color="tab:blue", lw=1.2, label="navecu")
    ax.plot(te[0], tn[0], "k^", ms=9, label="start")
    for t_m, label in marks:
        lat_m = np.interp(t_m, truth["t_s"], truth["lat_rad"])
        lon_m = np.interp(t_m, truth["t_s"], np.unwrap(truth["lon_rad"]))
        me, mn = en(lat_m, lon_m)
        ax.plot(me, mn, "*", color="tab:purple", ms=14, label=f"{label}, {t_m:.0f} s")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    ax.legend(loc="best")
    ax.set_title(f"{title}: track")
    p = out_dir / "track.png"
    fig.savefig(p, dpi=110, bbox_inches="tight")
    plt.close(fig)
    paths.append(p)

    paths += plot_error_series(series, outages, marks, title, out_dir, "time (min)")
    return paths


def plot_error_series(series, outages, marks, title, out_dir, xlabel,
                      log_above_m=None) -> list:
    """horizontal_error.png and heading_error.png against time: series as compute() gives
    it ("t", "herr", "heading"), outages as (t0, t1, ...) spans, marks as (t, label) lines;
    a log scale when the error exceeds log_above_m. Shared by the simulator's and the
    Kingston drive's reports."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    paths = []
    for key, ylabel, fname in (("herr", "horizontal error (m)", "horizontal_error.png"),
                               ("heading", "heading error (deg)", "heading_error.png")):
        fig, ax = plt.subplots(figsize=(10, 4))
        if key == "herr" and "t" in series:
            ax.plot(series["t"] / 60.0, series["herr"], color="tab:blue")
            if log_above_m is not None and series["herr"].max() > log_above_m:
                ax.set_yscale("log")
        elif key == "heading" and "heading" in series:
            ax.plot(series["heading"][0] / 60.0, series["heading"][1], color="tab:blue")
        for k, (t0, t1, *_) in enumerate(outages):
            ax.axvspan(t0 / 60.0, t1 / 60.0, color="tab:red", alpha=0.15,
                       label="GNSS outage" if k == 0 else None)
        for t_m, label in marks:
            ax.axvline(t_m / 60.0, color="tab:purple", ls="--", lw=1.2, label=label)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        if outages or marks:
            ax.legend(loc="upper left", fontsize=8)
        ax.set_title(f"{title}: {ylabel}")
        p = Path(out_dir) / fname
        fig.savefig(p, dpi=110, bbox_inches="tight")
        plt.close(fig)
        paths.append(p)
    return paths


def summary_table(rep: dict) -> str:
    """A short human summary of report.json."""
    h = rep["horizontal_error_m"]
    lines = [f"drive: {rep['duration_s'] / 60:.1f} min, {rep['distance_m'] / 1000:.2f} km"]
    if not rep.get("navigating"):
        lines.append("navecu never started navigating (see its NAV_Status)")
        return "\n".join(lines)

    def f(x, unit="m"):
        return "n/a" if x is None else f"{x:.2f} {unit}"

    lines += [f"horizontal error: rms {f(h['rms'])}, p95 {f(h['p95'])}, max {f(h['max'])}, "
              f"final {f(h['final'])} ({f(rep['final_error_pct_of_distance'], '%')} of distance)",
              f"heading error:    rms {f(rep['heading_error_deg']['rms'], 'deg')}, "
              f"max {f(rep['heading_error_deg']['max'], 'deg')}"]
    hr = rep.get("height")
    if hr and hr["status"] == "ok":
        e = hr["error_m"]
        within = ("no VertAccuracy known" if hr["frac_within_2sigma"] is None else
                  f"{hr['frac_within_2sigma'] * 100:.1f} % within 2 VertAccuracy, median "
                  f"|error|/sigma {hr['median_error_over_sigma']:.2f} (95.4 %, 0.67 if "
                  "consistent)")
        lines.append(f"height error:     rms {f(e['rms'])}, max {f(e['max'])}, mean "
                     f"{e['mean']:+.2f} m, final {e['final']:+.2f} m; {within}")
    elif hr:
        lines.append("height error:     unknown (no truth height or no NAV_Height)")
    if "odo_rejected" in rep:
        n_odo = rep["odo_rejected"]
        lines.append("odometer updates refused (CntOdoRejected): "
                     + ("never reported" if n_odo is None else f"{n_odo}"))
    for o in rep["outages"]:
        pct = o.get("end_error_pct_of_distance")
        lines.append(f"outage {o['label'] or ''} {o['start_s']:.0f}-{o['end_s']:.0f} s "
                     f"({o['distance_m']:.0f} m): max error {f(o['max_error_m'])}, "
                     f"at its end {f(o['end_error_m'])}"
                     + (f" ({pct:.2f} % of the distance)" if pct is not None else ""))
    modes = rep.get("modes_seen")
    if modes:
        lines.append("modes (NAV_Status): " + ", ".join(
            f"{k} {v['share'] * 100:.1f} %" for k, v in modes.items()))
    sc = rep.get("sigma_consistency")
    if sc:
        if sc["status"] == "ok":
            lines.append(f"sigma consistency: {sc['frac_within_2sigma'] * 100:.1f} % within "
                         f"2 sigma, median error/sigma {sc['median_error_over_sigma']:.2f} "
                         f"(median sigma {sc['sigma_median_m']:.2f} m; {sc['epochs_used']} of "
                         f"{sc['epochs']} epochs; a consistent sigma gives 98.2 %, 0.83 "
                         "if it is the DRMS, 86.5 %, 1.18 if per axis)")
        else:
            lines.append(f"sigma consistency: unknown (HorizAccuracy 655.35 'unknown' at "
                         f"{sc['epochs_sigma_unknown']} of {sc['epochs']} epochs, no status at "
                         f"{sc['epochs_without_status']}, 0 at {sc['epochs_sigma_zero']})")
    fc = rep.get("filter_calibration")
    if fc:
        truth = (f"true mu {fc['mu_true']:.5f}, mounting yaw {fc['mount_yaw_true_deg']:+.3f} deg"
                 if fc["mu_true"] is not None and fc["mount_yaw_true_deg"] is not None else
                 "truths unknown")
        if fc["last"] is None:
            lines.append(f"filter calibration: none (no NAV_Calibration with CalSource Filter); "
                         f"{truth}")
        else:
            reached = fc["gnss_driving_reached_at_s"]
            if fc["at_s"] is not None:
                at600 = (f"after {fc['gnss_driving_s']:.0f} s of GNSS driving ({reached:.0f} s): "
                         f"odo scale {fc['odo_scale']:.5f}, mounting yaw "
                         f"{fc['mount_yaw_deg']:+.3f} deg; ")
            else:
                at600 = (f"none after {fc['gnss_driving_s']:.0f} s of GNSS driving "
                         f"({'never reached' if reached is None else f'{reached:.0f} s'}); ")
            la = fc["last"]
            lines.append(f"filter calibration: {at600}last ({la['at_s']:.0f} s): odo scale "
                         f"{la['odo_scale']:.5f}, mounting yaw {la['mount_yaw_deg']:+.3f} deg; "
                         f"{truth}")
    for g in rep.get("gnss_faults") or []:
        n = g.get("epochs")
        n = "" if n is None else f" ({n} epoch{'s' if n != 1 else ''})"
        what = {"jump": lambda g: f"jump {g['metres']:g} m{n}", "freeze": lambda g: f"freeze{n}",
                "latency_spike": lambda g: f"latency spike +{g['extra_s']:g} s"}[g["kind"]](g)
        rej = ("n/a" if g["gnss_rejected"] is None else
               f"{g['cnt_gnss_rejected_before']} -> {g['cnt_gnss_rejected_after']} "
               f"(+{g['gnss_rejected']})")
        lines.append(f"GNSS {what} at {g['t_start_s']:.1f} s: max error +-10 s "
                     f"{f(g['max_error_m'])} (clean {f(g['clean_max_error_m'])}), max step "
                     f"{f(g['max_step_m'])} (clean {f(g['clean_max_step_m'])}), "
                     f"CntGnssRejected {rej}")
    c = rep.get("calibration")
    if c:
        if c["error_before_pct"] is not None:
            before = (f"{c['error_before_pct']:.2f} % of distance before it "
                      f"({c['error_before_m']:.0f} m after {c['distance_before_m'] / 1000:.2f} km)")
        else:
            before = "no error before it (not navigating)"
        truth = f"true dH {c['dH_true_deg']:+.3f} deg, mu {c['mu_true']:.5f}"
        if c["performed"]:
            after = ("n/a" if c["error_after_pct"] is None else
                     f"{c['error_after_pct']:.2f} % after (max {c['error_after_max_m']:.0f} m "
                     f"over {c['distance_after_m'] / 1000:.2f} km)")
            when = "n/a" if c["time_s"] is None else f"{c['time_s']:.1f} s"
            lines.append(f"calibration ({c['source']}, asked at {c['requested_at_s']:g} s) done at "
                         f"{when}: dH {c['dH_deg']:+.3f} deg, mu {c['mu']:.5f} ({truth})")
            lines.append(f"  error {before}, {after}")
        else:
            lines.append(f"calibration ({c['source']}) asked at {c['requested_at_s']:g} s: NOT "
                         f"performed by the firmware (CalCount {c['cal_count']}, CalStatus "
                         f"{c['cal_status']}); {truth}")
            lines.append(f"  error {before}")
    return "\n".join(lines)


TRUTH_KEYS = ("t_s", "lat_rad", "lon_rad", "heading_rad", "dist_m")


def read_truth(path) -> dict:
    """truth.npz as tools.sim.run writes it, or SystemExit naming the file and what is
    wrong: unreadable, another kind of file, a column missing, of another length, not
    finite, or time not increasing."""
    try:
        with np.load(path, allow_pickle=False) as z:
            data = dict(z)
    except (OSError, ValueError, EOFError) as e:   # zipfile.BadZipFile is an OSError
        raise SystemExit(f"report: {path}: not a truth.npz of tools.sim.run: {e}") from None
    missing = [k for k in TRUTH_KEYS if k not in data]
    if missing:
        raise SystemExit(f"report: {path}: no {', '.join(missing)}: not a truth.npz of "
                         "tools.sim.run")
    t = np.asarray(data["t_s"], dtype=float)
    for k in TRUTH_KEYS:
        col = np.asarray(data[k], dtype=float)
        if col.shape != t.shape or t.ndim != 1 or t.size < 2:
            raise SystemExit(f"report: {path}: {k} has shape {col.shape}, t_s {t.shape}")
        bad = np.nonzero(~np.isfinite(col))[0]
        if bad.size:
            raise SystemExit(f"report: {path}: {k} is not finite at {bad.size} samples "
                             f"(first at index {bad[0]})")
    back = np.nonzero(np.diff(t) <= 0)[0]
    if back.size:
        raise SystemExit(f"report: {path}: t_s does not increase at {back.size} samples "
                         f"(first at index {back[0] + 1}, {t[back[0]]:g} -> {t[back[0] + 1]:g} s)")
    return data


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--truth", required=True, help="truth.npz written by tools.sim.run")
    ap.add_argument("--nav", required=True, help="navecu output log (candump)")
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--scenario", default=None,
                    help="the run's scenario (name or .toml): adds its truths and calibration")
    args = ap.parse_args(argv)
    data = read_truth(args.truth)
    outages = [tuple(o) for o in data.pop("outages", np.zeros((0, 2))).tolist()]
    try:
        nav = read_nav_log(args.nav)
    except (OSError, ValueError) as e:
        raise SystemExit(f"report: {args.nav}: not a CAN log it can read: {e}") from None
    if not nav:
        raise SystemExit(f"report: {args.nav}: no NAV_* frame in it: not a navecu output log "
                         "(or navecu sent nothing); no report")
    rep, series = compute(data, nav, outages)
    if args.scenario:
        scen = scenario.load(args.scenario)
        imu_name, gnss_name = scenario.preset_names(scen)
        imu, odo = scenario.sensor_specs(scen, imu_name, scen["vehicle"])
        hdg = scenario.heading_command_deg(float(data["heading_rad"][0]), scen)
        rep["truth"] = scenario.scenario_truths(scen, float(data["heading_rad"][0]), imu, odo, hdg)
        cal = scen.get("calibration")
        cal_log = read_calibration_log(args.nav)
        rep["calibration"] = (calibration_report(data, series, cal_log, cal, rep["truth"])
                              if cal else None)
        no_gnss = not sensors.GNSS_PRESETS[gnss_name].enabled
        t600 = None if no_gnss else gnss_driving_reached(
            data, FILTER_CAL_GNSS_DRIVING_S, rep.get("navigation_start_s", 0.0),
            outages=outages)
        rep["filter_calibration"] = filter_calibration(cal_log, rep["truth"], t600)
        faults = scen.get("gnss_faults")
        rep["gnss_faults"] = (gnss_fault_report(series, nav.get("NAV_Status"),
                                                fault_windows_from_table(faults), outages)
                              if faults else None)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "report.json").write_text(json.dumps(rep, indent=2))
    plot(data, series, None, outages, out, Path(args.out).name,
         marks=calibration_marks(rep.get("calibration")) + fault_marks(rep.get("gnss_faults")))
    print(summary_table(rep))


if __name__ == "__main__":
    main()
