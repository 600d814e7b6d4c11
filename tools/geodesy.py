"""WGS-84 for the Python tools: the constants of firmware/nav/earth.h and the conversions
the simulator, its report and the Kingston tools share (one copy; docs/frames.md).

Two forms of the radii of curvature, the same formula rounded in a different order, each
kept bit for bit for the numbers already produced with it:

- earth_radii(sin_lat): the firmware's earth.c in double precision (the simulator's truth
  and its Earth model: gravity, earth_rate_n, transport_rate_n, pos_rate);
- radii_m(lat_rad): the error statistics (horizontal_error_m, horizontal_distance_m) and
  the GNSS error model of tools/sim/sensors.py.

Angles in radians unless a name says _deg; ENU navigation frame; numpy arrays or floats.
"""
from __future__ import annotations

import math

import numpy as np

# --- WGS-84 (NIMA TR8350.2), the constants of firmware/nav/earth.h -----------------------
WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563
WGS84_E2 = 6.69437999014e-3
WGS84_OMEGA_IE_RPS = 7.292115e-5
WGS84_GAMMA_E_MPS2 = 9.7803253359
WGS84_GAMMA_P_MPS2 = 9.8321849378
WGS84_SOMIGLIANA_K = 0.00193185265241
WGS84_M = 0.00344978650684


# --- Earth model (earth.c, double) ----------------------------------------------------------
def earth_radii(sin_lat):
    """Meridian and prime-vertical radii of curvature (m) for sin(latitude), as earth.c."""
    w2 = 1.0 - WGS84_E2 * sin_lat * sin_lat
    w = np.sqrt(w2)
    r_n = WGS84_A_M / w
    r_m = WGS84_A_M * (1.0 - WGS84_E2) / (w2 * w)
    return r_m, r_n


def gravity(sin_lat, h_m):
    """Normal gravity (m/s^2), Somigliana with the second-order height series."""
    s2 = sin_lat * sin_lat
    g0 = WGS84_GAMMA_E_MPS2 * (1.0 + WGS84_SOMIGLIANA_K * s2) / np.sqrt(1.0 - WGS84_E2 * s2)
    inv_a = 1.0 / WGS84_A_M
    k1 = 2.0 * inv_a * (1.0 + WGS84_F + WGS84_M - 2.0 * WGS84_F * s2)
    k2 = 3.0 * inv_a * inv_a
    return g0 * (1.0 - k1 * h_m + k2 * h_m * h_m)


def earth_rate_n(lat_rad):
    """w_ie in ENU, shape (..., 3)."""
    lat = np.asarray(lat_rad, dtype=float)
    return np.stack([np.zeros_like(lat), WGS84_OMEGA_IE_RPS * np.cos(lat),
                     WGS84_OMEGA_IE_RPS * np.sin(lat)], axis=-1)


def transport_rate_n(lat_rad, h_m, v_n):
    """w_en in ENU (seed 001 eq. 7), shape (..., 3)."""
    sl, cl = np.sin(lat_rad), np.cos(lat_rad)
    r_m, r_n = earth_radii(sl)
    inv_rm = 1.0 / (r_m + h_m)
    inv_rn = 1.0 / (r_n + h_m)
    tl = sl / cl
    v_n = np.asarray(v_n, dtype=float)
    return np.stack([-v_n[..., 1] * inv_rm, v_n[..., 0] * inv_rn,
                     v_n[..., 0] * tl * inv_rn], axis=-1)


def pos_rate(lat_rad, h_m, v_n):
    """d(lat, lon, h)/dt (seed 001 eq. 6) as three arrays."""
    r_m, r_n = earth_radii(np.sin(lat_rad))
    return v_n[..., 1] / (r_m + h_m), v_n[..., 0] / ((r_n + h_m) * np.cos(lat_rad)), v_n[..., 2]


# --- local distances -----------------------------------------------------------------------
def radii_m(lat_rad):
    """Meridian and prime-vertical radii of curvature (WGS-84), m."""
    w2 = 1.0 - WGS84_E2 * np.sin(lat_rad) ** 2
    return WGS84_A_M * (1.0 - WGS84_E2) / w2 ** 1.5, WGS84_A_M / np.sqrt(w2)


def horizontal_error_m(lat_true, lon_true, lat_est, lon_est):
    """(distance, east, north) in m of the estimates from the true positions (rad), on the
    local radii at the true latitude; longitudes wrapped to [-pi, pi)."""
    rm, rn = radii_m(lat_true)
    dn = (lat_est - lat_true) * rm
    dlon = (lon_est - lon_true + math.pi) % (2 * math.pi) - math.pi
    de = dlon * rn * np.cos(lat_true)
    return np.hypot(de, dn), de, dn


def horizontal_distance_m(lat1_deg, lon1_deg, lat2_deg, lon2_deg):
    """Horizontal distance between two (arrays of) points in degrees, local radii at the
    first, m; longitude differences wrapped to [-180, 180) degrees."""
    la1, la2 = np.radians(lat1_deg), np.radians(lat2_deg)
    rm, rn = radii_m(la1)
    dn = (la2 - la1) * rm
    de = np.radians((np.asarray(lon2_deg) - lon1_deg + 180.0) % 360.0 - 180.0) * rn * np.cos(la1)
    return np.hypot(de, dn)
