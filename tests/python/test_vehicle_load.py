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
    ("a key the format does not have", lambda s: s.replace('direction = "gear"', 'direction = "gear"\ncrc = "autosar"'), "crc"),
    ("a counter the message does not have", lambda s: s.replace('direction = "gear"', 'direction = "gear"\ncounter = "COUNTER"'), "COUNTER"),
    ("a counter that is a value read", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\ncounter = "GE_Fahrstufe"'), "value"),
    ("a counter wider than 8 bits", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\ncounter = "GE_MMom_Soll_02"'), "10 bits"),
    ("a counter modulus beyond its bits", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\ncounter = "COUNTER_DISABLED"\ncounter_modulus = 17'), "2..16"),
    ("a counter of parts, one twice", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\ncounter = ["COUNTER_DISABLED", "COUNTER_DISABLED"]'), "different"),
    ("a counter of parts wider than 8 bits", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\ncounter = ["COUNTER_DISABLED", "GE_Status_Kraftschluss", "GE_MMom_Status_02"]'), "10 bits"),
    ("a counter of parts, one on the checksum", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\nchecksum = "vw_mqb"\nchecksum_data_ids = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16]\ncounter = ["COUNTER_DISABLED", "CHECKSUM"]'), "overlaps"),
    ("a counter that is no name", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\ncounter = 3'), "a signal name or a list"),
    ("a counter modulus of 1", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\ncounter = "COUNTER_DISABLED"\ncounter_modulus = 1'), "counter_modulus"),
    ("a counter modulus without a counter", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\ncounter_modulus = 15'), "without a counter"),
    ("a counter on navecu's own WheelSpeeds", lambda s: s.replace('message = "ESP_19"', 'native = true\ncounter = "WheelCounter"').replace('direction = "gear"', 'direction = "signed"'), "E2E"),
    ("a unit the DBC contradicts", lambda s: s.replace('unit = "km/h"', 'unit = "m/s"'), "Unit_KiloMeterPerHour"),
    ("a track of 15.95 m", lambda s: s.replace("track_m = 1.51", "track_m = 15.95"), "track_m = 15.95 m is not a car's (between 0.5 and 3 m)"),
    ("a message on the UDS request ID", lambda s: s.replace("base = 0x6C0", "base = 0x6C0\nCMD_Control = 0x7A0"), "CMD_Control = 0x7A0 is the UDS request"),
    ("a hold value another list names", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\nhold = ["D"]'), "hold 'D'"),
    ("a hold value beyond the signal", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\nhold = [99]'), "hold 99"),
    ("a hold that is not a value", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\nhold = [true]'), "hold must be a list"),
    ("a placeholder wheel range", lambda s: s.replace('unit = "km/h"', 'unit = "km/h"\nrange = [0.0, 15.0]'), "refuses speeds above 15 km/h"),
    ("a wheel range without 0", lambda s: s.replace('unit = "km/h"', 'unit = "km/h"\nrange = [1.0, 300.0]'), "refuses a standing car"),
    ("a keyed checksum without its data IDs", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\nchecksum = "vw_mqb"'), "needs checksum_data_ids"),
    ("15 data IDs", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\nchecksum = "vw_mqb"\nchecksum_data_ids = [' + ', '.join(['1'] * 15) + ']'), "must be 16 bytes"),
    ("a data ID beyond a byte", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\nchecksum = "vw_mqb"\nchecksum_data_ids = [256' + ', 1' * 15 + ']'), "must be 16 bytes"),
    ("data IDs for an unkeyed checksum", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\nchecksum = "subaru"\nchecksum_data_ids = [' + ', '.join(['1'] * 16) + ']'), "not subaru"),
    ("data IDs on navecu's own WheelSpeeds", lambda s: s.replace('message = "ESP_19"', 'native = true\nchecksum_data_ids = [' + ', '.join(['1'] * 16) + ']').replace('direction = "gear"', 'direction = "signed"'), "E2E"),
    ("data IDs without a checksum", lambda s: s.replace('stopped = ["P", "N"]', 'stopped = ["P", "N"]\nchecksum_data_ids = [' + ', '.join(['1'] * 16) + ']'), "not none"),
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


# what opendbc's files have that cantools refuses (one of each; normalise_dbc)
ODD_DBC = """VERSION ""

BU_: XXX

BO_ 1275 2017_5: 8 XXX
 SG_ 0_COUNTER : 7|4@0+ (1,0) [0|15] "" XXX
 SG_ TORQUE : 15|13@0+ (.25,-500) [-500|1547.75] "Nm" XXX

BO_ 13274 LKAS_HUD_A: 5 XXX
 SG_ BEEP : 7|2@0+ (1,0) [0|3] "" XXX

CM_ "Front target"
CM_ SG_ 13274 BEEP "kept, as BO_ 13274 of 2017_5";
SIG_GROUP_ 13274 HUD 1 : BEEP;
VAL_ 1275 0_COUNTER 0 "zero" 1 "one as in 2017_5"
VAL_ 1275 GONE 0 "no such signal"
  1 "over two lines" ;
VAL_ 13274 BEEP 1 "once" 2 "twice" ;
VAL_ 1275 GONE_TOO 0 "the last line, no newline" ;"""


def test_opendbc_oddities_are_normalised_and_said():
    """Each oddity is made DBC and said once; what a frame decodes to is the file's: the
    scale .25 is 0.25, 0x33DA is a 29-bit identifier (opendbc's convention: above 0x7FF
    without the flag), the value names stay with their signals, a name beginning with a
    digit is prefixed with _."""
    text, notes = vehicle.normalise_dbc(ODD_DBC)
    assert len(notes) == 6, notes
    for word in ("comment", "extended", "closing", "GONE, GONE_TOO", "0.25", "2017_5"):
        assert any(word in n for n in notes), (word, notes)
    import cantools
    db = cantools.database.load_string(text, database_format="dbc", strict=False)
    m = db.get_message_by_name("_2017_5")
    assert m.frame_id == 1275 and not m.is_extended_frame
    assert m.get_signal_by_name("_0_COUNTER").choices[1] == "one as in 2017_5"  # a string
    # TORQUE: raw 0x0BB8 = 3000 in its 13 big-endian bits -> 3000 * 0.25 - 500 = 250 Nm
    raw = (3000 << 3).to_bytes(2, "big")
    assert m.decode(bytes([0x10]) + raw + bytes(5))["TORQUE"] == 250.0
    hud = db.get_message_by_name("LKAS_HUD_A")
    assert hud.is_extended_frame and hud.frame_id == 0x33DA
    assert hud.get_signal_by_name("BEEP").comment == "kept, as BO_ 13274 of 2017_5"
    assert hud.get_signal_by_name("BEEP").choices[2] == "twice"
    assert [g.name for g in hud.signal_groups] == ["HUD"]  # SIG_GROUP_ follows the flag


# well-formed DBC that a careless rewrite would change: a VAL_ over two lines, its ';' on a
# line of its own, an SG_ in column 0, and strings that look like names and identifiers
WELL_FORMED = """VERSION ""

BU_: XXX

BO_ 100 M: 8 XXX
SG_ S : 0|8@1+ (0.5,0) [0|127.5] "x.5" XXX
 SG_ T : 8|8@1+ (1,0) [0|255] "" XXX

CM_ SG_ 100 S "as BO_ 13274 and 2017_5 name it";
VAL_ 100 S 0 "zero"
 1 "one" ;
VAL_ 100 T 0 "zero" 1 "one"
;
"""


def test_well_formed_dbcs_are_left_as_they_are():
    """A file cantools already loads is not changed: every opendbc file that loaded before
    decodes the same after (compared signal by signal when this was written), and these."""
    for text in (vehicle.opendbc_text("vw_mqb.dbc"), WELL_FORMED):
        assert vehicle.normalise_dbc(text) == (text, [])
    import cantools
    db = cantools.database.load_string(WELL_FORMED, database_format="dbc", strict=False)
    assert db.get_message_by_name("M").get_signal_by_name("S").choices[1] == "one"


def test_every_dbc_of_the_pinned_opendbc_loads_but_one():
    """docs/vehicles.md: of the pinned opendbc's DBC files (generator files through its
    generator) only toyota_2017_ref_pt.dbc does not load: an identifier with bit 30 set
    (0x40140639), neither an 11-bit nor a 29-bit identifier."""
    import opendbc
    from pathlib import Path
    root = Path(opendbc.DBC_PATH)
    refs = [p.name for p in sorted(root.glob("*.dbc"))]
    refs += [str(p.relative_to(root)) for p in sorted((root / "generator").rglob("*.dbc"))
             if not p.name.startswith("_")]
    failed = []
    for ref in refs:
        try:
            vehicle.load_dbc("opendbc:" + ref)
        except vehicle.ProfileError:
            failed.append(ref)
    assert len(refs) > 80 and failed == ["toyota_2017_ref_pt.dbc"], failed


def test_an_extended_message_is_not_read(profiles):
    """navecu reads classic frames with 11-bit identifiers: a profile naming a 29-bit
    message is refused (it would be generated and never match a frame)."""
    (profiles / "ext.toml").write_text(GOOD.format(name="ext").replace(
        'message = "Getriebe_11"', 'message = "KN_Getriebe_01"').replace(
        'signal = "GE_Fahrstufe"', 'signal = "KN_Getriebe_ECUKnockOutTimer"'))
    with pytest.raises(vehicle.ProfileError, match="29-bit"):
        vehicle.load("ext")

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


def test_a_counter_is_the_dbc_signal_its_bits_and_the_generated_check(profiles):
    """`counter` names the message's rolling counter: its width is the DBC signal's length,
    its modulus 2^length unless `counter_modulus` says otherwise; the generated decoder
    checks it (vehicle_counter_step on the generated codec's field) after the checksum and
    before the ranges. A profile that names none has no counter code and includes no
    vehicle_counter.h (its image does not link vehicle_counter.c)."""
    gear = 'stopped = ["P", "N"]'
    (profiles / "plain.toml").write_text(GOOD.format(name="plain"))
    plain = vehicle.load("plain")
    assert all(r.counter is None for r in plain.reads)
    src = vehicle.vehicle_profile_c(plain)
    assert "vehicle_counter.h" not in src and "vehicle_counter_step" not in src
    assert "(void)c;" in src
    (profiles / "ctr.toml").write_text(GOOD.format(name="ctr").replace(
        gear, gear + '\ncounter = "COUNTER_DISABLED"'))
    r = next(r for r in vehicle.load("ctr").reads if r.role == "gear")
    assert (r.counter.name, r.counter.length, r.counter_modulus) == ("COUNTER_DISABLED", 4, 16)
    src = vehicle.vehicle_profile_c(vehicle.load("ctr"))
    assert '#include "vehicle_counter.h"' in src and "(void)c;" not in src
    check = "vehicle_counter_step(c, VEHICLE_MSG_GEAR, s.counter_disabled, 16u) <= 0"
    assert src.count(check) == 1
    case = src[src.index("case VEH_CAN_GETRIEBE_11_FRAME_ID"):]
    assert case.index("_unpack(") < case.index(check) < case.index("_is_in_range(")
    (profiles / "ctr15.toml").write_text(GOOD.format(name="ctr15").replace(
        gear, gear + '\ncounter = "COUNTER_DISABLED"\ncounter_modulus = 15'))
    assert "s.counter_disabled, 15u)" in vehicle.vehicle_profile_c(vehicle.load("ctr15"))


def test_the_car_encoder_counts_and_can_be_told_a_counter(profiles):
    """CarEncoder (the tests' and the simulator's car) sends a named counter +1 per frame of
    its message from 0, wrapping at the modulus; `counter=` sends a given value and counts
    on from it; a counter in the values is overridden."""
    (profiles / "ctr.toml").write_text(GOOD.format(name="ctr").replace(
        'stopped = ["P", "N"]', 'stopped = ["P", "N"]\ncounter = "COUNTER_DISABLED"\n'
        'counter_modulus = 15'))
    p = vehicle.load("ctr")
    car = vehicle.CarEncoder(p)
    r = next(r for r in p.reads if r.role == "gear")
    got = [r.message.decode(bytes(car.message("gear", {"COUNTER_DISABLED": 9}).data))
           ["COUNTER_DISABLED"] for _ in range(17)]
    assert got == list(range(15)) + [0, 1]
    assert r.message.decode(bytes(car.message("gear", {}, counter=7).data))["COUNTER_DISABLED"] == 7
    assert r.message.decode(bytes(car.message("gear", {}).data))["COUNTER_DISABLED"] == 8


def test_a_counter_on_the_checksum_is_refused(profiles):
    """A counter named on the checksum's bits (Subaru's CHECKSUM, byte 0) would refuse a
    good frame whenever the checksum repeats (1 in 256): refused, naming the checksum; the
    real COUNTER loads."""
    text = (vehicle.ROOT / "vehicles" / "subaru_global_2017.toml").read_text()
    (profiles / "sub.toml").write_text(text.replace('name = "subaru_global_2017"', 'name = "sub"'))
    assert vehicle.load("sub").reads[0].counter.name == "COUNTER"
    bad = text.replace('counter = "COUNTER"         # 4 bits', 'counter = "CHECKSUM"  # 4 bits', 1)
    assert bad != text
    (profiles / "sub.toml").write_text(bad.replace('name = "subaru_global_2017"', 'name = "sub"'))
    with pytest.raises(vehicle.ProfileError, match="counter CHECKSUM overlaps the subaru"):
        vehicle.load("sub")


def _opendbc_vw_mqb():
    """opendbc's own Volkswagen MQB checksum module (car/volkswagen/mqbcan.py), loaded
    without its package's __init__, which needs openpilot's message schema (pycapnp) for
    the rest of opendbc.car; the module itself needs only car/crc.py."""
    import os
    import types
    import opendbc
    car = os.path.join(os.path.dirname(opendbc.__file__), "car")
    saved = {k: sys.modules.get(k) for k in ("opendbc.car", "opendbc.car.volkswagen",
                                             "opendbc.car.crc",
                                             "opendbc.car.volkswagen.mqbcan")}
    try:
        for name, path in (("opendbc.car", car),
                           ("opendbc.car.volkswagen", os.path.join(car, "volkswagen"))):
            if name not in sys.modules:
                pkg = types.ModuleType(name)
                pkg.__path__ = [path]
                sys.modules[name] = pkg
        import importlib
        return importlib.import_module("opendbc.car.volkswagen.mqbcan")
    finally:
        for k, v in saved.items():
            if v is None:
                sys.modules.pop(k, None)
            else:
                sys.modules[k] = v


def test_the_vw_checksum_is_opendbcs():
    """vehicles/vw_mqb.toml's data IDs are opendbc's for Getriebe_11 (0x0AD), and the test
    encoder's CRC (tools/vehicle.py, which the firmware's is tested against in
    test_vehicle_profiles) is opendbc's volkswagen_mqb_meb_checksum on 2,000 random frames,
    every counter value."""
    import numpy as np
    vw = _opendbc_vw_mqb()
    r = next(x for x in vehicle.load("vw_mqb").reads if x.role == "gear")
    assert r.checksum == "vw_mqb" and r.message.frame_id == 0x0AD
    assert list(r.checksum_data_ids) == vw.VOLKSWAGEN_MQB_MEB_CONSTANTS[0x0AD]
    rng = np.random.default_rng(3)
    fill = vehicle.CAR_CHECKSUMS["vw_mqb"].fill
    for _ in range(2000):
        data = bytearray(rng.integers(0, 256, 8, dtype=np.uint8).tobytes())
        fill(0x0AD, data, r.checksum_data_ids)
        assert data[0] == vw.volkswagen_mqb_meb_checksum(0x0AD, None, data), data.hex()


def _opendbc_hkg_checksum():
    """opendbc's own Hyundai/Kia checksum of its safety tests (safety/tests/test_hyundai.py,
    the function `checksum`, which fills WHL_SPD11's): taken out of the file by its syntax
    tree and run alone, the module itself needing opendbc's compiled safety library."""
    import ast
    import os
    import opendbc
    path = os.path.join(os.path.dirname(opendbc.__file__), "safety", "tests", "test_hyundai.py")
    with open(path) as f:
        tree = ast.parse(f.read())
    fn = next(n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "checksum")
    scope = {}
    exec(compile(ast.Module(body=[fn], type_ignores=[]), path, "exec"), scope)
    return scope["checksum"]


def test_a_checksum_for_one_frame_length_refuses_another():
    """Hyundai/Kia's WHL_SPD11 checksum is defined on 8 bytes: named on a message of
    another length, the profile is refused, saying so."""
    import types
    with pytest.raises(vehicle.ProfileError, match="8-byte frames; M has 4"):
        vehicle._checksum({"checksum": "hkg_whl_spd"}, "p.toml [gear]",
                          types.SimpleNamespace(length=4, name="M"))
    assert vehicle._checksum({"checksum": "hkg_whl_spd"}, "p.toml [wheels]",
                             types.SimpleNamespace(length=8, name="M")) == "hkg_whl_spd"


def _hyundai_text(name: str) -> str:
    text = (vehicle.ROOT / "vehicles" / "hyundai_sonata_2020.toml").read_text()
    return text.replace('name = "hyundai_sonata_2020"', f'name = "{name}"')


HKG_COUNTER = 'counter = ["WHL_SPD_AliveCounter_MSB", "WHL_SPD_AliveCounter_LSB"]'


def test_a_counter_of_parts_is_joined_most_significant_first(profiles):
    """Hyundai/Kia's counter of two 2-bit signals: the generated decoder joins them MSB
    first (byte 3's top bits above byte 1's), and with counter_modulus 15 a joined 15 is
    refused: the order matters once the modulus is not the full 2^4 (test_vehicle_profiles'
    counter tests, with the full 16, cannot see a swap). Listed the other way round the
    generated expression swaps too."""
    (profiles / "hkg15.toml").write_text(_hyundai_text("hkg15").replace(
        HKG_COUNTER, HKG_COUNTER + "\ncounter_modulus = 15"))
    src = vehicle.vehicle_profile_c(vehicle.load("hkg15"))
    assert ("(uint8_t)(((uint32_t)s.whl_spd_alive_counter_msb << 2u) | "
            "(uint32_t)s.whl_spd_alive_counter_lsb), 15u)") in src
    r = vehicle.load("hkg15").reads[0]
    assert r.counter.values(14) == {"WHL_SPD_AliveCounter_MSB": 3, "WHL_SPD_AliveCounter_LSB": 2}
    (profiles / "hkgrev.toml").write_text(_hyundai_text("hkgrev").replace(
        HKG_COUNTER, 'counter = ["WHL_SPD_AliveCounter_LSB", "WHL_SPD_AliveCounter_MSB"]'))
    assert ("(uint8_t)(((uint32_t)s.whl_spd_alive_counter_lsb << 2u) | "
            "(uint32_t)s.whl_spd_alive_counter_msb), 16u)") in vehicle.vehicle_profile_c(
                vehicle.load("hkgrev"))


@pytest.mark.parametrize("what,change,word", [
    ("without its counter", lambda s: s.replace(HKG_COUNTER + "\n", ""),
     "name WHL_SPD11's rolling counter"),
    ("with half its counter", lambda s: s.replace(HKG_COUNTER, 'counter = "WHL_SPD_AliveCounter_MSB"'),
     "name WHL_SPD11's rolling counter"),
    ("on another 8-byte message", lambda s: s.replace('signal = "CF_Lvr_Gear"', 'signal = "CF_Lvr_Gear"\nchecksum = "hkg_whl_spd"'),
     "LVR12 has no signal of its own"),
])
def test_the_hyundai_kia_checksum_needs_its_layout(profiles, what, change, word):
    """hkg_whl_spd is WHL_SPD11's layout: named on a message without signals on its fields,
    or without the counter on the bits it does not cover, the profile is refused."""
    (profiles / "hkgbad.toml").write_text(change(_hyundai_text("hkgbad")))
    with pytest.raises(vehicle.ProfileError, match=word):
        vehicle.load("hkgbad")


def test_the_hyundai_kia_checksum_is_opendbcs():
    """The test encoder's Hyundai/Kia WHL_SPD11 checksum (tools/vehicle.py, which the
    firmware's is tested against in test_vehicle_profiles) is opendbc's on 2,000 random
    frames (its function ORs the checksum into cleared fields), and the profile's counter
    is the one opendbc's safety code reads: (byte 3 >> 6) << 2 | byte 1 >> 6."""
    import numpy as np
    ref = _opendbc_hkg_checksum()
    fill = vehicle.CAR_CHECKSUMS["hkg_whl_spd"].fill
    r = vehicle.load("hyundai_sonata_2020").reads[0]
    assert (r.role, r.message.frame_id, r.checksum) == ("wheels", 0x386, "hkg_whl_spd")
    rng = np.random.default_rng(5)
    for _ in range(2000):
        data = bytearray(rng.integers(0, 256, 8, dtype=np.uint8).tobytes())
        data[5] &= 0x3F
        data[7] &= 0x3F
        _, want, _ = ref((0x386, bytes(data), 0))
        fill(0x386, data)
        assert bytes(data) == bytes(want), data.hex()
        value = int(rng.integers(0, 16))
        raw = r.message.decode(r.message.encode({**{x.name: 0 for x in r.message.signals},
                                                 **r.counter.values(value)},
                                                scaling=False), scaling=False)
        frame = r.message.encode(raw, scaling=False)
        assert ((frame[3] >> 6) << 2) | (frame[1] >> 6) == value


# ------------------------------------------- wheel speeds in two messages, one per axle
def _split_text(name: str) -> str:
    text = (vehicle.ROOT / "vehicles" / "nissan_x_trail_2017.toml").read_text()
    return text.replace('name = "nissan_x_trail_2017"', f'name = "{name}"')


MESSAGES = 'messages = {front = "WHEEL_SPEEDS_FRONT", rear = "WHEEL_SPEEDS_REAR"}'
# (what is wrong, the change to the Nissan profile, a word the message must hold)
SPLIT_CASES = [
    ("message and messages both", lambda s: s.replace(MESSAGES, MESSAGES + '\nmessage = "WHEEL_SPEEDS_FRONT"'), "not both"),
    ("neither message nor messages", lambda s: s.replace(MESSAGES + "\n", ""), "neither"),
    ("messages not a table", lambda s: s.replace(MESSAGES, 'messages = "WHEEL_SPEEDS_FRONT"'), "messages must be a table"),
    ("no rear axle", lambda s: s.replace(', rear = "WHEEL_SPEEDS_REAR"', ""), "front = ..., rear = ..."),
    ("an axle the format does not have", lambda s: s.replace("rear =", "middle = "), "front = ..., rear = ..."),
    ("an axle's message not a string", lambda s: s.replace('rear = "WHEEL_SPEEDS_REAR"', "rear = 645"), "front = ..., rear = ..."),
    ("an axle's message not in the DBC", lambda s: s.replace('"WHEEL_SPEEDS_REAR"}', '"WHEEL_SPEEDS_BACK"}'), "no message WHEEL_SPEEDS_BACK"),
    ("a front wheel's signal in the rear message", lambda s: s.replace('fl = "WHEEL_SPEED_FL"', 'fl = "WHEEL_SPEED_RL"'), "WHEEL_SPEEDS_FRONT has no signal WHEEL_SPEED_RL"),
    ("a rear wheel's signal in the front message", lambda s: s.replace('rr = "WHEEL_SPEED_RR"', 'rr = "WHEEL_SPEED_FR"'), "WHEEL_SPEEDS_REAR has no signal WHEEL_SPEED_FR"),
    ("one message for both axles", lambda s: s.replace('rear = "WHEEL_SPEEDS_REAR"', 'rear = "WHEEL_SPEEDS_FRONT"'), "both axles"),
    ("a counter neither message has", lambda s: s.replace('direction = "gear"', 'direction = "gear"\ncounter = "COUNTER"'), "no signal COUNTER"),
    ("a keyed checksum on both axles", lambda s: s.replace('direction = "gear"', 'direction = "gear"\nchecksum = "vw_mqb"'), "split over two messages is not supported"),
    ("navecu's own WheelSpeeds with messages", lambda s: s.replace('direction = "gear"', 'native = true').replace('unit = "kph"\n', ""), "messages"),
]


@pytest.mark.parametrize("what,change,word", SPLIT_CASES, ids=[c[0] for c in SPLIT_CASES])
def test_a_split_mistake_is_named(profiles, what, change, word):
    """`[wheels] messages = {front, rear}` instead of `message`: exactly one of the two, the
    two axles and no other, each a string naming a message of the DBC, each axle's signals
    in its own message, two different messages; each refusal names what is wrong."""
    text = change(_split_text("bad"))
    assert text != _split_text("bad"), what
    (profiles / "bad.toml").write_text(text)
    with pytest.raises(vehicle.ProfileError) as e:
        vehicle.load("bad")
    assert word in str(e.value), str(e.value)


def test_one_message_per_axle_loads_as_two_signal_sets(profiles):
    """The Nissan profile: two signal sets, the front axle's (FL, FR of WHEEL_SPEEDS_FRONT)
    and the rear's (RL, RR of WHEEL_SPEEDS_REAR), in that order, then the gear; the
    generated layer includes vehicle_pair.h, refuses to build without VEHICLE_SPLIT_WHEELS,
    defines vehicle_reset and hands each half to vehicle_pair_half after its checks."""
    (profiles / "nis.toml").write_text(_split_text("nis"))
    p = vehicle.load("nis")
    assert p.split_wheels
    assert [(r.role, r.message.name, [s.name for s in r.signals]) for r in p.wheel_reads()] == [
        ("wheels_front", "WHEEL_SPEEDS_FRONT", ["WHEEL_SPEED_FL", "WHEEL_SPEED_FR"]),
        ("wheels_rear", "WHEEL_SPEEDS_REAR", ["WHEEL_SPEED_RL", "WHEEL_SPEED_RR"])]
    assert [r.role for r in p.reads] == ["wheels_front", "wheels_rear", "gear"]
    assert p.wheel_step_mps == pytest.approx(0.005 / 3.6)
    src = vehicle.vehicle_profile_c(p)
    assert '#include "vehicle_pair.h"' in src and "#if !VEHICLE_SPLIT_WHEELS" in src
    assert "void vehicle_reset(void)" in src and "vehicle_counter.h" not in src
    for frame, axle in (("WHEEL_SPEEDS_FRONT", "FRONT"), ("WHEEL_SPEEDS_REAR", "REAR")):
        case = src[src.index(f"case VEH_CAN_{frame}_FRAME_ID"):]
        case = case[:case.index("    case ", 10)]
        assert case.index("_LENGTH") < case.index("_is_in_range(") < \
            case.index(f"vehicle_pair_half(&wheel_pair, VEHICLE_AXLE_{axle},")
        assert "return VEHICLE_WHEELS_HELD;" in case
    # a profile of one wheel message has none of it
    (profiles / "one.toml").write_text(GOOD.format(name="one"))
    one = vehicle.load("one")
    src = vehicle.vehicle_profile_c(one)
    assert not one.split_wheels and "vehicle_pair" not in src and "vehicle_reset" not in src


def test_each_axles_message_has_its_checksum_and_counter(profiles):
    """checksum and counter name each axle's message's own: both checked, each with its own
    sequence (the front's in the caller's vehicle_counters_t, the rear's in the generated
    layer's own state, cleared by vehicle_reset), in the order DLC, checksum, counter,
    ranges, and only then the half is paired. (A synthetic profile on Subaru's DBC: its
    Wheel_Speeds as the front axle, Brake_Pressure_L_R as the rear, both with CHECKSUM and
    COUNTER.)"""
    text = (vehicle.ROOT / "vehicles" / "subaru_global_2017.toml").read_text()
    text = text.replace('name = "subaru_global_2017"', 'name = "sub2"').replace(
        'message = "Wheel_Speeds"',
        'messages = {front = "Wheel_Speeds", rear = "Brake_Pressure_L_R"}').replace(
        'rl = "RL", rr = "RR"', 'rl = "Brake_1", rr = "Brake_2"')
    (profiles / "sub2.toml").write_text(text)
    p = vehicle.load("sub2")
    assert [(r.role, r.checksum, r.counter.name, r.counter_modulus) for r in p.wheel_reads()] == [
        ("wheels_front", "subaru", "COUNTER", 16), ("wheels_rear", "subaru", "COUNTER", 16)]
    src = vehicle.vehicle_profile_c(p)
    assert "static vehicle_counters_t rear_counters;" in src
    reset = src[src.index("void vehicle_reset(void)"):]
    assert "rear_counters.last[(unsigned)VEHICLE_MSG_WHEELS - 1u] = 0u;" in reset[:reset.index("}")]
    for frame, counters, axle in (("WHEEL_SPEEDS", "c", "FRONT"),
                                  ("BRAKE_PRESSURE_L_R", "&rear_counters", "REAR")):
        case = src[src.index(f"case VEH_CAN_{frame}_FRAME_ID"):]
        case = case[:case.index("    case ", 10)]
        steps = ["_LENGTH", "vehicle_checksum_subaru(",
                 f"vehicle_counter_step({counters}, VEHICLE_MSG_WHEELS, s.counter, 16u)",
                 "_is_in_range(", f"vehicle_pair_half(&wheel_pair, VEHICLE_AXLE_{axle},"]
        at = [case.index(x) for x in steps]
        assert at == sorted(at), (frame, at)


def _wheel_sig(length, scale, lo, hi, signed=False, offset=0.0):
    from types import SimpleNamespace
    return SimpleNamespace(name="FL", length=length, scale=scale, offset=offset,
                           is_signed=signed, minimum=lo, maximum=hi, unit="km/h")


@pytest.mark.parametrize("sig,signed,refused", [
    (_wheel_sig(16, 0.01, 0.0, 655.35), False, None),             # the span its bits hold
    (_wheel_sig(12, 0.035, 0.0, 143.325), False, None),            # the span, rounded in float
    (_wheel_sig(16, 0.01, 0.0, 15.0), False, "above 15 km/h"),     # mazda_2017's RL
    (_wheel_sig(16, 0.01, 1.0, 655.35), False, "a standing car"),
    (_wheel_sig(16, 0.01, 0.0, 300.0, signed=True), True, "reversing"),   # signed, no negatives
    (_wheel_sig(16, 0.01, -50.0, 300.0, signed=True), True, None),
    (_wheel_sig(8, 0.5, 0.0, 100.0), False, "above 100 km/h"),    # its bits hold 127.5
    (_wheel_sig(8, 0.5, 0.0, 127.5), False, None),                 # all its bits hold
])
def test_a_wheel_range_that_refuses_a_car_is_named(sig, signed, refused):
    """_check_wheel_range: a wheel speed's range must take 0, 150 km/h and (signed speeds)
    reversing at 18 km/h wherever its bits can hold them; the full span always passes."""
    if refused is None:
        vehicle._check_wheel_range([sig], 1 / 3.6, signed, "w")
    else:
        with pytest.raises(vehicle.ProfileError, match=refused):
            vehicle._check_wheel_range([sig], 1 / 3.6, signed, "w")


def test_a_profile_loads_alike_after_another_was_selected():
    """A profile's identifiers come from navecu.dbc as it is, not from the protocol another
    profile made the tools speak (navecu_can.select_vehicle): with the Ford's selected (its
    block from 0x106 puts NAV_Heartbeat on 0x124), the RAV4's GNSS_Height moved to 0x124
    collided with it and the RAV4 was refused (found by tools/comma2k19/recar.py, which
    reads the RAV4's recording while it speaks to another profile)."""
    from tools import navecu_can
    fresh = {n: vehicle.load(n).can_ids for n in ("toyota_rav4_2017", "vw_mqb")}
    try:
        navecu_can.select_vehicle("ford_escape_2020")
        for n, ids in fresh.items():
            assert vehicle.load(n).can_ids == ids
    finally:
        navecu_can.select_vehicle(None)
