"""The host tool (tools/navecu_uds.py) against a live navecu on vcan0 (run inside
with_vcan.sh): the configuration round trip, the security refusals and the DTCs.

    python -m tools.vcan.navecu_uds_check [--navecu build/host/navecu]

Starts build/host/navecu --can vcan0 --nvm NVM (a fresh image in a temporary directory;
no IMU, GNSS or wheel frames until the DTC step), then runs the tool's commands through
its main() exactly as on the command line, and a few raw requests through its Tool
class, and prints one JSON object with what each step gave (exit statuses, the dumps,
the NRCs) for tests/python/test_navecu_uds_live.py to judge:

  round trip  dump -> edit (five parameters of four types) -> load -> save -> navecu
              stopped and started again on the same NVM image -> dump
  security    a WriteDataByIdentifier in the extended session without SecurityAccess;
              three wrong keys, then a request in the delay (raw and through the tool)
  DTCs        IMU samples for 1 s, then none: ReadDTCInformation once the silent IMU's
              DTC is confirmed, ClearDiagnosticInformation, ReadDTCInformation again

Exit status 0 when every step ran (the verdicts are the test's), 1 when one raised, 2 with
"NO VCAN" when vcan0 is missing.
"""
import io
import struct
import sys
import tempfile
import time
import traceback
from pathlib import Path

from tools import gen_stationary_log
from tools import navecu_uds as nu
from tools.vcan.uds_check import IFACE, check_main, start_navecu, stop_navecu

# the edit of the round trip: a u16, two vec3 (one in degrees), a real in deg/sqrt(h) and
# an enum, each away from its default
EDIT = {"level_s": 45, "gnss_lever_b_m": [1.0, -0.5, 0.25], "imu_mount_rad": [0.0, 0.0, 90.0],
        "gyro_arw_rad_rts": 0.42, "gnss_accuracy": "declared"}
IMU_SILENT_DTC = 0xD10187  # U1101-87 (docs/can.md, "Diagnostic trouble codes"), confirmed
IMU_STALE_S = 0.5           # without an IMU sample: IMU_STALE
IMU_SILENT_CONFIRM_S = 2.0  # then its DTC is confirmed
IMU_S = 1.0                 # IMU samples sent before the silence


def send_imu(seconds):
    """IMU pairs of a car at rest at 100 Hz (tools/gen_stationary_log.py's, E2E-valid),
    paced in real time on vcan0; the number of frames sent."""
    import can
    frames = [m for m in gen_stationary_log.generate(duration_s=seconds)
              if m.arbitration_id in (0x100, 0x101)]
    with can.Bus(interface="socketcan", channel=IFACE) as tx:
        t0 = time.monotonic()
        for m in frames:
            delay = m.timestamp - frames[0].timestamp - (time.monotonic() - t0)
            if delay > 0:
                time.sleep(delay)
            tx.send(can.Message(arbitration_id=m.arbitration_id, data=m.data,
                                is_extended_id=False))
    return len(frames)


def tool(*argv):
    """The tool's main() on argv: (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    try:
        rc = nu.main(["--channel", IFACE, *map(str, argv)], out=out, err=err)
    except Exception:  # noqa: BLE001 - a bug of the tool: reported, the other steps go on
        return -1, out.getvalue(), err.getvalue() + traceback.format_exc()
    return rc, out.getvalue(), err.getvalue()


def raw(fn):
    """(None, result) when positive, (the NRC, None) when negative, (-1, the traceback)
    when it raised otherwise."""
    from udsoncan.exceptions import NegativeResponseException
    try:
        return None, fn()
    except NegativeResponseException as e:
        return e.response.code, None
    except Exception:  # noqa: BLE001 - reported, the other steps go on
        return -1, traceback.format_exc()


def wrong_key(level, seed, params=None):  # udsoncan's security_algo signature
    return struct.pack(">I", nu.key_of_seed(struct.unpack(">I", bytes(seed))[0]) ^ 1)


def client_args():
    return nu.parser().parse_args(["--channel", IFACE, "info"])


def run(binary, work: Path):
    r = {}
    tab = nu.table()
    nvm = work / "nvm.bin"
    proc = start_navecu(binary, "--nvm", nvm)
    try:
        r["info"] = tool("info")
        a_toml, b_toml, edited = work / "a.toml", work / "b.toml", work / "edited.toml"
        r["dump_a"] = tool("dump", "--toml", a_toml)[0]
        values = nu.read_toml(str(a_toml), tab)
        values.update(EDIT)
        edited.write_text(nu.to_toml(values, tab), encoding="utf-8")
        r["edited"] = edited.read_text()
        r["dump_a_text"] = a_toml.read_text()
        r["load"] = tool("load", edited)
        r["dump_loaded"] = tool("dump")
        r["save"] = tool("save")
        r["firmware_summary_1"] = stop_navecu(proc)
        proc = start_navecu(binary, "--nvm", nvm)
        r["dump_restarted"] = tool("dump")
        # raw requests: a write without SecurityAccess, then three wrong keys
        client = nu.open_client(client_args(), tab)
        try:
            t = nu.Tool(client, tab)
            p = tab["level_s"]
            client.change_session(nu.SESSION_EXTENDED)
            r["nrc_write_locked"] = raw(lambda: client.write_data_by_identifier(
                int(p["did"]), nu.to_wire(p, 46)))[0]
            client.config["security_algo"] = wrong_key
            r["nrc_wrong_keys"] = [raw(lambda: client.unlock_security_access(1))[0]
                                   for _ in range(3)]
            r["nrc_in_delay"] = raw(lambda: client.request_seed(1))[0]
        finally:
            nu.close_client(client)
        r["write_in_delay"] = tool("write", "level_s=46")
        # the fault: IMU samples for 1 s, then none; its DTC read after it is confirmed
        r["imu_frames"] = send_imu(IMU_S)
        time.sleep(IMU_STALE_S + IMU_SILENT_CONFIRM_S + 1.0)
        r["dtc_cli"] = tool("dtc")
        client = nu.open_client(client_args(), tab)
        try:
            t = nu.Tool(client, tab)
            r["dtc_before"] = raw(lambda: t.dtc())
            r["dtc_supported"] = raw(lambda: t.dtc(supported=True))
            r["dtc_count"] = raw(lambda: t.dtc_count())
            r["nrc_clear"] = raw(lambda: t.clear_dtc())[0]
            r["dtc_after"] = raw(lambda: t.dtc())
        finally:
            nu.close_client(client)
        r["clear_cli"] = tool("clear-dtc")
    finally:
        r["firmware_summary"] = stop_navecu(proc)
    return r


def run_in_tmp(binary):
    with tempfile.TemporaryDirectory(prefix="navecu_uds_check_") as d:
        return run(binary, Path(d))


def main(argv=None):
    return check_main(__doc__, run_in_tmp, argv)


if __name__ == "__main__":
    sys.exit(main())
