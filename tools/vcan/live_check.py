#!/usr/bin/env python3
"""Run build/host/navecu live on vcan0, replay a log into it, record what it sends.

Run inside a vcan environment (tools/vcan/with_vcan.sh). Prints one JSON line:
{"mode", "sent", "retries", "replay_s", "recorded", "firmware_summary", "frames": [...]}
where frames are the recorded 'ID#DATA' strings in order (NAV_* output); --fastest adds
the replay's flow-control figures ("replay": tools/can_replay.py replay()), --out FILE
writes the recorded frames as a candump log too (with their kernel receive times),
--no-frames leaves "frames" out of the JSON line.

    with_vcan.sh .venv/bin/python -m tools.vcan.live_check --log IN.log --speed 1
    with_vcan.sh .venv/bin/python -m tools.vcan.live_check --log IN.log --max-rate 3000
    with_vcan.sh .venv/bin/python -m tools.vcan.live_check --log IN.log --fastest --out NAV.log
    with_vcan.sh .venv/bin/python -m tools.vcan.live_check --interop
    with_vcan.sh .venv/bin/python -m tools.vcan.live_check --latency --log IN.log
    with_vcan.sh .venv/bin/python -m tools.vcan.live_check --robust --log IN.log
"""
from __future__ import annotations

import argparse
import json
import os
import shlex
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import can

from tools import can_replay, navecu_can

ROOT = Path(__file__).resolve().parents[2]

# navecu's outputs (the messages its DBC says it sends)
NAV_IDS = [m.frame_id for m in navecu_can.load_db().messages if "NAVECU" in m.senders]
NAV_STATUS_ID = navecu_can.load_db().get_message_by_name("NAV_Status").frame_id
FRAME_HEAD = struct.Struct("=IB")  # struct can_frame: can_id, len (data at offset 8)
CHANNEL = "vcan0"  # --channel


def start_firmware(extra=()):  # noqa: D103
    proc = subprocess.Popen([os.environ.get("NAVECU_BIN", str(ROOT / "build/host/navecu")),
                             "--can", CHANNEL, *extra],
                            stderr=subprocess.PIPE, text=True)
    line = proc.stderr.readline()
    if "running on" not in line:
        raise SystemExit(f"navecu did not start: {line}{proc.stderr.read()}")
    return proc


def stop_firmware(proc) -> str:
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=20)
    return err.strip()


class Recorder(threading.Thread):
    """Receives NAV_* frames (and extra_ids) until stopped; keeps 'ID#DATA' strings in
    order and the kernel receive timestamps, and counts the NAV_Status page 0 frames that
    tools/can_replay.py --fastest takes as acknowledgements (acked), so that the replay
    can stay within its window of this recorder too (can_replay.replay follower)."""

    def __init__(self, extra_ids=()):
        super().__init__(daemon=True)
        filters = [{"can_id": i, "can_mask": 0x7FF, "extended": False}
                   for i in NAV_IDS + list(extra_ids)]
        self.bus = can.Bus(channel=CHANNEL, interface="socketcan", can_filters=filters,
                           receive_own_messages=False)
        # a Python reader in a UML guest can fall behind for a moment: give the socket room
        # (SO_RCVBUFFORCE = 33, root only; else the capped SO_RCVBUF)
        try:
            self.bus.socket.setsockopt(socket.SOL_SOCKET, 33, 8 << 20)
        except OSError:
            self.bus.socket.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 8 << 20)
        self.frames, self.times, self.stop = [], [], False
        self.acked = 0

    def run(self):
        # One recvmsg per frame on the raw socket, a kernel receive timeout (SO_RCVTIMEO)
        # to look at self.stop: no select and no clock read per frame (inside User-Mode
        # Linux every system call costs, a clock read is one).
        sock = self.bus.socket
        sock.setblocking(True)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVTIMEO, struct.pack("@ll", 0, 50000))
        anc = socket.CMSG_SPACE(16)
        frames, times = self.frames, self.times
        while not self.stop:
            try:
                cf, ancdata, _, _ = sock.recvmsg(16, anc)
            except BlockingIOError:         # SO_RCVTIMEO: nothing for 50 ms
                continue
            except OSError:                 # the interface went down: keep listening
                time.sleep(0.05)
                continue
            can_id, dlc = FRAME_HEAD.unpack_from(cf)
            data = cf[8:8 + dlc]
            fid = can_id & 0x7FF
            frames.append(f"{fid:03X}#{data.hex().upper()}")
            times.append(_timestamp(ancdata))
            if fid == NAV_STATUS_ID and dlc >= 3 and data[0] & 0x0F == 0:
                self.acked += 1             # can_replay.is_ack
        self.bus.shutdown()

    def finish(self, idle_s=1.0):
        """Stop once no frame has arrived for idle_s."""
        n, quiet = -1, 0.0
        while quiet < idle_s:
            time.sleep(0.05)
            quiet = quiet + 0.05 if len(self.frames) == n else 0.0
            n = len(self.frames)
        self.stop = True
        self.join()

    def write(self, path) -> int:
        """The recorded frames as a candump log (tools/navecu_can.write_candump), with
        their kernel receive times."""
        def msgs():
            for f, t in zip(self.frames, self.times):
                fid, data = f.split("#")
                yield can.Message(timestamp=t, arbitration_id=int(fid, 16),
                                  data=bytes.fromhex(data), is_extended_id=False,
                                  channel=CHANNEL)
        return navecu_can.write_candump(path, msgs())


def _timestamp(ancdata) -> float:
    """The kernel receive time of a frame (SO_TIMESTAMPNS, which python-can enables)."""
    for level, kind, data in ancdata:
        if level == socket.SOL_SOCKET and len(data) >= 16:
            sec, nsec = struct.unpack_from("@qq", data)
            return sec + nsec * 1e-9
    return 0.0


def firmware_args(a) -> list:
    return ((["--imu-rate-hz", str(a.imu_rate_hz)] if a.imu_rate_hz else [])
            + shlex.split(a.navecu_args or ""))


def replay_mode(a) -> dict:
    rec = Recorder()
    rec.start()
    fw = start_firmware(firmware_args(a))
    try:
        if a.fastest:
            r = can_replay.replay(a.log, CHANNEL, fastest=True, ack_every=a.ack_every,
                                  window=a.window, follower=lambda: rec.acked)
        else:
            r = can_replay.replay(a.log, CHANNEL, speed=a.speed, max_rate=a.max_rate)
    except (can_replay.AckTimeout, ValueError) as e:
        summary = stop_firmware(fw)
        rec.finish(0.1)
        raise SystemExit(f"live_check: {e}\n{summary}") from None
    # stop within the firmware's 0.5 s of IMU silence: after that it reports the silence in
    # extra NAV_Status frames (app_poll) that a --can-log run has not
    time.sleep(0.2)
    summary = stop_firmware(fw)
    rec.finish(0.5)
    res = {"mode": "fastest" if a.fastest else "speed" if a.speed else "max_rate",
           "sent": r["sent"], "retries": r["retries"], "replay_s": r["seconds"],
           "recorded": len(rec.frames), "firmware_summary": summary}
    if a.fastest:
        res["replay"] = r
    if a.out:
        res["out"] = str(a.out)
        res["written"] = rec.write(a.out)
    if not a.no_frames:
        res["frames"] = rec.frames
    return res


def interop_mode() -> dict:
    """cansend commands to the running firmware; candump sees its NAV_Status change."""
    db = navecu_can.load_db()
    sender = navecu_can.E2ESender(db)
    kp = sender.encode("CMD_KnownPosition", {"Latitude": 45.0, "Longitude": 10.0})
    ctl = sender.encode("CMD_Control", {"Command": 2, "HeadingValid": 1, "Heading": 30.0,
                                        "Height": 100.0})
    dump = ROOT / "build" / "interop_candump.log"
    dump.parent.mkdir(exist_ok=True)
    fw = start_firmware()
    cd = subprocess.Popen(["candump", "-L", f"{CHANNEL},310:7FF"], stdout=open(dump, "w"))
    time.sleep(0.3)
    for msg in (kp, ctl):
        subprocess.run(["cansend", CHANNEL,
                        f"{msg.arbitration_id:03X}#{bytes(msg.data).hex().upper()}"], check=True)
    # a few IMU samples so that the firmware's status cycle runs (sample-driven)
    quant = navecu_can.ImuQuantizer()
    with can.Bus(channel=CHANNEL, interface="socketcan") as bus:
        for k in range(30):
            rate, accel = quant.signals([0.0, 0.0, 0.0], [0.0, 0.0, 0.098])
            for m in sender.encode_imu_pair(rate, accel):
                bus.send(m)
            time.sleep(0.01)
    time.sleep(0.3)
    summary = stop_firmware(fw)
    cd.terminate()
    cd.wait()
    modes = []
    for line in dump.read_text().splitlines():
        frame = line.split()[2]
        data = bytes.fromhex(frame.split("#")[1])
        sig = db.decode_message(NAV_STATUS_ID, data, decode_choices=False)
        if sig["StatusPage"] == 0:
            modes.append(int(sig["Mode"]))
    return {"mode": "interop", "status_modes": modes, "firmware_summary": summary}


def latency_mode(a) -> dict:
    """Kernel receive time of each IMU_Accel (which completes an IMU sample) to that of the
    NAV_Position it causes, both stamped by the recorder's socket, at real-time replay."""
    rec = Recorder(extra_ids=[navecu_can.load_db().get_message_by_name("IMU_Accel").frame_id])
    rec.start()
    fw = start_firmware(["--level-s", "1"])
    can_replay.replay(a.log, CHANNEL, speed=1.0)
    time.sleep(0.2)
    stop_firmware(fw)
    rec.finish(0.5)
    lat, last_imu = [], None
    for f, t in zip(rec.frames, rec.times):
        if f.startswith("101#"):
            last_imu = t
        elif f.startswith("300#") and last_imu is not None:
            lat.append((t - last_imu) * 1e6)
    lat.sort()
    q = (lambda p: lat[min(len(lat) - 1, int(p * len(lat)))]) if lat else (lambda p: None)
    return {"mode": "latency", "n": len(lat), "p50_us": q(0.50), "p99_us": q(0.99),
            "max_us": lat[-1] if lat else None}


def robust_mode(a) -> dict:
    """Replay half the log, kill the replay, take vcan0 down and up, replay the rest: the
    firmware keeps running, NAV_Status shows the gap (IMU stale), outputs resume."""
    msgs = list(can.LogReader(a.log))
    half = len(msgs) // 2
    first, second = Path("/tmp/robust_a.log"), Path("/tmp/robust_b.log")
    navecu_can.write_candump(first, msgs[:half])
    navecu_can.write_candump(second, msgs[half:])
    rec = Recorder()
    rec.start()
    fw = start_firmware(["--level-s", "1"])
    can_replay.replay(str(first), CHANNEL, max_rate=3000)
    n_before = len(rec.frames)
    time.sleep(1.5)                         # the replay is gone: IMU silent
    subprocess.run(["ip", "link", "set", CHANNEL, "down"], check=True)
    time.sleep(0.5)
    subprocess.run(["ip", "link", "set", CHANNEL, "up"], check=True)
    alive_after_down_up = fw.poll() is None
    can_replay.replay(str(second), CHANNEL, max_rate=3000)
    time.sleep(0.3)
    alive = fw.poll() is None
    summary = stop_firmware(fw)
    rec.finish(0.5)
    db = navecu_can.load_db()
    stale = 0
    for f in rec.frames[n_before:]:
        fid, data = f.split("#")
        if fid == "310":
            sig = db.decode_message(NAV_STATUS_ID, bytes.fromhex(data), decode_choices=False)
            if sig["StatusPage"] == 0 and int(sig["HealthFlags"]) & 0x1:
                stale += 1
    pos_after = sum(1 for f in rec.frames[n_before:] if f.startswith("300#"))
    return {"mode": "robust", "alive_after_down_up": alive_after_down_up, "alive": alive,
            "stale_status_frames": stale, "nav_position_after_restart": pos_after,
            "firmware_summary": summary}


def main() -> int:
    global CHANNEL
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--log")
    ap.add_argument("--channel", default=CHANNEL)
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--speed", type=float)
    g.add_argument("--max-rate", type=float)
    g.add_argument("--fastest", action="store_true",
                   help="flow-controlled replay (tools/can_replay.py --fastest)")
    ap.add_argument("--ack-every", type=int, default=None,
                    help="IMU samples per NAV_Status page 0 (default: IMU rate / 10 Hz)")
    ap.add_argument("--window", type=int, default=can_replay.WINDOW)
    ap.add_argument("--imu-rate-hz", type=int, default=None,
                    help="passed to navecu (default: its own, 100)")
    ap.add_argument("--navecu-args", default=None, metavar="'ARGS'",
                    help="more navecu options, one shell-quoted string "
                         "(--navecu-args='--level-s 1')")
    ap.add_argument("--out", help="write the recorded frames to this candump log")
    ap.add_argument("--no-frames", action="store_true", help="no 'frames' in the JSON line")
    ap.add_argument("--interop", action="store_true")
    ap.add_argument("--latency", action="store_true")
    ap.add_argument("--robust", action="store_true")
    a = ap.parse_args()
    CHANNEL = a.channel
    if a.ack_every is None:
        # navecu's emit_due: status every imu / status_rate samples, status rate 10 Hz
        a.ack_every = max(1, (a.imu_rate_hz or 100) // 10)
    if a.interop:
        res = interop_mode()
    elif a.latency:
        res = latency_mode(a)
    elif a.robust:
        res = robust_mode(a)
    else:
        res = replay_mode(a)
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
