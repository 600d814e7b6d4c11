"""Vehicle profiles (vehicles/NAME.toml, docs/vehicles.md): the car's DBC, the messages
navecu reads from its bus, its geometry, and the identifiers navecu's own messages take on
it. Generates the firmware's vehicle layer and checks the identifiers for collisions.

    python -m tools.vehicle generate NAME OUT_DIR   veh_can.[ch] (cantools' C generator on the
                                                    car messages used), vehicle_profile.c
                                                    (firmware/vehicle/vehicle.h) and
                                                    navecu.dbc (the protocol with this
                                                    profile's identifiers); fails on a
                                                    collision
    python -m tools.vehicle check NAME [--ids stock] the collision report (exit 1 on any)
    python -m tools.vehicle dbc NAME OUT.dbc         navecu.dbc with this profile's identifiers

A collision is one of navecu's identifiers that the car uses on one of its buses: named in
the car's DBC for that bus, or seen in a recording of it (a DBC does not list every frame a
car sends). `--ids stock` checks the DBC's own identifiers instead of the profile's.
"""
from __future__ import annotations

import argparse
import re
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import can
import cantools
from cantools.database.can.c_source import camel_to_snake_case, generate as generate_c

from tools import navecu_can

ROOT = Path(__file__).resolve().parent.parent
VEHICLES = ROOT / "vehicles"
CODEC_DB = "veh_can"
#: m/s per unit of a wheel-speed signal
SPEED_UNITS = {"m/s": 1.0, "km/h": 1.0 / 3.6, "kph": 1.0 / 3.6, "mph": 0.44704}
#: rad/s per unit of a yaw-rate signal
RATE_UNITS = {"rad/s": 1.0, "deg/s": 3.141592653589793 / 180.0}


def _toyota_checksum(frame_id: int, data: bytearray) -> None:
    """Toyota: the last byte is ID bytes + DLC + the other bytes, modulo 256."""
    data[-1] = ((frame_id >> 8) + (frame_id & 0xFF) + len(data) + sum(data[:-1])) & 0xFF


def _subaru_checksum(frame_id: int, data: bytearray) -> None:
    """Subaru (global platform): the first byte is ID bytes + the other bytes, modulo 256."""
    data[0] = ((frame_id >> 8) + (frame_id & 0xFF) + sum(data[1:])) & 0xFF


def _honda_checksum(frame_id: int, data: bytearray) -> None:
    """Honda: the last byte's low nibble is 8 - the sum of every other nibble (the 11-bit
    identifier's and the data's), modulo 16."""
    nibbles = sum((b >> 4) + (b & 0xF) for b in data[:-1]) + (data[-1] >> 4)
    nibbles += (frame_id >> 8) + ((frame_id >> 4) & 0xF) + (frame_id & 0xF)
    data[-1] = (data[-1] & 0xF0) | ((8 - nibbles) & 0xF)


def _crc8h2f(crc: int, byte: int) -> int:
    """One byte into a CRC-8H2F (AUTOSAR: polynomial 0x2F, most significant bit first)."""
    crc ^= byte
    for _ in range(8):
        crc = ((crc << 1) ^ 0x2F) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


def _vw_mqb_checksum(frame_id: int, data: bytearray, data_ids: tuple) -> None:
    """Volkswagen MQB (AUTOSAR E2E profile 2): the first byte is the CRC-8H2F (initial value
    and final XOR 0xFF) of bytes 1.. and then the message's data ID for the frame's counter
    (byte 1's low nibble), data_ids[counter]. frame_id: in the data IDs, not summed."""
    crc = 0xFF
    for b in data[1:]:
        crc = _crc8h2f(crc, b)
    data[0] = _crc8h2f(crc, data_ids[data[1] & 0x0F]) ^ 0xFF


#: Hyundai/Kia WHL_SPD11's fields (byte, mask): its checksum's, least significant first
#: (Checksum_LSB, Checksum_MSB), and its rolling counter's (AliveCounter_LSB, _MSB)
_HKG_WHL_SPD_CHECKSUM = ((5, 0xC0), (7, 0xC0))
_HKG_WHL_SPD_COUNTER = ((1, 0xC0), (3, 0xC0))


def _hkg_whl_spd_checksum(frame_id: int, data: bytearray) -> None:
    """Hyundai/Kia WHL_SPD11 (opendbc's hyundai_kia_generic, 0x386): a 4-bit checksum split
    over the top 2 bits of bytes 5 (low half) and 7 (high half), the number of bits set
    in the frame but the top 2 bits of bytes 1, 3, 5 and 7 (its counter's and its own),
    XOR 9, modulo 16. frame_id: not in it."""
    skip = dict(_HKG_WHL_SPD_CHECKSUM + _HKG_WHL_SPD_COUNTER)
    ones = sum(bin(b & ~skip.get(i, 0) & 0xFF).count("1") for i, b in enumerate(data))
    _field_set(_HKG_WHL_SPD_CHECKSUM, data, (ones ^ 9) & 0xF)


def _field_get(fields: tuple, data) -> int:
    """The value of bit fields ((byte, mask), ...), least significant first, in data."""
    value, shift = 0, 0
    for byte, mask in fields:
        low = (mask & -mask).bit_length() - 1
        value |= ((data[byte] & mask) >> low) << shift
        shift += bin(mask).count("1")
    return value


def _field_set(fields: tuple, data: bytearray, value: int) -> None:
    """Write value into the bit fields ((byte, mask), ...), least significant first."""
    for byte, mask in fields:
        low = (mask & -mask).bit_length() - 1
        width = bin(mask).count("1")
        data[byte] = (data[byte] & ~mask & 0xFF) | (((value & ((1 << width) - 1)) << low) & mask)
        value >>= width


@dataclass(frozen=True)
class CarChecksum:
    """A car maker's frame checksum: fill(frame_id, data) writes it (the test encoder,
    CarEncoder), in its fields ((byte, mask), ... least significant first; byte -1 the
    last); the firmware checks it with vehicle_checksum_NAME
    (firmware/vehicle/vehicle_checksum.c). A keyed checksum also takes the message's data
    IDs (the profile's checksum_data_ids, data_ids of them): fill(frame_id, data, ids),
    and the firmware's function a table of them. length: the one frame length it is
    defined for (0: any). uncovered: other bits it does not see (Hyundai/Kia's counter):
    a flip there passes it."""
    fill: object
    fields: tuple
    data_ids: int = 0   # how many data IDs the message needs (0: none)
    length: int = 0
    uncovered: tuple = ()

    @property
    def width(self) -> int:
        """its bits"""
        return sum(bin(m).count("1") for _, m in self.fields)

    def get(self, data) -> int:
        return _field_get(self.fields, data)

    def put(self, data: bytearray, value: int) -> None:
        _field_set(self.fields, data, value)


#: the car makers' checksums a profile may name
CAR_CHECKSUMS = {"toyota": CarChecksum(_toyota_checksum, ((-1, 0xFF),)),
                 "subaru": CarChecksum(_subaru_checksum, ((0, 0xFF),)),
                 "honda": CarChecksum(_honda_checksum, ((-1, 0x0F),)),
                 "vw_mqb": CarChecksum(_vw_mqb_checksum, ((0, 0xFF),), 16),
                 "hkg_whl_spd": CarChecksum(_hkg_whl_spd_checksum, _HKG_WHL_SPD_CHECKSUM,
                                            length=8, uncovered=_HKG_WHL_SPD_COUNTER)}
CHECKSUMS = ("none",) + tuple(CAR_CHECKSUMS)
DIRECTIONS = {"signed": "VEHICLE_DIR_SIGNED", "gear": "VEHICLE_DIR_GEAR",
              "none": "VEHICLE_DIR_NONE"}
WHEELS = ("fl", "fr", "rl", "rr")
#: the axles of wheel speeds split over two messages ([wheels] messages = {front, rear}):
#: the role of each message's signal set, and its wheels (left, right), in WHEELS' order
AXLES = {"front": ("wheels_front", ("fl", "fr")), "rear": ("wheels_rear", ("rl", "rr"))}
#: the roles of the wheel speeds' message(s): one message, or one per axle
WHEEL_ROLES = ("wheels",) + tuple(role for role, _ in AXLES.values())


class ProfileError(ValueError):
    """A profile that cannot be used, with the reason."""


@dataclass(frozen=True)
class CarCounter:
    """A message's rolling counter: one DBC signal, or several that together make one
    number (Hyundai/Kia WHL_SPD11's AliveCounter_MSB and _LSB), most significant first."""
    parts: tuple   # cantools Signals

    @property
    def name(self) -> str:
        return "+".join(p.name for p in self.parts)

    @property
    def length(self) -> int:
        return sum(p.length for p in self.parts)

    def values(self, value: int) -> dict:
        """Each part's raw value for the counter's value."""
        out, shift = {}, 0
        for p in reversed(self.parts):
            out[p.name] = (value >> shift) & ((1 << p.length) - 1)
            shift += p.length
        return out


@dataclass
class CarSignalSet:
    """One car message navecu reads, and the signals it takes from it."""
    role: str               # "wheels" (or "wheels_front", "wheels_rear"), "gear", "yaw_rate"
    message: object         # cantools Message
    signals: list           # cantools Signals, in the firmware's order
    checksum: str = "none"
    counter: object = None  # the rolling counter (CarCounter), or None
    counter_modulus: int = 0   # it runs 0..modulus-1 (2^length unless the profile says)
    checksum_data_ids: tuple = ()  # a keyed checksum's data IDs (CarChecksum.data_ids)


@dataclass
class Profile:
    name: str
    description: str
    native_wheels: bool
    direction: str
    track_m: float
    wheelbase_m: float
    can_ids: dict                      # navecu message name -> identifier
    buses: dict = field(default_factory=dict)   # bus name -> cantools Database
    ecu_bus: str | None = None
    reads: list = field(default_factory=list)   # CarSignalSet
    speed_factor: float = 1.0          # m/s per wheel-signal unit
    wheel_step_mps: float = 0.0        # the wheel speed signal's resolution (DBC scale), m/s
    rate_factor: float = 1.0           # rad/s per yaw-rate unit, sign included
    gear_values: dict = field(default_factory=dict)  # raw gear value -> +1, -1, 0
    gear_hold: set = field(default_factory=set)      # raw gear values that keep the direction
    recordings: list = field(default_factory=list)   # (path, {channel: bus})
    dbc_notes: dict = field(default_factory=dict)    # bus -> what normalise_dbc changed

    @property
    def split_wheels(self) -> bool:
        """The wheel speeds come in two messages, one per axle (firmware/vehicle/vehicle_pair.h)."""
        return any(r.role in ("wheels_front", "wheels_rear") for r in self.reads)

    def wheel_reads(self) -> list:
        """The wheel speeds' signal set(s): one, or the front's and the rear's."""
        return [r for r in self.reads if r.role in WHEEL_ROLES]


# ------------------------------------------------------------------ loading a profile
def opendbc_text(ref: str) -> str:
    """A DBC of the pinned opendbc package (tools/requirements-data.txt): 'file.dbc' in
    its dbc/ folder, or a generator file 'generator/MAKE/file.dbc', whose IMPORT lines opendbc's
    own generator resolves."""
    try:
        import opendbc
    except ImportError as e:
        raise ProfileError("the opendbc package is not installed (make venv installs the pinned "
                           "one: tools/requirements-data.txt)") from e
    if ref.startswith("generator/"):
        name = Path(ref).stem + "_generated"
        generated = opendbc.get_generated_dbcs()
        if name not in generated:
            raise ProfileError(f"opendbc has no generator file {ref}")
        return generated[name]
    path = Path(opendbc.DBC_PATH) / ref
    if not path.is_file():
        raise ProfileError(f"opendbc has no {ref}")
    return path.read_text(encoding="utf-8")


#: a comment that names a signal's message but not the signal (`CM_ SG_ 304 "...";`) or
#: names no object (`CM_ 145 "...";`), or a network comment without its `;`
#: (`CM_ "Front target"`, toyota_radar_dsu_tssp.dbc): not DBC syntax, so cantools refuses
#: the whole file; opendbc's Honda generator files (_honda_common.dbc) and
#: hyundai_kia_generic.dbc have the first two
MALFORMED_COMMENT = re.compile(r'^CM_ (?:(?:SG_ )?\d+ "(?:[^"\\]|\\.)*";|"(?:[^"\\]|\\.)*")'
                               r'[ \t]*\r?\n', re.M)
#: a keyword followed by a message's identifier, wherever a DBC names a message by it
_DBC_ID_REF = re.compile(r'\b(BO_|VAL_|SG_|SIG_VALTYPE_|BO_TX_BU_|SG_MUL_VAL_|SIG_GROUP_|'
                         r'BU_BO_REL_[ \t]+\w+)([ \t]+)(\d+)\b')
_DBC_BO = re.compile(r'^[ \t]*BO_[ \t]+(\d+)[ \t]+(\w+)[ \t]*:', re.M)
_DBC_SG = re.compile(r'^[ \t]*SG_[ \t]+(\w+)\b')
_DBC_STRING = re.compile(r'("(?:[^"\\]|\\.)*")')
_DBC_STATEMENT = re.compile(r'^[ \t]*[A-Z][A-Z0-9_]*_\b')  # a line that starts a statement
_DBC_VAL_HEAD = re.compile(r'^VAL_[ \t]+(\d+)[ \t]+(\w+)\b')
_DBC_LEADING_POINT = re.compile(r'(?<![\w.])(-?)\.(\d)')
_DBC_DIGIT_NAME = re.compile(r'^([ \t]*BO_[ \t]+\d+[ \t]+|[ \t]*SG_[ \t]+)(\d\w*)', re.M)
_DBC_EXTENDED = 0x80000000


def _outside_strings(text: str, fn) -> str:
    """fn applied to the parts of text outside its quoted strings (comments, value names,
    units): they stay as they are."""
    parts = _DBC_STRING.split(text)
    return "".join(fn(p) if k % 2 == 0 else p for k, p in enumerate(parts))


def _val_statements(lines: list) -> list:
    """(first, last, closed) line indices of every VAL_ statement: it runs until a line
    with its ';' (outside strings) or up to the line before the next statement."""
    out, i = [], 0
    while i < len(lines):
        if not _DBC_VAL_HEAD.match(lines[i]):
            i += 1
            continue
        j = i
        while True:
            if ";" in _DBC_STRING.sub("", lines[j]):
                out.append((i, j, True))
                break
            if (j + 1 >= len(lines) or not lines[j + 1].strip()
                    or _DBC_STATEMENT.match(lines[j + 1])):
                out.append((i, j, False))
                break
            j += 1
        i = j + 1
    return out


def normalise_dbc(text: str) -> tuple:
    """(text, notes): what cantools refuses in opendbc's files and the DBC format does not
    leave in doubt, made DBC, each kind said once in notes with how many (`python -m
    tools.vehicle check` prints them). A frame's decoding is the file's own, and quoted
    strings (comments, value names, units) are left as they are:
    - malformed comments (MALFORMED_COMMENT) dropped;
    - an identifier above 0x7FF written without the extended-frame flag (bit 31): it can only
      be a 29-bit identifier, so the flag is set wherever the file names it (opendbc's
      convention; navecu reads 11-bit frames, so such a message is never one it reads, and
      cannot collide with its own); not where the file also has it with the flag (said);
    - a `VAL_` table's missing closing `;` added, and `VAL_` tables of signals the
      message does not have dropped (value names only);
    - numbers written without their leading zero (`.25`) in signal definitions;
    - message and signal names that begin with a digit (`2017_5`, not a DBC or C name)
      prefixed with `_`: a profile names them so (`_2017_5`)."""
    notes = []
    n = len(MALFORMED_COMMENT.findall(text))
    if n:
        text = MALFORMED_COMMENT.sub("", text)
        notes.append(f"{n} malformed comment(s) dropped")
    ids = {int(i) for i, _ in _DBC_BO.findall(text)}
    ext = {i for i in ids if 0x7FF < i < (1 << 29) and (i | _DBC_EXTENDED) not in ids}
    both = sorted(i for i in ids if 0x7FF < i < (1 << 29) and (i | _DBC_EXTENDED) in ids)
    if ext:
        text = _outside_strings(text, lambda s: _DBC_ID_REF.sub(
            lambda m: m[1] + m[2] + str(int(m[3]) | _DBC_EXTENDED) if int(m[3]) in ext
            else m[0], s))
        notes.append(f"{len(ext)} identifier(s) above 0x7FF taken as extended (29-bit)")
    if both:
        notes.append("identifier(s) above 0x7FF also present with the extended flag, left as "
                     f"they are: {', '.join(f'0x{i:X}' for i in both)}")
    lines = text.split("\n")
    signals, msg_id = set(), None
    for line in lines:
        bo, sg = _DBC_BO.match(line), _DBC_SG.match(line)
        if bo:
            msg_id = int(bo[1])
        elif sg and msg_id is not None:
            signals.add((msg_id, sg[1]))
        elif line.strip() and not line.startswith((" ", "\t")):
            msg_id = None
    closed, stale, drop = 0, set(), set()
    for first, last, ok in _val_statements(lines):
        head = _DBC_VAL_HEAD.match(lines[first])
        if (int(head[1]), head[2]) not in signals:
            stale.add(head[2])
            drop.update(range(first, last + 1))
        elif not ok:
            lines[last] = lines[last].rstrip("\r").rstrip() + " ;" + (
                "\r" if lines[last].endswith("\r") else "")
            closed += 1
    if closed:
        notes.append(f"{closed} value table(s) without their closing ; closed")
    if stale:
        notes.append(f"{len([1 for _ in stale])} value table(s) of signals that do not exist "
                     f"dropped ({', '.join(sorted(stale))})")
    lines = [s for k, s in enumerate(lines) if k not in drop]
    fixed = 0
    for i, line in enumerate(lines):
        if _DBC_SG.match(line):
            new = _outside_strings(line, lambda s: _DBC_LEADING_POINT.sub(r"\g<1>0.\2", s))
            fixed += new != line
            lines[i] = new
    text = "\n".join(lines)
    if fixed:
        notes.append(f"{fixed} signal(s) with numbers like .25 read as 0.25")
    names = sorted({m[2] for m in _DBC_DIGIT_NAME.finditer(text)})
    taken = sorted(n for n in names if re.search(r'(?<!\w)_' + re.escape(n) + r'\b', text))
    if taken:
        notes.append(f"name(s) beginning with a digit whose _ name is taken, left as they are "
                     f"(cantools refuses them): {', '.join(taken)}")
        names = [n for n in names if n not in taken]
    if names:
        rename = re.compile(r'(?<!\w)(' + "|".join(map(re.escape, names)) + r')\b')
        text = _outside_strings(text, lambda s: rename.sub(r"_\1", s))
        notes.append(f"name(s) beginning with a digit prefixed with _: {', '.join(names)}")
    return text, notes


def load_dbc(ref: str, notes: list | None = None):
    """'opendbc:PATH' (the opendbc package) or a path in the repository, normalised
    (normalise_dbc; what it changed is appended to notes)."""
    if ref.startswith("opendbc:"):
        text = opendbc_text(ref.split(":", 1)[1])
    else:
        path = ROOT / ref
        if not path.is_file():
            raise ProfileError(f"DBC {ref} not found")
        text = path.read_text(encoding="utf-8")
    text, changed = normalise_dbc(text)
    if notes is not None:
        notes.extend(changed)
    try:
        return cantools.database.load_string(text, database_format="dbc", strict=False)
    except Exception as e:  # cantools raises several kinds for a malformed DBC
        raise ProfileError(f"DBC {ref} does not load: {e}") from e


def _message(db, name: str, where: str):
    """A message navecu reads: an 11-bit identifier, at most 8 bytes. (A DBC may declare
    a message of 8 bytes or fewer CAN FD, as Ford's does every message of its powertrain
    bus, which its CAN cars send as classic frames: its layout is a classic frame's.)"""
    try:
        msg = db.get_message_by_name(name)
    except KeyError as e:
        raise ProfileError(f"{where}: no message {name} in the car's DBC") from e
    if msg.is_extended_frame or msg.length > 8:
        raise ProfileError(f"{where}: {name} is "
                           + ("an extended (29-bit) frame" if msg.is_extended_frame
                              else f"a CAN FD frame of {msg.length} bytes")
                           + "; navecu reads classic CAN frames with 11-bit identifiers")
    return msg


def _signal(msg, name: str, where: str):
    try:
        return msg.get_signal_by_name(name)
    except KeyError as e:
        raise ProfileError(f"{where}: message {msg.name} has no signal {name}") from e


def _ids(spec: dict) -> dict:
    """navecu's identifiers: the DBC's, moved by `base` (the messages in DBC order from it)
    and then by the per-message map."""
    db = navecu_can.load_db(navecu_can.DBC_PATH)
    ids = {m.name: m.frame_id for m in db.messages}
    base = spec.get("base")
    if base is not None:
        ids = {m.name: int(base) + i for i, m in enumerate(db.messages)}
    for name, value in spec.items():
        if name == "base":
            continue
        if name not in ids:
            raise ProfileError(f"can_ids: navecu has no message {name}")
        ids[name] = int(value)
    bad = [f"{n}=0x{v:X}" for n, v in ids.items() if not 0 <= v <= 0x7FF]
    if bad:
        raise ProfileError(f"can_ids: not 11-bit identifiers: {', '.join(bad)}")
    seen = {}
    for n, v in ids.items():
        if v in seen:
            raise ProfileError(f"can_ids: {n} and {seen[v]} share 0x{v:03X}")
        seen[v] = n
    for label, v in uds_ids().items():
        if v in seen:
            raise ProfileError(f"can_ids: {seen[v]} = 0x{v:03X} is the {label}: navecu would "
                               "refuse to start (move the message, or the UDS IDs)")
    return ids


#: what a profile's tables may hold: key -> (required, type(s)); a key not listed is refused
#: (a misspelt `checksum` would otherwise leave the checksum unchecked without a word)
_NUM = (int, float)
#: the keys of every table that reads a car message: its checksum and rolling counter
_STR_OR_LIST = (str, list)
_MSG_CHECKS = {"checksum": (False, str), "checksum_data_ids": (False, list),
               "counter": (False, _STR_OR_LIST), "counter_modulus": (False, int)}
SCHEMA = {
    "": {"name": (True, str), "description": (False, str), "ecu_bus": (False, str),
         "buses": (False, dict), "wheels": (True, dict), "gear": (False, dict),
         "yaw_rate": (False, dict), "geometry": (True, dict), "can_ids": (False, dict),
         "recordings": (False, list)},
    "wheels": {"native": (False, bool), "direction": (False, str), "message": (False, str),
               "messages": (False, dict), "signals": (False, dict), "unit": (False, str), "scale": (False, _NUM),
               **_MSG_CHECKS, "range": (False, list)},
    "gear": {"message": (True, str), "signal": (True, str), "forward": (False, list),
             "reverse": (True, list), "stopped": (False, list), "hold": (False, list),
             **_MSG_CHECKS},
    "yaw_rate": {"message": (True, str), "signal": (True, str), "unit": (False, str),
                 "left_positive": (False, bool), **_MSG_CHECKS, "range": (False, list)},
    "geometry": {"track_m": (True, _NUM), "wheelbase_m": (True, _NUM)},
    "recordings": {"file": (True, str), "channels": (True, dict)},
}
_TYPE_NAMES = {str: "a string", dict: "a table", list: "a list", bool: "true or false",
               _NUM: "a number", int: "an integer",
               _STR_OR_LIST: "a signal name or a list of them"}


def _check_table(tab, schema: dict, where: str) -> None:
    if not isinstance(tab, dict):
        raise ProfileError(f"{where} must be a table")
    for key, value in tab.items():
        if key not in schema:
            raise ProfileError(f"{where}: unknown key {key!r} (known: {', '.join(schema)})")
        typ = schema[key][1]
        if not isinstance(value, typ) or (typ is not bool and isinstance(value, bool)):
            raise ProfileError(f"{where}: {key} must be {_TYPE_NAMES[typ]}, not {value!r}")
    for key, (required, _) in schema.items():
        if required and key not in tab:
            raise ProfileError(f"{where} needs {key}")


def _check_shape(t: dict, fname: str) -> None:
    """Every table's keys and value types (SCHEMA), before anything is read from them."""
    _check_table(t, SCHEMA[""], fname)
    for sect in ("wheels", "gear", "yaw_rate", "geometry"):
        if sect in t:
            _check_table(t[sect], SCHEMA[sect], f"{fname} [{sect}]")
    w = t["wheels"]
    if w.get("native", False):
        for key in (*_MSG_CHECKS, "message", "messages"):
            if key in w:
                raise ProfileError(f"{fname} [wheels]: {key} is for a car message; navecu's "
                                   "WheelSpeeds (native = true) carry their own E2E CRC and "
                                   "counter")
    else:
        if ("message" in w) == ("messages" in w):
            raise ProfileError(f"{fname} [wheels] needs either message (one message for the "
                               "four wheels) or messages = {front = ..., rear = ...} (one per "
                               "axle), not " + ("both" if "message" in w else "neither")
                               + " (or native = true)")
        if "messages" in w and (sorted(w["messages"]) != sorted(AXLES) or not all(
                isinstance(v, str) for v in w["messages"].values())):
            raise ProfileError(f"{fname} [wheels]: messages must name the two axles' messages, "
                               "{front = ..., rear = ...}, not " + repr(w["messages"]))
        if "signals" not in w:
            raise ProfileError(f"{fname} [wheels] needs signals (or native = true)")
        if sorted(w["signals"]) != sorted(WHEELS) or not all(
                isinstance(v, str) for v in w["signals"].values()):
            raise ProfileError(f"{fname} [wheels]: signals must name the four wheels' signals, "
                               f"{{{', '.join(k + ' = ...' for k in WHEELS)}}}")
    for key in ("forward", "reverse", "stopped"):
        if not all(isinstance(v, str) for v in t.get("gear", {}).get(key, [])):
            raise ProfileError(f"{fname} [gear]: {key} must be a list of the DBC's value names")
    if not all(isinstance(v, (str, int)) and not isinstance(v, bool)
               for v in t.get("gear", {}).get("hold", [])):
        raise ProfileError(f"{fname} [gear]: hold must be a list of the DBC's value names or "
                           "raw values")
    for i, rec in enumerate(t.get("recordings", [])):
        _check_table(rec, SCHEMA["recordings"], f"{fname} [[recordings]] {i + 1}")
    for key, value in t.get("buses", {}).items():
        if not isinstance(value, str):
            raise ProfileError(f"{fname} [buses]: {key} must be a DBC (a string)")
    for key, value in t.get("can_ids", {}).items():
        if not isinstance(value, int) or isinstance(value, bool):
            raise ProfileError(f"{fname} [can_ids]: {key} must be an integer (0x6C0, not a "
                               f"string), not {value!r}")


def load(name: str) -> Profile:
    path = VEHICLES / f"{name}.toml"
    if not path.is_file():
        known = ", ".join(sorted(p.stem for p in VEHICLES.glob("*.toml")))
        raise ProfileError(f"no vehicle profile {name} (vehicles/: {known})")
    try:
        t = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise ProfileError(f"{path.name}: not TOML: {e}") from e
    if t.get("name") != name:
        raise ProfileError(f"{path.name}: name must be {name!r}")
    _check_shape(t, path.name)
    wheels = t.get("wheels", {})
    geo = t.get("geometry", {})
    try:
        p = Profile(name=name, description=str(t.get("description", "")),
                    native_wheels=bool(wheels.get("native", False)),
                    direction=str(wheels.get("direction", "signed")),
                    track_m=float(geo["track_m"]), wheelbase_m=float(geo["wheelbase_m"]),
                    can_ids=_ids(t.get("can_ids", {})))
    except KeyError as e:
        raise ProfileError(f"{path.name}: [geometry] needs {e}") from e
    except ProfileError as e:
        raise ProfileError(f"{path.name}: {e}") from e
    if p.direction not in DIRECTIONS:
        raise ProfileError(f"{path.name}: direction must be one of {', '.join(DIRECTIONS)}")
    for what, value, lo, hi in (("track_m", p.track_m, 0.5, 3.0),
                                ("wheelbase_m", p.wheelbase_m, 1.0, 6.0)):
        if not lo < value < hi:
            raise ProfileError(f"{path.name}: [geometry] {what} = {value:g} m is not a car's "
                               f"(between {lo:g} and {hi:g} m)")
    for bus, ref in t.get("buses", {}).items():
        p.dbc_notes[bus] = []
        p.buses[bus] = load_dbc(ref, p.dbc_notes[bus])
    p.ecu_bus = t.get("ecu_bus")
    if p.native_wheels:
        if p.direction != "signed":
            raise ProfileError(f"{path.name}: navecu's WheelSpeeds are signed")
        ws = navecu_can.load_db(navecu_can.DBC_PATH).get_message_by_name("WheelSpeeds")
        p.wheel_step_mps = abs(float(ws.signals[0].scale))  # navecu.dbc: m/s
    else:
        _car_reads(p, t, path.name)
    for rec in t.get("recordings", []):
        f = ROOT / rec["file"]
        if not f.is_file():
            raise ProfileError(f"{path.name}: recording {rec['file']} not found")
        p.recordings.append((f, dict(rec["channels"])))
    return p


def _car_reads(p: Profile, t: dict, fname: str) -> None:
    if p.ecu_bus not in p.buses:
        raise ProfileError(f"{fname}: ecu_bus must name one of [buses]")
    db = p.buses[p.ecu_bus]
    w = t["wheels"]
    # (role, message, its wheels): one message for the four, or one per axle, each axle's
    # signals in its own message
    if "messages" in w:
        if w["messages"]["front"] == w["messages"]["rear"]:
            raise ProfileError(f"{fname} [wheels]: messages names {w['messages']['front']} for "
                               "both axles: one message for the four wheels is `message`")
        parts = [(role, _message(db, w["messages"][axle], f"{fname} [wheels] {axle} axle"),
                  wheels, f"{fname} [wheels] {axle} axle") for axle, (role, wheels) in AXLES.items()]
    else:
        parts = [("wheels", _message(db, w["message"], f"{fname} [wheels]"), WHEELS,
                  f"{fname} [wheels]")]
    part_sigs = [[_signal(msg, w["signals"][k], where) for k in wheels]
                 for _, msg, wheels, where in parts]
    sigs = [sig for ps in part_sigs for sig in ps]
    _range_override(w, sigs, f"{fname} [wheels]")
    unit = w.get("unit", "m/s")
    if unit not in SPEED_UNITS:
        hint = (" (an angular speed: unit = \"m/s\" and scale = the tyre's rolling radius "
                "in m)" if str(unit).lower() in DBC_ANGULAR_UNITS else "")
        raise ProfileError(f"{fname}: wheel unit must be one of {', '.join(SPEED_UNITS)}"
                           + hint)
    _check_dbc_unit(sigs, unit, "scale" in w, f"{fname} [wheels]")
    p.speed_factor = SPEED_UNITS[unit] * float(w.get("scale", 1.0))
    p.wheel_step_mps = abs(float(sigs[0].scale)) * p.speed_factor
    _check_wheel_range(sigs, p.speed_factor, p.direction == "signed", f"{fname} [wheels]")
    for (role, msg, _, _), ps in zip(parts, part_sigs):
        p.reads.append(_signal_set(role, w, msg, ps, fname))
    if p.direction == "gear":
        g = t.get("gear")
        if g is None:
            raise ProfileError(f"{fname}: direction 'gear' needs a [gear] table")
        gmsg = _message(db, g["message"], f"{fname} [gear]")
        gsig = _signal(gmsg, g["signal"], f"{fname} [gear]")
        # a DBC may give one name to several raw values (VW's GE_Fahrstufe: 13 and 14 are
        # both "T"): a name in the profile stands for all of them
        names = {}
        for k, v in (gsig.choices or {}).items():
            names.setdefault(str(v), []).append(int(k))
        for key, sign in (("forward", 1), ("reverse", -1), ("stopped", 0)):
            for n in g.get(key, []):
                if n not in names:
                    raise ProfileError(f"{fname} [gear]: {gsig.name} has no value {n!r} "
                                       f"(the DBC's: {', '.join(names)})")
                for raw in names[n]:
                    p.gear_values[raw] = sign
        if -1 not in p.gear_values.values():
            raise ProfileError(f"{fname} [gear]: no reverse gear named")
        # values during which the direction is kept (a shift in progress): the DBC's names,
        # or raw values where it names none (mazda_2017's 0, "shifting" in a comment only)
        lo = gsig.minimum if gsig.minimum is not None else _raw_span(gsig)[0]
        hi = gsig.maximum if gsig.maximum is not None else _raw_span(gsig)[1]
        rlo, rhi = _raw_bits(gsig)
        for n in g.get("hold", []):
            raws = names.get(n) if isinstance(n, str) else [n]
            if raws is None or not all(rlo <= r <= rhi and
                                       lo <= gsig.offset + gsig.scale * r <= hi and
                                       r not in p.gear_values for r in raws):
                raise ProfileError(f"{fname} [gear]: hold {n!r} is not a value of {gsig.name} "
                                   "that no other list names (the DBC's names, or a raw "
                                   f"value its {gsig.length} bits and its range [{lo:g}, {hi:g}] "
                                   "hold)")
            p.gear_hold.update(raws)
        p.reads.append(_signal_set("gear", g, gmsg, [gsig], fname))
    y = t.get("yaw_rate")
    if y is not None:
        ymsg = _message(db, y["message"], f"{fname} [yaw_rate]")
        ysig = _signal(ymsg, y["signal"], f"{fname} [yaw_rate]")
        _range_override(y, [ysig], f"{fname} [yaw_rate]")
        unit = y.get("unit", "rad/s")
        if unit not in RATE_UNITS:
            raise ProfileError(f"{fname}: yaw-rate unit must be one of {', '.join(RATE_UNITS)}")
        p.rate_factor = RATE_UNITS[unit] * (1.0 if y.get("left_positive", True) else -1.0)
        p.reads.append(_signal_set("yaw_rate", y, ymsg, [ysig], fname))
    ids = [r.message.frame_id for r in p.reads]
    if len(set(ids)) != len(ids):
        raise ProfileError(f"{fname}: wheels (each axle's), gear and yaw rate must be "
                           "different messages")


#: the wheel-speed units DBCs write (lower case), as the profile's `unit` names them; an
#: angular speed needs the tyre's rolling radius as `scale`
DBC_SPEED_UNITS = {"m/s": "m/s", "km/h": "km/h", "kph": "km/h", "kmh": "km/h",
                   "unit_kilometerperhour": "km/h", "mph": "mph", "unit_milesperhour": "mph"}
DBC_ANGULAR_UNITS = ("rad/s", "rpm", "1/min", "unit_radianpersecond")


def _check_dbc_unit(sigs: list, unit: str, scaled: bool, where: str) -> None:
    """The profile's wheel unit against the unit the DBC gives the signals, where the DBC
    gives one this knows: `unit = "m/s"` on a km/h signal would make every speed 3.6 times
    too large without a word. A DBC whose unit is wrong needs a corrected copy."""
    for sig in sigs:
        dbc = (sig.unit or "").strip().lower()
        if dbc in DBC_ANGULAR_UNITS and not scaled:
            raise ProfileError(f"{where}: {sig.name} is an angular speed ({sig.unit}): give "
                               f"unit = \"m/s\" and scale = the tyre's rolling radius in m"
                               + (" / 9.549 (rpm to rad/s)" if dbc != "rad/s"
                                  and "radian" not in dbc else ""))
        known = DBC_SPEED_UNITS.get(dbc)
        if known is not None and SPEED_UNITS[known] != SPEED_UNITS[unit]:
            raise ProfileError(f"{where}: unit = {unit!r}, but the DBC gives {sig.name} in "
                               f"{sig.unit}")


def _raw_bits(sig) -> tuple:
    """The raw values a signal's bits can hold."""
    if sig.is_signed:
        return -(1 << (sig.length - 1)), (1 << (sig.length - 1)) - 1
    return 0, (1 << sig.length) - 1


def _raw_span(sig) -> tuple:
    """The physical values a signal's bits can hold (DBC units)."""
    lo, hi = _raw_bits(sig)
    a, b = sig.offset + sig.scale * lo, sig.offset + sig.scale * hi
    return (min(a, b), max(a, b))


def _range_override(spec: dict, sigs: list, where: str) -> None:
    """`range = [lo, hi]` (the signal's DBC units) replaces the DBC's [min|max] of the
    table's signal(s) where that is wrong (a placeholder): the generated decoder's range
    check then uses it. It must lie within what the signal's bits can hold."""
    r = spec.get("range")
    if r is None:
        return
    if (not isinstance(r, list) or len(r) != 2 or
            not all(isinstance(x, (int, float)) for x in r) or not r[0] < r[1]):
        raise ProfileError(f"{where}: range must be [lo, hi] with lo < hi")
    for sig in sigs:
        lo, hi = _raw_span(sig)
        eps = 1e-9 * max(1.0, abs(lo), abs(hi))
        if r[0] < lo - eps or r[1] > hi + eps:
            raise ProfileError(f"{where}: range {r} is beyond what {sig.name}'s "
                               f"{sig.length} bits hold ([{lo:g}, {hi:g}])")
        sig.minimum, sig.maximum = float(r[0]), float(r[1])


#: a wheel speed's range that ends below this (m/s; 150 km/h) while its bits hold more is
#: taken for a DBC placeholder (opendbc's mazda_2017 gives RL [0|15] km/h): it would refuse
#: that wheel's frames above it
WHEEL_RANGE_MIN_MPS = 150.0 / 3.6
#: signed wheel speeds (direction = "signed") must take reversing down to this (m/s)
WHEEL_RANGE_REVERSE_MPS = -5.0


def _check_wheel_range(sigs: list, factor: float, signed: bool, where: str) -> None:
    """Every wheel signal's range (the DBC's, or `range`) must take a standing car (0),
    a car's speeds (up to WHEEL_RANGE_MIN_MPS at least) and, for signed speeds, reversing
    (down to WHEEL_RANGE_REVERSE_MPS), wherever its bits can hold them: else the profile
    must say `range` (a placeholder range would refuse good frames)."""
    for sig in sigs:
        lo, hi = _raw_span(sig)
        eps = 1e-9 * max(1.0, abs(lo), abs(hi))
        top = hi if sig.maximum is None else float(sig.maximum)
        bottom = lo if sig.minimum is None else float(sig.minimum)
        k = abs(factor)
        why = None
        if top * k < min(WHEEL_RANGE_MIN_MPS, hi * k) - eps * k:
            why = f"speeds above {top * k * 3.6:.0f} km/h"
        elif bottom > eps and lo <= 0.0:
            why = "a standing car"
        elif signed and bottom * k > max(WHEEL_RANGE_REVERSE_MPS, lo * k) + eps * k:
            why = f"reversing faster than {-bottom * k * 3.6:.0f} km/h"
        if why is not None:
            raise ProfileError(
                f"{where}: {sig.name}'s range [{bottom:g}, {top:g}] {sig.unit or ''} refuses "
                f"{why} (a DBC placeholder?); give range = [lo, hi] (its bits hold "
                f"[{lo:g}, {hi:g}])")


#: the widest rolling counter (bits): its raw value is a uint8_t in the generated codec
COUNTER_MAX_BITS = 8


def _counter(spec: dict, msg, data_sigs: list, where: str, checksum: str) -> tuple:
    """(CarCounter, modulus) of the table's `counter`, the message's rolling counter, or
    (None, 0). It is a DBC signal of the message, or a list of them that together make
    one number, most significant first (Hyundai/Kia's counter split over two 2-bit
    fields); each unsigned, unscaled, none of the values read and none of the checksum's
    bits (a checksum taken for a counter would refuse a good frame whenever it repeats),
    at most COUNTER_MAX_BITS bits together; it runs 0..modulus-1, modulus = 2^its length
    (the DBC's) unless `counter_modulus` says otherwise (2..2^length: 15 for a 4-bit
    counter that never sends 15)."""
    names = spec.get("counter")
    if names is None:
        if "counter_modulus" in spec:
            raise ProfileError(f"{where}: counter_modulus without a counter")
        return None, 0
    if isinstance(names, str):
        names = [names]
    if not names or not all(isinstance(n, str) for n in names) or len(set(names)) != len(names):
        raise ProfileError(f"{where}: counter must be a signal name or a list of different "
                           f"ones, not {names!r}")
    parts = []
    for name in names:
        sig = _signal(msg, name, where)
        if any(sig is d for d in data_sigs):
            raise ProfileError(f"{where}: counter {name} is a signal the profile reads as a "
                               "value")
        if sig.length > COUNTER_MAX_BITS:
            raise ProfileError(f"{where}: counter {name} has {sig.length} bits; at most "
                               f"{COUNTER_MAX_BITS} are supported")
        if sig.is_signed or sig.scale != 1 or sig.offset != 0 or sig.is_float:
            raise ProfileError(f"{where}: counter {name} must be an unsigned integer signal "
                               f"(scale 1, offset 0), not {'signed ' if sig.is_signed else ''}"
                               f"({sig.scale:g}, {sig.offset:g})")
        if checksum != "none":
            bits = _bits_of(msg, [sig])
            if any(bits.get(byte % msg.length, 0) & mask
                   for byte, mask in CAR_CHECKSUMS[checksum].fields):
                raise ProfileError(f"{where}: counter {name} overlaps the {checksum} "
                                   "checksum's bits")
        parts.append(sig)
    counter = CarCounter(tuple(parts))
    if not 1 <= counter.length <= COUNTER_MAX_BITS:
        raise ProfileError(f"{where}: counter {counter.name} has {counter.length} bits; at "
                           f"most {COUNTER_MAX_BITS} are supported")
    full = 1 << counter.length
    modulus = spec.get("counter_modulus", full)
    if not 2 <= modulus <= full:
        raise ProfileError(f"{where}: counter_modulus {modulus} is not 2..{full} (what "
                           f"{counter.name}'s {counter.length} bits count through)")
    return counter, int(modulus)


def _checksum(spec: dict, fname: str, msg=None) -> str:
    c = spec.get("checksum", "none")
    if c not in CHECKSUMS:
        raise ProfileError(f"{fname}: checksum must be one of {', '.join(CHECKSUMS)}")
    need = CAR_CHECKSUMS[c].length if c != "none" else 0
    if need and msg is not None and msg.length != need:
        raise ProfileError(f"{fname}: the {c} checksum is defined for {need}-byte frames; "
                           f"{msg.name} has {msg.length}")
    return c


def _data_ids(spec: dict, checksum: str, msg, role: str, where: str) -> tuple:
    """The table's checksum_data_ids: as many bytes as its keyed checksum needs, and only
    with one; one message's (an axle's half would need its own)."""
    ids = spec.get("checksum_data_ids")
    n = CAR_CHECKSUMS[checksum].data_ids if checksum != "none" else 0
    if n == 0:
        if ids is not None:
            raise ProfileError(f"{where}: checksum_data_ids is for a keyed checksum "
                               f"({', '.join(k for k, c in CAR_CHECKSUMS.items() if c.data_ids)})"
                               f", not {checksum}")
        return ()
    if role in ("wheels_front", "wheels_rear"):
        raise ProfileError(f"{where}: a keyed checksum on wheel speeds split over two "
                           "messages is not supported (each message has its own data IDs)")
    if msg.length < 2:
        raise ProfileError(f"{where}: the {checksum} checksum needs a counter byte after its "
                           f"own: {msg.name} has {msg.length} byte(s)")
    if ids is None:
        raise ProfileError(f"{where}: the {checksum} checksum needs checksum_data_ids, its "
                           f"{n} data IDs of {msg.name} (one per counter value)")
    if len(ids) != n or any(isinstance(x, bool) or not isinstance(x, int) or not 0 <= x <= 255
                            for x in ids):
        raise ProfileError(f"{where}: checksum_data_ids must be {n} bytes (0..255), not "
                           f"{ids!r}")
    return tuple(ids)


def _bits_of(msg, sigs) -> dict:
    """{byte: mask} of the bits the signals sigs take in msg."""
    raw = {x.name: 0 for x in msg.signals}
    for sig in sigs:
        raw[sig.name] = (1 << sig.length) - 1
    data = msg.encode(raw, scaling=False, strict=False, padding=False)
    return {i: b for i, b in enumerate(data) if b}


def _fixed_layout(checksum: str, msg, counter, where: str) -> None:
    """A checksum defined for one message's layout (CarChecksum.length: Hyundai/Kia's
    WHL_SPD11) needs that layout: a signal of the message on each of its fields, and the
    bits it does not cover (the rolling counter's) the profile's counter, which then checks
    them: named on another message of that length it would refuse every frame, and a
    counter left unnamed would go unchecked."""
    cs = CAR_CHECKSUMS.get(checksum)
    if cs is None or cs.length == 0:
        return
    for byte, mask in cs.fields:
        if not any(_bits_of(msg, [x]) == {byte % msg.length: mask} for x in msg.signals):
            raise ProfileError(f"{where}: the {checksum} checksum is in byte {byte}'s bits "
                               f"0x{mask:02X}, where {msg.name} has no signal of its own")
    want = {}
    for byte, mask in cs.uncovered:
        want[byte % msg.length] = want.get(byte % msg.length, 0) | mask
    if want and (counter is None or _bits_of(msg, counter.parts) != want):
        raise ProfileError(f"{where}: the {checksum} checksum does not cover "
                           + ", ".join(f"byte {b}'s bits 0x{m:02X}" for b, m in want.items())
                           + f": name {msg.name}'s rolling counter there as `counter`")


def _signal_set(role: str, spec: dict, msg, sigs: list, fname: str) -> CarSignalSet:
    """The message of the profile's table `role` (spec) and the signals read from it, with
    its checksum (and a keyed checksum's data IDs) and rolling counter."""
    where = f"{fname} [{role}]"
    checksum = _checksum(spec, where, msg)
    counter, modulus = _counter(spec, msg, sigs, where, checksum)
    _fixed_layout(checksum, msg, counter, where)
    return CarSignalSet(role, msg, sigs, checksum, counter, modulus,
                        checksum_data_ids=_data_ids(spec, checksum, msg, role, where))


# ----------------------------------------------------------------------- collisions
@dataclass
class Collision:
    can_id: int
    navecu: str
    bus: str
    what: str      # the car's message name, or "not in the DBC"
    source: str    # "DBC" or a recording's file name
    frames: int = 0
    rate_hz: float = 0.0

    def line(self) -> str:
        seen = f", {self.frames} frames, {self.rate_hz:.1f} Hz" if self.frames else ""
        return (f"0x{self.can_id:03X} {self.navecu}: {self.bus} bus, {self.what} "
                f"({self.source}{seen})")


def recorded_ids(path: Path, channels: dict) -> dict:
    """{(bus, id): (frames, rate Hz, DLCs)} of a candump recording (python-can reads it;
    malformed lines skipped and their count said on stderr, navecu_can.LogFile); a file
    python-can has no reader for, or whose reader fails, is a ProfileError."""
    per = {}
    t0 = t1 = None
    try:
        with navecu_can.LogFile(path) as log:
            msgs = list(log)
    except (OSError, ValueError) as e:
        raise ProfileError(f"recording {path}: not a CAN log it can read: "
                           f"{type(e).__name__}: {e}") from None
    if log.skipped:
        print(f"vehicle: {log.note()}", file=sys.stderr)
    for msg in msgs:
        if msg.is_error_frame or msg.is_extended_id:
            continue
        bus = channels.get(str(msg.channel))
        if bus is None:
            continue
        n, dlcs = per.get((bus, msg.arbitration_id), (0, set()))
        dlcs.add(msg.dlc)
        per[(bus, msg.arbitration_id)] = (n + 1, dlcs)
        t0 = msg.timestamp if t0 is None else t0
        t1 = msg.timestamp
    span = (t1 - t0) if t0 is not None and t1 > t0 else 1.0
    return {k: (n, n / span, d) for k, (n, d) in per.items()}


def uds_ids() -> dict:
    """The UDS server's request and response IDs (their defaults in the parameter table,
    firmware/app/params.toml), checked against the car's buses like navecu's messages."""
    from tools import gen_params
    by_name = {q["name"]: q for q in gen_params.load()}
    return {"UDS request (uds_request_id)": int(by_name["uds_request_id"]["default"]),
            "UDS response (uds_response_id)": int(by_name["uds_response_id"]["default"])}


def collisions(p: Profile, ids: dict | None = None) -> list:
    """Every identifier of navecu's (the profile's, or ids) the car uses on a bus."""
    ids = p.can_ids if ids is None else ids
    by_id = {v: k for k, v in ids.items()}
    out = []
    for bus, db in p.buses.items():
        for m in db.messages:
            if not m.is_extended_frame and m.frame_id in by_id:
                out.append(Collision(m.frame_id, by_id[m.frame_id], bus, m.name, "DBC"))
    for path, channels in p.recordings:
        rec = recorded_ids(path, channels)
        for (bus, cid), (n, rate, _) in sorted(rec.items()):
            if cid not in by_id:
                continue
            db = p.buses.get(bus)
            named = None
            if db is not None:
                named = next((m.name for m in db.messages if m.frame_id == cid), None)
            prev = next((c for c in out if c.can_id == cid and c.bus == bus), None)
            if prev is not None:
                prev.source += f", {path.name}"
                prev.frames, prev.rate_hz = n, rate
                continue
            out.append(Collision(cid, by_id[cid], bus, named or "not in the DBC", path.name,
                                 n, rate))
    return sorted(out, key=lambda c: (c.can_id, c.bus))


def stock_ids() -> dict:
    return {m.name: m.frame_id for m in navecu_can.load_db(navecu_can.DBC_PATH).messages}


# ------------------------------------------------------------------- the car's frames
class CarEncoder:
    """The car's own frames that a profile reads, encoded with the car's DBC as the car
    sends them: the wheel speeds (unsigned where the profile takes the direction from the
    gear), the gear (on every change and every gear_period_s), the ESP yaw rate; where the
    profile names a message's rolling counter, +1 per frame of that message from 0."""

    def __init__(self, p: Profile, gear_period_s: float = 1.0):
        self.p = p
        self.by_role = {r.role: r for r in p.reads}
        self.gear_period_s = gear_period_s
        self.counters = {r.role: 0 for r in p.reads if r.counter is not None}  # the next
        self._gear = None
        self._gear_t = -1e9
        gear = self.by_role.get("gear")
        if gear is not None:
            sig = gear.signals[0]
            names = {int(k): str(v) for k, v in (sig.choices or {}).items()}
            fwd = [v for v, s in p.gear_values.items() if s > 0]
            rev = [v for v, s in p.gear_values.items() if s < 0]
            self.gear_raw = {1: fwd[0], -1: rev[0]}
            self.gear_names = names

    def message(self, role: str, values: dict, t: float = 0.0,
                counter: int | None = None) -> can.Message:
        """The car's frame of role ("wheels" or an axle's "wheels_front", "wheels_rear";
        "gear", "yaw_rate") at t with these signal
        values (the DBC's physical units; the message's other signals at their initial
        value, else 0 or their minimum if that is above 0), encoded with the car's DBC
        without range checks (cantools rounds to the nearest raw value), with the car's
        checksum where the profile names one. Where it names a rolling counter, the frame
        carries `counter` if given (the next frame then counts on from it), else the next
        value of the role's sequence (a counter in values is overridden)."""
        r = self.by_role[role]
        msg = r.message
        full = {s.name: (s.initial if s.initial is not None else
                         (s.minimum if s.minimum is not None and s.minimum > 0 else 0))
                for s in msg.signals}
        full.update(values)
        if r.counter is not None:
            value = self.counters[role] if counter is None else int(counter)
            full.update(r.counter.values(value))
            self.counters[role] = (value + 1) % r.counter_modulus
        data = bytearray(msg.encode(full, scaling=True, strict=False))
        if r.checksum != "none":
            cs = CAR_CHECKSUMS[r.checksum]
            if cs.data_ids:
                cs.fill(msg.frame_id, data, r.checksum_data_ids)
            else:
                cs.fill(msg.frame_id, data)
        return can.Message(timestamp=t, arbitration_id=msg.frame_id, is_extended_id=False,
                           dlc=msg.length, data=bytes(data))

    def wheels(self, t: float, v_mps) -> list:
        """The frames at t for wheel speeds v_mps (FL, FR, RL, RR, signed m/s): the gear's
        where due, then the wheel speeds' message, or the front axle's and the rear's."""
        out = []
        direction = 1 if sum(v_mps) >= 0 else -1
        if self.p.direction == "gear" and (direction != self._gear
                                            or t - self._gear_t >= self.gear_period_s):
            self._gear, self._gear_t = direction, t
            sig = self.by_role["gear"].signals[0]
            out.append(self.message("gear", {sig.name: self.gear_raw[direction]}, t))
        first = 0   # the first wheel of v_mps that the message carries
        for r in self.p.wheel_reads():
            vals = {}
            for s, v in zip(r.signals, v_mps[first:first + len(r.signals)]):
                unit = abs(v) if self.p.direction != "signed" else v
                lo = s.minimum if s.minimum is not None else -1e9
                hi = s.maximum if s.maximum is not None else 1e9
                vals[s.name] = min(max(unit / self.p.speed_factor, lo), hi)
            out.append(self.message(r.role, vals, t))
            first += len(r.signals)
        return out

    def yaw_rate(self, t: float, rate_rps: float) -> list:
        """The ESP's yaw-rate frame at t (rad/s, left positive), if the profile reads one."""
        if "yaw_rate" not in self.by_role:
            return []
        s = self.by_role["yaw_rate"].signals[0]
        return [self.message("yaw_rate", {s.name: rate_rps / self.p.rate_factor}, t)]


# ------------------------------------------------------------------------ generation
def profile_dbc_text(p: Profile) -> str:
    """firmware/can/navecu.dbc with this profile's identifiers: every line that names a
    message by its identifier (BO_, CM_ BO_/SG_, VAL_, BA_ ... BO_/SG_, SG_MUL_VAL_)."""
    stock = stock_ids()
    move = {stock[n]: p.can_ids[n] for n in stock}
    text = navecu_can.DBC_PATH.read_text(encoding="utf-8")
    pat = re.compile(r"^(BO_ |CM_ BO_ |CM_ SG_ |VAL_ |SG_MUL_VAL_ |BA_ \"\w+\" BO_ |"
                     r"BA_ \"\w+\" SG_ )(\d+)\b", re.M)
    out = pat.sub(lambda m: m.group(1) + str(move.get(int(m.group(2)), int(m.group(2)))), text)
    if p.name != "native":
        out = out.replace('CM_ "navecu CAN protocol.',
                          f'CM_ "navecu CAN protocol, identifiers of vehicle profile {p.name}.', 1)
    return out


def _c_float(x: float) -> str:
    return f"NAV_C({x!r})"


def _c_name(msg) -> str:
    return camel_to_snake_case(msg.name)


def vehicle_profile_c(p: Profile) -> str:
    """The generated vehicle_profile.c: the profile's constants and vehicle_decode."""
    stock = navecu_can.load_db(navecu_can.DBC_PATH).messages
    ids = ", ".join(f"0x{p.can_ids[m.name]:03X}u" for m in stock)
    L = ["/* GENERATED FILE - DO NOT EDIT. Source: vehicles/" + p.name + ".toml and the car's DBC",
         " * (tools/vehicle.py; firmware/vehicle/vehicle.h). */",
         '#include "vehicle.h"', ""]
    counted = any(r.counter is not None for r in p.reads)
    if p.reads:
        L += [f'#include "{CODEC_DB}.h"', '#include "vehicle_checksum.h"']
        L += ['#include "vehicle_counter.h"'] if counted else []
        L += ['#include "vehicle_pair.h"'] if p.split_wheels else []
        L += [""]
    if p.split_wheels:
        L += _split_state_c(p)
    for r in p.reads:
        if r.checksum_data_ids:
            L += [f"/* {r.message.name}'s {r.checksum} checksum data IDs, by its counter "
                  "(checksum_data_ids) */",
                  f"static const uint8_t {_c_name(r.message)}_data_ids[{len(r.checksum_data_ids)}] = {{",
                  "    " + ", ".join(f"0x{x:02X}u" for x in r.checksum_data_ids) + "};", ""]
    L += [f"const vehicle_profile_t vehicle_profile = {{\"{p.name}\", {DIRECTIONS[p.direction]}, "
          f"{1 if p.native_wheels else 0}u, {_c_float(p.track_m)}, {_c_float(p.wheelbase_m)}, "
          f"{_c_float(p.wheel_step_mps)},",
          f"                                           {{{ids}}}}};", ""]
    fids = [f"{CODEC_DB.upper()}_{_c_name(r.message).upper()}_FRAME_ID" for r in p.reads]
    L += ["size_t vehicle_rx_ids(uint32_t *ids, size_t max)", "{"]
    if fids:
        L += ["    static const uint32_t rx[] = {" + ", ".join(fids) + "};",
              "    const size_t n = sizeof rx / sizeof rx[0];",
              "    for (size_t i = 0u; i < n && i < max; i++) {",
              "        ids[i] = rx[i];", "    }", "    return n;"]
    else:
        L += ["    (void)ids;", "    (void)max;", "    return 0u;"]
    L += ["}", ""]
    L += ["vehicle_verdict_t vehicle_decode(const hal_can_frame_t *f, vehicle_counters_t *c,",
          "                                 vehicle_msg_t *m)", "{",
          "    m->kind = VEHICLE_MSG_NONE;"]
    if not counted:
        L += ["    (void)c; /* the profile names no rolling counter */"]
    if not p.reads:
        L += ["    (void)f;", "    return VEHICLE_OK; /* the wheels come in navecu's WheelSpeeds */",
              "}", ""]
        return "\n".join(L)
    L += ["    if (f->extended) {", "        return VEHICLE_OK;", "    }", "    switch (f->id) {"]
    for r in p.reads:
        L += _decode_case(p, r)
    L += ["    default:", "        return VEHICLE_OK;", "    }", "}", ""]
    return "\n".join(L)


#: the rear axle's rolling counter, where split wheel speeds name one: the generated file's
#: own, the caller's vehicle_counters_t having a place for one wheel-speed message only
REAR_COUNTERS = "rear_counters"


def _split_state_c(p: Profile) -> list:
    """What the generated layer of a profile with split wheel speeds keeps of its own (the
    held half, the rear axle's counter) and its vehicle_reset (vehicle.h)."""
    rear = next(r for r in p.reads if r.role == "wheels_rear")
    L = ["#if !VEHICLE_SPLIT_WHEELS",
         f'#error "profile {p.name} sends its wheel speeds in two messages: build the '
         'application with VEHICLE_SPLIT_WHEELS 1 (vehicle.h)"',
         "#endif", "",
         "/* The half of the wheel speeds held until the other axle's (vehicle_pair.h)"
         + (f", and the rear axle's rolling\n * counter {rear.counter.name}"
            if rear.counter is not None else "") + ":",
         " * this file's own state, not the caller's (rx_state_t is the same size for every",
         " * profile: those whose wheel speeds come in one message pay nothing for it);",
         " * forgotten by vehicle_reset, which the caller calls where it clears its receive",
         " * state. */",
         "static vehicle_pair_t wheel_pair;"]
    if rear.counter is not None:
        L += [f"static vehicle_counters_t {REAR_COUNTERS}; /* its slot VEHICLE_MSG_WHEELS only */"]
    L += ["", "void vehicle_reset(void)", "{", "    wheel_pair.held = 0u;"]
    if rear.counter is not None:
        L += [f"    {REAR_COUNTERS}.last[(unsigned)VEHICLE_MSG_WHEELS - 1u] = 0u;"]
    L += ["}", ""]
    return L


def _decode_case(p: Profile, r: CarSignalSet) -> list:
    mn = _c_name(r.message)
    up = f"{CODEC_DB.upper()}_{mn.upper()}"
    fn = f"{CODEC_DB}_{mn}"
    kind = "VEHICLE_MSG_WHEELS" if r.role in WHEEL_ROLES else \
        {"gear": "VEHICLE_MSG_GEAR", "yaw_rate": "VEHICLE_MSG_YAW_RATE"}[r.role]
    L = [f"    case {up}_FRAME_ID: {{", f"        m->kind = {kind};",
         f"        if (f->dlc != {up}_LENGTH) {{", "            return VEHICLE_BAD_DLC;", "        }"]
    if r.checksum != "none":
        keyed = f", {_c_name(r.message)}_data_ids" if r.checksum_data_ids else ""
        L += [f"        if (!vehicle_checksum_{r.checksum}(f->id, f->data, f->dlc{keyed})) {{",
              "            return VEHICLE_BAD_CHECKSUM;", "        }"]
    L += [f"        struct {fn}_t s;",
          f"        if ({fn}_unpack(&s, f->data, f->dlc) != 0) {{",
          "            return VEHICLE_BAD_DLC;", "        }"]
    if r.counter is not None:
        counters = f"&{REAR_COUNTERS}" if r.role == "wheels_rear" else "c"
        # the parts, most significant first, joined into one number
        terms, shift = [], 0
        for part in reversed(r.counter.parts):
            x = f"(uint32_t)s.{camel_to_snake_case(part.name)}"
            terms.insert(0, f"({x} << {shift}u)" if shift else x)
            shift += part.length
        value = (f"s.{camel_to_snake_case(r.counter.parts[0].name)}"
                 if len(terms) == 1 else "(uint8_t)(" + " | ".join(terms) + ")")
        L += [f"        /* {r.counter.name}: {r.counter.length} bits, modulo {r.counter_modulus}: a "
              "repeat or a value it never takes is refused, lost frames are not */",
              f"        if (vehicle_counter_step({counters}, {kind}, {value}, {r.counter_modulus}u) <= 0) {{",
              "            return VEHICLE_BAD_COUNTER;", "        }"]
    fields = [camel_to_snake_case(s.name) for s in r.signals]
    cond = " ||\n            ".join(f"!{fn}_{x}_is_in_range(s.{x})" for x in fields)
    L += [f"        if ({cond}) {{", "            return VEHICLE_BAD_VALUE;", "        }"]
    if r.role == "wheels":
        for i, x in enumerate(fields):
            L.append(f"        m->wheel_mps[{i}] = {fn}_{x}_decode(s.{x}) * "
                     f"{_c_float(p.speed_factor)};")
    elif r.role in WHEEL_ROLES:
        axle = "FRONT" if r.role == "wheels_front" else "REAR"
        other = "rear" if axle == "FRONT" else "front"
        left, right = (f"{fn}_{x}_decode(s.{x}) * {_c_float(p.speed_factor)}" for x in fields)
        L += [f"        /* the {axle.lower()} axle's half: held until the {other} axle's, or "
              "with it one sample (vehicle_pair.h) */",
              f"        if (vehicle_pair_half(&wheel_pair, VEHICLE_AXLE_{axle},",
              f"                              {left},",
              f"                              {right}, m->wheel_mps) == 0) {{",
              "            return VEHICLE_WHEELS_HELD;", "        }"]
    elif r.role == "gear":
        x = fields[0]
        L.append(f"        switch (s.{x}) {{")
        for raw, sign in sorted(p.gear_values.items()):
            L += [f"        case {raw}:", f"            m->gear_direction = {sign};",
                  "            break;"]
        for raw in sorted(p.gear_hold):
            L += [f"        case {raw}: /* held: the direction kept, the frame not read */",
                  "            m->kind = VEHICLE_MSG_NONE;", "            return VEHICLE_OK;"]
        L += ["        default:", "            return VEHICLE_BAD_VALUE; /* a gear the profile "
              "does not name */", "        }"]
    else:
        x = fields[0]
        L.append(f"        m->yaw_rate_rps = {fn}_{x}_decode(s.{x}) * {_c_float(p.rate_factor)};")
    L += ["        return VEHICLE_OK;", "    }"]
    return L


def generate(p: Profile, out: Path) -> None:
    """Write the firmware's vehicle layer for p into out/."""
    out.mkdir(parents=True, exist_ok=True)
    if p.reads:
        msgs = [r.message for r in p.reads]
        sub = cantools.database.can.Database(messages=msgs, strict=False)
        h, c, _, _ = generate_c(sub, CODEC_DB, f"{CODEC_DB}.h", f"{CODEC_DB}.c", "fuzzer.c",
                                floating_point_numbers=True, use_float=True, use_round=True)
        banner = ("/* GENERATED FILE - DO NOT EDIT. Source: vehicles/" + p.name +
                  ".toml and the car's DBC (tools/vehicle.py). */\n")
        strip = lambda s: re.sub(r"(generated by cantools version [0-9.]+) .*$", r"\1.", s,
                                 flags=re.M)
        (out / f"{CODEC_DB}.h").write_text(banner + strip(h))
        (out / f"{CODEC_DB}.c").write_text(banner + strip(c))
    else:
        banner = (f"/* GENERATED FILE - DO NOT EDIT (tools/vehicle.py): vehicle profile {p.name} "
                  "reads no car message. */\n")
        (out / f"{CODEC_DB}.h").write_text(banner)
        (out / f"{CODEC_DB}.c").write_text(banner + "typedef int veh_can_empty_t; /* ISO C: not "
                                           "an empty translation unit */\n")
    (out / "vehicle_profile.c").write_text(vehicle_profile_c(p))
    (out / "navecu.dbc").write_text(profile_dbc_text(p))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("generate")
    g.add_argument("name")
    g.add_argument("out")
    c = sub.add_parser("check")
    c.add_argument("name")
    c.add_argument("--ids", choices=("profile", "stock"), default="profile")
    d = sub.add_parser("dbc")
    d.add_argument("name")
    d.add_argument("out")
    a = ap.parse_args(argv)
    try:
        p = load(a.name)
    except ProfileError as e:
        print(f"vehicle: {e}", file=sys.stderr)
        return 2
    if a.cmd == "dbc":
        Path(a.out).write_text(profile_dbc_text(p))
        return 0
    for bus, notes in p.dbc_notes.items():
        for note in notes:
            print(f"vehicle: {p.name}: {bus} DBC normalised: {note}")
    ids = stock_ids() if getattr(a, "ids", "profile") == "stock" else p.can_ids
    label = "the DBC's stock identifiers" if ids is not p.can_ids else f"profile {p.name}"
    try:
        found = collisions(p, {**ids, **uds_ids()})
    except ProfileError as e:
        print(f"vehicle: {p.name}: {e}", file=sys.stderr)
        return 2
    if found:
        print(f"vehicle: {len(found)} collision(s) of navecu's identifiers ({label}) with "
              f"the car's buses:", file=sys.stderr)
        for col in found:
            print("  " + col.line(), file=sys.stderr)
        return 1
    sources = ", ".join(list(p.buses) + [r[0].name for r in p.recordings]) or "no car bus"
    print(f"vehicle: {label}: no collision with {sources}")
    if a.cmd == "generate":
        generate(p, Path(a.out))
        print(f"vehicle: {p.name} generated into {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
