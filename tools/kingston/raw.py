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
- pseudorange rate = -Doppler x the L1 wavelength (against the reference's velocity and the
  satellites': median residual 0.016 m/s after the common clock drift).
The receiver's reported pseudorange sigma (0.05 to 9.5 m) is sent as it is; it gives no
Doppler sigma or C/N0 (sent as 0: unknown, the ECU's parameters apply).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from tools import gnss_raw as gr
from tools.geodesy import WGS84_OMEGA_IE_RPS


def read(data_dir: Path) -> np.ndarray:
    return np.genfromtxt(Path(data_dir) / "gnss_raw.csv", delimiter=",", names=True,
                         dtype=float)


def epochs(raw: np.ndarray, fixes: np.ndarray, height_offset_m: float = 0.0) -> list:
    """[(gps time of week s, RawEpoch)], one per time in gnss_raw.csv, satellites by PRN.
    fixes: gnss.csv rows; the latest fix at or before an epoch is the receiver's position
    for the signal's travel time (an error of 100 m moves a satellite by under 1 mm).
    height_offset_m is subtracted from the fixes' heights (their datum, docs/kingston.md)."""
    out = []
    t_fix = fixes["time_s"]
    times = np.unique(raw["time_s"])
    for t in times:
        k = int(np.searchsorted(t_fix, t + 1e-6)) - 1
        if k < 0:
            k = 0
        f = fixes[k]
        rx = gr.ecef_from_geodetic(np.radians(f["lat_deg"]), np.radians(f["lon_deg"]),
                                   float(f["height_m"]) - height_offset_m)
        rows = raw[raw["time_s"] == t]
        rows = rows[np.argsort(rows["prn"])]
        ep = gr.RawEpoch(tow_s=float(t))
        for r in rows[:gr.MAX_SATS]:
            s_rx = np.array([r["sat_x_m"], r["sat_y_m"], r["sat_z_m"]])
            v_rx = np.array([r["sat_vx_mps"], r["sat_vy_mps"], r["sat_vz_mps"]])
            tau = float(np.linalg.norm(s_rx - rx)) / gr.C_MPS
            a = -WGS84_OMEGA_IE_RPS * tau
            ep.meas.append(gr.RawMeas(
                sv_id=int(r["prn"]), sat_pos_m=gr.rotate_z(s_rx, a),
                sat_vel_mps=gr.rotate_z(v_rx, a),
                pseudorange_m=float(r["pseudorange_m"] + r["sat_clock_corr_m"]
                                    - r["iono_corr_m"] - r["tropo_corr_m"]),
                range_rate_mps=float(-r["doppler"] * gr.GPS_L1_WAVELENGTH_M),
                pr_sigma_m=float(r["pseudorange_std_m"]),
                elevation_deg=float(np.degrees(r["elevation"]))))
        out.append((float(t), ep))
    return out
