"""A profile with a mistake is refused by tools/vehicle.py with a message that names it
(`python -m tools.vehicle check NAME`, docs/vehicles.md), not with a Python traceback, and
a misspelt or unknown key is refused rather than ignored (a misspelt `checksum` left the
car's checksum unchecked without a word)."""
import subprocess
import sys

import pytest

from tools import vehicle

GOOD = """name = "{name}"
ecu_bus = "pt"
[buses]
pt = "opendbc:vw_mqb.dbc"
[wheels]
message = "ESP_19"
signals = {{fl = "ESP_VL_Radgeschw_02", fr = "ESP_VR_Radgeschw_02", rl = "ESP_HL_Radgeschw_02", rr = "ESP_HR_Radgeschw_02"}}
unit = "km/h"
direction = "gear"
[gear]
message = "Getriebe_11"
signal = "GE_Fahrstufe"
forward = ["D"]
reverse = ["R"]
stopped = ["P", "N"]
[geometry]
track_m = 1.51
wheelbase_m = 2.637
[can_ids]
base = 0x6C0
"""

# (what is wrong, the change to GOOD, a word the message must hold)
CASES = [
    ("no [wheels] table", lambda s: s.replace("[wheels]", "[wheelz]"), "wheelz"),
    ("no wheel message", lambda s: s.replace('message = "ESP_19"\n', ""), "message"),
    ("three wheels", lambda s: s.replace(', rr = "ESP_HR_Radgeschw_02"', ""), "signals"),
    ("a track that is not a number", lambda s: s.replace("1.51", '"1.51"'), "track_m"),
    ("no wheelbase", lambda s: s.replace("wheelbase_m = 2.637\n", ""), "wheelbase_m"),
    ("a scale that is not a number", lambda s: s.replace('unit = "km/h"', 'unit = "km/h"\nscale = "x"'), "scale"),
    ("a base given as a string", lambda s: s.replace("base = 0x6C0", 'base = "0x6C0"'), "base"),
    ("a gear list given as a string", lambda s: s.replace('forward = ["D"]', 'forward = "D"'), "forward"),
    ("a misspelt checksum", lambda s: s.replace('direction = "gear"', 'direction = "gear"\nchksum = "toyota"'), "chksum"),
    ("a key the format does not have", lambda s: s.replace('direction = "gear"', 'direction = "gear"\ncounter = "COUNTER"'), "counter"),
    ("a unit the DBC contradicts", lambda s: s.replace('unit = "km/h"', 'unit = "m/s"'), "Unit_KiloMeterPerHour"),
    ("a recording without its channels", lambda s: s + '[[recordings]]\nfile = "data/comma2k19-rav4/car_bus.log"\n', "channels"),
]


@pytest.fixture
def profiles(tmp_path, monkeypatch):
    monkeypatch.setattr(vehicle, "VEHICLES", tmp_path)
    return tmp_path


def test_the_good_profile_loads(profiles):
    (profiles / "good.toml").write_text(GOOD.format(name="good"))
    assert vehicle.load("good").can_ids["IMU_Rate"] == 0x6C0


@pytest.mark.parametrize("what,change,word", CASES, ids=[c[0] for c in CASES])
def test_a_mistake_is_named(profiles, what, change, word):
    (profiles / "bad.toml").write_text(change(GOOD.format(name="bad")))
    with pytest.raises(vehicle.ProfileError) as e:
        vehicle.load("bad")
    assert word in str(e.value) and "bad.toml" in str(e.value), (what, str(e.value))


def test_check_says_it_without_a_traceback(tmp_path):
    """The command line: exit status 2 and one line, for a profile in vehicles/."""
    name = "zz_test_bad_profile"
    path = vehicle.VEHICLES / f"{name}.toml"
    path.write_text(GOOD.format(name=name).replace("[wheels]", "[wheelz]"))
    try:
        r = subprocess.run([sys.executable, "-m", "tools.vehicle", "check", name],
                           capture_output=True, text=True, cwd=vehicle.ROOT)
    finally:
        path.unlink()
    assert r.returncode == 2
    assert "Traceback" not in r.stderr and r.stderr.startswith("vehicle: "), r.stderr


def test_a_dbc_with_malformed_comments_loads():
    """Every Honda generator file of opendbc has `CM_ SG_ 304 "...";` (a signal comment
    without its signal), which made cantools refuse the whole DBC ("Invalid syntax at line
    211"): the comment is dropped, the messages load; a well-formed comment is kept."""
    db = vehicle.load_dbc("opendbc:generator/honda/honda_civic_touring_2016_can.dbc")
    assert db.get_message_by_name("WHEEL_SPEEDS").frame_id == 0x1D0
    assert vehicle.load_dbc("opendbc:hyundai_kia_generic.dbc").get_message_by_name("WHL_SPD11")
    text = 'CM_ SG_ 304 "no signal";\nCM_ 145 "no object";\nCM_ SG_ 304 GAS "kept";\n'
    assert vehicle.MALFORMED_COMMENT.sub("", text) == 'CM_ SG_ 304 GAS "kept";\n'


FORD = """name = "{name}"
ecu_bus = "pt"
[buses]
pt = "opendbc:ford_lincoln_base_pt.dbc"
[wheels]
message = "WheelSpeed"
signals = {{fl = "WhlFl_W_Meas", fr = "WhlFr_W_Meas", rl = "WhlRl_W_Meas", rr = "WhlRr_W_Meas"}}
{unit}
direction = "none"
[geometry]
track_m = 1.58
wheelbase_m = 2.71
"""


@pytest.mark.parametrize("unit", ['unit = "rad/s"', 'unit = "m/s"', 'unit = "km/h"'])
def test_an_angular_wheel_speed_asks_for_the_tyre_radius(profiles, unit):
    """Ford's WheelSpeed gives each wheel's angular speed (rad/s): without the tyre's
    rolling radius as `scale` the profile is refused with what to write."""
    (profiles / "ford.toml").write_text(FORD.format(name="ford", unit=unit))
    with pytest.raises(vehicle.ProfileError, match="rolling radius"):
        vehicle.load("ford")
    (profiles / "ford.toml").write_text(FORD.format(name="ford", unit='unit = "m/s"\nscale = 0.355'))
    assert vehicle.load("ford").speed_factor == 0.355
