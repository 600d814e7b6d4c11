#!/usr/bin/env python3
"""Replay a CAN log onto a bus (python-can): candump .log, .asc, .blf, .csv, .trc, .gz.

    python -m tools.can_replay LOG [--channel vcan0] [--vehicle NAME] [--speed 1.0 | --max-rate FPS | --fastest]

--speed S replays with the log's timing scaled by 1/S (1 = real time, 10 = ten times
faster; can.MessageSync paces it). --max-rate F ignores the log's timing and sends at most
F frames per second.

--fastest replays as fast as the firmware keeps up, without losing frames, by flow
control on the firmware's own output: navecu sends one NAV_Status page 0 (id 0x310,
StatusPage = 0 in byte 0's low nibble) every ACK_EVERY IMU samples it has processed
(firmware/app/app.c emit_due: IMU rate / status rate, 100 Hz / 10 Hz = 10 by default, in
every mode), so a second socket, filtered to 0x310, counts those frames as
acknowledgements, and the replay never lets the IMU samples it has sent (IMU_Accel frames,
0x101) run more than WINDOW samples ahead of acked * ACK_EVERY. Within the window frames go
out back to back; the replay waits only for acknowledgements, and TIMEOUT seconds without
one while it waits is an error, not a hang. At the end it waits for the acknowledgement of
the last complete status period. The rate found is the firmware's (and the bus's), not a
guess.

The firmware counts more than 7 IMU periods (70 ms at 100 Hz) between two samples as lost
samples (app.c on_imu_accel, CntTimeJumps), so the replay must not pause that long. While
it waits, the firmware works through the window: 30 samples take 10-30 ms inside User-Mode
Linux (docs/live-can.md). If an acknowledgement takes KEEPALIVE_S anyway, one more sample
goes out per KEEPALIVE_S, never more than HARD_WINDOW samples ahead (about 1000 frames, a
quarter of the firmware's socket buffer): still lossless, and no pause of the replay's
making. The summary counts these keepalives, and gives the longest time between two
acknowledgements (kernel receive times).

After 0.5 s without an IMU sample the firmware also sends NAV_Status page 0 with the
IMU-stale flag on its receive clock (app_poll). It does so only once it has processed all
it received, so these count as acknowledgements too; the summary counts them
(stale_status), because a run with any is not comparable frame for frame with --can-log.

Frames the bus refuses (ENOBUFS) are retried, never dropped silently; the summary on stderr
says how many were sent, retried and how long it took.
"""
from __future__ import annotations

import argparse
import errno
import gc
import struct
import sys
import time

import can

from tools import navecu_can as nc

# From the DBC (with --vehicle, that profile's identifiers: use_vehicle)
IMU_ACCEL_ID = 0x101      # the second frame of an IMU sample: one per sample
NAV_STATUS_ID = 0x310     # page 0 once per status period: the acknowledgement
HEALTH_IMU_STALE = 0x1    # NAV_Status HealthFlags bit IMU_STALE


def use_vehicle(name=None) -> None:
    """The identifiers and the IMU_STALE bit of the protocol, with vehicle profile name's
    identifiers (None: the DBC's)."""
    global IMU_ACCEL_ID, NAV_STATUS_ID, HEALTH_IMU_STALE
    db = nc.select_vehicle(name)
    IMU_ACCEL_ID = db.get_message_by_name("IMU_Accel").frame_id
    NAV_STATUS_ID = db.get_message_by_name("NAV_Status").frame_id
    HEALTH_IMU_STALE = nc.health_flag(db, "IMU_STALE")


use_vehicle()
ACK_EVERY = 10            # IMU samples per NAV_Status page 0: 100 Hz / 10 Hz (navecu defaults)
WINDOW = 30               # IMU samples the replay may run ahead of the acknowledged ones
ACK_TIMEOUT_S = 2.0
KEEPALIVE_S = 0.03        # a wait this long lets one more sample go (within HARD_WINDOW)
HARD_WINDOW = 400         # IMU samples ahead that the replay never exceeds
CAN_EFF_FLAG = 0x80000000
CAN_FRAME = struct.Struct("=IB3x8s")   # struct can_frame: id, dlc, pad, data


class AckTimeout(RuntimeError):
    """--fastest waited ACK_TIMEOUT_S for an acknowledgement that did not come."""


def is_ack(msg) -> bool:
    """A NAV_Status page 0."""
    return (msg.arbitration_id == NAV_STATUS_ID and not msg.is_extended_id
            and len(msg.data) >= 3 and msg.data[0] & 0x0F == 0)


def is_stale(msg) -> bool:
    """A NAV_Status page 0 with HealthFlags bit 0, IMU stale: 0.5 s without an IMU sample
    (or a sample processed 0.5 s after it was received)."""
    d = msg.data
    return is_ack(msg) and bool((d[1] | d[2] << 8) & HEALTH_IMU_STALE)


class AckCounter:
    """The acknowledgement socket of --fastest: NAV_Status frames only (kernel filter)."""

    def __init__(self, channel, interface="socketcan"):
        self.bus = can.Bus(channel=channel, interface=interface, receive_own_messages=False,
                           can_filters=[{"can_id": NAV_STATUS_ID, "can_mask": 0x7FF,
                                         "extended": False}])
        self.acked = self.stale = 0
        self.blocked_since = None  # monotonic time since which the replay waits in vain
        self.last_t = None       # kernel receive time of the last acknowledgement
        self.max_gap_s = 0.0     # longest time between two acknowledgements

    def poll(self, timeout):
        """Wait up to timeout s for a frame, then read all that are queued."""
        msg = self.bus.recv(timeout=timeout)
        while msg is not None:
            if is_ack(msg):
                self.acked += 1
                self.stale += is_stale(msg)
                if self.last_t is not None:
                    self.max_gap_s = max(self.max_gap_s, msg.timestamp - self.last_t)
                self.last_t = msg.timestamp
            msg = self.bus.recv(timeout=0.0)

    def close(self):
        self.bus.shutdown()


def replay(log, channel, speed=None, max_rate=None, interface="socketcan", skip=None,
           fastest=False, ack_every=ACK_EVERY, window=WINDOW, timeout_s=ACK_TIMEOUT_S,
           follower=None) -> dict:
    """Replay log onto channel; returns {"sent", "retries", "seconds"}, for fastest with
    the flow control's figures too (replay_fastest).

    fastest: flow control on the firmware's NAV_Status page 0 (module docstring).
    follower: with fastest, an optional callable returning how many acknowledgements
    another consumer of the firmware's output has seen (e.g. a recorder of the NAV_*
    frames); the replay then stays within the window of that consumer too, so that it
    cannot outrun it either."""
    if fastest:
        return replay_fastest(log, channel, interface, ack_every, window, timeout_s, follower)
    sent = retries = 0
    t0 = time.monotonic()
    with nc.LogFile(log) as reader, can.Bus(channel=channel, interface=interface) as bus:
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
    return {"sent": sent, "retries": retries, "seconds": time.monotonic() - t0,
            **_skipped(reader)}


def load_frames(log, skipped=None) -> list:
    """The log's frames as (is IMU_Accel, struct can_frame bytes), ready to write to a raw
    CAN socket. Loaded before the replay starts: parsing is no part of the paced loop.
    A candump log's malformed lines are skipped (nc.LogFile); skipped: a list that gets
    the LogFile, for its count."""
    out = []
    with nc.LogFile(log) as reader:
        if skipped is not None:
            skipped.append(reader)
        for m in reader:
            if m.is_extended_id:
                can_id = m.arbitration_id | CAN_EFF_FLAG
            else:
                can_id = m.arbitration_id
                if m.arbitration_id == NAV_STATUS_ID:
                    raise ValueError(f"{log} contains NAV_Status (0x310) frames: --fastest "
                                     "takes the firmware's NAV_Status as acknowledgements")
            data = bytes(m.data)
            if m.is_fd or len(data) > 8:
                raise ValueError(f"{log}: a CAN FD frame (id {m.arbitration_id:X}): --fastest "
                                 "sends classic CAN frames only")
            frame = CAN_FRAME.pack(can_id, m.dlc, data.ljust(8, b"\0"))
            out.append((can_id == IMU_ACCEL_ID, frame))
    return out


def replay_fastest(log, channel, interface="socketcan", ack_every=ACK_EVERY, window=WINDOW,
                   timeout_s=ACK_TIMEOUT_S, follower=None, frames=None,
                   keepalive_s=KEEPALIVE_S, hard_window=HARD_WINDOW) -> dict:
    """--fastest (module docstring). Returns {"sent", "retries", "seconds", "samples",
    "acked", "stale_status", "waits", "wait_s", "max_wait_ms", "max_ack_gap_ms",
    "ack_every", "window"}: max_ack_gap_ms is the longest time between two
    acknowledgements (kernel receive times), an upper bound for the firmware's pause
    between two IMU samples but for scheduling noise.

    The frames go straight to the raw socket (one write each, no python-can per-frame
    work and no clock read per frame: inside User-Mode Linux a clock read is a system call
    of about 0.1 ms)."""
    if window < ack_every:
        raise ValueError(f"window ({window}) must be at least ack_every ({ack_every}): "
                         "with less the replay would wait for an acknowledgement that needs "
                         "samples it has not sent")
    skipped = []
    if frames is None:
        frames = load_frames(log, skipped)
    sent = retries = samples = waits = keepalives = 0
    wait_s = max_wait = 0.0
    keepalive = (keepalive_s, hard_window) if keepalive_s else None
    acks = AckCounter(channel, interface)
    gc_enabled = gc.isenabled()
    gc.disable()    # no collector pause in the paced loop (it makes no cyclic garbage)
    try:
        with can.Bus(channel=channel, interface=interface) as bus:
            sock = bus.socket
            sock.setblocking(True)
            t0 = time.monotonic()
            limit = window
            for is_imu, fr in frames:
                if is_imu:
                    if samples >= limit:
                        waits += 1
                        tw = time.monotonic()
                        limit, kept = _wait_for_ack(acks, follower, ack_every, window,
                                                    samples + 1, timeout_s, keepalive)
                        keepalives += kept
                        dt = time.monotonic() - tw
                        wait_s += dt
                        max_wait = max(max_wait, dt)
                    samples += 1
                while True:
                    try:
                        sock.send(fr)
                        break
                    except OSError as e:   # ENOBUFS: the queue is full for a moment
                        if e.errno not in (errno.ENOBUFS, errno.EAGAIN):
                            raise can.CanOperationError(f"send failed: {e}", e.errno) from e
                        retries += 1
                        time.sleep(0.0005)
                sent += 1
            # the acknowledgement of the last complete status period: the firmware has
            # processed (at least) everything up to it
            _wait_for_ack(acks, follower, ack_every, 0, samples // ack_every * ack_every,
                          timeout_s)
            seconds = time.monotonic() - t0
    finally:
        acks.close()
        if gc_enabled:
            gc.enable()
    return {"sent": sent, "retries": retries, "seconds": seconds, "samples": samples,
            "acked": acks.acked, "stale_status": acks.stale, "waits": waits,
            "keepalives": keepalives,
            "wait_s": round(wait_s, 3), "max_wait_ms": round(max_wait * 1e3, 1),
            "max_ack_gap_ms": round(acks.max_gap_s * 1e3, 1), "ack_every": ack_every,
            "window": window, **(_skipped(skipped[0]) if skipped else {})}


def _skipped(log) -> dict:
    """A result's count of the log's malformed lines (nc.LogFile), and the line saying so."""
    return {"malformed": log.malformed, "malformed_note": log.note()}


def _limit(acks, follower, ack_every, window) -> int:
    acked = acks.acked if follower is None else min(acks.acked, follower())
    return acked * ack_every + window


def _wait_for_ack(acks, follower, ack_every, window, need, timeout_s, keepalive=None):
    """Read acknowledgements until need <= limit; returns (limit, False). AckTimeout after
    timeout_s without progress. keepalive = (seconds, hard window): after that long, the
    sample may go anyway if it is within the hard window; returns (need, True) then. The
    timeout counts from the last progress, across keepalives."""
    t_start = time.monotonic()
    if acks.blocked_since is None:
        acks.blocked_since = t_start
    seen = (acks.acked, follower() if follower else 0)
    while need > (limit := _limit(acks, follower, ack_every, window)):
        # a follower (a thread of this process) advances on its own: short waits then
        step = 0.002 if follower is not None and acks.acked * ack_every + window >= need \
            else 0.05
        if keepalive:
            step = min(step, max(0.0, t_start + keepalive[0] - time.monotonic()) + 0.0005)
        acks.poll(step)
        now = time.monotonic()
        now_seen = (acks.acked, follower() if follower else 0)
        if now_seen != seen:
            seen, acks.blocked_since = now_seen, now
        elif now - acks.blocked_since > timeout_s:
            who = ("the firmware" if acks.acked * ack_every + window < need
                   else "the follower (recorder)")
            raise AckTimeout(
                f"--fastest: no acknowledgement from {who} for {timeout_s:g} s, waiting for "
                f"IMU sample {need} with {acks.acked} NAV_Status page 0 received "
                f"({acks.acked * ack_every} samples acknowledged, ack every {ack_every}, "
                f"window {window}"
                + (f", follower {follower()}" if follower else "")
                + "). Is navecu running on this bus, with an IMU rate / status rate equal to "
                "--ack-every, and does the log hold only samples it accepts?")
        if keepalive and now - t_start >= keepalive[0] \
                and need <= _limit(acks, follower, ack_every, keepalive[1]):
            return need, True       # still blocked: blocked_since stays
    acks.blocked_since = None
    return limit, False


def _scaled(reader, factor):
    for msg in reader:
        msg.timestamp *= factor
        yield msg


def summary_line(r) -> str:
    s = (f"can_replay: {r['sent']} frames in {r['seconds']:.1f} s "
         f"({r['sent'] / max(r['seconds'], 1e-9):.0f} /s), {r['retries']} retries")
    if "malformed" in r:
        s += f"; {r['malformed_note']}"
    if "acked" in r:
        s += (f"; --fastest: {r['samples']} IMU samples, {r['acked']} acknowledged status "
              f"periods (every {r['ack_every']}, window {r['window']}), {r['waits']} waits "
              f"({r['wait_s']:.1f} s, longest {r['max_wait_ms']:.1f} ms, "
              f"{r['keepalives']} keepalives), longest time "
              f"between acknowledgements {r['max_ack_gap_ms']:.1f} ms, "
              f"{r['stale_status']} stale NAV_Status")
    return s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("log")
    ap.add_argument("--channel", default="vcan0")
    ap.add_argument("--vehicle", default=None,
                    help="the firmware's vehicle profile (its identifiers; default the DBC's)")
    ap.add_argument("--interface", default="socketcan")
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--speed", type=float, default=None, help="time scale (1 = real time)")
    g.add_argument("--max-rate", type=float, default=None, help="frames per second, untimed")
    g.add_argument("--fastest", action="store_true",
                   help="as fast as the firmware acknowledges (NAV_Status page 0): lossless")
    ap.add_argument("--ack-every", type=int, default=ACK_EVERY,
                    help="IMU samples per NAV_Status page 0 = IMU rate / status rate "
                         f"(default {ACK_EVERY} = 100 Hz / 10 Hz, navecu's defaults)")
    ap.add_argument("--window", type=int, default=WINDOW,
                    help=f"IMU samples sent ahead of the acknowledged ones (default {WINDOW})")
    ap.add_argument("--timeout-s", type=float, default=ACK_TIMEOUT_S,
                    help=f"--fastest: error after this long without an acknowledgement "
                         f"(default {ACK_TIMEOUT_S:g})")
    a = ap.parse_args(argv)
    use_vehicle(a.vehicle)
    if a.ack_every < 1:
        ap.error("--ack-every must be at least 1")
    try:
        r = replay(a.log, a.channel, a.speed, a.max_rate, a.interface, fastest=a.fastest,
                   ack_every=a.ack_every, window=a.window, timeout_s=a.timeout_s)
    except (AckTimeout, ValueError, OSError) as e:
        print(f"can_replay: {e}", file=sys.stderr)
        return 1
    print(summary_line(r), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
