#!/usr/bin/env python3
"""Regenerate the per-message signal tables of docs/can.md from firmware/can/navecu.dbc.

Only the text between the markers
    <!-- BEGIN GENERATED: tools/gen_can_doc.py -->
    <!-- END GENERATED -->
is rewritten; the prose around it is hand-written. The hand-written overview table (rows
starting "| 0x") is checked against the DBC (ID, name, sender, DLC, E2E) but not rewritten.

    python -m tools.gen_can_doc            rewrite docs/can.md
    python -m tools.gen_can_doc --check    exit 1 if docs/can.md is stale or its overview disagrees

The meaning column is the DBC comment of the signal where there is one, else the text in
MEANING below, followed by the value table and, for multiplexed signals, the page. A DBC
signal with neither comment nor MEANING entry is an error: new signals must be documented.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from tools import navecu_can

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "can.md"
BEGIN = "<!-- BEGIN GENERATED: tools/gen_can_doc.py -->"
END = "<!-- END GENERATED -->"

_INC = "over the sample interval, quantisation remainder carried to the next sample"
_RAW_EPOCH = ("number of the raw epoch (its GNSS_RawEpoch) this satellite frame belongs to, "
              "0..14 (15 invalid)")
_E2E_CRC = "E2E CRC8 SAE J1850 over ID and bytes 0..6"
_IMU_CRC = ("E2E CRC8 SAE J1850 of the IMU sample, over this frame's ID, the 8 bytes of "
            "IMU_Rate and bytes 0..6 of this frame")
_NAV_CNT = "E2E alive counter 0..14, +1 per frame of this message"
_HEIGHT = "height above the WGS-84 ellipsoid"

# (message, signal) or signal -> meaning, for signals without a DBC comment.
MEANING = {
    "GpsWeek": "GPS week number (weeks since 1980-01-06, no 1024 rollover)",
    ("GNSS_Time", "GnssEpoch"): "number of the epoch this frame belongs to",
    "GnssTimeCrc": _E2E_CRC,
    "RateX": "angular rate about the vehicle's x axis (right): the pitch rate of the car body",
    "RateY": "angular rate about the vehicle's y axis (forward): the roll rate",
    "RateZ": "angular rate about the vehicle's z axis (up): the yaw rate, left positive",
    "RollRate": "rate of NAV_Attitude's Roll",
    "PitchRate": "rate of NAV_Attitude's Pitch",
    "HeadingRate": "rate of NAV_Attitude's Heading (clockwise positive)",
    "AccelX": "acceleration along the vehicle's x axis (right), gravity removed",
    "AccelY": "acceleration along the vehicle's y axis (forward), gravity removed",
    "AccelZ": "acceleration along the vehicle's z axis (up), gravity removed",
    "AccelEast": "d/dt of VelEast",
    "AccelNorth": "d/dt of VelNorth",
    "AccelUp": "d/dt of VelUp",
    "VelAccEast": "1-sigma of VelEast; 40.95 unknown",
    "VelAccNorth": "1-sigma of VelNorth; 40.95 unknown",
    "VelAccUp": "1-sigma of VelUp; 40.95 unknown",
    "HeadingAccuracy": "1-sigma of NAV_Attitude's Heading; 40.95 unknown",
    ("NAV_Time", "TimeOfWeek"): "GPS time of week of the output set's validity, 1 us; "
                                "1099511.627775 unknown",
    ("NAV_Time", "GpsWeek"): "GPS week of it; 65535 unknown (no GNSS_Time received)",
    "AngleIncX": "angle increment about body x (right), " + _INC,
    "AngleIncY": "angle increment about body y (forward), " + _INC,
    "AngleIncZ": "angle increment about body z (up), " + _INC,
    "VelIncX": "velocity increment (integrated specific force) along body x (right), " + _INC,
    "VelIncY": "velocity increment along body y (forward), " + _INC,
    "VelIncZ": "velocity increment along body z (up); +g*dt at rest, " + _INC,
    "ImuCounter": "E2E alive counter 0..14; the same value in the IMU_Rate and IMU_Accel "
                  "of one sample",
    ("IMU_Time", "SampleTime"): "the IMU's clock at the end of the sample interval, 1 us, "
                                "wrapping at 2^32 (71.6 min): the interval of the sample is "
                                "this less the previous sample's (imu_time = stamped)",
    ("IMU_Time", "ImuCounter"): "the ImuCounter of the IMU_Rate/IMU_Accel pair of the same "
                                "sample (its own E2E alive counter too)",
    "ImuTimeCrc": _E2E_CRC,
    "ImuFault": "1: the IMU reports a fault in this sample",
    "ImuCrc": _IMU_CRC,
    "WheelSpeedFL": "front-left wheel speed, positive rolling forward, negative backward",
    "WheelSpeedFR": "front-right wheel speed, sign as FL",
    "WheelSpeedRL": "rear-left wheel speed, sign as FL",
    "WheelSpeedRR": "rear-right wheel speed, sign as FL",
    "WheelCounter": "E2E alive counter 0..14",
    "WheelCrc": _E2E_CRC,
    ("GNSS_Position", "Latitude"): "geodetic latitude of the fix (WGS-84), north positive",
    ("GNSS_Position", "Longitude"): "longitude of the fix, east positive",
    "VelEast": "velocity east (ENU)",
    "VelNorth": "velocity north",
    "VelUp": "velocity up",
    ("GNSS_Velocity", "GnssEpoch"): "number of the epoch this frame belongs to; also the "
                                    "E2E counter, so 0..14 (15 invalid)",
    "SpeedAccuracy": "receiver's speed accuracy estimate, saturated at 1.5 m/s",
    "GnssVelCrc": _E2E_CRC,
    "FixType": "fix type of the epoch",
    "NumSatellites": "satellites used in the fix",
    ("GNSS_Status", "HorizAccuracy"): "receiver's horizontal position accuracy estimate",
    ("GNSS_Status", "VertAccuracy"): "receiver's vertical position accuracy estimate",
    ("GNSS_Status", "GnssEpoch"): "number of the epoch this frame closes",
    "TimeOfWeek": "GPS time of week of the epoch",
    ("GNSS_Height", "Height"): _HEIGHT + " of the fix",
    "SatPosY": "ECEF y at the transmit time, as SatPosX",
    "SatPosZ": "ECEF z at the transmit time, as SatPosX",
    "SatVelY": "ECEF y velocity, as SatVelX",
    "SatVelZ": "ECEF z velocity, as SatVelX",
    "RawSlot": "the satellite's index in its raw epoch, 0..NumMeas-1: its five frames share it",
    "RawSatXCrc": _E2E_CRC,
    "RawSatYCrc": _E2E_CRC,
    "RawSatZCrc": _E2E_CRC,
    "RawRangeCrc": _E2E_CRC,
    "RawRateCrc": _E2E_CRC,
    "RawEpochCrc": _E2E_CRC,
    ("GNSS_RawSatX", "GnssEpoch"): _RAW_EPOCH,
    ("GNSS_RawSatY", "GnssEpoch"): _RAW_EPOCH,
    ("GNSS_RawSatZ", "GnssEpoch"): _RAW_EPOCH,
    ("GNSS_RawRange", "GnssEpoch"): _RAW_EPOCH,
    ("GNSS_RawRate", "GnssEpoch"): _RAW_EPOCH,
    ("GNSS_RawEpoch", "GnssEpoch"): "number of the raw epoch this frame closes, 0..14 (15 "
                                    "invalid)",
    ("GNSS_Height", "GnssEpoch"): "number of the epoch this frame belongs to",
    ("CMD_KnownPosition", "Latitude"): "geodetic latitude of the vehicle now (WGS-84)",
    ("CMD_KnownPosition", "Longitude"): "longitude of the vehicle now",
    "Command": "command to execute",
    "HeadingValid": "1: Heading is given (SetInitialPosition)",
    ("CMD_Control", "Heading"): "heading of the forward axis, clockwise from true north "
                                "(SetInitialPosition)",
    ("CMD_Control", "Height"): _HEIGHT + " (SetInitialPosition)",
    "CmdCounter": "E2E alive counter 0..14",
    "CmdCrc": _E2E_CRC,
    ("NAV_Position", "Latitude"): "navigated geodetic latitude (WGS-84)",
    ("NAV_Position", "Longitude"): "navigated longitude",
    ("NAV_Height", "Height"): "navigated " + _HEIGHT,
    ("NAV_Height", "VertAccuracy"): "estimated vertical accuracy, saturated",
    ("NAV_Height", "TimeOfValidity"): "IMU time of this NAV_* set (samples since the first "
                                      "IMU sample / IMU rate; imu_time = stamped: the sum of "
                                      "the samples' IMU_Time intervals) in ms, modulo 65536",
    "NavCounter": _NAV_CNT,
    "NavCrc": _E2E_CRC,
    "Roll": "roll, right side down positive",
    "Pitch": "pitch, nose up positive",
    ("NAV_Attitude", "Heading"): "heading of the forward axis, clockwise from true north",
    "StatusPage": "multiplexer: page 0 state, pages 1..6 health counters",
    ("NAV_Status", "HorizAccuracy"): "estimated horizontal position accuracy, saturated",
    "CntBadDlc": "frames of a known message with DLC other than 8",
    "CntBadCrc": "frames with a wrong E2E CRC",
    "CntBadCounter": "frames with a repeated or invalid (15) E2E counter",
    "CntImuPairBroken": "IMU_Rate/IMU_Accel that did not form a pair",
    "CntImuLost": "IMU samples lost (counter gaps)",
    "CntBadValue": "frames with a value out of its range or implausible",
    "CntGnssRejected": "GNSS epochs rejected (impossible position, mismatched epoch, no position)",
    "InitRoll": "roll of the vehicle (right side down +), docs/frames.md",
    "InitPitch": "pitch of the vehicle (nose up +)",
    "AttCounter": "E2E alive counter",
    "AttCrc": "E2E CRC8 (SAE J1850)",
    "CntCmdRejected": "commands refused (unknown, missing known position, nothing to store)",
    "CntCoreRejected": "IMU samples the strapdown core refused (non-finite, out of its valid region)",
    "CntTimeJumps": "receive timestamps that went backwards, and IMU gaps found from receive time",
    "CntFilterResets": "Kalman filter found diverged and reset (docs/reliability.md)",
    "CntTasksLate": "main-loop passes with a late task: the watchdog kick withheld",
    "CntNonFinite": "navigation outputs not finite, not sent",
    "CntImuSaturated": "IMU samples with an axis at its configured range",
    "CntOdoRejected": "odometer/standstill updates refused by the filter's gate",
    "CntImuStuck": "IMU axes found stuck (a raw value repeated 2 s while another axis of the sensor showed its noise)",
    "CntRxLost": "received frames lost (a receive overrun; a replayed log's unreadable lines)",
    "HeadingCorrection": "heading correction from the calibration at a known point",
    "OdoScaleError": "odometer scale factor error (relative)",
    "CalValid": "1: a calibration is in use",
    "CalStored": "1: the calibration in use is stored in NVM",
}


def fmt_num(x) -> str:
    if x is None:
        return ""
    x = float(x)
    if x == int(x) and abs(x) < 1e15:
        return str(int(x))
    return repr(x)


def fmt_factor(x) -> str:
    s = fmt_num(x)
    m, e = math.frexp(float(x))
    if m == 0.5 and e - 1 < -3:
        s += f" (2^{e - 1})"
    return s


def meaning(msg, sig) -> str:
    text = sig.comment or MEANING.get((msg.name, sig.name)) or MEANING.get(sig.name)
    if not text:
        raise SystemExit(f"gen_can_doc: {msg.name}.{sig.name} has no DBC comment and no "
                         "MEANING entry in tools/gen_can_doc.py")
    text = text.rstrip(".")
    choices = sig.conversion.choices
    if choices and not sig.comment:  # a DBC comment already explains the values
        text += "; " + ", ".join(f"{k} {v}" for k, v in sorted(choices.items()))
    if sig.multiplexer_ids:
        pages = ", ".join(str(i) for i in sig.multiplexer_ids)
        text = f"page {pages}: " + text
    return text.replace("|", "/")


def _signal_order(sig):
    """Multiplexer first, then the multiplexed signals page by page, then the rest; by start
    bit within each group."""
    if sig.is_multiplexer:
        return (0, 0, sig.start)
    if sig.multiplexer_ids:
        return (1, min(sig.multiplexer_ids), sig.start)
    return (2, 0, sig.start)


def generate(db) -> str:
    out = []
    for msg in sorted(db.messages, key=lambda m: m.frame_id):
        e2e = navecu_can.e2e_signals(msg)
        cycle = f"{msg.cycle_time} ms" if msg.cycle_time else "none in the DBC"
        receivers = sorted({r for s in msg.signals for r in s.receivers})
        out.append(f"### 0x{msg.frame_id:03X} {msg.name}")
        out.append("")
        first, second = navecu_can.IMU_PAIR
        if not e2e:
            e2e_text = "no E2E"
        elif msg.name == first:
            e2e_text = (f"E2E with {second} (one IMU sample): counter `{e2e[0].name}`, no CRC "
                        f"of its own, {second}'s CRC covers all 8 bytes")
        elif msg.name == second:
            e2e_text = (f"E2E with {first} (one IMU sample): counter `{e2e[0].name}`, CRC "
                        f"`{e2e[1].name}` over both frames")
        elif e2e[0] is None:
            e2e_text = f"E2E: CRC `{e2e[1].name}`, no alive counter"
        else:
            e2e_text = f"E2E: counter `{e2e[0].name}`, CRC `{e2e[1].name}`"
        out.append(f"Sender {', '.join(msg.senders)}, receiver {', '.join(receivers)}; "
                   f"{msg.length} bytes, standard ID; cycle time {cycle}; {e2e_text}.")
        if msg.comment:
            out.append("")
            out.append(msg.comment)
        out.append("")
        out.append("| signal | start bit | length | signed | factor | offset | min | max | unit "
                   "| meaning |")
        out.append("|---|---:|---:|---|---|---|---|---|---|---|")
        for sig in sorted(msg.signals, key=_signal_order):
            name = f"{sig.name} (multiplexer)" if sig.is_multiplexer else sig.name
            out.append(
                f"| {name} | {sig.start} | {sig.length} | {'yes' if sig.is_signed else 'no'} "
                f"| {fmt_factor(sig.conversion.scale)} | {fmt_num(sig.conversion.offset)} "
                f"| {fmt_num(sig.minimum)} | {fmt_num(sig.maximum)} | {sig.unit or ''} "
                f"| {meaning(msg, sig)} |")
        out.append("")
        if any(sig.name == "HealthFlags" for sig in msg.signals):
            out += health_flags_table(db)
    return "\n".join(out)


def health_flags_table(db) -> list:
    """The HealthFlags bits: the DBC's value table HealthFlagBits, the one the firmware's
    NAVECU_HEALTH_* constants are generated from (tools/gen_protocol.py)."""
    out = ["HealthFlags bits (the DBC's value table `HealthFlagBits`):", "",
           "| bit | value | name | set while |", "|---:|---:|---|---|"]
    for bit, (name, text) in sorted(navecu_can.health_bits(db).items()):
        out.append(f"| {bit} | {1 << bit} | {name} | {text.replace('|', '/')} |")
    out.append("")
    return out


def check_overview(db, text: str) -> list:
    """Differences between the hand-written overview rows ("| 0x...") and the DBC."""
    problems, seen = [], set()
    for line in text.split(BEGIN)[0].splitlines():
        if not line.startswith("| 0x"):
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 6:
            problems.append(f"overview row has too few columns: {line}")
            continue
        fid, name, sender, dlc, _rate, e2e = cells[:6]
        name = name.strip("`")
        try:
            msg = db.get_message_by_name(name)
        except KeyError:
            problems.append(f"overview names {name}, which is not in the DBC")
            continue
        seen.add(name)
        want = {"ID": f"0x{msg.frame_id:03X}", "sender": ", ".join(msg.senders),
                "DLC": str(msg.length), "E2E": "yes" if navecu_can.is_e2e(msg) else "no"}
        got = {"ID": fid.upper().replace("0X", "0x"), "sender": sender, "DLC": dlc,
               "E2E": e2e.split()[0].lower() if e2e else ""}
        for key, value in want.items():
            if got[key] != value:
                problems.append(f"overview {name}: {key} is {got[key]!r}, DBC says {value!r}")
    for msg in db.messages:
        if msg.name not in seen:
            problems.append(f"overview lacks {msg.name}")
    return problems


def render(doc_text: str, generated: str) -> str:
    if doc_text.count(BEGIN) != 1 or doc_text.count(END) != 1:
        raise SystemExit(f"gen_can_doc: {DOC} needs exactly one {BEGIN} and one {END}")
    head, rest = doc_text.split(BEGIN)
    _, tail = rest.split(END)
    return f"{head}{BEGIN}\n\n{generated}\n{END}{tail}"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description="Regenerate the signal tables of docs/can.md.")
    p.add_argument("--check", action="store_true", help="exit 1 if the document is stale")
    p.add_argument("--doc", type=Path, default=DOC)
    a = p.parse_args(argv)
    db = navecu_can.load_db()
    text = a.doc.read_text(encoding="utf-8")
    new = render(text, generate(db))
    problems = check_overview(db, new)
    for problem in problems:
        print(f"gen_can_doc: {problem}", file=sys.stderr)
    if a.check:
        if new != text:
            print(f"gen_can_doc: {a.doc} is stale; run python -m tools.gen_can_doc",
                  file=sys.stderr)
            return 1
        return 1 if problems else 0
    if new != text:
        a.doc.write_text(new, encoding="utf-8")
        print(f"gen_can_doc: rewrote {a.doc}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
