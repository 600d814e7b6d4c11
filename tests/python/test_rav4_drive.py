"""The real 2017 RAV4 bus through the RAV4 build (make drive, tools/comma2k19/run.py): every
wheel-speed, gear and yaw-rate frame of the car in the run's window is read and passes the
car's checks; every other car frame is counted foreign, and only that; the outputs equal a
run with only the frames the profile reads (NAV_Status page 1, which carries CntForeign,
aside); the car's traffic raises no HealthFlags bit."""
import json
import os
from pathlib import Path

import pytest

from tools.comma2k19 import run

ROOT = Path(__file__).resolve().parents[2]
NAVECU = Path(os.environ.get("NAVECU_RAV4_BIN", ROOT / "build/host/navecu-toyota_rav4_2017"))


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    if not NAVECU.exists():
        pytest.fail(f"{NAVECU} missing: make VEHICLE=toyota_rav4_2017 (make test builds it)")
    out = tmp_path_factory.mktemp("rav4")
    rc = run.main(["--outage", "none", "--out", str(out), "--navecu", str(NAVECU)])
    rep = json.loads((out / "report.json").read_text())
    return rc, rep


def test_every_car_message_of_the_profile_is_read(drive):
    _, rep = drive
    sent = rep["car_bus"]["profile_messages"]
    read = rep["runs"]["bus"]["car_messages_read"]
    assert read == {"wheel_speeds": sent["WHEEL_SPEEDS"], "gear": sent["GEAR_PACKET"],
                    "yaw_rate": sent["KINEMATICS"]}
    assert read["wheel_speeds"] > 4900   # 82.9 Hz over the 60 s


def test_the_rest_of_the_bus_is_foreign_and_only_that(drive):
    _, rep = drive
    bus = rep["runs"]["bus"]
    foreign = rep["car_bus"]["frames"] - sum(rep["car_bus"]["profile_messages"].values())
    assert bus["foreign_frames"] == foreign
    assert rep["runs"]["quiet"]["foreign_frames"] == 0
    assert "bad dlc 0, bad crc 0, bad counter 0" in bus["rejected"]
    assert "bad value 0" in bus["rejected"]
    # fused without refusals: the fixes' missing accuracy and vertical velocity declared
    # (GNSS_OPTIONS), only the two fixes valid before the first IMU sample refused
    assert "gnss 2," in bus["rejected"]


def test_car_traffic_changes_no_output_and_raises_no_flag(drive):
    rc, rep = drive
    assert rep["bus_outputs_equal_quiet_outputs"] is True
    assert rep["health_flags_raised_by_car_traffic"] == []
    assert rc == 0


def test_navigates_with_gnss_time(drive):
    _, rep = drive
    bus = rep["runs"]["bus"]
    assert bus["navigating"] and bus["nav_time"]["gps_weeks"] == [2012]
