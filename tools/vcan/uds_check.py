"""navecu's UDS server live on vcan0, as a tester with udsoncan sees it (run inside
with_vcan.sh).

    python -m tools.vcan.uds_check [--navecu build/host/navecu]

Starts build/host/navecu --can vcan0 (the whole application: its UDS server on its ISO-TP
channel, request 0x7A0 / response 0x7A8 by default), talks to it with udsoncan over
can-isotp (both independent of the firmware), and prints one JSON object: what every step
answered (values read, negative response codes, the firmware's summary at exit), for
tests/python/test_uds_live.py to judge. The client follows docs/can.md, "Diagnostics
(UDS)", alone: the DID encodings (float32 / uint16 / uint8 big-endian, SI) and the
demonstration seed-key algorithm. Exit status 0 when every step ran (the verdicts are the
test's), 1 when one raised, 2 with "NO VCAN" when vcan0 is missing.
"""
import argparse
import json
import os
import signal
import struct
import subprocess
import sys
import time
import traceback
from pathlib import Path

import can
import isotp
import udsoncan
from udsoncan.client import Client
from udsoncan.connections import PythonIsoTpConnection
from udsoncan.exceptions import NegativeResponseException

from tools import gen_params
from tools.navecu_uds import ID_DIDS

ROOT = Path(__file__).resolve().parents[2]
IFACE = "vcan0"


def key_of_seed(seed: int) -> int:
    """docs/can.md: k = rotl32(s XOR 0x4E415645, 5) + 0x43553136 (mod 2^32)"""
    x = seed ^ 0x4E415645
    return ((((x << 5) | (x >> 27)) & 0xFFFFFFFF) + 0x43553136) & 0xFFFFFFFF


def security_algo(level, seed, params=None):  # udsoncan's signature
    return struct.pack(">I", key_of_seed(struct.unpack(">I", seed)[0]))


def wrong_algo(level, seed, params=None):
    return struct.pack(">I", key_of_seed(struct.unpack(">I", seed)[0]) ^ 1)


class Codec(udsoncan.DidCodec):
    """A struct format, one value or a tuple."""

    def __init__(self, fmt):
        self.fmt = fmt

    def encode(self, *v):
        if len(v) == 1 and isinstance(v[0], (list, tuple)):
            v = v[0]
        return struct.pack(self.fmt, *v)

    def decode(self, payload):
        v = struct.unpack(self.fmt, payload)
        return v[0] if len(v) == 1 else list(v)

    def __len__(self):
        return struct.calcsize(self.fmt)


class Text(udsoncan.DidCodec):
    """An ASCII string of any length (the read reply's last DID, or read alone)."""

    def encode(self, v):
        return v.encode()

    def decode(self, payload):
        return payload.decode("ascii")

    def __len__(self):
        raise udsoncan.DidCodec.ReadAllRemainingData


FORMATS = {"u16": ">H", "enum": ">B", "real": ">f", "vec3": ">3f"}


def codecs(params):
    out = {int(p["did"]): Codec(FORMATS[p["type"]]) for p in params}
    out.update({did: Text() for did in ID_DIDS})
    out[0xF1A1] = Codec(">BBBBI")  # NVM status: version, source, loaded, refused, seq
    return out


def nrc_of(fn):
    """the negative response code fn() got, or None when it was positive"""
    try:
        fn()
        return None
    except NegativeResponseException as e:
        return e.response.code


def start_navecu(binary, *args):
    """navecu --can vcan0 [args], once it said it runs"""
    proc = subprocess.Popen([binary, "--can", IFACE, *map(str, args)], stderr=subprocess.PIPE,
                            text=True)
    line = proc.stderr.readline()
    if "running on" not in line:
        raise RuntimeError(f"navecu did not start: {line}{proc.stderr.read()}")
    return proc


def stop_navecu(proc):
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=20)
    return err.strip()


def run(binary, params):
    r = {}
    proc = start_navecu(binary)
    bus = can.Bus(interface="socketcan", channel=IFACE,
                  can_filters=[{"can_id": 0x7A8, "can_mask": 0x7FF, "extended": False}])
    addr = isotp.Address(isotp.AddressingMode.Normal_11bits, txid=0x7A0, rxid=0x7A8)
    stack = isotp.CanStack(bus, address=addr, params={"blocking_send": False, "tx_padding": 0xCC})
    conn = PythonIsoTpConnection(stack)
    config = dict(udsoncan.configs.default_client_config)
    config.update({"data_identifiers": codecs(params), "security_algo": security_algo,
                   "request_timeout": 5.0, "p2_timeout": 2.0, "p2_star_timeout": 6.0})
    try:
        with Client(conn, config=config) as c:
            # every parameter DID, one by one, then every DID at once
            r["params"] = {}
            for p in params:
                v = c.read_data_by_identifier(int(p["did"])).service_data.values[int(p["did"])]
                r["params"][p["name"]] = v
            r["ident"] = {}
            for did, name in ID_DIDS.items():
                r["ident"][name] = c.read_data_by_identifier(did).service_data.values[did]
            # the strings have no length of their own: one of them, last, in a multi read
            dids = [int(p["did"]) for p in params] + [0xF1A0]
            many = c.read_data_by_identifier(dids).service_data.values
            r["many_count"] = len(many)
            r["many_same"] = all(many[int(p["did"])] == r["params"][p["name"]] for p in params)
            # the session answer: P2 50 ms, P2* 5000 ms
            r["nrc_write_default"] = nrc_of(
                lambda: c.write_data_by_identifier(0x0204, 45))
            resp = c.change_session(3)
            r["session_p2"] = [resp.service_data.p2_server_max,
                               resp.service_data.p2_star_server_max]
            r["nrc_write_locked"] = nrc_of(lambda: c.write_data_by_identifier(0x0204, 45))
            r["nrc_reset_locked"] = nrc_of(lambda: c.ecu_reset(1))
            c.unlock_security_access(1)
            r["seed_when_unlocked"] = c.request_seed(1).service_data.seed.hex()
            r["nrc_write_range"] = nrc_of(lambda: c.write_data_by_identifier(0x0204, 0))
            r["nrc_write_uds_id"] = nrc_of(lambda: c.write_data_by_identifier(0x0250, 0x7B0))
            c.write_data_by_identifier(0x0204, 45)
            c.write_data_by_identifier(0x0242, [1.0, -0.5, 0.25])
            r["level_s_back"] = c.read_data_by_identifier(0x0204).service_data.values[0x0204]
            r["lever_back"] = c.read_data_by_identifier(0x0242).service_data.values[0x0242]
            # RoutineControl StoreParameters saves them; a later write stays in RAM only
            r["store_params_rid"] = \
                c.start_routine(0x0200).service_data.routine_id_echo
            r["nrc_unknown_routine"] = nrc_of(lambda: c.start_routine(0x0299))
            c.write_data_by_identifier(0x0204, 30)
            c.tester_present()
            # ECUReset: the response, then the application restarts (default session)
            r["reset_type"] = c.ecu_reset(1).service_data.reset_type_echo
            time.sleep(0.3)
            r["nrc_write_after_reset"] = nrc_of(lambda: c.write_data_by_identifier(0x0204, 45))
            r["level_s_after_reset"] = \
                c.read_data_by_identifier(0x0204).service_data.values[0x0204]
            r["lever_after_reset"] = \
                c.read_data_by_identifier(0x0242).service_data.values[0x0242]
            r["nvm_status"] = c.read_data_by_identifier(0xF1A1).service_data.values[0xF1A1]
            # three wrong keys: 0x35, 0x35, 0x36, then the delay's 0x37
            c.change_session(3)
            c.config["security_algo"] = wrong_algo
            r["nrc_wrong_keys"] = [nrc_of(lambda: c.unlock_security_access(1)) for _ in range(3)]
            r["nrc_in_delay"] = nrc_of(lambda: c.request_seed(1))
            c.config["security_algo"] = security_algo
            r["nrc_unknown_service"] = nrc_of(lambda: c.communication_control(0, 1))
    finally:
        stack.stop()
        bus.shutdown()
        r["firmware_summary"] = stop_navecu(proc)
    return r


def check_main(doc, run_check, argv=None):
    """The main of a live check (this one, dtc_check, navecu_uds_check): --navecu BINARY;
    exit 2 "NO VCAN" without vcan0; run_check(binary)'s dict printed as one JSON line
    (exit 0), or its exception's traceback as {"exception": ...} (exit 1)."""
    ap = argparse.ArgumentParser(description=doc.split("\n")[0])
    ap.add_argument("--navecu", default=os.environ.get("NAVECU_BIN",
                                                       str(ROOT / "build/host/navecu")))
    a = ap.parse_args(argv)
    if not Path("/sys/class/net/" + IFACE).exists():
        print(f"NO VCAN: {IFACE} missing", file=sys.stderr)
        return 2
    try:
        r = run_check(a.navecu)
    except Exception:  # noqa: BLE001 - reported to the test
        print(json.dumps({"exception": traceback.format_exc()}))
        return 1
    print(json.dumps(r))
    return 0


def main(argv=None):
    return check_main(__doc__, lambda binary: run(binary, gen_params.load()), argv)


if __name__ == "__main__":
    sys.exit(main())
