#!/usr/bin/env python3
"""Write the seed corpora of the fuzz harnesses: tests/fuzz/corpus/<harness>/seed-*.

Valid inputs, so that the fuzzer starts from the protocol rather than from nothing:
frames encoded from the DBC with E2E (tools/navecu_can.py, cantools), candump lines and a
log written by python-can, NVM images in calstore.h's layout, and record sequences for
the application harnesses (formats in tests/fuzz/fuzz_app_common.c, fuzz_options.c,
fuzz_calstore.c, fuzz_codec.c), and ISO-TP exchanges for fuzz_isotp.c. Deterministic: the outputs are committed.

    .venv/bin/python tests/fuzz/make_seeds.py
"""
import os
import shutil
import struct
import sys
import tempfile
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
from tools import navecu_can as nc  # noqa: E402  (cantools, python-can)

OUT = ROOT / "tests" / "fuzz" / "corpus"
DB = nc.load_db()


def write(harness, name, data):
    d = OUT / harness
    d.mkdir(parents=True, exist_ok=True)
    (d / f"seed-{name}").write_bytes(bytes(data))


def mid_values(msg):
    """A physical value for every signal of msg: 0 where the range allows it, else the
    middle; for a multiplexed message only page 0's signals."""
    vals = {}
    for s in msg.signals:
        if s.multiplexer_ids and 0 not in s.multiplexer_ids:
            continue
        lo = s.minimum if s.minimum is not None else 0.0
        hi = s.maximum if s.maximum is not None else 0.0
        v = 0.0 if lo <= 0.0 <= hi else (lo + hi) / 2.0
        vals[s.name] = v
    return vals


# ---- fuzz_codec: id(4) dlc(1) data(8) bit(1) then floats ----
def seeds_codec():
    sender = nc.E2ESender(DB)
    for msg in DB.messages:
        if msg.name in nc.IMU_PAIR:
            continue
        vals = mid_values(msg)
        e2e = nc.e2e_signals(msg)
        if e2e is not None:
            vals.pop(e2e[1].name, None)
            frame = sender.encode(msg.name, vals)
        else:
            frame = nc.encode_frame(DB, msg.name, vals)
        floats = [float(v) for v in list(vals.values())[:4]]
        data = struct.pack("<IB", msg.frame_id, 8) + bytes(frame.data) + bytes([7])
        write("fuzz_codec", msg.name, data + struct.pack(f"<{len(floats)}f", *floats))
    rate, accel = sender.encode_imu_pair((0.001, -0.002, 0.0005), (0.01, 0.0, 0.098))
    for m, bit in ((rate, 3), (accel, 60)):
        data = struct.pack("<IB", m.arbitration_id, 8) + bytes(m.data) + bytes([bit])
        write("fuzz_codec", f"imu-{m.arbitration_id:03X}", data + struct.pack("<3f", 0.001, -0.25, 15.9))
    # a short frame (DLC 3) and an unknown ID
    write("fuzz_codec", "short", struct.pack("<IB", 0x110, 3) + bytes(8) + bytes([0]))
    write("fuzz_codec", "unknown", struct.pack("<IB", 0x555, 8) + bytes(range(8)) + bytes([1]))


# ---- the application's records (fuzz_app_common.c) ----
RX_IDS = ["IMU_Rate", "IMU_Accel", "WheelSpeeds", "GNSS_Position", "GNSS_Velocity",
          "GNSS_Status", "GNSS_Height", "CMD_KnownPosition", "CMD_Control",
          "CMD_InitialAttitude"]


def r_imu(n, w=(0, 0, 0), v=(0, 0, 0), shifts=0, wheel=None, fault=False, lose=False):
    op = 0x0C | (0x10 if wheel is not None else 0) | (0x20 if fault else 0) | (0x40 if lose else 0)
    return bytes([op, n - 1]) + struct.pack("<3b3bBb", *w, *v, shifts, wheel or 0)


def r_gnss(dlat=0, dlon=0, ve=0, vn=0, hacc=20, flags=0):
    return bytes([0x0E]) + struct.pack("<hhbbBB", dlat, dlon, ve, vn, hacc, flags)


def r_wheels(speeds, dt=20):
    return bytes([0x0D, dt]) + struct.pack("<4b", *speeds)


def r_pause(ms):
    return bytes([0x0F]) + struct.pack("<H", ms)


def r_raw(frame, dt=10, flags=0):
    kind = RX_IDS.index(DB.get_message_by_frame_id(frame.arbitration_id).name)
    return bytes([kind | flags, dt]) + bytes(frame.data)


def r_command(cmd, sender, **extra):
    vals = {"Command": cmd, "HeadingValid": 0, "Heading": 0, "Height": 0}
    vals.update(extra)
    return r_raw(sender.encode("CMD_Control", vals))


def app_records():
    """name -> (flags byte, records)"""
    seeds = {}
    # navigating at once, standing still on zero wheel speeds, then GNSS epochs
    recs = r_imu(200, wheel=0) + r_imu(100, wheel=0)
    for k in range(3):
        recs += r_gnss(dlat=k, hacc=20) + r_imu(100, wheel=0)
    seeds["standstill-gnss"] = (0x01, recs)
    # levelling for 30 s (3000 samples) into navigation
    seeds["levelling"] = (0x02, r_imu(250, wheel=0) * 12 + r_pause(600))
    # driving at about 10 m/s on the odometer with GNSS, then calibration commands
    sender = nc.E2ESender(DB)
    recs = r_imu(100, wheel=0)
    for k in range(6):
        recs += r_imu(100, w=(0, 0, 1), wheel=62) + r_gnss(dlat=3 * k, dlon=k, vn=62, hacc=15)
    recs += r_imu(60, wheel=0)
    seeds["drive"] = (0x01, recs)
    # every receive ID as raw frames built by the Python protocol (no prelude): an
    # initialization by command, IMU samples and wheel speeds, one GNSS epoch, commands
    frames = [nc.encode_frame(DB, "CMD_KnownPosition", {"Latitude": 45.0, "Longitude": 10.0})]
    frames.append(sender.encode("CMD_Control", {"Command": 2, "HeadingValid": 1, "Heading": 30.0,
                                                "Height": 100.0}))
    frames.append(sender.encode("CMD_InitialAttitude", {"InitRoll": 0.0, "InitPitch": 0.0}))
    recs = b"".join(r_raw(f, dt=1) for f in frames)
    for k in range(20):
        rate, accel = sender.encode_imu_pair((0.0, 0.0, 0.0), (0.0, 0.0, 9.80665 * 0.01))
        recs += r_raw(rate, dt=10) + r_raw(accel, dt=0)
        if k % 2 == 0:
            recs += r_raw(sender.encode("WheelSpeeds", {"WheelSpeedFL": 0.0, "WheelSpeedFR": 0.0,
                                                        "WheelSpeedRL": 0.0, "WheelSpeedRR": 0.0}), dt=0)
    recs += r_raw(nc.encode_frame(DB, "GNSS_Position", {"Latitude": 45.0, "Longitude": 10.0}), dt=1)
    recs += r_raw(sender.encode("GNSS_Velocity", {"VelEast": 0.0, "VelNorth": 0.0, "VelUp": 0.0,
                                                  "GnssEpoch": 0, "SpeedAccuracy": 0.5}), dt=1)
    recs += r_raw(nc.encode_frame(DB, "GNSS_Height", {"Height": 100.0, "GnssEpoch": 0}), dt=1)
    recs += r_raw(nc.encode_frame(DB, "GNSS_Status", {"FixType": 3, "NumSatellites": 9,
                                                      "HorizAccuracy": 2.0, "VertAccuracy": 3.0,
                                                      "GnssEpoch": 0, "TimeOfWeek": 100200}), dt=1)
    for cmd in (5, 6, 3, 4, 1):
        recs += r_command(cmd, sender)
    seeds["raw-protocol"] = (0x00, recs)
    # a stored calibration at boot, navigating, a gap in the IMU samples, the fault bit
    seeds["nvm-gap-fault"] = (0x05, r_imu(50, wheel=0) + r_imu(40, lose=True) +
                              r_imu(20, fault=True) + r_pause(2000) + r_imu(30))
    return seeds


def seeds_app():
    for name, (flags, recs) in app_records().items():
        write("fuzz_app", name, bytes([flags]) + recs)


def config_bytes(imu=100, nav=50, status=10, level=30, axle=0, reals=None):
    r = dict(base=2000.0, arw=8.73e-7, bg=7.27e-8, ba=1e-3, bgrw=2e-9, barw=8.2e-6, lat=0.1,
             gl=(0.0, 0.0, 0.0), corr=20.0, ol=(0.0, 0.0, 0.0))
    r.update(reals or {})
    return struct.pack("<4HB", imu, nav, status, level, axle) + struct.pack(
        "<14f", r["base"], r["arw"], r["bg"], r["ba"], r["bgrw"], r["barw"], r["lat"], *r["gl"],
        r["corr"], *r["ol"])


def seeds_options():
    recs = app_records()
    write("fuzz_options", "defaults-standstill", config_bytes() + bytes([0x01]) +
          recs["standstill-gnss"][1])
    write("fuzz_options", "400hz-front-levers",
          config_bytes(imu=400, nav=400, status=50, level=1, axle=1,
                       reals=dict(gl=(0.5, 1.2, 1.0), ol=(0.0, -1.4, -0.3), lat=0.5, corr=600.0)) +
          bytes([0x01]) + recs["drive"][1])
    write("fuzz_options", "10hz-levelling", config_bytes(imu=10, nav=10, status=1, level=2) +
          bytes([0x02]) + r_imu(30, wheel=0) + r_gnss())
    write("fuzz_options", "edges", config_bytes(reals=dict(base=0.0, lat=0.0, corr=0.0,
                                                           arw=1e-30, bg=1e-30)) + bytes([0x01]))


# ---- fuzz_calstore: flags(1) record(13) cut(2) torn(1) then the NVM image ----
SECTOR = 512  # tests/support/fake_hal.h: 2 sectors of 512 bytes (room for the extension)
EXT_OFFSET = 64  # calstore.h: the version 2 extension (parameters, DTC bytes) in a slot


def ext_image(seq, entries=b"", dtc=b"\xff" * 16, version=2):
    body = b"NPAR" + bytes([version, 0]) + struct.pack("<HIHH", 32 + len(entries), seq,
                                                      len(entries), 0) + dtc + entries
    return body + struct.pack("<I", zlib.crc32(body))


def slot_v2(seq, entries=b"", dh=0.0, mu=0.0, base=0.0, source=0, commit=True, version=2):
    v1 = slot_image(seq, dh, mu, base, source, commit)[:36]
    img = v1 + b"\xff" * (EXT_OFFSET - 36) + ext_image(seq, entries, version=version)
    return img + b"\xff" * (SECTOR - len(img))


def entry(did, value):
    return struct.pack(">HB", did, len(value)) + value


def slot_image(seq, dh, mu, base, source, commit=True):
    body = b"NCAL" + bytes([1, source]) + struct.pack("<HI3f", 24, seq, dh, mu, base)
    img = body + struct.pack("<I", zlib.crc32(body)) + b"\xff" * 4
    img += b"DONE" if commit else b"\xff" * 4
    return img + b"\xff" * (SECTOR - len(img))


def calstore_input(flags, rec, image, cut=0, torn=0):
    return bytes([flags]) + struct.pack("<3fBHB", *rec, cut, torn) + image


def seeds_calstore():
    rec = (0.01, 0.012, 2500.0, 1)
    erased = b"\xff" * (2 * SECTOR)
    one = slot_image(5, -0.02, 0.01, 3000.0, 2) + b"\xff" * SECTOR
    both = slot_image(7, 0.1, -0.05, 100.0, 3) + slot_image(8, 0.2, 0.05, 0.0, 1)
    torn = slot_image(9, 0.1, 0.0, 1.0, 1, commit=False) + slot_image(3, 0.0, 0.0, 0.0, 3)
    wrap = slot_image(0xFFFFFFFF, 0.3, 0.1, 5.0, 1) + slot_image(0, 0.3, 0.1, 6.0, 1)
    write("fuzz_calstore", "empty-save", calstore_input(0x01, rec, erased))
    write("fuzz_calstore", "one-save-twice", calstore_input(0x09, rec, one))
    write("fuzz_calstore", "both-cut", calstore_input(0x03, rec, both, cut=20, torn=0x0F))
    write("fuzz_calstore", "torn-cut-backwards", calstore_input(0x07, rec, torn, cut=38, torn=0x00))
    write("fuzz_calstore", "seq-wrap-erase", calstore_input(0x11, rec, wrap))
    write("fuzz_calstore", "bad-record", calstore_input(0x01, (float("nan"), 0.0, 1.0, 1), one))
    ext = slot_v2(4, entry(0x0204, struct.pack(">H", 20))) + b"\xff" * SECTOR
    write("fuzz_calstore", "v2-carried", calstore_input(0x09, rec, ext))
    write("fuzz_calstore", "v2-cut", calstore_input(0x03, rec, ext, cut=40, torn=0xF0))


# ---- fuzz_nvstore: flags(1) cut(2) torn(1) level(1) dtc_index(1) dtc_status(1) n(1),
# n entry bytes, then the NVM image ----
def nvstore_input(flags, image=b"", entries=b"", cut=0, torn=0, level=20, dtc=(3, 0x09)):
    return (bytes([flags]) + struct.pack("<HBBBBB", cut, torn, level, dtc[0], dtc[1],
                                         len(entries)) + entries + image)


def seeds_nvstore():
    good = (entry(0x0204, struct.pack(">H", 45)) + entry(0x0240, struct.pack(">f", 0.08))
            + entry(0x0213, struct.pack(">3f", 1.0, -0.5, 0.25)) + entry(0x0210, b"\x01"))
    bad = (entry(0x7FEE, b"\x00\x01") + entry(0x0250, b"\x07\x11")
           + entry(0x0204, b"\x1e") + entry(0x0240, struct.pack(">f", 1e6)) + b"\x02\x40\x04")
    v2 = slot_v2(1, good) + b"\xff" * SECTOR
    v1 = slot_image(5, -0.02, 0.01, 3000.0, 2) + b"\xff" * SECTOR
    newer = slot_v2(2, good, version=3) + b"\xff" * SECTOR
    write("fuzz_nvstore", "empty-save", nvstore_input(0x01))
    write("fuzz_nvstore", "v2-load-save", nvstore_input(0x01, v2))
    write("fuzz_nvstore", "v1-migrate-save", nvstore_input(0x01, v1))
    write("fuzz_nvstore", "newer-refused", nvstore_input(0x00, newer))
    write("fuzz_nvstore", "entries-good", nvstore_input(0x20, entries=good))
    write("fuzz_nvstore", "entries-bad", nvstore_input(0x20, entries=bad))
    write("fuzz_nvstore", "cut-save", nvstore_input(0x03, v2, cut=100, torn=0x0F))
    write("fuzz_nvstore", "cut-backwards", nvstore_input(0x07, v2, cut=200, torn=0x00))
    write("fuzz_nvstore", "dtc-erase", nvstore_input(0x18, v2))


# ---- fuzz_candump: a line, or a whole log ----
def seeds_candump():
    write("fuzz_candump", "line", b"(1436509052.249713) vcan0 123#DEADBEEF")
    write("fuzz_candump", "line-ext-dir", b"(0000000001.000000) can0 1FFFFFFF#0011223344556677 R\r")
    write("fuzz_candump", "lines-mixed",
          b"(1.5) can0 7FF#\n\n \t\r\n(2.123456789) any 100#00\n(3.0) can0 123#R\n"
          b"(4.0) can0 123##0DEAD\n(5.0) can0 20000000#00\n(6.0) c 12#00\n(7.0) can0 321#1")
    sender = nc.E2ESender(DB)
    msgs = [nc.encode_frame(DB, "CMD_KnownPosition", {"Latitude": 45.0, "Longitude": 10.0},
                            timestamp=100.0)]
    for k in range(3):
        rate, accel = sender.encode_imu_pair((0.0, 0.0, 0.001), (0.0, 0.0, 0.098),
                                             timestamp=100.01 * (k + 1))
        msgs += [rate, accel]
    tmp = Path(tempfile.mkdtemp())
    try:
        log = tmp / "seed.log"
        nc.write_candump(log, msgs)
        write("fuzz_candump", "python-can-log", log.read_bytes())
    finally:
        shutil.rmtree(tmp)


# ---- fuzz_isotp: cfg(8) then records (tests/fuzz/fuzz_isotp.c) ----
def iso_cfg(padding=1, pad=0xCC, bs=8, st_min=0, wft=10, wait_rx=0, timeout=250, wait_period=99):
    return bytes([padding, pad, bs, st_min, wft, wait_rx, timeout, wait_period])


def iso_frame(*data, dt=1, where=0, dlc=None):
    d = bytes(data) + bytes(8 - len(data))
    return bytes([0, dt, where, len(data) if dlc is None else dlc]) + d


def iso_poll(dt_10us=1):
    return bytes([1]) + struct.pack("<H", dt_10us)


def iso_send(n, dt=1):
    return bytes([2, dt]) + struct.pack("<H", n)


def iso_receive(cap=4095):
    return bytes([3]) + struct.pack("<H", cap)


def iso_clock(step):
    return bytes([5, step])


def iso_tester_message(n, bs=8):
    """a tester's n-byte message, FF then CFs, with a poll for each FC of block size bs"""
    msg = bytes((i * 7 + 1) & 0xFF for i in range(n))
    r = iso_frame(0x10 | (n >> 8), n & 0xFF, *msg[:6]) + iso_poll()
    pos, sn, k = 6, 1, 0
    while pos < n:
        chunk = msg[pos:pos + 7]
        r += iso_frame(0x20 | sn, *chunk, dlc=8)
        pos, sn, k = pos + len(chunk), (sn + 1) & 0xF, k + 1
        if bs and k % bs == 0:
            r += iso_poll()
    return r + iso_receive()


def seeds_isotp():
    write("fuzz_isotp", "receive-62", iso_cfg() + iso_tester_message(62))
    write("fuzz_isotp", "receive-300-bs3", iso_cfg(bs=3, st_min=0xF5) + iso_tester_message(300, bs=3))
    write("fuzz_isotp", "send-100-bs2-stmin",
          iso_cfg() + iso_send(100) + iso_poll() + iso_frame(0x30, 2, 5)
          + b"".join(iso_poll(600) for _ in range(3)) + iso_frame(0x30, 0, 0xF3)
          + b"".join(iso_poll(40) for _ in range(14)))
    write("fuzz_isotp", "wait-while-busy",
          iso_cfg(wft=2) + iso_frame(0x01, 0x3E) + iso_frame(0x10, 20, 1, 2, 3, 4, 5, 6)
          + iso_poll() + iso_poll(10000) + iso_receive() + iso_poll()
          + iso_frame(0x21, 7, 8, 9, 10, 11, 12, 13) + iso_frame(0x22, 14, 15, 16, 17, 18, 19, 20)
          + iso_receive())
    write("fuzz_isotp", "overflow-both",
          iso_cfg() + iso_frame(0x10, 0, 0, 0, 0x13, 0x88, 1, 2) + iso_poll()
          + iso_send(3000) + iso_poll() + iso_frame(0x32, 0, 0) + iso_poll())
    write("fuzz_isotp", "timeouts-refused",
          iso_cfg(timeout=10) + iso_frame(0x10, 20, 1, 2, 3, 4, 5, 6) + iso_poll()
          + iso_clock(200) + iso_poll() + bytes([4]) + iso_send(5) + iso_poll()
          + iso_clock(255) + iso_poll() + iso_clock(100) + iso_poll())
    write("fuzz_isotp", "unpadded-wrong-sn",
          iso_cfg(padding=0, pad=0x00) + iso_frame(0x10, 30, 1, 2, 3, 4, 5, 6) + iso_poll()
          + iso_frame(0x21, 1, 2, 3, 4, 5, 6, 7) + iso_frame(0x23, 1, 2, 3, 4, 5, 6, 7)
          + iso_send(9) + iso_poll() + iso_frame(0x30, 0, 0, dlc=3) + iso_poll()
          + iso_frame(0x21, 7, 8, dlc=3, where=1) + iso_frame(0x02, 1, 2, where=2))


def main():
    shutil.rmtree(OUT, ignore_errors=True)
    seeds_codec()
    seeds_app()
    seeds_options()
    seeds_calstore()
    seeds_nvstore()
    seeds_candump()
    seeds_isotp()
    for d in sorted(OUT.iterdir()):
        print(f"make_seeds: {d.relative_to(ROOT)}: {len(list(d.iterdir()))} seeds")
    return 0


if __name__ == "__main__":
    sys.exit(main())
