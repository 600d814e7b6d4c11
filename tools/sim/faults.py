"""Fault drives (`make faults`): the simulator's default drive with one fault injected per
row, the firmware run on each, and what it noticed and what it cost.

    python -m tools.sim.faults [--out out/faults] [--only NAME ...] [--doc docs/reliability.md]
                               [--seed 1] [--jobs N] [--navecu build/host/navecu]

The clean drive is generated once exactly as `make sim` does (tools/sim/run.py: the default
scenario, its IMU and GNSS presets, seed 1, run.firmware_args) and kept in memory as its
sorted frame list. Frame-level faults transform that list (loss, duplicates, reordering,
bad CRCs, bad counters, IMU silence, IMU timing jitter); sensor-level faults change the
sensor data and re-encode only that sensor's frames (the IMU samples that change through
navecu_can's ImuQuantizer and E2ESender, ImuEncoder; wheels and GNSS through run.frames).
The CMD_* frames (the driver's initialization at t = 0) are never touched by the
frame-level faults: without them the firmware does not navigate at all, which is not what
these rows measure.

For each row (out/<row>/: can_in.log, nav.log, navecu.txt; out/faults.json; the table in
--doc between the markers below):

- detected: the NAV_Status HealthFlags bits set at some time from the fault's start on but
  never in the clean run (bit names from the DBC comment of HealthFlags, named like the
  firmware's APP_FLAG_* defines), Mode values and NAV_Calibration CalStatus values the
  clean run never showed, and every Cnt* counter of every NAV_Status page whose last value
  is higher than the clean run's ("CntBadCrc +193"); "not detected" if nothing differs;
- non-finite: the firmware's own count of non-finite outputs it held back (its stderr
  line "non-finite outputs N"; "n/a" without it), and whether every decoded NAV_* value of
  nav.log is finite;
- RMS, max: the horizontal error (report.compute's series, every NAV_Position) over the
  whole drive, and the RMS ratio to the clean run;
- recovery: from the end of the fault window until the horizontal error stays within
  max(1 m, 1.5 x the clean run's error at the same instant) for 10 s; "0 s" if it was in
  that band from the window's end, "none" if it never got back; "n/a" for whole-drive
  faults;
- exit: navecu's exit status.

Exit status 1 if a row crashed (navecu exit status other than 0), has a non-finite output,
or if frame loss 1 % or 5 % raises the RMS above 1.5 x the clean run's (issue #9 floor).
"""
from __future__ import annotations

import argparse
import json
import math
import multiprocessing as mp
import os
import re
import subprocess
import sys
import time
import traceback
import zlib
from dataclasses import dataclass, field
from multiprocessing.connection import wait as mp_wait
from pathlib import Path
from types import SimpleNamespace
from typing import Callable, Optional

import can
import numpy as np

from tools import navecu_can as nc
from tools.navecu_can import counter_max, health_bits, status_signals
from tools.sim import report, run, scenario, sensors, trajectory

ROOT = Path(__file__).resolve().parents[2]
BEGIN = "<!-- BEGIN GENERATED: make faults -->"
END = "<!-- END GENERATED -->"

RECOVERY_HOLD_S = 10.0       # the error must stay in the band this long
RECOVERY_FLOOR_M = 1.0       # band: max(floor, factor x clean error at the same instant)
RECOVERY_FACTOR = 1.5
LOSS_RMS_LIMIT = 1.5         # frame loss 1 % and 5 %: RMS at most this x the clean run's

ORDER_WHEELS = {4}               # run.frames' order keys of each sensor's frames
ORDER_GNSS = {5, 6, 7, 8}


# ============================================================================ the clean drive
@dataclass
class Drive:
    """The clean default drive: truth, sensor data, firmware options, and its frames as
    run.frames gives them, sorted like run.main sorts them: (t_s, order, can.Message)."""
    scenario: str
    imu_name: str
    gnss_name: str
    seed: int
    imu_rate_hz: int
    truth: object
    dtheta: np.ndarray
    dv: np.ndarray
    wheels: tuple
    gnss: dict
    fw_args: list
    heading_deg: float
    db: object
    frames: list
    imu_encoder: "ImuEncoder" = None

    @property
    def messages(self) -> list:
        return [m for _, _, m in self.frames]


def build_drive(name: str = "default", seed: int = 1, imu_rate_hz: int = 100,
                log=print, car=None) -> Drive:
    """The clean drive, as run.main builds it for `make sim` (same presets, seeds, options,
    frames and order). car: as run.frames', a vehicle profile's tools.vehicle.CarEncoder
    (the wheel speeds in the car's own frames; with navecu_can.select_vehicle of that
    profile for navecu's identifiers)."""
    scen = scenario.load(name)
    imu_name, gnss_name = scenario.preset_names(scen)
    t = time.monotonic()
    truth = trajectory.generate(scen, imu_rate_hz)
    imu_spec, odo = scenario.sensor_specs(scen, imu_name, truth.vehicle)
    imu_seed, odo_seed, gnss_seed = sensors.drive_seeds(seed)
    dtheta, dv = sensors.apply_imu(truth, imu_spec, imu_seed)
    wheels = sensors.wheel_speeds(truth, odo, odo_seed)
    gnss = sensors.gnss_epochs(truth, sensors.GNSS_PRESETS[gnss_name], gnss_seed)
    if scen.get("gnss_faults") or scen.get("calibration"):
        raise SystemExit(f"scenario '{name}': fault drives start from a drive without "
                         "[gnss_faults] or [calibration]")
    fw_args = run.firmware_args(sensors.PRESETS[imu_name], sensors.GNSS_PRESETS[gnss_name],
                                odo)
    log(f"  trajectory and sensors ({scen.get('name', name)}, IMU {imu_name}, GNSS "
        f"{gnss_name}): {time.monotonic() - t:.1f} s")
    t = time.monotonic()
    db = nc.load_db()
    hdg = scenario.heading_command_deg(truth.heading_rad[0], scen)
    fr = run.frames(truth, dtheta, dv, wheels, gnss, db, heading_deg=hdg, car=car)
    fr.sort(key=lambda x: (x[0], x[1]))
    log(f"  CAN encoding: {len(fr)} frames, {time.monotonic() - t:.1f} s")
    d = Drive(scen.get("name", name), imu_name, gnss_name, seed, imu_rate_hz, truth,
              dtheta, dv, wheels, gnss, fw_args, hdg, db, fr)
    d.imu_encoder = ImuEncoder(d)
    return d


# ============================================================================ IMU re-encoding
class ImuEncoder:
    """The clean drive's IMU frames re-encoded from other increments by navecu_can, as
    run.frames encodes them: quantised by ImuQuantizer (remainder carried), and each sample
    whose raw values differ from the clean drive's sent again through
    E2ESender.encode_imu_pair with the clean frame's time and counter (the pair CRC follows);
    the other samples keep the clean frames."""

    def __init__(self, drive: Drive):
        self.db = drive.db
        rate_def, accel_def = map(self.db.get_message_by_name, nc.IMU_PAIR)
        msgs = drive.messages
        ids = np.array([m.arbitration_id for m in msgs])
        self.i_rate = np.nonzero(ids == rate_def.frame_id)[0]
        self.i_accel = np.nonzero(ids == accel_def.frame_id)[0]
        n = len(drive.truth.t_s) - 1
        if len(self.i_rate) != n or len(self.i_accel) != n:
            raise RuntimeError("IMU frames of the clean drive are not one pair per sample")
        cnt_sig = nc.e2e_signals(rate_def)[0]
        self.counters = [nc._counter_value(msgs[i].data, cnt_sig) for i in self.i_rate]
        self.clean_raw = self.raw(drive.dtheta, drive.dv)

    @staticmethod
    def raw(dtheta, dv) -> np.ndarray:
        """(n, 6) raw AngleIncX/Y/Z, VelIncX/Y/Z of samples 1..n of these increments."""
        q = nc.ImuQuantizer()
        return np.array([q.quantize_angle(a) + q.quantize_vel(v)
                         for a, v in zip(dtheta[1:], dv[1:])], dtype=np.int64).reshape(-1, 6)

    def frames(self, drive: Drive, dtheta, dv) -> tuple:
        """The clean sorted frame list with its IMU frames carrying these increments (new
        frames where a sample's raw values changed), and the number of samples changed."""
        raw = self.raw(dtheta, dv)
        changed = np.nonzero(np.any(raw != self.clean_raw, 1))[0]
        sender = nc.E2ESender(self.db)
        q = nc.ImuQuantizer()
        out = list(drive.frames)
        for k in changed:
            rate, accel = q.raw_signals(raw[k, :3].tolist(), raw[k, 3:].tolist())
            i_r, i_a = self.i_rate[k], self.i_accel[k]
            msgs = sender.encode_imu_pair(rate, accel, out[i_r][2].timestamp,
                                          counter=self.counters[k])
            for idx, m in zip((i_r, i_a), msgs):
                out[idx] = (out[idx][0], out[idx][1], m)
        return out, int(len(changed))


def reencode(drive: Drive, wheels=None, gnss=None) -> list:
    """The clean sorted frame list with the wheel and/or GNSS frames encoded from other
    data by run.frames (the IMU loop skipped: a truth with its first instant only; each
    message has its own E2E counter, so the others' frames are the clean ones)."""
    tr = drive.truth
    stub = SimpleNamespace(t_s=tr.t_s[:1], lat_rad=tr.lat_rad, lon_rad=tr.lon_rad, h_m=tr.h_m,
                           heading_rad=tr.heading_rad)
    w = wheels if wheels is not None else (np.zeros(0), np.zeros((0, 4)))
    g = gnss if gnss is not None else {k: np.asarray(v)[:0] for k, v in drive.gnss.items()}
    fr = run.frames(stub, drive.dtheta[:1], drive.dv[:1], w, g, drive.db,
                    heading_deg=drive.heading_deg)
    orders = (ORDER_WHEELS if wheels is not None else set()) | (ORDER_GNSS if gnss is not None
                                                                else set())
    out = [x for x in drive.frames if x[1] not in orders] + [x for x in fr if x[1] in orders]
    out.sort(key=lambda x: (x[0], x[1]))
    return out


# ============================================================================ frame-level faults
def copy_msg(m: can.Message, timestamp: Optional[float] = None, data=None) -> can.Message:
    return can.Message(timestamp=m.timestamp if timestamp is None else float(timestamp),
                       arbitration_id=m.arbitration_id, is_extended_id=m.is_extended_id,
                       is_fd=False, dlc=m.dlc,
                       data=bytearray(m.data if data is None else data))


def _defs(db):
    return {d.frame_id: d for d in db.messages}


def protected_mask(msgs, db=None) -> np.ndarray:
    """Frames no frame-level fault touches: the commands (CMD_*), the driver's
    initialization."""
    db = db if db is not None else nc.DEFAULT_DB
    ids = {d.frame_id for d in db.messages if d.name.startswith("CMD_")}
    return np.array([m.arbitration_id in ids for m in msgs], dtype=bool)


def _eligible(msgs, db, protect):
    p = protected_mask(msgs, db) if protect is None else np.asarray(protect, dtype=bool)
    return np.nonzero(~p)[0]


def _pick(rng, idx, frac) -> np.ndarray:
    k = int(round(frac * len(idx)))
    return np.sort(rng.choice(idx, size=k, replace=False)) if k else np.zeros(0, dtype=int)


def drop_frames(msgs, frac, rng, db=None, protect=None) -> tuple:
    """frac of the (unprotected) frames dropped at random: (new list, number dropped)."""
    drop = _pick(rng, _eligible(msgs, db, protect), frac)
    keep = np.ones(len(msgs), dtype=bool)
    keep[drop] = False
    return [m for m, k in zip(msgs, keep) if k], int(len(drop))


def duplicate_frames(msgs, frac, rng, db=None, protect=None) -> tuple:
    """frac of the frames sent twice in a row (the copy right after, same time)."""
    dup = set(_pick(rng, _eligible(msgs, db, protect), frac).tolist())
    out = []
    for i, m in enumerate(msgs):
        out.append(m)
        if i in dup:
            out.append(copy_msg(m))
    return out, len(dup)


def reorder_frames(msgs, frac, rng, db=None, protect=None) -> tuple:
    """frac of the adjacent frame pairs (i, i+1) swapped, pairs not overlapping; the
    receive times stay in order (each frame takes the other's time)."""
    el = np.zeros(len(msgs), dtype=bool)
    el[_eligible(msgs, db, protect)] = True
    starts = np.nonzero(el[:-1] & el[1:])[0]
    k = int(round(frac * max(len(msgs) - 1, 0)))
    chosen = np.zeros(len(msgs), dtype=bool)
    n = 0
    for i in rng.permutation(starts):
        if n >= k:
            break
        if chosen[i] or chosen[i + 1] or (i > 0 and chosen[i - 1]) or \
                (i + 2 < len(msgs) and chosen[i + 2]):
            continue
        chosen[i] = chosen[i + 1] = True
        n += 1
    out = list(msgs)
    i = 0
    while i < len(msgs) - 1:
        if chosen[i] and chosen[i + 1]:
            a, b = msgs[i], msgs[i + 1]
            out[i] = copy_msg(b, timestamp=a.timestamp)
            out[i + 1] = copy_msg(a, timestamp=b.timestamp)
            i += 2
        else:
            i += 1
    return out, n


def _e2e_info(db):
    """frame_id -> (name, counter signal, CRC signal or None) of the E2E messages."""
    out = {}
    for d in db.messages:
        e = nc.e2e_signals(d)
        if e is not None:
            out[d.frame_id] = (d.name, e[0], e[1])
    return out


def flip_crcs(msgs, frac, rng, db=None, protect=None) -> tuple:
    """The CRC byte (byte 7) of frac of the frames that carry one (E2E messages; IMU_Accel
    carries its sample's) inverted: (new list, number of frames)."""
    db = db if db is not None else nc.DEFAULT_DB
    info = _e2e_info(db)
    el = _eligible(msgs, db, protect)
    el = np.array([i for i in el if msgs[i].arbitration_id in info
                   and info[msgs[i].arbitration_id][2] is not None], dtype=int)
    sel = _pick(rng, el, frac)
    out = list(msgs)
    for i in sel:
        d = bytearray(msgs[i].data)
        d[7] ^= 0xFF
        out[i] = copy_msg(msgs[i], data=d)
    return out, int(len(sel))


def _set_counter(data: bytearray, sig, value: int) -> bytearray:
    word = int.from_bytes(bytes(data), "little")
    word = (word & ~(0xF << sig.start)) | ((value & 0xF) << sig.start)
    return bytearray(word.to_bytes(8, "little"))


def change_counters(msgs, frac, rng, db=None, protect=None) -> tuple:
    """The alive counter of frac of the E2E data elements changed to another valid value
    (0..14) with the CRC recomputed, so only the counter is wrong. A data element is one
    E2E frame, or an IMU sample (IMU_Rate + IMU_Accel: both counters changed, the pair
    CRC recomputed). (new list, number of elements)."""
    db = db if db is not None else nc.DEFAULT_DB
    info = _e2e_info(db)
    rate_id, accel_id = (db.get_message_by_name(n).frame_id for n in nc.IMU_PAIR)
    ok = np.zeros(len(msgs), dtype=bool)
    ok[_eligible(msgs, db, protect)] = True
    units = []
    for i, m in enumerate(msgs):
        fid = m.arbitration_id
        if not ok[i] or fid not in info or fid == rate_id:
            continue
        if fid == accel_id:
            if i > 0 and ok[i - 1] and msgs[i - 1].arbitration_id == rate_id and \
                    nc._counter_value(msgs[i - 1].data, info[rate_id][1]) == \
                    nc._counter_value(m.data, info[accel_id][1]):
                units.append(i)
            continue
        if info[fid][2] is not None:
            units.append(i)
    sel = _pick(rng, np.array(units, dtype=int), frac)
    out = list(msgs)
    for i in sel:
        m = msgs[i]
        fid = m.arbitration_id
        cs = info[fid][1]
        old = nc._counter_value(m.data, cs)
        new = (old + int(rng.integers(1, nc.E2E_COUNTER_MAX + 1))) % (nc.E2E_COUNTER_MAX + 1)
        d = _set_counter(m.data, cs, new)
        if fid == accel_id:
            r = _set_counter(msgs[i - 1].data, info[rate_id][1], new)
            d[7] = nc.imu_pair_crc(fid, r, d)
            out[i - 1] = copy_msg(msgs[i - 1], data=r)
        else:
            d[7] = nc.e2e_crc(fid, d)
        out[i] = copy_msg(m, data=d)
    return out, int(len(sel))


def _imu_ids(db):
    return {db.get_message_by_name(n).frame_id for n in nc.IMU_PAIR}


def drop_imu(msgs, t0, t1, db=None) -> tuple:
    """No IMU frame with t0 <= t < t1: (new list, IMU samples removed)."""
    db = db if db is not None else nc.DEFAULT_DB
    ids = _imu_ids(db)
    rate_id = db.get_message_by_name(nc.IMU_PAIR[0]).frame_id
    out, n = [], 0
    for m in msgs:
        if m.arbitration_id in ids and t0 <= m.timestamp < t1:
            n += m.arbitration_id == rate_id
            continue
        out.append(m)
    return out, n


def jitter_imu(msgs, frac_of_period, period_s, rng, db=None) -> tuple:
    """Every IMU sample's frames moved in time by the same uniform draw in
    +-frac_of_period x period_s (the two frames of a sample share their time), the log
    re-sorted by time (a stable sort: frames at equal times keep their order). Below half
    a period the IMU samples keep their order. (new list, samples jittered)."""
    db = db if db is not None else nc.DEFAULT_DB
    ids = _imu_ids(db)
    times = sorted({m.timestamp for m in msgs if m.arbitration_id in ids})
    shift = dict(zip(times, rng.uniform(-frac_of_period, frac_of_period, len(times)) * period_s))
    keyed = []
    for i, m in enumerate(msgs):
        if m.arbitration_id in ids:
            m = copy_msg(m, timestamp=m.timestamp + shift[m.timestamp])
        keyed.append((m.timestamp, i, m))
    keyed.sort(key=lambda x: (x[0], x[1]))
    return [m for _, _, m in keyed], len(times)


# ============================================================================ sensor-level faults
def freeze_axis(dtheta, t_s, t0, t1, axis, lsb):
    """dtheta with one axis's increment held at its value at t0 (rounded to the CAN LSB:
    a stuck sensor repeats one output word) for t0 <= t < t1."""
    out = np.array(dtheta, copy=True)
    sel = (t_s >= t0) & (t_s < t1)
    k0 = int(np.nonzero(sel)[0][0])
    out[sel, axis] = round(out[k0, axis] / lsb) * lsb
    return out


def clip_increments(x, limit, axes=(0, 1, 2)):
    out = np.array(x, copy=True)
    for a in axes:
        out[:, a] = np.clip(out[:, a], -limit, limit)
    return out


# ============================================================================ recovery
def _after(t, err, band, t_end):
    """(times from t_end on, whether err is within band there, the indices where not)."""
    t, err, band = (np.asarray(x, dtype=float) for x in (t, err, band))
    sel = t >= t_end
    ok = (err <= band)[sel]
    return t[sel], ok, np.nonzero(~ok)[0]


def recovery_time(t, err, band, t_end, hold_s: float = RECOVERY_HOLD_S):
    """Seconds from t_end until err stays <= band for hold_s: 0.0 if it does from the
    first sample at or after t_end, None if it never does (including when the series
    ends less than hold_s after the last return into the band)."""
    t, ok, bad = _after(t, err, band, t_end)
    if t.size == 0:
        return None
    limit = np.full(t.size, t[-1])           # in the band from here until ...
    if bad.size:
        nxt = np.searchsorted(bad, np.arange(t.size))   # the first bad sample at or after
        has = nxt < bad.size
        limit[has] = t[bad[nxt[has]]]
    good = ok & (limit - t >= hold_s - 1e-9)
    if not good.any():
        return None
    i = int(np.argmax(good))
    return 0.0 if i == 0 else float(t[i] - t_end)


def settled_time(t, err, band, t_end, hold_s: float = RECOVERY_HOLD_S):
    """Seconds from t_end until err is within band for good (to the end of the series, at
    least hold_s of it): 0.0 if it never leaves the band after t_end, None if it is out of
    the band within hold_s of the end."""
    t, ok, bad = _after(t, err, band, t_end)
    if t.size == 0:
        return None
    if bad.size == 0:
        return 0.0 if t[-1] - t[0] >= hold_s - 1e-9 else None
    i = int(bad[-1]) + 1
    if i >= t.size or t[-1] - t[i] < hold_s - 1e-9:
        return None
    return float(t[i] - t_end)


def recovery_text(first, settled) -> str:
    """The table's recovery cell: the first return into the band, and when the error left
    it again later, when it settled for good."""
    if first is None:
        return "none"
    s = "0 s" if first == 0.0 else f"{first:.1f} s"
    if settled != first:
        s += (f" (out again later; for good after {settled:.0f} s)" if settled is not None
              else " (out again later, to the end)")
    return s


def band_m(t, t_clean, err_clean):
    return np.maximum(RECOVERY_FLOOR_M,
                      RECOVERY_FACTOR * np.interp(t, t_clean, err_clean))


# ============================================================================ rows
@dataclass
class Fault:
    name: str                        # the row label
    window: tuple                    # (t0, t1) s; t1 None: to the end of the drive
    build: Callable                  # drive -> (sorted list of can.Message, info dict)
    kind: str = "window"             # window | whole | boot | step
    args: list = field(default_factory=list)   # extra navecu options
    nvm_bytes: int = 0               # >0: --nvm FILE with this many random bytes

    @property
    def slug(self) -> str:
        return slugify(self.name)


def slugify(name: str) -> str:
    s = re.sub(r"[^a-z0-9]+", "-", name.lower().replace("%", "pct")).strip("-")
    return s or "row"


def _rng(drive: Drive, name: str):
    return np.random.default_rng(np.random.SeedSequence([drive.seed, zlib.crc32(name.encode())]))


def check_window(drive: Drive, t0: float, t1: float, what: str, min_speed=0.5):
    """A fault window in the middle of the drive: moving throughout, no GNSS outage within
    it or in the 10 s after, GNSS epochs in it."""
    tr = drive.truth
    sel = (tr.t_s >= t0) & (tr.t_s <= max(t1, t0))
    if not sel.any() or np.min(np.abs(tr.speed_mps[sel])) < min_speed:
        raise SystemExit(f"{what}: window {t0:g}-{t1:g} s is not all while driving")
    for (a, b, *_l) in tr.outages:
        if a <= max(t1, t0) + 10.0 and b >= t0 - 5.0:
            raise SystemExit(f"{what}: window {t0:g}-{t1:g} s meets the GNSS outage {a:g}-{b:g} s")
    g = drive.gnss["t_s"]
    if not np.any((g >= t0 - 0.5) & (g <= max(t1, t0) + 0.5)):
        raise SystemExit(f"{what}: no GNSS epoch in {t0:g}-{t1:g} s")


def _frame_fault(name, what, fn, *a, **kw):
    def build(d):
        msgs, n = fn(d.messages, *a, _rng(d, name), d.db, **kw)
        return msgs, {"count": n, "injected": f"{n} {what}", "frames_in": len(msgs)}
    return build


def faults(drive: Drive) -> list:
    """The rows, in table order, with their windows checked against the drive."""
    d = drive
    tr = d.truth
    dt = 1.0 / d.imu_rate_hz
    end = float(tr.t_s[-1])
    rows = []
    for p in (1, 5, 20):
        rows.append(Fault(f"frame loss {p} %", (0.0, end), _frame_fault(
            f"frame loss {p} %", "frames dropped", drop_frames, p / 100.0), kind="whole"))
    rows.append(Fault("duplicated frames 2 %", (0.0, end), _frame_fault(
        "duplicated frames 2 %", "frames sent twice", duplicate_frames, 0.02), kind="whole"))
    rows.append(Fault("reordered frames 2 %", (0.0, end), _frame_fault(
        "reordered frames 2 %", "adjacent pairs swapped", reorder_frames, 0.02),
        kind="whole"))
    rows.append(Fault("bad CRCs 1 %", (0.0, end), _frame_fault(
        "bad CRCs 1 %", "CRC bytes inverted", flip_crcs, 0.01), kind="whole"))
    rows.append(Fault("bad counters 1 %", (0.0, end), _frame_fault(
        "bad counters 1 %", "counters changed (frames or IMU samples)", change_counters, 0.01),
        kind="whole"))

    # the z gyro stuck through the first roundabout (heading -90 deg net, 210 deg turned)
    w_stuck = (286.0, 306.0)
    check_window(d, *w_stuck, "stuck gyro axis")
    sel = (tr.t_s >= w_stuck[0]) & (tr.t_s < w_stuck[1])
    turned = float(np.degrees(np.sum(np.abs(np.diff(np.unwrap(tr.heading_rad[sel]))))))
    if turned < 90.0:
        raise SystemExit(f"stuck gyro axis: only {turned:.0f} deg of turning in {w_stuck}")

    def stuck(d):
        th = freeze_axis(d.dtheta, d.truth.t_s, *w_stuck, 2, nc.ANGLE_LSB_RAD)
        msgs, n = d.imu_encoder.frames(d, th, d.dv)
        return [m for _, _, m in msgs], {"injected": f"z held 20 s ({turned:.0f} deg turned)",
                                         "samples_changed": n, "turned_deg": round(turned, 1),
                                         "frozen_rate_dps": float(np.degrees(
                                             th[np.argmax(sel), 2]) / dt)}
    rows.append(Fault("stuck gyro axis", w_stuck, stuck))

    # the same z gyro stuck for good: through the tunnel (625-715 s, 1,980 m without GNSS)
    # only the car's own turn (app.c stuck_yaw) holds the heading
    def stuck_for_good(d):
        th = freeze_axis(d.dtheta, d.truth.t_s, w_stuck[0], math.inf, 2, nc.ANGLE_LSB_RAD)
        msgs, n = d.imu_encoder.frames(d, th, d.dv)
        return [m for _, _, m in msgs], {"injected": "z held to the drive's end (the tunnel "
                                                     "included)", "samples_changed": n}
    rows.append(Fault("z gyro stuck for good", (w_stuck[0], None), stuck_for_good))

    # A gyro of +-15 deg/s and an accelerometer of +-1.01 g on every axis (an IMU with too
    # small a range for the car): the gyro clips in turns, the accelerometer's z axis,
    # which carries gravity, clips on every crest and bump that pushes up by more than
    # 0.1 m/s^2. The firmware is told the ranges, as an ECU is configured for its IMU.
    gyro_dps, acc_mps2 = 15.0, 9.9
    peak_w = float(np.degrees(np.max(np.abs(d.dtheta[1:]))) / dt)
    peak_a = float(np.max(np.abs(d.dv[1:])) / dt)
    if not (peak_w > gyro_dps and peak_a > acc_mps2):
        raise SystemExit(f"saturation: the drive's peaks ({peak_w:.1f} deg/s, {peak_a:.2f} "
                         f"m/s^2) are not above the ranges {gyro_dps}, {acc_mps2}")

    def gyro_sat(d):
        th = clip_increments(d.dtheta, math.radians(gyro_dps) * dt)
        msgs, n = d.imu_encoder.frames(d, th, d.dv)
        clipped = int(np.sum(np.any(np.abs(d.dtheta[1:]) > math.radians(gyro_dps) * dt, 1)))
        return [m for _, _, m in msgs], {"injected": f"{clipped} IMU samples clipped at "
                                                     f"{gyro_dps:g} deg/s",
                                         "samples_clipped": clipped, "range_dps": gyro_dps,
                                         "drive_peak_dps": round(peak_w, 2)}

    def acc_sat(d):
        v = clip_increments(d.dv, acc_mps2 * dt, axes=(0, 1, 2))
        msgs, n = d.imu_encoder.frames(d, d.dtheta, v)
        clipped = int(np.sum(np.any(np.abs(d.dv[1:]) > acc_mps2 * dt, 1)))
        return [m for _, _, m in msgs], {"injected": f"{clipped} IMU samples clipped at "
                                                     f"{acc_mps2:g} m/s^2 (every axis)",
                                         "samples_clipped": clipped, "range_mps2": acc_mps2,
                                         "drive_peak_mps2": round(peak_a, 2)}
    rows.append(Fault("gyro saturation", (0.0, end), gyro_sat, kind="whole",
                      args=["--gyro-range-dps", f"{gyro_dps:g}"]))
    rows.append(Fault("accel saturation", (0.0, end), acc_sat, kind="whole",
                      args=["--accel-range-mps2", f"{acc_mps2:g}"]))

    w_jump = (850.0, 855.0)
    check_window(d, *w_jump, "GNSS jump")
    for metres, label in ((100.0, "100 m"), (1000.0, "1 km")):
        def jump(d, metres=metres):
            g, flog = sensors.apply_gnss_faults(d.gnss, {"jumps": [{
                "t_s": w_jump[0], "metres": metres, "azimuth_deg": 90.0,
                "duration_s": w_jump[1] - w_jump[0]}]})
            return [m for _, _, m in reencode(d, gnss=g)], {
                "injected": f"{flog[0]['epochs']} GNSS epochs moved {metres:g} m east",
                "epochs": flog[0]["epochs"], "metres": metres, "azimuth_deg": 90.0}
        rows.append(Fault(f"GNSS jump {label}", w_jump, jump))

    t_tow = 900.0
    check_window(d, t_tow, t_tow, "GNSS time jump")

    def tow_jump(d):
        g = {k: np.array(v, copy=True) for k, v in d.gnss.items()}
        sel = g["t_s"] >= t_tow - 1e-9
        g["t_meas_s"][sel] += 10.0
        return [m for _, _, m in reencode(d, gnss=g)], {
            "injected": f"TimeOfWeek +10 s on {int(sel.sum())} GNSS epochs",
            "epochs": int(sel.sum()), "tow_offset_s": 10.0}
    rows.append(Fault("GNSS time jump", (t_tow, t_tow), tow_jump, kind="step"))

    w_lock = (343.5, 345.0)      # braking from 12 m/s to the red light
    check_window(d, *w_lock, "wheel lock", min_speed=8.0)
    w_spin = (378.0, 380.0)      # pulling away from it, 0 -> 14 m/s
    check_window(d, *w_spin, "wheel spin", min_speed=4.0)
    for name, w, scale in (("wheel lock under braking", w_lock, 0.0),
                           ("wheel spin", w_spin, 1.3)):
        def wheel(d, w=w, scale=scale):
            tw, v = d.wheels
            v = np.array(v, copy=True)
            sel = (tw >= w[0]) & (tw < w[1])
            v[sel] = v[sel] * scale + 0.0
            return [m for _, _, m in reencode(d, wheels=(tw, v))], {
                "injected": (f"{int(sel.sum())} WheelSpeeds frames "
                             + ("at 0" if scale == 0.0 else f"x {scale:g}")),
                "frames_changed": int(sel.sum()), "scale": scale}
        rows.append(Fault(name, w, wheel))

    for secs in (1.0, 10.0):
        w = (480.0, 480.0 + secs)
        check_window(d, *w, f"IMU silent {secs:g} s")

        def silent(d, w=w):
            msgs, n = drop_imu(d.messages, *w, d.db)
            return msgs, {"injected": f"{n} IMU samples removed", "samples_removed": n}
        rows.append(Fault(f"IMU silent {secs:g} s", w, silent))

    def jitter(d):
        msgs, n = jitter_imu(d.messages, 0.3, dt, _rng(d, "IMU rate jitter"), d.db)
        return msgs, {"injected": f"{n} IMU samples moved by up to +-30 % of 10 ms",
                      "samples_jittered": n, "jitter_frac_of_period": 0.3}
    rows.append(Fault("IMU rate jitter", (0.0, end), jitter, kind="whole"))

    rows.append(Fault("corrupt NVM at boot", (0.0, 0.0), lambda d: (d.messages, {
        "injected": "--nvm: 4096 random bytes"}),
                      kind="boot", nvm_bytes=4096))
    return rows


# ============================================================================ running
def navecu_options(navecu: str) -> str:
    try:
        return subprocess.run([navecu, "--help"], capture_output=True, text=True,
                              timeout=30).stdout
    except OSError:
        return ""


def _decoded_finite(nav: dict, cnt_pages: dict) -> bool:
    for name, cols in nav.items():
        if name == "NAV_Status":
            page = cols.get("StatusPage")
            for sig, p in cnt_pages.items():
                if sig in cols and not np.all(np.isfinite(cols[sig][page == p])):
                    return False
            for sig in ("Mode", "HealthFlags", "HorizAccuracy"):
                if sig in cols and not np.all(np.isfinite(cols[sig][page == 0])):
                    return False
            continue
        for k, v in cols.items():
            if k != "t_s" and not np.all(np.isfinite(v)):
                return False
    return True


def evaluate(drive: Drive, msgs: list, out_dir: Path, cmd_tail: list, navecu: str,
             nvm: Optional[Path] = None) -> dict:
    """Write the log, run the firmware, decode its output: the raw material of a row."""
    out_dir.mkdir(parents=True, exist_ok=True)
    can_in, nav_log = out_dir / "can_in.log", out_dir / "nav.log"
    nc.write_candump(can_in, msgs)
    cmd = [navecu, "--can-log", str(can_in), "--out", str(nav_log), "--imu-rate-hz",
           str(drive.imu_rate_hz)] + drive.fw_args + cmd_tail
    if nvm is not None:
        cmd += ["--nvm", str(nvm)]
    t = time.monotonic()
    try:
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
        rc, err = res.returncode, res.stderr
    except subprocess.TimeoutExpired as e:
        rc, err = "timeout", (e.stderr or b"").decode(errors="replace") if isinstance(
            e.stderr, bytes) else (e.stderr or "")
    fw_s = time.monotonic() - t
    (out_dir / "navecu.txt").write_text(err)
    r = {"exit_status": rc, "stderr": err, "command": cmd, "firmware_s": fw_s,
         "frames_in": len(msgs)}
    m = re.search(r"non-finite outputs?\s*[:=]?\s*(\d+)", err)
    r["nonfinite_outputs"] = int(m.group(1)) if m else None
    if not nav_log.exists() or nav_log.stat().st_size == 0:
        r.update({"navigating": False, "t": np.zeros(0), "herr": np.zeros(0), "status": None,
                  "cal": None, "decoded_finite": True})
        return r
    t = time.monotonic()
    nav = report.read_nav_log(nav_log, wraps_from_log=True)  # the log's time is the IMU time
    tr = drive.truth
    truth_r = {"t_s": tr.t_s, "lat_rad": tr.lat_rad, "lon_rad": tr.lon_rad,
               "heading_rad": tr.heading_rad, "dist_m": tr.dist_m}
    rep, series = report.compute(truth_r, nav, tr.outages)
    cnt = status_signals(drive.db)
    st = nav.get("NAV_Status")
    keep = ["t_s", "StatusPage", "Mode", "HealthFlags"] + list(cnt)
    r.update({"navigating": bool(rep.get("navigating")),
              "t": series.get("t", np.zeros(0)), "herr": series.get("herr", np.zeros(0)),
              "status": {k: st[k] for k in keep if st is not None and k in st},
              "decoded_finite": _decoded_finite(nav, cnt),
              "within_2sigma": rep["sigma_consistency"].get("frac_within_2sigma"),
              "error_over_sigma": rep["sigma_consistency"].get("median_error_over_sigma"),
              "outages": _outage_claims(rep["outages"], st, series.get("heading"))})
    cal = report.read_calibration_log(nav_log)
    r["cal"] = {"t_s": cal["t_s"], "CalStatus": cal["CalStatus"]}
    r["decode_s"] = time.monotonic() - t
    return r


def _outage_claims(outages: list, status, heading=None) -> list:
    """report.compute's GNSS outages, each with the HorizAccuracy in force at its end (m;
    the latest page-0 value at most report.SIGMA_MAX_AGE_S old, None if none or 655.35
    "unknown", as report.sigma_consistency takes it) and the heading error there (deg;
    heading: report.compute's (t, error deg) series)."""
    t_h, h = report.status_page(status, 0, "HorizAccuracy")
    out = []
    for o in outages:
        o = dict(o)
        acc = float(report.latest_at(t_h, h, [o["end_s"]], report.SIGMA_MAX_AGE_S)[0])
        o["end_horiz_accuracy_m"] = (acc if np.isfinite(acc)
                                     and acc < report.HORIZ_ACCURACY_UNKNOWN_M else None)
        hd = np.nan
        if heading is not None and len(heading[0]):
            hd = float(report.latest_at(heading[0], heading[1], [o["end_s"]])[0])
        o["end_heading_error_deg"] = hd if np.isfinite(hd) else None
        out.append(o)
    return out


def _child(conn, fn, args):
    try:
        conn.send(("ok", fn(*args)))
    except BaseException:
        conn.send(("error", traceback.format_exc()))
    finally:
        conn.close()


class Runner:
    """Up to `jobs` rows at a time in forked processes (the frame lists are inherited, not
    pickled); results by key."""

    def __init__(self, jobs: int):
        self.jobs = max(1, jobs)
        self.ctx = mp.get_context("fork")
        self.running = {}       # conn -> (key, process)
        self.results = {}

    def submit(self, key, fn, *args):
        while len(self.running) >= self.jobs:
            self._reap()
        recv, send = self.ctx.Pipe(duplex=False)
        p = self.ctx.Process(target=_child, args=(send, fn, args), daemon=True)
        p.start()
        send.close()
        self.running[recv] = (key, p)

    def _reap(self):
        for conn in mp_wait(list(self.running)):
            key, p = self.running.pop(conn)
            try:
                status, value = conn.recv()
            except EOFError:
                status, value = "error", f"worker for {key} died (exit code {p.exitcode})"
            p.join()
            self.results[key] = value if status == "ok" else {"worker_error": value}

    def finish(self) -> dict:
        while self.running:
            self._reap()
        return self.results


# ============================================================================ comparison
STATUS_SLACK_S = 1.0   # NAV_Status rows carry the time of the last NAV set: during an IMU
                       # gap it stands still at the gap's start


def _flags_seen(status, t0: float) -> int:
    if not status or "HealthFlags" not in status:
        return 0
    t, page, f = status["t_s"], status["StatusPage"], status["HealthFlags"]
    sel = (page == 0) & np.isfinite(f)
    if t0 > 0:
        sel &= np.isfinite(t) & (t >= t0 - STATUS_SLACK_S)
    bits = 0
    for v in np.unique(f[sel]):
        bits |= int(v)
    return bits


def _modes_seen(status, t0: float) -> set:
    if not status or "Mode" not in status:
        return set()
    t, page, mo = status["t_s"], status["StatusPage"], status["Mode"]
    sel = (page == 0) & np.isfinite(mo)
    if t0 > 0:
        sel &= np.isfinite(t) & (t >= t0 - STATUS_SLACK_S)
    return {int(v) for v in np.unique(mo[sel])}


def _last_counters(status, cnt_pages: dict) -> dict:
    out = {}
    if not status:
        return out
    for sig, p in cnt_pages.items():
        if sig not in status:
            continue
        v = status[sig][(status["StatusPage"] == p) & np.isfinite(status[sig])]
        if v.size:
            out[sig] = int(v[-1])
    return out


def detection(db, row: dict, clean: dict, t0: float, bits: dict) -> dict:
    """What the firmware showed of the fault that the clean run never showed."""
    cnt_pages = status_signals(db)
    new_bits = _flags_seen(row.get("status"), t0) & ~_flags_seen(clean.get("status"), 0.0)
    flags = [bits.get(b, (f"BIT{b}", ""))[0] for b in range(16) if new_bits >> b & 1]
    c_row, c_clean = _last_counters(row.get("status"), cnt_pages), _last_counters(
        clean.get("status"), cnt_pages)
    counters = {k: v - c_clean.get(k, 0) for k, v in c_row.items() if v > c_clean.get(k, 0)}
    top = counter_max(db)
    saturated = [k for k in counters if c_row[k] >= top.get(k, math.inf)]
    mode_names = nc.choices(db, "NAV_Status", "Mode")
    modes = sorted(_modes_seen(row.get("status"), t0) - _modes_seen(clean.get("status"), 0.0))
    cal_names = nc.choices(db, "NAV_Calibration", "CalStatus")

    def cal_set(r):
        c = r.get("cal") or {}
        v = np.asarray(c.get("CalStatus", ()), dtype=float)
        return {int(x) for x in np.unique(v[np.isfinite(v)])}
    cal = sorted(cal_set(row) - cal_set(clean))
    parts = [f"{k} +{v}" + (" (saturated)" if k in saturated else "")
             for k, v in counters.items()]
    if flags:
        parts.append("HealthFlags " + " ".join(flags))
    if modes:
        parts.append("Mode " + " ".join(mode_names.get(m, str(m)) for m in modes))
    if cal:
        parts.append("CalStatus " + " ".join(cal_names.get(c, str(c)) for c in cal))
    return {"health_flags": flags, "counters": counters, "counters_saturated": saturated,
            "modes": [mode_names.get(m, str(m)) for m in modes],
            "cal_status": [cal_names.get(c, str(c)) for c in cal],
            "text": ", ".join(parts) if parts else "not detected"}


def _fmt_window(f: Fault) -> str:
    if f.kind == "whole":
        return "whole drive"
    if f.kind == "boot":
        return "at boot"
    if f.kind == "step":
        return f"from {f.window[0]:g} on"
    if f.window[1] is None:
        return f"{f.window[0]:g} to the end"
    return f"{f.window[0]:g}-{f.window[1]:g}"


def _rms(x):
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else None


def summarize(drive: Drive, f: Optional[Fault], raw: dict, clean: dict, bits: dict,
              info: dict, note: str = "") -> dict:
    name = f.name if f else "clean"
    row = {"name": name, "slug": f.slug if f else "clean",
           "window_s": list(f.window) if f else None,
           "window": _fmt_window(f) if f else "-", "kind": f.kind if f else "clean",
           "injected": info, "navecu_args": (f.args if f else []), "note": note}
    if "worker_error" in raw:
        row.update({"error": raw["worker_error"], "exit_status": "tool error",
                    "detected": {"text": "-"}, "nonfinite_outputs": None,
                    "decoded_finite": None, "rms_m": None, "max_m": None,
                    "rms_ratio": None, "recovery_s": None, "recovery": "-"})
        return row
    t, herr = raw["t"], raw["herr"]
    rms, mx = _rms(herr), (float(np.max(herr)) if len(herr) else None)
    c_rms = _rms(clean["herr"])
    row.update({"exit_status": raw["exit_status"], "navigating": raw["navigating"],
                "nonfinite_outputs": raw["nonfinite_outputs"],
                "decoded_finite": raw["decoded_finite"], "rms_m": rms, "max_m": mx,
                "rms_ratio": (rms / c_rms) if rms is not None and c_rms else None,
                "within_2sigma": raw.get("within_2sigma"),
                "error_over_sigma": raw.get("error_over_sigma"),
                "outages": raw.get("outages"),
                "firmware_s": raw["firmware_s"], "decode_s": raw.get("decode_s"),
                "frames_in": raw["frames_in"],
                "navecu_summary": raw["stderr"].strip().splitlines()})
    if f is None:
        row.update({"detected": {"text": "-"}, "recovery_s": None, "recovery": "-"})
        return row
    row["detected"] = detection(drive.db, raw, clean, f.window[0], bits)
    if f.kind == "whole" or (f.kind == "window" and f.window[1] is None):
        row.update({"recovery_s": None, "recovery": "n/a"})
    elif not len(t):
        row.update({"recovery_s": None, "recovery": "none"})
    else:
        t_end = f.window[1] if f.window[1] is not None else f.window[0]
        band = band_m(t, clean["t"], clean["herr"])
        rec = recovery_time(t, herr, band, t_end)
        settled = settled_time(t, herr, band, t_end)
        row.update({"recovery_s": rec, "settled_s": settled,
                    "recovery": recovery_text(rec, settled)})
    return row


def problems(rows: list) -> list:
    out = []
    clean = next((r for r in rows if r["name"] == "clean"), None)
    for r in rows:
        if r.get("error"):
            out.append(f"{r['name']}: the tool failed on this row:\n{r['error']}")
            continue
        if r["exit_status"] != 0:
            out.append(f"{r['name']}: navecu exit status {r['exit_status']} "
                       f"({'; '.join(r.get('navecu_summary', [])[-2:])})")
        if r["nonfinite_outputs"]:
            out.append(f"{r['name']}: the firmware caught {r['nonfinite_outputs']} non-finite "
                       "outputs")
        if r["decoded_finite"] is False:
            out.append(f"{r['name']}: nav.log holds a non-finite value")
        if r["name"] in ("frame loss 1 %", "frame loss 5 %") and clean is not None:
            if r["rms_m"] is None or clean["rms_m"] is None or \
                    r["rms_m"] > LOSS_RMS_LIMIT * clean["rms_m"]:
                out.append(f"{r['name']}: RMS {r['rms_m']} m above {LOSS_RMS_LIMIT} x the clean "
                           f"run's {clean['rms_m']} m (issue #9 floor)")
    return out


def _f(x, nd=2, unit=""):
    return "-" if x is None else f"{x:.{nd}f}{unit}"


def _nonfinite_cell(r) -> str:
    if r.get("error"):
        return "-"
    fw = "n/a" if r["nonfinite_outputs"] is None else str(r["nonfinite_outputs"])
    return fw + ("" if r["decoded_finite"] else ", NaN in nav.log")


def _injected_text(r) -> str:
    return (r.get("injected") or {}).get("injected", "-")


def _pct(x) -> str:
    return "-" if x is None else f"{100.0 * x:.1f} %"


def markdown_table(rows: list) -> str:
    head = ("| fault | window (s) | injected | navecu exit | how detected | non-finite | "
            "RMS (m) | max (m) | RMS / clean | within 2σ | error / σ | recovery |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    lines = []
    for r in rows:
        det = r["detected"]["text"] if isinstance(r.get("detected"), dict) else "-"
        if r.get("note"):
            det += f" ({r['note']})"
        lines.append(
            f"| {r['name']} | {r['window']} | {_injected_text(r)} | {r['exit_status']} | "
            f"{det} | {_nonfinite_cell(r)} | {_f(r.get('rms_m'))} | {_f(r.get('max_m'))} | "
            f"{_f(r.get('rms_ratio'))} | {_pct(r.get('within_2sigma'))} | "
            f"{_f(r.get('error_over_sigma'))} | {r.get('recovery', '-')} |")
    return head + "\n".join(lines) + "\n"


INTRO = """# Reliability

## Fault drives (`make faults`)

`make faults` (`python -m tools.sim.faults --doc docs/reliability.md`, about 5 minutes)
re-runs the simulator's default drive (`tools/sim/scenarios/default.toml`: 22 min, mid-grade
IMU, standalone GNSS, seed 1, the firmware options of `make sim`) once clean and once per
fault below, runs `build/host/navecu` on each, and writes `out/faults/<row>/` (`can_in.log`,
`nav.log`, `navecu.txt`), `out/faults/faults.json` (windows, counts, every number) and the
table between the markers. Frame-level faults (loss, duplicates, reordering, bad CRCs and
counters, IMU silence and timing jitter) transform the clean frame list, seeded; the
driver's initialization commands at t = 0 are left alone. Sensor-level faults (a stuck or
saturating gyro, a saturating accelerometer, GNSS position and time jumps, locked and
spinning wheels) change the sensor data before its encoding. Windows are in the middle of
the drive, while driving, with GNSS. Columns:

- **how detected**: the NAV_Status HealthFlags bits set at any time from the fault's start
  on but never in the clean run, Mode and NAV_Calibration CalStatus values the clean run
  never showed, and each Cnt* counter of NAV_Status whose last value is above the clean
  run's (the difference); "not detected" if nothing differs;
- **non-finite**: the firmware's own count of non-finite outputs it held back (stderr
  `non-finite outputs N`; "n/a" if it does not print one); ", NaN in nav.log" if a decoded
  NAV_* value is not finite;
- **RMS, max**: horizontal error against the truth over the whole drive (every
  NAV_Position); **RMS / clean**: against the clean run's RMS;
- **within 2σ**: the share of the epochs with a known HorizAccuracy (NAV_Status page 0,
  at most 1 s old, not 655.35 "unknown") whose error is at most twice it: whether the
  claim holds; **error / σ**: their median error over it, how much it claims beyond the
  error (tools/sim/report.py `sigma_consistency`);
- **recovery**: from the end of the fault window until the horizontal error stays within
  max(1 m, 1.5 x the clean run's error at the same instant) for 10 s; "0 s": it was in that
  band from the window's end; "none": never again; "n/a": the fault lasts to the drive's
  end.
  When the error leaves the band again after that first return, the cell adds when it was
  back in the band for good (to the end of the drive).

The command fails if navecu exits with a status other than 0, if an output is non-finite,
or if 1 % or 5 % frame loss raises the RMS above 1.5 x the clean run's. Rerun with
`make faults`, or a few rows with `python -m tools.sim.faults --only "wheel spin"`.

"""


def write_doc(path: Path, block: str) -> None:
    gen = f"{BEGIN}\n{block.rstrip()}\n{END}"
    if path.exists():
        text = path.read_text()
        if BEGIN in text and END in text.split(BEGIN, 1)[1]:
            pre, rest = text.split(BEGIN, 1)
            post = rest.split(END, 1)[1]
            text = pre + gen + post
        else:
            text = text.rstrip() + "\n\n" + gen + "\n"
    else:
        text = INTRO + gen + "\n"
    path.write_text(text)


def _jsonable(x):
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(ROOT / "out" / "faults"))
    ap.add_argument("--only", nargs="+", default=None, metavar="NAME",
                    help="run only these rows (label or folder name; the clean run always)")
    ap.add_argument("--doc", default=None, help="write the table into this Markdown file")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--navecu", default=str(ROOT / "build" / "host" / "navecu"))
    a = ap.parse_args(argv)
    t_start = time.monotonic()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if not Path(a.navecu).exists():
        raise SystemExit(f"no firmware at {a.navecu} (make)")

    print("clean drive (tools/sim/run.py's default drive):", flush=True)
    drive = build_drive("default", a.seed)
    rows = faults(drive)
    if a.only:
        want = {w.lower() for w in a.only}
        unknown = want - {f.name.lower() for f in rows} - {f.slug for f in rows}
        if unknown:
            raise SystemExit(f"no row {', '.join(sorted(unknown))} (rows: "
                             + ", ".join(f.name for f in rows) + ")")
        rows = [f for f in rows if f.name.lower() in want or f.slug in want]
    help_text = navecu_options(a.navecu)
    bits = health_bits(drive.db)

    runner = Runner(a.jobs)
    runner.submit("clean", evaluate, drive, drive.messages, out / "clean", [], a.navecu)
    infos, notes = {}, {}
    for f in rows:
        t = time.monotonic()
        msgs, info = f.build(drive)
        infos[f.name] = info
        args = []
        for opt, val in zip(f.args[::2], f.args[1::2]):
            if opt in help_text:
                args += [opt, val]
            else:
                notes[f.name] = (f"navecu has no {opt} option: run without it, the firmware "
                                 "not told the range")
                print(f"ERROR: row '{f.name}': {notes[f.name]}", file=sys.stderr, flush=True)
        nvm = None
        if f.nvm_bytes:
            (out / f.slug).mkdir(parents=True, exist_ok=True)
            nvm = out / f.slug / "nvm.bin"
            nvm.write_bytes(_rng(drive, f.name).integers(0, 256, f.nvm_bytes,
                                                         dtype=np.uint8).tobytes())
        print(f"  {f.name}: {info.get('injected')} ({time.monotonic() - t:.1f} s)", flush=True)
        runner.submit(f.name, evaluate, drive, msgs, out / f.slug, args, a.navecu, nvm)
        del msgs
    raw = runner.finish()

    clean_raw = raw["clean"]
    if "worker_error" in clean_raw:
        print(f"the clean run failed:\n{clean_raw['worker_error']}", file=sys.stderr)
        return 1
    table = [summarize(drive, None, clean_raw, clean_raw, bits, {})]
    for f in rows:
        table.append(summarize(drive, f, raw[f.name], clean_raw, bits, infos.get(f.name, {}),
                               notes.get(f.name, "")))
    elapsed = time.monotonic() - t_start
    md = markdown_table(table)
    c = table[0]
    block = (f"Generated by `make faults`: default drive, seed {a.seed}, clean run RMS "
             f"{_f(c['rms_m'])} m, max {_f(c['max_m'])} m.\n\n" + md)
    fails = problems(table)
    (out / "faults.json").write_text(json.dumps(_jsonable({
        "scenario": drive.scenario, "imu": drive.imu_name, "gnss": drive.gnss_name,
        "seed": a.seed, "runtime_s": round(elapsed, 1), "navecu_args": drive.fw_args,
        "navecu_binary": report.navecu_binary(a.navecu),
        "health_bits": {str(b): list(v) for b, v in bits.items()},
        "recovery": {"hold_s": RECOVERY_HOLD_S, "floor_m": RECOVERY_FLOOR_M,
                     "factor": RECOVERY_FACTOR},
        "rows": table, "failures": fails}), indent=2))
    print()
    print(md)
    for n, msg in notes.items():
        print(f"ERROR: row '{n}': {msg}")
    if a.doc:
        if a.only:
            print(f"--only: {a.doc} not updated (it holds the whole table)")
        else:
            write_doc(Path(a.doc), block)
            print(f"table written into {a.doc}")
    print(f"{out / 'faults.json'}; {len(table)} runs in {elapsed:.0f} s")
    if fails:
        print("FAILED:\n  " + "\n  ".join(fails), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
