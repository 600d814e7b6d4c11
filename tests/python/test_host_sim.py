"""End to end: a CAN log through the host firmware (build/host/navecu).

The stationary log is written by tools/gen_stationary_log.py with exact IMU increments
through the real encoding (E2E, remainder carry); the firmware's output log is read back
with python-can and decoded with cantools from the same DBC.
"""
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import can
import cantools
import pytest

from tools import navecu_can

ROOT = Path(__file__).resolve().parents[2]
DBC = ROOT / "firmware" / "can" / "navecu.dbc"
NAVECU = Path(os.environ.get("NAVECU_BIN", ROOT / "build" / "host" / "navecu"))

LAT0_DEG, LON0_DEG, H0_M = 45.0, 10.0, 100.0
R_M_45, R_N_45 = 6367381.8156, 6388838.2901  # WGS-84 radii at 45 deg (test_earth.c)


def run(*args, **kw):
    return subprocess.run([str(a) for a in args], check=True, capture_output=True, text=True, **kw)


@pytest.fixture(scope="module")
def stationary(tmp_path_factory):
    """A 10-minute stationary log (tilted, heading 30 deg) and two firmware runs over it."""
    if not NAVECU.exists():
        pytest.fail(f"{NAVECU} not built: run 'make' first")
    d = tmp_path_factory.mktemp("stationary")
    log = d / "stationary.log"
    run(sys.executable, "-m", "tools.gen_stationary_log", "--out", log,
        "--duration-s", 600, "--imu-rate-hz", 100, "--lat-deg", LAT0_DEG, "--lon-deg", LON0_DEG,
        "--height-m", H0_M, "--heading-deg", 30, "--roll-deg", 2, "--pitch-deg", -1, cwd=ROOT)
    outs = []
    for k in range(2):
        out = d / f"nav{k}.log"
        res = run(NAVECU, "--can-log", log, "--out", out)
        outs.append((out, res.stderr))
    return log, outs


def horiz_dist_m(lat_deg, lon_deg):
    dn = math.radians(lat_deg - LAT0_DEG) * (R_M_45 + H0_M)
    de = math.radians(lon_deg - LON0_DEG) * (R_N_45 + H0_M) * math.cos(math.radians(LAT0_DEG))
    return math.hypot(dn, de)


def test_stationary_10min_within_1m(stationary):
    """NAV_Position at the end of 10 min standing still is within 1 m of the start."""
    _, outs = stationary
    db = cantools.database.load_file(DBC, strict=True)
    pos_id = db.get_message_by_name("NAV_Position").frame_id
    last = None
    n = 0
    with can.LogReader(outs[0][0]) as reader:
        for msg in reader:
            if msg.arbitration_id == pos_id:
                last = db.decode_message(msg.arbitration_id, msg.data)
                n += 1
    assert last is not None, "no NAV_Position frames"
    err = horiz_dist_m(last["Latitude"], last["Longitude"])
    print(f"stationary 600 s: {n} NAV_Position frames, final error {err:.3f} m; {outs[0][1]}")
    # 50 Hz for the 570 s after 30 s of levelling, both ends included
    assert n == 570 * 50 + 1
    assert err < 1.0


def test_output_byte_identical(stationary):
    _, outs = stationary
    assert outs[0][0].read_bytes() == outs[1][0].read_bytes()


def rejections(summary: str) -> dict:
    """The counters of navecu's 'rejected:' summary line, by name."""
    line = summary.split("rejected:", 1)[1].splitlines()[0]
    return {m.group(1).strip(): int(m.group(2)) for m in re.finditer(r"([a-z ]+?) (\d+)(?:,|$)", line)}


def test_nothing_rejected_on_clean_log(stationary):
    _, outs = stationary
    counts = rejections(outs[0][1])
    assert len(counts) == 10 and all(v == 0 for v in counts.values()), counts
    assert re.search(r"\b0 malformed lines skipped", outs[0][1])


def frames_only(path: Path) -> list:
    """The 'ID#DATA' fields of a candump log, without timestamps."""
    return [line.split()[2] for line in path.read_text().splitlines()]


def test_same_frames_at_any_replay_speed(stationary, tmp_path):
    """The time base is the IMU counter: the log replayed 10x faster (receive times
    compressed) or 3x slower gives the same data-driven output frames; only their
    timestamps follow the receive clock, and the time-driven NAV_Heartbeat (one a second
    of the HAL clock, here the log's timestamps), left out of the comparison, goes with it."""
    log, outs = stationary
    all_ref = frames_only(outs[0][0])
    reference = navecu_can.data_driven(all_ref)
    n_hb = len(all_ref) - len(reference)
    assert n_hb > 0
    for scale in (0.1, 3.0):
        src = tmp_path / f"scaled{scale}.log"
        with can.LogReader(log) as reader, can.Logger(str(src)) as writer:
            for msg in reader:
                msg.timestamp *= scale
                writer.on_message_received(msg)
        out = tmp_path / f"out{scale}.log"
        run(NAVECU, "--can-log", src, "--out", out)
        got = frames_only(out)
        assert navecu_can.data_driven(got) == reference, f"replay x{1 / scale:g} differs"
        # about one heartbeat a second of the scaled log
        assert abs((len(got) - len(reference)) - (n_hb - 1) * scale) <= 2, (len(got), scale)


def test_cantools_cli_decodes_output(stationary):
    """`cantools decode firmware/can/navecu.dbc < nav.log` reads the firmware's output."""
    _, outs = stationary
    lines = outs[0][0].read_text().splitlines(keepends=True)
    head = "".join(lines[len(lines) // 2:len(lines) // 2 + 200])  # while navigating
    res = subprocess.run([sys.executable, "-m", "cantools", "decode", str(DBC)], input=head,
                         capture_output=True, text=True, check=True)
    assert "NAV_Position(" in res.stdout and "Latitude: 4" in res.stdout
    assert "NAV_Status(" in res.stdout


def test_bad_log_lines_counted_not_fatal(stationary, tmp_path):
    """A log with garbage, truncated lines and an unknown ID still runs to the end."""
    log, _ = stationary
    lines = log.read_text().splitlines(keepends=True)[:5000]
    bad = (lines[:100] + ["garbage line\n", "(12.5) can0 10\n", "(1.000000) can0 7FF#00\n"]
           + ["(1.0) can0 100#00112233445566778899\n"] + lines[100:])
    src = tmp_path / "bad.log"
    src.write_text("".join(bad))
    out = tmp_path / "out.log"
    res = run(NAVECU, "--can-log", src, "--out", out)
    assert re.search(r"\b3 malformed lines skipped", res.stderr), res.stderr
    # a frame of an identifier navecu does not read is another node's traffic, not refused
    assert re.search(r"foreign frames \(not read, not refused\): 1$", res.stderr, re.M), res.stderr


def test_trailing_garbage_counted(stationary, tmp_path):
    """Malformed lines after the last frame are still counted and reported."""
    log, _ = stationary
    lines = log.read_text().splitlines(keepends=True)[:3000]
    src = tmp_path / "tail.log"
    src.write_text("".join(lines) + "not a frame\n(1.0) can0 12#\n")
    res = run(NAVECU, "--can-log", src, "--out", tmp_path / "out.log")
    assert re.search(r"\b2 malformed lines skipped", res.stderr), res.stderr


def test_usage_errors():
    res = subprocess.run([str(NAVECU)], capture_output=True, text=True)
    assert res.returncode == 2 and "--can-log" in res.stderr
    res = subprocess.run([str(NAVECU), "--help"], capture_output=True, text=True)
    assert res.returncode == 0
    for opt in ("--can-log", "--out", "--imu-rate-hz", "--nav-rate-hz", "--status-rate-hz",
                "--level-s", "--nvm", "--iface", "--help"):
        assert opt in res.stdout
    res = subprocess.run([str(NAVECU), "--can-log", "/nonexistent", "--out", "/tmp/x.log"],
                         capture_output=True, text=True)
    assert res.returncode == 1


def test_supervision_quiet_on_a_clean_log(stationary):
    """Every pass of the loop kicked the watchdog: no late task, no filter reset."""
    _, outs = stationary
    m = re.search(r"supervision: (\d+) filter resets, (\d+) late task passes, (\d+) watchdog "
                  r"kicks", outs[0][1])
    assert m, outs[0][1]
    n_frames = int(re.search(r"(\d+) frames in", outs[0][1]).group(1))
    assert (int(m.group(1)), int(m.group(2)), int(m.group(3))) == (0, 0, n_frames)
    assert "WATCHDOG" not in outs[0][1]


def test_watchdog_expiry_exits_nonzero(stationary, tmp_path):
    """A stuck task (app_poll no longer called after 60 s of bus time, --test-stall-poll-s)
    makes app_tasks_ok withhold the kick; 200 ms later the host's watchdog expires: the run
    ends there with exit status 3 and says so, as the ECU would reset."""
    log, _ = stationary
    r = subprocess.run([str(NAVECU), "--can-log", str(log), "--out", str(tmp_path / "o.log"),
                        "--test-stall-poll-s", "60"], capture_output=True, text=True)
    assert r.returncode == 3, r.stderr
    m = re.search(r"WATCHDOG EXPIRED at ([0-9.]+) s", r.stderr)
    assert m, r.stderr
    # the first frame's time + 60 s of stall + 300 ms until app_poll is late + 200 ms of
    # watchdog timeout, within a frame period or two
    t_first = float(log.read_text().split(")", 1)[0].lstrip("("))
    assert float(m.group(1)) - t_first == pytest.approx(60.5, abs=0.03)


def test_report_filter_at_prints_the_floors_figures_and_changes_no_output(tmp_path):
    """--report-filter-at-s S prints, once S s of IMU samples are processed, what the
    filter knows of the heading and the z gyro (tools/sim/gyro_floor.py's figures): on the
    regression's sim-clean drive at 200 s every sigma is positive and finite and every
    correlation within -1..1; at 0 s the filter has not started and it says so; beyond the
    drive's end (277 s) it says that the time was not reached; the output frames are the
    same every way (a report on stderr, nothing sent)."""
    import json
    import lzma
    case = next(c for c in json.loads((ROOT / "tests/regression/cases.json").read_text())["cases"]
                if c["name"] == "sim-clean")
    log = tmp_path / "in.log"
    log.write_bytes(lzma.decompress((ROOT / "tests/regression" / case["input"]).read_bytes()))
    outs = {}
    for at in ("200", "0", "1000"):
        r = subprocess.run([str(NAVECU), "--can-log", str(log), "--out", str(tmp_path / f"{at}.log"),
                            *case["args"].split(), "--report-filter-at-s", at],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        outs[at] = (r.stderr, (tmp_path / f"{at}.log").read_bytes())
    m = re.search(r"filter at 200\.00 s: car heading sigma ([0-9.]+) deg; z gyro turn-on bias "
                  r"sigma ([0-9.]+) deg/h, in-run ([0-9.]+) deg/h; correlations heading/turn-on "
                  r"([-+][0-9.]+), heading/in-run ([-+][0-9.]+), turn-on/in-run ([-+][0-9.]+) .*"
                  r"scale factor sigma ([0-9]+) ppm", outs["200"][0])
    assert m, outs["200"][0]
    sig = [float(m.group(i)) for i in (1, 2, 3, 7)]
    rho = [float(m.group(i)) for i in (4, 5, 6)]
    assert all(0.0 < s < 1e6 for s in sig) and all(-1.0 <= r <= 1.0 for r in rho)
    assert "filter at 0.00 s: not running" in outs["0"][0]
    assert re.search(r"filter at 1000\.00 s: not reached \(27[0-9.]+ s", outs["1000"][0])
    assert outs["200"][1] == outs["0"][1] == outs["1000"][1]
