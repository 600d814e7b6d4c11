#!/usr/bin/env python3
"""Run the firmware on a CAN log twice, live on a SocketCAN bus and with --can-log, and
check that the two give the same NAV_* frames (`make sim BUS=vcan0`, tools/sim/run.py).

    python -m tools.vcan.bus_run IN.log OUT_DIR [--bus vcan0] [--imu-rate-hz 100]
                                 [--navecu-args='MORE NAVECU OPTIONS']

1. OUT_DIR/nav_file.log: `navecu --can-log IN.log`, the reference.
2. OUT_DIR/nav.log: `navecu --can vcan0` with IN.log replayed into it by
   tools/can_replay.py --fastest (as fast as the firmware acknowledges) and its output
   recorded (python -m tools.vcan.live_check --fastest --out). On vcan0 this runs inside
   tools/vcan/with_vcan.sh (User-Mode Linux where the kernel has no CAN); another
   interface is used directly and must exist.
3. The check: nav.log and nav_file.log carry the same payloads, frame for frame and in
   order, all but NAV_Heartbeat's (the one time-driven output, sent on the ECU's own clock:
   a live ECU sends it before the replay starts, so it differs by design; left out by its
   identifier, navecu_can.data_driven, and counted apart); the firmware received every
   frame replayed and lost, rejected and time-jumped none; no NAV_Status reported the IMU
   stale.

Exit status 0 when identical, 1 when not, 2 when no vcan is possible here (with_vcan.sh
exit 77), 3 when the live run itself failed.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

from tools import navecu_can

ROOT = Path(__file__).resolve().parents[2]
WITH_VCAN = ROOT / "tools" / "vcan" / "with_vcan.sh"
NO_VCAN = 77


class BusRunError(RuntimeError):
    def __init__(self, msg, code):
        super().__init__(msg)
        self.code = code


def payloads(path) -> list:
    """'ID#DATA' of every frame of a candump -L log, in order."""
    out = []
    for line in Path(path).read_text().splitlines():
        parts = line.split()
        if len(parts) >= 3 and "#" in parts[2]:
            out.append(parts[2].upper())
    return out


def counters(summary: str) -> dict:
    """navecu's 'rejected:' summary line as {name: count}."""
    m = re.search(r"rejected: (.*)", summary)
    if not m:
        return {}
    return {k.strip(): int(v) for k, v in re.findall(r"([a-z ]+?) (\d+)(?:,|$)", m.group(1))}


def run(navecu, can_in, out_dir, bus="vcan0", imu_rate_hz=100, navecu_args=(),
        timeout_s=3600) -> dict:
    """Both runs and the comparison (module docstring); navecu_args go to both firmware
    runs. Raises BusRunError when the live run could not be made (code 2: no vcan here,
    3: it failed)."""
    out_dir = Path(out_dir)
    nav_file, nav_bus = out_dir / "nav_file.log", out_dir / "nav.log"
    ref = subprocess.run([str(navecu), "--can-log", str(can_in), "--out", str(nav_file),
                          "--imu-rate-hz", str(imu_rate_hz), *navecu_args],
                         capture_output=True, text=True)
    if ref.returncode != 0:
        raise BusRunError(f"navecu --can-log failed:\n{ref.stderr}", 3)
    cmd = [sys.executable, "-m", "tools.vcan.live_check", "--log", str(can_in), "--fastest",
           "--channel", bus, "--imu-rate-hz", str(imu_rate_hz), "--out", str(nav_bus),
           "--no-frames", "--navecu-args=" + shlex.join(navecu_args)]
    if bus == "vcan0":
        cmd = [str(WITH_VCAN)] + cmd
    env = dict(os.environ, NAVECU_BIN=str(navecu), NAVECU_VCAN_TIMEOUT=str(timeout_s))
    live = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=env,
                          timeout=timeout_s + 120)
    if live.returncode == NO_VCAN:
        why = [ln for ln in live.stderr.splitlines() if "SKIPPED:" in ln]
        raise BusRunError("NO VCAN: " + (why[-1] if why else "with_vcan.sh exit 77"), 2)
    if live.returncode != 0 or not live.stdout.strip():
        raise BusRunError(f"the live run failed (exit {live.returncode}):\n"
                          f"{live.stderr.strip()[-3000:]}", 3)
    r = json.loads(live.stdout.strip().splitlines()[-1])
    all_bus, all_file = payloads(nav_bus), payloads(nav_file)
    # the data-driven frames: all but the time-driven NAV_Heartbeat (module docstring)
    a, b = navecu_can.data_driven(all_bus), navecu_can.data_driven(all_file)
    same = sum(1 for x, y in zip(a, b) if x == y)
    first = next((i for i, (x, y) in enumerate(zip(a, b)) if x != y),
                 None if len(a) == len(b) else min(len(a), len(b)))
    m = re.search(r"navecu: (\d+) frames in", r["firmware_summary"])
    c = counters(r["firmware_summary"])
    losses = {k: c.get(k) for k in ("imu lost", "imu pair broken", "bad counter", "bad crc",
                                    "time jumps")}
    rp = r["replay"]
    return {
        "bus": bus, "identical": first is None, "frames_bus": len(a), "frames_file": len(b),
        "heartbeats_bus": len(all_bus) - len(a), "heartbeats_file": len(all_file) - len(b),
        "frames_equal": same, "first_difference": first,
        "difference": None if first is None else
        {"bus": a[first] if first < len(a) else None,
         "file": b[first] if first < len(b) else None},
        "sent": r["sent"], "received_by_firmware": int(m.group(1)) if m else None,
        "firmware_losses": losses, "stale_status": rp["stale_status"],
        "replay_s": rp["seconds"], "frames_per_s": rp["sent"] / max(rp["seconds"], 1e-9),
        "replay": rp, "firmware_summary": r["firmware_summary"],
        "file_summary": ref.stderr.strip(),
    }


def lossless(res) -> bool:
    """Every frame replayed reached the firmware, it lost none, no stale status."""
    return (res["received_by_firmware"] == res["sent"]
            and all(v == 0 for v in res["firmware_losses"].values())
            and res["stale_status"] == 0)


def describe(res) -> list:
    """Human-readable lines for the simulator's output."""
    rp = res["replay"]
    lines = [f"replay --fastest: {res['sent']} frames in {res['replay_s']:.1f} s "
             f"({res['frames_per_s']:.0f} frames/s, window {rp['window']} samples, "
             f"{rp['waits']} waits, longest {rp['max_wait_ms']:.0f} ms), firmware received "
             f"{res['received_by_firmware']}, losses "
             + ", ".join(f"{k} {v}" for k, v in res["firmware_losses"].items())
             + f", stale status {res['stale_status']}"]
    hb = (f" (NAV_Heartbeat, the time-driven output, left out: {res['heartbeats_bus']} live, "
          f"{res['heartbeats_file']} in the file run)")
    if res["identical"]:
        lines.append(f"NAV payloads over {res['bus']} identical to --can-log frame for frame: "
                     f"{res['frames_equal']} of {res['frames_file']} frames{hb}")
    else:
        lines.append(f"NAV payloads over {res['bus']} DIFFER from --can-log: "
                     f"{res['frames_equal']} of {res['frames_file']} equal ({res['frames_bus']} "
                     f"recorded), first difference at frame {res['first_difference']}: "
                     f"{res['difference']}{hb}")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("log")
    ap.add_argument("out_dir")
    ap.add_argument("--bus", default="vcan0")
    ap.add_argument("--imu-rate-hz", type=int, default=100)
    ap.add_argument("--navecu", default=str(ROOT / "build" / "host" / "navecu"))
    ap.add_argument("--navecu-args", default="", help="more navecu options, one string")
    a = ap.parse_args(argv)
    Path(a.out_dir).mkdir(parents=True, exist_ok=True)
    try:
        res = run(a.navecu, a.log, a.out_dir, a.bus, a.imu_rate_hz, shlex.split(a.navecu_args))
    except BusRunError as e:
        print(f"bus_run: {e}", file=sys.stderr)
        return e.code
    for line in describe(res):
        print(line)
    return 0 if res["identical"] and lossless(res) else 1


if __name__ == "__main__":
    sys.exit(main())
