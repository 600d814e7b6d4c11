#!/usr/bin/env python3
"""Write a candump log of a vehicle standing still on the rotating WGS-84 Earth.

At t = 0: CMD_KnownPosition (the true latitude/longitude), then CMD_Control with
Command = 2 (SetInitialPosition), HeadingValid = 1, Heading and Height. Then, for
k = 1 .. duration*rate, one IMU sample at t = k/rate (IMU_Rate then IMU_Accel, same
ImuCounter, the pair CRC in IMU_Accel: navecu_can.E2ESender.encode_imu_pair) carrying the
exact increments over ((k-1)/rate, k/rate] of a vehicle at rest, quantised to the DBC's
LSBs with the remainder carried (navecu_can.ImuQuantizer); and WheelSpeeds frames at
50 Hz (t = j/50, j = 1 ..), all four speeds 0.

Frames (docs/frames.md): navigation n = ENU, body b = x right, y forward, z up.
    angle increment    dtheta_b = C_nb w_ie_n dt,        w_ie_n = (0, U cos lat, U sin lat)
    velocity increment dv_b     = C_nb (0, 0, gamma) dt  (specific force at rest = -g_n)
with gamma the normal gravity as firmware/nav/earth.c computes it (TR8350.2 eqs. 4-1, 4-3).
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from tools import geodesy, navecu_can
from tools.sim import trajectory

WHEEL_RATE_HZ = 50.0


def normal_gravity(lat_rad: float, h_m: float) -> float:
    """Normal gravity magnitude (m/s^2) as firmware/nav/earth.c computes it (TR8350.2 eqs.
    4-1, 4-3), from tools/geodesy.py."""
    return float(geodesy.gravity(math.sin(lat_rad), h_m))


def earth_rate_n(lat_rad: float) -> np.ndarray:
    """Earth rate in ENU: (0, U cos lat, U sin lat) rad/s."""
    return geodesy.earth_rate_n(lat_rad)


def c_bn(roll_rad: float, pitch_rad: float, heading_rad: float) -> np.ndarray:
    """Body-to-navigation DCM, v_n = C_bn v_b, Euler 3-1-2 of docs/frames.md:
    C_bn = Rz(-H) Rx(pitch) Ry(roll)."""
    return trajectory.quat_to_dcm(trajectory.quat_from_euler(roll_rad, pitch_rad, heading_rad))


def stationary_increments(lat_deg, height_m, roll_deg, pitch_deg, heading_deg, dt_s):
    """Exact (dtheta_b rad, dv_b m/s) over dt_s of a vehicle at rest."""
    lat = math.radians(lat_deg)
    c_nb = c_bn(math.radians(roll_deg), math.radians(pitch_deg), math.radians(heading_deg)).T
    dtheta_b = c_nb @ earth_rate_n(lat) * dt_s
    dv_b = c_nb @ np.array([0.0, 0.0, normal_gravity(lat, height_m)]) * dt_s
    return dtheta_b, dv_b


def generate(duration_s=600.0, imu_rate_hz=100.0, lat_deg=45.0, lon_deg=10.0, height_m=100.0,
             heading_deg=30.0, roll_deg=0.0, pitch_deg=0.0, db=None):
    """Yield the frames of the log, in time order (an IMU pair before a WheelSpeeds frame of
    the same timestamp)."""
    sender = navecu_can.E2ESender(db)
    n_imu = int(round(duration_s * imu_rate_hz))
    n_wheel = int(round(duration_s * WHEEL_RATE_HZ))
    yield sender.encode("CMD_KnownPosition", {"Latitude": lat_deg, "Longitude": lon_deg}, 0.0)
    heading_cmd_deg = (round(heading_deg % 360.0 * 100.0) % 36000) / 100.0  # [0, 359.99]
    yield sender.encode("CMD_Control", {"Command": 2, "HeadingValid": 1,
                                        "Heading": heading_cmd_deg, "Height": height_m}, 0.0)
    dtheta_b, dv_b = stationary_increments(lat_deg, height_m, roll_deg, pitch_deg, heading_deg,
                                           1.0 / imu_rate_hz)
    quant = navecu_can.ImuQuantizer()
    k = j = 1
    while k <= n_imu or j <= n_wheel:
        t_imu = k / imu_rate_hz if k <= n_imu else math.inf
        t_wheel = j / WHEEL_RATE_HZ if j <= n_wheel else math.inf
        if t_imu <= t_wheel:
            rate, accel = quant.signals(dtheta_b, dv_b)
            yield from sender.encode_imu_pair(rate, accel, t_imu)  # IMU_Rate, then IMU_Accel
            k += 1
        else:
            yield sender.encode("WheelSpeeds", {"WheelSpeedFL": 0.0, "WheelSpeedFR": 0.0,
                                                "WheelSpeedRL": 0.0, "WheelSpeedRR": 0.0}, t_wheel)
            j += 1


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True, help="candump log to write (.log)")
    p.add_argument("--duration-s", type=float, default=600.0)
    p.add_argument("--imu-rate-hz", type=float, default=100.0)
    p.add_argument("--lat-deg", type=float, default=45.0)
    p.add_argument("--lon-deg", type=float, default=10.0)
    p.add_argument("--height-m", type=float, default=100.0)
    p.add_argument("--heading-deg", type=float, default=30.0)
    p.add_argument("--roll-deg", type=float, default=0.0)
    p.add_argument("--pitch-deg", type=float, default=0.0)
    a = p.parse_args(argv)
    if not (a.duration_s > 0 and a.imu_rate_hz > 0):
        p.error("--duration-s and --imu-rate-hz must be positive")
    if not abs(a.lat_deg) < 89.0:
        p.error("--lat-deg must be within (-89, 89)")
    n = navecu_can.write_candump(a.out, generate(
        a.duration_s, a.imu_rate_hz, a.lat_deg, a.lon_deg, a.height_m, a.heading_deg,
        a.roll_deg, a.pitch_deg))
    print(f"{a.out}: {n} frames, {a.duration_s:g} s stationary at {a.lat_deg:g} deg N "
          f"{a.lon_deg:g} deg E {a.height_m:g} m, roll {a.roll_deg:g} pitch {a.pitch_deg:g} "
          f"heading {a.heading_deg:g} deg, IMU {a.imu_rate_hz:g} Hz, wheels {WHEEL_RATE_HZ:g} Hz, "
          f"gravity {normal_gravity(math.radians(a.lat_deg), a.height_m):.10f} m/s^2")
    return 0


if __name__ == "__main__":
    sys.exit(main())
