"""navecu_can - the Python side of the navecu CAN protocol (docs/can.md).

The protocol is firmware/can/navecu.dbc; everything here is derived from it:

- load_db()                 the DBC, loaded by cantools with strict checking;
- crc8_sae_j1850(data)      CRC8 SAE-J1850 (poly 0x1D, init 0xFF, xor-out 0xFF, not reflected);
- E2ESender                 encodes messages, filling the 4-bit counter and the CRC of E2E
                            messages; encode_imu_pair() for the two frames of an IMU sample;
- check_e2e(msg, db)        checks the E2E protection of one received frame (not IMU_Accel);
- check_imu_pair(r, a, db)  checks one IMU sample, IMU_Rate + IMU_Accel, with the pair CRC;
- E2EReceiver               checks a stream of frames, pairing the IMU frames by counter;
- ImuQuantizer              quantises IMU increments with the remainder carried to the next sample;
- write_candump(path, msgs) writes a candump (.log) file through python-can;
- health_bits, status_signals, counter_max, choices: NAV_Status and NAV_Calibration read
  back (HealthFlags bit names, the counter pages, value tables).

E2E messages are the ones with a *Crc signal in byte 7 (start bit 56, 8 bits) and one 4-bit
alive counter (*Counter or GnssEpoch, not multiplexed) in bytes 0..6: CRC over
[id & 0xFF, id >> 8, data[0..6]], stored in data[7]. The exception is the IMU sample
(IMU_PAIR): IMU_Rate (counter, no CRC) then IMU_Accel (same counter, CRC) are one E2E data
element; the CRC in IMU_Accel's byte 7 is over the 17 bytes
[0x01, 0x01 (IMU_Accel's ID, low byte first), IMU_Rate data[0..7], IMU_Accel data[0..6]].

All frames are classic CAN, 8 data bytes, 11-bit identifiers; timestamps in seconds. Every
bus and log-file operation goes through python-can.
"""

from __future__ import annotations

import math
import re
import sys
from pathlib import Path
from typing import Iterable, Mapping, Optional

import can
import cantools
from crccheck.crc import Crc8SaeJ1850

DBC_PATH = Path(__file__).resolve().parent.parent / "firmware" / "can" / "navecu.dbc"

CRC_START_BIT = 56
#: E2E alive counters run 0..14; 15 is never sent and invalid on reception.
E2E_COUNTER_MAX = 14

#: E2E messages with a CRC and no alive counter: NAV_Time's TimeOfWeek itself advances.
E2E_NO_COUNTER = ("NAV_Time",)

#: The IMU sample: (first frame, second frame). The first carries the counter and no CRC;
#: the CRC in the second covers all 8 bytes of the first (docs/can.md, E2E protection).
IMU_PAIR = ("IMU_Rate", "IMU_Accel")
ANGLE_SIGNALS = ("AngleIncX", "AngleIncY", "AngleIncZ")
VEL_SIGNALS = ("VelIncX", "VelIncY", "VelIncZ")


_VEHICLE_DB = None  # the protocol with a vehicle profile's identifiers (select_vehicle)


def load_db(path: Optional[Path] = None) -> cantools.database.can.Database:
    """The navecu DBC, loaded with cantools' strict checks (overlapping or out-of-frame
    signals raise); without a path, with the identifiers of the vehicle profile chosen by
    select_vehicle, if any."""
    if path is None and _VEHICLE_DB is not None:
        return _VEHICLE_DB
    return cantools.database.load_file(str(path or DBC_PATH), database_format="dbc", strict=True)


def select_vehicle(name: Optional[str]) -> cantools.database.can.Database:
    """Use the identifiers of vehicle profile `name` (vehicles/NAME.toml; None or "native":
    the DBC's) for every later load_db() and DEFAULT_DB: the tools then speak to a build of
    that profile (make VEHICLE=NAME)."""
    global _VEHICLE_DB, DEFAULT_DB
    _VEHICLE_DB = None
    if name not in (None, "native"):
        from tools import vehicle
        _VEHICLE_DB = cantools.database.load_string(
            vehicle.profile_dbc_text(vehicle.load(name)), database_format="dbc", strict=True)
    DEFAULT_DB = load_db()
    return DEFAULT_DB


def _axis_format(db, message: str, names: tuple) -> tuple:
    """(LSB, physical min, physical max) shared by the three axis signals of an IMU message;
    raises if the DBC gives the axes different scalings or ranges."""
    msg = db.get_message_by_name(message)
    formats = {(s.conversion.scale, s.conversion.offset, s.minimum, s.maximum)
               for s in map(msg.get_signal_by_name, names)}
    if len(formats) != 1:
        raise ValueError(f"{message}: {', '.join(names)} differ in scaling or range")
    scale, offset, lo, hi = formats.pop()
    if offset != 0:
        raise ValueError(f"{message}: IMU increments must have offset 0")
    return float(scale), float(lo), float(hi)


#: The DBC at DBC_PATH, loaded once; the default wherever a `db` argument is omitted.
DEFAULT_DB = load_db()
#: IMU quantisation steps and physical ranges per sample, read from the DBC
#: (IMU_Rate AngleInc*, IMU_Accel VelInc*).
ANGLE_LSB_RAD, ANGLE_MIN_RAD, ANGLE_MAX_RAD = _axis_format(DEFAULT_DB, IMU_PAIR[0], ANGLE_SIGNALS)
VEL_LSB_MPS, VEL_MIN_MPS, VEL_MAX_MPS = _axis_format(DEFAULT_DB, IMU_PAIR[1], VEL_SIGNALS)


def crc8_sae_j1850(data: bytes) -> int:
    """CRC8 SAE-J1850: poly 0x1D, init 0xFF, xor-out 0xFF, not reflected. b"123456789" -> 0x4B."""
    return Crc8SaeJ1850.calc(bytes(data))


def _id_bytes(frame_id: int) -> bytes:
    return bytes([frame_id & 0xFF, (frame_id >> 8) & 0xFF])


def e2e_crc(frame_id: int, data: bytes) -> int:
    """The E2E CRC of a frame: over the 2 ID bytes (low first) and payload bytes 0..6."""
    return crc8_sae_j1850(_id_bytes(frame_id) + bytes(data[:7]))


def imu_pair_crc(accel_id: int, rate_data: bytes, accel_data: bytes) -> int:
    """The E2E CRC of one IMU sample, stored in IMU_Accel's byte 7: over IMU_Accel's 2 ID
    bytes (low first), IMU_Rate's 8 payload bytes and IMU_Accel's payload bytes 0..6."""
    if len(rate_data) != 8:
        raise ValueError("IMU_Rate payload must be 8 bytes")
    return crc8_sae_j1850(_id_bytes(accel_id) + bytes(rate_data) + bytes(accel_data[:7]))


def _crc_signal(message):
    return next((s for s in message.signals
                 if s.name.endswith("Crc") and s.start == CRC_START_BIT and s.length == 8), None)


def _counter_signal(message, last_bit: int):
    """The single non-multiplexed 4-bit unsigned *Counter/*Epoch signal within bits
    0..last_bit."""
    counter = [s for s in message.signals
               if s.name.endswith(("Counter", "Epoch")) and s.length == 4 and not s.is_signed
               and s.multiplexer_ids is None and s.start + s.length - 1 <= last_bit]
    if len(counter) != 1:
        raise ValueError(f"{message.name}: E2E message without a single 4-bit alive counter "
                         f"in bits 0..{last_bit}")
    return counter[0]


def e2e_signals(message) -> Optional[tuple]:
    """(counter signal, CRC signal) of an E2E-protected cantools message, or None.

    For IMU_Rate, the first frame of the IMU pair, the CRC signal is None: the CRC of the
    sample is IMU_Accel's ImuCrc (see imu_pair_crc). For E2E_NO_COUNTER messages the
    counter signal is None."""
    crc = _crc_signal(message)
    if message.name == IMU_PAIR[0]:
        if crc is not None:
            raise ValueError(f"{message.name}: the first frame of the IMU pair has no CRC")
        return _counter_signal(message, 63), None
    if crc is None:
        return None
    if message.name in E2E_NO_COUNTER:
        return None, crc
    return _counter_signal(message, CRC_START_BIT - 1), crc


def _to_raw(signal, value):
    """Physical value -> raw integer, rounded to nearest (cantools' own scaling truncates:
    0.29 with factor 0.01 would become 28). Choice names pass through to cantools."""
    if isinstance(value, str):
        return value
    if hasattr(value, "value") and hasattr(value, "name"):  # cantools NamedSignalValue
        return value.value
    conv = signal.conversion
    raw = (float(value) - conv.offset) / conv.scale
    if not math.isfinite(raw):
        raise ValueError(f"signal {signal.name}: value {value!r} is not finite")
    return int(math.floor(raw + 0.5))


def encode_frame(db, name: str, signals: Mapping, timestamp: float = 0.0) -> can.Message:
    """Encode one message (physical values, rounded to the nearest LSB, range-checked
    strictly against the DBC) into a classic CAN frame. No E2E filling: see E2ESender."""
    msg_def = db.get_message_by_name(name)
    raw = {}
    for sig_name, value in signals.items():
        raw[sig_name] = _to_raw(msg_def.get_signal_by_name(sig_name), value)
    data = msg_def.encode(raw, scaling=False, strict=True)
    return _make_message(msg_def, data, timestamp)


def _make_message(msg_def, data: bytes, timestamp: float) -> can.Message:
    if msg_def.length != 8 or msg_def.is_extended_frame or msg_def.is_fd:
        raise ValueError(f"{msg_def.name}: navecu frames are classic CAN, 11-bit ID, DLC 8")
    return can.Message(timestamp=float(timestamp), arbitration_id=msg_def.frame_id,
                       is_extended_id=False, is_fd=False, dlc=8, data=data)


def _axis_values(values, names: tuple) -> dict:
    """Signals of one IMU frame: a mapping of signal names (passed on as it is) or three
    physical values for the X, Y, Z axis signals."""
    if isinstance(values, Mapping):
        return dict(values)
    values = list(values)
    if len(values) != 3:
        raise ValueError(f"expected 3 values for {', '.join(names)}, got {len(values)}")
    return dict(zip(names, values))


class E2ESender:
    """Encodes messages of the DBC; for E2E messages fills the counter and the CRC.

    Each message ID has its own alive counter, which starts at 0 and advances by one per
    frame, wrapping 14 -> 0; 15 is never sent. A counter value given explicitly in `signals`
    is sent as it is (within the DBC range 0..14) and the sequence continues after it:
    GNSS_Velocity's epoch number, shared with GNSS_Status and GNSS_Height, or a test
    injecting a jump.

    The IMU sample is sent with encode_imu_pair(), never frame by frame: IMU_Rate and
    IMU_Accel share one counter and IMU_Accel's CRC covers IMU_Rate.
    """

    def __init__(self, db=None):
        self.db = db if db is not None else DEFAULT_DB
        self._next = {}  # frame_id -> next counter value

    def next_counter(self, name: str) -> int:
        """The counter value the next frame of message `name` will carry."""
        return self._next.get(self.db.get_message_by_name(name).frame_id, 0)

    def _advance(self, frame_ids, counter: int) -> None:
        for frame_id in frame_ids:
            self._next[frame_id] = 0 if counter >= E2E_COUNTER_MAX else counter + 1

    def encode(self, name: str, signals: Mapping, timestamp: float = 0.0) -> can.Message:
        msg_def = self.db.get_message_by_name(name)
        if name in IMU_PAIR:
            raise ValueError(f"{name} is one half of an IMU sample: use encode_imu_pair()")
        e2e = e2e_signals(msg_def)
        if e2e is None:
            return encode_frame(self.db, name, signals, timestamp)
        counter_sig, crc_sig = e2e
        if crc_sig.name in signals:
            raise ValueError(f"{name}: {crc_sig.name} is computed by E2ESender, do not pass it")
        values = dict(signals)
        if counter_sig is None:
            values[crc_sig.name] = 0
            msg = encode_frame(self.db, name, values, timestamp)
            msg.data[7] = e2e_crc(msg_def.frame_id, msg.data)
            return msg
        if counter_sig.name in values:
            counter = int(values[counter_sig.name])
        else:
            counter = self._next.get(msg_def.frame_id, 0)
            values[counter_sig.name] = counter
        values[crc_sig.name] = 0
        msg = encode_frame(self.db, name, values, timestamp)
        msg.data[7] = e2e_crc(msg_def.frame_id, msg.data)
        self._advance([msg_def.frame_id], counter)
        return msg

    def encode_imu_pair(self, angle, vel, timestamp: float = 0.0, fault: int = 0,
                        counter: Optional[int] = None) -> tuple:
        """The two frames of one IMU sample, (IMU_Rate, IMU_Accel), in the order they are
        sent, with one counter and the pair CRC in IMU_Accel's byte 7.

        angle: the IMU_Rate signals (a mapping, e.g. ImuQuantizer.signals()[0]) or the three
        angle increments in rad; vel: the IMU_Accel signals or the three velocity increments
        in m/s. Physical values are rounded to the nearest LSB here, without carry: use
        ImuQuantizer for the carried remainder. fault: ImuFault (unless given in vel).
        counter: sent as it is, the sequence continuing after it (default: the next one);
        an ImuCounter in the mappings counts as given and must agree."""
        rate_def, accel_def = map(self.db.get_message_by_name, IMU_PAIR)
        rate_counter, _ = e2e_signals(rate_def)
        accel_counter, accel_crc = e2e_signals(accel_def)
        rate = _axis_values(angle, ANGLE_SIGNALS)
        accel = _axis_values(vel, VEL_SIGNALS)
        if accel_crc.name in accel:
            raise ValueError(f"{accel_crc.name} is computed by E2ESender, do not pass it")
        given = {int(v) for v in (counter, rate.get(rate_counter.name),
                                  accel.get(accel_counter.name)) if v is not None}
        if len(given) > 1:
            raise ValueError(f"IMU pair: conflicting counters {sorted(given)}")
        value = given.pop() if given else self._next.get(rate_def.frame_id, 0)
        rate[rate_counter.name] = accel[accel_counter.name] = value
        accel.setdefault("ImuFault", fault)
        accel[accel_crc.name] = 0
        m_rate = encode_frame(self.db, rate_def.name, rate, timestamp)  # range-checks value
        m_accel = encode_frame(self.db, accel_def.name, accel, timestamp)
        m_accel.data[7] = imu_pair_crc(accel_def.frame_id, m_rate.data, m_accel.data)
        self._advance([rate_def.frame_id, accel_def.frame_id], value)
        return m_rate, m_accel


def is_e2e(msg_def) -> bool:
    """True if the cantools message carries E2E protection: a *Crc signal in byte 7, or
    IMU_Rate, protected by the CRC in IMU_Accel."""
    return e2e_signals(msg_def) is not None


def _frame_ok(msg: can.Message) -> bool:
    return (not (msg.is_extended_id or msg.is_fd or msg.is_remote_frame or msg.is_error_frame)
            and msg.dlc == 8 and len(msg.data) == 8)


def _counter_value(data: bytes, counter_sig) -> int:
    return (int.from_bytes(bytes(data), "little") >> counter_sig.start) & 0x0F


def check_e2e(msg: can.Message, db) -> bool:
    """Check one received frame: known standard ID, classic CAN, DLC 8; for E2E messages also
    the CRC in byte 7 and a counter in 0..14 (15 is invalid).
    A known message without E2E passes on the frame checks alone. IMU_Rate has no CRC of its
    own: it passes on the frame checks and its counter, and is really checked with the
    IMU_Accel that follows it (check_imu_pair). IMU_Accel cannot be checked alone: ValueError.
    The counter sequence is the receiver's business (it needs the previous frame)."""
    if not _frame_ok(msg):
        return False
    try:
        msg_def = db.get_message_by_frame_id(msg.arbitration_id)
    except KeyError:
        return False
    if msg_def.name == IMU_PAIR[1]:
        raise ValueError(f"{msg_def.name}: its CRC also covers {IMU_PAIR[0]}; "
                         "use check_imu_pair()")
    e2e = e2e_signals(msg_def)
    if e2e is None:
        return True
    counter_sig, crc_sig = e2e
    if crc_sig is not None and msg.data[7] != e2e_crc(msg.arbitration_id, msg.data):
        return False
    return counter_sig is None or _counter_value(msg.data, counter_sig) <= E2E_COUNTER_MAX


def check_imu_pair(rate_msg: can.Message, accel_msg: can.Message, db=None) -> bool:
    """Check one IMU sample: rate_msg must be a valid IMU_Rate frame and accel_msg a valid
    IMU_Accel frame (standard ID, classic CAN, DLC 8), both with the same counter in 0..14,
    and IMU_Accel's byte 7 must be the pair CRC (imu_pair_crc)."""
    db = db if db is not None else DEFAULT_DB
    rate_def, accel_def = map(db.get_message_by_name, IMU_PAIR)
    if not (_frame_ok(rate_msg) and _frame_ok(accel_msg)):
        return False
    if (rate_msg.arbitration_id, accel_msg.arbitration_id) != (rate_def.frame_id,
                                                               accel_def.frame_id):
        return False
    if accel_msg.data[7] != imu_pair_crc(accel_def.frame_id, rate_msg.data, accel_msg.data):
        return False
    counter = _counter_value(rate_msg.data, e2e_signals(rate_def)[0])
    return (counter <= E2E_COUNTER_MAX
            and counter == _counter_value(accel_msg.data, e2e_signals(accel_def)[0]))


class E2EReceiver:
    """Checks received frames one by one as a receiver does: check_e2e for single frames;
    an IMU_Rate is held until the next IMU_Accel, and that IMU_Accel passes only if the two
    form a valid pair (check_imu_pair: same counter, pair CRC). An IMU_Accel without a held
    IMU_Rate fails; a held IMU_Rate that another IMU_Rate replaces was never confirmed.
    check() returns True for an IMU_Rate that passes the frame checks: its integrity is
    known only when its IMU_Accel arrives. The counter sequence is not checked."""

    def __init__(self, db=None):
        self.db = db if db is not None else DEFAULT_DB
        self._rate_id, self._accel_id = (self.db.get_message_by_name(n).frame_id
                                         for n in IMU_PAIR)
        self._held_rate = None

    def check(self, msg: can.Message) -> bool:
        if msg.arbitration_id == self._accel_id and not msg.is_extended_id:
            rate, self._held_rate = self._held_rate, None
            return rate is not None and check_imu_pair(rate, msg, self.db)
        ok = check_e2e(msg, self.db)
        if msg.arbitration_id == self._rate_id and not msg.is_extended_id:
            self._held_rate = msg if ok else None
        return ok


class ImuQuantizer:
    """Quantises IMU increments to the CAN LSBs, carrying each axis's remainder to the next
    sample:  raw_k = round(exact_k/LSB + carry_{k-1}),  carry_k = exact_k/LSB + carry_{k-1} - raw_k
    (carry kept in LSB units, |carry| <= 1/2), so the sum of the transmitted increments
    equals the sum of the exact ones within half an LSB at all times. The LSBs and the
    per-sample ranges default to the DBC's (ANGLE_LSB_RAD, VEL_LSB_MPS); a raw value whose
    physical value leaves the DBC range raises ValueError."""

    def __init__(self, angle_lsb_rad: float = ANGLE_LSB_RAD, vel_lsb_mps: float = VEL_LSB_MPS):
        self.angle_lsb_rad = angle_lsb_rad
        self.vel_lsb_mps = vel_lsb_mps
        self.angle_raw_range = self._raw_range(ANGLE_MIN_RAD, ANGLE_MAX_RAD, angle_lsb_rad)
        self.vel_raw_range = self._raw_range(VEL_MIN_MPS, VEL_MAX_MPS, vel_lsb_mps)
        self.carry_angle_lsb = [0.0, 0.0, 0.0]
        self.carry_vel_lsb = [0.0, 0.0, 0.0]

    @staticmethod
    def _raw_range(lo: float, hi: float, lsb: float) -> tuple:
        # the DBC writes the maximum with 15 significant digits: allow for that rounding
        return math.ceil(lo / lsb - 1e-6), math.floor(hi / lsb + 1e-6)

    @staticmethod
    def _step(exact: float, lsb: float, carry: list, axis: int, raw_range: tuple) -> int:
        total = float(exact) / lsb + carry[axis]
        if not math.isfinite(total):
            raise ValueError("IMU increment is not finite")
        raw = int(math.floor(total + 0.5))
        if not raw_range[0] <= raw <= raw_range[1]:
            raise ValueError(f"IMU increment {exact!r} exceeds the CAN range "
                             f"[{raw_range[0] * lsb}, {raw_range[1] * lsb}]")
        carry[axis] = total - raw
        return raw

    def quantize_angle(self, dtheta_rad: Iterable[float]) -> list:
        """Raw AngleIncX/Y/Z (units of angle_lsb_rad) for one sample's angle increments."""
        return [self._step(v, self.angle_lsb_rad, self.carry_angle_lsb, i, self.angle_raw_range)
                for i, v in enumerate(dtheta_rad)]

    def quantize_vel(self, dv_mps: Iterable[float]) -> list:
        """Raw VelIncX/Y/Z (units of vel_lsb_mps) for one sample's velocity increments."""
        return [self._step(v, self.vel_lsb_mps, self.carry_vel_lsb, i, self.vel_raw_range)
                for i, v in enumerate(dv_mps)]

    def signals(self, dtheta_rad: Iterable[float], dv_mps: Iterable[float]) -> tuple:
        """(IMU_Rate signals, IMU_Accel signals) in physical units, exact multiples of the
        LSBs, without counter, ImuFault and CRC (E2ESender.encode_imu_pair fills them)."""
        return self.raw_signals(self.quantize_angle(dtheta_rad), self.quantize_vel(dv_mps))

    def raw_signals(self, angle_raw: Iterable[int], vel_raw: Iterable[int]) -> tuple:
        """(IMU_Rate signals, IMU_Accel signals) of raw AngleIncX/Y/Z and VelIncX/Y/Z values
        (as quantize_angle and quantize_vel give them), in physical units."""
        rate = {name: raw * self.angle_lsb_rad for name, raw in zip(ANGLE_SIGNALS, angle_raw)}
        accel = {name: raw * self.vel_lsb_mps for name, raw in zip(VEL_SIGNALS, vel_raw)}
        return rate, accel


def write_candump(path, messages: Iterable[can.Message]) -> int:
    """Write messages to a candump -L style log through python-can's CanutilsLogWriter
    (.log; a .log.gz path is compressed). Returns the number of frames written."""
    n = 0
    with can.Logger(str(path)) as writer:
        for msg in messages:
            writer.on_message_received(msg)
            n += 1
    return n


#: A candump -L line as the firmware's log reader takes it (hal/common/candump.h, the
#: rule): "(" seconds "." 1..9 digits ")", an interface of 1..15 printable characters, a
#: classic frame ID#DATA (3 hex digits, or 8 for an extended ID, 0..8 data bytes as hex
#: pairs) and an optional direction R or T, blanks around. Everything else is malformed:
#: python-can would raise on some of it and change other lines silently (a 4-digit ID
#: becomes an extended one, 11 data bytes a frame of 11). A standard ID is at most 0x7FF,
#: an extended one below 2^29 (at or above it the CAN_ERR_FLAG: an error frame).
CANDUMP_LINE = re.compile(r"[ \t]*\([0-9]+\.[0-9]{1,9}\)[ \t]+[!-~]{1,15}[ \t]+"
                          r"(?:[0-7][0-9A-Fa-f]{2}|[01][0-9A-Fa-f]{7})#(?:[0-9A-Fa-f]{2}){0,8}"
                          r"(?:[ \t]+[RT])?[ \t\r]*")


class LogFile:
    """The frames of a CAN log file, through python-can's LogReader (candump .log, .asc,
    .blf, ...), as a context manager and an iterable of can.Message.

    A candump text log (.log) is read as the firmware reads one (navecu --can-log): blank
    lines are skipped, and a line that is not a classic CAN frame by CANDUMP_LINE's rule
    (garbage, bad or odd hex, more than 8 bytes, a remote, FD or error frame, bytes that
    are not UTF-8, a line cut short) is skipped and counted, never raised on nor changed:
    `malformed` is their number, `first_malformed` the first few as (line number, text),
    `note()` the line a tool prints. Other formats are python-can's business. A file that
    cannot be opened raises OSError."""

    KEEP = 5
    _line_ok = staticmethod(CANDUMP_LINE.fullmatch)

    def __init__(self, path):
        self.path = str(path)
        self.malformed = self.rejected = 0
        self.first_malformed: list = []
        self.first_rejected: list = []
        if self.path.endswith(".log"):
            self._fh = open(self.path, encoding="utf-8", errors="replace")
            self._reader = can.CanutilsLogReader(self._lines())
        else:
            self._fh = None
            self._reader = can.LogReader(self.path)

    def _lines(self):
        for lineno, line in enumerate(self._fh, 1):
            text = line.rstrip("\n")
            if not text.strip(" \t\r"):
                continue
            if self._line_ok(text):
                yield " ".join(text.split())  # python-can splits on single spaces only
                continue
            self.malformed += 1
            if len(self.first_malformed) < self.KEEP:
                self.first_malformed.append((lineno, text[:60]))

    def __iter__(self):
        return iter(self._reader)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
        else:
            self._reader.stop()

    def reject(self, msg: can.Message, why: str) -> None:
        """Count a frame of the log that the tool reading it cannot take (e.g. a known
        identifier with another length): `rejected`, the first few in `first_rejected`."""
        self.rejected += 1
        if len(self.first_rejected) < self.KEEP:
            self.first_rejected.append((msg.timestamp, msg.arbitration_id, why))

    def note(self) -> str:
        """'N malformed lines of FILE skipped (first: line L, 'text')', and the rejected
        frames if any, for a summary."""
        s = (f"{self.malformed} malformed line{'s' if self.malformed != 1 else ''} of "
             f"{self.path} skipped")
        if self.first_malformed:
            lineno, text = self.first_malformed[0]
            s += f" (first: line {lineno}, {text!r})"
        if self.rejected:
            t, ident, why = self.first_rejected[0]
            s += (f", {self.rejected} frame{'s' if self.rejected != 1 else ''} rejected "
                  f"(first: 0x{ident:03X} at {t:.6f} s, {why})")
        return s

    @property
    def skipped(self) -> int:
        """Malformed lines and rejected frames."""
        return self.malformed + self.rejected


def read_log(path, skipped: Optional[list] = None) -> list:
    """All frames of a log file python-can can read (candump .log, .asc, .blf, ...), a
    candump log's malformed lines skipped (LogFile); skipped: a list that gets the
    LogFile, for its count; without one a count above 0 is said on stderr."""
    with LogFile(path) as log:
        frames = list(log)
    if skipped is not None:
        skipped.append(log)
    elif log.skipped:
        print(f"read_log: {log.note()}", file=sys.stderr)
    return frames


# ---------------------------------------------------------------- the time-driven output
#: The ECU's one time-driven output (docs/can.md "NAV_Heartbeat"): sent every second of its
#: own uptime from power-on, whatever the input. Every other output is driven by the data,
#: so the same input gives the same frames from a file, over vcan and on the target; the
#: heartbeat differs between them by design (a live ECU sends it before the replay starts)
#: and every identity comparison of outputs leaves it out, through data_driven().
TIME_DRIVEN = ("NAV_Heartbeat",)


def time_driven_ids(db=None) -> frozenset:
    """The identifiers of the time-driven outputs in db (default: load_db(), the DBC's or
    the vehicle profile's chosen by select_vehicle)."""
    db = db if db is not None else load_db()
    return frozenset(db.get_message_by_name(n).frame_id for n in TIME_DRIVEN)


def _frame_id(item):
    """The identifier of a can.Message, a candump -L line ('(t) can0 ID#DATA') or an
    'ID#DATA' string; None for anything else."""
    if hasattr(item, "arbitration_id"):
        return item.arbitration_id
    token = next((t for t in item.split() if "#" in t), None)
    if token is None:
        return None
    try:
        return int(token.split("#", 1)[0], 16)
    except ValueError:
        return None


def data_driven(items: Iterable, db=None) -> list:
    """items (can.Message, candump -L lines or 'ID#DATA' strings, in order) without the frames of the
    time-driven outputs (TIME_DRIVEN): what must be identical between a file run, a live
    run and the target for the same input."""
    ids = time_driven_ids(db)
    return [x for x in items if _frame_id(x) not in ids]


def choice_value(message: str, signal: str, name: str, db=None) -> int:
    """The value of the DBC's enumeration name (VAL_) of a signal, e.g.
    choice_value("NAV_Calibration", "CalSource", "Filter")."""
    sig = (db or DEFAULT_DB).get_message_by_name(message).get_signal_by_name(signal)
    return next(int(k) for k, v in (sig.choices or {}).items() if str(v) == name)


# ---------------------------------------------------------------- NAV_Status, read back
def counter_max(db) -> dict:
    """NAV_Status: {signal: the largest value it can carry} of every Cnt* signal."""
    msg = db.get_message_by_name("NAV_Status")
    return {s.name: (1 << s.length) - 1 for s in msg.signals if s.name.startswith("Cnt")}


def status_signals(db) -> dict:
    """NAV_Status: {signal: page} of every Cnt* signal."""
    msg = db.get_message_by_name("NAV_Status")
    return {s.name: int(s.multiplexer_ids[0]) for s in msg.signals
            if s.name.startswith("Cnt") and s.multiplexer_ids}


def health_bits(db) -> dict:
    """{bit: (NAME, meaning)} of NAV_Status HealthFlags, from the DBC's value table
    HealthFlagBits (value 2^bit, text "NAME: meaning"): the same table the firmware's
    navecu_protocol.h is generated from (tools/gen_protocol.py)."""
    out = {}
    for value, text in db.dbc.value_tables["HealthFlagBits"].items():
        name, _, meaning = str(text).partition(":")
        out[int(value).bit_length() - 1] = (name.strip(), meaning.strip())
    return out


def health_flag(db, name: str) -> int:
    """The HealthFlags mask of the bit called name (e.g. "IMU_STALE")."""
    return next(1 << b for b, (n, _) in health_bits(db).items() if n == name)


def choices(db, msg: str, sig: str) -> dict:
    """{raw value: name} of a signal's value table in the DBC (empty without one)."""
    return {int(k): str(v) for k, v in
            (db.get_message_by_name(msg).get_signal_by_name(sig).choices or {}).items()}
