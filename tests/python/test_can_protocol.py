"""Tests of the navecu CAN protocol's Python side (docs/can.md): the DBC, CRC and E2E,
alive counters, the IMU quantiser, the stationary log generator and the generated doc."""

import math
import random
import subprocess
import sys
from pathlib import Path

import can
import cantools
import numpy as np
import pytest

from tools import gen_stationary_log as gen
from tools import navecu_can as nc

ROOT = Path(__file__).resolve().parents[2]

U = 7.292115e-5
ANGLE_LSB = 2.0**-21
VEL_LSB = 2.0**-12

E2E_MESSAGES = {"IMU_Rate", "IMU_Accel", "IMU_Time", "WheelSpeeds", "GNSS_Velocity", "GNSS_Time",
                "GNSS_RawSatX", "GNSS_RawSatY", "GNSS_RawSatZ", "GNSS_RawRange", "GNSS_RawRate",
                "GNSS_RawEpoch", "CMD_Control",
                "CMD_InitialAttitude", "NAV_Height", "NAV_Velocity", "NAV_Attitude", "NAV_Rates",
                "NAV_AttitudeRates", "NAV_Accel", "NAV_AccelEnu", "NAV_Status", "NAV_Accuracy",
                "NAV_Calibration", "NAV_Time", "NAV_Heartbeat"}


@pytest.fixture(scope="module")
def db():
    return nc.load_db()


# ------------------------------------------------------------------------------ DBC ----

def test_dbc_loads_strict(db):
    assert len(db.messages) == 31
    for msg in db.messages:
        assert msg.length == 8 and not msg.is_extended_frame and not msg.is_fd, msg.name
        assert msg.frame_id <= 0x7FF
    assert {m.name for m in db.messages if nc.is_e2e(m)} == E2E_MESSAGES
    # the IMU pair: IMU_Rate has a counter and no CRC of its own, IMU_Accel both
    rate, accel = (db.get_message_by_name(n) for n in nc.IMU_PAIR)
    assert [s.name for s in nc.e2e_signals(rate) if s is not None] == ["ImuCounter"]
    assert [s.name for s in nc.e2e_signals(accel)] == ["ImuCounter", "ImuCrc"]
    assert not any(s.name.endswith("Crc") for s in rate.signals)
    assert nc.e2e_signals(rate)[0].start == 60 and nc.e2e_signals(accel)[0].start == 52
    # every 4-bit epoch/counter runs 0..14 in the DBC, 15 being invalid
    for msg in db.messages:
        for sig in msg.signals:
            if sig.name.endswith(("Counter", "Epoch")) and sig.length == 4:
                assert (sig.minimum, sig.maximum) == (0, 14), (msg.name, sig.name)
    assert db.get_message_by_name("NAV_Status").cycle_time == 50
    # the one time-driven output: 1 s of the ECU's uptime, left out of identity comparisons
    assert db.get_message_by_name("NAV_Heartbeat").cycle_time == 1000
    assert nc.time_driven_ids(db) == {db.get_message_by_name("NAV_Heartbeat").frame_id}


def test_strict_load_rejects_overlapping_signals(tmp_path):
    """load_db really loads strictly: a DBC with overlapping signals is refused."""
    text = nc.DBC_PATH.read_text()
    bad = text.replace(" SG_ ImuFault : 51|1@1+", " SG_ ImuFault : 50|1@1+")
    assert bad != text
    path = tmp_path / "bad.dbc"
    path.write_text(bad)
    with pytest.raises(Exception):
        nc.load_db(path)


def test_imu_lsbs_match_dbc(db):
    rate = db.get_message_by_name("IMU_Rate")
    accel = db.get_message_by_name("IMU_Accel")
    for axis in "XYZ":
        sig = rate.get_signal_by_name(f"AngleInc{axis}")
        assert sig.scale == ANGLE_LSB == nc.ANGLE_LSB_RAD
        assert (sig.length, sig.is_signed, sig.minimum) == (20, True, -0.25)
        sig = accel.get_signal_by_name(f"VelInc{axis}")
        assert sig.scale == VEL_LSB == nc.VEL_LSB_MPS
        assert (sig.length, sig.is_signed, sig.minimum) == (17, True, -16)
    assert nc.ImuQuantizer().angle_raw_range == (-2**19, 2**19 - 1)
    assert nc.ImuQuantizer().vel_raw_range == (-2**16, 2**16 - 1)


def _on_grid(sig, x):
    """x moved to the nearest value the signal can represent, inside [min, max]."""
    conv = sig.conversion
    raw = round((x - conv.offset) / conv.scale)
    lo = math.ceil((sig.minimum - conv.offset) / conv.scale - 1e-9)
    hi = math.floor((sig.maximum - conv.offset) / conv.scale + 1e-9)
    return min(max(raw, lo), hi) * conv.scale + conv.offset


def _value_sets(sig):
    lo, hi = sig.minimum, sig.maximum
    return {"min": _on_grid(sig, lo), "max": _on_grid(sig, hi),
            "zero": _on_grid(sig, min(max(0.0, lo), hi)), "middle": _on_grid(sig, (lo + hi) / 2)}


def _pages(msg):
    """Signal-name sets to encode: one per multiplexer page (NAV_Status 0..6), else all."""
    mux = [s for s in msg.signals if s.is_multiplexer]
    if not mux:
        return [(None, [s.name for s in msg.signals])]
    ids = sorted({i for s in msg.signals for i in (s.multiplexer_ids or [])})
    return [(page, [s.name for s in msg.signals
                    if s.multiplexer_ids is None or page in s.multiplexer_ids]) for page in ids]


def test_every_message_round_trips(db):
    n_checked = 0
    for msg in db.messages:
        pages = _pages(msg)
        if msg.name == "NAV_Status":
            assert [p for p, _ in pages] == [0, 1, 2, 3, 4, 5, 6]
        if msg.name == "NAV_Calibration":
            assert [p for p, _ in pages] == [0, 1, 2]
        for page, names in pages:
            for case in ("min", "max", "zero", "middle"):
                values = {}
                for name in names:
                    sig = msg.get_signal_by_name(name)
                    values[name] = _value_sets(sig)[case]
                if page is not None:
                    mux = next(s for s in msg.signals if s.is_multiplexer)
                    values[mux.name] = page
                frame = nc.encode_frame(db, msg.name, values)
                assert frame.dlc == 8 and not frame.is_extended_id
                back = msg.decode(bytes(frame.data), decode_choices=False)
                assert set(back) == set(values), (msg.name, page)
                for name, value in values.items():
                    scale = msg.get_signal_by_name(name).conversion.scale
                    assert back[name] == pytest.approx(value, abs=scale * 1e-6), \
                        (msg.name, page, case, name)
                n_checked += 1
    # NAV_Status: 7 pages, NAV_Calibration: 3
    assert n_checked == 4 * (len(db.messages) - 2 + 7 + 3)


def test_encode_rounds_to_nearest(db):
    """cantools' own scaling truncates (0.29 -> 28 * 0.01); navecu_can rounds."""
    frame = nc.encode_frame(db, "NAV_Velocity", {"VelEast": 0.29, "VelNorth": -0.29,
                                                 "VelUp": 0.0, "NavCounter": 0, "NavCrc": 0})
    back = db.decode_message(frame.arbitration_id, bytes(frame.data))
    assert back["VelEast"] == pytest.approx(0.29)
    assert back["VelNorth"] == pytest.approx(-0.29)


def test_encode_rejects_out_of_range(db):
    with pytest.raises(cantools.database.EncodeError):
        nc.encode_frame(db, "WheelSpeeds", {"WheelSpeedFL": 90.0, "WheelSpeedFR": 0,
                                            "WheelSpeedRL": 0, "WheelSpeedRR": 0,
                                            "WheelCounter": 0, "WheelCrc": 0})


# ------------------------------------------------------------------------------ E2E ----

def _crc8_bitwise(data: bytes) -> int:
    crc = 0xFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


def test_crc_check_value():
    assert nc.crc8_sae_j1850(b"123456789") == 0x4B
    rng = random.Random(1)
    for _ in range(200):
        data = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 12)))
        assert nc.crc8_sae_j1850(data) == _crc8_bitwise(data)


def test_crc_covers_id_low_byte_first():
    data = bytes(range(1, 9))
    assert nc.e2e_crc(0x301, data) == _crc8_bitwise(bytes([0x01, 0x03]) + data[:7])


def _middle_signals(msg, counter_and_crc=False, page=0):
    e2e = nc.e2e_signals(msg)
    skip = set() if counter_and_crc or e2e is None else {s.name for s in e2e if s is not None}
    names = dict(_pages(msg)).get(page if any(s.is_multiplexer for s in msg.signals) else None)
    values = {n: _value_sets(msg.get_signal_by_name(n))["middle"] for n in names
              if n not in skip}
    mux = next((s for s in msg.signals if s.is_multiplexer), None)
    if mux is not None:  # StatusPage, CalPage
        values[mux.name] = page
    return values


def test_e2e_encode_check_and_bit_flips(db):
    sender = nc.E2ESender(db)
    for msg in db.messages:
        if msg.name in nc.IMU_PAIR:
            continue  # test_imu_pair_*
        frame = sender.encode(msg.name, _middle_signals(msg), timestamp=1.5)
        assert frame.timestamp == 1.5
        assert nc.check_e2e(frame, db), msg.name
        if not nc.is_e2e(msg):
            continue
        assert frame.data[7] == nc.e2e_crc(msg.frame_id, frame.data)
        for bit in range(64):  # CRC8 detects every single-bit error
            bad = can.Message(arbitration_id=frame.arbitration_id, is_extended_id=False,
                              dlc=8, data=bytearray(frame.data))
            bad.data[bit // 8] ^= 1 << (bit % 8)
            assert not nc.check_e2e(bad, db), (msg.name, bit)
        # same payload under another E2E message's ID fails: the ID is in the CRC
        other = next(m for m in db.messages if nc.is_e2e(m) and m.frame_id != msg.frame_id
                     and m.name not in nc.IMU_PAIR)
        moved = can.Message(arbitration_id=other.frame_id, is_extended_id=False, dlc=8,
                            data=bytearray(frame.data))
        assert not nc.check_e2e(moved, db)


def test_check_e2e_rejects_counter_15_bad_dlc_and_unknown_id(db):
    frame = nc.encode_frame(db, "CMD_Control", {"Command": 0, "HeadingValid": 0, "Heading": 0,
                                                "Height": 0, "CmdCounter": 14, "CmdCrc": 0})
    frame.data[6] |= 0x0F  # counter 15
    frame.data[7] = nc.e2e_crc(frame.arbitration_id, frame.data)
    assert not nc.check_e2e(frame, db)
    short = can.Message(arbitration_id=0x120, is_extended_id=False, dlc=7, data=bytes(7))
    assert not nc.check_e2e(short, db)
    assert not nc.check_e2e(can.Message(arbitration_id=0x7FF, is_extended_id=False, dlc=8,
                                        data=bytes(8)), db)
    assert not nc.check_e2e(can.Message(arbitration_id=0x100, is_extended_id=True, dlc=8,
                                        data=bytes(8)), db)


def test_alive_counters_wrap_14_to_0_and_never_send_15(db):
    sender = nc.E2ESender(db)
    for msg in db.messages:
        e2e = nc.e2e_signals(msg)
        if e2e is None or msg.name in nc.IMU_PAIR or e2e[0] is None:
            continue  # no counter: NAV_Time (its TimeOfWeek advances)
        counter_sig = e2e[0]
        seen = []
        for _ in range(47):
            frame = sender.encode(msg.name, _middle_signals(msg))
            seen.append(msg.decode(bytes(frame.data))[counter_sig.name])
            assert nc.check_e2e(frame, db)
        assert seen == [k % 15 for k in range(47)], msg.name
        assert 15 not in seen


def test_counters_are_per_message_and_imu_pair_shares_one(db):
    sender = nc.E2ESender(db)
    quant = nc.ImuQuantizer()
    for k in range(47):
        rate, accel = quant.signals([1e-4, 0, 0], [0, 0, 0.098])
        a, b = sender.encode_imu_pair(rate, accel, timestamp=k * 0.01)
        assert (a.arbitration_id, b.arbitration_id) == (0x100, 0x101)
        assert a.timestamp == b.timestamp == k * 0.01
        assert db.decode_message(0x100, bytes(a.data))["ImuCounter"] == k % 15
        assert db.decode_message(0x101, bytes(b.data))["ImuCounter"] == k % 15
        assert nc.check_imu_pair(a, b, db)
    assert sender.next_counter("IMU_Rate") == sender.next_counter("IMU_Accel") == 47 % 15
    assert sender.next_counter("WheelSpeeds") == 0


def test_imu_frames_only_as_a_pair(db):
    sender = nc.E2ESender(db)
    for name in nc.IMU_PAIR:
        with pytest.raises(ValueError):
            sender.encode(name, _middle_signals(db.get_message_by_name(name)))
    a, b = sender.encode_imu_pair([0, 0, 0], [0, 0, 0])
    assert nc.check_e2e(a, db)  # IMU_Rate alone: frame and counter checks only
    with pytest.raises(ValueError):
        nc.check_e2e(b, db)  # IMU_Accel's CRC needs its IMU_Rate
    with pytest.raises(ValueError):
        sender.encode_imu_pair([0, 0, 0], {"VelIncX": 0, "VelIncY": 0, "VelIncZ": 0,
                                           "ImuCrc": 0})
    with pytest.raises(ValueError):  # conflicting explicit counters
        sender.encode_imu_pair({"AngleIncX": 0, "AngleIncY": 0, "AngleIncZ": 0,
                                "ImuCounter": 3}, [0, 0, 0], counter=4)
    with pytest.raises(cantools.database.EncodeError):
        sender.encode_imu_pair([0, 0, 0], [0, 0, 0], counter=15)
    with pytest.raises(cantools.database.EncodeError):
        sender.encode_imu_pair([0.3, 0, 0], [0, 0, 0])
    assert sender.next_counter("IMU_Rate") == 1  # failed encodes do not advance it


# Test vector of the pair CRC: angles (1e-3, -2e-3, 0.1) rad = raw (2097, -4194, 209715),
# velocity increments (0.01, -0.02, 0.0980665) m/s = raw (41, -82, 402), ImuFault 0,
# ImuCounter 5. Bytes worked out by hand from the DBC layout; CRC over
# 01 01 | 31 08 e0 f9 fe 33 33 53 | 29 00 5c ff 4b 06 50.
IMU_PAIR_RATE_HEX = "3108e0f9fe333353"
IMU_PAIR_ACCEL_HEX = "29005cff4b0650ae"
IMU_PAIR_CRC = 0xAE


def test_imu_pair_crc_check_value(db):
    sender = nc.E2ESender(db)
    rate, accel = sender.encode_imu_pair([1e-3, -2e-3, 0.1], [0.01, -0.02, 0.0980665],
                                         counter=5)
    assert bytes(rate.data).hex() == IMU_PAIR_RATE_HEX
    assert bytes(accel.data).hex() == IMU_PAIR_ACCEL_HEX
    assert rate.data[7] >> 4 == 5 and (accel.data[6] >> 4) == 5
    covered = bytes([0x01, 0x01]) + bytes(rate.data) + bytes(accel.data[:7])
    assert len(covered) == 17
    assert accel.data[7] == _crc8_bitwise(covered) == nc.imu_pair_crc(0x101, rate.data,
                                                                         accel.data)
    assert accel.data[7] == IMU_PAIR_CRC
    # not the single-frame CRC of IMU_Accel
    assert accel.data[7] != nc.e2e_crc(0x101, accel.data)
    assert nc.check_imu_pair(rate, accel, db)
    assert nc.check_imu_pair(rate, accel)  # default DBC


def _pairs(db, n, seed=3):
    sender = nc.E2ESender(db)
    rng = random.Random(seed)
    return [sender.encode_imu_pair([rng.uniform(-0.25, 0.2499) for _ in range(3)],
                                   [rng.uniform(-16, 15.99) for _ in range(3)],
                                   fault=rng.randrange(2)) for _ in range(n)]


def _copy(frame, arbitration_id=None):
    return can.Message(arbitration_id=frame.arbitration_id if arbitration_id is None
                       else arbitration_id, is_extended_id=False, dlc=8,
                       data=bytearray(frame.data), timestamp=frame.timestamp)


def test_imu_pair_any_bit_flip_fails(db):
    for rate, accel in _pairs(db, 16):
        assert nc.check_imu_pair(rate, accel, db)
        for bit in range(64):
            bad = _copy(rate)
            bad.data[bit // 8] ^= 1 << (bit % 8)
            assert not nc.check_imu_pair(bad, accel, db), ("IMU_Rate", bit)
            bad = _copy(accel)
            bad.data[bit // 8] ^= 1 << (bit % 8)
            assert not nc.check_imu_pair(rate, bad, db), ("IMU_Accel", bit)

    # every two-bit error in the 128 bits of one pair (the CRC is linear, so one pair
    # stands for all)
    rate, accel = _pairs(db, 1)[0]
    for i in range(128):
        for j in range(i + 1, 128):
            r, a = _copy(rate), _copy(accel)
            for bit in (i, j):
                frame = r if bit < 64 else a
                frame.data[bit % 64 // 8] ^= 1 << (bit % 8)
            assert not nc.check_imu_pair(r, a, db), (i, j)


def test_imu_pair_counter_mismatch_order_and_ids_fail(db):
    pairs = _pairs(db, 20)
    for k in range(len(pairs) - 1):
        # IMU_Rate of one sample with the IMU_Accel of the next: counter and CRC differ
        assert not nc.check_imu_pair(pairs[k][0], pairs[k + 1][1], db)
        assert not nc.check_imu_pair(pairs[k + 1][0], pairs[k][1], db)
    # a mismatched counter with a CRC recomputed over the bytes as they are still fails
    rate, accel = _copy(pairs[3][0]), _copy(pairs[3][1])
    assert rate.data[7] >> 4 == accel.data[6] >> 4 == 3
    accel.data[6] = (accel.data[6] & 0x0F) | (4 << 4)
    accel.data[7] = nc.imu_pair_crc(0x101, rate.data, accel.data)
    assert not nc.check_imu_pair(rate, accel, db)
    # counter 15 in both frames, CRC right: invalid
    rate.data[7] |= 0xF0
    accel.data[6] |= 0xF0
    accel.data[7] = nc.imu_pair_crc(0x101, rate.data, accel.data)
    assert not nc.check_imu_pair(rate, accel, db)
    assert not nc.check_e2e(rate, db)
    rate, accel = pairs[0]
    assert not nc.check_imu_pair(accel, rate, db)  # order
    assert not nc.check_imu_pair(_copy(rate, 0x110), accel, db)  # other IDs
    assert not nc.check_imu_pair(rate, _copy(accel, 0x110), db)
    short = can.Message(arbitration_id=0x100, is_extended_id=False, dlc=7,
                        data=bytes(rate.data[:7]))
    assert not nc.check_imu_pair(short, accel, db)


def test_e2e_receiver_pairs_imu_frames(db):
    sender = nc.E2ESender(db)
    wheel = sender.encode("WheelSpeeds", _middle_signals(db.get_message_by_name("WheelSpeeds")))
    p = [sender.encode_imu_pair([1e-4 * k, 0, 0], [0, 0, 0.098]) for k in range(4)]
    rx = nc.E2EReceiver(db)
    assert [rx.check(f) for f in (p[0][0], wheel, p[0][1], p[1][0], p[1][1])] == [True] * 5
    assert not rx.check(p[2][1])          # IMU_Accel without its IMU_Rate
    assert rx.check(p[2][0]) and rx.check(p[3][0])
    assert not rx.check(p[2][1])          # IMU_Rate of the next sample held: counters differ
    assert rx.check(p[3][0]) and rx.check(p[3][1])


def test_explicit_counter_is_sent_and_sequence_continues(db):
    sender = nc.E2ESender(db)
    vel = {"VelEast": 1.0, "VelNorth": 2.0, "VelUp": 0.0, "SpeedAccuracy": 0.3}
    frame = sender.encode("GNSS_Velocity", dict(vel, GnssEpoch=9))
    assert db.decode_message(0x121, bytes(frame.data))["GnssEpoch"] == 9
    assert nc.check_e2e(frame, db)
    assert sender.next_counter("GNSS_Velocity") == 10
    with pytest.raises(ValueError):
        sender.encode("GNSS_Velocity", dict(vel, GnssVelCrc=0))


# ------------------------------------------------------------------------ quantiser ----

def test_quantizer_keeps_sub_lsb_earth_rate():
    """100 000 samples of the Earth rate at 400 Hz (0.38 LSB each): with the carried
    remainder the running sum stays within LSB/2 of the exact sum; rounding each sample
    on its own would send 0 every time and lose all of it."""
    inc = 7.292115e-5 / 400.0
    assert inc < ANGLE_LSB / 2
    quant = nc.ImuQuantizer()
    sent = 0
    n = 100_000
    worst = 0.0
    for k in range(1, n + 1):
        raw = quant.quantize_angle([inc, -inc, 0.0])
        assert raw[1] == -raw[0] and raw[2] == 0
        sent += raw[0]
        worst = max(worst, abs(sent * ANGLE_LSB - k * inc))
    exact = n * inc
    assert worst <= ANGLE_LSB / 2 * (1 + 1e-9)
    assert abs(sent * ANGLE_LSB - exact) <= ANGLE_LSB / 2
    assert sent == round(exact / ANGLE_LSB) > 1000
    naive = sum(round(inc / ANGLE_LSB) for _ in range(n))
    assert naive == 0 and exact > 1000 * ANGLE_LSB


def test_quantizer_random_increments_both_channels():
    rng = random.Random(7)
    quant = nc.ImuQuantizer()
    exact_a = exact_v = 0.0
    sent_a = sent_v = 0
    for _ in range(20_000):
        a, v = rng.uniform(-0.01, 0.01), rng.uniform(-0.2, 0.2)
        exact_a += a
        exact_v += v
        sent_a += quant.quantize_angle([a, 0, 0])[0]
        sent_v += quant.quantize_vel([0, v, 0])[1]
        assert abs(sent_a * ANGLE_LSB - exact_a) <= ANGLE_LSB / 2 + 1e-12
        assert abs(sent_v * VEL_LSB - exact_v) <= VEL_LSB / 2 + 1e-12


def test_quantizer_rejects_out_of_range():
    with pytest.raises(ValueError):
        nc.ImuQuantizer().quantize_angle([0.6, 0, 0])
    with pytest.raises(ValueError):
        nc.ImuQuantizer().quantize_angle([0, -0.2501, 0])
    with pytest.raises(ValueError):
        nc.ImuQuantizer().quantize_vel([0, 0, 16.0])
    nc.ImuQuantizer().quantize_angle([-0.25, 0.25 - ANGLE_LSB, 0])  # the DBC's limits
    nc.ImuQuantizer().quantize_vel([-16.0, 16.0 - VEL_LSB, 0])
    with pytest.raises(ValueError):
        nc.ImuQuantizer().quantize_vel([float("nan"), 0, 0])


# ------------------------------------------------------------ attitude and gravity ----

def test_c_bn_follows_frames_md():
    r, p, h = math.radians(12), math.radians(-7), math.radians(250)
    c = gen.c_bn(r, p, h)
    assert np.allclose(c @ c.T, np.eye(3), atol=1e-15)
    assert np.allclose(c[2], [-math.cos(p) * math.sin(r), math.sin(p), math.cos(p) * math.cos(r)])
    assert np.allclose(c[:, 1], [math.sin(h) * math.cos(p), math.cos(h) * math.cos(p), math.sin(p)])
    assert math.isclose(math.asin(c[2][1]), p)
    assert math.isclose(math.atan2(-c[2][0], c[2][2]), r)
    assert math.isclose(math.atan2(c[0][1], c[1][1]) % (2 * math.pi), h)
    # heading 90 deg points the car east
    assert np.allclose(gen.c_bn(0, 0, math.pi / 2) @ [0, 1, 0], [1, 0, 0])


def test_normal_gravity_values():
    # TR8350.2: gamma_e at the equator, gamma_p at the poles; free-air gradient ~3.086e-6 /m
    assert gen.normal_gravity(0.0, 0.0) == pytest.approx(9.7803253359, abs=1e-10)
    assert gen.normal_gravity(math.pi / 2, 0.0) == pytest.approx(9.8321849378, abs=1e-9)
    grad = (gen.normal_gravity(math.radians(45), 0) - gen.normal_gravity(math.radians(45), 100)) / 100
    assert grad == pytest.approx(3.086e-6, rel=2e-3)


# --------------------------------------------------------------- stationary log ----

def _run_gen(tmp_path, *args):
    out = tmp_path / "stationary.log"
    res = subprocess.run([sys.executable, "-m", "tools.gen_stationary_log", "--out", str(out),
                          *args], capture_output=True, text=True, check=True, cwd=ROOT)
    assert len(res.stdout.strip().splitlines()) == 1 and "frames" in res.stdout
    return out


@pytest.mark.parametrize("duration, rate, lat, height, roll, pitch, heading", [
    (60.0, 100.0, 45.0, 100.0, 0.0, 0.0, 30.0),
    (30.0, 400.0, -33.9, 1500.0, 4.0, -6.5, 301.0),
])
def test_stationary_log(tmp_path, db, duration, rate, lat, height, roll, pitch, heading):
    lon = 10.0
    out = _run_gen(tmp_path, "--duration-s", str(duration), "--imu-rate-hz", str(rate),
                   "--lat-deg", str(lat), "--lon-deg", str(lon), "--height-m", str(height),
                   "--roll-deg", str(roll), "--pitch-deg", str(pitch),
                   "--heading-deg", str(heading))
    frames = list(can.LogReader(str(out)))
    n_imu = round(duration * rate)
    n_wheel = round(duration * 50)
    assert len(frames) == 2 + 2 * n_imu + n_wheel
    rx = nc.E2EReceiver(db)
    assert all(rx.check(f) for f in frames)
    assert all(f.dlc == 8 and not f.is_extended_id and not f.is_fd for f in frames)
    times = [f.timestamp for f in frames]
    assert times == sorted(times) and times[0] == 0.0
    assert times[-1] == pytest.approx(duration)

    known = db.decode_message(frames[0].arbitration_id, bytes(frames[0].data))
    assert frames[0].arbitration_id == 0x200
    assert known["Latitude"] == pytest.approx(lat, abs=1e-7)
    assert known["Longitude"] == pytest.approx(lon, abs=1e-7)
    ctl = db.decode_message(frames[1].arbitration_id, bytes(frames[1].data), decode_choices=False)
    assert frames[1].arbitration_id == 0x201 and frames[1].timestamp == 0.0
    assert ctl["Command"] == 2 and ctl["HeadingValid"] == 1
    assert ctl["Heading"] == pytest.approx(heading, abs=0.005)
    assert ctl["Height"] == pytest.approx(height, abs=0.05)

    sum_a = np.zeros(3)
    sum_v = np.zeros(3)
    k = 0
    wheel = 0
    i = 2
    while i < len(frames):
        f = frames[i]
        if f.arbitration_id == 0x110:
            w = db.decode_message(0x110, bytes(f.data))
            assert [w[f"WheelSpeed{x}"] for x in ("FL", "FR", "RL", "RR")] == [0, 0, 0, 0]
            assert w["WheelCounter"] == wheel % 15
            wheel += 1
            assert f.timestamp == pytest.approx(wheel / 50.0, abs=1e-6)
            i += 1
            continue
        g = frames[i + 1]
        assert (f.arbitration_id, g.arbitration_id) == (0x100, 0x101)
        assert nc.check_imu_pair(f, g, db)
        a = db.decode_message(0x100, bytes(f.data))
        v = db.decode_message(0x101, bytes(g.data))
        assert a["ImuCounter"] == v["ImuCounter"] == k % 15 and v["ImuFault"] == 0
        k += 1
        assert f.timestamp == g.timestamp == pytest.approx(k / rate, abs=1e-6)
        sum_a += [a["AngleIncX"], a["AngleIncY"], a["AngleIncZ"]]
        sum_v += [v["VelIncX"], v["VelIncY"], v["VelIncZ"]]
        i += 2
    assert k == n_imu and wheel == n_wheel

    phi = math.radians(lat)
    c_nb = gen.c_bn(math.radians(roll), math.radians(pitch), math.radians(heading)).T
    want_a = c_nb @ np.array([0.0, U * math.cos(phi), U * math.sin(phi)]) * duration
    want_v = c_nb @ np.array([0.0, 0.0, gen.normal_gravity(phi, height)]) * duration
    assert np.all(np.abs(sum_a - want_a) <= ANGLE_LSB), (sum_a, want_a)
    assert np.all(np.abs(sum_v - want_v) <= VEL_LSB), (sum_v, want_v)
    if roll == pitch == 0.0:  # level: independent of the matrix code
        h = math.radians(heading)
        level = np.array([-math.sin(h) * U * math.cos(phi), math.cos(h) * U * math.cos(phi),
                          U * math.sin(phi)]) * duration
        assert np.all(np.abs(sum_a - level) <= ANGLE_LSB)
        assert abs(sum_v[2] - gen.normal_gravity(phi, height) * duration) <= VEL_LSB


def test_stationary_log_default_arguments(tmp_path):
    out = _run_gen(tmp_path)
    with out.open() as f:
        n = sum(1 for _ in f)
    assert n == 2 + 2 * 60_000 + 30_000


# -------------------------------------------------------------------------- doc ----

def test_can_doc_is_current():
    res = subprocess.run([sys.executable, "-m", "tools.gen_can_doc", "--check"],
                         capture_output=True, text=True, cwd=ROOT)
    assert res.returncode == 0, res.stderr


# ------------------------------------------------------------------ reading a CAN log ----

# (line, a frame?) by hal/common/candump.h's rule, which navecu --can-log applies
CANDUMP_CASES = [
    ("(0000000001.000000) can0 101#0011223344556677", True),
    ("  (1.5)\tvcan0 7FF#   ", True),
    ("(1.123456789) can0 123#0011 R\r", True),
    ("(1.0) can0 1FFFFFFF#00", True),
    ("(1.0) can0 123#", True),
    ("this is not a candump line", False),             # regression_inputs' three
    ("(12.5) can0 1234#00", False),                     # python-can: extended 0x1234
    ("(100.000000) can0 100#0011223344556677889900", False),  # python-can: 11 bytes
    ("(1.0) can0 GARBAGE", False),                      # python-can: ValueError
    ("(1.0) can0 101#ZZ", False),                       # python-can: ValueError
    ("(1.0) can0 101#001", False),                      # odd digits: cut short
    ("(1.0) can0 800#00", False),
    ("(1.0) can0 20000000#00", False),                  # CAN_ERR_FLAG: an error frame
    ("(1.0) can0 123#R", False),
    ("(1.0) can0 123##100", False),
    ("(1.0 can0 123#00", False),
    ("(1.0) can0 123#00 X", False),
    ("(0.2) can0 123#0011\tR", True),                   # python-can: split on " " only
    ("(\u0661\u0660.5) can0 123#00", False),            # python's \d takes Arabic digits
]


def test_log_file_skips_and_counts_malformed_lines_as_navecu_does(tmp_path):
    """nc.LogFile (every tool's candump reader) takes the lines the firmware takes and skips
    and counts the others, where python-can's reader raised (a traceback half way through
    a replay) or changed the frame; navecu --can-log on the same file counts as many."""
    good = "(0000000002.000000) can0 310#0000000000000000"
    lines = [good]
    for text, _ in CANDUMP_CASES:
        lines += [text, good]
    log = tmp_path / "mixed.log"
    data = ("\n".join(lines) + "\n\n").encode() + b"(3.0) can0 101#00\xff\xfe\n" + \
        (good + "\n").encode()
    log.write_bytes(data)
    n_bad = sum(not ok for _, ok in CANDUMP_CASES) + 1   # + the line that is not UTF-8
    n_frames = len(CANDUMP_CASES) + 2 + sum(ok for _, ok in CANDUMP_CASES)
    with nc.LogFile(log) as f:
        frames = list(f)
    assert (len(frames), f.malformed) == (n_frames, n_bad)
    assert f.first_malformed[0] == (12, "this is not a candump line")
    assert all(len(m.data) <= 8 and m.arbitration_id < 1 << 29 for m in frames)
    assert f"{n_bad} malformed lines of {log} skipped (first: line 12," in f.note()
    skipped = []
    assert len(nc.read_log(log, skipped)) == n_frames and skipped[0].malformed == n_bad
    navecu = ROOT / "build" / "host" / "navecu"
    if navecu.exists():
        r = subprocess.run([str(navecu), "--can-log", str(log), "--out", str(tmp_path / "o.log")],
                           capture_output=True, text=True, timeout=30)
        assert f"{n_frames} frames in, {n_bad} malformed lines skipped" in r.stderr


def test_can_replay_counts_malformed_lines_and_names_a_missing_log(tmp_path, capsys):
    """The log replayer on python-can's virtual bus: a malformed line once ended the
    replay half way with "not enough values to unpack"; now it is skipped and counted in
    the summary, as navecu --can-log skips it. A missing log: one line, exit status 1."""
    from tools import can_replay
    log = tmp_path / "in.log"
    good = [f"({k * 0.01:.6f}) can0 100#{k:016X}" for k in range(20)]
    log.write_text("\n".join(good[:10] + ["(0.1) can0 GARBAGE"] + good[10:]) + "\n")
    assert can_replay.main([str(log), "--interface", "virtual", "--channel", "t",
                            "--max-rate", "100000"]) == 0
    err = capsys.readouterr().err
    assert "can_replay: 20 frames" in err and "1 malformed line of" in err
    assert "(first: line 11, '(0.1) can0 GARBAGE')" in err
    assert can_replay.main([str(tmp_path / "none.log"), "--interface", "virtual",
                            "--channel", "t"]) == 1
    assert "No such file or directory" in capsys.readouterr().err
