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
