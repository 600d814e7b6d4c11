"""The configured IMU rate checked against the data, end to end (firmware/app/imu_rate.h,
docs/can.md): drives from the simulator (tools/sim) through build/host/navecu.

One short drive (standing 12 s, then 10 m/s with a turn) is simulated once at 400 Hz; its
increments summed in fours are the same drive from a 100 Hz IMU, and a third log switches
from 100 Hz to 400 Hz and back while driving (an IMU reconfigured at run time). The GNSS
is the simulator's standalone receiver (5 Hz, 0.1 s latency). navecu runs with the
simulator's sensor options, a 10 s levelling, and NAV_Status at the configured IMU rate,
so the first flagged status follows the epoch that found the mismatch within one sample.
Measured: the usable GNSS epoch after which IMU_RATE_MISMATCH appears, and that nothing
navigates while it is set.
"""
import dataclasses
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from tools import navecu_can as nc
from tools.sim import run, scenario, sensors, trajectory

ROOT = Path(__file__).resolve().parents[2]
NAVECU = os.environ.get("NAVECU_BIN", str(ROOT / "build" / "host" / "navecu"))

DRIVE = """name = "imu-rate"
[start]
lat_deg = 45.0
lon_deg = 10.0
h_m = 100.0
heading_deg = 30.0
[sim]
imu = "mid-grade"
gnss = "standalone"
[[segment]]
kind = "stop"
duration_s = 12
[[segment]]
kind = "speed"
to_mps = 10
accel_mps2 = 2.0
[[segment]]
kind = "straight"
duration_s = 20
[[segment]]
kind = "turn"
radius_m = 40
angle_deg = 90
[[segment]]
kind = "straight"
duration_s = 25
"""
BASE_HZ = 400
SWITCH = ((0.0, 100), (30.0, 400), (45.0, 100))   # (from t_s, IMU rate) while driving
NAV_MSGS = ("NAV_Position", "NAV_Velocity", "NAV_Attitude")


def _resample(truth, dth, dv, rate_at):
    """The 400 Hz samples as an IMU at rate_at(t) Hz (100 or 400) sends them: each kept
    sample carries the increments summed since the one before (exact integrals)."""
    keep, th, v = [0], [dth[0]], [dv[0]]
    acc_t, acc_v = np.zeros(3), np.zeros(3)
    for k in range(1, len(truth.t_s)):
        acc_t += dth[k]
        acc_v += dv[k]
        if k % (BASE_HZ // rate_at(truth.t_s[k])) == 0:
            keep.append(k)
            th.append(acc_t.copy())
            v.append(acc_v.copy())
            acc_t[:] = 0.0
            acc_v[:] = 0.0
    keep = np.array(keep)
    return dataclasses.replace(truth, t_s=truth.t_s[keep]), np.array(th), np.array(v)


def _write_log(path, truth, dth, dv, wheels, gnss):
    fr = run.frames(truth, dth, dv, wheels, gnss, nc.load_db())
    fr.sort(key=lambda x: (x[0], x[1]))
    nc.write_candump(path, (m for _, _, m in fr))
    return path


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    out = tmp_path_factory.mktemp("imu_rate")
    p = out / "drive.toml"
    p.write_text(DRIVE)
    sc = scenario.load_scenario(p)
    truth = trajectory.generate(sc, BASE_HZ)
    imu, odo = scenario.sensor_specs(sc, "mid-grade", sc["vehicle"])
    dth, dv = sensors.apply_imu(truth, imu, 3)
    wheels = sensors.wheel_speeds(truth, odo, 4)
    gnss = sensors.gnss_epochs(truth, sensors.GNSS_PRESETS["standalone"], 5)
    logs = {"400": _write_log(out / "imu400.log", truth, dth, dv, wheels, gnss)}
    t100, th100, v100 = _resample(truth, dth, dv, lambda t: 100)
    logs["100"] = _write_log(out / "imu100.log", t100, th100, v100, wheels, gnss)
    tsw, thsw, vsw = _resample(truth, dth, dv,
                               lambda t: [r for t0, r in SWITCH if t > t0][-1])
    logs["switch"] = _write_log(out / "switch.log", tsw, thsw, vsw, wheels, gnss)
    fw = run.firmware_args(sensors.PRESETS["mid-grade"], sensors.GNSS_PRESETS["standalone"],
                           odo)
    return {"dir": out, "logs": logs, "fw": fw + ["--level-s", "10"], "truth": truth}


def run_navecu(drive, log, rate_hz, tag=""):
    out = drive["dir"] / f"{Path(log).stem}_at{rate_hz}{tag}.out.log"
    res = subprocess.run([NAVECU, "--can-log", str(log), "--out", str(out),
                          "--imu-rate-hz", str(rate_hz), "--status-rate-hz", str(rate_hz)]
                         + drive["fw"], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    return out, res.stderr


def _lines(path):
    for line in open(path):
        parts = line.split()
        fid, data = parts[2].split("#")
        yield float(parts[0].strip("()")), int(fid, 16), bytes.fromhex(data)


def usable_epochs(log) -> list:
    """Receive times of the GNSS epochs navecu can use (3-D fix, 4 satellites or more)."""
    db = nc.load_db()
    st = db.get_message_by_name("GNSS_Status")
    out = []
    for t, fid, data in _lines(log):
        if fid == st.frame_id:
            m = db.decode_message(fid, data, decode_choices=False)
            if m["FixType"] >= 3 and m["NumSatellites"] >= 4:
                out.append(t)
    return out


def outputs(log) -> dict:
    """NAV_Status page 0 as (t, mismatch flag, Mode, ImuRateMeasured) and the times of the
    navigation frames."""
    db = nc.load_db()
    st = db.get_message_by_name("NAV_Status")
    bit = nc.health_flag(db, "IMU_RATE_MISMATCH")
    nav_ids = {db.get_message_by_name(n).frame_id for n in NAV_MSGS}
    status, nav = [], []
    for t, fid, data in _lines(log):
        if fid == st.frame_id and data[0] & 0x0F == 0:
            m = db.decode_message(fid, data, decode_choices=False)
            status.append((t, bool(m["HealthFlags"] & bit), int(m["Mode"]),
                           float(m["ImuRateMeasured"])))
        elif fid in nav_ids:
            nav.append(t)
    return {"status": status, "nav": np.array(nav)}


def episodes(status) -> list:
    """[(t_on, t_off or None, ImuRateMeasured)] of the IMU_RATE_MISMATCH flag."""
    eps, on = [], None
    for t, flag, _, measured in status:
        if flag and on is None:
            on = (t, measured)
        elif not flag and on is not None:
            eps.append((on[0], t, on[1]))
            on = None
    if on is not None:
        eps.append((on[0], None, on[1]))
    return eps


def epochs_between(epochs, t0, t1) -> int:
    """Usable epochs received in (t0, t1): the status of a sample precedes the frames
    received after that sample at the same time stamp."""
    return sum(1 for t in epochs if t0 < t < t1)


FAULT = nc.choices(nc.load_db(), "NAV_Status", "Mode")
FAULT = next(k for k, v in FAULT.items() if v == "Fault")


@pytest.mark.parametrize("data_hz,cfg_hz", [(400, 100), (100, 400)])
def test_wrong_rate_flagged_within_3_epochs_and_no_navigation(drive, data_hz, cfg_hz):
    """A 400 Hz log configured as 100 Hz, and a 100 Hz log configured as 400 Hz: the
    mismatch is flagged after the third usable GNSS epoch (the first with two intervals
    behind it), with the rate measured from the data in ImuRateMeasured, and holds to the
    end: mode Fault, and not one NAV_Position, NAV_Velocity or NAV_Attitude frame."""
    log = drive["logs"][str(data_hz)]
    out, stderr = run_navecu(drive, log, cfg_hz)
    o = outputs(out)
    eps = episodes(o["status"])
    assert len(eps) == 1, eps
    t_on, t_off, measured = eps[0]
    n = epochs_between(usable_epochs(log), -1.0, t_on)
    print(f"{data_hz} Hz log, rate set to {cfg_hz}: IMU_RATE_MISMATCH at {t_on:.3f} s, after "
          f"usable GNSS epoch {n}; ImuRateMeasured {measured:g} Hz; NAV frames {len(o['nav'])}")
    assert n <= 3
    assert measured == data_hz
    assert t_off is None
    assert len(o["nav"]) == 0
    assert all(mode == FAULT for t, _, mode, _ in o["status"] if t >= t_on)
    assert f"configured {cfg_hz} Hz, the data still disagree (measured {data_hz}.00 Hz" in stderr


@pytest.mark.parametrize("hz", [400, 100])
def test_right_rate_never_flagged(drive, hz):
    """The same logs with the rate set right: never flagged, and the drive is navigated
    to the end (GnssIns) within a few metres of the truth."""
    out, stderr = run_navecu(drive, drive["logs"][str(hz)], hz)
    o = outputs(out)
    assert episodes(o["status"]) == []
    assert "IMU rate mismatch" not in stderr
    assert len(o["nav"]) > 1000
    assert o["status"][-1][2] == 5                               # GnssIns
    assert final_error_m(drive, out) < 5.0


def final_error_m(drive, out) -> float:
    """Horizontal distance of the last NAV_Position from the truth at its receive time."""
    db = nc.load_db()
    pos = db.get_message_by_name("NAV_Position")
    last = None
    for t, fid, data in _lines(out):
        if fid == pos.frame_id:
            last = (t, db.decode_message(fid, data))
    t, m = last
    tr = drive["truth"]
    lat = math.degrees(float(np.interp(t, tr.t_s, tr.lat_rad)))
    lon = math.degrees(float(np.interp(t, tr.t_s, tr.lon_rad)))
    n = math.radians(m["Latitude"] - lat) * 6371000.0
    e = math.radians(m["Longitude"] - lon) * 6371000.0 * math.cos(math.radians(lat))
    return math.hypot(e, n)


def test_rate_change_while_driving(drive):
    """The IMU switches from 100 Hz (configured) to 400 Hz at 30 s and back at 45 s while
    driving: navigation stops within three usable epochs of the switch (flag, Fault, no
    NAV_* frames while it lasts), the flag clears within three epochs of the switch back,
    and navigation re-acquires from GNSS (the course at 10 m/s) and ends within 5 m of
    the truth."""
    log = drive["logs"]["switch"]
    out, stderr = run_navecu(drive, log, 100)
    o = outputs(out)
    eps = episodes(o["status"])
    assert len(eps) == 1, eps
    t_on, t_off, measured = eps[0]
    epochs = usable_epochs(log)
    (t_up, _), (t_down, _) = SWITCH[1], SWITCH[2]
    n_on = epochs_between(epochs, t_up, t_on)
    n_off = epochs_between(epochs, t_down, t_off)
    nav_while = o["nav"][(o["nav"] >= t_on) & (o["nav"] < t_off)]
    t_nav = o["nav"][o["nav"] >= t_off]
    err = final_error_m(drive, out)
    print(f"IMU 100 -> 400 Hz at {t_up:g} s: flagged at {t_on:.3f} s, {n_on} usable epochs "
          f"after the switch (ImuRateMeasured {measured:g} Hz); back to 100 Hz at {t_down:g} "
          f"s: cleared at {t_off:.3f} s, {n_off} epochs after; NAV frames while flagged "
          f"{len(nav_while)}, navigation again at {t_nav[0]:.3f} s; final error {err:.2f} m")
    assert t_up < t_on and n_on <= 3
    assert measured == 400
    assert t_down < t_off and n_off <= 3
    assert len(nav_while) == 0
    assert all(mode == FAULT for t, _, mode, _ in o["status"] if t_on <= t < t_off)
    assert t_nav[0] - t_off < 0.5                                # re-acquired at once
    assert o["status"][-1][2] == 5                               # GnssIns
    assert err < 5.0
    assert "the data match again" in stderr


def _rescaled(src: Path, dst: Path, factor: float) -> Path:
    with open(src) as f, open(dst, "w") as g:
        for line in f:
            t, rest = line.split(" ", 1)
            g.write(f"({float(t.strip('()')) * factor:.6f}) {rest}")
    return dst


def test_decision_independent_of_arrival_times(drive):
    """The check counts samples and reads TimeOfWeek, never arrival times: the 400 Hz log
    configured as 100 Hz replayed 10 times faster and 3 times slower gives the same output
    frames (identifiers and payloads) as at its own speed; NAV_Heartbeat, the one
    time-driven output, left out (nc.data_driven: it follows the receive clock by design)."""
    log = drive["logs"]["400"]
    ref, _ = run_navecu(drive, log, 100)
    hb = nc.time_driven_ids()
    frames = [(fid, data) for _, fid, data in _lines(ref) if fid not in hb]
    for factor, tag in ((0.1, "fast"), (3.0, "slow")):
        other = _rescaled(log, drive["dir"] / f"imu400_{tag}.log", factor)
        out, _ = run_navecu(drive, other, 100, tag)
        assert [(fid, data) for _, fid, data in _lines(out) if fid not in hb] == frames, tag
