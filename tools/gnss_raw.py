"""Raw GNSS measurements (issue #20): the protocol's satellite frames, the Earth-rotation
and ECEF geometry they need, and a reference least-squares solution to check them.

One raw epoch on the bus (firmware/can/navecu.dbc, docs/can.md "Raw GNSS measurements"):
for every satellite five frames with the same RawSlot and GnssEpoch (GNSS_RawSatX,
GNSS_RawSatY, GNSS_RawSatZ: its ECEF position and velocity at the signal's transmit time,
in the ECEF axes of that time; GNSS_RawRange: the corrected pseudorange, system, number,
elevation; GNSS_RawRate: the pseudorange rate, both sigmas, C/N0), then GNSS_RawEpoch
(TimeOfWeek, NumMeas) closing it.

Used by the Kingston converter (gnss_raw.csv through the protocol) and the simulator's
receiver model (tools/sim/receiver.py); the least-squares solver is the independent check
of both (tests/python/test_gnss_raw.py), not the firmware's algorithm.

Conventions (IS-GPS-200 section 20.3.3.4.3.3.2 for the Earth's rotation):
- ECEF WGS-84, metres; the ECEF axes rotate at WGS84_OMEGA_IE_RPS about z;
- a satellite position in the ECEF axes of the transmit time, s_tx, is in the axes of the
  receive time, tau = range / c later, R3(omega tau) s_tx, with
  R3(a) = [[cos a, sin a, 0], [-sin a, cos a, 0], [0, 0, 1]];
- pseudorange rate = -Doppler x wavelength (positive when the range grows).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Iterable, Optional, Sequence

import numpy as np

from tools import navecu_can as nc
from tools.geodesy import WGS84_A_M, WGS84_E2, WGS84_OMEGA_IE_RPS

C_MPS = 299792458.0
GPS_L1_HZ = 1575.42e6
GPS_L1_WAVELENGTH_M = C_MPS / GPS_L1_HZ
MAX_SATS = 16          # RawSlot 0..15 (NumMeas at most 16)
SAT_FRAMES = ("GNSS_RawSatX", "GNSS_RawSatY", "GNSS_RawSatZ")
AXES = ("X", "Y", "Z")
EPOCH_MSG = "GNSS_RawEpoch"
GPS = 0                # GnssSystem: u-blox gnssId


@dataclass
class RawMeas:
    """One satellite's measurements of an epoch, as the protocol carries them."""
    sv_id: int
    sat_pos_m: Sequence[float]      # ECEF at the transmit time, axes of the transmit time
    sat_vel_mps: Sequence[float]    # ECEF velocity, the same axes
    pseudorange_m: float            # corrected: satellite clock, ionosphere, troposphere
    range_rate_mps: float           # pseudorange rate
    pr_sigma_m: float = 0.0         # 0: no estimate (the ECU's parameter)
    rr_sigma_mps: float = 0.0
    elevation_deg: float = 0.0
    cn0_dbhz: int = 0
    system: int = GPS
    pr_valid: bool = True
    rr_valid: bool = True


@dataclass
class RawEpoch:
    tow_s: float
    meas: list = field(default_factory=list)
    clock_reset: bool = False


# --- geometry --------------------------------------------------------------------------------
def ecef_from_geodetic(lat_rad, lon_rad, h_m) -> np.ndarray:
    sl, cl = math.sin(lat_rad), math.cos(lat_rad)
    n = WGS84_A_M / math.sqrt(1.0 - WGS84_E2 * sl * sl)
    return np.array([(n + h_m) * cl * math.cos(lon_rad), (n + h_m) * cl * math.sin(lon_rad),
                     (n * (1.0 - WGS84_E2) + h_m) * sl])


def geodetic_from_ecef(x) -> tuple:
    """(lat_rad, lon_rad, h_m); Bowring's iteration to 1e-12 rad."""
    x, y, z = map(float, x)
    lon = math.atan2(y, x)
    p = math.hypot(x, y)
    lat = math.atan2(z, p * (1.0 - WGS84_E2))
    for _ in range(10):
        sl = math.sin(lat)
        n = WGS84_A_M / math.sqrt(1.0 - WGS84_E2 * sl * sl)
        h = p / math.cos(lat) - n
        new = math.atan2(z, p * (1.0 - WGS84_E2 * n / (n + h)))
        if abs(new - lat) < 1e-13:
            lat = new
            break
        lat = new
    sl = math.sin(lat)
    n = WGS84_A_M / math.sqrt(1.0 - WGS84_E2 * sl * sl)
    return lat, lon, p / math.cos(lat) - n


def enu_axes(lat_rad, lon_rad) -> np.ndarray:
    """Rows: east, north, up unit vectors in ECEF."""
    sl, cl, so, co = math.sin(lat_rad), math.cos(lat_rad), math.sin(lon_rad), math.cos(lon_rad)
    return np.array([[-so, co, 0.0], [-sl * co, -sl * so, cl], [cl * co, cl * so, sl]])


def rotate_z(v, angle_rad) -> np.ndarray:
    """R3(angle) v: a vector of the ECEF axes of time t in the axes of t + angle/omega."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    v = np.asarray(v, dtype=float)
    return np.array([c * v[0] + s * v[1], -s * v[0] + c * v[1], v[2]])


def sat_in_receive_axes(sat_pos_m, sat_vel_mps, rx_m) -> tuple:
    """The satellite's position and velocity turned from the axes of its transmit time to
    those of the receive time (the Earth turned by omega x tau meanwhile), and tau."""
    s = np.asarray(sat_pos_m, dtype=float)
    tau = float(np.linalg.norm(s - rx_m)) / C_MPS
    for _ in range(2):  # tau from the rotated position; converged to 1e-12 s after two
        tau = float(np.linalg.norm(rotate_z(s, WGS84_OMEGA_IE_RPS * tau) - rx_m)) / C_MPS
    a = WGS84_OMEGA_IE_RPS * tau
    return rotate_z(s, a), rotate_z(sat_vel_mps, a), tau


def elevation_rad(sat_rx_axes_m, rx_m) -> float:
    lat, lon, _ = geodetic_from_ecef(rx_m)
    d = enu_axes(lat, lon) @ (np.asarray(sat_rx_axes_m) - rx_m)
    return math.atan2(d[2], math.hypot(d[0], d[1]))


# --- the reference solution ------------------------------------------------------------------
@dataclass
class Solution:
    pos_m: np.ndarray
    clock_m: float
    residuals_m: np.ndarray
    iterations: int
    vel_mps: Optional[np.ndarray] = None
    drift_mps: Optional[float] = None
    rate_residuals_mps: Optional[np.ndarray] = None


def solve(meas: Iterable[RawMeas], x0_m=None, iterations: int = 10) -> Optional[Solution]:
    """Weighted least squares for the receiver position and clock (pseudoranges), then its
    velocity and clock drift (pseudorange rates), each satellite turned into the receive
    axes. None with fewer than 4 valid pseudoranges."""
    ms = [m for m in meas if m.pr_valid]
    if len(ms) < 4:
        return None
    x = np.zeros(3) if x0_m is None else np.array(x0_m, dtype=float)
    b = 0.0
    w = np.array([1.0 / max(m.pr_sigma_m, 0.1) for m in ms])
    for it in range(iterations):
        rows, res = [], []
        for m in ms:
            s, _, _ = sat_in_receive_axes(m.sat_pos_m, m.sat_vel_mps, x)
            rho = float(np.linalg.norm(s - x))
            e = (s - x) / rho
            rows.append(np.concatenate([-e, [1.0]]))
            res.append(m.pseudorange_m - (rho + b))
        h = np.array(rows) * w[:, None]
        dx = np.linalg.lstsq(h, np.array(res) * w, rcond=None)[0]
        x += dx[:3]
        b += dx[3]
        if np.linalg.norm(dx) < 1e-4:
            break
    res = []
    rows, rr = [], []
    for m in ms:
        s, v, _ = sat_in_receive_axes(m.sat_pos_m, m.sat_vel_mps, x)
        rho = float(np.linalg.norm(s - x))
        e = (s - x) / rho
        res.append(m.pseudorange_m - (rho + b))
        if m.rr_valid:
            rows.append(np.concatenate([-e, [1.0]]))
            rr.append(m.range_rate_mps - float(e @ v))
    sol = Solution(pos_m=x, clock_m=b, residuals_m=np.array(res), iterations=it + 1)
    if len(rr) >= 4:
        hv = np.array(rows)
        vd = np.linalg.lstsq(hv, np.array(rr), rcond=None)[0]
        sol.vel_mps, sol.drift_mps = vd[:3], float(vd[3])
        sol.rate_residuals_mps = np.array(rr) - hv @ vd
    return sol


# --- the protocol ----------------------------------------------------------------------------
def encode_epoch(sender: "nc.E2ESender", epoch: RawEpoch, gnss_epoch: int,
                 t_s: float) -> list:
    """The frames of one raw epoch in the order they are sent: each satellite's five
    frames, slot by slot, then GNSS_RawEpoch. gnss_epoch: the epoch number 0..14."""
    if len(epoch.meas) > MAX_SATS:
        raise ValueError(f"{len(epoch.meas)} satellites: the protocol carries {MAX_SATS}")
    out = []
    for slot, m in enumerate(epoch.meas):
        head = {"RawSlot": slot, "GnssEpoch": gnss_epoch}
        for name, axis, p, v in zip(SAT_FRAMES, AXES, m.sat_pos_m, m.sat_vel_mps):
            out.append(sender.encode(name, dict(head, **{f"SatPos{axis}": float(p),
                                                         f"SatVel{axis}": float(v)}), t_s))
        out.append(sender.encode("GNSS_RawRange", dict(
            head, Pseudorange=float(m.pseudorange_m) if m.pr_valid else 0.0,
            GnssSystem=int(m.system), SvId=int(m.sv_id),
            Elevation=float(min(max(m.elevation_deg, 0.0), 90.0)),
            PseudorangeValid=int(bool(m.pr_valid))), t_s))
        out.append(sender.encode("GNSS_RawRate", dict(
            head, RangeRate=float(m.range_rate_mps) if m.rr_valid else 0.0,
            PseudorangeSigma=float(min(max(m.pr_sigma_m, 0.0), 25.5)),
            RangeRateSigma=float(min(max(m.rr_sigma_mps, 0.0), 2.55)),
            Cn0=int(min(max(m.cn0_dbhz, 0), 63)), RangeRateValid=int(bool(m.rr_valid))),
            t_s))
    out.append(sender.encode(EPOCH_MSG, {
        "TimeOfWeek": round(float(epoch.tow_s) % 604800.0, 3), "NumMeas": len(epoch.meas),
        "GnssEpoch": gnss_epoch, "ClockReset": int(bool(epoch.clock_reset))}, t_s))
    return out


def decode_epochs(messages: Iterable, db=None) -> list:
    """Raw epochs back from frames (python-can messages), as a client reads them: the
    satellites of each GNSS_RawEpoch's slots whose five frames came with its epoch number
    and a good CRC; a slot with a frame missing is left out."""
    db = db if db is not None else nc.DEFAULT_DB
    ids = {db.get_message_by_name(n).frame_id: n for n in
           SAT_FRAMES + ("GNSS_RawRange", "GNSS_RawRate", EPOCH_MSG)}
    pending: dict = {}
    epochs = []
    for msg in messages:
        name = ids.get(msg.arbitration_id)
        if name is None or not nc.check_e2e(msg, db):
            continue
        sig = db.decode_message(msg.arbitration_id, msg.data, decode_choices=False)
        if name == EPOCH_MSG:
            ep = RawEpoch(tow_s=float(sig["TimeOfWeek"]), clock_reset=bool(sig["ClockReset"]))
            for slot in range(int(sig["NumMeas"])):
                f = pending.get((int(sig["GnssEpoch"]), slot), {})
                if len(f) != 5:
                    continue
                ep.meas.append(RawMeas(
                    sv_id=int(f["GNSS_RawRange"]["SvId"]),
                    system=int(f["GNSS_RawRange"]["GnssSystem"]),
                    sat_pos_m=[float(f[n][f"SatPos{a}"]) for n, a in zip(SAT_FRAMES, AXES)],
                    sat_vel_mps=[float(f[n][f"SatVel{a}"]) for n, a in zip(SAT_FRAMES, AXES)],
                    pseudorange_m=float(f["GNSS_RawRange"]["Pseudorange"]),
                    pr_valid=bool(f["GNSS_RawRange"]["PseudorangeValid"]),
                    elevation_deg=float(f["GNSS_RawRange"]["Elevation"]),
                    range_rate_mps=float(f["GNSS_RawRate"]["RangeRate"]),
                    rr_valid=bool(f["GNSS_RawRate"]["RangeRateValid"]),
                    pr_sigma_m=float(f["GNSS_RawRate"]["PseudorangeSigma"]),
                    rr_sigma_mps=float(f["GNSS_RawRate"]["RangeRateSigma"]),
                    cn0_dbhz=int(f["GNSS_RawRate"]["Cn0"])))
            epochs.append(ep)
            pending = {}
            continue
        pending.setdefault((int(sig["GnssEpoch"]), int(sig["RawSlot"])), {})[name] = sig
    return epochs
