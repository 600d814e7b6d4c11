"""The DTC table (firmware/app/dtc.toml -> tools/gen_dtc.py -> firmware/app/gen/dtc_table.[ch]
and docs/can.md): the generated files are the table's, the DTC numbers encode as SAE J2012
/ ISO 14229-1 say, every HealthFlags bit of the DBC has exactly one DTC, and a broken table
is refused with its reason."""
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tools import gen_dtc, navecu_can

ROOT = Path(__file__).resolve().parents[2]


def test_generated_files_are_up_to_date():
    r = subprocess.run([sys.executable, "-m", "tools.gen_dtc", "--check"], cwd=ROOT,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


@pytest.mark.parametrize("code, ftb, number, text", [
    ("U1101", 0x87, 0xD10187, "U1101-87"),  # U = 3 -> bits 23..22 = 11, then 01 0001 0000 0001
    ("C1101", 0x96, 0x510196, "C1101-96"),  # C = 1 -> 01
    ("P0300", 0x00, 0x030000, "P0300-00"),  # the classic misfire code, P = 0
    ("B3FFF", 0xFF, 0xBFFFFF, "B3FFF-FF"),  # B = 2 -> 10, the largest digits
])
def test_dtc_number_encoding(code, ftb, number, text):
    assert gen_dtc.dtc_number(code, ftb) == number
    assert gen_dtc.dtc_text(number) == text


@pytest.mark.parametrize("code, ftb", [("U4101", 0), ("X1101", 0), ("U110", 0), ("U1101", 256),
                                       ("u1101", 0)])
def test_dtc_number_refuses(code, ftb):
    with pytest.raises(gen_dtc.TableError):
        gen_dtc.dtc_number(code, ftb)


def test_one_dtc_per_health_flag_in_the_generated_c():
    dtcs = gen_dtc.load()
    bits = navecu_can.health_bits(navecu_can.load_db())
    assert sorted(d["bit"] for d in dtcs) == sorted(bits)
    assert len(dtcs) <= gen_dtc.DTC_MAX
    c = (ROOT / gen_dtc.OUT_C).read_text()
    rows = re.findall(r"\[DTC_(\w+)\] = \{0x([0-9A-F]{6})u, NAVECU_HEALTH_(\w+), (\d+)u"
                      r"( \| DTC_DEBOUNCED)?( \| DTC_EVENTS)?\}", c)
    assert len(rows) == len(dtcs)
    for d, (name, num, flag, ds, debounced, events) in zip(dtcs, rows):
        assert name == d["name"].upper() and flag == d["flag"]
        assert int(num, 16) == gen_dtc.dtc_number(d["code"], int(d["ftb"]))
        assert int(ds) == round(float(d["confirm_s"]) * 10)  # 0.1 s units
        assert bool(debounced) == d.get("debounced", False)
        assert bool(events) == d.get("events", False)
    # the conditions a fault-free drive goes through are debounced: a start's waits (a
    # client found U1102-87 confirmed on the second start before), and a refusal now and
    # then (a review found one gated GNSS fix a drive confirming U1103-81 on the second)
    assert {d["flag"] for d in dtcs if d.get("debounced")} == {
        "NO_GNSS", "NO_HEADING", "REACQUIRE", "REJECTED", "ODO_REJECTED"}
    # the refusals' flags mark events held for a second: their conditions go on through
    # short passes (a review found a 1 Hz sender's refusals never confirming without it)
    assert {d["flag"] for d in dtcs if d.get("events")} == {"REJECTED", "ODO_REJECTED"}
    # the start's waits are tested only while the car moves, and the generated mask says so
    moving = {d["flag"] for d in dtcs if d.get("while_moving")}
    assert moving == {"NO_GNSS", "NO_HEADING", "REACQUIRE"}
    h = (ROOT / gen_dtc.OUT_H).read_text()
    mask = int(re.search(r"#define DTC_WHILE_MOVING_FLAGS 0x([0-9A-F]{4})u", h).group(1), 16)
    assert mask == sum(1 << d["bit"] for d in dtcs if d["flag"] in moving)
    doc = (ROOT / gen_dtc.DOC).read_text()
    for d in dtcs:
        assert f"| {d['index']} | {gen_dtc.dtc_text(d['number'])} |" in doc


BASE = """
[[dtc]]
name = "a"
flag = "IMU_STALE"
code = "U1101"
ftb = 0x87
ftb_name = "missing message"
confirm_s = 2.0
description = "x"
"""


@pytest.mark.parametrize("edit, why", [
    (lambda t: t.replace('flag = "IMU_STALE"', 'flag = "NOPE"'), "not in HealthFlagBits"),
    (lambda t: t + t.replace('name = "a"', 'name = "b"'), "has a DTC already"),
    (lambda t: t + t, "name used twice"),
    (lambda t: t.replace("confirm_s = 2.0", "confirm_s = -1.0"), "confirm_s outside"),
    (lambda t: t.replace("confirm_s = 2.0", "confirm_s = 2.05"), "whole number of 0.1 s"),
    (lambda t: t.replace("confirm_s = 2.0\n", ""), "needs confirm_s"),
    (lambda t: t.replace("confirm_s = 2.0", "confirm_s = 4000.0"), "confirm_s outside"),
    (lambda t: t.replace("confirm_s = 2.0", "confirm_s = 2.0\ndebounce = true"),
     "unknown key debounce"),
    (lambda t: t.replace("confirm_s = 2.0", "confirm_s = 2.0\ndebounced = 1"), "true or false"),
    (lambda t: t.replace("confirm_s = 2.0", "confirm_s = 2.0\nwhile_moving = \"yes\""),
     "while_moving must be true or false"),
    (lambda t: t.replace("confirm_s = 2.0", "confirm_s = 2.0\nevents = true"),
     "events needs debounced"),
    (lambda t: t.replace("confirm_s = 2.0", "confirm_s = 0.0\ndebounced = true"),
     "debounced needs a confirm_s"),
    (lambda t: t.replace('code = "U1101"', 'code = "Q1101"'), "a letter P/C/B/U"),
    (lambda t: t, "HealthFlagBits without a DTC: IMU_FAULT"),
])
def test_broken_tables_refused(tmp_path, edit, why):
    flags = {"IMU_STALE": (0, "stale"), "IMU_FAULT": (1, "fault")}
    p = tmp_path / "dtc.toml"
    p.write_text(edit(BASE))
    with pytest.raises(gen_dtc.TableError, match=why):
        gen_dtc.load(p, flags)


def test_more_than_the_nvm_record_refused(tmp_path):
    flags = {f"F{i}": (i, "") for i in range(17)}
    rows = "".join(BASE.replace('name = "a"', f'name = "d{i}"')
                   .replace('flag = "IMU_STALE"', f'flag = "F{i}"')
                   .replace('code = "U1101"', f'code = "U1{i:03X}"') for i in range(17))
    p = tmp_path / "dtc.toml"
    p.write_text(rows)
    with pytest.raises(gen_dtc.TableError, match="the NVM record holds 16"):
        gen_dtc.load(p, flags)
