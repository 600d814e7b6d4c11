"""Build the committed inputs of the replay regression (docs/regression.md).

    python -m tools.regression_inputs [--out tests/regression] [--navecu build/host/navecu]

Writes tests/regression/inputs/<case>.log.xz (candump logs, xz-compressed), the NVM images
two cases boot from, and tests/regression/cases.json (per case: what it exercises, its
input, its navecu options, its NVM). Run it only to add or change a case, then
`make regression-update` and commit all of tests/regression/ together. The regression
itself (tools/regression.py, `make regression`) replays the committed logs and never runs
the simulator or the converter, so a change of their numerics does not move it.

The simulated cases start from tools/sim/scenarios/regress.toml (4.6 min, 1.7 km), built
exactly as `make sim SCENARIO=regress` builds it (tools/sim/faults.py build_drive: mid-grade
IMU, standalone GNSS, seed 1, tools/sim/run.py firmware_args):

- sim-clean: the drive as it is: levelling, the filter from the first fix on, the outage
  at 112-140 s (dead reckoning), the red light (standstill), S-bends, reversing;
- sim-options: the same log with other options: output rates, a 20 s levelling, the front
  axle as the odometer with its lever arm, a GNSS lever arm, and IMU ranges the drive
  exceeds (saturation counted and flagged);
- sim-watchdog: the same log with a stuck task from 100 s on (--test-stall-poll-s): the
  emulated watchdog expires, exit status 3;
- sim-dgnss: the first 180 s of tools/sim/scenarios/regress-dgnss.toml, the drive with an automotive MEMS IMU
  (its large gyro bias in the filter's options) and differential GNSS (fixes accurate
  enough for the filter's GNSS sigma floor);
- sim-faults: the drive with faults at once (FAULTS below): a stuck gyro, locked and
  spinning wheels, GNSS jumps, a frozen fix, a latency spike and a time-of-week jump, lost
  IMU samples bridged, IMU gaps too long to bridge (re-acquired from GNSS, moving and
  standing), a gap only the receive time shows, the IMU's fault bit, random frame loss,
  duplicates, reordering, bad CRCs and counters, foreign and malformed frames and lines,
  receive time going backwards, and a corrupt NVM at boot;
- sim-commands: the drive with commands mid-drive (COMMANDS below): a one-point
  calibration refused while the filter runs, a refused store, a refused attitude, an
  unknown command, a Reset while driving (initialization again from the GNSS course and
  the next stop), SetInitialPosition while moving (levelling restarted until the car
  stops), SetInitialPosition with CMD_InitialAttitude at the last stop, EraseCalibration;
- sim-dr-calibration: the drive without GNSS (dead reckoning, seed 000), booting from an
  NVM image with a stored calibration: one-point calibrations refused (too close, no
  point), performed at a known position and at a GNSS fix, and stores.

kingston-900s: the first 900 s of the recorded Kingston drive (520 s standing, then 2.4 km
in town) converted as tools/kingston/run.py converts it (10 Hz IMU, CMD_InitialAttitude,
GNSS with the default outages every 240 s for 60 s) and run with its options.
"""
from __future__ import annotations

import argparse
import dataclasses
import lzma
import math
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import can
import numpy as np

from tools import navecu_can as nc
from tools import regression
from tools.kingston import convert
from tools.kingston import run as kingston_run
from tools.sim import faults, sensors

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "tests" / "regression"
SCENARIO = "regress"
KINGSTON_S = 900.0
DGNSS_S = 180.0      # sim-dgnss to the red light: the automotive IMU's noise compresses less
# frame order key of the commands sent mid-drive: after run.frames' (0..10) at equal times
O_CMD = 11


# ======================================================================== small helpers
def xz_bytes(data: bytes) -> bytes:
    return lzma.compress(data, preset=9 | lzma.PRESET_EXTREME)


def candump_text(msgs) -> str:
    """The candump lines nc.write_candump writes for these frames."""
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "x.log"
        nc.write_candump(p, msgs)
        return p.read_text()


def truth_at(truth, t: float) -> dict:
    """The drive's true position, height, heading, roll and pitch at time t (deg, m)."""
    def at(x):
        return float(np.interp(t, truth.t_s, x))
    lon = math.degrees(at(np.unwrap(truth.lon_rad)))
    return {"lat": math.degrees(at(truth.lat_rad)), "lon": (lon + 180.0) % 360.0 - 180.0,
            "h": at(truth.h_m), "heading": math.degrees(at(np.unwrap(truth.heading_rad))) % 360.0,
            "roll": at(truth.roll_rad), "pitch": at(truth.pitch_rad)}


def time_at_distance(truth, metres: float) -> float:
    """The first IMU instant at which the drive has covered this distance."""
    return float(truth.t_s[int(np.searchsorted(truth.dist_m, metres))])


class Commands:
    """CMD_* frames sent mid-drive, their E2E counters continuing those of run.frames'
    initialization at t = 0 (one CMD_Control, CMD_KnownPosition without E2E)."""

    def __init__(self, db, truth):
        self.sender = nc.E2ESender(db)
        self.sender.encode("CMD_Control", {"Command": 0, "HeadingValid": 0, "Heading": 0.0,
                                           "Height": 0.0})  # the one sent at t = 0
        self.truth = truth
        self.frames = []

    def add(self, t, name, signals):
        self.frames.append((t, O_CMD, self.sender.encode(name, signals, t)))

    def known_position(self, t):
        p = truth_at(self.truth, t)
        self.add(t, "CMD_KnownPosition", {"Latitude": p["lat"], "Longitude": p["lon"]})

    def control(self, t, command, heading=None):
        p = truth_at(self.truth, t)
        self.add(t, "CMD_Control", {"Command": command, "HeadingValid": int(heading is not None),
                                    "Heading": round((heading or 0.0) % 360.0, 2) % 360.0,
                                    "Height": p["h"]})

    def initial_attitude(self, t):
        p = truth_at(self.truth, t)
        self.add(t, "CMD_InitialAttitude", {"InitRoll": p["roll"], "InitPitch": p["pitch"]})


def merged(frames, extra) -> list:
    """Sorted (t, order, msg) list of both."""
    out = list(frames) + list(extra)
    out.sort(key=lambda x: (x[0], x[1]))
    return out


def without_gnss(frames) -> list:
    return [x for x in frames if x[1] not in faults.ORDER_GNSS]


def first_epoch_after(frames, t) -> list:
    """The four frames of the first GNSS epoch after t."""
    t1 = min(x[0] for x in frames if x[1] in faults.ORDER_GNSS and x[0] > t)
    return [x for x in frames if x[1] in faults.ORDER_GNSS and x[0] == t1]


def raw_frame(t, frame_id, data, extended=False) -> can.Message:
    return can.Message(timestamp=float(t), arbitration_id=frame_id, is_extended_id=extended,
                       dlc=len(data), data=bytearray(data))


# ======================================================================== the cases
def sim_drive(scenario=SCENARIO):
    return faults.build_drive(scenario, seed=1, imu_rate_hz=100, log=print)


def sim_args(drive) -> list:
    return ["--imu-rate-hz", str(drive.imu_rate_hz)] + list(drive.fw_args)


def args_text(args: list) -> str:
    """navecu options as cases.json holds them: one shell-quoted string."""
    return shlex.join(args)


# sim-faults: (what, window) - the windows are checked against the drive (check_window:
# moving, GNSS at hand, no outage within 10 s)
FAULTS = {"stuck z gyro": (88.0, 95.0),          # through the roundabout
          "wheel lock": (152.0, 153.5),           # braking for the red light
          "wheel spin": (179.0, 181.0),           # pulling away from it
          "GNSS jump 100 m": (70.0, 72.0),
          "GNSS frozen fix": (213.0, 218.0),
          "IMU silent 1 s (moving)": (190.0, 191.0),
          "IMU fault bit": (50.0, 50.5)}
STANDING_GAP = (165.0, 166.0)                    # IMU silent 1 s at the red light
LOST_3 = (76.005, 76.035)                        # 3 IMU samples: bridged
LOST_15 = (80.005, 80.155)                       # 15: the counter wraps, the time shows it
LATENCY_SPIKE = (222.0, 0.6)
TOW_JUMP = (240.0, 10.0)
RANDOM = {"loss": 0.003, "duplicates": 0.002, "reorder": 0.002, "crc": 0.002,
          "counter": 0.002}


def faulty_drive(drive) -> tuple:
    """sim-faults' frames (a candump text) and what was injected."""
    tr, db = drive.truth, drive.db
    for what, w in FAULTS.items():
        faults.check_window(drive, *w, what)
    info = {}
    th = faults.freeze_axis(drive.dtheta, tr.t_s, *FAULTS["stuck z gyro"], 2, nc.ANGLE_LSB_RAD)
    imu_frames, n = drive.imu_encoder.frames(drive, th, drive.dv)
    w0, w1 = FAULTS["stuck z gyro"]
    info["stuck z gyro"] = (f"z held {w1 - w0:g} s from {w0:g} s ({n} samples re-encoded: "
                            "the quantisation carry differs after it)")
    tw, v = drive.wheels
    v = np.array(v, copy=True)
    for what, scale in (("wheel lock", 0.0), ("wheel spin", 1.3)):
        sel = (tw >= FAULTS[what][0]) & (tw < FAULTS[what][1])
        v[sel] = v[sel] * scale + 0.0
        info[what] = f"{int(sel.sum())} WheelSpeeds frames x {scale:g}"
    j0, j1 = FAULTS["GNSS jump 100 m"]
    f0, f1 = FAULTS["GNSS frozen fix"]
    g, flog = sensors.apply_gnss_faults(drive.gnss, {
        "freeze": [{"t0_s": f0, "t1_s": f1}],
        "jumps": [{"t_s": j0, "metres": 100.0, "azimuth_deg": 90.0, "duration_s": j1 - j0}],
        "latency_spike": [{"t_s": LATENCY_SPIKE[0], "extra_s": LATENCY_SPIKE[1]}]})
    sel = g["t_s"] >= TOW_JUMP[0] - 1e-9
    g["t_meas_s"][sel] += TOW_JUMP[1]
    label = {"freeze": "GNSS frozen fix", "jump": "GNSS jump 100 m east",
             "latency_spike": f"GNSS latency spike +{LATENCY_SPIKE[1]:g} s"}
    info.update({label[e["kind"]]: f"{e['epochs']} epochs from {e['t_start_s']:g} s"
                 for e in flog})
    info["GNSS time-of-week jump"] = f"+{TOW_JUMP[1]:g} s on {int(sel.sum())} epochs"
    fr = faults.reencode(dataclasses.replace(drive, frames=imu_frames), wheels=(tw, v), gnss=g)

    # the IMU's own fault bit (IMU_Accel ImuFault), the pair CRC recomputed
    accel_def = db.get_message_by_name(nc.IMU_PAIR[1])
    fault_bit = accel_def.get_signal_by_name("ImuFault").start
    w0, w1 = FAULTS["IMU fault bit"]
    n = 0
    for i, (t, o, m) in enumerate(fr):
        if m.arbitration_id == accel_def.frame_id and w0 <= t < w1:
            d = bytearray(m.data)
            d[fault_bit // 8] |= 1 << fault_bit % 8
            d[7] = nc.imu_pair_crc(accel_def.frame_id, fr[i - 1][2].data, d)
            fr[i] = (t, o, faults.copy_msg(m, data=d))
            n += 1
    info["IMU fault bit"] = f"{n} samples"
    msgs = [m for _, _, m in fr]
    for what, w in (("IMU silent 1 s (moving)", FAULTS["IMU silent 1 s (moving)"]),
                    ("IMU silent 1 s (standing)", STANDING_GAP), ("IMU lost 3", LOST_3),
                    ("IMU lost 15", LOST_15)):
        msgs, n = faults.drop_imu(msgs, *w, db)
        info[what] = f"{n} samples removed"
    rng = np.random.default_rng(np.random.SeedSequence([1, 14]))
    for what, fn in (("loss", faults.drop_frames), ("duplicates", faults.duplicate_frames),
                     ("reorder", faults.reorder_frames), ("crc", faults.flip_crcs),
                     ("counter", faults.change_counters)):
        msgs, n = fn(msgs, RANDOM[what], rng, db)
        info[f"random {what}"] = f"{n} ({RANDOM[what] * 100:g} %)"
    # foreign, malformed and out-of-range frames, and receive time going backwards
    ids = {n: db.get_message_by_name(n).frame_id for n in
           ("WheelSpeeds", "NAV_Status", "GNSS_Position", "GNSS_Status", "GNSS_Height",
            "CMD_KnownPosition")}
    cmd = nc.E2ESender(db)
    repeated = cmd.encode("CMD_Control", {"Command": 0, "HeadingValid": 0, "Heading": 0.0,
                                          "Height": 0.0, "CmdCounter": 0}, 40.0)
    bad_crc = faults.copy_msg(repeated, timestamp=41.0)
    bad_crc.data[7] ^= 0x5A
    lat_e7 = int(95e7).to_bytes(4, "little", signed=True)
    inject = [
        (raw_frame(30.0, 0x7AB, bytes(8)), "unknown identifier"),
        (raw_frame(31.0, 0x1ABCDEF0, bytes(8), extended=True), "extended identifier"),
        (raw_frame(32.0, ids["WheelSpeeds"], bytes(6)), "WheelSpeeds with DLC 6"),
        (raw_frame(33.0, ids["NAV_Status"], bytes(8)), "our own NAV_Status echoed"),
        (repeated, "CMD_Control with a repeated counter"),
        (bad_crc, "CMD_Control with a bad CRC"),
        (raw_frame(60.05, ids["GNSS_Position"], lat_e7 + bytes(4)),
         "GNSS_Position at latitude 95 deg"),
        (raw_frame(60.06, ids["GNSS_Status"], bytes([7, 0, 0, 0, 0, 0, 0, 0])),
         "GNSS_Status with FixType 7"),
        (raw_frame(60.07, ids["GNSS_Height"], (6_000_000).to_bytes(3, "little") + bytes(5)),
         "GNSS_Height of 60 km"),
        (raw_frame(62.0, ids["CMD_KnownPosition"], lat_e7 + bytes(4)),
         "CMD_KnownPosition at latitude 95 deg"),
    ]
    times = [m.timestamp for m in msgs]
    for m, _what in sorted(inject, key=lambda x: -x[0].timestamp):  # latest first
        msgs.insert(int(np.searchsorted(times, m.timestamp, side="right")), m)
    info.update({what: f"at {m.timestamp:g} s" for m, what in inject})
    t_back = 235.0
    k = int(np.searchsorted([m.timestamp for m in msgs], t_back, side="right"))
    msgs.insert(k, raw_frame(t_back - 1.0, 0x7AC, bytes(8)))
    info["receive time 1 s backwards"] = f"at {t_back:g} s (an unknown identifier)"
    lines = candump_text(msgs).splitlines(keepends=True)
    bad_lines = ["this is not a candump line\n", "(12.5) can0 1234#00\n",
                 "(100.000000) can0 100#0011223344556677889900\n"]
    for frac, line in zip((0.1, 0.4, 0.7), bad_lines):
        lines.insert(int(frac * len(lines)), line)
    info["malformed lines"] = f"{len(bad_lines)}"
    return "".join(lines), info


COMMANDS = [  # (t_s, what)
    (50.0, "CMD_KnownPosition + CalibrateHere: refused, the filter runs"),
    (52.0, "CalibrateAtGnss: the next fix refuses it"),
    (54.0, "StoreCalibration: nothing calibrated to store"),
    (56.0, "CMD_InitialAttitude while navigating: refused"),
    (58.0, "Command 9: undefined"),
    (60.0, "Command 0: none"),
    (70.0, "Reset while driving: initialization from the GNSS course and the next stop"),
    (222.0, "SetInitialPosition while moving: levelling restarts until the car stands"),
    (263.0, "SetInitialPosition without a heading: waits for one (NO_HEADING)"),
    (264.0, "SetInitialPosition at the last stop"),
    (266.0, "CMD_InitialAttitude: levelling ends at once"),
    (270.0, "EraseCalibration"),
]


def commands_drive(drive) -> tuple:
    c = Commands(drive.db, drive.truth)
    c.known_position(50.0)
    c.control(50.0, 5)
    c.control(52.0, 6)
    c.control(54.0, 3)
    c.initial_attitude(56.0)
    c.control(58.0, 9)
    c.control(60.0, 0)
    c.control(70.0, 1)
    for ts in (222.0, 264.0):
        c.known_position(ts)
        c.control(ts, 2, heading=truth_at(drive.truth, ts)["heading"])
        if ts == 222.0:
            c.known_position(263.0)
            c.control(263.0, 2)
    c.initial_attitude(266.0)
    c.control(270.0, 4)
    return [m for _, _, m in merged(drive.frames, c.frames)], {t: w for t, w in COMMANDS}


DR_MIN_BASE_M = 300.0


def dr_calibration_drive(drive) -> tuple:
    """sim-dr-calibration's frames, what they do, and the time of the first calibration."""
    tr = drive.truth
    c = Commands(drive.db, tr)
    base = without_gnss(drive.frames)
    t_close = time_at_distance(tr, 150.0)
    t_cal1 = time_at_distance(tr, 500.0)
    t_gnss = time_at_distance(tr, 1100.0)
    plan = [(t_close, "CMD_KnownPosition + CalibrateHere 150 m from the base: too close"),
            (t_cal1, "CMD_KnownPosition + CalibrateHere at 500 m: performed, stored"),
            (t_cal1 + 1.0, "CalibrateHere without a new point: refused"),
            (t_cal1 + 3.0, "StoreCalibration 3 s after a save: refused (flash wear)"),
            (t_cal1 + 15.0, "StoreCalibration: stored"),
            (t_gnss, "CalibrateAtGnss at 1100 m and one GNSS epoch: performed")]
    for ts in (t_close, t_cal1):
        c.known_position(ts)
        c.control(ts, 5)
    c.control(t_cal1 + 1.0, 5)
    c.control(t_cal1 + 3.0, 3)
    c.control(t_cal1 + 15.0, 3)
    c.control(t_gnss, 6)
    frames = merged(base, c.frames + first_epoch_after(drive.frames, t_gnss))
    return [m for _, _, m in frames], {f"{t:.2f}": w for t, w in plan}, t_cal1


def kingston_frames():
    d = convert.load().head(KINGSTON_S)
    t_end = float(d.imu["time_s"][-1] - d.t0_gps)
    outages = convert.parse_outages("default", t_end)
    # no CalibrateHere: the slice never reaches run.py's 5 km
    frames, _meta = convert.build(d, gnss=True, outages=outages, calibrate_at_km=None)
    return [m for _, _, m in frames], outages


def nvm_after(navecu, text: str, args: list, until_s: float) -> bytes:
    """The NVM image a fresh ECU holds after the frames of this log up to until_s."""
    keep = []
    for line in text.splitlines(keepends=True):
        if float(line[1:line.index(")")]) > until_s:
            break
        keep.append(line)
    with tempfile.TemporaryDirectory() as d:
        log, nvm = Path(d) / "in.log", Path(d) / "nvm.bin"
        log.write_text("".join(keep))
        subprocess.run([navecu, "--can-log", str(log), "--out", str(Path(d) / "out.log"),
                        "--nvm", str(nvm)] + args, check=True, capture_output=True)
        return nvm.read_bytes()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(OUT))
    ap.add_argument("--navecu", default=str(ROOT / "build" / "host" / "navecu"))
    a = ap.parse_args(argv)
    out = Path(a.out)
    # built beside the committed inputs, which are replaced only when all are built (the
    # Kingston data may be missing, a case may fail)
    inputs = out / "inputs.new"
    if inputs.exists():
        shutil.rmtree(inputs)
    inputs.mkdir(parents=True)

    def write_log(name, text):
        (inputs / f"{name}.log.xz").write_bytes(xz_bytes(text.encode()))
        return f"inputs/{name}.log.xz"

    drive = sim_drive()
    args = sim_args(drive)
    cases = []
    clean = write_log("sim-clean", candump_text(drive.messages))
    cases.append({"name": "sim-clean", "input": clean, "args": args, "nvm": None,
                  "what": "tools/sim/scenarios/regress.toml as make sim runs it"})
    cases.append({"name": "sim-options", "input": clean, "nvm": None, "args": args + [
        "--nav-rate-hz", "25", "--status-rate-hz", "20", "--level-s", "20",
        "--odo-axle", "front", "--odo-lever-m", "0,2.7,0", "--gnss-lever-m", "0.1,0.5,1.2",
        "--gyro-range-dps", "20", "--accel-range-mps2", "9.9"],
        "what": "sim-clean's log with other output rates, levelling time, odometer axle, "
                "lever arms and IMU ranges the drive exceeds"})
    cases.append({"name": "sim-watchdog", "input": clean, "nvm": None,
                  "args": args + ["--test-stall-poll-s", "100"],
                  "what": "sim-clean's log with app_poll stopped at 100 s: the watchdog "
                          "expires, exit status 3"})

    dgnss = sim_drive(SCENARIO + "-dgnss")
    cases.append({"name": "sim-dgnss", "nvm": None, "args": sim_args(dgnss),
                  "input": write_log("sim-dgnss", candump_text(
                      m for m in dgnss.messages if m.timestamp <= DGNSS_S)),
                  "what": f"the first {DGNSS_S:g} s of tools/sim/scenarios/regress-dgnss.toml "
                          "as make sim runs it: the regress drive with an automotive IMU and "
                          "differential GNSS"})

    text, info = faulty_drive(drive)
    rng = np.random.default_rng(np.random.SeedSequence([1, 4096]))
    (inputs / "corrupt.nvm").write_bytes(rng.integers(0, 256, 4096, dtype=np.uint8).tobytes())
    cases.append({"name": "sim-faults", "input": write_log("sim-faults", text), "args": args,
                  "nvm": "inputs/corrupt.nvm",
                  "what": "the regress drive with many faults at once, a corrupt NVM at boot",
                  "injected": info})

    msgs, info = commands_drive(drive)
    cases.append({"name": "sim-commands", "input": write_log("sim-commands", candump_text(msgs)),
                  "args": args + ["--level-s", "10"], "nvm": "fresh",
                  "what": "the regress drive with commands mid-drive", "commands": {
                      f"{t:g}": w for t, w in info.items()}})

    msgs, plan, t_cal1 = dr_calibration_drive(drive)
    text = candump_text(msgs)
    dr_args = args + ["--cal-min-base-m", f"{DR_MIN_BASE_M:g}"]
    (inputs / "calibrated.nvm").write_bytes(nvm_after(a.navecu, text, dr_args, t_cal1 + 0.5))
    cases.append({"name": "sim-dr-calibration", "input": write_log("sim-dr-calibration", text),
                  "args": dr_args, "nvm": "inputs/calibrated.nvm",
                  "what": "the regress drive without GNSS, booting from a stored calibration "
                          "(the NVM of this log's first calibration), one-point calibrations",
                  "commands": plan})

    msgs, outages = kingston_frames()
    cases.append({"name": "kingston-900s", "input": write_log("kingston-900s", candump_text(msgs)),
                  "args": kingston_run.RATES + kingston_run.SENSORS, "nvm": None,
                  "what": f"the first {KINGSTON_S:g} s of the Kingston drive as "
                          "tools/kingston/run.py converts and runs it, GNSS outages "
                          + ", ".join(f"{o[0]:g}-{o[1]:g} s" for o in outages)})
    for c in cases:
        c["args"] = args_text(c["args"])
    if (out / "inputs").exists():
        shutil.rmtree(out / "inputs")
    inputs.rename(out / "inputs")
    (out / "cases.json").write_text(regression.to_json({
        "about": "tools/regression_inputs.py wrote this and inputs/; tools/regression.py "
                 "replays them (docs/regression.md)", "cases": cases}) + "\n")
    for c in cases:
        print(f"{c['name']}: {c['input']} ({(out / c['input']).stat().st_size} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
