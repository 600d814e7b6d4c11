#!/usr/bin/env python3
"""Replay a CAN log onto a bus (python-can): candump .log, .asc, .blf, .csv, .trc, .gz.

    tools/can_replay.py LOG [--channel vcan0] [--speed 1.0 | --max-rate FPS]

--speed S replays with the log's timing scaled by 1/S (1 = real time, 10 = ten times
faster; can.MessageSync paces it). --max-rate F ignores the log's timing and sends at most
F frames per second: the way to find "as fast as the firmware keeps up without losing
frames" (docs/can.md). Frames the bus refuses (ENOBUFS) are retried, never dropped
silently; the summary on stderr says how many were sent, retried and how long it took.
"""
from __future__ import annotations

import argparse
import sys
import time

import can


def replay(log, channel, speed=None, max_rate=None, interface="socketcan", skip=None) -> dict:
    sent = retries = 0
    t0 = time.monotonic()
    with can.Bus(channel=channel, interface=interface) as bus, can.LogReader(log) as reader:
        if max_rate:
            source = reader
            period = 1.0 / max_rate
        else:
            factor = 1.0 / speed if speed else 1.0
            source = can.MessageSync(_scaled(reader, factor), timestamps=True, skip=skip or 60.0)
            period = 0.0
        next_t = time.monotonic()
        for msg in source:
            if period:
                now = time.monotonic()
                if now < next_t:
                    time.sleep(next_t - now)
                next_t = max(next_t + period, time.monotonic() - 0.01)
            out = can.Message(arbitration_id=msg.arbitration_id, data=msg.data,
                              is_extended_id=msg.is_extended_id, dlc=msg.dlc)
            while True:
                try:
                    bus.send(out, timeout=1.0)
                    break
                except can.CanOperationError:
                    retries += 1
                    time.sleep(0.001)
            sent += 1
    return {"sent": sent, "retries": retries, "seconds": time.monotonic() - t0}


def _scaled(reader, factor):
    for msg in reader:
        msg.timestamp *= factor
        yield msg


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("log")
    ap.add_argument("--channel", default="vcan0")
    ap.add_argument("--interface", default="socketcan")
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--speed", type=float, default=None, help="time scale (1 = real time)")
    g.add_argument("--max-rate", type=float, default=None, help="frames per second, untimed")
    a = ap.parse_args(argv)
    r = replay(a.log, a.channel, a.speed, a.max_rate, a.interface)
    print(f"can_replay: {r['sent']} frames in {r['seconds']:.1f} s "
          f"({r['sent'] / max(r['seconds'], 1e-9):.0f} /s), {r['retries']} retries",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
