"""The recorded Kingston 2008 drive -> one candump log through the project DBC.

    python -m tools.kingston.convert --out out/kingston/can_in.log [--data DIR]
        [--no-gnss] [--outages "a-b,c-d" | every:PERIOD:LENGTH[:OFFSET] | default | none]
        [--calibrate-at-km 5 | none] [--imu-rule rect|trapezoid] [--no-odometer] [--level]
        [--no-gnss-velocity]

Writes the log and a sidecar JSON next to it (can_in.json): the time base, what was
converted, dropped or found irregular, the initialization and the calibration point.
docs/kingston.md explains every rule; in short:

- Time base: t = 0 s at the first IMU sample (GPS time of week t0_gps = imu.csv's first
  time_s, 152143.09 s in week 1485); every frame's timestamp is GPS time - t0_gps, rounded
  to the microsecond. Rows of the 1 Hz files stamped before t = 0 (or after the last IMU
  sample) cannot be sent and are counted in the sidecar ("before_start", "after_end").
- IMU, at its own rate (10 Hz): the firmware takes angle and velocity increments per sample,
  over the interval that ends at the sample time. imu.csv holds rate and specific-force
  samples x_k at t_k. Rule "rect" (the default): x_k is the mean over the interval that
  ends at t_k, the increment is x_k * (t_k - t_{k-1}). Rule "trapezoid": x_k is
  instantaneous, the increment is (x_{k-1} + x_k) / 2 * (t_k - t_{k-1}), which is the
  same sum but 50 ms (half a period) later. Measured (tools/kingston/analyse.py): the
  reference heading's 1 s increments match -wz best at lag 0 ms with "rect" and at +50 ms
  with "trapezoid" (residual 0.095 vs 0.269 deg/s at lag 0), the reference speed's match
  fy at +10 ms vs +60 ms: the samples are interval means (or carry half a period of
  latency), hence "rect". With either rule the first row only closes the interval before
  t = 0: N rows give N - 1 IMU samples, the first at t = 0.1 s (the firmware's IMU time of
  that sample is 1 / rate, the same). Quantised with the remainder carry (ImuQuantizer),
  sent with encode_imu_pair (one counter, pair CRC). Duplicated time stamps are dropped
  and counted (identical or conflicting values); a gap of m sample periods is sent as lost
  samples: the ImuCounter skips m - 1 values, the sample after the gap carries the
  increment of its own last nominal period (trapezoid: of the straight line between the
  two samples around the gap), and the firmware bridges the lost ones (docs/can.md). Time
  going backwards or samples off the rate grid by more than a quarter period are errors.
  The recorded file has none of these (checked, counted as 0).
- WheelSpeeds: one frame per odometer row (1 Hz OBD speed), all four wheels = the speed,
  rounded to the DBC's 0.02 m/s.
- GNSS: one epoch per gnss.csv row (1 Hz): GNSS_Position, GNSS_Velocity, GNSS_Height,
  GNSS_Status as tools/sim/run.py frames() sends them. FixType 3 (the CSV has no fix type),
  NumSatellites = gnss_raw.csv's rows at that time (0 when it has none: the firmware
  ignores epochs with fewer than 4), HorizAccuracy = the 68.27 % radius of a circular
  Gaussian with the mean of the lat/lon variances, 1.5152 * sqrt((sd_N^2 + sd_E^2) / 2),
  as the simulator defines it; VertAccuracy = height_std_m; both saturate at 102.3 m.
  SpeedAccuracy: the receiver's velocity log has no accuracy: a constant 0.2 m/s (the
  fixes' 68 % horizontal velocity error against the reference is 0.12 m/s). Height: the
  receiver's is above mean sea level, about 34.1 m above the reference's ellipsoidal height
  (the geoid undulation there is -34 m). GNSS_Height carries the WGS-84 ellipsoidal height
  (docs/can.md), as a receiver configured for it would send: the receiver's value minus
  GNSS_HEIGHT_ABOVE_REF_M, measured on these files (docs/kingston.md).
  TimeOfWeek: the row's GPS time of week.
- Initialization at t = 0, from reference.csv's first row (GPS 152143.0, 0.09 s before the
  first IMU sample; the car stands still): CMD_KnownPosition, CMD_Control
  SetInitialPosition (Command 2, HeadingValid 1, Heading = azimuth, Height = the
  reference's ellipsoidal height), then CMD_InitialAttitude (roll, pitch in rad).
- --calibrate-at-km D: at the first reference epoch whose travelled distance (the reference
  positions' polyline) is >= D km, at the first IMU sample time at or after that epoch:
  CMD_KnownPosition with the reference position interpolated (linearly in time) to that
  time, immediately followed by CMD_Control CalibrateHere (Command 5). Both frames are
  sent right after that IMU sample, so the firmware's state is valid at the frame time.
- --no-gnss: no GNSS frame at all (dead reckoning); --no-odometer: no WheelSpeeds frame
  (with --no-gnss the firmware runs free-inertial); --no-gnss-velocity: no GNSS_Velocity
  frame (position-only GNSS). --outages: GNSS epochs with
  a <= t < b (seconds from t = 0) are dropped, for each a-b; "every:P:L" is the outages
  [kP, kP + L) for k = 1, 2, ... that end within the data, "every:P:L:O" the same moved
  O seconds later (0 <= O < P: the same schedule at another phase of the drive);
  "default" = every:240:60.
"""
from __future__ import annotations

import argparse
import os
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tools import navecu_can as nc
from tools.data_csv import DataError, read_csv
from tools.geodesy import horizontal_distance_m

ROOT = Path(__file__).resolve().parents[2]


#: The recorded drive: data/kingston-2008 in the repository (its README.md: source,
#: licence), or the folder $NAVECU_KINGSTON_DIR names; --data DIR overrides both.
DATA_DIR = Path(os.environ.get("NAVECU_KINGSTON_DIR") or ROOT / "data" / "kingston-2008")
IMU_RATE_HZ = 10
DEFAULT_OUTAGES = "every:240:60"
DEFAULT_CAL_KM = 5.0
IMU_RULES = ("rect", "trapezoid")
SPEED_ACCURACY_MPS = 0.2
HACC_PER_SIGMA = 1.5152  # 68.27 % radius of a circular Gaussian, in sigmas per axis
ACC_MAX_M = 102.3  # GNSS_Status Horiz/VertAccuracy range
GNSS_HEIGHT_ABOVE_REF_M = 34.1  # measured datum difference (docs/kingston.md), removed
GPS_WEEK = 1485

# frame order at equal timestamps
O_KNOWN, O_SETPOS, O_ATT, O_RATE, O_ACCEL, O_WHEEL = 0, 1, 2, 3, 4, 5
O_GPOS, O_GVEL, O_GHGT, O_GSTAT, O_CAL_KNOWN, O_CAL_CMD = 6, 7, 8, 9, 10, 11
O_GRAW = 12  # a raw epoch's frames, in their own order (tools/gnss_raw.encode_epoch)


@dataclass
class Drive:
    """The CSV files as numpy structured arrays (columns as in the README)."""
    imu: np.ndarray
    odo: np.ndarray
    gnss: np.ndarray
    ref: np.ndarray
    raw_time_s: np.ndarray  # gnss_raw.csv time_s, one per satellite row
    data_dir: Path

    @property
    def t0_gps(self) -> float:
        return float(self.imu["time_s"][0])

    def head(self, seconds: float) -> "Drive":
        """The first `seconds` of the drive (every file cut at t0_gps + seconds): a shorter
        drive with the same time base, for tests."""
        t_end = self.t0_gps + seconds

        def cut(a):
            return a[a["time_s"] < t_end]
        return Drive(imu=cut(self.imu), odo=cut(self.odo), gnss=cut(self.gnss),
                     ref=cut(self.ref), raw_time_s=self.raw_time_s[self.raw_time_s < t_end],
                     data_dir=self.data_dir)


#: the columns the converter reads from each file (data/kingston-2008/README.md)
COLUMNS = {
    "imu.csv": ("time_s", "fx_mps2", "fy_mps2", "fz_mps2", "wx_radps", "wy_radps", "wz_radps"),
    "odometer.csv": ("time_s", "speed_mps"),
    "gnss.csv": ("time_s", "lat_deg", "lon_deg", "height_m", "lat_std_m", "lon_std_m",
                 "height_std_m", "ve_mps", "vn_mps", "vu_mps"),
    "reference.csv": ("time_s", "lat_deg", "lon_deg", "height_m", "ve_mps", "vn_mps", "vu_mps",
                      "roll_deg", "pitch_deg", "azimuth_deg"),
    "gnss_raw.csv": ("time_s",),
}


def _read_csv(path: Path) -> np.ndarray:
    """One of the drive's files, every cell a finite number (data_csv.read_csv: DataError
    with the file and line otherwise)."""
    return read_csv(path, COLUMNS[Path(path).name])


def load(data_dir=None) -> Drive:
    d = Path(data_dir) if data_dir else DATA_DIR
    if not (d / "imu.csv").exists():
        raise DataError(f"no Kingston data in {d} (imu.csv missing)")
    return Drive(imu=_read_csv(d / "imu.csv"), odo=_read_csv(d / "odometer.csv"),
                 gnss=_read_csv(d / "gnss.csv"), ref=_read_csv(d / "reference.csv"),
                 raw_time_s=_read_csv(d / "gnss_raw.csv")["time_s"], data_dir=d)


# ------------------------------------------------------------------ geometry ----

def reference_track(drive: Drive) -> dict:
    """reference.csv on the log's time base: t_s (s from the first IMU sample), lat/lon in
    degrees, and dist_m, the travelled distance along the polyline of the 1 Hz reference
    positions from its first row."""
    r = drive.ref
    ds = horizontal_distance_m(r["lat_deg"][:-1], r["lon_deg"][:-1], r["lat_deg"][1:],
                               r["lon_deg"][1:])
    return {"t_s": r["time_s"] - drive.t0_gps, "lat_deg": r["lat_deg"], "lon_deg": r["lon_deg"],
            "heading_deg": r["azimuth_deg"], "dist_m": np.concatenate(([0.0], np.cumsum(ds)))}


# ----------------------------------------------------------------------- IMU ----

@dataclass
class ImuSeries:
    """The IMU samples as sent: frame times, exact increments and lost samples before each."""
    t_s: np.ndarray          # (M,) frame time, s from the first IMU sample
    dtheta_rad: np.ndarray   # (M, 3) angle increments, body x right, y forward, z up
    dv_mps: np.ndarray       # (M, 3) velocity increments
    lost_before: np.ndarray  # (M,) samples missing before this one (counter skips)
    timing: dict


def imu_increments(imu: np.ndarray, t0_gps: float, rate_hz: int = IMU_RATE_HZ,
                   rule: str = "rect") -> ImuSeries:
    """Angle and velocity increments between consecutive IMU rows by `rule` ("rect" or
    "trapezoid", module docstring), with the timing checks (duplicates dropped and counted,
    gaps as lost samples, backwards time or off-grid samples raise ValueError)."""
    if rule not in IMU_RULES:
        raise ValueError(f"IMU rule '{rule}': one of {', '.join(IMU_RULES)}")
    period = 1.0 / rate_hz
    t = np.asarray(imu["time_s"], dtype=float)
    w = np.column_stack([imu["wx_radps"], imu["wy_radps"], imu["wz_radps"]])
    f = np.column_stack([imu["fx_mps2"], imu["fy_mps2"], imu["fz_mps2"]])
    dt_all = np.diff(t)
    if np.any(dt_all < -1e-3 * period):
        k = int(np.argmax(dt_all < -1e-3 * period))
        raise ValueError(f"imu.csv: time goes backwards after row {k + 1} (t = {t[k]})")
    dup = np.concatenate(([False], np.abs(dt_all) <= 1e-3 * period))
    dup_identical = int(sum(1 for k in np.flatnonzero(dup)
                            if np.array_equal(w[k], w[k - 1]) and np.array_equal(f[k], f[k - 1])))
    keep = ~dup
    t, w, f = t[keep], w[keep], f[keep]
    dt = np.diff(t)
    steps = np.rint(dt / period).astype(int)
    offgrid = np.abs(dt - steps * period)
    if offgrid.size and offgrid.max() > 0.25 * period:
        k = int(np.argmax(offgrid))
        raise ValueError(f"imu.csv: interval {dt[k]:.4f} s at t = {t[k]} is off the "
                         f"{rate_hz} Hz grid")
    single = steps == 1
    dth = np.empty((len(dt), 3))
    dvel = np.empty((len(dt), 3))
    if rule == "rect":
        dth[single] = w[1:][single] * dt[single, None]
        dvel[single] = f[1:][single] * dt[single, None]
    else:
        dth[single] = 0.5 * (w[:-1][single] + w[1:][single]) * dt[single, None]
        dvel[single] = 0.5 * (f[:-1][single] + f[1:][single]) * dt[single, None]
    gaps = []
    for k in np.flatnonzero(~single):
        # the sample after the gap: the increment of its own last nominal period
        if rule == "rect":
            dth[k] = w[k + 1] * period
            dvel[k] = f[k + 1] * period
        else:  # of the straight line between the two samples around the gap
            alpha = 1.0 - period / dt[k]
            ws = w[k] + (w[k + 1] - w[k]) * alpha
            fs = f[k] + (f[k + 1] - f[k]) * alpha
            dth[k] = 0.5 * (ws + w[k + 1]) * period
            dvel[k] = 0.5 * (fs + f[k + 1]) * period
        gaps.append({"after_t_s": round(float(t[k] - t0_gps), 6), "interval_s": float(dt[k]),
                     "missing_samples": int(steps[k] - 1)})
    lost = np.maximum(steps - 1, 0)
    timing = {
        "rows": int(len(imu)), "rate_hz": rate_hz, "rule": rule, "nominal_interval_s": period,
        "interval_min_s": float(dt.min()), "interval_max_s": float(dt.max()),
        "max_offgrid_s": float(offgrid.max()) if offgrid.size else 0.0,
        "duplicates_identical": dup_identical,
        "duplicates_conflicting": int(dup.sum()) - dup_identical,
        "gaps": gaps, "missing_samples": int(lost.sum()),
        "samples_sent": int(len(dt)),
        "note": "the first row opens the first interval: rows - duplicates - 1 samples are sent",
    }
    return ImuSeries(t_s=np.round(t[1:] - t0_gps, 6), dtheta_rad=dth, dv_mps=dvel,
                     lost_before=lost, timing=timing)


# -------------------------------------------------------------------- options ----

def parse_outages(spec, t_end_s: float) -> list:
    """'a-b,c-d' | 'every:P:L[:O]' | 'default' | 'none' -> [(a, b), ...] in s from t = 0."""
    if spec is None:
        return []
    spec = str(spec).strip()
    if spec in ("", "none"):
        return []
    if spec == "default":
        spec = DEFAULT_OUTAGES
    if spec.startswith("every:"):
        fields = spec.split(":")[1:]
        try:
            if len(fields) not in (2, 3):
                raise ValueError
            period, length, offset = (float(x) for x in fields + ["0"] * (3 - len(fields)))
        except ValueError:
            raise ValueError(f"outages: '{spec}' is not every:PERIOD:LENGTH[:OFFSET]") from None
        if not (math.isfinite(period) and 1.0 <= period and 0 < length < period):
            raise ValueError(f"outages: '{spec}' needs 0 < LENGTH < PERIOD, PERIOD a finite "
                             "number of seconds, at least 1")
        if not 0 <= offset < period:
            raise ValueError(f"outages: '{spec}' needs 0 <= OFFSET < PERIOD")
        out, k = [], 1
        while k * period + offset + length <= t_end_s:
            out.append((k * period + offset, k * period + offset + length))
            k += 1
        return out
    out = []
    for part in spec.split(","):
        try:
            a, b = (float(x) for x in part.strip().split("-"))
        except ValueError:
            raise ValueError(f"outages: '{part}' is not a-b (seconds from the start)") from None
        if not 0 <= a < b:
            raise ValueError(f"outages: '{part}' needs 0 <= a < b")
        out.append((a, b))
    return sorted(out)


def in_outage(t_s: float, outages) -> int:
    """Index of the outage [a, b) holding t_s, or -1."""
    for i, (a, b) in enumerate(outages):
        if a <= t_s < b:
            return i
    return -1


def _row_times(rows, t0_gps, t_last_s):
    """Relative times of a 1 Hz file and the masks of rows before t = 0 / after the end."""
    t = np.round(rows["time_s"] - t0_gps, 6)
    return t, t < 0.0, t > t_last_s


def _timing_1hz(t_gps) -> dict:
    dt = np.diff(t_gps)
    return {"rows": int(len(t_gps)), "interval_min_s": float(dt.min()),
            "interval_max_s": float(dt.max()),
            "duplicates": int(np.sum(dt == 0)), "gaps": int(np.sum(dt > 1.5))}


# --------------------------------------------------------------------- frames ----

def build(drive: Drive, *, gnss: bool = True, outages=(), calibrate_at_km=DEFAULT_CAL_KM,
          speed_accuracy_mps: float = SPEED_ACCURACY_MPS, imu_rule: str = "rect",
          initial_attitude: bool = True, odometer: bool = True, gnss_velocity: bool = True,
          gnss_raw: bool = False, raw_keep_in_outages: int = 0, db=None) -> tuple:
    """Every input frame of the drive as (t_s, order, can.Message), sorted, and the sidecar
    metadata (a dict, JSON-ready)."""
    db = db if db is not None else nc.DEFAULT_DB
    sender = nc.E2ESender(db)
    t0 = drive.t0_gps
    out = []
    imu = imu_increments(drive.imu, t0, rule=imu_rule)
    t_last = float(imu.t_s[-1])
    meta = {"data_dir": str(drive.data_dir), "gps_week": GPS_WEEK,
            "t0_gps_s": t0, "time_base": "t = GPS time of week - t0_gps_s (first IMU sample)",
            "imu": imu.timing, "last_imu_sample_s": t_last}

    # initialization: reference's first row
    r0 = drive.ref[0]
    hdg0 = (round(float(r0["azimuth_deg"]) % 360.0 * 100.0) % 36000) / 100.0
    init = {"ref_gps_s": float(r0["time_s"]), "lat_deg": float(r0["lat_deg"]),
            "lon_deg": float(r0["lon_deg"]), "height_m": float(r0["height_m"]),
            "heading_deg": hdg0, "roll_deg": float(r0["roll_deg"]),
            "pitch_deg": float(r0["pitch_deg"]), "frame_time_s": 0.0}
    meta["init"] = init
    out.append((0.0, O_KNOWN, sender.encode("CMD_KnownPosition", {
        "Latitude": init["lat_deg"], "Longitude": init["lon_deg"]}, 0.0)))
    out.append((0.0, O_SETPOS, sender.encode("CMD_Control", {
        "Command": 2, "HeadingValid": 1, "Heading": hdg0, "Height": init["height_m"]}, 0.0)))
    init["initial_attitude_sent"] = bool(initial_attitude)
    if initial_attitude:
        out.append((0.0, O_ATT, sender.encode("CMD_InitialAttitude", {
            "InitRoll": math.radians(init["roll_deg"]),
            "InitPitch": math.radians(init["pitch_deg"])}, 0.0)))

    # IMU
    quant = nc.ImuQuantizer()
    rate_name = nc.IMU_PAIR[0]
    for k in range(len(imu.t_s)):
        t = float(imu.t_s[k])
        rate, accel = quant.signals(imu.dtheta_rad[k], imu.dv_mps[k])
        counter = None
        if imu.lost_before[k]:
            counter = (sender.next_counter(rate_name) + int(imu.lost_before[k])) % (
                nc.E2E_COUNTER_MAX + 1)
        r, a = sender.encode_imu_pair(rate, accel, t, counter=counter)
        out.append((t, O_RATE, r))
        out.append((t, O_ACCEL, a))

    # odometer
    t_odo, before, after = _row_times(drive.odo, t0, t_last)
    speeds = drive.odo["speed_mps"]
    if np.any(np.abs(speeds) > 81.9):
        raise ValueError("odometer speed beyond the WheelSpeeds range (81.9 m/s)")
    n_wheel = 0
    for t, v, skip in zip(t_odo, speeds, before | after):
        if skip or not odometer:
            continue
        v = float(v)
        out.append((float(t), O_WHEEL, sender.encode("WheelSpeeds", {
            "WheelSpeedFL": v, "WheelSpeedFR": v, "WheelSpeedRL": v, "WheelSpeedRR": v},
            float(t))))
        n_wheel += 1
    meta["odometer"] = dict(_timing_1hz(drive.odo["time_s"]), enabled=bool(odometer),
                            frames=n_wheel,
                            before_start=int(before.sum()), after_end=int(after.sum()))

    # GNSS
    g = drive.gnss
    t_g, before, after = _row_times(g, t0, t_last)
    raw_epochs, raw_counts = np.unique(np.rint(drive.raw_time_s), return_counts=True)
    nsat_by_s = dict(zip(raw_epochs.astype(int).tolist(), raw_counts.tolist()))
    outages = [tuple(map(float, o)) for o in outages]
    dropped = [0] * len(outages)
    n_epochs = n_below4 = n_hacc_sat = n_vacc_sat = 0
    for i in range(len(g)):
        t = float(t_g[i])
        if before[i] or after[i] or not gnss:
            continue
        k = in_outage(t, outages)
        if k >= 0:
            dropped[k] += 1
            continue
        row = g[i]
        nsat = int(nsat_by_s.get(int(round(float(row["time_s"]))), 0))
        hacc = HACC_PER_SIGMA * math.sqrt(0.5 * (row["lat_std_m"] ** 2 + row["lon_std_m"] ** 2))
        vacc = float(row["height_std_m"])
        n_hacc_sat += hacc > ACC_MAX_M
        n_vacc_sat += vacc > ACC_MAX_M
        n_below4 += nsat < 4
        epoch = sender.next_counter("GNSS_Velocity")
        out.append((t, O_GPOS, sender.encode("GNSS_Position", {
            "Latitude": float(row["lat_deg"]), "Longitude": float(row["lon_deg"])}, t)))
        if gnss_velocity:
            out.append((t, O_GVEL, sender.encode("GNSS_Velocity", {
                "VelEast": float(row["ve_mps"]), "VelNorth": float(row["vn_mps"]),
                "VelUp": float(row["vu_mps"]), "SpeedAccuracy": speed_accuracy_mps}, t)))
        out.append((t, O_GHGT, sender.encode("GNSS_Height", {
            "Height": float(row["height_m"]) - GNSS_HEIGHT_ABOVE_REF_M, "GnssEpoch": epoch},
            t)))
        out.append((t, O_GSTAT, sender.encode("GNSS_Status", {
            "FixType": 3, "NumSatellites": min(nsat, 63),
            "HorizAccuracy": min(hacc, ACC_MAX_M), "VertAccuracy": min(vacc, ACC_MAX_M),
            "GnssEpoch": epoch,
            "TimeOfWeek": round(float(row["time_s"]) % 604800.0, 3)}, t)))
        n_epochs += 1
    meta["gnss"] = dict(
        _timing_1hz(g["time_s"]), enabled=bool(gnss), velocity_sent=bool(gnss_velocity),
        epochs_sent=n_epochs,
        before_start=int(before.sum()), after_end=int(after.sum()),
        epochs_below_4_satellites_sent=int(n_below4),
        horiz_accuracy_saturated=int(n_hacc_sat), vert_accuracy_saturated=int(n_vacc_sat),
        speed_accuracy_mps=speed_accuracy_mps,
        height_note=f"receiver heights (above mean sea level) minus {GNSS_HEIGHT_ABOVE_REF_M} m: "
                    "ellipsoidal, as the reference's (geoid undulation)",
        outages=[{"start_s": a, "end_s": b, "epochs_dropped": n}
                 for (a, b), n in zip(outages, dropped)],
        epochs_dropped_in_outages=int(sum(dropped)))

    # raw measurements (issue #20): gnss_raw.csv as raw epochs, after the fix of the same
    # second; in an outage none, or with raw_keep_in_outages N the N highest satellites (a
    # partial outage: an urban canyon that leaves a few)
    meta["gnss_raw"] = None
    if gnss_raw and gnss:
        from tools import gnss_raw as gr
        from tools.kingston import raw as kraw
        n_raw = n_partial = n_sats = 0
        for tow, ep in kraw.epochs(kraw.read(drive.data_dir), drive.gnss,
                                   GNSS_HEIGHT_ABOVE_REF_M):
            t = tow - t0
            if t < 0.0 or t > t_last:
                continue
            if in_outage(t, outages) >= 0:
                if raw_keep_in_outages <= 0:
                    continue
                ep.meas = sorted(ep.meas, key=lambda m: -m.elevation_deg)[:raw_keep_in_outages]
                n_partial += 1
            number = n_raw % (nc.E2E_COUNTER_MAX + 1)
            for k, m in enumerate(gr.encode_epoch(sender, ep, number, t)):
                out.append((t, O_GRAW + k, m))
            n_raw += 1
            n_sats += len(ep.meas)
        meta["gnss_raw"] = {"epochs_sent": n_raw, "satellites_sent": n_sats,
                            "partial_epochs_in_outages": n_partial,
                            "keep_in_outages": int(raw_keep_in_outages)}

    # one-point calibration at a known point
    meta["calibration"] = None
    if calibrate_at_km is not None:
        ref = reference_track(drive)
        reached = np.flatnonzero(ref["dist_m"] >= 1000.0 * calibrate_at_km)
        if not reached.size:
            raise ValueError(f"the reference never reaches {calibrate_at_km} km "
                             f"({ref['dist_m'][-1] / 1000:.2f} km in all)")
        k = int(reached[0])
        t_epoch = float(ref["t_s"][k])
        i = int(np.searchsorted(imu.t_s, t_epoch - 1e-9))
        if i >= len(imu.t_s):
            raise ValueError("calibration point after the last IMU sample")
        t_cal = float(imu.t_s[i])
        lat = float(np.interp(t_cal, ref["t_s"], ref["lat_deg"]))
        lon = float(np.interp(t_cal, ref["t_s"], ref["lon_deg"]))
        dist = float(np.interp(t_cal, ref["t_s"], ref["dist_m"]))
        out.append((t_cal, O_CAL_KNOWN, sender.encode("CMD_KnownPosition", {
            "Latitude": lat, "Longitude": lon}, t_cal)))
        out.append((t_cal, O_CAL_CMD, sender.encode("CMD_Control", {
            "Command": 5, "HeadingValid": 0, "Heading": 0.0, "Height": 0.0}, t_cal)))
        meta["calibration"] = {
            "at_km": calibrate_at_km, "ref_epoch_gps_s": float(drive.ref["time_s"][k]),
            "ref_epoch_t_s": t_epoch, "time_s": t_cal, "gps_s": round(t0 + t_cal, 6),
            "lat_deg": lat, "lon_deg": lon, "distance_m": dist,
            "frames": "CMD_KnownPosition then CMD_Control Command 5 (CalibrateHere), "
                      "right after the IMU sample at time_s"}
    out.sort(key=lambda x: (x[0], x[1]))
    meta["frames"] = len(out)
    return out, meta


def sidecar_path(log_path) -> Path:
    p = Path(log_path)
    return p.with_name(p.name[:-4] + ".json" if p.name.endswith(".log") else p.name + ".json")


def convert(out_log, data_dir=None, **kw) -> dict:
    """Load, build and write the log and its sidecar JSON; returns the metadata."""
    drive = load(data_dir)
    frames, meta = build(drive, **kw)
    out_log = Path(out_log)
    out_log.parent.mkdir(parents=True, exist_ok=True)
    nc.write_candump(out_log, (m for _, _, m in frames))
    meta["log"] = str(out_log)
    sidecar_path(out_log).write_text(json.dumps(meta, indent=2))
    return meta


def parse_km(s):
    return None if str(s).strip().lower() in ("none", "off", "") else float(s)


def summary(meta: dict) -> str:
    imu, odo, g = meta["imu"], meta["odometer"], meta["gnss"]
    lines = [f"t0 = GPS {meta['t0_gps_s']:.2f} s (week {meta['gps_week']}); "
             f"{meta['frames']} frames",
             f"IMU: {imu['rows']} rows -> {imu['samples_sent']} samples at {imu['rate_hz']} Hz, "
             f"rule {imu['rule']} "
             f"(interval {imu['interval_min_s']:.4f}..{imu['interval_max_s']:.4f} s, "
             f"duplicates {imu['duplicates_identical']}+{imu['duplicates_conflicting']}, "
             f"gaps {len(imu['gaps'])}, missing {imu['missing_samples']})",
             f"odometer: {odo['rows']} rows -> {odo['frames']} WheelSpeeds "
             f"({odo['before_start']} before t = 0, {odo['after_end']} after the end)"]
    if g["enabled"]:
        lines.append(f"GNSS: {g['rows']} rows -> {g['epochs_sent']} epochs ({g['before_start']} "
                     f"before t = 0, {g['epochs_dropped_in_outages']} in "
                     f"{len(g['outages'])} outages, {g['epochs_below_4_satellites_sent']} sent "
                     "with < 4 satellites)")
    else:
        lines.append("GNSS: none (--no-gnss)")
    r = meta.get("gnss_raw")
    if r:
        lines.append(f"raw GNSS: {r['epochs_sent']} epochs, {r['satellites_sent']} satellites "
                     f"({r['partial_epochs_in_outages']} in outages with the "
                     f"{r['keep_in_outages']} highest)")
    c = meta["calibration"]
    if c:
        lines.append(f"calibration: CalibrateHere at t = {c['time_s']:.2f} s "
                     f"({c['distance_m'] / 1000:.3f} km), {c['lat_deg']:.7f}, {c['lon_deg']:.7f}")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=None, help=f"data folder (default {DATA_DIR})")
    ap.add_argument("--out", required=True, help="output candump log (sidecar: same name .json)")
    ap.add_argument("--no-gnss", action="store_true", help="omit every GNSS frame")
    ap.add_argument("--outages", default="none",
                    help="'a-b,c-d' seconds from t = 0, every:P:L[:O], default (every:240:60), none")
    ap.add_argument("--calibrate-at-km", default=str(DEFAULT_CAL_KM), type=parse_km,
                    help="CalibrateHere at this reference distance (km), or none")
    ap.add_argument("--imu-rule", choices=IMU_RULES, default="rect",
                    help="IMU increment rule (module docstring; default rect)")
    ap.add_argument("--level", action="store_true",
                    help="no CMD_InitialAttitude: the firmware levels on its own (30 s)")
    ap.add_argument("--no-odometer", action="store_true",
                    help="omit every WheelSpeeds frame (with --no-gnss: free inertial)")
    ap.add_argument("--no-gnss-velocity", action="store_true",
                    help="omit every GNSS_Velocity frame (GNSS position only)")
    ap.add_argument("--gnss-raw", action="store_true",
                    help="also send gnss_raw.csv as raw epochs (GNSS_Raw*, docs/can.md)")
    ap.add_argument("--raw-keep", type=int, default=0, metavar="N",
                    help="with --gnss-raw: in the outages keep the N highest satellites' raw "
                         "measurements (a partial outage) instead of none")
    a = ap.parse_args(argv)
    try:
        drive = load(a.data)
    except DataError as e:
        print(f"kingston.convert: {e}", file=sys.stderr)
        return 1
    t_end = float(drive.imu["time_s"][-1] - drive.t0_gps)
    try:
        outages = parse_outages(a.outages, t_end)
    except ValueError as e:
        ap.error(str(e))
    try:
        meta = convert(a.out, a.data, gnss=not a.no_gnss, outages=outages,
                       calibrate_at_km=a.calibrate_at_km, imu_rule=a.imu_rule,
                       initial_attitude=not a.level, odometer=not a.no_odometer,
                       gnss_velocity=not a.no_gnss_velocity, gnss_raw=a.gnss_raw,
                       raw_keep_in_outages=a.raw_keep)
    except ValueError as e:   # the data's own irregularities (time going back, a range)
        print(f"kingston.convert: {e}; nothing written", file=sys.stderr)
        return 1
    print(summary(meta))
    print(f"wrote {a.out} and {sidecar_path(a.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
