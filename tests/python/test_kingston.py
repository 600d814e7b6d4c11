"""The Kingston 2008 converter (tools/kingston/convert.py) on the real recorded data.

The log of the first 1300 s (which holds the 5 km calibration point at 1195 s and five
outages of the default schedule) is built once, written as a candump file, read back and
decoded through the DBC: frame counts against the CSV rows, IMU increments, speeds and GNSS
values against the CSVs, E2E protection, the initialization and calibration commands and
the outages. The IMU timing checks run on the whole file; gaps and duplicates on a
synthetic one. The data are the repository's data/kingston-2008 (convert.DATA_DIR): a
missing folder is a failure, not a skip.
"""
import math

import can
import numpy as np
import pytest

from tools import navecu_can as nc
from tools.kingston import convert

HEAD_S = 1300.0

@pytest.fixture(scope="module")
def drive():
    return convert.load()


@pytest.fixture(scope="module")
def head(drive, tmp_path_factory):
    """(drive cut to HEAD_S, outages, meta, decoded frames as (t, name, signals, msg))."""
    d = drive.head(HEAD_S)
    t_end = float(d.imu["time_s"][-1] - d.t0_gps)
    outages = convert.parse_outages("default", t_end)
    frames, meta = convert.build(d, outages=outages, calibrate_at_km=5.0)
    log = tmp_path_factory.mktemp("kingston") / "can_in.log"
    assert nc.write_candump(log, (m for _, _, m in frames)) == len(frames)
    db = nc.DEFAULT_DB
    decoded = []
    rx = nc.E2EReceiver(db)
    with can.LogReader(str(log)) as reader:
        for msg in reader:
            assert rx.check(msg), f"E2E check failed: {msg}"
            m = db.get_message_by_frame_id(msg.arbitration_id)
            decoded.append((round(msg.timestamp, 6), m.name,
                            db.decode_message(msg.arbitration_id, bytes(msg.data),
                                              decode_choices=False), msg))
    return d, outages, meta, decoded


def _by_name(decoded, name):
    return [(t, s) for t, n, s, _ in decoded if n == name]


def test_imu_timing_of_the_whole_file(drive):
    imu = convert.imu_increments(drive.imu, drive.t0_gps)
    tm = imu.timing
    assert tm["rows"] == len(drive.imu) == 35305
    assert tm["samples_sent"] == tm["rows"] - 1  # the first row only opens an interval
    assert tm["duplicates_identical"] == tm["duplicates_conflicting"] == 0
    assert tm["gaps"] == [] and tm["missing_samples"] == 0
    assert abs(tm["interval_min_s"] - 0.1) < 1e-9 and abs(tm["interval_max_s"] - 0.1) < 1e-9
    assert imu.t_s[0] == pytest.approx(0.1) and imu.t_s[-1] == pytest.approx(3530.4)


def test_frame_counts_match_the_csv_rows(head):
    d, outages, meta, decoded = head
    t0 = d.t0_gps
    n_imu = len(d.imu) - 1
    assert len(_by_name(decoded, "IMU_Rate")) == len(_by_name(decoded, "IMU_Accel")) == n_imu
    # the 1 Hz files: rows stamped before the first IMU sample or after the last one cannot
    # be sent (documented; 2 before, and after only because this drive is cut at HEAD_S)
    t_last = meta["last_imu_sample_s"]
    odo_t = d.odo["time_s"] - t0
    odo_before, odo_after = int(np.sum(odo_t < 0)), int(np.sum(odo_t > t_last))
    assert odo_before == meta["odometer"]["before_start"] == 2
    assert odo_after == meta["odometer"]["after_end"]
    assert len(_by_name(decoded, "WheelSpeeds")) == len(d.odo) - odo_before - odo_after
    g_t = d.gnss["time_s"] - t0
    g_before, g_after = int(np.sum(g_t < 0)), int(np.sum(g_t > t_last))
    assert g_before == meta["gnss"]["before_start"] == 2
    assert g_after == meta["gnss"]["after_end"]
    in_out = sum(int(np.sum((g_t >= a) & (g_t < b))) for a, b in outages)
    n_epochs = len(d.gnss) - g_before - g_after - in_out
    assert meta["gnss"]["epochs_sent"] == n_epochs
    for name in ("GNSS_Position", "GNSS_Velocity", "GNSS_Height", "GNSS_Status"):
        assert len(_by_name(decoded, name)) == n_epochs, name
    assert len(decoded) == meta["frames"]


def test_imu_increments_round_trip_within_the_carry(head):
    d, _, _, decoded = head
    exact = convert.imu_increments(d.imu, d.t0_gps)
    rate = _by_name(decoded, "IMU_Rate")
    accel = _by_name(decoded, "IMU_Accel")
    assert np.allclose([t for t, _ in rate], exact.t_s, atol=1e-6)
    ang = np.array([[s[k] for k in nc.ANGLE_SIGNALS] for _, s in rate])
    vel = np.array([[s[k] for k in nc.VEL_SIGNALS] for _, s in accel])
    # the sum of the sent increments stays within half an LSB of the exact sum (the carry)
    da = np.abs(np.cumsum(ang, axis=0) - np.cumsum(exact.dtheta_rad, axis=0)) / nc.ANGLE_LSB_RAD
    dv = np.abs(np.cumsum(vel, axis=0) - np.cumsum(exact.dv_mps, axis=0)) / nc.VEL_LSB_MPS
    print(f"IMU round trip: max accumulated difference {da.max():.3f} LSB (angle), "
          f"{dv.max():.3f} LSB (velocity) over {len(ang)} samples")
    assert da.max() <= 0.5 + 1e-6 and dv.max() <= 0.5 + 1e-6
    # rule "rect": the increment is the sample times the interval
    assert np.allclose(exact.dtheta_rad[0], 0.1 * np.array(
        [d.imu[c][1] for c in ("wx_radps", "wy_radps", "wz_radps")]))
    # counters run 0..14 without a skip, the same in both frames of a sample
    counters = [s["ImuCounter"] for _, s in rate]
    assert counters == [k % 15 for k in range(len(counters))]
    assert counters == [s["ImuCounter"] for _, s in accel]


def test_wheel_speeds_round_trip(head):
    d, _, meta, decoded = head
    wheels = _by_name(decoded, "WheelSpeeds")
    t_rel = d.odo["time_s"] - d.t0_gps
    rows = d.odo[(t_rel >= 0) & (t_rel <= meta["last_imu_sample_s"])]
    assert np.allclose([t for t, _ in wheels], rows["time_s"] - d.t0_gps, atol=1e-6)
    got = np.array([[s[k] for k in ("WheelSpeedFL", "WheelSpeedFR", "WheelSpeedRL",
                                    "WheelSpeedRR")] for _, s in wheels])
    assert np.all(got == got[:, :1])
    assert np.max(np.abs(got[:, 0] - rows["speed_mps"])) <= 0.01 + 1e-9


def test_gnss_round_trip(head):
    d, outages, meta, decoded = head
    t0 = d.t0_gps
    pos, vel = _by_name(decoded, "GNSS_Position"), _by_name(decoded, "GNSS_Velocity")
    hgt, sta = _by_name(decoded, "GNSS_Height"), _by_name(decoded, "GNSS_Status")
    t_rel = d.gnss["time_s"] - t0
    sent = np.array([0 <= t <= meta["last_imu_sample_s"] and convert.in_outage(t, outages) < 0
                     for t in t_rel])
    rows = d.gnss[sent]
    assert np.allclose([t for t, _ in pos], rows["time_s"] - t0, atol=1e-6)
    lat = np.array([s["Latitude"] for _, s in pos])
    lon = np.array([s["Longitude"] for _, s in pos])
    assert np.max(np.abs(lat - rows["lat_deg"])) <= 1e-7
    assert np.max(np.abs(lon - rows["lon_deg"])) <= 1e-7
    ve = np.array([[s["VelEast"], s["VelNorth"], s["VelUp"]] for _, s in vel])
    assert np.max(np.abs(ve - np.column_stack([rows["ve_mps"], rows["vn_mps"], rows["vu_mps"]]))) \
        <= 0.005 + 1e-9
    # the receiver's height, kept (about 34.1 m above the reference's: documented)
    heights = np.array([s["Height"] for _, s in hgt])
    # ellipsoidal: the receiver's height above mean sea level minus the measured undulation
    assert np.max(np.abs(heights - (rows["height_m"] - convert.GNSS_HEIGHT_ABOVE_REF_M))) <= 0.005 + 1e-9
    raw_t, raw_n = np.unique(np.rint(d.raw_time_s), return_counts=True)
    nsat = dict(zip(raw_t.astype(int).tolist(), raw_n.tolist()))
    for (t, s), row, (_, v), (_, h) in zip(sta, rows, vel, hgt):
        assert s["FixType"] == 3
        assert s["NumSatellites"] == nsat.get(int(round(row["time_s"])), 0)
        assert s["TimeOfWeek"] == pytest.approx(row["time_s"], abs=5e-4)
        hacc = 1.5152 * math.sqrt(0.5 * (row["lat_std_m"] ** 2 + row["lon_std_m"] ** 2))
        assert s["HorizAccuracy"] == pytest.approx(min(hacc, 102.3), abs=0.05 + 1e-9)
        assert s["GnssEpoch"] == v["GnssEpoch"] == h["GnssEpoch"]
    epochs = [s["GnssEpoch"] for _, s in sta]
    assert epochs == [k % 15 for k in range(len(epochs))]
    # the frames of one epoch: Position, Velocity, Height, Status, in that order
    names = [n for _, n, _, _ in decoded if n.startswith("GNSS_")]
    assert names[:4] == ["GNSS_Position", "GNSS_Velocity", "GNSS_Height", "GNSS_Status"]


def test_initialization_from_the_reference_start(head):
    d, _, _, decoded = head
    r0 = d.ref[0]
    (t1, n1, kp, _), (t2, n2, ctl, _), (t3, n3, att, _) = decoded[:3]
    assert (t1, t2, t3) == (0.0, 0.0, 0.0)
    assert (n1, n2, n3) == ("CMD_KnownPosition", "CMD_Control", "CMD_InitialAttitude")
    assert abs(kp["Latitude"] - r0["lat_deg"]) <= 1e-7
    assert abs(kp["Longitude"] - r0["lon_deg"]) <= 1e-7
    assert ctl["Command"] == 2 and ctl["HeadingValid"] == 1
    assert ctl["Heading"] == pytest.approx(r0["azimuth_deg"], abs=0.005 + 1e-9)
    assert ctl["Height"] == pytest.approx(r0["height_m"], abs=0.05 + 1e-9)
    assert att["InitRoll"] == pytest.approx(math.radians(r0["roll_deg"]), abs=2.4e-7)
    assert att["InitPitch"] == pytest.approx(math.radians(r0["pitch_deg"]), abs=2.4e-7)
    assert decoded[3][1] == "IMU_Rate" and decoded[3][0] == pytest.approx(0.1)


def test_calibration_command_at_5_km(head):
    d, _, meta, decoded = head
    ref = convert.reference_track(d)
    cal = meta["calibration"]
    k = int(np.argmax(ref["dist_m"] >= 5000.0))
    assert ref["dist_m"][k - 1] < 5000.0 <= ref["dist_m"][k]
    assert cal["ref_epoch_gps_s"] == d.ref["time_s"][k]
    # the first IMU sample at or after that epoch
    assert ref["t_s"][k] <= cal["time_s"] < ref["t_s"][k] + 0.1
    i = next(j for j, (_, n, s, _) in enumerate(decoded)
             if n == "CMD_Control" and s["Command"] == 5)
    # right after that sample's two frames, CMD_KnownPosition then CalibrateHere
    assert [n for _, n, _, _ in decoded[i - 3:i + 1]] == \
        ["IMU_Rate", "IMU_Accel", "CMD_KnownPosition", "CMD_Control"]
    assert {t for t, _, _, _ in decoded[i - 3:i + 1]} == {cal["time_s"]}
    kp = decoded[i - 1][2]
    assert abs(kp["Latitude"] - np.interp(cal["time_s"], ref["t_s"], ref["lat_deg"])) <= 1e-7
    assert abs(kp["Longitude"] - np.interp(cal["time_s"], ref["t_s"], ref["lon_deg"])) <= 1e-7
    assert decoded[i][2]["CmdCounter"] == 1  # after SetInitialPosition's 0
    assert 5000.0 <= cal["distance_m"] < 5000.0 + 15.0
    assert sum(1 for _, n, _, _ in decoded if n == "CMD_Control") == 2


def test_outages_drop_exactly_the_requested_seconds(head):
    d, outages, meta, decoded = head
    assert outages == [(240.0, 300.0), (480.0, 540.0), (720.0, 780.0), (960.0, 1020.0),
                       (1200.0, 1260.0)]
    t_sent = {round(t, 6) for t, _ in _by_name(decoded, "GNSS_Status")}
    t_all = [round(t, 6) for t in d.gnss["time_s"] - d.t0_gps
             if 0 <= t <= meta["last_imu_sample_s"]]
    for t in t_all:
        assert (t in t_sent) == (convert.in_outage(t, outages) < 0), t
    for o in meta["gnss"]["outages"]:
        assert o["epochs_dropped"] == 60  # one epoch per second, 60 s each
    # no GNSS frame of any kind inside an outage
    for t, n, _, _ in decoded:
        if n.startswith("GNSS_"):
            assert convert.in_outage(t, outages) < 0


def test_outage_specs():
    assert convert.parse_outages("none", 3530.4) == []
    assert convert.parse_outages("100-160, 20-30", 3530.4) == [(20.0, 30.0), (100.0, 160.0)]
    sched = convert.parse_outages("default", 3530.4)
    assert len(sched) == 14 and sched[0] == (240.0, 300.0) and sched[-1] == (3360.0, 3420.0)
    # the same schedule moved 120 s later: each outage 120 s on, the last one that still
    # ends within the data (3360 + 120 + 60 = 3540 s does not)
    moved = convert.parse_outages("every:240:60:120", 3530.4)
    assert moved[0] == (360.0, 420.0) and moved[-1] == (3240.0, 3300.0) and len(moved) == 13
    assert convert.parse_outages("every:240:60:0", 3530.4) == sched
    for bad in ("30-20", "a-b", "every:60:60", "every:240:60:240", "every:240:60:-1",
                "every:240:60:1:2", "every:240:60:", "every:240:60:nan", "every:240:60:inf",
                "every:inf:60", "every:nan:60", "every:0.5:0.1"):
        with pytest.raises(ValueError):
            convert.parse_outages(bad, 3530.4)


def test_no_gnss_sends_no_gnss_frame(drive):
    frames, meta = convert.build(drive.head(30.0), gnss=False, calibrate_at_km=None)
    names = {nc.DEFAULT_DB.get_message_by_frame_id(m.arbitration_id).name for _, _, m in frames}
    assert not any(n.startswith("GNSS_") for n in names)
    assert meta["gnss"]["epochs_sent"] == 0 and meta["calibration"] is None
    assert "WheelSpeeds" in names and "IMU_Rate" in names


def test_gaps_and_duplicates_are_counted_not_hidden():
    t = 1000.0 + 0.1 * np.array([0, 1, 2, 2, 3, 7, 8], dtype=float)  # a duplicate, a gap
    n = len(t)
    imu = np.zeros(n, dtype=[(c, float) for c in ("time_s", "fx_mps2", "fy_mps2", "fz_mps2",
                                                  "wx_radps", "wy_radps", "wz_radps")])
    imu["time_s"] = t
    imu["fz_mps2"] = 9.8
    imu["wz_radps"] = np.arange(n) * 0.01
    imu["wz_radps"][3] = imu["wz_radps"][2]  # an identical duplicate
    s = convert.imu_increments(imu, t[0])
    assert s.timing["duplicates_identical"] == 1 and s.timing["duplicates_conflicting"] == 0
    assert s.timing["missing_samples"] == 3 and len(s.timing["gaps"]) == 1
    assert list(s.lost_before) == [0, 0, 0, 3, 0]
    assert np.allclose(s.t_s, [0.1, 0.2, 0.3, 0.7, 0.8])
    imu["wz_radps"][3] += 1.0  # now it conflicts
    assert convert.imu_increments(imu, t[0]).timing["duplicates_conflicting"] == 1
    imu["time_s"][5] = imu["time_s"][4] - 0.05  # time going backwards
    with pytest.raises(ValueError):
        convert.imu_increments(imu, t[0])


def test_report_outage_table():
    """tools/kingston/run.py's outages table and median error at the outages' ends (the
    report.json fields of `make kingston`), on synthetic errors."""
    from tools.kingston import run as krun

    t = np.arange(0.0, 100.0, 0.1)
    herr = 0.5 * t
    ref_t = np.arange(0.0, 101.0, 1.0)
    ref_dist = 10.0 * ref_t
    rows = krun.outage_table(t, herr, ref_t, ref_dist,
                             [{"start_s": 10.0, "end_s": 20.0}, {"start_s": 40.0, "end_s": 60.0},
                              {"start_s": 200.0, "end_s": 260.0}])
    assert [set(r) for r in rows] == [{"start_s", "end_s", "distance_m", "start_error_m",
                                       "max_error_m", "end_error_m",
                                       "end_error_pct_of_distance", "max_error_after_m",
                                       "after_within_end_plus_1m"}] * 3
    a, b, c = rows
    assert a["distance_m"] == pytest.approx(100.0) and b["distance_m"] == pytest.approx(200.0)
    assert a["end_error_m"] == pytest.approx(10.0) and a["max_error_m"] == pytest.approx(10.0)
    assert a["start_error_m"] == pytest.approx(5.0)
    assert a["end_error_pct_of_distance"] == pytest.approx(10.0)
    assert b["end_error_m"] == pytest.approx(30.0)
    assert c["end_error_m"] is None and c["end_error_pct_of_distance"] is None  # after the end
    # after an outage: the largest error within AFTER_OUTAGE_S (30 s) of its end
    assert a["max_error_after_m"] == pytest.approx(25.0, abs=0.06)  # grows: above end + 1
    assert a["after_within_end_plus_1m"] is False
    flat = krun.outage_table(t, np.where(t > 20.0, 10.5, herr), ref_t, ref_dist,
                             [{"start_s": 10.0, "end_s": 20.0}])
    assert flat[0]["max_error_after_m"] == pytest.approx(10.5)
    assert flat[0]["after_within_end_plus_1m"] is True
    assert c["max_error_after_m"] is None and c["after_within_end_plus_1m"] is None
    assert krun.median_outage_end_error(rows) == pytest.approx(20.0)
    assert krun.median_outage_end_error([]) is None


def test_compare_by_minute_shares_add_up_to_the_difference():
    """tools.kingston.compare: the minutes' shares of the two runs' mean-square difference
    add up to it, and a difference put in one minute is that minute's alone."""
    from tools.kingston import compare
    t = np.arange(0.0, 300.0, 0.1)
    ea = np.full(t.size, 1.0)
    eb = np.full(t.size, 1.0)
    ea[(t >= 120.0) & (t < 180.0)] = 3.0             # A 2 m worse in the third minute
    eb[(t >= 240.0) & (t < 250.0)] = 2.0             # B worse for 10 s of the fifth
    rows = compare.by_minute(t, ea, t, eb)
    total = float(np.mean(ea ** 2) - np.mean(eb ** 2))
    assert sum(r[0] for r in rows) == pytest.approx(total, rel=1e-12)
    share = {m0: sh for sh, m0, _, _ in rows}
    assert share[120] == pytest.approx(600 * 8.0 / t.size, rel=1e-12)
    assert share[240] == pytest.approx(-100 * 3.0 / t.size, rel=1e-12)
    assert share[0] == share[60] == 0.0
    rms = {m0: (ra, rb) for _, m0, ra, rb in rows}
    assert rms[120] == pytest.approx((3.0, 1.0))


def _small_data(tmp_path, seconds=60.0):
    """The first `seconds` of each of the drive's CSV files, rows as they are."""
    d = tmp_path / "data"
    d.mkdir()
    t_end = convert.load().t0_gps + seconds
    for name in convert.COLUMNS:
        lines = (convert.DATA_DIR / name).read_text().splitlines(keepends=True)
        (d / name).write_text(lines[0] + "".join(ln for ln in lines[1:]
                                                 if float(ln.split(",")[0]) < t_end))
    return d


def _edit(path, line_no, fn):
    lines = path.read_text().splitlines(keepends=True)
    lines[line_no - 1] = fn(lines[line_no - 1])
    path.write_text("".join(lines))


def _cell(col, value):
    def fn(line):
        cells = line.rstrip("\n").split(",")
        cells[col] = value
        return ",".join(cells) + "\n"
    return fn


@pytest.mark.parametrize("name, edit, what", [
    # numpy's genfromtxt read these as NaN: the converter then died in the quantiser or
    # the encoder ("IMU increment is not finite", "signal Latitude: value nan ...")
    ("imu.csv", (101, _cell(1, "nan")), "imu.csv: line 101: fx_mps2 = nan is not finite"),
    ("imu.csv", (101, _cell(1, "abc")), "imu.csv: line 101: fx_mps2 = 'abc' is not a number"),
    ("imu.csv", (101, _cell(1, "")), "imu.csv: line 101: fx_mps2 = '' is not a number"),
    ("gnss.csv", (30, _cell(2, "inf")), "gnss.csv: line 30: lon_deg = inf is not finite"),
    ("odometer.csv", (30, _cell(1, "nan")), "odometer.csv: line 30: speed_mps = nan is not"),
    # NaN in gnss_raw's time was a satellite silently not counted
    ("gnss_raw.csv", (20, _cell(0, "xx")), "gnss_raw.csv: line 20: time_s = 'xx' is not a"),
    # these were numpy tracebacks
    ("imu.csv", (101, lambda ln: ln[:30] + "\n"), "imu.csv: line 101: 3 fields, the header "
                                                  "has 7 (a line cut short?)"),
    ("imu.csv", (1, lambda ln: ln.replace("wz_radps", "wz")), "imu.csv: no column wz_radps"),
    ("reference.csv", None, "reference.csv: No such file or directory"),
    ("gnss.csv", "header", "gnss.csv: no data row"),
    ("gnss.csv", b"\xff", "gnss.csv: not UTF-8 text (line 5: byte 0xFF)"),
])
def test_corrupt_data_file_refused_with_its_line(tmp_path, capsys, name, edit, what):
    d = _small_data(tmp_path)
    path = d / name
    if edit is None:
        path.unlink()
    elif edit == "header":
        path.write_text(path.read_text().splitlines(keepends=True)[0])
    elif isinstance(edit, bytes):
        lines = path.read_bytes().splitlines(keepends=True)
        path.write_bytes(b"".join(lines[:4]) + edit + b"\n" + b"".join(lines[4:]))
    else:
        _edit(path, *edit)
    out = tmp_path / "can_in.log"
    assert convert.main(["--data", str(d), "--out", str(out), "--calibrate-at-km", "none"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("kingston.convert: ") and what in err, err
    assert not out.exists()


def test_data_irregularities_are_one_line_not_a_traceback(tmp_path, capsys):
    d = _small_data(tmp_path)
    out = tmp_path / "can_in.log"
    # the default calibration point is beyond a short drive
    assert convert.main(["--data", str(d), "--out", str(out)]) == 1
    assert "the reference never reaches 5.0 km" in capsys.readouterr().err
    lines = (d / "imu.csv").read_text().splitlines(keepends=True)
    lines[200], lines[201] = lines[201], lines[200]
    (d / "imu.csv").write_text("".join(lines))
    assert convert.main(["--data", str(d), "--out", str(out), "--calibrate-at-km", "none"]) == 1
    assert "time goes backwards" in capsys.readouterr().err
    assert not out.exists()
