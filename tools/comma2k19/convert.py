"""The comma2k19 RAV4 segment as navecu's input: the car's whole recorded bus, unchanged,
merged with the windshield device's IMU and u-blox GNSS encoded as navecu frames.

    python -m tools.comma2k19.convert OUT.log [--data data/comma2k19-rav4]
        [--vehicle toyota_rav4_2017] [--channels can0,can1,can2,can3] [--no-car-bus]
        [--outage A-B] [--imu-time grid|stamped]

The files are described in data/comma2k19-rav4/README.md; docs/vehicles.md says how they
are used. What navecu is given beyond the recording (none of it is in the car's frames):

- **Time base**: t = segment clock - t0, t0 the first IMU sample; the firmware's own time
  is its IMU sample count (docs/can.md), the log's timestamps only order the frames.
- **IMU**: 104.26 Hz with jittered stamps (314..316 ticks of 32.768 kHz) resampled to a
  fixed IMU_RATE_HZ grid without losing any motion: the trapezoidal integral of the rates
  and specific forces at the device's stamps, interpolated to the grid, differenced (each
  grid increment holds exactly what the device measured over that interval); sent in the
  device's own axes (x forward, y right, z down): the firmware is configured with the
  device's mounting in the car (--imu-mount-deg, the meta's imu_mount_deg_312: its x
  forward / y right / z down axes and the roll, pitch and yaw of the segment's reference,
  device_mount_deg, as README "Mounting" measures them; the RAV4's -0.90 / -3.75 / +1.25
  deg), the rotation that navecu's own body axes (x right, y forward, z up) need.
- **The segment's own facts** come from its files, not from constants: its GPS week and
  time of week less the segment clock from the fixes (gps_time_of), the device's mounting
  from the reference pose (device_mount_deg), so another comma2k19 segment in this
  folder's format (another car, `--vehicle` its profile) is converted as this one is.
  With --imu-time stamped, no resampling: one sample per device sample after the first,
  its increments the trapezoidal integral over its own interval (the previous stamp to
  its own), and before its IMU_Rate an IMU_Time with the device's own stamp in
  microseconds (round(t_s * 1e6) modulo 2^32); the firmware is then run with
  --imu-time stamped and the nominal rate STAMPED_RATE_HZ (run.py).
- **GNSS**: the u-blox fixes (9.7 Hz), sent when they were logged (t_s), with their own
  time of validity in TimeOfWeek (gps_tow_s) and the week in GNSS_Time; the latency of the
  earliest-logged fix is the firmware's --gnss-latency-ms (gnss_latency_ms in the meta);
  the log has no accuracy fields and no vertical velocity: the frames carry
  HorizAccuracy, VertAccuracy, SpeedAccuracy and VelUp 0, and the firmware is told so
  (run.py: --gnss-accuracy declared with the receiver class's datasheet figures,
  --gnss-vel-up none).
- **Initial state**: the car never stops, so it cannot level: the reference pose at t0
  (position, height, the car's heading, roll and pitch) in CMD_KnownPosition,
  SetInitialPosition and CMD_InitialAttitude; or (init_state none, run.py --init none) no
  command at all: the firmware's in-motion alignment starts it from GNSS.
- **The car's bus**: every frame of car_bus.log (all four channels on navecu's bus, as if a
  gateway bridged them: 2,258 frames/s), untouched, at its recorded time.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

import can
import numpy as np

from tools import navecu_can as nc
from tools import vehicle
from tools.data_csv import read_csv

ROOT = Path(__file__).resolve().parents[2]
DATA_DIR = Path(os.environ.get("NAVECU_COMMA2K19_DIR") or ROOT / "data" / "comma2k19-rav4")
IMU_RATE_HZ = 100
#: --imu-time stamped: the device's nominal rate, what the firmware is configured with
#: (104.264 Hz measured, README "IMU"; a u16 parameter)
STAMPED_RATE_HZ = 104
#: the mounting is derived to this step (deg): the reference's per-epoch scatter of the
#: velocity's direction in the device's axes is 0.10 deg in yaw and 0.27 deg in elevation
#: (README "Mounting"), its mean known to a few hundredths
MOUNT_STEP_DEG = 0.05
#: reference epochs used for the mounting: moving at least this fast (m/s)
MOUNT_MIN_SPEED_MPS = 1.0
MOUNT_MIN_EPOCHS = 100
#: the fixes' GPS time of week less t_fix_s agree to this (s; the files carry 1 us)
TOW_OFFSET_TOL_S = 2e-6
# frame order within one timestamp: commands, then IMU halves, then GNSS epoch
O_KNOWN, O_SETPOS, O_ATT, O_CAR, O_TIME, O_RATE, O_ACCEL = 0, 1, 2, 3, 4, 5, 6
O_GPOS, O_GVEL, O_GHGT, O_GTIME, O_GSTAT = 7, 8, 9, 10, 11


def _csv(path: Path) -> np.ndarray:
    """One of the segment's CSV files, every cell a finite number (data_csv.read_csv:
    DataError, a ValueError, naming the file and line otherwise)."""
    return read_csv(path)


def _rot(axis: int, a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    m = np.eye(3)
    i, j = [(1, 2), (0, 2), (0, 1)][axis]
    m[i, i] = m[j, j] = c
    m[i, j], m[j, i] = (-s, s) if axis != 1 else (s, -s)
    return m


def zyx(yaw_deg: float, pitch_deg: float, roll_deg: float) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll): maps a vector from the rotated frame to the reference
    one (aerospace Z-Y-X, e.g. body FRD to NED)."""
    return (_rot(2, math.radians(yaw_deg)) @ _rot(1, math.radians(pitch_deg))
            @ _rot(0, math.radians(roll_deg)))


#: FRD <-> RFU and NED <-> ENU (its own inverse)
P_SWAP = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def car_from_device(mount_deg: dict) -> np.ndarray:
    """car RFU <- device FRD, of the device's Z-Y-X angles against the car (FRD; README
    "Mounting")."""
    return P_SWAP @ zyx(mount_deg["yaw"], mount_deg["pitch"], mount_deg["roll"])


def device_mount_deg(ref: np.ndarray) -> dict:
    """The device's roll, pitch and yaw against the car (Z-Y-X in FRD, deg, to
    MOUNT_STEP_DEG) from the segment's reference pose, as README "Mounting" measures them:
    the car's forward axis the mean direction of the velocity in the device's axes over the
    epochs moving at least MOUNT_MIN_SPEED_MPS, its down axis the mean local vertical made
    square to it (the car's mean roll taken as 0). ValueError when fewer than
    MOUNT_MIN_EPOCHS epochs move (a car that did not drive cannot tell its forward axis)."""
    fwd, down = np.zeros(3), np.zeros(3)
    n = 0
    for r in ref:
        v_ned = np.array([r["vn_mps"], r["ve_mps"], -r["vu_mps"]])
        speed = float(np.linalg.norm(v_ned))
        if speed < MOUNT_MIN_SPEED_MPS:
            continue
        c_dev_ned = zyx(r["heading_deg"], r["pitch_deg"], r["roll_deg"]).T
        fwd += c_dev_ned @ v_ned / speed
        down += c_dev_ned[:, 2]
        n += 1
    if n < MOUNT_MIN_EPOCHS:
        raise ValueError(f"reference.csv: {n} epochs at {MOUNT_MIN_SPEED_MPS} m/s or more, "
                         f"{MOUNT_MIN_EPOCHS} needed for the device's mounting")
    fwd /= np.linalg.norm(fwd)
    down -= fwd * float(fwd @ down)
    down /= np.linalg.norm(down)
    c_car_dev = np.vstack([fwd, np.cross(down, fwd), down])   # car FRD <- device FRD
    angles = {"roll": math.atan2(c_car_dev[2, 1], c_car_dev[2, 2]),
              "pitch": -math.asin(max(-1.0, min(1.0, c_car_dev[2, 0]))),
              "yaw": math.atan2(c_car_dev[1, 0], c_car_dev[0, 0])}
    return {k: round(round(math.degrees(a) / MOUNT_STEP_DEG) * MOUNT_STEP_DEG, 2) + 0.0
            for k, a in angles.items()}


def gps_time_of(gps: np.ndarray) -> tuple:
    """(GPS week, GPS time of week less the segment clock, s) of the segment, from its
    fixes: gps_tow_s - t_fix_s, one constant (README "Time base"). ValueError when the
    fixes disagree by more than TOW_OFFSET_TOL_S or carry more than one week."""
    d = gps["gps_tow_s"] - gps["t_fix_s"]
    weeks = set(int(w) for w in gps["gps_week"])
    if len(d) == 0 or len(weeks) != 1:
        raise ValueError(f"gnss_ublox.csv: {len(d)} fixes in weeks {sorted(weeks)}: one "
                         "week needed")
    off = round(float(np.median(d)), 6)
    if float(np.max(np.abs(d - off))) > TOW_OFFSET_TOL_S:
        raise ValueError("gnss_ublox.csv: gps_tow_s - t_fix_s is not one constant (up to "
                         f"{float(np.max(np.abs(d - off))):.6f} s from {off:.6f} s)")
    return weeks.pop(), off


def car_attitude(roll_deg, pitch_deg, heading_deg, c_car_dev) -> tuple:
    """The car's roll, pitch, heading (deg, docs/frames.md: 3-1-2, roll right side down,
    pitch nose up, heading clockwise from north) from the device's reference attitude
    (Z-Y-X against NED) and the mounting (c_car_dev: car_from_device)."""
    c_ned_dev = zyx(heading_deg, pitch_deg, roll_deg)
    c_bn = P_SWAP @ c_ned_dev @ c_car_dev.T   # ENU <- car RFU
    pitch = math.asin(max(-1.0, min(1.0, c_bn[2, 1])))
    roll = math.atan2(-c_bn[2, 0], c_bn[2, 2])
    heading = math.atan2(c_bn[0, 1], c_bn[1, 1]) % (2 * math.pi)
    return math.degrees(roll), math.degrees(pitch), math.degrees(heading)


def euler_312_deg(C) -> tuple:
    """(roll, pitch, yaw) deg of a rotation C (vehicle <- IMU) in docs/frames.md's 3-1-2
    convention, C = Rz(-yaw) Rx(pitch) Ry(roll): what --imu-mount-deg takes
    (firmware/app/mounting.h)."""
    pitch = math.asin(max(-1.0, min(1.0, C[2, 1])))
    roll = math.atan2(-C[2, 0], C[2, 2])
    yaw = math.atan2(C[0, 1], C[1, 1])
    return tuple(round(math.degrees(x), 4) for x in (roll, pitch, yaw))




def resample_increments(t_s, w, f, rate_hz: int = IMU_RATE_HZ) -> dict:
    """Angle and velocity increments on a fixed grid t0 + k / rate_hz (k = 0..) from
    samples at irregular stamps: the trapezoidal integral at the stamps, linearly
    interpolated to the grid and differenced. Sum of the increments = the integral over
    the grid's span (nothing lost or counted twice)."""
    t_s = np.asarray(t_s, dtype=float)
    if t_s.size < 2 or np.any(np.diff(t_s) <= 0.0):
        raise ValueError("IMU stamps must increase strictly")
    dt = np.diff(t_s)
    cum = {}
    for name, x in (("w", np.asarray(w, float)), ("f", np.asarray(f, float))):
        seg = 0.5 * (x[1:] + x[:-1]) * dt[:, None]
        cum[name] = np.vstack([np.zeros(3), np.cumsum(seg, axis=0)])
    n = int(math.floor((t_s[-1] - t_s[0]) * rate_hz + 1e-9))
    grid = t_s[0] + np.arange(n + 1) / rate_hz
    out = {}
    for name in ("w", "f"):
        g = np.column_stack([np.interp(grid, t_s, cum[name][:, i]) for i in range(3)])
        out[name] = np.diff(g, axis=0)
    return {"t_grid_s": grid, "dtheta": out["w"], "dv": out["f"],
            "interval_min_s": float(dt.min()), "interval_max_s": float(dt.max()),
            "rate_measured_hz": float((len(t_s) - 1) / (t_s[-1] - t_s[0]))}


def stamped_increments(t_s, w, f) -> dict:
    """Angle and velocity increments at the device's own stamps, no resampling: sample k
    (k = 1..) covers (t_{k-1}, t_k], the trapezoidal integral of the rates and specific
    forces over it; the same integral as resample_increments' before its interpolation.
    stamp_us: the device's stamps in microseconds modulo 2^32 (IMU_Time SampleTime)."""
    t_s = np.asarray(t_s, dtype=float)
    if t_s.size < 2 or np.any(np.diff(t_s) <= 0.0):
        raise ValueError("IMU stamps must increase strictly")
    dt = np.diff(t_s)
    out = {}
    for name, x in (("w", np.asarray(w, float)), ("f", np.asarray(f, float))):
        out[name] = 0.5 * (x[1:] + x[:-1]) * dt[:, None]
    stamp_us = np.round(t_s * 1e6).astype(np.int64) % (1 << 32)
    return {"t_s": t_s, "dtheta": out["w"], "dv": out["f"], "stamp_us": stamp_us[1:],
            "interval_min_s": float(dt.min()), "interval_max_s": float(dt.max()),
            "rate_measured_hz": float((len(t_s) - 1) / (t_s[-1] - t_s[0]))}


def parse_outage(spec):
    if spec in (None, "", "none"):
        return None
    try:
        a, b = (float(x) for x in spec.split("-"))
    except ValueError:
        raise ValueError(f"outage '{spec}' is not A-B (s from the start)") from None
    if not 0 <= a < b:
        raise ValueError(f"outage '{spec}' needs 0 <= A < B")
    return (a, b)


_CAR_FRAMES = {}


def car_frames(path: Path, skipped: list | None = None) -> list:
    """The frames of a car's candump log (python-can through nc.LogFile: a malformed line
    skipped and counted, as navecu skips it), read once per process; skipped: a list that
    gets the LogFile, for its count."""
    key = str(Path(path).resolve())
    if key not in _CAR_FRAMES:
        with nc.LogFile(path) as reader:
            _CAR_FRAMES[key] = (list(reader), reader)
    frames, reader = _CAR_FRAMES[key]
    if skipped is not None:
        skipped.append(reader)
    return frames


def build(data_dir=None, vehicle_name="toyota_rav4_2017", channels=None, car_bus=True,
          outage=None, car_ids=None, imu_time="grid", init_state="reference") -> tuple:
    """Every input frame as (t_s, order, can.Message) sorted, and the metadata (a dict,
    JSON-ready): module docstring. channels: the car_bus.log channels taken (None: all);
    car_ids: only the car's frames with these identifiers (None: all); imu_time: grid
    (resampled to IMU_RATE_HZ) or stamped (the device's samples with IMU_Time);
    init_state: reference (the reference pose at t0 in the initialization commands) or none
    (no command: the firmware starts by itself, the in-motion alignment)."""
    if imu_time not in ("grid", "stamped"):
        raise ValueError(f"imu_time {imu_time!r}: grid or stamped")
    if init_state not in ("reference", "none"):
        raise ValueError(f"init_state {init_state!r}: reference or none")
    data = Path(data_dir or DATA_DIR)
    db = nc.select_vehicle(vehicle_name)
    sender = nc.E2ESender(db)
    imu = _csv(data / "imu.csv")
    gps = _csv(data / "gnss_ublox.csv")
    ref = _csv(data / "reference.csv")
    gps_week, tow_minus_t_s = gps_time_of(gps)
    mount_deg = device_mount_deg(ref)
    c_car_dev = car_from_device(mount_deg)

    # IMU: device FRD -> car RFU, resampled
    w_dev = np.column_stack([imu["wx_radps"], imu["wy_radps"], imu["wz_radps"]])
    f_dev = np.column_stack([imu["ax_mps2"], imu["ay_mps2"], imu["az_mps2"]])
    if imu_time == "grid":
        rs = resample_increments(imu["t_s"], w_dev, f_dev)
        t0 = float(rs["t_grid_s"][0])
        t_imu = np.round(rs["t_grid_s"][1:] - t0, 6)
    else:
        rs = stamped_increments(imu["t_s"], w_dev, f_dev)
        t0 = float(rs["t_s"][0])
        t_imu = np.round(rs["t_s"][1:] - t0, 6)
    t_last = float(t_imu[-1])
    out = []
    meta = {"data_dir": str(data), "vehicle": vehicle_name, "t0_segment_s": t0,
            "t0_gps_tow_s": t0 + tow_minus_t_s, "gps_week": gps_week,
            "time_base": "t = segment clock - t0_segment_s (first IMU sample)",
            "imu": {"rows": int(len(imu)), "rate_measured_hz": rs["rate_measured_hz"],
                    "interval_min_s": rs["interval_min_s"],
                    "interval_max_s": rs["interval_max_s"],
                    "imu_time": imu_time,
                    "resampled_to_hz": IMU_RATE_HZ if imu_time == "grid" else None,
                    "configured_rate_hz": IMU_RATE_HZ if imu_time == "grid" else STAMPED_RATE_HZ,
                    "samples_sent": int(len(t_imu)),
                    "mounting_deg": mount_deg,
                    "axes": "the device's own (x forward, y right, z down)",
                    # the device's axes in the car's (x right, y forward, z up): the
                    # firmware's --imu-mount-deg; the samples go in the device's own axes
                    "imu_mount_deg_312": list(euler_312_deg(c_car_dev))},
            "last_imu_sample_s": t_last}

    # initial state: the reference at t0
    def ref_at(col):
        return float(np.interp(t0, ref["t_s"], ref[col]))
    roll, pitch, heading = car_attitude(ref_at("roll_deg"), ref_at("pitch_deg"),
                                        ref_at("heading_deg"), c_car_dev)
    hdg_cmd = (round(heading * 100.0) % 36000) / 100.0
    init = {"lat_deg": ref_at("lat_deg"), "lon_deg": ref_at("lon_deg"),
            "height_m": ref_at("height_m"), "heading_deg": hdg_cmd, "roll_deg": roll,
            "pitch_deg": pitch, "speed_mps": math.hypot(ref_at("ve_mps"), ref_at("vn_mps")),
            "source": "reference.csv at t0 (interpolated), the car's attitude from the "
                      "device's and the mounting"}
    init["sent"] = init_state == "reference"  # none: the firmware starts by itself
    meta["init"] = init
    if init_state == "reference":
        out.append((0.0, O_KNOWN, sender.encode("CMD_KnownPosition", {
            "Latitude": init["lat_deg"], "Longitude": init["lon_deg"]}, 0.0)))
        out.append((0.0, O_SETPOS, sender.encode("CMD_Control", {
            "Command": 2, "HeadingValid": 1, "Heading": hdg_cmd, "Height": init["height_m"]},
            0.0)))
        out.append((0.0, O_ATT, sender.encode("CMD_InitialAttitude", {
            "InitRoll": math.radians(roll), "InitPitch": math.radians(pitch)}, 0.0)))

    quant = nc.ImuQuantizer()
    for k in range(len(t_imu)):
        t = float(t_imu[k])
        rate, accel = quant.signals(rs["dtheta"][k], rs["dv"][k])
        if imu_time == "stamped":
            out.append((t, O_TIME, sender.encode("IMU_Time", {
                "SampleTime": int(rs["stamp_us"][k]),
                "ImuCounter": sender.next_counter("IMU_Rate")}, t)))
        r, a = sender.encode_imu_pair(rate, accel, t)
        out.append((t, O_RATE, r))
        out.append((t, O_ACCEL, a))

    # GNSS: u-blox, sent when logged
    latency = gps["t_s"] - gps["t_fix_s"]
    lat_ms = int(math.floor(float(latency.min()) * 1000.0))
    meta["gnss_latency_ms"] = lat_ms
    n_ep = n_out = 0
    for row in gps:
        t = round(float(row["t_s"]) - t0, 6)
        if t < 0.0 or t > t_last:
            continue
        t_fix = float(row["t_fix_s"]) - t0
        if outage is not None and outage[0] <= t_fix < outage[1]:
            n_out += 1
            continue
        ep = sender.next_counter("GNSS_Velocity")
        out.append((t, O_GPOS, sender.encode("GNSS_Position", {
            "Latitude": float(row["lat_deg"]), "Longitude": float(row["lon_deg"])}, t)))
        out.append((t, O_GVEL, sender.encode("GNSS_Velocity", {
            "VelEast": float(row["ve_mps"]), "VelNorth": float(row["vn_mps"]), "VelUp": 0.0,
            "SpeedAccuracy": 0.0}, t)))
        out.append((t, O_GHGT, sender.encode("GNSS_Height", {
            "Height": float(row["height_m"]), "GnssEpoch": ep}, t)))
        out.append((t, O_GTIME, sender.encode("GNSS_Time", {
            "GpsWeek": int(row["gps_week"]), "GnssEpoch": ep}, t)))
        out.append((t, O_GSTAT, sender.encode("GNSS_Status", {
            "FixType": 3, "NumSatellites": min(int(row["n_raw_meas"]), 63),
            "HorizAccuracy": 0.0, "VertAccuracy": 0.0,
            "GnssEpoch": ep, "TimeOfWeek": round(float(row["gps_tow_s"]) % 604800.0, 3)}, t)))
        n_ep += 1
    meta["gnss"] = {"receiver": "u-blox (gnss_ublox.csv)", "rows": int(len(gps)),
                    "epochs_sent": n_ep,
                    "accuracy_and_vel_up_sent": "0: the log has none (declared to the firmware)",
                    "latency_s": {"min": float(latency.min()), "max": float(latency.max()),
                                  "median": float(np.median(latency))},
                    "outage": None if outage is None else
                    {"start_s": outage[0], "end_s": outage[1], "epochs_dropped": n_out}}

    # the car's bus
    prof = vehicle.load(vehicle_name)
    read_ids = {}
    for r in prof.reads:
        read_ids[r.message.frame_id] = r.message.name
    per_ch, per_id, n_car = {}, {}, 0
    skipped = []
    if car_bus:
        for msg in car_frames(data / "car_bus.log", skipped):
            ch = str(msg.channel)
            if ((channels is not None and ch not in channels) or
                    (car_ids is not None and msg.arbitration_id not in car_ids)):
                continue
            t = round(float(msg.timestamp) - t0, 6)
            if t < 0.0 or t > t_last:
                continue
            out.append((t, O_CAR, can.Message(
                timestamp=t, arbitration_id=msg.arbitration_id,
                is_extended_id=msg.is_extended_id, data=bytes(msg.data), dlc=msg.dlc)))
            per_ch[ch] = per_ch.get(ch, 0) + 1
            if msg.arbitration_id in read_ids:
                name = read_ids[msg.arbitration_id]
                per_id[name] = per_id.get(name, 0) + 1
            n_car += 1
    meta["car_bus"] = {"file": str(data / "car_bus.log"), "frames": n_car,
                       "per_channel": per_ch, "profile_messages": per_id,
                       "frames_per_s": n_car / t_last if t_last > 0 else None,
                       "malformed_lines": skipped[0].malformed if skipped else 0,
                       "malformed_first": skipped[0].first_malformed if skipped else []}
    out.sort(key=lambda x: (x[0], x[1]))
    meta["frames"] = len(out)
    return out, meta


def write(out_log, frames, meta) -> None:
    out_log = Path(out_log)
    out_log.parent.mkdir(parents=True, exist_ok=True)
    nc.write_candump(out_log, (m for _, _, m in frames))
    out_log.with_suffix(".json").write_text(json.dumps(meta, indent=2) + "\n")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", help="candump log to write (its metadata beside it, .json)")
    ap.add_argument("--data", default=None)
    ap.add_argument("--vehicle", default="toyota_rav4_2017")
    ap.add_argument("--channels", default=None, help="car_bus.log channels (default all)")
    ap.add_argument("--no-car-bus", action="store_true", help="without the car's frames")
    ap.add_argument("--outage", default=None, help="GNSS outage A-B, s from the start")
    ap.add_argument("--imu-time", default="grid", choices=("grid", "stamped"),
                    help="grid: resampled to IMU_RATE_HZ; stamped: the device's samples with "
                         "IMU_Time")
    a = ap.parse_args(argv)
    try:
        frames, meta = build(a.data, a.vehicle,
                             None if a.channels is None else set(a.channels.split(",")),
                             not a.no_car_bus, parse_outage(a.outage), imu_time=a.imu_time)
    except (OSError, ValueError, vehicle.ProfileError) as e:
        print(f"comma2k19: {e}", file=sys.stderr)
        return 1
    write(a.out, frames, meta)
    print(f"comma2k19: {meta['frames']} frames, {meta['car_bus']['frames']} of the car's "
          f"bus ({meta['car_bus']['malformed_lines']} malformed lines of it skipped), "
          f"{meta['gnss']['epochs_sent']} GNSS epochs -> {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
