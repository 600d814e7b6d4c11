#!/usr/bin/env python3
"""Self-test of a SocketCAN vcan interface with python-can (run it under with_vcan.sh).

    tools/vcan/with_vcan.sh .venv/bin/python tools/vcan/vcan_selftest.py [--frames N]

Checks, each reported as one JSON object on stdout (exit status 0 only if all pass):
  burst   - N frames sent from one python-can Bus arrive on a second Bus, all of them, in
            order, with their ids and payloads; reports frames/s (first send to last receive).
  cansend - `cansend vcan0 123#DEADBEEF` (can-utils) is received by a python-can Bus.
"""
import argparse
import json
import platform
import shutil
import socket
import subprocess
import sys
import threading
import time

import can


RCVBUF_BYTES = 4 << 20


def enlarge_rcvbuf(bus: can.BusABC, n_bytes: int) -> int:
    """Ask for an n_bytes receive buffer (SO_RCVBUFFORCE as root, else capped by rmem_max).

    Returns the size the kernel granted. A CAN frame costs about 1 kB of buffer (skb
    truesize), so the default ~200 kB holds only ~200 frames for a reader that lags."""
    sock = bus.socket
    for opt in (getattr(socket, "SO_RCVBUFFORCE", 33), socket.SO_RCVBUF):
        try:
            sock.setsockopt(socket.SOL_SOCKET, opt, n_bytes)
            break
        except OSError:
            continue
    return sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)


def burst(channel: str, n_frames: int, window: int, timeout_s: float) -> dict:
    """Send n_frames on one Bus, receive them on another in a thread; check order and content.

    window > 0: the sender keeps at most `window` frames in flight (sent, not yet received),
    so a receiver slowed down by the GIL or by UML's scheduling cannot overflow its socket
    buffer; window = 0: send flat out (SocketCAN drops what the receive buffer cannot hold)."""
    received = []
    with can.Bus(interface="socketcan", channel=channel) as rx, \
            can.Bus(interface="socketcan", channel=channel) as tx:
        rcvbuf = enlarge_rcvbuf(rx, RCVBUF_BYTES)
        ready = threading.Event()

        def reader() -> None:
            ready.set()
            deadline = time.monotonic() + timeout_s
            while len(received) < n_frames and time.monotonic() < deadline:
                msg = rx.recv(timeout=0.5)
                if msg is not None:
                    received.append((msg.arbitration_id, bytes(msg.data), msg.is_extended_id))

        th = threading.Thread(target=reader, daemon=True)
        th.start()
        ready.wait()
        t0 = time.perf_counter()
        for i in range(n_frames):
            while window and i - len(received) >= window and th.is_alive():
                time.sleep(0.0002)
            tx.send(can.Message(arbitration_id=0x100 + (i % 0x600), is_extended_id=False,
                                data=i.to_bytes(4, "little") + b"\xa5\x5a\x00\xff"),
                    timeout=1.0)
        th.join(timeout_s)
        dt_s = time.perf_counter() - t0
    expected = [(0x100 + (i % 0x600), i.to_bytes(4, "little") + b"\xa5\x5a\x00\xff", False)
                for i in range(n_frames)]
    first_bad = next((i for i, (a, b) in enumerate(zip(received, expected)) if a != b), None)
    ok = received == expected
    return {"check": "burst", "ok": ok, "sent": n_frames, "received": len(received),
            "first_mismatch": first_bad, "window": window, "rcvbuf": rcvbuf, "seconds": round(dt_s, 3),
            "frames_per_s": round(len(received) / dt_s) if dt_s > 0 else None}


def cansend(channel: str, timeout_s: float) -> dict:
    """`cansend <channel> 123#DEADBEEF` must reach a python-can receiver."""
    tool = shutil.which("cansend")
    if tool is None:
        return {"check": "cansend", "ok": False, "missing": "cansend (Debian: can-utils)"}
    with can.Bus(interface="socketcan", channel=channel) as rx:
        proc = subprocess.run([tool, channel, "123#DEADBEEF"], capture_output=True, text=True,
                              timeout=timeout_s)
        msg = rx.recv(timeout=timeout_s) if proc.returncode == 0 else None
    got = None if msg is None else {"id": msg.arbitration_id, "data": msg.data.hex(),
                                     "extended": msg.is_extended_id, "dlc": msg.dlc}
    ok = (got is not None and got["id"] == 0x123 and got["data"] == "deadbeef"
          and not got["extended"] and got["dlc"] == 4)
    return {"check": "cansend", "ok": ok, "returncode": proc.returncode,
            "stderr": proc.stderr.strip(), "received": got}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--channel", default="vcan0")
    ap.add_argument("--frames", type=int, default=2000)
    ap.add_argument("--window", type=int, default=256,
                    help="most frames in flight; 0 = no flow control")
    ap.add_argument("--timeout-s", type=float, default=20.0)
    args = ap.parse_args()
    print(json.dumps({"check": "env", "kernel": platform.release(), "python": sys.executable,
                      "python_can": can.__version__}), flush=True)
    results = [burst(args.channel, args.frames, args.window, args.timeout_s),
               cansend(args.channel, args.timeout_s)]
    for r in results:
        print(json.dumps(r), flush=True)
    return 0 if all(r["ok"] for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
