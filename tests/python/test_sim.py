"""The simulator end to end: scenario -> sensors -> CAN log -> build/host/navecu -> report.

The proof that truth, encoding and mechanization agree: with perfect sensors (the perfect
IMU and GNSS presets, an odometer without scale error; only the CAN encoding's quantisation,
carried) the firmware's solution over the whole default drive stays within 5 m of the truth.
"""
import json
import os
from pathlib import Path

import can
import pytest

from tools import navecu_can as nc
from tools.sim import run, scenario, trajectory

ROOT = Path(__file__).resolve().parents[2]
NAVECU = os.environ.get("NAVECU_BIN", str(ROOT / "build" / "host" / "navecu"))


@pytest.fixture(scope="module")
def perfect_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("sim")
    # the default drive with a perfect odometer too (the firmware dead-reckons with it)
    scen = out / "default_perfect.toml"
    scen.write_text(scenario.scenario_path("default").read_text() + "\n[odometer]\nmu = 0.0\n")
    rc = run.main(["--scenario", str(scen), "--imu", "perfect", "--gnss", "perfect",
                   "--out", str(out), "--navecu", NAVECU])
    assert rc == 0
    return out


def test_perfect_imu_within_5m(perfect_run):
    rep = json.loads((perfect_run / "report.json").read_text())
    print(f"perfect IMU, {rep['duration_s'] / 60:.1f} min, {rep['distance_m'] / 1000:.1f} km: "
          f"max horizontal error {rep['horizontal_error_m']['max']:.2f} m")
    assert rep["duration_s"] >= 20 * 60
    assert rep["navigating"]
    assert rep["horizontal_error_m"]["max"] < 5.0


def test_report_fields_and_plots(perfect_run):
    rep = json.loads((perfect_run / "report.json").read_text())
    for key in ("duration_s", "distance_m", "horizontal_error_m", "heading_error_deg",
                "final_error_pct_of_distance", "outages"):
        assert key in rep
    assert set(rep["horizontal_error_m"]) == {"rms", "p95", "max", "final"}
    assert set(rep["heading_error_deg"]) == {"rms", "max"}
    assert len(rep["outages"]) >= 2
    for o in rep["outages"]:
        assert {"start_s", "end_s", "distance_m", "max_error_m", "end_error_m"} <= set(o)
    for png in ("track.png", "horizontal_error.png", "heading_error.png"):
        assert (perfect_run / png).stat().st_size > 10_000


def test_no_gnss_frames_in_outages(perfect_run):
    """Outage segments of the scenario have no GNSS frame in the CAN log."""
    truth = trajectory.generate(scenario.load_scenario(scenario.scenario_path("default")), 10)
    db = nc.load_db()
    gnss_ids = {db.get_message_by_name(n).frame_id
                for n in ("GNSS_Position", "GNSS_Velocity", "GNSS_Height", "GNSS_Status")}
    times = []
    with can.LogReader(str(perfect_run / "can_in.log")) as reader:
        times = [m.timestamp for m in reader if m.arbitration_id in gnss_ids]
    assert len(times) > 1000
    for t0, t1, *_ in truth.outages:
        inside = [t for t in times if t0 <= t <= t1]
        assert inside == [], (t0, t1, inside[:3])


# --- scenario tables for the sensors and commands: mounting, odometer, initialization,
# --- calibration (seed 000's experiment, scenarios/seed000.toml); fast, no firmware run
import math  # noqa: E402

import numpy as np  # noqa: E402

from tools.sim import report, sensors  # noqa: E402

SHORT = """name = "short"
[start]
lat_deg = {lat}
lon_deg = 37.5
h_m = 150.0
heading_deg = {heading}
[vehicle]
pitch_per_accel_deg = 0.0
roll_per_lat_accel_deg = 0.0
roughness_deg = 0.0
[[segment]]
kind = "stop"
duration_s = 2
[[segment]]
kind = "speed"
to_mps = 12
accel_mps2 = 2.0
[[segment]]
kind = "straight"
duration_s = 20
"""


def short_scenario(tmp_path, extra="", lat=56.0, heading=10.0):
    p = tmp_path / "short.toml"
    p.write_text(SHORT.format(lat=lat, heading=heading) + extra)
    return scenario.load_scenario(p)


def decode(db, msg):
    return db.decode_message(msg.arbitration_id, bytes(msg.data), decode_choices=False)


def test_scenario_tables_defaults_and_validation(tmp_path):
    sc = short_scenario(tmp_path)
    assert sc["imu_mounting"] == {"roll_deg": 0.0, "pitch_deg": 0.0, "yaw_deg": 0.0,
                                 "configured": False, "automatic": False}
    assert sc["odometer"] == {} and "calibration" not in sc
    assert sc["initialization"] == {"heading_reference": "car", "heading_error_deg": 0.0}
    for bad in ("[imu_mounting]\nheading_deg = 1\n", "[odometer]\nscale = 0.01\n",
                "[calibration]\nsource = \"gnss\"\n", "[calibration]\nat_s = 9\nsource = \"map\"\n",
                "[initialization]\nheading_reference = \"nose\"\n"):
        with pytest.raises(ValueError):
            short_scenario(tmp_path, bad)
    # every [odometer] key the format accepts is an OdoSpec field
    fields = set(sensors.OdoSpec.__dataclass_fields__)
    assert scenario._OPTIONAL_TABLES["odometer"] <= fields - {"track_m", "wheelbase_m"}
    # without the tables the default drive keeps its heading command and sensors
    default = scenario.load_scenario(scenario.scenario_path("default"))
    imu, odo = scenario.sensor_specs(default, "mid-grade", default["vehicle"])
    assert imu == sensors.PRESETS["mid-grade"] and odo.mu == sensors.OdoSpec().mu
    assert scenario.heading_command_deg(math.radians(30.004), default) == 30.0


def test_mounting_yaw_rotates_the_specific_force(tmp_path):
    """A level straight drive north along the equator (no Coriolis or transport rate
    across the track, no roughness): the body's lateral specific force is 0, and an IMU
    mounted with yaw psi sees the forward acceleration with the lateral component
    -sin(psi) x forward, i.e. the car moving psi to the left of its own forward axis."""
    sc = short_scenario(tmp_path, "[imu_mounting]\nyaw_deg = -0.15\n", lat=0.0, heading=0.0)
    truth = trajectory.generate(sc, 50)
    imu, _ = scenario.sensor_specs(sc, "perfect", sc["vehicle"])
    assert imu.mounting_yaw_deg == -0.15
    _, dv = sensors.apply_imu(truth, imu, 1)
    psi = math.radians(-0.15)
    moving = truth.speed_mps > 0.0
    # body: nothing lateral but the Coriolis force of the 4e-5 rad of latitude gained
    assert np.abs(truth.dv_b_mps[:, 0]).max() < 5e-9
    np.testing.assert_allclose(dv[:, 0], math.cos(psi) * truth.dv_b_mps[:, 0]
                               - math.sin(psi) * truth.dv_b_mps[:, 1], rtol=0, atol=1e-15)
    ramp = moving & (truth.t_s < 14.0)                            # the 0 -> 12 m/s ramp
    accel = dv[ramp].sum(axis=0)
    assert accel[1] == pytest.approx(12.0 * math.cos(psi), abs=1e-3)
    # the velocity gained points 0.15 deg to the right of the IMU's forward axis
    assert math.degrees(math.atan2(-accel[0], accel[1])) == pytest.approx(-0.15, abs=1e-5)


def test_odometer_mu_from_the_scenario(tmp_path):
    for extra, mu in (("", 0.012), ("[odometer]\nmu = 0.05\n", 0.05)):
        sc = short_scenario(tmp_path, extra)
        truth = trajectory.generate(sc, 50)
        _, odo = scenario.sensor_specs(sc, "perfect", sc["vehicle"])
        assert odo.mu == mu and odo.track_m == sc["vehicle"]["track_m"]
        tw, w = sensors.wheel_speeds(truth, odo, 1)
        cruise = tw > 14.0                                        # 12 m/s straight
        np.testing.assert_allclose(w[cruise], round(12.0 * (1 + mu) / 0.02) * 0.02, atol=1e-9)
        assert np.all(w[tw < 2.0] == 0.0)


def _frames_of(tmp_path, extra, seed=1, heading=10.0):
    sc = short_scenario(tmp_path, extra, heading=heading)
    truth = trajectory.generate(sc, 50)
    imu, odo = scenario.sensor_specs(sc, "perfect", sc["vehicle"])
    dth, dv = sensors.apply_imu(truth, imu, 3 * seed)
    wheels = sensors.wheel_speeds(truth, odo, 3 * seed + 1)
    gnss = sensors.gnss_epochs(truth, sensors.GNSS_PRESETS["none"], 3 * seed + 2)
    cal = sc.get("calibration")
    if cal is not None:
        cal = dict(cal, gnss_epoch=run.calibration_epoch(truth, cal, gnss, 3 * seed + 2))
    db = nc.load_db()
    fr = run.frames(truth, dth, dv, wheels, gnss, db,
                    heading_deg=scenario.heading_command_deg(truth.heading_rad[0], sc),
                    calibration=cal)
    fr.sort(key=lambda x: (x[0], x[1]))
    return sc, truth, db, [(t, m) for t, _, m in fr]


def test_calibration_here_frames(tmp_path):
    sc, truth, db, fr = _frames_of(tmp_path, """
[imu_mounting]
yaw_deg = -0.15
[initialization]
heading_reference = "imu"
heading_error_deg = -0.027
[calibration]
at_s = 12.3
""", heading=10.177)
    name = {db.get_message_by_name(n).frame_id: n
            for n in ("CMD_KnownPosition", "CMD_Control", "IMU_Rate", "IMU_Accel", "GNSS_Position")}
    names = [name.get(m.arbitration_id) for _, m in fr]
    assert "GNSS_Position" not in names                            # GNSS "none"
    known = [i for i, n in enumerate(names) if n == "CMD_KnownPosition"]
    ctrl = [i for i, n in enumerate(names) if n == "CMD_Control"]
    assert len(known) == 2 and len(ctrl) == 2
    # t = 0: the heading of the IMU's axes with the error (10.177 - 0.15 - 0.027, on the
    # DBC's 0.01 deg grid)
    c0 = decode(db, fr[ctrl[0]][1])
    assert c0["Command"] == 2 and c0["HeadingValid"] == 1
    assert c0["Heading"] == pytest.approx(10.0, abs=1e-9)
    # at 12.3 s, after that instant's IMU sample: the true position, then CalibrateHere
    i, j = known[1], ctrl[1]
    assert j == i + 1 and fr[i][0] == fr[j][0] == 12.3
    imu_at = [q for q, n in enumerate(names) if n == "IMU_Accel" and fr[q][0] == 12.3]
    assert len(imu_at) == 1 and imu_at[0] < i
    p = decode(db, fr[i][1])
    k = int(round(12.3 * 50))
    assert truth.t_s[k] == pytest.approx(12.3)
    assert p["Latitude"] == pytest.approx(math.degrees(truth.lat_rad[k]), abs=0.6e-7)
    assert p["Longitude"] == pytest.approx(math.degrees(truth.lon_rad[k]), abs=0.6e-7)
    c1 = decode(db, fr[j][1])
    assert c1["Command"] == 5 and c1["HeadingValid"] == 0 and c1["CmdCounter"] == 1
    assert nc.check_e2e(fr[j][1], db)
    assert abs(truth.speed_mps[k]) > 10.0                          # moving when calibrating
    truths = scenario.scenario_truths(sc, truth.heading_rad[0], *scenario.sensor_specs(
        sc, "perfect", sc["vehicle"]), c0["Heading"])
    assert truths["dH_deg"] == pytest.approx(-0.177, abs=1e-9)
    assert truths["imu_heading_error_deg"] == pytest.approx(-0.027, abs=1e-9)


def test_calibration_at_gnss_frames(tmp_path):
    _, truth, db, fr = _frames_of(tmp_path, """
[calibration]
at_s = 12.3
source = "gnss"
gnss = "perfect"
""")
    ids = {n: db.get_message_by_name(n).frame_id
           for n in ("CMD_KnownPosition", "CMD_Control", "GNSS_Position", "GNSS_Status")}
    ctrl = [(t, decode(db, m)) for t, m in fr if m.arbitration_id == ids["CMD_Control"]]
    assert [c["Command"] for _, c in ctrl] == [2, 6] and ctrl[1][0] == 12.3
    assert [t for t, m in fr if m.arbitration_id == ids["CMD_KnownPosition"]] == [0.0]
    pos = [(t, decode(db, m)) for t, m in fr if m.arbitration_id == ids["GNSS_Position"]]
    assert len(pos) == 1 and 12.3 < pos[0][0] <= 12.3 + 0.2       # the next 5 Hz epoch
    k = int(round(pos[0][0] * 50))
    assert pos[0][1]["Latitude"] == pytest.approx(math.degrees(truth.lat_rad[k]), abs=0.6e-7)
    assert sum(m.arbitration_id == ids["GNSS_Status"] for _, m in fr) == 1


def test_read_calibration_log_and_report(tmp_path):
    """NAV_Calibration frames take the time of the NAV_Height before them; the report finds
    the calibration by CalCount and measures the errors before and after it."""
    db = nc.load_db()
    tx = nc.E2ESender(db)
    msgs = []
    for k in range(0, 130):                      # t = 0, 0.5, ... 64.5 s
        t = 0.5 * k
        msgs.append(tx.encode("NAV_Height", {"Height": 100.0, "VertAccuracy": 1.0,
                                             "TimeOfValidity": int(t * 1000) % 65536}, t))
        if k % 2 == 0:
            done = t >= 40.0
            msgs.append(tx.encode("NAV_Calibration", {
                "CalPage": 0, "HeadingCorrection": -0.175 if done else 0.0,
                "OdoScaleError": 0.0119 if done else 0.0,
                "CalValid": int(done), "CalStored": 0, "CalStatus": 2 if done else 0,
                "CalSource": 1 if done else 0, "CalCount": int(done)}, t))
            # the automatic mounting estimate's page: not the calibration's, left out
            msgs.append(tx.encode("NAV_Calibration", {
                "CalPage": 1, "MountRoll": 180.0, "MountPitch": 0.0, "MountYaw": 90.0}, t))
    log = tmp_path / "nav.log"
    nc.write_candump(log, msgs)
    cl = report.read_calibration_log(log)
    assert len(cl["t_s"]) == 65 and cl["t_s"][0] == 0.0 and cl["t_s"][-1] == 64.0
    p1 = report.read_calibration_log(log, page=1)
    assert len(p1["t_s"]) == 65 and set(p1["MountYaw"]) == {90.0}
    # tabs between the fields and a line that is not UTF-8, as navecu and read_nav_log read
    # them (the scan had found no frame in the first and raised on the second)
    tabbed = tmp_path / "tabs.log"
    tabbed.write_bytes(b"(0.0) can0 30A#\xff\xfe\n" + log.read_bytes().replace(b" ", b"\t"))
    for k, v in report.read_calibration_log(tabbed).items():
        np.testing.assert_array_equal(v, cl[k])
    nc.write_candump(tmp_path / "nav.asc", msgs)             # another format: python-can
    for k, v in report.read_calibration_log(tmp_path / "nav.asc").items():
        np.testing.assert_array_equal(v, cl[k])
    t = np.arange(0.0, 65.0, 0.5)
    truth = {"t_s": t, "dist_m": 10.0 * t}
    herr = np.where(t <= 40.0, 0.01 * 10.0 * t, 0.5 + 0.001 * 10.0 * (t - 40.0))
    series = {"t": t, "herr": herr, "heading": (t, np.full_like(t, -0.18))}
    truths = {"dH_deg": -0.177, "odometer_mu": 0.012}
    rep = report.calibration_report(truth, series, cl, {"at_s": 39.7, "source": "known_position"},
                                    truths)
    assert rep["performed"] and rep["time_s"] == 40.0
    assert rep["dH_deg"] == pytest.approx(-0.175) and rep["mu"] == pytest.approx(0.0119)
    assert rep["cal_status"] == "OnePoint" and rep["cal_source"] == "KnownPosition"
    assert rep["dH_true_deg"] == -0.177 and rep["mu_true"] == 0.012
    assert rep["dH_firmware_at_cal_deg"] == pytest.approx(-0.18)
    assert rep["error_before_m"] == pytest.approx(3.95)
    assert rep["distance_before_m"] == pytest.approx(397.0)
    assert rep["error_before_pct"] == pytest.approx(100 * 3.95 / 397.0)
    assert rep["distance_after_m"] == pytest.approx(245.0)
    assert rep["error_after_max_m"] == pytest.approx(0.745)
    assert rep["error_after_pct"] == pytest.approx(100 * 0.745 / 245.0)
    assert report.calibration_marks(rep) == [(40.0, "calibration")]
    # a firmware that never calibrates: said so, with the error before
    none = {k: v[:20] for k, v in cl.items()}
    rep = report.calibration_report(truth, series, none, {"at_s": 39.7, "source": "gnss"}, truths)
    assert not rep["performed"] and rep["dH_deg"] is None and rep["error_after_pct"] is None
    assert rep["cal_status"] == "None" and rep["error_before_m"] == pytest.approx(3.95)
    line = report.summary_table({"duration_s": 65.0, "distance_m": 650.0, "navigating": True,
                                 "horizontal_error_m": {"rms": 1.0, "p95": 1.0, "max": 1.0,
                                                        "final": 1.0},
                                 "final_error_pct_of_distance": 0.1,
                                 "heading_error_deg": {"rms": 0.1, "max": 0.1}, "outages": [],
                                 "calibration": rep})
    assert "NOT performed" in line and "0.99 % of distance before it" in line


def test_mount_curve_pages_and_errors(tmp_path):
    """tools/sim/mount_curve.py: NAV_Calibration pages 1 and 2 paired on the log's time;
    the errors wrapped (roll -179.9 of a roll-180 install is 0.1 deg off)."""
    from tools.sim import mount_curve
    db = nc.load_db()
    tx = nc.E2ESender(db)
    msgs = []
    for k in range(1, 4):
        t = float(k)
        msgs.append(tx.encode("NAV_Calibration", {
            "CalPage": 0, "HeadingCorrection": 0.0, "OdoScaleError": 0.0, "CalValid": 0,
            "CalStored": 0, "CalStatus": 0, "CalSource": 0, "CalCount": 0}, t))
        msgs.append(tx.encode("NAV_Calibration", {
            "CalPage": 1, "MountRoll": -179.9, "MountPitch": 0.5, "MountYaw": 89.0 + k}, t))
        msgs.append(tx.encode("NAV_Calibration", {
            "CalPage": 2, "MountSigmaRollPitch": 0.01, "MountSigmaYaw": 0.2,
            "MountExcitation": 10.0 * k, "MountState": 1 if k < 3 else 2}, t))
    log = tmp_path / "nav.log"
    nc.write_candump(log, msgs)
    pages = mount_curve.read_mount_pages(log)
    np.testing.assert_array_equal(pages["t_s"], [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(pages["state"], [1, 1, 2])
    err = mount_curve.estimate_errors(pages, {"roll_deg": 180.0, "pitch_deg": 0.0,
                                              "yaw_deg": 90.0})
    np.testing.assert_allclose(err["roll"], [0.1, 0.1, 0.1], atol=1e-9)
    np.testing.assert_allclose(err["yaw"], [0.0, 1.0, 2.0], atol=1e-9)


def test_nav_log_time_across_a_gap_longer_than_the_wrap(tmp_path):
    """NAV_Height's TimeOfValidity wraps every 65.536 s. A run whose navigation stops for
    longer (a re-acquisition that waits for the GNSS course through a stop) lost a wrap when
    wraps were counted from TimeOfValidity going back: the report then compared the outputs
    with the truth 65.5 s away (a review's 787 m for 2.8 m). With the log's timestamps as
    the IMU time (wraps_from_log, a --can-log run) every set's time is resolved."""
    db = nc.load_db()
    tx = nc.E2ESender(db)  # the firmware's E2E: read_nav_log rejects a frame failing it
    lines = []
    for t in (10.0, 10.02, 100.0, 170.0):  # a gap of 89.98 s, then one of 70 s
        ms = int(round(t * 1000)) % 65536
        for m in (tx.encode("NAV_Position", {"Latitude": 45.0, "Longitude": 10.0}),
                  tx.encode("NAV_Height", {"Height": 100.0, "VertAccuracy": 1.0,
                                           "TimeOfValidity": ms})):
            lines.append(f"({t:.6f}) can0 {m.arbitration_id:03X}#{bytes(m.data).hex().upper()}")
    log = tmp_path / "nav.log"
    log.write_text("\n".join(lines) + "\n")
    t = report.read_nav_log(log, db, wraps_from_log=True)["NAV_Position"]["t_s"]
    assert list(np.round(t, 3)) == [10.0, 10.02, 100.0, 170.0]
    # a power-on later than the log's start: the log's time less it is the IMU time
    lines = [ln.replace(f"({t0:.6f})", f"({t0 + 30.0:.6f})") for ln in lines
             for t0 in (float(ln[1:ln.index(")")]),)]
    log.write_text("\n".join(lines) + "\n")
    t = report.read_nav_log(log, db, wraps_from_log=True, log_t0_s=30.0)["NAV_Position"]["t_s"]
    assert list(np.round(t, 3)) == [10.0, 10.02, 100.0, 170.0]
