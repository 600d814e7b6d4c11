"""The collision check of navecu's identifiers against a car's DBCs and recorded buses
(tools/vehicle.py, docs/vehicles.md): the RAV4's radar bus carries 0x123, navecu's stock
GNSS_Height, a frame its DBC does not name; the RAV4 profile moves it and collides with
nothing; a profile that collides is not generated (so not built)."""
import subprocess
import sys

import pytest

from tools import vehicle

ROOT = vehicle.ROOT


@pytest.fixture(scope="module")
def rav4():
    return vehicle.load("toyota_rav4_2017")


def test_stock_ids_collide_on_the_rav4_radar_bus(rav4):
    found = vehicle.collisions(rav4, vehicle.stock_ids())
    assert [(c.can_id, c.navecu, c.bus) for c in found] == [(0x123, "GNSS_Height", "radar")]
    c = found[0]
    # only the recording shows it (opendbc's toyota_adas.dbc has no 0x123): 600 frames in
    # the minute's two radar channels' worth of time, about 10 Hz
    assert c.what == "not in the DBC" and c.source == "car_bus.log"
    assert c.frames == 600 and c.rate_hz == pytest.approx(10.0, abs=0.2)


def test_rav4_profile_collides_with_nothing(rav4):
    assert rav4.can_ids["GNSS_Height"] == 0x124
    assert vehicle.collisions(rav4) == []


def test_vw_stock_ids_collide_in_its_dbc():
    vw = vehicle.load("vw_mqb")
    found = {(c.can_id, c.what) for c in vehicle.collisions(vw, vehicle.stock_ids())}
    assert (0x101, "ESP_02") in found
    assert vehicle.collisions(vw) == []


def test_check_cli_lists_the_collision():
    res = subprocess.run([sys.executable, "-m", "tools.vehicle", "check", "toyota_rav4_2017",
                          "--ids", "stock"], cwd=ROOT, capture_output=True, text=True)
    assert res.returncode == 1
    assert "0x123 GNSS_Height: radar bus, not in the DBC (car_bus.log, 600 frames" in res.stderr


def test_a_colliding_profile_is_not_generated(tmp_path, monkeypatch):
    text = (vehicle.VEHICLES / "toyota_rav4_2017.toml").read_text()
    assert "GNSS_Height = 0x124" in text
    bad = text.replace('name = "toyota_rav4_2017"', 'name = "rav4_bad"').replace(
        "GNSS_Height = 0x124", "GNSS_Height = 0x123")
    (tmp_path / "rav4_bad.toml").write_text(bad)
    monkeypatch.setattr(vehicle, "VEHICLES", tmp_path)
    out = tmp_path / "gen"
    assert vehicle.main(["generate", "rav4_bad", str(out)]) == 1
    assert not out.exists()


NATIVE = ('name = "bad"\n[wheels]\nnative = true\n[geometry]\ntrack_m = 1.6\n'
          'wheelbase_m = 2.7\n')


@pytest.mark.parametrize("text, what", [
    # each raised a Python traceback (UnicodeDecodeError; python-can's ValueError)
    (NATIVE.encode() + b"# \xff\n", "bad.toml: not TOML"),
    (NATIVE + '[[recordings]]\nfile = "vehicles/native.toml"\nchannels = {can0 = "pt"}\n',
     "native.toml: not a CAN log it can read"),
    (NATIVE + '[[recordings]]\nfile = "tools/requirements.txt"\nchannels = {can0 = "pt"}\n',
     "requirements.txt: not a CAN log it can read"),
])
def test_a_profile_that_cannot_be_read_is_refused_in_one_line(tmp_path, monkeypatch, capsys,
                                                               text, what):
    p = tmp_path / "bad.toml"
    p.write_bytes(text if isinstance(text, bytes) else text.encode())
    monkeypatch.setattr(vehicle, "VEHICLES", tmp_path)
    assert vehicle.main(["check", "bad"]) == 2
    err = capsys.readouterr().err
    assert what in err and "Traceback" not in err


def test_a_recordings_malformed_lines_are_counted(tmp_path, monkeypatch, capsys):
    """A recording with a line python-can cannot read stopped the check with a traceback;
    now the line is skipped and counted (the firmware's rule, navecu_can.LogFile)."""
    rec = tmp_path / "rec.log"
    rec.write_text("(1.0) can0 0AA#0011223344556677\n(1.1) can0 GARBAGE\n"
                   "(1.2) can0 0AA#0011223344556677\n")
    (tmp_path / "bad.toml").write_text(
        NATIVE + f'[[recordings]]\nfile = "{rec}"\nchannels = {{can0 = "pt"}}\n')
    monkeypatch.setattr(vehicle, "VEHICLES", tmp_path)
    assert vehicle.main(["check", "bad"]) == 0
    assert (f"vehicle: 1 malformed line of {rec} skipped (first: line 2, "
            "'(1.1) can0 GARBAGE')") in capsys.readouterr().err
