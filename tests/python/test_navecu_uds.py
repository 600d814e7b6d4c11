"""The host tool tools/navecu_uds.py without a bus: its TOML, range checks, NRC names and
exit statuses, then the whole tool against the log runner (tools/uds_logrun.py:
build/host/navecu replaying the session's frames), which is the firmware's own UDS server
and ISO-TP channel, so every answer here is the firmware's.
"""
import io
import math
import os
import struct
from pathlib import Path

import pytest
import udsoncan

from tools import gen_params, gen_stationary_log
from tools import navecu_uds as nu
from tools.vcan import uds_check

ROOT = Path(__file__).resolve().parents[2]
NAVECU = os.environ.get("NAVECU_BIN", str(ROOT / "build" / "host" / "navecu"))
TAB = nu.table()


def f32(x):
    return struct.unpack(">f", struct.pack(">f", x))[0]


def defaults():
    """{name: default in its unit} of the table (a vehicle default: the native profile's
    values are not in the table, so a value inside the range)."""
    out = {}
    for p in gen_params.load():
        if p["type"] == "enum":
            out[p["name"]] = p["default"]
        elif p["vehicle_default"]:
            out[p["name"]] = (p["min"] + p["max"]) / 2
        else:
            out[p["name"]] = p["default"]
    return out


# ---------------------------------------------------------------- offline
def test_names_units_and_dids_are_the_tables():
    params = gen_params.load()
    assert list(TAB) == [p["name"] for p in params]
    assert nu.default_ids() == (0x7A0, 0x7A8)


def test_toml_round_trip_of_every_parameter(tmp_path):
    vals = {n: nu.check_value(TAB[n], v) for n, v in defaults().items()}
    path = tmp_path / "p.toml"
    path.write_text(nu.to_toml(vals, TAB))
    back = nu.read_toml(str(path), TAB)
    assert back == vals
    assert nu.to_toml(back, TAB) == path.read_text()


def test_wire_round_trip_gives_the_same_float32_and_a_short_decimal():
    for name, v in defaults().items():
        p = TAB[name]
        v = nu.check_value(p, v)
        payload = nu.to_wire(p, v)
        back = nu.from_wire(p, payload)
        assert nu.to_wire(p, back) == payload, name  # the same bytes again
        if p["type"] in ("real", "vec3"):
            xs = back if p["type"] == "vec3" else [back]
            orig = v if p["type"] == "vec3" else [v]
            for x, o in zip(xs, orig):
                assert f32(x * p["factor"]) == f32(o * p["factor"]), name
                assert len(repr(x)) <= 10, (name, x)  # 206.2648, not 206.26480102539062


def test_wire_encoding_is_si_float32_big_endian():
    p = TAB["imu_mount_rad"]  # degrees in the table, radians on the wire
    assert nu.to_wire(p, [0.0, 0.0, 90.0]) == struct.pack(">3f", 0.0, 0.0, math.pi / 2)
    assert nu.to_wire(TAB["level_s"], 45) == b"\x00\x2d"
    assert nu.to_wire(TAB["gnss_accuracy"], "declared") == b"\x01"


@pytest.mark.parametrize("name", [n for n, p in TAB.items() if p["type"] != "enum"])
def test_range_checked_before_sending(name):
    p = TAB[name]
    lo, hi = p["min"], p["max"]
    step = 1 if p["type"] == "u16" else max(abs(hi - lo) * 1e-6, 1e-12)

    def val(x):  # a vec3's other two components inside the range
        return [x, hi, hi] if p["type"] == "vec3" else x

    nu.check_value(p, val(hi))
    with pytest.raises(nu.InputError, match="outside"):
        nu.check_value(p, val(hi + step))
    with pytest.raises(nu.InputError, match="outside"):
        nu.check_value(p, val(lo - step))
    if p["min_exclusive"]:
        with pytest.raises(nu.InputError, match="outside"):
            nu.check_value(p, val(lo))
    else:
        nu.check_value(p, val(lo))


def test_bad_values_refused():
    with pytest.raises(nu.InputError, match="not one of"):
        nu.check_value(TAB["gnss_accuracy"], "guessed")
    with pytest.raises(nu.InputError, match="not an integer"):
        nu.check_value(TAB["level_s"], 30.5)
    with pytest.raises(nu.InputError, match="not an integer"):
        nu.check_value(TAB["level_s"], True)
    with pytest.raises(nu.InputError, match="three numbers"):
        nu.check_value(TAB["gnss_lever_b_m"], [1.0, 2.0])
    with pytest.raises(nu.InputError, match="finite"):
        nu.check_value(TAB["gnss_corr_s"], float("nan"))
    with pytest.raises(nu.InputError, match="finite"):
        nu.check_value(TAB["gnss_corr_s"], "20")


def test_a_bad_file_names_every_bad_entry(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('level_s = 0\nnot_a_param = 1\ngnss_accuracy = "guessed"\n')
    with pytest.raises(nu.InputError) as e:
        nu.read_toml(str(path), TAB)
    msg = str(e.value)
    assert "level_s: 0 outside" in msg and "not_a_param" in msg and "guessed" in msg
    path.write_text("level_s = = 3\n")
    with pytest.raises(nu.InputError, match="not TOML"):
        nu.read_toml(str(path), TAB)
    with pytest.raises(nu.InputError, match="No such file"):
        nu.read_toml(str(tmp_path / "missing.toml"), TAB)


def test_nrc_names_are_iso_14229s():
    assert nu.nrc_name(0x33) == "securityAccessDenied"
    assert nu.nrc_name(0x35) == "invalidKey"
    assert nu.nrc_name(0x36) == "exceedNumberOfAttempts"
    assert nu.nrc_name(0x37) == "requiredTimeDelayNotExpired"
    assert nu.nrc_name(0x7F) == "serviceNotSupportedInActiveSession"
    assert nu.nrc_name(0x72) == "generalProgrammingFailure"
    assert nu.nrc_name(0xA0) == "reservedForSpecificConditionsNotCorrect"
    assert nu.nrc_name(0x01) == "ISOSAEReserved"
    # against udsoncan's own table (written independently): the same names, capitalised
    # (udsoncan writes 0x78's hyphen as '_')
    def norm(s):
        return s.lower().replace("_", "").replace("-", "")
    for code, name in nu.NRC_NAMES.items():
        theirs = udsoncan.Response.Code.get_name(code)
        assert theirs is not None and norm(theirs) == norm(name), (hex(code), theirs, name)


def test_dtc_names():
    # docs/can.md's DTC table (dtc branch): 3 bytes D10187 is U1101-87, 510196 C1101-96
    assert nu.dtc_name(0xD10187) == "U1101-87"
    assert nu.dtc_name(0x510196) == "C1101-96"
    assert nu.dtc_name(0x012345) == "P0123-45"
    assert nu.dtc_name(0x9ABCDE) == "B1ABC-DE"
    assert nu.dtc_status_names(0x09) == ["testFailed", "confirmedDTC"]
    assert nu.dtc_status_names(0x50) == ["testNotCompletedSinceLastClear",
                                         "testNotCompletedThisOperationCycle"]


def test_key_is_the_documented_demonstration_key():
    for seed in (0, 1, 0x12345678, 0xFFFFFFFF, 0x4E415645):
        assert nu.key_of_seed(seed) == uds_check.key_of_seed(seed)
    # by hand: seed 0x4E415645 -> x = 0, rotl 0, + 0x43553136
    assert nu.key_of_seed(0x4E415645) == 0x43553136


def wrong_key(level, seed, params=None):  # udsoncan's security_algo signature
    return struct.pack(">I", nu.key_of_seed(struct.unpack(">I", bytes(seed))[0]) ^ 1)


def run(*argv):
    out, err = io.StringIO(), io.StringIO()
    rc = nu.main(list(map(str, argv)), out=out, err=err)
    return rc, out.getvalue(), err.getvalue()


def test_exit_status_usage():
    assert run()[0] == nu.EXIT_USAGE
    assert run("frobnicate")[0] == nu.EXIT_USAGE
    assert run("read")[0] == nu.EXIT_USAGE
    rc, _, err = run("--log-runner", "write", "level_s")
    assert rc == nu.EXIT_USAGE and "NAME=VALUE" in err
    assert run("--help")[0] == nu.EXIT_OK


def test_exit_status_bad_input_before_the_bus(tmp_path):
    # a channel that does not exist: the input is refused before it is opened
    bus = ["--interface", "virtual", "--channel", "none"]
    rc, _, err = run(*bus, "write", "level_s=0")
    assert rc == nu.EXIT_INPUT and "outside [1, 600] s" in err
    rc, _, err = run(*bus, "read", "no_such_param")
    assert rc == nu.EXIT_INPUT and "not a parameter" in err
    rc, _, err = run(*bus, "load", tmp_path / "missing.toml")
    assert rc == nu.EXIT_INPUT


def test_exit_status_transport():
    rc, _, err = run("--log-runner", "--navecu", "/nonexistent/navecu", "info")
    assert rc == nu.EXIT_TRANSPORT and "missing" in err
    rc, _, err = run("--log-runner", "--navecu", NAVECU, "--navecu-arg=--bogus", "info")
    assert rc == nu.EXIT_TRANSPORT and "navecu: bad or missing value for --bogus" in err, err
    # python-can's virtual bus: nobody answers
    rc, _, err = run("--interface", "virtual", "--channel", "navecu_uds_test", "--timeout",
                     "0.2", "info")
    assert rc == nu.EXIT_TRANSPORT and "no answer" in err, err


# ---------------------------------------------------------------- the log runner
@pytest.fixture
def lr(tmp_path):
    """The tool's main() on the log runner, one power-on session in tmp_path."""
    assert Path(NAVECU).exists(), f"{NAVECU} missing: make build/host/navecu"
    base = ["--log-runner", "--navecu", NAVECU, "--session", tmp_path / "session.log",
            "--nvm", tmp_path / "nvm.bin", "--timeout", "10"]

    def go(*argv):
        return run(*base, *argv)
    go.tmp = tmp_path
    return go


def test_log_runner_info_and_dump_defaults(lr):
    rc, out, err = lr("info")
    assert rc == 0, err
    assert "sw_version: navecu 0.16.0-dev" in out and "serial: NAVECU-00000000" in out
    assert "vehicle: native" in out and "build: host f32 " in out
    rc, text, err = lr("dump")
    assert rc == 0, err
    vals = nu.read_toml_text(text, TAB)
    for name, p in TAB.items():
        if p["vehicle_default"]:
            continue
        v = vals[name]
        if p["type"] in ("real", "vec3"):
            assert nu.to_wire(p, v) == nu.to_wire(p, nu.check_value(p, p["default"])), name
        else:
            assert v == p["default"], name
    assert vals["uds_request_id"] == 0x7A0 and "uds_request_id = 0x7A0" in text


def test_log_runner_dump_edit_load_dump(lr):
    a = lr.tmp / "a.toml"
    assert lr("dump", "--toml", a)[0] == 0
    vals = nu.read_toml(str(a), TAB)
    vals.update({"level_s": 45, "gnss_lever_b_m": [1.0, -0.5, 0.25],
                 "imu_mount_rad": [0.0, 180.0, -90.0], "gyro_arw_rad_rts": 0.42,
                 "gnss_accuracy": "declared", "dyn_rate_hz": 0})
    edited = lr.tmp / "edited.toml"
    edited.write_text(nu.to_toml(vals, TAB))
    rc, out, err = lr("load", edited)
    assert rc == 0, err
    assert f"loaded {len(TAB) - 2} parameters" in out  # the two read-only IDs compared
    rc, text, err = lr("dump")
    assert rc == 0, err
    assert text == edited.read_text()
    rc, out, _ = lr("read", "imu_mount_rad", "level_s")
    assert out == "imu_mount_rad = 0.0,180.0,-90.0\nlevel_s = 45\n"


def test_log_runner_write_order_within_the_ecus_rules(lr):
    """imu_rate_hz = 20 first is refused while nav_rate_hz is 50 (the output rates within
    the IMU rate, the ECU's rule): tried again after nav_rate_hz and dyn_rate_hz."""
    rc, out, err = lr("write", "imu_rate_hz=20", "nav_rate_hz=10", "dyn_rate_hz=20")
    assert rc == 0, err
    assert lr("read", "imu_rate_hz", "nav_rate_hz", "dyn_rate_hz")[1] == \
        "imu_rate_hz = 20\nnav_rate_hz = 10\ndyn_rate_hz = 20\n"
    # a value no order makes valid: the ECU's 0x31
    rc, _, err = lr("write", "nav_rate_hz=30")
    assert rc == nu.EXIT_NRC and "0x31 requestOutOfRange" in err


def test_log_runner_load_refuses_a_changed_read_only_id(lr, tmp_path):
    path = tmp_path / "ids.toml"
    path.write_text("level_s = 50\nuds_request_id = 0x7B0\n")
    rc, _, err = lr("load", path)
    assert rc == nu.EXIT_INPUT and "read-only over UDS" in err
    assert lr("read", "level_s")[1] == "level_s = 30\n"  # nothing was written


def test_log_runner_negative_responses_by_name(lr):
    rc, _, err = lr("write", "uds_request_id=0x7B0")  # read-only: the ECU's 0x31
    assert rc == nu.EXIT_NRC
    assert "negative response 0x31 requestOutOfRange to WriteDataByIdentifier (0x2E)" in err


def test_log_runner_reset_then_the_ecu_answers_and_unlocks_again(lr):
    """ECUReset restarts the application in the default session, locked (which
    configuration it restarts with is the firmware's: docs/can.md); the tool's next
    write enters the extended session and unlocks again."""
    assert lr("write", "gnss_lever_b_m=1,-0.5,0.25")[0] == 0
    rc, out, err = lr("reset")
    assert rc == 0 and "reset type 1" in out, err
    rc, out, err = lr("write", "level_s=45")
    assert rc == 0, err
    assert lr("read", "level_s")[1] == "level_s = 45\n"


def test_log_runner_security(lr):
    """The tool's unlock bypassed: the raw requests through its client."""
    a = nu.parser().parse_args(["--log-runner", "--navecu", NAVECU, "--session",
                                str(lr.tmp / "session.log"), "--timeout", "10", "info"])
    client = nu.open_client(a, TAB)
    try:
        p = TAB["level_s"]

        def nrc(fn):
            try:
                fn()
                return None
            except udsoncan.exceptions.NegativeResponseException as e:
                return e.response.code
        assert nrc(lambda: client.write_data_by_identifier(0x0204, nu.to_wire(p, 46))) == 0x7F
        client.change_session(3)
        assert nrc(lambda: client.write_data_by_identifier(0x0204, nu.to_wire(p, 46))) == 0x33
        client.config["security_algo"] = wrong_key
        assert [nrc(lambda: client.unlock_security_access(1)) for _ in range(3)] == \
            [0x35, 0x35, 0x36]
        assert nrc(lambda: client.request_seed(1)) == 0x37
    finally:
        nu.close_client(client)
    rc, _, err = lr("write", "level_s=46")  # the same power-on: still in the delay
    assert rc == nu.EXIT_NRC and "0x37 requiredTimeDelayNotExpired to SecurityAccess" in err


def test_log_runner_save_then_power_cycle_keeps_the_parameters(lr, tmp_path):
    assert lr("write", "level_s=45", "gyro_arw_rad_rts=0.42")[0] == 0
    rc, _, err = lr("save")
    assert rc == 0, err
    (tmp_path / "session.log").unlink()  # a power cycle: a new session on the same NVM
    Path(str(tmp_path / "session.log") + ".nvm0").unlink()
    assert lr("read", "level_s", "gyro_arw_rad_rts")[1] == \
        "level_s = 45\ngyro_arw_rad_rts = 0.42\n"


IMU_SILENT_DTC = 0xD10187  # U1101-87, IMU_STALE (docs/can.md, "Diagnostic trouble codes")
TEST_FAILED, CONFIRMED = 0x01, 0x08


def test_log_runner_dtc_of_the_silent_imu(tmp_path):
    """The fault injected on the log runner: IMU samples for 1 s, then none. Its DTC
    fails once the IMU is stale (0.5 s of bus time without a sample), is confirmed 2 s
    later, is read, cleared, and right after the clear is no longer confirmed."""
    a = nu.parser().parse_args(["--log-runner", "--navecu", NAVECU, "--session",
                                str(tmp_path / "session.log"), "--timeout", "10", "info"])
    client = nu.open_client(a, TAB)
    try:
        bus, t = client._navecu_bus, nu.Tool(client, TAB)

        def status():
            client.tester_present()  # one pass of the firmware at this bus time first
            return {d["id"]: d["status"] for d in t.dtc()["dtcs"]}.get(IMU_SILENT_DTC, 0)
        bus.inject([m for m in gen_stationary_log.generate(duration_s=1.0)
                    if m.arbitration_id in (0x100, 0x101)])
        alive = status()
        bus.advance(1.0)
        failing = status()
        bus.advance(2.5)
        confirmed = status()
        t.clear_dtc()
        cleared = status()
    finally:
        nu.close_client(client)
    assert alive & TEST_FAILED == 0, hex(alive)
    assert failing & (TEST_FAILED | CONFIRMED) == TEST_FAILED, hex(failing)
    assert confirmed & (TEST_FAILED | CONFIRMED) == TEST_FAILED | CONFIRMED, hex(confirmed)
    assert cleared & CONFIRMED == 0, hex(cleared)


def test_log_runner_session_with_a_malformed_line_and_dump_to_a_bad_path(lr, capfd):
    """A session log with a line navecu skips (edited by hand, cut by a crash) was a
    python-can traceback ('not enough values to unpack'); now the line is skipped and
    counted, as navecu skips it. dump --toml into a folder that does not exist was
    'transport: FileNotFoundError', exit 2: it is a bad file, exit 3."""
    assert lr("info")[0] == 0
    session = lr.tmp / "session.log"
    session.write_text(session.read_text() + "(0.5) can0 GARBAGE\n")
    rc, out, err = lr("info")
    assert rc == 0 and "serial: NAVECU-00000000" in out, err
    assert f"1 malformed line of {session} skipped" in capfd.readouterr().err
    rc, _, err = lr("dump", "--toml", str(lr.tmp / "no" / "such" / "ecu.toml"))
    assert rc == nu.EXIT_INPUT and "ecu.toml: No such file or directory" in err, err
