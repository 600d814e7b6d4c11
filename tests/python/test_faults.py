"""make faults (tools/sim/faults.py): the frame-level fault transformations on a small
synthetic frame list, the IMU re-encoding of the sensor-level faults, and the recovery-time
functions on synthetic error series. Fast: no firmware run, no full drive."""
from types import SimpleNamespace

import numpy as np
import pytest

from tools import navecu_can as nc
from tools.sim import faults

DB = nc.DEFAULT_DB
ID = {n: DB.get_message_by_name(n).frame_id for n in
      ("IMU_Rate", "IMU_Accel", "WheelSpeeds", "GNSS_Position", "GNSS_Velocity", "GNSS_Height",
       "GNSS_Status", "CMD_KnownPosition", "CMD_Control")}
IMU_HZ = 100


def synthetic_frames(seconds=4.0):
    """A sorted frame list like run.frames': the initialization commands at 0, IMU pairs at
    100 Hz, wheel speeds at 50 Hz, GNSS epochs (4 frames) at 5 Hz."""
    s = nc.E2ESender(DB)
    rng = np.random.default_rng(7)
    fr = [(0.0, 0, s.encode("CMD_KnownPosition", {"Latitude": 45.0, "Longitude": 10.0})),
          (0.0, 1, s.encode("CMD_Control", {"Command": 2, "HeadingValid": 1, "Heading": 30.0,
                                            "Height": 100.0}))]
    q = nc.ImuQuantizer()
    n = int(seconds * IMU_HZ)
    for k in range(1, n + 1):
        t = k / IMU_HZ
        r, a = s.encode_imu_pair(*q.signals(rng.normal(0, 1e-3, 3), rng.normal(0, 1e-2, 3)), t)
        fr += [(t, 2, r), (t, 3, a)]
    for k in range(0, n // 2):
        t = k / 50.0
        v = 5.0 + 0.02 * k
        fr.append((t, 4, s.encode("WheelSpeeds", {"WheelSpeedFL": v, "WheelSpeedFR": v,
                                                  "WheelSpeedRL": v, "WheelSpeedRR": v}, t)))
    for k in range(0, n // 20):
        t = k / 5.0
        e = s.next_counter("GNSS_Velocity")
        fr.append((t, 5, s.encode("GNSS_Position", {"Latitude": 45.0, "Longitude": 10.0}, t)))
        fr.append((t, 6, s.encode("GNSS_Velocity", {"VelEast": 1.0, "VelNorth": 2.0, "VelUp": 0.0,
                                                    "SpeedAccuracy": 0.1}, t)))
        fr.append((t, 7, s.encode("GNSS_Height", {"Height": 100.0, "GnssEpoch": e}, t)))
        fr.append((t, 8, s.encode("GNSS_Status", {
            "FixType": 3, "NumSatellites": 9, "HorizAccuracy": 3.2, "VertAccuracy": 4.5,
            "GnssEpoch": e, "TimeOfWeek": 302400.0 + t}, t)))
    fr.sort(key=lambda x: (x[0], x[1]))
    return [m for _, _, m in fr]


@pytest.fixture(scope="module")
def frames():
    return synthetic_frames()


def rng(seed=1):
    return np.random.default_rng(seed)


def key(m):
    return (m.arbitration_id, bytes(m.data))


def commands(msgs):
    return [key(m) for m in msgs if m.arbitration_id in (ID["CMD_KnownPosition"],
                                                         ID["CMD_Control"])]


def all_valid(msgs):
    """Every frame passes the E2E checks (IMU pairs as pairs)."""
    rx = nc.E2EReceiver(DB)
    return all(rx.check(m) for m in msgs)


def test_synthetic_list_is_valid(frames):
    assert len(frames) > 1000
    assert all_valid(frames)


@pytest.mark.parametrize("frac", [0.01, 0.05, 0.2])
def test_drop_fraction_and_commands_kept(frames, frac):
    out, n = faults.drop_frames(frames, frac, rng(), DB)
    eligible = len(frames) - 2
    assert abs(n - frac * eligible) <= 1
    assert len(out) == len(frames) - n
    assert commands(out) == commands(frames)
    # what is left is the original in its order
    it = iter(frames)
    assert all(any(m is o for o in it) for m in out)


def test_drop_is_seeded(frames):
    a, _ = faults.drop_frames(frames, 0.05, rng(3), DB)
    b, _ = faults.drop_frames(frames, 0.05, rng(3), DB)
    c, _ = faults.drop_frames(frames, 0.05, rng(4), DB)
    assert [key(m) for m in a] == [key(m) for m in b] != [key(m) for m in c]


def test_duplicates_counted_and_adjacent(frames):
    out, n = faults.duplicate_frames(frames, 0.02, rng(), DB)
    assert abs(n - 0.02 * (len(frames) - 2)) <= 1
    assert len(out) == len(frames) + n
    twice = sum(1 for a, b in zip(out, out[1:])
                if key(a) == key(b) and a.timestamp == b.timestamp)
    assert twice == n
    # removing each copy gives the original list back
    dedup = [out[0]] + [b for a, b in zip(out, out[1:]) if key(a) != key(b)]
    assert [key(m) for m in dedup] == [key(m) for m in frames]


def test_reorders_counted_swapped_and_time_monotonic(frames):
    out, n = faults.reorder_frames(frames, 0.02, rng(), DB)
    assert n == round(0.02 * (len(frames) - 1))
    assert len(out) == len(frames)
    swapped = [i for i in range(len(frames)) if key(out[i]) != key(frames[i])]
    # each swap changes two adjacent positions (unless the two frames were identical)
    assert len(swapped) <= 2 * n
    assert len(swapped) >= 2 * n - 2
    for i in swapped:
        j = i + 1 if i + 1 < len(frames) and key(out[i]) == key(frames[i + 1]) else i - 1
        assert key(out[i]) == key(frames[j]) and key(out[j]) == key(frames[i])
    assert sorted(key(m) for m in out) == sorted(key(m) for m in frames)
    ts = [m.timestamp for m in out]
    assert ts == [m.timestamp for m in frames]           # receive times stay in order
    assert commands(out) == commands(frames)


def test_crc_flip_changes_byte_7_only(frames):
    out, n = faults.flip_crcs(frames, 0.01, rng(), DB)
    info = faults._e2e_info(DB)
    with_crc = [m for m in frames if m.arbitration_id in info
                and info[m.arbitration_id][2] is not None
                and m.arbitration_id not in (ID["CMD_KnownPosition"], ID["CMD_Control"])]
    assert {DB.get_message_by_frame_id(m.arbitration_id).name for m in with_crc} == {
        "IMU_Accel", "WheelSpeeds", "GNSS_Velocity"}
    assert n == round(0.01 * len(with_crc)) and n > 0
    changed = [(a, b) for a, b in zip(frames, out) if key(a) != key(b)]
    assert len(changed) == n
    for a, b in changed:
        assert a.data[:7] == b.data[:7]
        assert a.data[7] ^ b.data[7] == 0xFF
        assert a.timestamp == b.timestamp and a.arbitration_id == b.arbitration_id
    # each changed frame now fails its E2E check, nothing else does
    rx = nc.E2EReceiver(DB)
    bad = {id(b) for _, b in changed}
    assert all(rx.check(m) == (id(m) not in bad) for m in out)


def test_counter_change_keeps_valid_crc(frames):
    out, n = faults.change_counters(frames, 0.01, rng(), DB)
    assert n > 0
    changed = [i for i, (a, b) in enumerate(zip(frames, out)) if key(a) != key(b)]
    info = faults._e2e_info(DB)
    imu_units = 0
    for i in changed:
        a, b = frames[i], out[i]
        cs = info[a.arbitration_id][1]
        ca, cb = nc._counter_value(a.data, cs), nc._counter_value(b.data, cs)
        assert ca != cb and 0 <= cb <= nc.E2E_COUNTER_MAX
        # the payload outside the counter and the CRC byte is unchanged
        mask = ~(0xF << cs.start) & ((1 << 56) - 1)
        assert int.from_bytes(a.data, "little") & mask == int.from_bytes(b.data, "little") & mask
        if a.arbitration_id == ID["IMU_Accel"]:
            imu_units += 1
            assert i - 1 in changed
            assert nc.check_imu_pair(out[i - 1], b, DB)
        elif a.arbitration_id != ID["IMU_Rate"]:
            assert nc.check_e2e(b, DB)
    assert n == len(changed) - imu_units
    assert all_valid(out)                       # only the counters are wrong


def test_imu_silence_window(frames):
    out, n = faults.drop_imu(frames, 1.0, 2.0, DB)
    assert n == 100
    imu = (ID["IMU_Rate"], ID["IMU_Accel"])
    assert not [m for m in out if m.arbitration_id in imu and 1.0 <= m.timestamp < 2.0]
    assert len(out) == len(frames) - 200
    assert [m for m in out if m.arbitration_id not in imu] == \
        [m for m in frames if m.arbitration_id not in imu]


def test_jitter_keeps_order_and_bounds(frames):
    period = 1.0 / IMU_HZ
    out, n = faults.jitter_imu(frames, 0.3, period, rng(), DB)
    assert n == 400 and len(out) == len(frames)
    imu = (ID["IMU_Rate"], ID["IMU_Accel"])
    a = [m for m in frames if m.arbitration_id in imu]
    b = [m for m in out if m.arbitration_id in imu]
    assert [key(m) for m in a] == [key(m) for m in b]           # IMU order kept
    d = np.array([y.timestamp - x.timestamp for x, y in zip(a, b)])
    assert np.all(np.abs(d) <= 0.3 * period + 1e-12)
    assert np.std(d) > 0.1 * period                             # really jittered
    assert np.all(d[0::2] == d[1::2])                           # a sample's two frames together
    ts = [m.timestamp for m in out]
    assert ts == sorted(ts)                                     # the log stays in time order
    assert [m for m in out if m.arbitration_id not in imu] == \
        [m for m in frames if m.arbitration_id not in imu]


def _imu_frames(dtheta, dv, t):
    """(t, order, msg) of one IMU pair per sample 1..n, as run.frames sends them."""
    s, q = nc.E2ESender(DB), nc.ImuQuantizer()
    out = []
    for k in range(1, len(t)):
        r, a = s.encode_imu_pair(*q.signals(dtheta[k], dv[k]), float(t[k]))
        out += [(float(t[k]), 2, r), (float(t[k]), 3, a)]
    return out


def test_imu_encoder_is_navecu_cans_encoding():
    """ImuEncoder.frames gives the frames run.frames' own loop gives for the changed
    increments (counters, pair CRC, remainder carry), leaves the other frames alone and
    counts the samples that changed."""
    g = np.random.default_rng(5)
    n = 300
    t = np.arange(n + 1) / IMU_HZ
    th, dv = g.normal(0, 1e-3, (n + 1, 3)), g.normal(0, 1e-2, (n + 1, 3))
    th[0] = dv[0] = 0.0
    s = nc.E2ESender(DB)
    wheels = [(float(x), 4, s.encode("WheelSpeeds", {"WheelSpeedFL": 1.0, "WheelSpeedFR": 1.0,
                                                      "WheelSpeedRL": 1.0, "WheelSpeedRR": 1.0},
                                      float(x))) for x in t[::5]]
    fr = sorted(_imu_frames(th, dv, t) + wheels, key=lambda x: (x[0], x[1]))
    drive = faults.Drive("synthetic", "perfect", "none", 1, IMU_HZ, SimpleNamespace(t_s=t), th,
                         dv, None, None, [], 0.0, DB, fr)
    enc = faults.ImuEncoder(drive)
    same, n_same = enc.frames(drive, th, dv)
    assert n_same == 0 and [key(m) for _, _, m in same] == [key(m) for _, _, m in fr]
    th2 = faults.freeze_axis(th, t, 1.0, 1.5, 2, nc.ANGLE_LSB_RAD)
    out, changed = enc.frames(drive, th2, dv)
    want = sorted(_imu_frames(th2, dv, t) + wheels, key=lambda x: (x[0], x[1]))
    assert [(m.timestamp, key(m)) for _, _, m in out] == [(m.timestamp, key(m)) for _, _, m in want]
    assert [o for _, o, _ in out] == [o for _, o, _ in want]
    imu_id = ID["IMU_Rate"]
    differ = sum(key(a) != key(b) for (_, _, a), (_, _, b) in zip(out, fr)
                 if a.arbitration_id == imu_id)
    assert changed == differ >= 50
    assert all_valid([m for _, _, m in out])


def test_freeze_axis_repeats_one_word():
    t = np.arange(0, 10, 0.01)
    th = np.column_stack([np.zeros_like(t), np.zeros_like(t), 1e-3 * np.sin(t)])
    out = faults.freeze_axis(th, t, 2.0, 5.0, 2, nc.ANGLE_LSB_RAD)
    sel = (t >= 2.0) & (t < 5.0)
    q = nc.ImuQuantizer()
    raw = np.array([q.quantize_angle(x)[2] for x in out])
    assert len(set(raw[sel])) == 1
    assert np.array_equal(out[~sel], th[~sel])


# ---- recovery time -------------------------------------------------------------------------
T = np.arange(0.0, 200.0, 0.02)
BAND = np.full(T.size, 2.0)


def test_recovery_never_left_is_zero():
    err = np.full(T.size, 1.0)
    assert faults.recovery_time(T, err, BAND, 50.0) == 0.0
    assert faults.settled_time(T, err, BAND, 50.0) == 0.0
    assert faults.recovery_text(0.0, 0.0) == "0 s"


def test_recovery_time_of_a_return():
    err = np.where((T >= 40.0) & (T < 73.4), 10.0, 1.0)
    assert faults.recovery_time(T, err, BAND, 50.0) == pytest.approx(23.4, abs=0.021)
    assert faults.settled_time(T, err, BAND, 50.0) == pytest.approx(23.4, abs=0.021)


def test_recovery_needs_the_hold():
    # back at 60 s for 5 s only, out again, back for good at 80 s
    err = np.where(((T >= 50.0) & (T < 60.0)) | ((T >= 65.0) & (T < 80.0)), 10.0, 1.0)
    assert faults.recovery_time(T, err, BAND, 50.0) == pytest.approx(30.0, abs=0.021)
    # in the band for 10 s from the end of the window, out later: first return 0 s
    err2 = np.where((T >= 70.0) & (T < 90.0), 10.0, 1.0)
    assert faults.recovery_time(T, err2, BAND, 50.0) == 0.0
    assert faults.settled_time(T, err2, BAND, 50.0) == pytest.approx(40.0, abs=0.021)
    assert faults.recovery_text(0.0, 40.0) == "0 s (out again later; for good after 40 s)"


def test_recovery_never():
    err = np.where(T >= 50.0, 10.0, 1.0)
    assert faults.recovery_time(T, err, BAND, 50.0) is None
    assert faults.recovery_text(None, None) == "none"
    # back only in the last 5 s: not held for 10 s
    err = np.where((T >= 50.0) & (T < 195.0), 10.0, 1.0)
    assert faults.recovery_time(T, err, BAND, 50.0) is None
    assert faults.settled_time(T, err, BAND, 50.0) is None


def test_band_floor_and_factor():
    t = np.array([0.0, 1.0, 2.0])
    b = faults.band_m(t, t, np.array([0.1, 2.0, 4.0]))
    assert b.tolist() == [1.0, 3.0, 6.0]


def test_health_bits_from_the_dbc():
    bits = faults.health_bits(DB)
    assert bits[0][0] == "IMU_STALE" and bits[3][0] == "REJECTED" and bits[7][0] == "FILTER_RESET"
    assert all(isinstance(b, int) and 0 <= b < 16 for b in bits)


def test_slug_and_doc_markers(tmp_path):
    assert faults.slugify("frame loss 1 %") == "frame-loss-1-pct"
    doc = tmp_path / "r.md"
    faults.write_doc(doc, "table one")
    text = doc.read_text()
    assert faults.BEGIN in text and "table one" in text and text.startswith("# Reliability")
    doc.write_text("# Mine\n\nabove\n\n" + faults.BEGIN + "\nold\n" + faults.END + "\n\nbelow\n")
    faults.write_doc(doc, "table two")
    text = doc.read_text()
    assert text.startswith("# Mine\n\nabove\n\n") and text.endswith("\n\nbelow\n")
    assert "table two" in text and "old" not in text
