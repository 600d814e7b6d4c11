"""The Kingston receiver's raw measurements (gnss_raw.csv) as the protocol's raw epochs
(tools/gnss_raw.py; issue #20).

gnss_raw.csv gives, per satellite and epoch, what the NovAtel OEM4 logged: the satellite's
ECEF position and velocity, its clock correction, the ionospheric and tropospheric
corrections (m), the pseudorange and its sigma, the L1 Doppler (Hz), elevation and azimuth
(rad). Measured on the file against the SPAN reference (tests/python/test_gnss_raw.py):
- corrected pseudorange = pseudorange + sat_clock_corr - iono_corr - tropo_corr (the other
  sign combinations leave residuals 2.5 to 4.5 times larger);
- the satellite positions are already in the ECEF axes of the receive time (the Earth's
  rotation during the signal's travel applied: turning them once more leaves residuals of
  11 m against 0.6 m), so they are turned back here into the axes of the transmit time,
  which the protocol carries (the ECU turns them forward itself);
- the satellite velocities are not: they are in the axes of the transmit time, and are
  sent as they are. The positions' own rate of change says so: at the transmit time
  s(t - tau(t)) changes at v (1 - dtau/dt), which the velocities meet to 0.1 mm/s, and
  turned back as the positions are, they miss it by up to 16 mm/s (omega tau |v| in x and
  y, none in z; tests/python/test_gnss_raw.py). Turned back, the Doppler velocity of the
  first standstill was 5 mm/s south, and --gnss-input raw drifted 2.2 m south in its 500 s;
- pseudorange rate = -Doppler x the L1 wavelength (against the reference's velocity and the
  satellites': median absolute residual 0.018 m/s after the common clock drift, `--residuals
  0 3600 --rates`).
The receiver's reported pseudorange sigma (0.05 to 9.5 m) is sent as it is; it gives no
Doppler sigma or C/N0 (sent as 0: unknown, the ECU's parameters apply).

Each satellite's corrected range against the SPAN reference, per epoch:

    python -m tools.kingston.raw --residuals T0 T1 [--relative-to PRN] [--rates] [--data DIR]

prints, for every raw epoch from T0 to T1 s of the drive (the log's time base, as
tools.kingston.run and compare), the satellites (PRN at elevation, degrees) and each one's
corrected pseudorange less its geometric range from the reference position (interpolated
to the epoch; ellipsoidal height, as reference.csv), less the epoch's median: what the
firmware's bias learning (firmware/app/raw_bias.h) averages, with the reference in place
of the filter's position. With --relative-to, less that satellite's instead (epochs
without it are skipped: the median moves with the satellites in view, a difference does
not), and then each satellite's mean over the window. With --rates, the pseudorange rates
instead (m/s): each one less the satellite's velocity and the reference's along the line of
sight, less the median, which is printed too (in brackets: the receiver's clock drift),
and then how much one epoch's residual tells of the next's (their correlation 1 s apart).

    python -m tools.kingston.raw --residuals T0 T1 --corrections

prints instead what the receiver's switches between its two sets of corrections (told
apart by the sign of the ionospheric corrections; the satellites' clock corrections step
with them) do to the ranges: the common step and each satellite's, across a switch and
within a set, and each satellite's mean residual in each set (docs/kalman.md, "Tightly
coupled GNSS").
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from tools import gnss_raw as gr
from tools.data_csv import read_csv
from tools.geodesy import WGS84_OMEGA_IE_RPS


def read(data_dir: Path) -> np.ndarray:
    return read_csv(Path(data_dir) / "gnss_raw.csv", ("time_s",))


def receiver_at(fixes: np.ndarray, t: float, height_offset_m: float = 0.0) -> np.ndarray:
    """The receiver's ECEF position at GPS time t for the signal's travel time: the latest
    fix at or before t (the first before any), its height less height_offset_m (the fixes'
    datum, docs/kingston.md); an error of 100 m moves a satellite by under 1 mm."""
    k = max(int(np.searchsorted(fixes["time_s"], t + 1e-6)) - 1, 0)
    f = fixes[k]
    return gr.ecef_from_geodetic(np.radians(f["lat_deg"]), np.radians(f["lon_deg"]),
                                 float(f["height_m"]) - height_offset_m)


def travel_turn_rad(sat_rx_axes_m: np.ndarray, rx_m: np.ndarray) -> float:
    """How far the Earth turns (rad) while the signal travels from a satellite given in the
    receive time's axes to the receiver: omega tau, tau the range over c (no iteration:
    the range is already the receive time's)."""
    return WGS84_OMEGA_IE_RPS * float(np.linalg.norm(sat_rx_axes_m - rx_m)) / gr.C_MPS


def epochs(raw: np.ndarray, fixes: np.ndarray, height_offset_m: float = 0.0) -> list:
    """[(gps time of week s, RawEpoch)], one per time in gnss_raw.csv, satellites by PRN.
    fixes: gnss.csv rows, the receiver's position (receiver_at)."""
    out = []
    times = np.unique(raw["time_s"])
    for t in times:
        rx = receiver_at(fixes, t, height_offset_m)
        rows = raw[raw["time_s"] == t]
        rows = rows[np.argsort(rows["prn"])]
        ep = gr.RawEpoch(tow_s=float(t))
        for r in rows[:gr.MAX_SATS]:
            s_rx = np.array([r["sat_x_m"], r["sat_y_m"], r["sat_z_m"]])
            v_tx = np.array([r["sat_vx_mps"], r["sat_vy_mps"], r["sat_vz_mps"]])
            ep.meas.append(gr.RawMeas(
                sv_id=int(r["prn"]), sat_pos_m=gr.rotate_z(s_rx, -travel_turn_rad(s_rx, rx)),
                sat_vel_mps=v_tx,
                pseudorange_m=corrected_pseudorange_m(r),
                range_rate_mps=range_rate_mps(r),
                pr_sigma_m=float(r["pseudorange_std_m"]),
                elevation_deg=float(np.degrees(r["elevation"]))))
        out.append((float(t), ep))
    return out


def corrected_pseudorange_m(r) -> float:
    """The module docstring's sign combination: pseudorange + satellite clock - iono -
    tropo, m."""
    return float(r["pseudorange_m"] + r["sat_clock_corr_m"] - r["iono_corr_m"]
                 - r["tropo_corr_m"])


def range_rate_mps(r) -> float:
    """The pseudorange rate of the module docstring: -Doppler x the L1 wavelength, m/s."""
    return float(-r["doppler"] * gr.GPS_L1_WAVELENGTH_M)


def residuals(raw: np.ndarray, ref: np.ndarray, t0_gps_s: float, t0_s: float,
              t1_s: float, relative_to: int = 0, rates: bool = False) -> list:
    """[(t s of the drive, [(prn, elevation deg, residual less the epoch's median)], that
    median)] for the raw epochs from t0_s to t1_s; ref: reference.csv rows (GPS time, lat,
    lon, ellipsoidal height, and with rates its velocity ve/vn/vu_mps). The satellites are
    in the receive time's axes (module docstring), so the geometric range is |sat -
    receiver|. relative_to: a PRN whose residual replaces the median (epochs without it
    left out). rates: the pseudorange rates (-Doppler x the L1 wavelength) less the
    satellite's velocity (turned into the receive time's axes) less the reference's along
    the line of sight, m/s; the median is then the receiver's clock drift (and what the
    satellites' rates share)."""
    out = []
    for t in np.unique(raw["time_s"]):
        t_s = float(t) - t0_gps_s
        if t_s < t0_s or t_s > t1_s:
            continue
        if t < ref["time_s"][0] or t > ref["time_s"][-1]:
            continue
        lat = np.radians(np.interp(t, ref["time_s"], ref["lat_deg"]))
        lon = np.radians(np.interp(t, ref["time_s"], ref["lon_deg"]))
        rx = gr.ecef_from_geodetic(lat, lon, float(np.interp(t, ref["time_s"],
                                                             ref["height_m"])))
        rows = raw[raw["time_s"] == t]
        rows = rows[np.argsort(rows["prn"])]
        if rates:
            v_rx = gr.enu_axes(lat, lon).T @ np.array(
                [np.interp(t, ref["time_s"], ref[k]) for k in ("ve_mps", "vn_mps", "vu_mps")])
        res = []
        for r in rows:
            sat = np.array([r["sat_x_m"], r["sat_y_m"], r["sat_z_m"]])
            los = sat - rx
            if rates:
                u = los / np.linalg.norm(los)
                # the velocity is in the transmit time's axes (module docstring): turned
                # into the receive time's, as the positions are
                v_sat = gr.rotate_z(np.array([r["sat_vx_mps"], r["sat_vy_mps"],
                                              r["sat_vz_mps"]]), travel_turn_rad(sat, rx))
                res.append(range_rate_mps(r) - float(u @ (v_sat - v_rx)))
            else:
                res.append(corrected_pseudorange_m(r) - float(np.linalg.norm(los)))
        res = np.array(res)
        if relative_to:
            own = res[rows["prn"] == relative_to]
            if own.size == 0:
                continue
            med = float(own[0])
        else:
            med = float(np.median(res))
        out.append((t_s, [(int(r["prn"]), float(np.degrees(r["elevation"])), float(v - med))
                          for r, v in zip(rows, res)], med))
    return out


def epoch_to_epoch_correlation(rows: list, gap_s: float = 1.0, beyond: float = 1.0) -> tuple:
    """(correlation, pairs, left out): each satellite's residual (residuals' rows, less the
    median) against its own gap_s later, over the satellites and epochs; residuals beyond
    `beyond` (faults, in the rows' unit) are left out. How much one epoch's error tells
    of the next's: 0 for white errors."""
    per = {}
    for t_s, sats, _ in rows:
        for p, _, v in sats:
            per.setdefault(p, {})[int(round(t_s * 10.0))] = v
    a, b, out = [], [], 0
    step = int(round(gap_s * 10.0))
    for series in per.values():
        for k, v in series.items():
            w = series.get(k + step)
            if w is None:
                continue
            if abs(v) > beyond or abs(w) > beyond:
                out += 1
                continue
            a.append(v)
            b.append(w)
    if len(a) < 3:
        return float("nan"), len(a), out
    return float(np.corrcoef(a, b)[0, 1]), len(a), out


def correction_set(iono_corr_m: np.ndarray) -> int:
    """The correction set of one epoch's rows, by the sign of their ionospheric corrections:
    -1 or +1 (the receiver's two sources, module docstring), 0 (none applied), 2 (mixed)."""
    signs = set(int(v) for v in np.sign(iono_corr_m))
    return signs.pop() if len(signs) == 1 else 2


def correction_switches(raw: np.ndarray, rows: list, t0_gps_s: float) -> dict:
    """What the receiver's switches of correction set do to its ranges. rows: residuals()
    of the pseudoranges (each epoch's satellites less its median, and that median). From
    one epoch to the next 1 s later, across a switch of set and within one: the RMS change
    of the median (a step common to all ranges: what the clock takes) and of each
    satellite's residual less the median (a step between satellites: what a learnt bias
    keeps); and each satellite's mean residual in each set. The satellites' clock
    corrections too: the median absolute change of each one's from one epoch to the next
    1 s later, across a switch and within a set.
    Returns {"epochs": {set: n}, "switches": n, "common_m": (across, within),
    "sat_m": (across, within), "pairs": (across, within), "clock_m": (across, within),
    "mean_m": {prn: {set: (mean, n)}}}."""
    window = {t_s for t_s, _, _ in rows}
    sets, clocks = {}, ([], [])
    before = None
    for t in np.unique(raw["time_s"]):
        if float(t) - t0_gps_s not in window:
            continue
        ep = raw[raw["time_s"] == t]
        cs = sets[float(t) - t0_gps_s] = correction_set(ep["iono_corr_m"])
        clk = dict(zip(ep["prn"].astype(int), ep["sat_clock_corr_m"]))
        if before is not None and abs(float(t) - before[0] - 1.0) < 0.05:
            clocks[0 if cs != before[1] else 1].extend(
                abs(c - before[2][p]) for p, c in clk.items() if p in before[2])
        before = (float(t), cs, clk)
    epochs, means = {}, {}
    common = ([], [])
    sat = ([], [])
    prev = None
    for t_s, sats, med in rows:
        cs = sets[t_s]
        epochs[cs] = epochs.get(cs, 0) + 1
        cur = {p: v for p, _, v in sats}
        for p, v in cur.items():
            means.setdefault(p, {}).setdefault(cs, []).append(v)
        if prev is not None and abs(t_s - prev[0] - 1.0) < 0.05:
            k = 0 if cs != prev[1] else 1
            common[k].append(med - prev[2])
            sat[k].extend(cur[p] - prev[3][p] for p in cur if p in prev[3])
        prev = (t_s, cs, med, cur)

    def rms(v):
        return float(np.sqrt(np.mean(np.square(v)))) if v else float("nan")
    return {"epochs": epochs, "switches": len(common[0]),
            "common_m": (rms(common[0]), rms(common[1])), "sat_m": (rms(sat[0]), rms(sat[1])),
            "pairs": (len(sat[0]), len(sat[1])),
            "clock_m": tuple(float(np.median(c)) if c else float("nan") for c in clocks),
            "mean_m": {p: {cs: (float(np.mean(v)), len(v)) for cs, v in d.items()}
                       for p, d in means.items()}}


def main(argv=None) -> int:
    from tools.kingston import convert  # the drive's time base; not needed by epochs()
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--residuals", nargs=2, type=float, metavar=("T0", "T1"), required=True,
                    help="window, s of the drive")
    ap.add_argument("--relative-to", type=int, default=0, metavar="PRN",
                    help="less this satellite's residual instead of the epoch's median")
    ap.add_argument("--rates", action="store_true",
                    help="the pseudorange rates (m/s) instead of the pseudoranges, and each "
                         "epoch's median (the receiver's clock drift)")
    ap.add_argument("--corrections", action="store_true",
                    help="instead of the epochs, what the receiver's switches of correction "
                         "set (the sign of its ionospheric corrections) do to the ranges")
    ap.add_argument("--data", default=None, help=f"data folder (default {convert.DATA_DIR})")
    a = ap.parse_args(argv)
    if a.corrections and (a.rates or a.relative_to):
        ap.error("--corrections is of the pseudoranges less the median")
    drive = convert.load(a.data)
    raw = read(Path(a.data) if a.data else convert.DATA_DIR)
    rows = residuals(raw, drive.ref, drive.t0_gps, a.residuals[0], a.residuals[1],
                     a.relative_to, a.rates)
    if a.corrections:
        sw = correction_switches(raw, rows, drive.t0_gps)
        names = {-1: "negative", 1: "positive", 0: "none", 2: "mixed"}
        print("epochs by the sign of their ionospheric corrections: " +
              ", ".join(f"{names[k]} {n}" for k, n in sorted(sw["epochs"].items())) +
              f"; {sw['switches']} switches between epochs 1 s apart")
        print(f"change 1 s later, across a switch / within a set (RMS): the median "
              f"{sw['common_m'][0]:.2f} / {sw['common_m'][1]:.2f} m; each satellite less the "
              f"median {sw['sat_m'][0]:.2f} / {sw['sat_m'][1]:.2f} m ({sw['pairs'][0]} / "
              f"{sw['pairs'][1]} pairs); the satellites' clock corrections (median absolute) "
              f"{sw['clock_m'][0]:.3f} / {sw['clock_m'][1]:.3f} m")
        print("each satellite's mean residual less the median, by set (m, epochs):")
        for p, d in sorted(sw["mean_m"].items()):
            print(f"  PRN {p:2d}: " + "  ".join(f"{names[k]} {m:+.2f} ({n})"
                                               for k, (m, n) in sorted(d.items())))
        return 0
    less = f"PRN {a.relative_to}'s" if a.relative_to else "the epoch's median"
    what = ("pseudorange rate less the satellite's and the reference's velocity along the "
            "line of sight" if a.rates else
            "corrected pseudorange less the range from the reference")
    unit, fmt = ("m/s", "+6.2f") if a.rates else ("m", "+5.1f")
    print(f"{what}, less {less} ({unit}): PRN@elevation residual"
          + (f"; [{less} itself]" if a.rates else ""))
    for t_s, sats, med in rows:
        print(f"{t_s:8.1f} s  {len(sats)}: " +
              "  ".join(f"{p:2d}@{el:2.0f} {v:{fmt}}" for p, el, v in sats) +
              (f"  [{med:+.2f}]" if a.rates else ""))
    if a.rates:
        r, n, out = epoch_to_epoch_correlation(rows)
        print(f"each satellite's residual against its own 1 s later: correlation {r:.3f} over "
              f"{n} pairs ({out} with a residual beyond 1 m/s left out)")
    if a.relative_to:
        per = {}
        for _, sats, _ in rows:
            for p, _, v in sats:
                per.setdefault(p, []).append(v)
        print(f"mean over {len(rows)} epochs with PRN {a.relative_to}: " +
              "  ".join(f"{p}: {np.mean(v):+.2f} {unit} ({len(v)})"
                        for p, v in sorted(per.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
