"""Drive-simulator truth: an analytic vehicle trajectory and its exact IMU increments.

This is the Python twin of tests/support/truth.c + motions.c (the C generator that is
proven against the firmware to millimetres): the motion is an analytic function of time,
so velocity, acceleration, attitude and body rates are exact; the specific force and the
inertial rate follow from the mechanization equations of docs/frames.md solved for the
sensor outputs, with the Earth model of firmware/nav/earth.c (same constants and formulas,
in double precision); they are integrated over every IMU interval with 5-point
Gauss-Legendre quadrature and the truth position with RK4.

Frames (docs/frames.md): navigation frame ENU; body x right, y forward, z up; Euler 3-1-2
``C_bn = Rz(-heading) Rx(pitch) Ry(roll)``; heading clockwise from north in [0, 2 pi),
pitch nose up positive, roll right side down positive; ``q_bn = {w, x, y, z}``.

The scenario file (TOML) and its loading: tools/sim/scenario.py.

Motion model
------------
* speed ``s(t)`` (signed, along the path; negative when reversing): piecewise constant,
  joined by quintic smoothstep ramps ``s0 + (s1 - s0) p(u)``, ``p = 10u^3 - 15u^4 + 6u^5``
  (C2: zero acceleration and jerk-free joins), duration ``1.875 |s1 - s0| / accel`` so that
  the peak acceleration is ``accel``;
* curvature ``kappa(t)`` (right positive, relative to the nose, so that the heading rate is
  ``kappa s``): in a turn ``kappa = kmax K(t)``, ``K`` a trapezoid with quintic ramps,
  ``kmax = sign(angle) sign(s) / radius``; the heading ``H(t)`` is its closed-form integral
  (exact, no numerical quadrature);
* path grade ``gamma(t)`` (hill): ``gmax S(x/D)``, ``S(u) = 2 sin^3(pi u) cos(pi u) / (3
  sqrt(3)/8)`` (peak 1, odd about the middle: net height change 0; C2 at both ends);
* ``v_enu = s (cos gamma sin H, cos gamma cos H, sin gamma)``, ``a_enu = dv_enu/dt``
  analytic;
* attitude: heading ``H``; pitch ``gamma + k_p ds/dt + rough_p``; roll ``-k_r s^2 kappa +
  rough_r`` (a right turn rolls the body left side down); the roughness is a sum of three
  incommensurate 1-3 Hz sinusoids per axis, scaled by ``s^2 / (s^2 + 5^2)`` (none at
  standstill); Euler rates analytic, ``w_nb_b`` from them as truth.c does;
* Earth: ``f_b = C_nb (a_enu + (2 w_ie + w_en) x v - g_n)``, ``g_n = (0, 0, -gamma(lat, h))``;
  ``w_ib_b = C_nb (w_ie + w_en) + w_nb_b``.

Increments of interval k (``t_{k-1}, t_k]``): 5-point Gauss-Legendre of ``w_ib_b`` and
``f_b``, node positions extrapolated linearly from ``t_{k-1}`` with the position rate (as
truth.c); an interval that contains a segment boundary is split there (the integrand is
only C0/C1 across a boundary). Position: RK4 per interval on the analytic velocity; the
sequential recursion is solved by a fixed-point iteration over the whole drive (each pass
vectorised; the dependence of the increments on the position is ~1e-3 of the
accumulated distance / Earth radius, so it converges to rounding in a few passes).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from tools.geodesy import earth_rate_n, gravity, pos_rate, transport_rate_n
from tools.sim.scenario import VEHICLE_DEFAULTS

# 5-point Gauss-Legendre on [-1, 1] (truth.c)
GL_X = np.array([-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                 0.9061798459386640])
GL_W = np.array([0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                 0.4786286704993665, 0.2369268850561891])

TURN_RAMP_FRAC_DEFAULT = 0.3
ROUGH_SPEED_REF_MPS = 5.0
# roughness: (frequency Hz, weight, phase rad); weights sum to 1 -> peak <= roughness_deg
_ROUGH_PITCH = ((1.17, 0.5, 0.3), (1.93, 0.3, 1.9), (2.71, 0.2, 4.1))
_ROUGH_ROLL = ((1.41, 0.5, 2.2), (2.23, 0.3, 0.7), (2.87, 0.2, 5.3))
_S_NORM = 3.0 * math.sqrt(3.0) / 8.0  # max of 2 sin^3 cos


# --- quaternions (nav_math.c conventions) ---------------------------------------------------
def quat_mul(a, b):
    a0, a1, a2, a3 = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    b0, b1, b2, b3 = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return np.stack([a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
                     a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                     a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
                     a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0], axis=-1)


def quat_from_euler(roll, pitch, heading):
    """q_bn of C_bn = Rz(-heading) Rx(pitch) Ry(roll), w >= 0 (quat_from_euler)."""
    roll, pitch, heading = np.broadcast_arrays(np.asarray(roll, float),
                                               np.asarray(pitch, float),
                                               np.asarray(heading, float))
    z = np.zeros_like(roll)
    qz = np.stack([np.cos(0.5 * heading), z, z, -np.sin(0.5 * heading)], axis=-1)
    qx = np.stack([np.cos(0.5 * pitch), np.sin(0.5 * pitch), z, z], axis=-1)
    qy = np.stack([np.cos(0.5 * roll), z, np.sin(0.5 * roll), z], axis=-1)
    q = quat_mul(quat_mul(qz, qx), qy)
    return np.where(q[..., :1] < 0.0, -q, q)


def quat_to_dcm(q):
    """C_bn (..., 3, 3) from q_bn (quat_to_dcm)."""
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack([
        np.stack([w * w + x * x - y * y - z * z, 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)], -1),
        np.stack([2.0 * (x * y + w * z), w * w - x * x + y * y - z * z, 2.0 * (y * z - w * x)], -1),
        np.stack([2.0 * (x * z - w * y), 2.0 * (y * z + w * x), w * w - x * x - y * y + z * z], -1),
    ], axis=-2)


def w_nb_from_euler_rates(roll, pitch, roll_rate, pitch_rate, heading_rate):
    """Body rate relative to ENU from 3-1-2 Euler rates (truth_w_nb_from_euler_rates)."""
    cp, sp, cr, sr = np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    ax = pitch_rate
    ay = -heading_rate * sp
    az = -heading_rate * cp
    return np.stack([cr * ax - sr * az, ay + roll_rate, sr * ax + cr * az], axis=-1)


# --- profiles ------------------------------------------------------------------------------
def _smooth(u):
    """Quintic smoothstep p(u), p', p'' and the integral P(u) = int_0^u p."""
    u2 = u * u
    u3 = u2 * u
    p = u3 * (10.0 - 15.0 * u + 6.0 * u2)
    p1 = 30.0 * u2 * (1.0 - u) ** 2
    p2 = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u)
    P = u2 * u2 * (2.5 - 3.0 * u + u2)
    return p, p1, p2, P


def _hill_shape(u):
    """S(u) (peak 1 at u = 1/3, -1 at 2/3) and dS/du."""
    a = math.pi * u
    s, c = np.sin(a), np.cos(a)
    S = 2.0 * s ** 3 * c / _S_NORM
    dS = 2.0 * math.pi * (3.0 * s * s * c * c - s ** 4) / _S_NORM
    return S, dS


def _hill_gmax_for_rise(distance_m, rise_m):
    """Peak grade angle whose bump reaches rise_m at mid-distance (exact, with sin)."""
    # int_0^{D/2} sin(gmax S(x/D)) dx = rise; Gauss-Legendre on 2 x 5 sub-intervals x 8
    xs, ws = np.polynomial.legendre.leggauss(16)
    edges = np.linspace(0.0, 0.5, 9)
    us = np.concatenate([0.5 * (b - a) * xs + 0.5 * (a + b) for a, b in zip(edges[:-1], edges[1:])])
    wts = np.concatenate([0.5 * (b - a) * ws for a, b in zip(edges[:-1], edges[1:])])
    Su, _ = _hill_shape(us)

    def rise(g):
        return distance_m * np.sum(wts * np.sin(g * Su))

    target = abs(rise_m)
    if not 0.0 < target < rise(0.5 * math.pi):
        raise ValueError(f"hill: rise_m {rise_m} impossible over {distance_m} m")
    lo, hi = 0.0, 0.5 * math.pi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if rise(mid) < target:
            lo = mid
        else:
            hi = mid
    return math.copysign(0.5 * (lo + hi), rise_m)


def _one_of(seg, keys, i):
    have = [k for k in keys if k in seg]
    if len(have) != 1:
        raise ValueError(f"segment {i} ({seg['kind']}): give exactly one of {keys}")
    return have[0]


class Trajectory:
    """The analytic motion of a scenario: pieces of time with closed-form profiles."""

    def __init__(self, scenario: dict):
        st = scenario["start"]
        veh = dict(VEHICLE_DEFAULTS)
        veh.update(scenario.get("vehicle", {}))
        self.vehicle = veh
        self.k_pitch = math.radians(veh["pitch_per_accel_deg"])
        self.k_roll = math.radians(veh["roll_per_lat_accel_deg"])
        self.rough = math.radians(veh["roughness_deg"])
        self.lat0 = math.radians(st["lat_deg"])
        self.lon0 = math.radians(st["lon_deg"])
        self.h0 = float(st["h_m"])
        rows = []  # t0, T, sA, sB, Ts, kmax, Tr, Th, gmax, Tg, H0, X0, D0, tstar, Xstar
        t, s, H, X, D = 0.0, 0.0, math.radians(st["heading_deg"]), 0.0, 0.0
        self.segment_times = []

        def add(T, sB=0.0, Ts=1.0, kmax=0.0, Tr=1.0, Th=0.0, gmax=0.0, Tg=1.0):
            nonlocal t, s, H, X, D
            sA = s
            tstar, Xstar = math.inf, 0.0
            if sB != 0.0 and sA * (sA + sB) < 0.0:  # speed crosses zero inside the ramp
                target = -sA / sB  # p(u*) = target, p monotonic
                lo, hi = 0.0, 1.0
                for _ in range(200):
                    mid = 0.5 * (lo + hi)
                    if _smooth(mid)[0] < target:
                        lo = mid
                    else:
                        hi = mid
                us = 0.5 * (lo + hi)
                tstar = us * Ts
                Xstar = sA * tstar + sB * Ts * _smooth(us)[3]
            rows.append((t, T, sA, sB, Ts, kmax, Tr, Th, gmax, Tg, H, X, D, tstar, Xstar))
            # state at the end of the piece
            if sB != 0.0:
                dX = sA * Ts + sB * Ts * 0.5
                if math.isfinite(tstar):
                    D += abs(Xstar) + abs(dX - Xstar)
                else:
                    D += abs(dX)
                X += dX
                s = sA + sB
            else:
                X += sA * T
                D += abs(sA) * T
            if kmax != 0.0:
                H += sA * kmax * (Tr + Th)
            t += T

        for i, seg in enumerate(scenario["segment"]):
            kind = seg["kind"]
            t_start = t
            if kind == "stop":
                if s != 0.0:
                    raise ValueError(f"segment {i} (stop): speed is {s} m/s, not 0")
                add(float(seg["duration_s"]))
            elif kind == "speed":
                s1 = float(seg["to_mps"])
                ds = s1 - s
                how = _one_of(seg, ("accel_mps2", "duration_s", "distance_m"), i)
                if ds == 0.0:
                    self.segment_times.append((t_start, t, kind))
                    continue
                if how == "accel_mps2":
                    a = abs(float(seg["accel_mps2"]))
                    if a <= 0.0:
                        raise ValueError(f"segment {i} (speed): accel must be > 0")
                    Ts = 1.875 * abs(ds) / a
                elif how == "duration_s":
                    Ts = float(seg["duration_s"])
                else:
                    d = float(seg["distance_m"])
                    if s * s1 < 0.0 or s + s1 == 0.0 or d <= 0.0:
                        raise ValueError(f"segment {i} (speed): distance_m needs a ramp "
                                         "that does not cross 0 m/s")
                    Ts = 2.0 * d / abs(s + s1)
                if not Ts > 0.0:
                    raise ValueError(f"segment {i} (speed): duration must be > 0")
                add(Ts, sB=ds, Ts=Ts)
            elif kind == "straight":
                how = _one_of(seg, ("distance_m", "duration_s"), i)
                if how == "distance_m":
                    if s == 0.0:
                        raise ValueError(f"segment {i} (straight): distance at speed 0")
                    T = float(seg["distance_m"]) / abs(s)
                else:
                    T = float(seg["duration_s"])
                add(T)
            elif kind == "turn":
                if s == 0.0:
                    raise ValueError(f"segment {i} (turn): speed is 0")
                R = float(seg["radius_m"])
                A = math.radians(float(seg["angle_deg"]))
                if R <= 0.0 or A == 0.0:
                    raise ValueError(f"segment {i} (turn): radius > 0 and angle != 0 needed")
                Ta = abs(A) * R / abs(s)  # Tr + Th
                if "ramp_s" in seg:
                    Tr = min(float(seg["ramp_s"]), Ta)
                else:
                    frac = float(seg.get("ramp_frac", TURN_RAMP_FRAC_DEFAULT))
                    if not 0.0 < frac <= 1.0:
                        raise ValueError(f"segment {i} (turn): 0 < ramp_frac <= 1")
                    Tr = frac * Ta
                if not Tr > 0.0:
                    raise ValueError(f"segment {i} (turn): ramp must be > 0")
                kmax = math.copysign(1.0, A) * math.copysign(1.0, s) / R
                add(Ta + Tr, kmax=kmax, Tr=Tr, Th=Ta - Tr)
            elif kind == "hill":
                if s == 0.0:
                    raise ValueError(f"segment {i} (hill): speed is 0")
                Dh = float(seg["distance_m"])
                how = _one_of(seg, ("grade_pct", "rise_m"), i)
                if how == "grade_pct":
                    gmax = math.atan(float(seg["grade_pct"]) / 100.0)
                else:
                    gmax = _hill_gmax_for_rise(Dh, float(seg["rise_m"]))
                T = Dh / abs(s)
                add(T, gmax=gmax, Tg=T)
            self.segment_times.append((t_start, t, kind))
        self.duration_s = t
        # hold the final state beyond the end (the last sample may fall just after it)
        add(math.inf)
        self.p = {k: np.array(v) for k, v in zip(
            ("t0", "T", "sA", "sB", "Ts", "kmax", "Tr", "Th", "gmax", "Tg", "H0", "X0", "D0",
             "tstar", "Xstar"), zip(*rows))}
        self.breaks = np.unique(self.p["t0"][1:])  # piece boundaries, incl. the end

    # ---------------------------------------------------------------------------------------
    def kinematics(self, t):
        """All analytic quantities at the times t (any shape)."""
        t = np.asarray(t, dtype=float)
        P = self.p
        i = np.clip(np.searchsorted(P["t0"], t, side="right") - 1, 0, len(P["t0"]) - 1)
        # zero-length pieces are never selected: searchsorted('right') skips to the last
        g = {k: v[i] for k, v in P.items()}
        tau = t - g["t0"]
        # speed
        Ts = g["Ts"]
        us = np.clip(tau / Ts, 0.0, 1.0)
        p, p1, p2, Pi = _smooth(us)
        sA, sB = g["sA"], g["sB"]
        s = sA + sB * p
        sd = sB * p1 / Ts
        sdd = sB * p2 / (Ts * Ts)
        tc = np.minimum(tau, Ts)
        X = g["X0"] + sA * tc + sB * Ts * Pi + (sA + sB) * (tau - tc)
        dX = X - g["X0"]
        after = tau > g["tstar"]
        dist = g["D0"] + np.where(after, np.abs(g["Xstar"]) + np.abs(dX - g["Xstar"]), np.abs(dX))
        # curvature / heading
        Tr, Th, kmax = g["Tr"], g["Th"], g["kmax"]
        a = np.clip(tau / Tr, 0.0, 1.0)
        b = np.clip((tau - Tr - Th) / Tr, 0.0, 1.0)
        pa, pa1, _, Pa = _smooth(a)
        pb, pb1, _, Pb = _smooth(b)
        K = pa - pb
        Kd = (pa1 - pb1) / Tr
        IK = Tr * Pa + np.clip(tau - Tr, 0.0, Th) + Tr * (b - Pb)
        kappa = kmax * K
        kappad = kmax * Kd
        H = g["H0"] + sA * kmax * IK  # turns are at constant speed sA
        Hd = kappa * s
        # grade
        Tg = g["Tg"]
        ug = np.clip(tau / Tg, 0.0, 1.0)
        S, dS = _hill_shape(ug)
        gam = g["gmax"] * S
        gamd = g["gmax"] * dS / Tg
        # roughness, scaled by c(s) = s^2 / (s^2 + s_ref^2)
        sr2 = ROUGH_SPEED_REF_MPS ** 2
        den = s * s + sr2
        c = s * s / den
        cd = 2.0 * s * sd * sr2 / (den * den)
        rp, rpd = self._rough(t, _ROUGH_PITCH)
        rr, rrd = self._rough(t, _ROUGH_ROLL)
        pitch = gam + self.k_pitch * sd + c * rp
        pitch_rate = gamd + self.k_pitch * sdd + cd * rp + c * rpd
        roll = -self.k_roll * s * s * kappa + c * rr
        roll_rate = -self.k_roll * (2.0 * s * sd * kappa + s * s * kappad) + cd * rr + c * rrd
        # velocity and its derivative (ENU)
        sH, cH, sg, cg = np.sin(H), np.cos(H), np.sin(gam), np.cos(gam)
        v = np.stack([s * cg * sH, s * cg * cH, s * sg], axis=-1)
        acc = (sd[..., None] * np.stack([cg * sH, cg * cH, sg], axis=-1)
               + (s * gamd)[..., None] * np.stack([-sg * sH, -sg * cH, cg], axis=-1)
               + (s * Hd)[..., None] * np.stack([cg * cH, -cg * sH, np.zeros_like(s)], axis=-1))
        return {"s": s, "sd": sd, "X": X, "dist": dist, "kappa": kappa, "H": H, "Hd": Hd,
                "gamma": gam, "roll": roll, "pitch": pitch, "roll_rate": roll_rate,
                "pitch_rate": pitch_rate, "v": v, "a": acc}

    def _rough(self, t, comps):
        r = np.zeros_like(t)
        rd = np.zeros_like(t)
        if self.rough == 0.0:
            return r, rd
        for f, w, ph in comps:
            om = 2.0 * math.pi * f
            r = r + self.rough * w * np.sin(om * t + ph)
            rd = rd + self.rough * w * om * np.cos(om * t + ph)
        return r, rd

    def attitude(self, k):
        """q_bn and w_nb_b for a kinematics dict."""
        q = quat_from_euler(k["roll"], k["pitch"], k["H"])
        w_nb = w_nb_from_euler_rates(k["roll"], k["pitch"], k["roll_rate"], k["pitch_rate"],
                                     k["Hd"])
        return q, w_nb


def sensed(kin, q_bn, w_nb_b, lat_rad, h_m):
    """w_ib_b and f_b (truth.c sensed()) for kinematics at positions (lat, h)."""
    g = gravity(np.sin(lat_rad), h_m)
    v = kin["v"]
    w_ie = earth_rate_n(lat_rad)
    w_en = transport_rate_n(lat_rad, h_m, v)
    w_in = w_ie + w_en
    w_cor = 2.0 * w_ie + w_en
    f_n = kin["a"] + np.cross(w_cor, v)
    f_n[..., 2] += g
    C = quat_to_dcm(q_bn)  # C_bn; C_nb x = C^T x
    f_b = np.einsum("...ji,...j->...i", C, f_n)
    w_ib = np.einsum("...ji,...j->...i", C, w_in) + w_nb_b
    return w_ib, f_b


# --- truth ---------------------------------------------------------------------------------
@dataclass
class Truth:
    """Truth at the IMU rate: samples k = 0..N at t_k = k / imu_rate_hz.

    Increments of row k integrate over (t_{k-1}, t_k]; row 0 is zero. Instantaneous
    quantities (f_b, w_ib_b, attitude, velocity) are at t_k.
    """
    t_s: np.ndarray            # (N+1,)
    lat_rad: np.ndarray        # (N+1,)
    lon_rad: np.ndarray        # (N+1,)
    h_m: np.ndarray            # (N+1,) ellipsoidal height
    v_enu_mps: np.ndarray      # (N+1, 3) Earth-relative velocity, ENU
    roll_rad: np.ndarray       # (N+1,)
    pitch_rad: np.ndarray      # (N+1,)
    heading_rad: np.ndarray    # (N+1,) [0, 2 pi)
    q_bn: np.ndarray           # (N+1, 4) {w, x, y, z}
    f_b_mps2: np.ndarray       # (N+1, 3) specific force, body
    w_ib_b_rps: np.ndarray     # (N+1, 3) inertial angular rate, body
    dtheta_b_rad: np.ndarray   # (N+1, 3)
    dv_b_mps: np.ndarray       # (N+1, 3)
    speed_mps: np.ndarray      # (N+1,) signed path speed (forward = +y body; < 0 reversing)
    yaw_rate_rps: np.ndarray   # (N+1,) heading rate
    dist_m: np.ndarray         # (N+1,) cumulative |path length|
    outages: list              # [(start_s, end_s, label)]
    name: str
    imu_rate_hz: float
    curvature_1pm: np.ndarray = None  # (N+1,) path curvature relative to the nose, right +
    grade_rad: np.ndarray = None      # (N+1,) path grade angle
    duration_s: float = 0.0           # scenario length (t_s[-1] may exceed it by < 1 sample)
    vehicle: dict = field(default_factory=dict)

    def longest_outage(self) -> tuple | None:
        """(start_s, end_s, distance_m) of the GNSS outage driven furthest, None without one
        (the one tools.sim.seeds reports and the references measure)."""
        outs = [(a, b) for (a, b, *_label) in self.outages]
        if not outs:
            return None
        dist = np.interp(np.array(outs, dtype=float), self.t_s, self.dist_m)
        k = int(np.argmax(dist[:, 1] - dist[:, 0]))
        return float(outs[k][0]), float(outs[k][1]), float(dist[k, 1] - dist[k, 0])

    def to_csv(self, path):
        """truth.csv: t, lat/lon (deg), h, vE/vN/vU, roll/pitch/heading (deg), dist, speed."""
        cols = np.column_stack([
            self.t_s, np.degrees(self.lat_rad), np.degrees(self.lon_rad), self.h_m,
            self.v_enu_mps, np.degrees(self.roll_rad), np.degrees(self.pitch_rad),
            np.degrees(self.heading_rad), self.dist_m, self.speed_mps])
        header = ("t_s,lat_deg,lon_deg,h_m,vE_mps,vN_mps,vU_mps,roll_deg,pitch_deg,"
                  "heading_deg,dist_m,speed_mps")
        fmt = ["%.4f", "%.10f", "%.10f", "%.4f", "%.5f", "%.5f", "%.5f", "%.6f", "%.6f",
               "%.6f", "%.4f", "%.5f"]
        np.savetxt(path, cols, fmt=fmt, delimiter=",", header=header, comments="")


def _integrate_position(lat0, lon0, h0, v0, vm, v1, dt, max_iter=40):
    """Sequential RK4 (truth.c) solved by fixed-point iteration over the whole drive."""
    n = len(v0)
    lat_prev = np.full(n, lat0)
    h_prev = h0 + np.concatenate([[0.0], np.cumsum(0.5 * dt * (v0[:-1, 2] + v1[:-1, 2]))])
    for _ in range(max_iter):
        r1 = pos_rate(lat_prev, h_prev, v0)
        r2 = pos_rate(lat_prev + 0.5 * dt * r1[0], h_prev + 0.5 * dt * r1[2], vm)
        r3 = pos_rate(lat_prev + 0.5 * dt * r2[0], h_prev + 0.5 * dt * r2[2], vm)
        r4 = pos_rate(lat_prev + dt * r3[0], h_prev + dt * r3[2], v1)
        inc = [dt / 6.0 * (r1[j] + 2.0 * r2[j] + 2.0 * r3[j] + r4[j]) for j in range(3)]
        lat = lat0 + np.concatenate([[0.0], np.cumsum(inc[0])])
        lon = lon0 + np.concatenate([[0.0], np.cumsum(inc[1])])
        h = h0 + np.concatenate([[0.0], np.cumsum(inc[2])])
        d_lat = np.max(np.abs(lat[:-1] - lat_prev)) if n else 0.0
        d_h = np.max(np.abs(h[:-1] - h_prev)) if n else 0.0
        lat_prev, h_prev = lat[:-1], h[:-1]
        if d_lat < 1e-14 and d_h < 1e-8:
            r1 = pos_rate(lat_prev, h_prev, v0)
            return lat, lon, h, r1
    raise RuntimeError("truth position iteration did not converge")


def generate(scenario: dict, imu_rate_hz: float, chunk: int = 40000) -> Truth:
    """Exact truth and IMU increments of a scenario at imu_rate_hz."""
    traj = Trajectory(scenario)
    rate = float(imu_rate_hz)
    dt = 1.0 / rate
    n = int(math.ceil(traj.duration_s * rate - 1e-9))
    k_all = np.arange(n + 1)
    t = k_all / rate
    kin = traj.kinematics(t)
    kin_mid = traj.kinematics((k_all[:-1] + 0.5) / rate)
    v = kin["v"]
    lat, lon, h, p0 = _integrate_position(traj.lat0, traj.lon0, traj.h0, v[:-1],
                                          kin_mid["v"], v[1:], dt)
    q, w_nb = traj.attitude(kin)
    w_ib, f_b = sensed(kin, q, w_nb, lat, h)

    dth = np.zeros((n + 1, 3))
    dvb = np.zeros((n + 1, 3))
    half = 0.5 * dt
    # intervals k = 1..n, in chunks; node times t_{k-1} + tau
    for c0 in range(0, n, chunk):
        c1 = min(n, c0 + chunk)
        kk = np.arange(c0, c1)  # index of the interval start sample (k - 1)
        tau = half * (GL_X[:, None] + 1.0)  # (5, 1)
        tn = kk[None, :] / rate + tau
        latn = lat[kk][None, :] + p0[0][kk][None, :] * tau
        hn = h[kk][None, :] + p0[2][kk][None, :] * tau
        kn = traj.kinematics(tn)
        qn, wn = traj.attitude(kn)
        wib, fb = sensed(kn, qn, wn, latn, hn)
        wts = (half * GL_W)[:, None, None]
        dth[c0 + 1:c1 + 1] = np.sum(wts * wib, axis=0)
        dvb[c0 + 1:c1 + 1] = np.sum(wts * fb, axis=0)

    # intervals containing a piece boundary: split there and integrate each part
    br = traj.breaks[(traj.breaks > 0.0) & (traj.breaks < n / rate)]
    kb = np.floor(br * rate).astype(int)  # interval start sample
    inside = (br - kb / rate > 1e-12) & ((kb + 1) / rate - br > 1e-12)
    br, kb = br[inside], kb[inside]
    if len(kb):
        sub_k, sub_a, sub_b = [], [], []
        for k0 in np.unique(kb):
            edges = np.concatenate([[k0 / rate], np.sort(br[kb == k0]), [(k0 + 1) / rate]])
            for a_, b_ in zip(edges[:-1], edges[1:]):
                sub_k.append(k0)
                sub_a.append(a_)
                sub_b.append(b_)
        sub_k, sub_a, sub_b = np.array(sub_k), np.array(sub_a), np.array(sub_b)
        hl = 0.5 * (sub_b - sub_a)
        tn = 0.5 * (sub_a + sub_b)[None, :] + hl[None, :] * GL_X[:, None]
        taun = tn - (sub_k / rate)[None, :]
        latn = lat[sub_k][None, :] + p0[0][sub_k][None, :] * taun
        hn = h[sub_k][None, :] + p0[2][sub_k][None, :] * taun
        kn = traj.kinematics(tn)
        qn, wn = traj.attitude(kn)
        wib, fb = sensed(kn, qn, wn, latn, hn)
        wts = GL_W[:, None, None] * hl[None, :, None]
        ddth = np.sum(wts * wib, axis=0)
        ddv = np.sum(wts * fb, axis=0)
        rows = sub_k + 1
        dth[np.unique(rows)] = 0.0
        dvb[np.unique(rows)] = 0.0
        np.add.at(dth, rows, ddth)
        np.add.at(dvb, rows, ddv)

    heading = np.mod(kin["H"], 2.0 * math.pi)
    heading[heading >= 2.0 * math.pi] = 0.0
    outages = [(o["start_s"], o["end_s"], o["label"]) for o in scenario.get("outage", [])]
    return Truth(
        t_s=t, lat_rad=lat, lon_rad=lon, h_m=h, v_enu_mps=v, roll_rad=kin["roll"],
        pitch_rad=kin["pitch"], heading_rad=heading, q_bn=q, f_b_mps2=f_b, w_ib_b_rps=w_ib,
        dtheta_b_rad=dth, dv_b_mps=dvb, speed_mps=kin["s"], yaw_rate_rps=kin["Hd"],
        dist_m=kin["dist"], outages=outages, name=str(scenario.get("name", "")),
        imu_rate_hz=rate, curvature_1pm=kin["kappa"], grade_rad=kin["gamma"],
        duration_s=traj.duration_s, vehicle=dict(traj.vehicle))


def timeline(scenario: dict):
    """[(start_s, end_s, kind)] of the scenario's segments (for placing outages)."""
    return Trajectory(scenario).segment_times


if __name__ == "__main__":  # print a scenario's timeline
    import sys

    from tools.sim.scenario import load

    sc = load(sys.argv[1])
    tr = Trajectory(sc)
    for i, (a, b, kind) in enumerate(tr.segment_times):
        print(f"{i:3d} {a:8.1f} {b:8.1f} {kind}")
    print(f"duration {tr.duration_s:.1f} s")
