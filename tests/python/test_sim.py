"""The simulator end to end: scenario -> sensors -> CAN log -> build/host/navecu -> report.

The proof that truth, encoding and mechanization agree: with the perfect IMU preset (no
sensor errors; only the CAN encoding's quantisation, carried) the firmware's free-inertial
solution over the whole default drive stays within 5 m of the truth.
"""
import json
import os
from pathlib import Path

import can
import pytest

from tools import navecu_can as nc
from tools.sim import run, trajectory

ROOT = Path(__file__).resolve().parents[2]
NAVECU = os.environ.get("NAVECU_BIN", str(ROOT / "build" / "host" / "navecu"))


@pytest.fixture(scope="module")
def perfect_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("sim")
    rc = run.main(["--scenario", "default", "--imu", "perfect", "--gnss", "perfect",
                   "--out", str(out), "--navecu", NAVECU])
    assert rc == 0
    return out


def test_perfect_imu_within_5m(perfect_run):
    rep = json.loads((perfect_run / "report.json").read_text())
    print(f"perfect IMU, {rep['duration_s'] / 60:.1f} min, {rep['distance_m'] / 1000:.1f} km: "
          f"max horizontal error {rep['horizontal_error_m']['max']:.2f} m")
    assert rep["duration_s"] >= 20 * 60
    assert rep["navigating"]
    assert rep["horizontal_error_m"]["max"] < 5.0


def test_report_fields_and_plots(perfect_run):
    rep = json.loads((perfect_run / "report.json").read_text())
    for key in ("duration_s", "distance_m", "horizontal_error_m", "heading_error_deg",
                "final_error_pct_of_distance", "outages"):
        assert key in rep
    assert set(rep["horizontal_error_m"]) == {"rms", "p95", "max", "final"}
    assert set(rep["heading_error_deg"]) == {"rms", "max"}
    assert len(rep["outages"]) >= 2
    for o in rep["outages"]:
        assert {"start_s", "end_s", "distance_m", "max_error_m", "end_error_m"} <= set(o)
    for png in ("track.png", "horizontal_error.png", "heading_error.png"):
        assert (perfect_run / png).stat().st_size > 10_000


def test_no_gnss_frames_in_outages(perfect_run):
    """Outage segments of the scenario have no GNSS frame in the CAN log."""
    truth = trajectory.generate(trajectory.load_scenario(run.scenario_path("default")), 10)
    db = nc.load_db()
    gnss_ids = {db.get_message_by_name(n).frame_id
                for n in ("GNSS_Position", "GNSS_Velocity", "GNSS_Height", "GNSS_Status")}
    times = []
    with can.LogReader(str(perfect_run / "can_in.log")) as reader:
        times = [m.timestamp for m in reader if m.arbitration_id in gnss_ids]
    assert len(times) > 1000
    for t0, t1, *_ in truth.outages:
        inside = [t for t in times if t0 <= t <= t1]
        assert inside == [], (t0, t1, inside[:3])
