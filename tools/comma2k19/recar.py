"""The RAV4 segment's real motion on another car's bus: its wheel speeds re-encoded as
another vehicle profile's own frames.

    python -m tools.comma2k19.recar --vehicle NAME [--out out/recar-NAME] [--data DIR]

Only the RAV4 has a recording (data/comma2k19-rav4); the other profiles are checked on
frames generated from their DBCs (tests/python/test_vehicle_profiles.py). This runs a
profile on real motion: the segment's device IMU and u-blox fixes as `make drive` sends
them (tools/comma2k19/convert.py, no car frame), and each of the RAV4's WHEEL_SPEEDS frames
of can0 (the four wheels, decoded with the RAV4 profile's DBC) sent at its recorded time as
the profile's own wheel-speed message(s), with its gear on every change and every second,
its checksum and counter (tools/vehicle.py CarEncoder); the car's other traffic is left
out (it is another car's). build/host/navecu-NAME (`make VEHICLE=NAME`) runs on it with the
options `make drive` uses (run.firmware_options, run.run_one), and the horizontal error against the reference pose is printed
beside what the firmware read and refused. The same motion through every profile should
navigate as the RAV4's own frames do: the profiles differ in resolution (0.005 to 0.0311
km/h, the Ford's 0.01 rad/s of wheel speed), not in what they say.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from tools import navecu_can as nc
from tools import vehicle
from tools.comma2k19 import convert, run
from tools.sim.run import Stages

ROOT = Path(__file__).resolve().parents[2]
#: the recording's car and the bus its wheel speeds are on
SOURCE_PROFILE = "toyota_rav4_2017"
SOURCE_CHANNEL = "can0"


def rav4_wheels(data_dir: Path, t0_segment_s: float, t_last_s: float) -> list:
    """[(t s of the run, [FL, FR, RL, RR] m/s)] of the recording's WHEEL_SPEEDS frames on
    can0 within the run, decoded with the RAV4 profile's DBC."""
    src = vehicle.load(SOURCE_PROFILE)
    wr = next(r for r in src.reads if r.role == "wheels")
    names = [s.name for s in wr.signals]   # FL, FR, RL, RR, as the profile lists them
    out = []
    for msg in convert.car_frames(data_dir / "car_bus.log"):
        if msg.arbitration_id != wr.message.frame_id or str(msg.channel) != SOURCE_CHANNEL:
            continue
        t = round(float(msg.timestamp) - t0_segment_s, 6)
        if t < 0.0 or t > t_last_s:
            continue
        sig = wr.message.decode(bytes(msg.data))
        out.append((t, [float(sig[n]) * src.speed_factor for n in names]))
    return out


def build(name: str, data_dir: Path | None = None) -> tuple:
    """(frames, meta, wheel frames sent) for profile `name`: convert.build's IMU and GNSS
    frames without the car's bus, and the RAV4's wheel speeds as the profile's frames."""
    data = Path(data_dir or convert.DATA_DIR)
    frames, meta = convert.build(data, name, car_bus=False)
    enc = vehicle.CarEncoder(vehicle.load(name))
    n = 0
    for t, v in rav4_wheels(data, meta["t0_segment_s"], meta["last_imu_sample_s"]):
        for m in enc.wheels(t, v):
            m.timestamp = t
            frames.append((t, convert.O_CAR, m))
            n += 1
    frames.sort(key=lambda x: (x[0], x[1]))
    meta["frames"] = len(frames)
    meta["recar"] = {"source": f"{SOURCE_PROFILE} WHEEL_SPEEDS on {SOURCE_CHANNEL}",
                     "profile_frames_sent": n}
    return frames, meta, n


def run_profile(name: str, out: Path, data_dir: Path | None = None,
                navecu: Path | None = None) -> dict:
    """Build, run navecu-NAME and compare as `make drive` does (run.run_one, into
    out/NAME/): its report (a dict, also out/report.json) with the frames sent."""
    if vehicle.load(name).native_wheels:
        raise ValueError(f"profile {name} reads navecu's own WheelSpeeds, no car's message: "
                         "the simulator's drives have it (make sim)")
    exe = Path(navecu or ROOT / "build" / "host" / f"navecu-{name}")
    dbc = ROOT / "build" / "vehicle" / name / "navecu.dbc"
    for p in (exe, dbc):
        if not p.exists():
            raise FileNotFoundError(f"{p} missing: make VEHICLE={name} first")
    out.mkdir(parents=True, exist_ok=True)
    stages = Stages(2)
    stages.start("convert the recording, re-encode its wheel speeds")
    frames, meta, n = build(name, data_dir)
    stages.done(f"{meta['frames']} frames, {n} of the profile's")
    truth = run.reference_truth(Path(data_dir or convert.DATA_DIR), meta["t0_segment_s"])
    opts = run.firmware_options(meta)
    rep, _, _ = run.run_one(stages, exe, name, frames, meta, out, opts, nc.load_db(dbc),
                            truth, None)
    rep["vehicle"] = name
    rep["profile_frames_sent"] = n
    rep["firmware_options"] = opts
    (out / "report.json").write_text(json.dumps(rep, indent=2, default=float) + "\n")
    return rep


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--vehicle", required=True, help="a profile of vehicles/")
    ap.add_argument("--out", default=None, help="default out/recar-NAME")
    ap.add_argument("--data", default=None, help=f"default {convert.DATA_DIR}")
    ap.add_argument("--navecu", default=None)
    a = ap.parse_args(argv)
    try:
        rep = run_profile(a.vehicle, Path(a.out or f"out/recar-{a.vehicle}"), a.data, a.navecu)
    except (vehicle.ProfileError, FileNotFoundError, RuntimeError, ValueError) as e:
        print(f"recar: {e}", file=sys.stderr)
        return 2
    e = rep["horizontal_error_m"]
    print(f"{a.vehicle}: {rep['profile_frames_sent']} wheel-speed frames sent; horizontal "
          f"error rms {e['rms']:.2f} m, p95 {e['p95']:.2f} m, max {e['max']:.2f} m; "
          f"car messages read {rep.get('car_messages_read')}; rejected {rep.get('rejected')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
