#!/usr/bin/env python3
"""Record a CAN bus to a log file (python-can): the format follows the extension
(.log candump, .asc, .blf, .csv, .trc; .gz compresses).

    tools/can_record.py OUT.log [--channel vcan0] [--duration-s 60] [--ids 300,301,...]

Stops after --duration-s, after --idle-s without frames (once something was received), or
on SIGINT/SIGTERM; prints how many frames it recorded.
"""
from __future__ import annotations

import argparse
import signal
import sys
import time

import can


def record(out, channel, duration_s=None, idle_s=None, ids=None, interface="socketcan",
           ready=None) -> int:
    stop = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.append(1))
    filters = [{"can_id": i, "can_mask": 0x7FF, "extended": False} for i in ids] if ids else None
    n = 0
    with can.Bus(channel=channel, interface=interface, can_filters=filters) as bus, \
            can.Logger(str(out)) as logger:
        if ready:
            ready()
        t_end = time.monotonic() + duration_s if duration_s else None
        last = None
        while not stop:
            if t_end and time.monotonic() > t_end:
                break
            msg = bus.recv(timeout=0.1)
            if msg is None:
                if idle_s and last is not None and time.monotonic() - last > idle_s:
                    break
                continue
            logger.on_message_received(msg)
            n += 1
            last = time.monotonic()
    return n


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--channel", default="vcan0")
    ap.add_argument("--interface", default="socketcan")
    ap.add_argument("--duration-s", type=float, default=None)
    ap.add_argument("--idle-s", type=float, default=None)
    ap.add_argument("--ids", default=None, help="comma-separated hex IDs to keep")
    a = ap.parse_args(argv)
    ids = [int(x, 16) for x in a.ids.split(",")] if a.ids else None
    n = record(a.out, a.channel, a.duration_s, a.idle_s, ids, a.interface)
    print(f"can_record: {n} frames -> {a.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
