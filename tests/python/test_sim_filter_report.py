"""The simulator's side of the Kalman-filter issue (#7), fast and without the firmware:
scenario inheritance (`base = "..."`) and the new scenarios (dgnss, outage5,
outage5-automotive, gnss-faults), GNSS fault injection down to the CAN frames (a jump moves
GNSS_Position by the given metres, a frozen fix repeats, a latency spike shifts the frame
time but not TimeOfWeek), and the report's sigma_consistency, filter_calibration and
gnss_faults on synthetic logs. No accuracy assertion on the firmware."""
import math
import re

import numpy as np
import pytest

from tools import geodesy, navecu_can as nc
from tools.sim import report, run, scenario, sensors, trajectory

BASE_NO_OUTAGE = """name = "base"
description = "the base"
[start]
lat_deg = 45.0
lon_deg = 10.0
h_m = 100.0
heading_deg = 30.0
[vehicle]
pitch_per_accel_deg = 0.0
roll_per_lat_accel_deg = 0.0
roughness_deg = 0.0
[sim]
imu = "mid-grade"
gnss = "standalone"
[odometer]
mu = 0.02
noise_mps = 0.01
[[segment]]
kind = "stop"
duration_s = 2
[[segment]]
kind = "speed"
to_mps = 12
accel_mps2 = 2.0
[[segment]]
kind = "straight"
duration_s = 40
"""
BASE = BASE_NO_OUTAGE + """[[outage]]
start_s = 20
end_s = 25
label = "bridge"
"""


def write(tmp_path, name, text):
    p = tmp_path / f"{name}.toml"
    p.write_text(text)
    return p


# --- scenario inheritance -------------------------------------------------------------------
def test_base_merges_tables_and_inherits_arrays(tmp_path):
    write(tmp_path, "base", BASE)
    child = write(tmp_path, "child", 'base = "base"\n[sim]\ngnss = "differential"\n'
                                     "[odometer]\nmu = 0.012\n[imu_mounting]\nyaw_deg = 0.3\n")
    sc = scenario.load_scenario(child)
    assert sc["name"] == "child" and sc["description"] == ""         # never inherited
    assert sc["base"] == "base"
    assert sc["sim"] == {"imu": "mid-grade", "gnss": "differential"}  # merged key by key
    assert sc["odometer"] == {"mu": 0.012, "noise_mps": 0.01}
    assert sc["imu_mounting"]["yaw_deg"] == 0.3
    assert sc["start"]["heading_deg"] == 30.0
    base = scenario.load_scenario(tmp_path / "base.toml")
    assert sc["segment"] == base["segment"] and sc["outage"] == base["outage"]
    # own outages replace the base's; `outage = []` drops them; own segments replace
    sc = scenario.load_scenario(write(tmp_path, "c2", 'base = "base"\n[[outage]]\nstart_s = 30\n'
                                                        "end_s = 35\n"))
    assert [(o["start_s"], o["end_s"]) for o in sc["outage"]] == [(30.0, 35.0)]
    sc = scenario.load_scenario(write(tmp_path, "c3", 'base = "base"\noutage = []\n'))
    assert sc["outage"] == [] and len(sc["segment"]) == 3
    sc = scenario.load_scenario(write(tmp_path, "c4", 'base = "base"\n[[segment]]\n'
                                                        'kind = "stop"\nduration_s = 5\n'))
    assert len(sc["segment"]) == 1
    # a chain (c5 -> child -> base), a path base, and the errors
    sc = scenario.load_scenario(write(tmp_path, "c5",
                                        'base = "child.toml"\n[sim]\nimu = "tactical"\n'))
    assert sc["sim"] == {"imu": "tactical", "gnss": "differential"}
    assert sc["odometer"]["mu"] == 0.012
    write(tmp_path, "loop_a", 'base = "loop_b"\n')
    write(tmp_path, "loop_b", 'base = "loop_a"\n')
    with pytest.raises(ValueError, match="cycle"):
        scenario.load_scenario(tmp_path / "loop_a.toml")
    with pytest.raises(ValueError, match="no file"):
        scenario.load_scenario(write(tmp_path, "orphan", 'base = "nowhere"\n'))
    with pytest.raises(ValueError, match=r"\[odometer\]"):                # merged, then validated
        scenario.load_scenario(write(tmp_path, "bad", 'base = "base"\n[odometer]\nscale = 1\n'))


def test_issue7_scenarios():
    default = scenario.load_scenario(scenario.scenario_path("default"))
    sc = {n: scenario.load_scenario(scenario.scenario_path(n))
          for n in ("dgnss", "outage5", "outage5-automotive", "gnss-faults")}
    for name, s in sc.items():
        assert s["name"] == name
        assert s["segment"] == default["segment"] and s["start"] == default["start"]
        assert s["sim"]["gnss"] == "differential"
        assert s["imu_mounting"]["yaw_deg"] == 0.3 and s["odometer"]["mu"] == sensors.OdoSpec().mu
    assert sc["dgnss"]["outage"] == default["outage"] and sc["dgnss"]["sim"]["imu"] == "mid-grade"
    assert sc["outage5"]["sim"]["imu"] == "tactical"
    assert sc["outage5-automotive"]["sim"]["imu"] == "automotive"
    assert sc["outage5-automotive"]["outage"] == sc["outage5"]["outage"]
    # outage5: one outage of at least 5 minutes, the car moving throughout
    (o,) = sc["outage5"]["outage"]
    assert o["end_s"] - o["start_s"] >= 300.0
    truth = trajectory.generate(sc["outage5"], 10)
    inside = (truth.t_s >= o["start_s"]) & (truth.t_s <= o["end_s"])
    assert truth.speed_mps[inside].min() > 5.0
    ep = sensors.gnss_epochs(truth, sensors.GNSS_PRESETS["differential"], 5)
    gap = np.diff(ep["t_s"]).max()
    assert gap >= 300.0
    # gnss-faults: every fault finds its epochs, while driving, outside the outages
    f = sc["gnss-faults"]["gnss_faults"]
    assert len(f["jumps"]) >= 1 and len(f["freeze"]) >= 1 and len(f["latency_spike"]) >= 1
    assert all(j["metres"] == 100.0 for j in f["jumps"])
    truth = trajectory.generate(sc["gnss-faults"], 10)
    ep = sensors.gnss_epochs(truth, sensors.GNSS_PRESETS["differential"], 5)
    _, log = sensors.apply_gnss_faults(ep, f)
    for e in log:
        a, b = e["t_start_s"], e["t_end_s"]
        assert np.interp(a, truth.t_s, np.abs(truth.speed_mps)) > 5.0
        assert all(not (o0 - 10 <= a <= o1 + 10 or o0 - 10 <= b <= o1 + 10)
                   for o0, o1, _ in truth.outages)


# --- GNSS fault injection -------------------------------------------------------------------
FAULTS = """[gnss_faults]
jumps = [[10.0, 100.0, 90.0], [20.0, -50.0, 0.0, 0.4]]
freeze = [[30.0, 31.0]]
latency_spike = [[35.0, 0.5]]
"""


def test_gnss_faults_table_validation(tmp_path):
    write(tmp_path, "base", BASE)
    sc = scenario.load_scenario(write(tmp_path, "f", 'base = "base"\n' + FAULTS))
    f = sc["gnss_faults"]
    assert f["jumps"] == [{"t_s": 10.0, "metres": 100.0, "azimuth_deg": 90.0, "duration_s": 0.0},
                          {"t_s": 20.0, "metres": -50.0, "azimuth_deg": 0.0, "duration_s": 0.4}]
    assert f["freeze"] == [{"t0_s": 30.0, "t1_s": 31.0}]
    assert f["latency_spike"] == [{"t_s": 35.0, "extra_s": 0.5}]
    sc = scenario.load_scenario(write(tmp_path, "g", BASE + "[gnss_faults]\njumps = [[5, 10]]\n"))
    assert sc["gnss_faults"]["jumps"][0]["azimuth_deg"] == scenario.GNSS_JUMP_AZIMUTH_DEG_DEFAULT
    for bad in ("jumps = [[5]]", "jumps = [[5, 0]]", "freeze = [[9, 8]]",
                "latency_spike = [[5, -1]]", "latency_spike = [[5, 1, 2]]", "glitch = [[1, 2]]",
                "jumps = 5"):
        with pytest.raises(ValueError):
            scenario.load_scenario(write(tmp_path, "h", BASE + "[gnss_faults]\n" + bad + "\n"))


def _gnss_frames(tmp_path, faults_toml):
    """The GNSS frames of the BASE drive without its outage, with a perfect receiver (no
    error, no latency), without and with the faults, as
    [(t, {message: decoded signals})] per epoch (GnssEpoch groups the four frames)."""
    sc = scenario.load_scenario(write(tmp_path, "f", BASE_NO_OUTAGE + faults_toml))
    truth = trajectory.generate(sc, 50)
    ep = sensors.gnss_epochs(truth, sensors.GNSS_PRESETS["perfect"], 1)
    out = []
    db = nc.load_db()
    names = {db.get_message_by_name(n).frame_id: n
             for n in ("GNSS_Position", "GNSS_Velocity", "GNSS_Height", "GNSS_Status")}
    empty = (np.zeros(0), np.zeros((0, 4)))
    for epochs in (ep, sensors.apply_gnss_faults(ep, sc.get("gnss_faults", {}))[0]):
        fr = run.frames(truth, truth.dtheta_b_rad, truth.dv_b_mps, empty, epochs, db)
        fr.sort(key=lambda x: (x[0], x[1]))
        rows = []
        for t, _, m in fr:
            n = names.get(m.arbitration_id)
            if n is None:
                continue
            if n == "GNSS_Position":
                rows.append((t, {}))
            rows[-1][1][n] = db.decode_message(m.arbitration_id, bytes(m.data),
                                               decode_choices=False)
            assert rows[-1][0] == t
        out.append(rows)
    return truth, ep, out


def _dist_m(a, b):
    lat = math.radians(a["Latitude"])
    rm, rn = geodesy.radii_m(lat)
    dn = math.radians(b["Latitude"] - a["Latitude"]) * rm
    de = math.radians(b["Longitude"] - a["Longitude"]) * rn * math.cos(lat)
    return math.hypot(de, dn), math.degrees(math.atan2(de, dn))


def test_fault_injection_frames(tmp_path):
    truth, ep, (clean, bad) = _gnss_frames(tmp_path, FAULTS)
    assert len(clean) == len(bad) == len(ep["t_s"])
    clean_at = {round(t, 3): s for t, s in clean}
    tow = {round(t, 3): s["GNSS_Status"]["TimeOfWeek"] for t, s in clean}
    moved = {}
    for t, s in bad:
        c = clean_at.get(round(t, 3))
        if c is None or c["GNSS_Position"] != s["GNSS_Position"]:
            moved[round(t, 3)] = s
    # the jumps: the epoch at 10 s 100 m east; the epochs 20.0 .. 20.4 s 50 m south
    d, az = _dist_m(clean_at[10.0]["GNSS_Position"], moved[10.0]["GNSS_Position"])
    assert d == pytest.approx(100.0, abs=0.02) and az == pytest.approx(90.0, abs=0.05)
    for t in (20.0, 20.2, 20.4):
        d, az = _dist_m(clean_at[t]["GNSS_Position"], moved[t]["GNSS_Position"])
        assert d == pytest.approx(50.0, abs=0.02) and abs(az) == pytest.approx(180.0, abs=0.05)
        assert moved[t]["GNSS_Velocity"]["VelEast"] == clean_at[t]["GNSS_Velocity"]["VelEast"]
        assert moved[t]["GNSS_Height"]["Height"] == clean_at[t]["GNSS_Height"]["Height"]
    assert 20.6 not in moved and 9.8 not in moved and 10.2 not in moved
    # the freeze: the epochs 30.0 .. 30.8 s repeat the epoch at 29.8 s (the car moves at
    # 12 m/s), their TimeOfWeek advances
    bad_at = {round(t, 3): s for t, s in bad}
    src = bad_at[29.8]
    assert src == clean_at[29.8]
    frozen = [bad_at[round(30.0 + 0.2 * k, 3)] for k in range(5)]
    for k, s in enumerate(frozen):
        assert s["GNSS_Position"] == src["GNSS_Position"]
        for c in ("VelEast", "VelNorth", "VelUp", "SpeedAccuracy"):
            assert s["GNSS_Velocity"][c] == src["GNSS_Velocity"][c]
        assert s["GNSS_Velocity"]["GnssEpoch"] != src["GNSS_Velocity"]["GnssEpoch"]
        assert s["GNSS_Height"]["Height"] == src["GNSS_Height"]["Height"]
        assert s["GNSS_Status"]["HorizAccuracy"] == src["GNSS_Status"]["HorizAccuracy"]
        assert s["GNSS_Status"]["TimeOfWeek"] == tow[round(30.0 + 0.2 * k, 3)]
    assert clean_at[30.8]["GNSS_Position"] != src["GNSS_Position"]
    assert _dist_m(src["GNSS_Position"], clean_at[30.8]["GNSS_Position"])[0] > 10.0
    assert bad_at[31.0]["GNSS_Position"] == clean_at[31.0]["GNSS_Position"]   # over
    # the latency spike: the epoch of 35.0 s delivered at 35.5 s, after those of 35.2 and
    # 35.4 s, with its own TimeOfWeek; the epoch counter follows the bus order
    times = [round(t, 3) for t, _ in bad]
    assert 35.0 not in times and 35.5 in times
    i = times.index(35.5)
    assert times[i - 2:i + 1] == [35.2, 35.4, 35.5]
    assert bad[i][1]["GNSS_Status"]["TimeOfWeek"] == tow[35.0]
    assert bad[i][1]["GNSS_Position"] == clean_at[35.0]["GNSS_Position"]
    assert bad[i - 1][1]["GNSS_Status"]["TimeOfWeek"] == tow[35.4]
    epochs = [s["GNSS_Status"]["GnssEpoch"] for _, s in bad]
    assert all((b - a) % 15 == 1 for a, b in zip(epochs, epochs[1:]))


def test_fault_log_and_errors(tmp_path):
    write(tmp_path, "base", BASE)
    sc = scenario.load_scenario(write(tmp_path, "f", 'base = "base"\n' + FAULTS))
    truth = trajectory.generate(sc, 50)
    ep = sensors.gnss_epochs(truth, sensors.GNSS_PRESETS["perfect"], 1)   # outage 20-25 s
    with pytest.raises(ValueError, match="jump at 20"):
        sensors.apply_gnss_faults(ep, sc["gnss_faults"])
    f = dict(sc["gnss_faults"], jumps=sc["gnss_faults"]["jumps"][:1])
    out, log = sensors.apply_gnss_faults(ep, f)
    assert [e["kind"] for e in log] == ["freeze", "jump", "latency_spike"]
    fr, j, sp = log
    assert fr["epochs"] == 5 and fr["frozen_epoch_t_s"] == pytest.approx(29.8)
    assert (fr["t_start_s"], fr["t_end_s"]) == pytest.approx((30.0, 30.8))
    assert j["epochs"] == 1 and j["t_start_s"] == j["t_end_s"] == pytest.approx(10.0)
    assert (sp["t_start_s"], sp["t_end_s"]) == pytest.approx((35.0, 35.5))
    assert np.all(np.diff(out["t_s"]) > 0.0)                  # delivery order
    k = int(np.argmin(np.abs(out["t_s"] - 35.5)))
    assert out["t_meas_s"][k] == pytest.approx(35.0)
    i = int(np.argmin(np.abs(out["t_s"] - 10.0)))
    assert np.hypot(*out["err_enu_m"][i, :2]) == pytest.approx(100.0)
    assert np.all(np.isnan(out["err_enu_m"][(out["t_s"] > 29.9) & (out["t_s"] < 30.9)]))
    assert ep["t_s"][int(np.argmin(np.abs(ep["t_s"] - 35.0)))] == pytest.approx(35.0)  # untouched
    for bad in ({"freeze": [{"t0_s": 21.0, "t1_s": 22.0}]},
                {"latency_spike": [{"t_s": 60.0, "extra_s": 1.0}]}):
        with pytest.raises(ValueError):
            sensors.apply_gnss_faults(ep, bad)


# --- report: sigma consistency, filter calibration, fault neighbourhoods ---------------------
def nav_log(tmp_path, n, sigma, rejected=None, t0=30.0, dt=0.1, height=None, vacc=None,
            odo_rejected=None):
    """A synthetic firmware output: per set NAV_Position, NAV_Height (TimeOfValidity;
    Height height[k], VertAccuracy vacc[k], default 100 m and 1 m), NAV_Status page 0 with
    HorizAccuracy sigma[k], page 3 with rejected[k] and page 6 with odo_rejected[k]; read
    back with read_nav_log. The log's own timestamps are off by 1000 s: times come from
    TimeOfValidity."""
    db = nc.load_db()
    tx = nc.E2ESender(db)
    msgs = []
    for k in range(n):
        t = t0 + k * dt
        ts = 1000.0 + t
        msgs.append(tx.encode("NAV_Position", {"Latitude": 45.0, "Longitude": 10.0}, ts))
        msgs.append(tx.encode("NAV_Height", {
            "Height": 100.0 if height is None else float(height[k]),
            "VertAccuracy": 1.0 if vacc is None else float(vacc[k]),
                                             "TimeOfValidity": int(round(t * 1000)) % 65536}, ts))
        msgs.append(tx.encode("NAV_Status", {"StatusPage": 0, "Mode": 5, "HealthFlags": 0,
                                             "HorizAccuracy": float(sigma[k]),
                                             "ImuRateMeasured": 0.0}, ts))
        if rejected is not None:
            msgs.append(tx.encode("NAV_Status", {"StatusPage": 3, "CntBadValue": 0,
                                                 "CntGnssRejected": int(rejected[k]),
                                                 "CntRxLost": 0}, ts))
        if odo_rejected is not None:
            msgs.append(tx.encode("NAV_Status", {"StatusPage": 6, "CntImuSaturated": 0,
                                                 "CntOdoRejected": int(odo_rejected[k]),
                                                 "CntImuStuck": 0}, ts))
    p = tmp_path / "nav.log"
    nc.write_candump(p, msgs)
    return report.read_nav_log(p)


def test_sigma_consistency_from_the_status_frames(tmp_path):
    n = 200
    sigma = np.where(np.arange(n) < 50, 655.35, 1.0)           # unknown at first
    nav = nav_log(tmp_path, n, sigma)
    st = nav["NAV_Status"]
    t = nav["NAV_Position"]["t_s"]
    assert t[0] == pytest.approx(30.0) and t[-1] == pytest.approx(30.0 + 0.1 * (n - 1))
    np.testing.assert_allclose(st["t_s"], t)                    # the time of the set
    herr = np.where(np.arange(n) % 4 == 0, 3.0, 1.5)            # 1/4 above 2 sigma
    sc = report.sigma_consistency(t, herr, st)
    assert sc["status"] == "ok" and sc["epochs"] == n
    assert sc["epochs_sigma_unknown"] == 50 and sc["epochs_used"] == 150
    assert sc["frac_within_2sigma"] == pytest.approx(np.mean(herr[50:] <= 2.0))
    assert sc["frac_within_2sigma"] == pytest.approx(113 / 150)
    assert sc["median_error_over_sigma"] == pytest.approx(1.5)
    assert sc["sigma_median_m"] == pytest.approx(1.0)
    # positions between two status frames take the latest sigma, none from the future
    sc = report.sigma_consistency(np.array([29.0, 34.95, 35.05]), np.array([1.0, 1.0, 1.0]), st)
    assert sc["epochs_without_status"] == 1 and sc["epochs_sigma_unknown"] == 1
    assert sc["epochs_used"] == 1
    # a status older than SIGMA_MAX_AGE_S does not count
    sc = report.sigma_consistency(np.array([t[-1] + 5.0]), np.array([1.0]), st)
    assert sc["epochs_without_status"] == 1 and sc["status"] == "unknown"
    # all unknown (the firmware before the filter): reported as such, no numbers
    nav = nav_log(tmp_path, 20, np.full(20, 655.35))
    sc = report.sigma_consistency(nav["NAV_Position"]["t_s"], np.ones(20), nav["NAV_Status"])
    assert sc["status"] == "unknown" and sc["epochs_sigma_unknown"] == 20
    assert sc["frac_within_2sigma"] is None and sc["median_error_over_sigma"] is None
    sc = report.sigma_consistency(np.ones(3), np.ones(3), None)
    assert sc["status"] == "unknown" and sc["epochs_without_status"] == 3
    assert report.SIGMA_CONSISTENT_DRMS["frac_within_2sigma"] == pytest.approx(0.9817, abs=1e-4)


def test_compute_report_fields_and_summary(tmp_path):
    """compute() on a synthetic log: truth standing 2 m south of the NAV positions."""
    n = 100
    nav = nav_log(tmp_path, n, np.full(n, 1.0))
    rm, _ = geodesy.radii_m(math.radians(45.0))
    t = np.linspace(0.0, 50.0, 501)
    truth = {"t_s": t, "lat_rad": np.full(t.size, math.radians(45.0) - 2.0 / rm),
             "lon_rad": np.full(t.size, math.radians(10.0)), "heading_rad": np.zeros(t.size),
             "dist_m": 10.0 * t}
    rep, series = report.compute(truth, nav, [(32.0, 36.0, "tunnel")])
    assert rep["horizontal_error_m"]["rms"] == pytest.approx(2.0, abs=0.01)
    assert {"rms", "max"} <= set(rep["heading_error_deg"])
    assert rep["sigma_consistency"]["frac_within_2sigma"] == 1.0
    assert rep["sigma_consistency"]["median_error_over_sigma"] == pytest.approx(2.0, abs=0.01)
    assert rep["modes_seen"]["GnssIns"]["share"] == 1.0
    (o,) = rep["outages"]
    assert o["distance_m"] == pytest.approx(40.0)
    assert o["end_error_pct_of_distance"] == pytest.approx(100 * o["end_error_m"] / 40.0)
    rep["filter_calibration"] = report.filter_calibration({}, {"odometer_mu": 0.012,
                                                               "imu_mounting_deg": {"yaw": 0.3}},
                                                          None)
    text = report.summary_table(rep)
    assert "sigma consistency: 100.0 % within 2 sigma" in text
    assert f"({o['end_error_pct_of_distance']:.2f} % of the distance)" in text
    assert "filter calibration: none" in text and "mounting yaw +0.300 deg" in text


def test_height_and_odometer_refusals_reported(tmp_path):
    """The height against truth.npz's h_m: the truth 100 m, NAV_Height 100 + e with e 0.5 m
    at 3 of 4 sets and 3 m at every 4th, VertAccuracy 1 m (unknown, 25.5, for the first
    20 sets): |error| RMS, max, mean and the share within 2 sigma of the known sets; the
    last CntOdoRejected of page 6. Without h_m (an older truth.npz): unknown, said so."""
    n = 100
    e = np.where(np.arange(n) % 4 == 0, 3.0, 0.5)
    vacc = np.where(np.arange(n) < 20, 25.5, 1.0)
    nav = nav_log(tmp_path, n, np.full(n, 1.0), height=100.0 + e, vacc=vacc,
                  odo_rejected=np.arange(n) // 10)
    t = np.linspace(0.0, 50.0, 501)
    truth = {"t_s": t, "lat_rad": np.full(t.size, math.radians(45.0)),
             "lon_rad": np.full(t.size, math.radians(10.0)), "heading_rad": np.zeros(t.size),
             "dist_m": 10.0 * t, "h_m": np.full(t.size, 100.0)}
    rep, _ = report.compute(truth, nav, [])
    hr = rep["height"]
    assert hr["status"] == "ok" and hr["epochs"] == n and hr["epochs_used"] == 80
    assert hr["error_m"]["rms"] == pytest.approx(math.sqrt(np.mean(e ** 2)), abs=0.01)
    assert hr["error_m"]["max"] == pytest.approx(3.0, abs=0.01)
    assert hr["error_m"]["mean"] == pytest.approx(np.mean(e), abs=0.01)
    assert hr["frac_within_2sigma"] == pytest.approx(0.75)
    assert hr["median_error_over_sigma"] == pytest.approx(0.5, abs=0.01)
    assert rep["odo_rejected"] == 9
    text = report.summary_table(rep)
    assert "75.0 % within 2 VertAccuracy" in text
    assert "odometer updates refused (CntOdoRejected): 9" in text
    del truth["h_m"]
    rep, _ = report.compute(truth, nav_log(tmp_path, 10, np.full(10, 1.0)), [])
    assert rep["height"]["status"] == "unknown" and rep["odo_rejected"] is None
    text = report.summary_table(rep)
    assert "height error:     unknown" in text and "CntOdoRejected): never reported" in text


def test_filter_calibration_after_600_s_of_gnss_driving():
    t = np.arange(0.0, 1500.0, 0.5)
    speed = np.where(t < 100.0, 0.0, 10.0)                      # stands 100 s, then drives
    truth = {"t_s": t, "dist_m": np.concatenate([[0.0], np.cumsum(speed[1:] * 0.5)])}
    # GNSS all the time but 300-400 s (fresh for 1 s after the last epoch): 600 s of GNSS
    # driving at about 100 + 600 + 99 s
    gnss_t = np.arange(0.0, 1500.0, 0.2)
    gnss_t = gnss_t[(gnss_t < 300.0) | (gnss_t > 400.0)]
    t600 = report.gnss_driving_reached(truth, 600.0, 30.0, gnss_t=gnss_t)
    assert t600 == pytest.approx(799.0, abs=1.5)
    assert report.gnss_driving_reached(truth, 600.0, 30.0, outages=[(300.0, 400.0)]) == \
        pytest.approx(800.0, abs=1.0)
    assert report.gnss_driving_reached(truth, 600.0, 30.0, gnss_t=np.zeros(0)) is None
    tc = np.arange(1.0, 1500.0, 1.0)
    src = np.where(tc < 200.0, 0, 3)                            # the filter from 200 s on
    cal = {"t_s": tc, "CalSource": src.astype(float), "OdoScaleError": 0.01 + 1e-6 * tc,
           "HeadingCorrection": 0.2 + 1e-4 * tc}
    truths = {"odometer_mu": 0.012, "imu_mounting_deg": {"yaw": 0.3}}
    fc = report.filter_calibration(cal, truths, t600)
    assert fc["frames"] == int(np.sum(src == 3))
    assert fc["at_s"] == pytest.approx(math.floor(t600))
    assert fc["odo_scale"] == pytest.approx(0.01 + 1e-6 * fc["at_s"])
    assert fc["mount_yaw_deg"] == pytest.approx(0.2 + 1e-4 * fc["at_s"])
    assert fc["odo_scale_error"] == pytest.approx(fc["odo_scale"] - 0.012)
    assert fc["mu_true"] == 0.012 and fc["mount_yaw_true_deg"] == 0.3
    assert fc["last"]["at_s"] == 1499.0
    fc = report.filter_calibration({k: v[:150] for k, v in cal.items()}, truths, t600)
    assert fc["frames"] == 0 and fc["last"] is None and fc["at_s"] is None


def test_gnss_fault_report(tmp_path):
    n = 1200                                                    # 30 .. 149.9 s
    t = 30.0 + 0.1 * np.arange(n)
    rejected = np.where(t < 90.0, 2, 7)                         # 5 rejections at 90 s
    nav = nav_log(tmp_path, n, np.full(n, 1.0), rejected=rejected)
    herr = np.full(n, 1.0)
    herr[(t > 91.0) & (t < 93.0)] = 4.0                         # a bump after the fault
    herr[(t > 40.0) & (t < 41.0)] = 9.0                         # another fault's
    series = {"t": nav["NAV_Position"]["t_s"], "herr": herr, "de": herr.copy(),
              "dn": np.zeros(n)}
    log = [{"kind": "jump", "t_s": 90.0, "metres": 100.0, "azimuth_deg": 0.0,
            "duration_s": 0.8, "epochs": 5, "epoch_t_s": [90.0], "t_start_s": 90.0,
            "t_end_s": 90.8},
           {"kind": "freeze", "t0_s": 40.0, "t1_s": 41.0, "epochs": 5, "t_start_s": 40.0,
            "t_end_s": 40.8}]
    rep = report.gnss_fault_report(series, nav["NAV_Status"], log, outages=[(130.0, 140.0)])
    assert [f["kind"] for f in rep] == ["freeze", "jump"]       # in time order
    j = rep[1]
    assert j["window_s"] == [80.0, pytest.approx(100.8)]
    assert j["max_error_m"] == 4.0 and j["clean_max_error_m"] == 1.0
    assert j["max_step_m"] == pytest.approx(3.0) and j["clean_max_step_m"] == 0.0
    assert (j["cnt_gnss_rejected_before"], j["cnt_gnss_rejected_after"]) == (2, 7)
    assert j["gnss_rejected"] == 5 and "epoch_t_s" not in j
    assert rep[0]["gnss_rejected"] == 0
    assert report.fault_marks(rep) == [(40.0, "GNSS freeze"), (90.0, "GNSS jump")]
    nominal = report.fault_windows_from_table({"jumps": [{"t_s": 5.0, "metres": 100.0,
                                                          "azimuth_deg": 0.0, "duration_s": 1.0}],
                                               "latency_spike": [{"t_s": 9.0, "extra_s": 0.5}]})
    assert [(f["kind"], f["t_start_s"], f["t_end_s"]) for f in nominal] == \
        [("jump", 5.0, 6.0), ("latency_spike", 9.0, 9.5)]


def test_report_rejects_bad_inputs_with_one_line(tmp_path, capsys):
    """tools.sim.report on corrupt inputs: a malformed line or a NAV_* frame of another
    length in nav.log is skipped and counted on stderr (a traceback before), and so is a
    NAV_* frame failing its E2E check (a NAV_Height with its time of validity changed and
    its CRC not: taken, it would have moved the set's time by 20 s); a log without
    any NAV_* frame (empty, or the input log given as --nav) is no report, where it said
    'navecu never started navigating'; a truth.npz that is missing, of another kind, with
    a NaN or with time going back is refused naming the file."""
    n = 100
    report_dir = tmp_path / "rep"
    nav_log(tmp_path, n, np.full(n, 1.0))
    nav = tmp_path / "nav.log"
    lines = nav.read_text().splitlines()
    lines[50:50] = ["(1005.0) can0 GARBAGE", "(1005.0) can0 300#0102", "(1005.0) can0 301#ZZ"]
    k = next(i for i in range(60, len(lines)) if " 301#" in lines[i])
    head, rest = lines[k].split("#")
    data, tail = rest.split(" ", 1)
    tov = (int.from_bytes(bytes.fromhex(data), "little") >> 32 & 0xFFFF) + 20000
    lines[k] = (head + "#" + data[:8] + (tov & 0xFFFF).to_bytes(2, "little").hex().upper()
                + data[12:] + " " + tail)
    nav.write_text("\n".join(lines) + "\n")
    rm, _ = geodesy.radii_m(math.radians(45.0))
    t = np.linspace(0.0, 50.0, 501)
    truth = {"t_s": t, "lat_rad": np.full(t.size, math.radians(45.0) - 2.0 / rm),
             "lon_rad": np.full(t.size, math.radians(10.0)), "heading_rad": np.zeros(t.size),
             "dist_m": 10.0 * t}
    good = tmp_path / "truth.npz"
    np.savez(good, **truth)
    args = ["--truth", str(good), "--out", str(report_dir)]
    report.main(args + ["--nav", str(nav)])
    cap = capsys.readouterr()
    assert "horizontal error: rms 2.00 m" in cap.out
    assert (f"read_nav_log: 2 malformed lines of {nav} skipped (first: line 51, "
            "'(1005.0) can0 GARBAGE'), 2 frames rejected (first: 0x300 at 1005.000000 s, "
            "NAV_Position with 2 bytes)") in cap.err
    for bad_nav, what in ((tmp_path / "empty.log", "no NAV_* frame in it"),
                          (tmp_path / "none.log", "No such file or directory"),
                          (good, "not a CAN log it can read")):
        if bad_nav.name == "empty.log":
            bad_nav.write_text("")
        with pytest.raises(SystemExit, match=re.escape(f"report: {bad_nav}: ") + ".*"
                           + re.escape(what)):
            report.main(args[2:] + ["--truth", str(good), "--nav", str(bad_nav)])
    nan_truth = dict(truth, lat_rad=truth["lat_rad"].copy())
    nan_truth["lat_rad"][7] = np.nan
    back_truth = dict(truth, t_s=truth["t_s"].copy())
    back_truth["t_s"][9] = 0.0
    for name, data, what in (("nan", nan_truth, "lat_rad is not finite at 1 samples "
                              "(first at index 7)"),
                             ("back", back_truth, "t_s does not increase"),
                             ("short", {k: v for k, v in truth.items() if k != "dist_m"},
                              "no dist_m")):
        p = tmp_path / f"{name}.npz"
        np.savez(p, **data)
        with pytest.raises(SystemExit, match=re.escape(f"report: {p}: {what}")):
            report.main(["--truth", str(p), "--nav", str(nav), "--out", str(report_dir)])
    with pytest.raises(SystemExit, match="not a truth.npz"):
        report.main(["--truth", str(nav), "--nav", str(nav), "--out", str(report_dir)])


@pytest.mark.parametrize("edit, what", [
    # taken without a word: a NaN heading, an infinite or negative duration, a misspelt key
    (("heading_deg = 30.0", "heading_deg = nan"), "start.heading_deg = nan is not a finite"),
    (("duration_s = 2", "duration_s = inf"), "segment[0].duration_s = inf is not a finite"),
    (("duration_s = 2", "duration_s = -2"), "segment 0 (stop): duration_s must be a "
                                            "non-negative number, not -2"),
    (("lat_deg = 45.0", "lat_deg = 45.0\nlatt_deg = 1.0"), "unknown [start] keys ['latt_deg']"),
    # tracebacks: a string for a number, a file cut short, bytes that are not UTF-8
    (("lat_deg = 45.0", 'lat_deg = "north"'), "[start] lat_deg must be a number, not 'north'"),
    (("[[segment]]\nkind = \"stop\"", "[[segment]\nkind = \"stop\""), "not TOML"),
    (("description = \"the base\"", "description = \"the base \xff\""), "not TOML"),
])
def test_a_malformed_scenario_is_refused_naming_the_key(tmp_path, edit, what):
    text = BASE.replace(*edit)
    assert text != BASE
    p = tmp_path / "bad.toml"
    p.write_bytes(text.encode("latin-1") if "\xff" in text else text.encode())
    with pytest.raises(ValueError, match=re.escape(what)):
        scenario.load_scenario(p)
    # the command-line tools (tools.sim.run, report, trajectory): one line, no traceback
    with pytest.raises(SystemExit, match=re.escape(f"scenario: {p}: ")):
        scenario.load(str(p))
    scenario.load_scenario(write(tmp_path, "good", BASE))
