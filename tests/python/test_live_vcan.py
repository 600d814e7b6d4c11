"""The firmware live on a SocketCAN bus: python-can replays a log into
`build/host/navecu --can vcan0`, a python-can recorder keeps what it sends.

vcan comes from tools/vcan/with_vcan.sh (the kernel's, or User-Mode Linux's on machines
without CAN). Under CI a missing vcan fails these tests; elsewhere they are skipped loudly.

- Determinism across transports: the NAV_* frames recorded over vcan at real time and at
  the fastest lossless rate (tools/can_replay.py --fastest: flow control on the firmware's
  NAV_Status) equal, frame for frame, the output of --can-log on the same log: all but
  NAV_Heartbeat, the one time-driven output (sent on the ECU's clock from its start, before
  the replay: different by design), left out by navecu_can.data_driven; the live ECU does
  send it (at 1 Hz of its uptime).
- No loss: 5 minutes of data with --fastest, every frame received by the firmware, none
  lost, rejected or seen after a time jump, every output frame received by the recorder.
- --fastest without a firmware on the bus is a clear error after its timeout, not a hang.
- Interop: can-utils cansend commands take effect, candump shows the firmware's status.
"""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from test_vcan_harness import no_vcan, require_vcan
from tools import navecu_can
from tools.vcan import bus_run

ROOT = Path(__file__).resolve().parents[2]
NAVECU = os.environ.get("NAVECU_BIN", str(ROOT / "build" / "host" / "navecu"))
WITH_VCAN = ROOT / "tools" / "vcan" / "with_vcan.sh"


def gen_log(path, duration_s):
    subprocess.run([sys.executable, "-m", "tools.gen_stationary_log", "--out", path,
                    "--duration-s", str(duration_s), "--roll-deg", "2", "--pitch-deg", "-1"],
                   check=True, capture_output=True, cwd=ROOT)


def reference(log, out):
    """The data-driven payloads of the --can-log run (NAV_Heartbeat left out)."""
    subprocess.run([NAVECU, "--can-log", log, "--out", out], check=True, capture_output=True)
    return navecu_can.data_driven(line.split()[2] for line in Path(out).read_text().splitlines())


def live(*args, timeout=600):
    env = dict(os.environ, NAVECU_BIN=NAVECU, NAVECU_VCAN_TIMEOUT=str(timeout))
    proc = subprocess.run([str(WITH_VCAN), sys.executable, "-m", "tools.vcan.live_check", *args],
                          capture_output=True, text=True, cwd=ROOT, env=env, timeout=timeout + 60)
    require_vcan(proc)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def counters(summary):
    line = summary.split("rejected:", 1)[1].splitlines()[0]
    return {m.group(1).strip(): int(m.group(2))
            for m in re.finditer(r"([a-z ]+?) (\d+)(?:,|$)", line)}


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    d = tmp_path_factory.mktemp("live")
    short, long_ = d / "short.log", d / "five_min.log"
    gen_log(short, 45)
    gen_log(long_, 300)
    return {"short": (short, reference(short, d / "short_ref.log")),
            "long": (long_, reference(long_, d / "long_ref.log"))}


def mode_changes(frames) -> int:
    """The changes of NAV_Status page 0's Mode in 'ID#DATA' frames, in order."""
    db = navecu_can.DEFAULT_DB
    sid = db.get_message_by_name("NAV_Status").frame_id
    modes = []
    for f in frames:
        fid, data = f.split("#")
        if int(fid, 16) == sid:
            m = db.decode_message(sid, bytes.fromhex(data), decode_choices=False)
            if m["StatusPage"] == 0:
                modes.append(m["Mode"])
    return sum(a != b for a, b in zip(modes, modes[1:]))


def test_fastest_lossless_5min_matches_log(logs, tmp_path):
    log, ref = logs["long"]
    out = tmp_path / "nav_vcan.log"
    r = live("--log", str(log), "--fastest", "--out", str(out))
    rp = r["replay"]
    print(f"--fastest: {rp['sent']} frames in {rp['seconds']:.1f} s "
          f"({rp['sent'] / rp['seconds']:.0f} frames/s), window {rp['window']}, "
          f"{rp['waits']} waits (longest {rp['max_wait_ms']} ms), {rp['keepalives']} keepalives, "
          f"longest time between acknowledgements {rp['max_ack_gap_ms']} ms")
    print(r["firmware_summary"])
    frames_in = int(re.search(r"navecu: (\d+) frames in", r["firmware_summary"]).group(1))
    assert frames_in == r["sent"] == 75002              # the firmware received every frame
    c = counters(r["firmware_summary"])
    lost = {k: c[k] for k in ("imu lost", "imu pair broken", "bad counter", "bad crc",
                              "bad dlc", "time jumps")}
    assert all(v == 0 for v in lost.values()), lost
    assert rp["stale_status"] == 0                      # it never waited 0.5 s for input
    # one status page 0 per 10 samples, and one more at each change of Mode between two
    # (output.c: the new Mode is told at once; the replay's window allows for them)
    assert 0 <= rp["acked"] - 30000 // rp["ack_every"] <= mode_changes(r["frames"])
    frames = navecu_can.data_driven(r["frames"])       # all but the time-driven heartbeat
    heartbeats = r["recorded"] - len(frames)
    assert heartbeats >= int(rp["seconds"])             # it went on at 1 Hz of its uptime
    assert len(frames) == len(ref)                      # the recorder received every output
    assert frames == ref                                # payloads and order as --can-log
    # --out: the same frames as a candump log
    assert navecu_can.data_driven(ln.split()[2] for ln in out.read_text().splitlines()) == ref
    # and a client reads it with the DBC: `cantools decode` of the recorded log
    lines = out.read_text().splitlines(keepends=True)
    head = "".join(lines[len(lines) // 2:len(lines) // 2 + 100])  # while navigating
    dec = subprocess.run([sys.executable, "-m", "cantools", "decode",
                          str(ROOT / "firmware" / "can" / "navecu.dbc")], input=head,
                         capture_output=True, text=True, check=True)
    assert "NAV_Position(" in dec.stdout and "NAV_Status(" in dec.stdout, dec.stdout[:500]


def test_real_time_matches_log(logs):
    log, ref = logs["short"]
    r = live("--log", str(log), "--speed", "1")
    assert r["replay_s"] >= 44.0
    assert navecu_can.data_driven(r["frames"]) == ref
    assert r["recorded"] - len(ref) >= 44              # NAV_Heartbeat at 1 Hz, left out


def test_bus_run_as_make_sim_bus(logs, tmp_path):
    """tools/vcan/bus_run.py, the firmware stage of `make sim BUS=vcan0`: --fastest with
    firmware options, recorded to nav.log, equal to the --can-log run's nav_file.log."""
    log, ref = logs["short"]
    try:
        r = bus_run.run(NAVECU, log, tmp_path, "vcan0", 100, ["--level-s", "20"], timeout_s=300)
    except bus_run.BusRunError as e:
        if e.code == 2:
            no_vcan(str(e).splitlines()[0].removeprefix("NO VCAN: "))
        raise
    print("\n".join(bus_run.describe(r)))
    assert r["identical"] and bus_run.lossless(r), r
    assert r["frames_equal"] == r["frames_file"] > 0
    # the option reached both runs: levelling 20 s instead of 30 changes the output
    assert navecu_can.data_driven(bus_run.payloads(tmp_path / "nav_file.log")) != ref
    assert r["heartbeats_bus"] >= 1 and r["heartbeats_file"] >= 44  # counted apart


def test_fastest_without_firmware_is_an_error(logs):
    """Nobody acknowledges: --fastest stops with a clear message after its timeout."""
    log, _ = logs["short"]
    env = dict(os.environ, NAVECU_VCAN_TIMEOUT="120")
    proc = subprocess.run([str(WITH_VCAN), sys.executable, "-m", "tools.can_replay", str(log),
                           "--fastest", "--timeout-s", "1"],
                          capture_output=True, text=True, cwd=ROOT, env=env, timeout=180)
    require_vcan(proc)
    assert proc.returncode == 1, proc.stderr
    assert "no acknowledgement from the firmware for 1 s" in proc.stderr, proc.stderr
    assert "with 0 NAV_Status page 0 received" in proc.stderr, proc.stderr


def test_cansend_candump_interop():
    r = live("--interop")
    # CMD_KnownPosition + CMD_Control SetInitialPosition sent with cansend: levelling (1)
    assert r["status_modes"] and all(m == 1 for m in r["status_modes"]), r


def test_replay_killed_link_down_up_restart(logs):
    """Replay half the log, stop it, take vcan0 down and up, replay the rest: the firmware
    keeps running, reports the silence (IMU-stale status) and the gap (IMU samples lost,
    Fault: a 2-s gap is beyond what it bridges), and counts the refused sends."""
    log, _ = logs["short"]
    r = live("--robust", "--log", str(log))
    print({k: v for k, v in r.items()})
    assert r["alive_after_down_up"] and r["alive"]
    assert r["stale_status_frames"] >= 5
    c = counters(r["firmware_summary"])
    assert c["imu lost"] >= 100 and c["time jumps"] >= 1
    assert "mode: fault" in r["firmware_summary"]
