"""The drive simulator's scenarios (tools/sim/scenarios/*.toml): finding one by name and
what a scenario sets beyond the motion, for every tool that runs or reports a drive
(tools/sim/run.py, report.py, faults.py): the sensors as installed on the car
(sensor_specs), the initial heading command (heading_command_deg) and the truths
report.json compares with (scenario_truths).
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from tools.sim import sensors, trajectory

SCENARIOS = Path(__file__).resolve().parent / "scenarios"


def scenario_path(name: str) -> Path:
    """A scenario by name (tools/sim/scenarios/NAME.toml) or an existing .toml path;
    SystemExit naming the known ones otherwise."""
    p = Path(name)
    if p.suffix == ".toml" and p.exists():
        return p
    p = SCENARIOS / f"{name}.toml"
    if not p.exists():
        known = ", ".join(sorted(q.stem for q in SCENARIOS.glob("*.toml")))
        raise SystemExit(f"no scenario '{name}' (known: {known})")
    return p


def heading_command_deg(heading0_rad: float, scen: dict | None = None) -> float:
    """The Heading of CMD_Control SetInitialPosition (deg, on the DBC's 0.01 deg grid): the
    car's true heading at t = 0, plus the IMU's mounting yaw if the scenario's
    [initialization] heading_reference is "imu", plus its heading_error_deg.

    The firmware takes the IMU's axes for the car's: it is told that its forward axis
    points along this heading and reports it as the car's. The error of the car's heading
    as the firmware sees it is dH = command - true car heading (seed 000's sign: dH =
    H_sins - H_true), its initial attitude error about the IMU's own axes command - (true
    car heading + mounting yaw)."""
    h = math.degrees(heading0_rad)
    if scen is not None:
        ini = scen.get("initialization", trajectory.INITIALIZATION_DEFAULTS)
        if ini.get("heading_reference", "car") == "imu":
            h += float(scen.get("imu_mounting", {}).get("yaw_deg", 0.0))
        h += float(ini.get("heading_error_deg", 0.0))
    return (round(h % 360.0 * 100.0) % 36000) / 100.0


def sensor_specs(scen: dict, imu_name: str, vehicle: dict):
    """(ImuSpec, OdoSpec) of a scenario: the IMU preset with the scenario's [imu_mounting]
    (the car's installation, whatever the IMU grade), the odometer with the [vehicle]'s
    track and wheelbase and the [odometer] table's fields (e.g. mu)."""
    m = dict(trajectory.MOUNTING_DEFAULTS)
    m.update(scen.get("imu_mounting", {}))
    imu = dataclasses.replace(sensors.PRESETS[imu_name], mounting_roll_deg=float(m["roll_deg"]),
                              mounting_pitch_deg=float(m["pitch_deg"]),
                              mounting_yaw_deg=float(m["yaw_deg"]))
    odo = sensors.OdoSpec(track_m=vehicle["track_m"], wheelbase_m=vehicle["wheelbase_m"],
                          **scen.get("odometer", {}))
    return imu, odo


def scenario_truths(scen: dict, heading0_rad: float, imu: "sensors.ImuSpec",
                    odo: "sensors.OdoSpec", heading_deg: float) -> dict:
    """What the scenario makes true, for report.json: the IMU's mounting, the odometer's
    scale error, the initial heading command, and the heading errors they give (seed 000:
    dH = H_sins - H_true; constant through the drive but for the gyros' drift)."""
    ini = dict(trajectory.INITIALIZATION_DEFAULTS)
    ini.update(scen.get("initialization", {}))
    h0 = math.degrees(heading0_rad) % 360.0
    dh = (heading_deg - h0 + 180.0) % 360.0 - 180.0
    return {"imu_mounting_deg": {"roll": imu.mounting_roll_deg, "pitch": imu.mounting_pitch_deg,
                                 "yaw": imu.mounting_yaw_deg},
            "odometer_mu": odo.mu,
            "initial_heading": {"reference": ini["heading_reference"],
                                "error_deg": float(ini["heading_error_deg"]),
                                "car_true_deg": h0, "commanded_deg": heading_deg},
            # the car's heading as the firmware sees it minus the true one
            "dH_deg": dh,
            # the firmware's initial attitude error about the IMU's own axes
            "imu_heading_error_deg": dh - imu.mounting_yaw_deg}
