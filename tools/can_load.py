"""Bus load of candump logs: frames per second by identifier and the share of a bitrate.

    python -m tools.can_load LOG [LOG ...] [--bitrate 500000] [--top 10]

Several logs (e.g. a run's input and output) are one bus. The rate of each identifier is its
frames over the span of the logs' timestamps. Bits per frame (ISO 11898-1, classic CAN):
the fixed fields of a data frame (SOF, ID, RTR, IDE, r0, DLC, CRC, delimiters, ACK, EOF, the
3-bit intermission) are 47 bits with an 11-bit identifier and 67 with a 29-bit one, plus 8
per data byte; bit stuffing adds up to one bit per 4 of the 34 + 8 n (11-bit) or 54 + 8 n
(29-bit) stuffed bits. The load is given without stuffing and with the worst case.
"""
from __future__ import annotations

import argparse
import sys

from tools import navecu_can as nc


def frame_bits(dlc: int, extended: bool) -> tuple:
    """(bits without stuffing, with worst-case stuffing) of one data frame."""
    fixed, stuffed = (67, 54) if extended else (47, 34)
    n = 8 * dlc
    return fixed + n, fixed + n + (stuffed + n - 1) // 4


def load(paths) -> dict:
    per, t0, t1 = {}, None, None
    for p in paths:
        for m in nc.read_log(p):
            key = (m.arbitration_id, bool(m.is_extended_id))
            n, dlc = per.get(key, (0, m.dlc))
            per[key] = (n + 1, max(dlc, m.dlc))
            t = float(m.timestamp)
            t0 = t if t0 is None or t < t0 else t0
            t1 = t if t1 is None or t > t1 else t1
    span = (t1 - t0) if t0 is not None and t1 > t0 else 0.0
    return {"span_s": span, "ids": per}


def report(res: dict, bitrate: int) -> dict:
    span = res["span_s"]
    if span <= 0:
        raise ValueError("the logs span no time")
    rows, fps, bits, bits_w = [], 0.0, 0.0, 0.0
    for (cid, ext), (n, dlc) in sorted(res["ids"].items()):
        r = n / span
        b, bw = frame_bits(dlc, ext)
        rows.append({"id": cid, "extended": ext, "dlc": dlc, "frames_per_s": r})
        fps += r
        bits += r * b
        bits_w += r * bw
    return {"span_s": span, "frames_per_s": fps, "bitrate": bitrate,
            "load_pct": 100.0 * bits / bitrate, "load_worst_stuffing_pct": 100.0 * bits_w / bitrate,
            "ids": rows}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("logs", nargs="+")
    ap.add_argument("--bitrate", type=int, default=500000)
    ap.add_argument("--top", type=int, default=10)
    a = ap.parse_args(argv)
    try:
        rep = report(load(a.logs), a.bitrate)
    except (OSError, ValueError) as e:
        print(f"can_load: {e}", file=sys.stderr)
        return 1
    print(f"can_load: {rep['frames_per_s']:.0f} frames/s over {rep['span_s']:.1f} s: "
          f"{rep['load_pct']:.1f} % of {a.bitrate} bit/s "
          f"({rep['load_worst_stuffing_pct']:.1f} % with worst-case bit stuffing)")
    for r in sorted(rep["ids"], key=lambda r: -r["frames_per_s"])[:a.top]:
        print(f"  0x{r['id']:0{8 if r['extended'] else 3}X} dlc {r['dlc']}: "
              f"{r['frames_per_s']:.1f}/s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
