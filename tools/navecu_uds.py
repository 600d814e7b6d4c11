"""navecu's diagnostic tester: configure and read out the ECU over UDS (ISO 14229-1) on
ISO-TP (ISO 15765-2), with udsoncan and can-isotp (tools/requirements.txt pins both).

    python -m tools.navecu_uds [BUS OPTIONS] COMMAND [ARGS]      (make uds ARGS="...")

Commands:
    info                       the identification DIDs (software version, serial, vehicle;
                               the NVM status DID 0xF1A1 where the ECU has it)
    read NAME...               parameters, in the unit of params.toml (the host option's)
    write NAME=VALUE...        parameters (vec3: X,Y,Z; enum: its value name), unlocked
    dump [--toml FILE]         every parameter as TOML (stdout without --toml)
    load FILE.toml             write every entry of FILE, each checked against the table
                               (name, type, range) before anything is sent
    save                       RoutineControl 0x0200 StoreParameters (to NVM)
    defaults                   RoutineControl 0x0202 RestoreDefaults (in RAM; save keeps them)
    reset                      ECUReset hardReset
    adopt-mounting             RoutineControl 0x0204 AdoptMounting
    dtc [--supported]          ReadDTCInformation 0x02 (status mask 0xFF) and 0x01 (their
                               number); --supported: 0x0A
    clear-dtc                  ClearDiagnosticInformation, group 0xFFFFFF (all)
    erase-cal                  RoutineControl 0x0201 EraseCalibration
    store-cal                  RoutineControl 0x0203 StoreCalibration

Bus: --interface socketcan --channel vcan0 (python-can), or --log-runner: build/host/navecu
on a CAN log (tools/uds_logrun.py; --session LOG continues one power-on, --nvm FILE the
ECU's NVM image, --navecu-arg ARG its options). --request-id / --response-id default to
the table's uds_request_id / uds_response_id defaults (0x7A0 / 0x7A8).

The parameter names, units, ranges and DIDs are firmware/app/params.toml's, through
tools/gen_params.py's loader: one source. Over UDS the values are SI (docs/can.md,
"Diagnostics (UDS)"); the tool converts with the table's to_si factor, so a TOML holds
what the host's command line would take.

Exit status: 0 ok, 1 a negative response (its NRC printed by its ISO 14229-1 name), 2 the
transport (no bus, no answer, a malformed answer), 3 a bad input (file, name, value out of
range), 4 usage. docs/diagnostics.md is the manual.
"""
from __future__ import annotations

import argparse
import logging
import math
import struct
import sys
import tomllib
from pathlib import Path
from typing import Optional

import udsoncan

from tools import gen_params

EXIT_OK, EXIT_NRC, EXIT_TRANSPORT, EXIT_INPUT, EXIT_USAGE = 0, 1, 2, 3, 4

# ISO 14229-1:2020 Table A.1, the negative response codes by name
NRC_NAMES = {
    0x10: "generalReject", 0x11: "serviceNotSupported", 0x12: "subFunctionNotSupported",
    0x13: "incorrectMessageLengthOrInvalidFormat", 0x14: "responseTooLong",
    0x21: "busyRepeatRequest", 0x22: "conditionsNotCorrect", 0x24: "requestSequenceError",
    0x25: "noResponseFromSubnetComponent", 0x26: "failurePreventsExecutionOfRequestedAction",
    0x31: "requestOutOfRange", 0x33: "securityAccessDenied", 0x34: "authenticationRequired",
    0x35: "invalidKey", 0x36: "exceedNumberOfAttempts", 0x37: "requiredTimeDelayNotExpired",
    0x70: "uploadDownloadNotAccepted", 0x71: "transferDataSuspended",
    0x72: "generalProgrammingFailure", 0x73: "wrongBlockSequenceCounter",
    0x78: "requestCorrectlyReceived-ResponsePending",
    0x7E: "subFunctionNotSupportedInActiveSession",
    0x7F: "serviceNotSupportedInActiveSession", 0x81: "rpmTooHigh", 0x82: "rpmTooLow",
    0x83: "engineIsRunning", 0x84: "engineIsNotRunning", 0x85: "engineRunTimeTooLow",
    0x86: "temperatureTooHigh", 0x87: "temperatureTooLow", 0x88: "vehicleSpeedTooHigh",
    0x89: "vehicleSpeedTooLow", 0x8A: "throttlePedalTooHigh", 0x8B: "throttlePedalTooLow",
    0x8C: "transmissionRangeNotInNeutral", 0x8D: "transmissionRangeNotInGear",
    0x8F: "brakeSwitchNotClosed", 0x90: "shifterLeverNotInPark",
    0x91: "torqueConverterClutchLocked", 0x92: "voltageTooHigh", 0x93: "voltageTooLow",
    0x94: "resourceTemporarilyNotAvailable",
}

# identification DIDs (firmware/app/app_uds.h) and the NVM status DID (nvm branch)
ID_DIDS = {0xF195: "sw_version", 0xF18C: "serial", 0xF1A0: "vehicle", 0xF1A2: "build"}
DID_NVM_STATUS = 0xF1A1
# RoutineControl 0x31 startRoutine identifiers (docs/can.md, "Diagnostics (UDS)")
ROUTINES = {"save": (0x0200, "StoreParameters"), "erase-cal": (0x0201, "EraseCalibration"),
            "defaults": (0x0202, "RestoreDefaults"), "store-cal": (0x0203, "StoreCalibration"),
            "adopt-mounting": (0x0204, "AdoptMounting")}
SESSION_EXTENDED = 0x03
SECURITY_LEVEL = 0x01
DTC_GROUP_ALL = 0xFFFFFF
FORMATS = {"u16": ">H", "enum": ">B", "real": ">f", "vec3": ">3f"}
# the DTC status bits, ISO 14229-1 Annex D.2
DTC_STATUS_BITS = ("testFailed", "testFailedThisOperationCycle", "pendingDTC", "confirmedDTC",
                   "testNotCompletedSinceLastClear", "testFailedSinceLastClear",
                   "testNotCompletedThisOperationCycle", "warningIndicatorRequested")


class InputError(ValueError):
    """A bad name, value or file: exit status 3."""


class WireError(ValueError):
    """An answer that does not decode as the table says: exit status 2."""


class TransportError(OSError):
    """No bus, or the log runner failed: exit status 2."""


class UsageError(ValueError):
    """Exit status 4."""


def nrc_name(code: int) -> str:
    if 0x38 <= code <= 0x4F:
        return "reservedByExtendedDataLinkSecurityDocument"
    if 0x95 <= code <= 0xEF:
        return "reservedForSpecificConditionsNotCorrect"
    return NRC_NAMES.get(code, "ISOSAEReserved")


def key_of_seed(seed: int) -> int:
    """The DEMONSTRATION key of firmware/diag/uds.h (not security):
    key = rotl32(seed XOR 0x4E415645, 5) + 0x43553136 (mod 2^32)."""
    x = (seed ^ 0x4E415645) & 0xFFFFFFFF
    return ((((x << 5) | (x >> 27)) & 0xFFFFFFFF) + 0x43553136) & 0xFFFFFFFF


def security_algo(level, seed, params=None):  # udsoncan's signature
    return struct.pack(">I", key_of_seed(struct.unpack(">I", bytes(seed))[0]))


def dtc_name(dtc: int) -> str:
    """A 3-byte DTC (DTCFormatIdentifier 0x00, SAE J2012-DA) as its code and failure type:
    0xD10187 -> U1101-87 (the high two bits the system P C B U, then four digits)."""
    hi, mid, ftb = (dtc >> 16) & 0xFF, (dtc >> 8) & 0xFF, dtc & 0xFF
    return f"{'PCBU'[hi >> 6]}{(hi >> 4) & 0x3}{hi & 0xF:X}{mid:02X}-{ftb:02X}"


def dtc_status_names(status: int) -> list:
    return [n for k, n in enumerate(DTC_STATUS_BITS) if status & (1 << k)]


# ---------------------------------------------------------------- the parameter table
def table() -> dict:
    """{name: the loader's parameter dict}, in the table's order."""
    return {p["name"]: p for p in gen_params.load()}


def _f32(x: float) -> float:
    return struct.unpack(">f", struct.pack(">f", x))[0]


def _unit_value(p: dict, si: float) -> float:
    """The shortest decimal in the parameter's unit that gives back the same float32 SI."""
    target = _f32(si)
    u = si / p["factor"]
    for digits in range(6, 18):
        c = float(f"{u:.{digits}g}")
        if _f32(c * p["factor"]) == target:
            return c
    return u


def from_wire(p: dict, payload: bytes):
    """A DID's payload -> the value in the parameter's unit (enum: its name)."""
    fmt = FORMATS[p["type"]]
    if len(payload) != struct.calcsize(fmt):
        raise WireError(f"{p['name']}: {len(payload)} bytes, expected {struct.calcsize(fmt)}")
    v = struct.unpack(fmt, payload)
    if p["type"] == "u16":
        return v[0]
    if p["type"] == "enum":
        if v[0] >= len(p["values"]):
            raise WireError(f"{p['name']}: value index {v[0]} not among {p['values']}")
        return p["values"][v[0]]
    vals = [_unit_value(p, x) for x in v]
    return vals if p["type"] == "vec3" else vals[0]


def check_value(p: dict, v):
    """v (from TOML or the command line, in the unit) checked against the table: the value
    to send, normalised (float for real, list of 3 floats for vec3, int, enum name)."""
    name = p["name"]

    def in_range(x: float) -> bool:
        lo_ok = x > p["min"] if p["min_exclusive"] else x >= p["min"]
        return lo_ok and x <= p["max"]

    def rng() -> str:
        return f"{'(' if p['min_exclusive'] else '['}{p['min']}, {p['max']}] {p['unit']}".strip()

    if p["type"] == "enum":
        if not isinstance(v, str) or v not in p["values"]:
            raise InputError(f"{name}: {v!r} is not one of {', '.join(p['values'])}")
        return v
    if p["type"] == "u16":
        if isinstance(v, bool) or not isinstance(v, int):
            raise InputError(f"{name}: {v!r} is not an integer")
        if not in_range(v):
            raise InputError(f"{name}: {v} outside {rng()}")
        return v
    if p["type"] == "vec3":
        if not isinstance(v, list) or len(v) != 3:
            raise InputError(f"{name}: needs three numbers [x, y, z], got {v!r}")
        xs = v
    else:
        xs = [v]
    out = []
    for x in xs:
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
            raise InputError(f"{name}: {x!r} is not a finite number")
        if not in_range(float(x)):
            raise InputError(f"{name}: {x} outside {rng()}")
        out.append(float(x))
    return out if p["type"] == "vec3" else out[0]


def to_wire(p: dict, v) -> bytes:
    """A checked value (check_value) -> the DID's payload (SI, docs/can.md)."""
    fmt = FORMATS[p["type"]]
    if p["type"] == "enum":
        return struct.pack(fmt, p["values"].index(v))
    if p["type"] == "u16":
        return struct.pack(fmt, v)
    xs = v if p["type"] == "vec3" else [v]
    return struct.pack(fmt, *[x * p["factor"] for x in xs])


def parse_cli_value(p: dict, text: str):
    """NAME=VALUE's VALUE as the host's option takes it (vec3 "X,Y,Z")."""
    try:
        if p["type"] == "enum":
            return text
        if p["type"] == "u16":
            return int(text, 0)
        if p["type"] == "vec3":
            return [float(s) for s in text.split(",")]
        return float(text)
    except ValueError:
        raise InputError(f"{p['name']}: {text!r} is not a {p['type']} value") from None


def _toml_scalar(x, hex_int: bool = False) -> str:
    if isinstance(x, str):
        return '"' + x.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(x, float):
        r = repr(x)
        return r if ("." in r or "e" in r or "inf" in r or "nan" in r) else r + ".0"
    return f"0x{x:03X}" if hex_int else str(x)


def to_toml(values: dict, tab: Optional[dict] = None, header: str = "") -> str:
    """values {name: value in unit} as TOML, one line each, with the unit and range."""
    tab = tab or table()
    lines = ["# navecu parameters (python -m tools.navecu_uds dump); units and ranges are",
             "# firmware/app/params.toml's. Edit, then: python -m tools.navecu_uds load FILE"]
    if header:
        lines += [f"# {h}" for h in header.splitlines()]
    for name, v in values.items():
        p = tab[name]
        val = ("[" + ", ".join(_toml_scalar(x) for x in v) + "]" if isinstance(v, list)
               else _toml_scalar(v, name.endswith("_id")))
        if p["type"] == "enum":
            note = " | ".join(p["values"])
        else:
            note = (f"{p['unit'] + ' ' if p['unit'] else ''}"
                    f"{'(' if p['min_exclusive'] else '['}{p['min']}, {p['max']}]")
        lines.append(f"{name} = {val}  # {note}")
    return "\n".join(lines) + "\n"


def read_toml(path: str, tab: Optional[dict] = None) -> dict:
    """A TOML file of parameters, every entry checked: {name: value to send}. InputError
    names the file and what is wrong; nothing is sent from a file with one bad entry."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as e:
        raise InputError(f"{path}: {e.strerror}") from None
    except UnicodeDecodeError as e:
        raise InputError(f"{path}: not TOML: {e}") from None
    return read_toml_text(text, tab, str(path))


def read_toml_text(text: str, tab: Optional[dict] = None, where: str = "TOML") -> dict:
    tab = tab or table()
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"{where}: not TOML: {e}") from None
    out, errors = {}, []
    for name, v in doc.items():
        if name not in tab:
            errors.append(f"{name}: not a parameter of firmware/app/params.toml")
            continue
        try:
            out[name] = check_value(tab[name], v)
        except InputError as e:
            errors.append(str(e))
    if errors:
        raise InputError(f"{where}: " + "; ".join(errors))
    return out


# ---------------------------------------------------------------- the connection
def default_ids(tab: Optional[dict] = None) -> tuple:
    tab = tab or table()
    return int(tab["uds_request_id"]["default"]), int(tab["uds_response_id"]["default"])


class Raw(udsoncan.DidCodec):
    """udsoncan DID codec: the payload as bytes (the tool decodes with the table)."""

    def __init__(self, length: Optional[int]):
        self.length = length

    def encode(self, v):
        return bytes(v)

    def decode(self, payload):
        return bytes(payload)

    def __len__(self):
        if self.length is None:
            raise udsoncan.DidCodec.ReadAllRemainingData
        return self.length


def open_client(a, tab: dict):
    """A connected udsoncan Client over the bus the options name (the caller closes it
    with close_client)."""
    import can

    req_id, rsp_id = a.request_id, a.response_id
    if a.log_runner:
        from tools.uds_logrun import LogRunnerBus
        bus = LogRunnerBus(navecu=a.navecu, response_id=rsp_id, session=a.session,
                           nvm=a.nvm, navecu_args=a.navecu_arg)
    else:
        try:
            bus = can.Bus(interface=a.interface, channel=a.channel,
                          can_filters=[{"can_id": rsp_id, "can_mask": 0x7FF,
                                        "extended": False}])
        except (OSError, can.CanError, ValueError, ImportError) as e:
            raise TransportError(f"cannot open {a.interface} channel {a.channel}: {e} "
                                 "(no such interface? `make vcan`, or --log-runner)") from None
    dids = {int(p["did"]): Raw(struct.calcsize(FORMATS[p["type"]])) for p in tab.values()}
    dids.update({did: Raw(None) for did in (*ID_DIDS, DID_NVM_STATUS)})
    return client_on_bus(bus, req_id, rsp_id, a.timeout, dids)


def client_on_bus(bus, req_id: int, rsp_id: int, timeout: float, dids: dict,
                  p2_star_s: Optional[float] = None):
    """An open udsoncan Client on ISO-TP over a python-can bus (close_client closes both):
    the ECU's and the bootloader's tools (navecu_flash.py) alike. p2_star_s: the wait after
    a 0x78 responsePending (default: timeout)."""
    import isotp
    from udsoncan.client import Client
    from udsoncan.connections import PythonIsoTpConnection

    addr = isotp.Address(isotp.AddressingMode.Normal_11bits, txid=req_id, rxid=rsp_id)
    stack = isotp.CanStack(bus, address=addr,
                           params={"blocking_send": False, "tx_padding": 0xCC, "stmin": 0,
                                   "blocksize": 0})
    conn = PythonIsoTpConnection(stack)
    config = dict(udsoncan.configs.default_client_config)
    config.update({"data_identifiers": dids, "security_algo": security_algo,
                   "request_timeout": timeout, "p2_timeout": timeout,
                   "p2_star_timeout": p2_star_s if p2_star_s is not None else timeout,
                   "use_server_timing": False})
    client = Client(conn, config=config)
    client.open()
    client._navecu_bus = bus
    return client


def close_client(client) -> None:
    try:
        client.close()
    finally:
        client._navecu_bus.shutdown()


# ---------------------------------------------------------------- the operations
class Tool:
    """The operations on an open udsoncan Client (importable: tests and scripts)."""

    def __init__(self, client, tab: Optional[dict] = None, out=sys.stdout):
        self.c = client
        self.tab = tab or table()
        self.out = out
        self.unlocked = False

    def say(self, text: str) -> None:
        print(text, file=self.out)

    def unlock(self) -> None:
        """Extended session, then SecurityAccess level 0x01 with the demonstration key."""
        if not self.unlocked:
            self.c.change_session(SESSION_EXTENDED)
            self.c.unlock_security_access(SECURITY_LEVEL)
            self.unlocked = True

    def read_raw(self, did: int) -> bytes:
        return self.c.read_data_by_identifier(did).service_data.values[did]

    def info(self) -> dict:
        from udsoncan.exceptions import NegativeResponseException
        r = {name: self.read_raw(did).decode("ascii", "replace") for did, name in ID_DIDS.items()}
        try:
            r["nvm_status"] = self.read_raw(DID_NVM_STATUS).hex()
        except NegativeResponseException as e:
            if e.response.code != 0x31:
                raise
            r["nvm_status"] = None  # not in this build (the nvm branch adds it)
        return r

    def read(self, names) -> dict:
        out = {}
        for n in names:
            if n not in self.tab:
                raise InputError(f"{n}: not a parameter of firmware/app/params.toml")
            p = self.tab[n]
            out[n] = from_wire(p, self.read_raw(int(p["did"])))
        return out

    def dump(self) -> dict:
        return self.read(list(self.tab))

    def write(self, values: dict) -> None:
        """{name: checked value}, written in the table's order. A rule between parameters
        (the output rates within the IMU rate: app_config_valid, the ECU's) can refuse a
        value inside its range with 0x31 until another one is written (lowering the IMU
        rate below today's output rate): such a write is tried again after the others,
        pass after pass while one succeeds; then the ECU's refusal is the result."""
        from udsoncan.exceptions import NegativeResponseException
        self.unlock()
        pending = [n for n in self.tab if n in values]
        while pending:
            deferred, refusal = [], None
            for name in pending:
                p = self.tab[name]
                try:
                    self.c.write_data_by_identifier(int(p["did"]), to_wire(p, values[name]))
                except NegativeResponseException as e:
                    if e.response.code != 0x31:
                        raise
                    deferred.append(name)
                    refusal = refusal or e
            if len(deferred) == len(pending):
                raise refusal
            pending = deferred

    def load(self, values: dict) -> list:
        """Every entry written; a read-only one (uds_write = false) is compared instead and
        must equal the ECU's. Returns the names written."""
        ro = [n for n in values if self.tab[n]["uds_read_only"]]
        if ro:
            now = self.read(ro)
            bad = [n for n in ro if now[n] != values[n]]
            if bad:
                raise InputError(", ".join(f"{n} = {values[n]} differs from the ECU's "
                                           f"{now[n]}, and is read-only over UDS" for n in bad))
        todo = {n: v for n, v in values.items() if n not in ro}
        self.write(todo)
        return [n for n in self.tab if n in todo]

    def routine(self, rid: int):
        self.unlock()
        return self.c.routine_control(rid, 0x01)

    def reset(self) -> int:
        self.unlock()
        return self.c.ecu_reset(0x01).service_data.reset_type_echo

    def dtc(self, supported: bool = False) -> dict:
        if supported:
            r = self.c.get_supported_dtc()
        else:
            r = self.c.get_dtc_by_status_mask(0xFF)
        sd = r.service_data
        return {"status_availability": sd.status_availability.get_byte_as_int(),
                "dtcs": [{"id": d.id, "status": d.status.get_byte_as_int()} for d in sd.dtcs]}

    def dtc_count(self) -> int:
        """ReadDTCInformation 0x01 reportNumberOfDTCByStatusMask, mask 0xFF."""
        return self.c.get_number_of_dtc_by_status_mask(0xFF).service_data.dtc_count

    def clear_dtc(self) -> None:
        self.c.clear_dtc(DTC_GROUP_ALL)


# ---------------------------------------------------------------- the command line
def _fmt(v) -> str:
    if isinstance(v, list):
        return ",".join(_fmt(x) for x in v)
    return str(v)


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="navecu_uds", description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="Exit status: 0 ok, 1 negative response, 2 transport, "
                                        "3 bad input, 4 usage. docs/diagnostics.md.")
    req, rsp = default_ids()
    ap.add_argument("--interface", default="socketcan", help="python-can interface")
    ap.add_argument("--channel", default="vcan0", help="python-can channel (default vcan0)")
    ap.add_argument("--request-id", type=lambda s: int(s, 0), default=req,
                    help=f"tester -> ECU (default 0x{req:03X}, the table's uds_request_id)")
    ap.add_argument("--response-id", type=lambda s: int(s, 0), default=rsp,
                    help=f"ECU -> tester (default 0x{rsp:03X}, the table's uds_response_id)")
    ap.add_argument("--timeout", type=float, default=2.0, help="seconds per request")
    ap.add_argument("-v", "--verbose", action="store_true", help="udsoncan's log")
    ap.add_argument("--log-runner", action="store_true",
                    help="no bus: build/host/navecu on a CAN log (tools/uds_logrun.py)")
    ap.add_argument("--navecu", default=None, help="the log runner's host executable")
    ap.add_argument("--session", default=None,
                    help="the log runner's session log (continues one power-on)")
    ap.add_argument("--nvm", default=None, help="the log runner's NVM image")
    ap.add_argument("--navecu-arg", action="append", default=[],
                    help="an option for the log runner's navecu (repeatable)")
    sub = ap.add_subparsers(dest="cmd", metavar="COMMAND")
    sub.add_parser("info", help="identification DIDs")
    p = sub.add_parser("read", help="parameters by name")
    p.add_argument("names", nargs="+", metavar="NAME")
    p = sub.add_parser("write", help="NAME=VALUE...")
    p.add_argument("pairs", nargs="+", metavar="NAME=VALUE")
    p = sub.add_parser("dump", help="every parameter as TOML")
    p.add_argument("--toml", default=None, metavar="FILE")
    p = sub.add_parser("load", help="write every entry of a TOML")
    p.add_argument("file", metavar="FILE.toml")
    for name, (rid, what) in ROUTINES.items():
        sub.add_parser(name, help=f"RoutineControl 0x{rid:04X} {what}")
    sub.add_parser("reset", help="ECUReset hardReset")
    p = sub.add_parser("dtc", help="ReadDTCInformation")
    p.add_argument("--supported", action="store_true")
    sub.add_parser("clear-dtc", help="ClearDiagnosticInformation (all groups)")
    return ap


def run(a, tab: dict, out=sys.stdout, client=None) -> int:
    """One command on an open client (or one opened from the options)."""
    own = client is None
    # inputs checked before the bus is touched
    values = None
    if a.cmd == "load":
        values = read_toml(a.file, tab)
    elif a.cmd == "write":
        values = {}
        for pair in a.pairs:
            if "=" not in pair:
                raise UsageError(f"write: {pair!r} is not NAME=VALUE")
            n, text = pair.split("=", 1)
            if n not in tab:
                raise InputError(f"{n}: not a parameter of firmware/app/params.toml")
            values[n] = check_value(tab[n], parse_cli_value(tab[n], text))
    elif a.cmd == "read":
        for n in a.names:
            if n not in tab:
                raise InputError(f"{n}: not a parameter of firmware/app/params.toml")
    if own:
        client = open_client(a, tab)
    try:
        t = Tool(client, tab, out)
        if a.cmd == "info":
            for k, v in t.info().items():
                t.say(f"{k}: {v if v is not None else '(no DID 0xF1A1 in this build)'}")
        elif a.cmd == "read":
            for k, v in t.read(a.names).items():
                t.say(f"{k} = {_fmt(v)}")
        elif a.cmd == "write":
            t.write(values)
            t.say(f"written: {', '.join(values)} (in RAM; 'save' stores them)")
        elif a.cmd == "dump":
            text = to_toml(t.dump(), tab)
            if a.toml:
                try:
                    Path(a.toml).write_text(text, encoding="utf-8")
                except OSError as e:   # a bad file, not the transport: exit 3
                    raise InputError(f"{a.toml}: {e.strerror or e}") from None
                t.say(f"dumped {len(tab)} parameters to {a.toml}")
            else:
                out.write(text)
        elif a.cmd == "load":
            names = t.load(values)
            t.say(f"loaded {len(names)} parameters from {a.file} (in RAM; 'save' stores them)")
        elif a.cmd in ROUTINES:
            rid, what = ROUTINES[a.cmd]
            t.routine(rid)
            t.say(f"routine 0x{rid:04X} {what}: done")
        elif a.cmd == "reset":
            t.say(f"ECUReset: reset type {t.reset()} accepted")
        elif a.cmd == "dtc":
            r = t.dtc(a.supported)
            what = "supported" if a.supported else f"with a status bit set ({t.dtc_count()} " \
                "counted by 0x19 01)"
            t.say(f"status availability mask 0x{r['status_availability']:02X}, "
                  f"{len(r['dtcs'])} DTC(s) {what}")
            for d in r["dtcs"]:
                t.say(f"  0x{d['id']:06X} {dtc_name(d['id'])} status 0x{d['status']:02X} "
                      f"({', '.join(dtc_status_names(d['status'])) or 'none'})")
        elif a.cmd == "clear-dtc":
            t.clear_dtc()
            t.say("DTCs cleared (group 0xFFFFFF)")
    finally:
        if own:
            close_client(client)
    return EXIT_OK


def main(argv=None, out=sys.stdout, err=sys.stderr) -> int:
    ap = parser()
    try:
        a = ap.parse_args(argv)
    except SystemExit as e:
        return EXIT_OK if e.code == 0 else EXIT_USAGE
    if not a.cmd:
        ap.print_usage(err)
        print("navecu_uds: a COMMAND is needed", file=err)
        return EXIT_USAGE
    if not a.verbose:  # udsoncan logs every negative response; the tool reports it once
        logging.getLogger("UdsClient").setLevel(logging.CRITICAL)
        logging.getLogger("isotp").setLevel(logging.CRITICAL)
    try:
        return run(a, table(), out)
    except UsageError as e:
        print(f"navecu_uds: {e}", file=err)
        return EXIT_USAGE
    except InputError as e:
        print(f"navecu_uds: bad input: {e}", file=err)
        return EXIT_INPUT
    except Exception as e:  # noqa: BLE001 - sorted into the exit statuses below
        return report(e, err)


def report(e: Exception, err, prog: str = "navecu_uds") -> int:
    """Say what went wrong (a negative response by its NRC's name) and return the exit
    status; the flash tool (navecu_flash.py) reports the same way."""
    from udsoncan.exceptions import (InvalidResponseException, NegativeResponseException,
                                     TimeoutException, UnexpectedResponseException)
    if isinstance(e, NegativeResponseException):
        r = e.response
        svc = r.service.get_name() if r.service is not None else "?"
        print(f"{prog}: negative response 0x{r.code:02X} {nrc_name(r.code)} to {svc} "
              f"(0x{r.service.request_id():02X})", file=err)
        return EXIT_NRC
    if isinstance(e, TimeoutException):
        print(f"{prog}: no answer: {e}", file=err)
        return EXIT_TRANSPORT
    if isinstance(e, (InvalidResponseException, UnexpectedResponseException, WireError)):
        print(f"{prog}: malformed answer: {e}", file=err)
        return EXIT_TRANSPORT
    if isinstance(e, TransportError):
        print(f"{prog}: transport: {e}", file=err)
        return EXIT_TRANSPORT
    if isinstance(e, OSError) or type(e).__module__.split(".")[0] in ("can", "isotp",
                                                                      "tools"):
        print(f"{prog}: transport: {type(e).__name__}: {e}", file=err)
        return EXIT_TRANSPORT
    raise e


if __name__ == "__main__":
    sys.exit(main())
