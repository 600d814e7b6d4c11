"""navecu on a shared bus (issue #15, docs/can.md): broken frames on its own identifiers are
refused without corrupting the epoch or the IMU sample they land in, and other nodes'
traffic changes nothing but the count of it.

The clean input is the replay regression's sim-clean log (tests/regression/, the regress
drive with standstill levelling, GNSS and the odometer) cut to its first 80 s, run with the
case's options; each test inserts frames into it and compares build/host/navecu's outputs
with the clean run's.
"""
import bisect
import os
import shlex
import subprocess
from pathlib import Path

import can
import numpy as np
import pytest

from tools import navecu_can as nc
from tools import regression

ROOT = Path(__file__).resolve().parents[2]
NAVECU = Path(os.environ.get("NAVECU_BIN", ROOT / "build" / "host" / "navecu"))
DB = nc.load_db(nc.DBC_PATH)          # native: the DBC's identifiers, whatever is selected
ID = {m.name: m.frame_id for m in DB.messages}
STATUS = DB.get_message_by_name("NAV_Status")
PAGE = nc.status_signals(DB)          # counter -> its NAV_Status page
REJECTED = nc.health_flag(DB, "REJECTED")
HOLD_S = 1.0                          # HealthFlags REJECTED: "rejected in the last second"
STATUS_HZ = 10                        # NAV_Status page 0 (docs/can.md, the default rate)
IMU_HZ = 100
T_END_S = 80.0                        # the clean log's cut: levelling ends at 35 s
T_GNSS_S = 60.0                       # the epoch hit: the first from here (navigating)
T_IMU_S = 65.0                        # the IMU sample hit: the first from here
FOREIGN_HZ = 2000


def navecu(msgs, d: Path, label: str, args) -> tuple:
    """(output frames, stderr) of navecu on msgs."""
    log, out = d / f"{label}.log", d / f"{label}-nav.log"
    nc.write_candump(log, msgs)
    res = subprocess.run([str(NAVECU), "--can-log", str(log), "--out", str(out)] + args,
                         capture_output=True, text=True, check=True)
    return nc.read_log(out), res.stderr


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    if not NAVECU.exists():
        pytest.fail(f"{NAVECU} not built: run 'make' first")
    d = tmp_path_factory.mktemp("shared_bus")
    case = next(c for c in regression.load_cases(regression.CASES_DIR) if c["name"] == "sim-clean")
    msgs = [m for m in nc.read_log(regression.input_log(case, regression.CASES_DIR, d))
            if m.timestamp < T_END_S]
    args = shlex.split(case["args"])
    outs, err = navecu(msgs, d, "clean", args)
    return msgs, args, outs, err, d


def others(outs) -> list:
    """Every output frame but NAV_Status and the time-driven NAV_Heartbeat (sent at the
    first poll of each second of HAL time, which an inserted frame may move), as (time,
    identifier, data)."""
    return [(m.timestamp, m.arbitration_id, bytes(m.data)) for m in nc.data_driven(outs)
            if m.arbitration_id != STATUS.frame_id]


def statuses(outs) -> list:
    """NAV_Status frames as (time, decoded signals, data)."""
    return [(m.timestamp, STATUS.decode(bytes(m.data), decode_choices=False), bytes(m.data))
            for m in outs if m.arbitration_id == STATUS.frame_id]


def page0_flags(outs) -> list:
    return [(t, int(s["HealthFlags"])) for t, s, _ in statuses(outs) if s["StatusPage"] == 0]


def with_frame(msgs, i: int, frame: can.Message) -> list:
    """msgs with frame inserted before msgs[i], at that frame's time."""
    frame.timestamp = msgs[i].timestamp
    return msgs[:i] + [frame] + msgs[i:]


def first(msgs, name: str, t_s: float) -> int:
    return next(i for i, m in enumerate(msgs)
                if m.arbitration_id == ID[name] and m.timestamp >= t_s)


def frame(name: str, data: bytes) -> can.Message:
    return can.Message(arbitration_id=ID[name], is_extended_id=False, dlc=len(data), data=data)


def altered(m: can.Message, name: str, change: dict, crc) -> bytes:
    """m's payload with signals changed (physical values), its counter kept, byte 7 set by
    crc(data) (the right CRC, or a wrong one)."""
    sig = DB.decode_message(ID[name], bytes(m.data), decode_choices=False)
    sig.update({k: sig[k] + v for k, v in change.items()})
    data = bytearray(nc.encode_frame(DB, name, sig).data)
    data[7] = crc(data)
    return bytes(data)


def gnss_epoch(msgs) -> int:
    """The index of the GNSS_Position opening the first epoch from T_GNSS_S; its velocity
    and height follow in the simulator's order, its GNSS_Status closes it (after a
    GNSS_Time when the epoch has one: status_of)."""
    i = first(msgs, "GNSS_Position", T_GNSS_S)
    assert [m.arbitration_id for m in msgs[i:i + 3]] == [
        ID[n] for n in ("GNSS_Position", "GNSS_Velocity", "GNSS_Height")]
    status_of(msgs, i)
    return i


def status_of(msgs, i: int) -> can.Message:
    """The GNSS_Status closing the epoch that msgs[i] opens (no other epoch's frame between)."""
    for m in msgs[i + 3:i + 5]:
        if m.arbitration_id == ID["GNSS_Status"]:
            return m
        assert m.arbitration_id == ID["GNSS_Time"], f"0x{m.arbitration_id:X} inside the epoch"
    raise AssertionError("no GNSS_Status closing the epoch")


def imu_sample(msgs) -> int:
    """The index of the IMU_Rate of the first sample from T_IMU_S; its IMU_Accel follows."""
    i = first(msgs, "IMU_Rate", T_IMU_S)
    assert msgs[i + 1].arbitration_id == ID["IMU_Accel"]
    return i


def velocity_crc(ok: bool):
    return lambda d: nc.e2e_crc(ID["GNSS_Velocity"], d) ^ (0 if ok else 0xA5)


def pair_crc(rate: can.Message, ok: bool):
    return lambda d: nc.imu_pair_crc(ID["IMU_Accel"], rate.data, d) ^ (0 if ok else 0xA5)


# (place, broken frame): (the index to insert at, the frame) from the clean frames
def _gnss_dlc7(msgs):
    i = gnss_epoch(msgs)
    return i + 2, frame("GNSS_Status", bytes(status_of(msgs, i).data[:7]))   # between velocity and height


def _gnss_bad_crc(msgs):
    i = gnss_epoch(msgs)                                               # before the real velocity
    return i + 1, frame("GNSS_Velocity", altered(msgs[i + 1], "GNSS_Velocity", {"VelEast": 5.0},
                                                 velocity_crc(False)))


def _imu_dlc7(msgs):
    i = imu_sample(msgs)
    return i + 1, frame("IMU_Accel", altered(msgs[i + 1], "IMU_Accel", {"VelIncX": 0.05},
                                             pair_crc(msgs[i], True))[:7])


def _imu_bad_crc(msgs):
    i = imu_sample(msgs)
    return i + 1, frame("IMU_Accel", altered(msgs[i + 1], "IMU_Accel", {"VelIncX": 0.05},
                                             pair_crc(msgs[i], False)))


BROKEN = {("gnss epoch", "7 bytes"): (_gnss_dlc7, "CntBadDlc"),
          ("gnss epoch", "bad CRC"): (_gnss_bad_crc, "CntBadCrc"),
          ("imu pair", "7 bytes"): (_imu_dlc7, "CntBadDlc"),
          ("imu pair", "bad CRC"): (_imu_bad_crc, "CntBadCrc")}


# the same places with a frame that passes every check: what a broken frame would do if it
# were taken
def _gnss_status_whole(msgs):
    i = gnss_epoch(msgs)
    return i + 2, frame("GNSS_Status", bytes(status_of(msgs, i).data))


def _gnss_velocity_good_crc(msgs):
    i = gnss_epoch(msgs)
    return i + 1, frame("GNSS_Velocity", altered(msgs[i + 1], "GNSS_Velocity", {"VelEast": 5.0},
                                                 velocity_crc(True)))


def _imu_good_crc(msgs):
    i = imu_sample(msgs)
    return i + 1, frame("IMU_Accel", altered(msgs[i + 1], "IMU_Accel", {"VelIncX": 0.05},
                                             pair_crc(msgs[i], True)))


TAKEN = {"GNSS_Status, 8 bytes, in the epoch": _gnss_status_whole,
         "GNSS_Velocity, right CRC, in the epoch": _gnss_velocity_good_crc,
         "IMU_Accel, right pair CRC, in the pair": _imu_good_crc}


@pytest.mark.parametrize("what", list(TAKEN))
def test_a_frame_taken_at_those_places_changes_the_outputs(clean, what):
    """The places and payloads below matter: the same frame with a right length and CRC
    changes the navigation outputs (so their byte identity below is not vacuous)."""
    msgs, args, outs, _, d = clean
    i, f = TAKEN[what](msgs)
    got, _ = navecu(with_frame(msgs, i, f), d, "taken", args)
    a, b = others(outs), others(got)
    print(f"{what} at {msgs[i].timestamp:.2f} s: {sum(x != y for x, y in zip(a, b))} of "
          f"{len(a)} output frames differ")
    assert a != b


@pytest.mark.parametrize("place,kind", list(BROKEN))
def test_broken_frame_refused_without_corrupting(clean, place, kind):
    """A 7-byte frame, or an 8-byte one with a wrong E2E CRC, on one of navecu's input
    identifiers, inside a GNSS epoch (between its frames) or between the two halves of an
    IMU sample: refused and counted (CntBadDlc or CntBadCrc, NAV_Status page 1, from the
    first output after it), REJECTED set for the documented second, and every other
    output byte for byte the clean run's: the epoch and the sample it landed in are used
    as if it had not been there."""
    msgs, args, outs, _, d = clean
    make, counter = BROKEN[(place, kind)]
    i, f = make(msgs)
    got, _ = navecu(with_frame(msgs, i, f), d, "broken", args)
    # the first output after the frame is the next IMU sample's
    t_after = next(m.timestamp for m in msgs[i:] if m.arbitration_id == ID["IMU_Accel"])
    t_reject = t_after - 1.0 / IMU_HZ          # the sample count at the refusal
    clean_flags = page0_flags(outs)
    assert all(not fl & REJECTED for t, fl in clean_flags if abs(t - t_after) < 2 * HOLD_S), \
        "the clean run flags REJECTED near the insertion: choose another place"

    assert others(got) == others(outs)

    st_clean, st_got = statuses(outs), statuses(got)
    assert [(t, s["StatusPage"]) for t, s, _ in st_got] == \
           [(t, s["StatusPage"]) for t, s, _ in st_clean]
    n_flagged = 0
    for (t, c, raw_c), (_, g, raw_g) in zip(st_clean, st_got):
        page = int(c["StatusPage"])
        if page == 0:
            extra = int(g["HealthFlags"]) ^ int(c["HealthFlags"])
            assert extra in (0, REJECTED), (t, c, g)
            if t_after <= t <= t_reject + HOLD_S - 1.0 / IMU_HZ:
                assert extra == REJECTED, (t, "REJECTED not set in the second after the frame")
                n_flagged += 1
            elif t > t_reject + HOLD_S + 1.0 / IMU_HZ or t < t_after:
                assert extra == 0, (t, "REJECTED outside the second after the frame")
            c, g = dict(c, HealthFlags=0), dict(g, HealthFlags=0)
        elif page == PAGE[counter]:
            assert g[counter] == c[counter] + (1 if t >= t_after else 0), (t, counter, c, g)
            g = dict(g, **{counter: c[counter]})
        else:
            assert raw_g == raw_c, (t, page, c, g)
        assert {k: v for k, v in g.items() if k != "NavCrc"} == \
               {k: v for k, v in c.items() if k != "NavCrc"}, (t, page)
    print(f"{kind} in the {place} at {msgs[i].timestamp:.2f} s: {counter} +1 from "
          f"{t_after:.2f} s, REJECTED on {n_flagged} page-0 frames, the rest identical")
    assert n_flagged >= int((HOLD_S - 2.0 / IMU_HZ) * STATUS_HZ)   # page 0 over the second


def test_foreign_traffic_changes_nothing_but_its_count(clean):
    """2,000 frames/s on identifiers navecu does not use (standard and extended, among them
    extended frames with navecu's own numbers; DLC 0..8, random data) interleaved with the
    clean log: every NAV output byte for byte the same, NAV_Status page 0 the same (no
    HealthFlags bit), and of page 1 only CntForeign differs: the number of foreign frames
    received before it, modulo 65536."""
    msgs, args, outs, _, d = clean
    rng = np.random.default_rng(2000)
    navecu_ids = set(ID.values())
    # the UDS request ID is navecu's too: its frames go to ISO-TP, never counted foreign
    from tools import gen_params
    uds_req = next(int(p["default"]) for p in gen_params.load() if p["name"] == "uds_request_id")
    free = np.array([i for i in range(0x800) if i not in navecu_ids and i != uds_req])
    n = int(T_END_S * FOREIGN_HZ)
    ts = (np.arange(n) + 0.5) / FOREIGN_HZ       # between the 10 ms IMU grid's instants
    extended = rng.random(n) < 0.3
    ids = np.where(extended, rng.integers(0, 1 << 29, n), rng.choice(free, n))
    own = np.flatnonzero(extended)[:len(navecu_ids)]
    ids[own] = sorted(navecu_ids)                # navecu's numbers, as extended frames
    dlc = rng.integers(0, 9, n)
    data = rng.integers(0, 256, (n, 8), dtype=np.uint8)
    foreign = [can.Message(timestamp=float(t), arbitration_id=int(i), is_extended_id=bool(x),
                           dlc=int(k), data=bytes(b[:k]))
               for t, i, x, k, b in zip(ts, ids, extended, dlc, data)]
    mixed = sorted(msgs + foreign, key=lambda m: m.timestamp)   # stable: the log's order kept
    got, err = navecu(mixed, d, "foreign", args)

    assert others(got) == others(outs)
    st_clean, st_got = statuses(outs), statuses(got)
    assert len(st_got) == len(st_clean)
    wrapped = pages = 0
    for (t, c, raw_c), (tg, g, raw_g) in zip(st_clean, st_got):
        assert tg == t
        if c["StatusPage"] != PAGE["CntForeign"]:
            assert raw_g == raw_c, (t, c, g)      # page 0: HealthFlags included
            continue
        before = bisect.bisect_left(ts, t)
        assert g["CntForeign"] == (c["CntForeign"] + before) % 65536, (t, before, c, g)
        wrapped += before >= 65536
        pages += 1
        assert {k: v for k, v in g.items() if k not in ("CntForeign", "NavCrc")} == \
               {k: v for k, v in c.items() if k not in ("CntForeign", "NavCrc")}, t
    print(f"{n} foreign frames ({extended.sum()} extended): outputs identical, CntForeign "
          f"= their count mod 65536 on {pages} page-1 frames, {wrapped} after "
          f"the wrap")
    assert wrapped > 0, "the count never passed 65536"
    assert f"foreign frames (not read, not refused): {n}\n" in err, err
