"""The drive simulator's scenarios (tools/sim/scenarios/*.toml): the file format, its
loading and validation (load_scenario, with `base` inheritance), finding one by name
(scenario_path, load), and what a scenario sets beyond the motion, for every tool that runs or
reports a drive (tools/sim/run.py, report.py, faults.py, grades.py): the IMU and GNSS
presets (preset_names), the sensors as installed on the car (sensor_specs), the initial
heading command (heading_command_deg) and the truths report.json compares with
(scenario_truths). The motion a scenario describes is tools/sim/trajectory.py's.

Scenario file (TOML, read by :func:`load_scenario`)
----------------------------------------------------
::

    name = "default"
    description = "..."

    [start]
    lat_deg = 45.0
    lon_deg = 10.0
    h_m = 100.0
    heading_deg = 30.0            # nose direction, clockwise from north

    [vehicle]                     # optional; the defaults are shown
    pitch_per_accel_deg = 0.4     # nose up per m/s^2 of longitudinal acceleration (squat/dive)
    roll_per_lat_accel_deg = 0.5  # roll out of the turn per m/s^2 of lateral acceleration
    roughness_deg = 0.05          # amplitude of road-induced pitch/roll oscillation
    track_m = 1.6                 # (for the wheel-speed model of the sensors)
    wheelbase_m = 2.7

    [[segment]]                   # executed in order
    kind = "stop"                 # stand still; the speed must already be 0
    duration_s = 40

    [[segment]]
    kind = "speed"                # change speed along a straight line, C2 (quintic) ramp
    to_mps = 14                   # negative: reversing (the nose keeps its direction)
    accel_mps2 = 1.5              # peak |acceleration|; or duration_s, or distance_m

    [[segment]]
    kind = "straight"             # constant speed
    distance_m = 500              # or duration_s

    [[segment]]
    kind = "turn"                 # constant speed, which must not be 0
    radius_m = 30
    angle_deg = 90                # heading change, positive = clockwise (right)
    ramp_frac = 0.3               # optional: curvature entry/exit ramp as a fraction of
                                  # angle*radius/|speed| (default 0.3; 0 < ramp_frac <= 1),
                                  # speed independent geometry; or ramp_s (seconds)

    [[segment]]
    kind = "hill"                 # constant speed, which must not be 0
    distance_m = 400              # path length of the bump
    grade_pct = 6                 # peak grade; or rise_m (peak height, negative = dip)

    [[outage]]                    # GNSS outages, for the sensor model and the report
    start_s = 300
    end_s = 360
    label = "tunnel"

    # --- optional tables for the sensors and the commands (tools/sim/run.py); defaults shown
    [sim]
    imu = "mid-grade"             # IMU preset (tools/sim/sensors.py PRESETS); --imu overrides
    gnss = "standalone"           # GNSS preset (GNSS_PRESETS; "none": no GNSS frames at all)

    [imu_mounting]                # the IMU on the car: sensor axes = body axes rotated by
    roll_deg = 0.0                # these (3-1-2, like the attitude; yaw clockwise positive),
    pitch_deg = 0.0               # with any IMU preset: the sensor's forward axis points
    yaw_deg = 0.0                 # along heading + yaw_deg
    configured = false            # true: the firmware is told (--imu-mount-deg R,P,Y)
    automatic = false             # true: the firmware estimates it (--imu-mount-source
                                  # automatic, firmware/app/mount_est.h); not with configured

    [odometer]                    # OdoSpec fields (tools/sim/sensors.py), e.g.
    mu = 0.012                    # scale error: wheel speeds read (1 + mu) x true

    [initialization]              # CMD_Control SetInitialPosition at t = 0
    heading_reference = "car"     # "car": the commanded heading is the car's true heading;
                                  # "imu": that of the IMU's forward axis (car + mounting
                                  # yaw), as a SINS's own alignment would find it
    heading_error_deg = 0.0       # added to it (then rounded to the DBC's 0.01 deg)

    [calibration]                 # one-point calibration (seed 000), absent: none
    at_s = 3431                   # when; the true position at this instant is the point
    source = "known_position"     # CMD_KnownPosition (true position) + CMD_Control 5
                                  # CalibrateHere; or "gnss": CMD_Control 6 CalibrateAtGnss
                                  # and the next GNSS epoch
    gnss = "standalone"           # source "gnss" with [sim] gnss = "none": the preset of the
                                  # one epoch sent after the command

    [gnss_faults]                 # bad GNSS epochs (tools/sim/sensors.py apply_gnss_faults),
                                  # absent: none; every time is on the drive's clock (s)
    jumps = [[300, 100], [500, 100, 90, 1.0]]
                                  # [t_s, metres, azimuth_deg = 0 (north), duration_s = 0]:
                                  # the first epoch at or after t_s (and every epoch up to
                                  # duration_s after it) reports its position moved by metres
                                  # towards the azimuth (clockwise from north); velocity,
                                  # height and accuracies unchanged
    freeze = [[700, 705]]         # [t0, t1]: epochs with t0 <= t < t1 repeat the last epoch
                                  # before t0 (position, velocity, height, accuracies,
                                  # satellites, fix) while their time of week advances
    latency_spike = [[900, 0.6]]  # [t_s, extra_s]: the first epoch at or after t_s is
                                  # delivered extra_s late (frames at t + extra_s, after the
                                  # epochs reported meanwhile) with its TimeOfWeek unchanged

    [gnss_raw]                    # raw measurements (tools/sim/receiver.py, issue #20),
                                  # absent: none
    enabled = true                # send a raw epoch (GNSS_Raw*) each second, none in outages
    canyons = [[200, 500, 4.0]]   # [start_s, end_s, 2H/W(, max_sats)]: street canyons along
                                  # the heading; max_sats keeps the highest of those left
    faults = [{kind = "multipath", start_s = 100, end_s = 160, rank = 1, error_m = 50.0},
              {kind = "clock_step", at_s = 200, step_m = 3000.0, flagged = false}]
                                  # receiver faults (tools/sim/receiver.py ReceiverSpec)
    receiver = {orbit_clock_m = 0.0}
                                  # the receiver model's figures other than its defaults
                                  # (ReceiverSpec's fields, e.g. an error switched off)

Inheritance: a top-level ``base = "default"`` (a scenario name in the same folder, or a
.toml path relative to this file's folder) starts from that scenario: its tables ([start],
[vehicle], [sim], [imu_mounting], [odometer], [initialization], [calibration],
[gnss_faults], [gnss_raw]) are merged key by key with this file's (this file's keys win), its
[[segment]] and [[outage]] arrays are kept unless this file gives its own (which replace
them as a whole; ``outage = []`` drops the base's outages). name and description are never
inherited. Bases may themselves have a base (no cycles).
"""
from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path

from tools.sim import sensors

SCENARIOS = Path(__file__).resolve().parent / "scenarios"


# --- the file ------------------------------------------------------------------------------
VEHICLE_DEFAULTS = {
    "pitch_per_accel_deg": 0.4,
    "roll_per_lat_accel_deg": 0.5,
    "roughness_deg": 0.05,
    "track_m": 1.6,
    "wheelbase_m": 2.7,
}
_SEG_KEYS = {
    "stop": {"duration_s"},
    "speed": {"to_mps", "accel_mps2", "duration_s", "distance_m"},
    "straight": {"distance_m", "duration_s"},
    "turn": {"radius_m", "angle_deg", "ramp_frac", "ramp_s"},
    "hill": {"distance_m", "grade_pct", "rise_m"},
}


# segment keys that are lengths of time or road (a negative one shortened the drive)
_SEG_NOT_NEGATIVE = {"duration_s", "distance_m", "radius_m", "ramp_frac", "ramp_s"}
START_KEYS = ("lat_deg", "lon_deg", "h_m", "heading_deg")


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _check_numbers(x, where: str, key: str = "") -> None:
    """Every number in a scenario finite: TOML writes nan and inf, and a NaN heading or an
    infinite duration went into the trajectory without a word."""
    if isinstance(x, float) and not math.isfinite(x):
        raise ValueError(f"{where}: {key} = {x} is not a finite number")
    if isinstance(x, dict):
        for k, v in x.items():
            _check_numbers(v, where, f"{key}.{k}" if key else str(k))
    elif isinstance(x, list):
        for i, v in enumerate(x):
            _check_numbers(v, where, f"{key}[{i}]")


MOUNTING_DEFAULTS = {"roll_deg": 0.0, "pitch_deg": 0.0, "yaw_deg": 0.0, "configured": False,
                     "automatic": False}
INITIALIZATION_DEFAULTS = {"heading_reference": "car", "heading_error_deg": 0.0}
_OPTIONAL_TABLES = {
    "sim": {"imu", "gnss"},
    "imu_mounting": set(MOUNTING_DEFAULTS),
    # the OdoSpec fields a scenario may set (track and wheelbase come from [vehicle])
    "odometer": {"mu", "wheel_mu_sigma", "rate_hz", "latency_s", "noise_mps", "slip_frac",
                 "slip_accel_threshold_mps2", "driven_axle"},
    "initialization": set(INITIALIZATION_DEFAULTS),
    "calibration": {"at_s", "source", "gnss"},
    "gnss_faults": {"jumps", "freeze", "latency_spike"},
    "gnss_raw": {"enabled", "canyons", "faults", "receiver"},
}
GNSS_JUMP_AZIMUTH_DEG_DEFAULT = 0.0   # a jump without an azimuth moves the fix north
# every simulated drive's GPS time at its t = 0 (tools.sim.run sends it, tools.sim.receiver
# places the constellation by it)
GPS_TOW0_S = 302400.0  # GNSS time of week at t = 0 (Wednesday noon)
GPS_WEEK = 2400        # its GPS week (2026-01-04 .. 2026-01-10)


def _gnss_faults(path, table: dict) -> dict:
    """[gnss_faults] as lists of dicts (format in the module docstring), validated."""
    def rows(key, lo, hi):
        out = table.get(key, [])
        if not isinstance(out, list):
            raise ValueError(f"{path}: [gnss_faults] {key} must be a list of lists")
        for r in out:
            if (not isinstance(r, list) or not lo <= len(r) <= hi
                    or not all(isinstance(x, (int, float)) for x in r)):
                n = f"{lo}..{hi}" if lo != hi else f"{lo}"
                raise ValueError(f"{path}: [gnss_faults] {key}: {r!r} is not a list of {n} "
                                 "numbers")
        return [[float(x) for x in r] for r in out]

    jumps = []
    for r in rows("jumps", 2, 4):
        t, m = r[0], r[1]
        az = r[2] if len(r) > 2 else GNSS_JUMP_AZIMUTH_DEG_DEFAULT
        dur = r[3] if len(r) > 3 else 0.0
        if not (t > 0.0 and m != 0.0 and dur >= 0.0):
            raise ValueError(f"{path}: [gnss_faults] jump {r}: needs t_s > 0, metres != 0, "
                             "duration_s >= 0")
        jumps.append({"t_s": t, "metres": m, "azimuth_deg": az, "duration_s": dur})
    freeze = []
    for r in rows("freeze", 2, 2):
        if not 0.0 < r[0] < r[1]:
            raise ValueError(f"{path}: [gnss_faults] freeze {r}: needs 0 < t0 < t1")
        freeze.append({"t0_s": r[0], "t1_s": r[1]})
    spikes = []
    for r in rows("latency_spike", 2, 2):
        if not (r[0] > 0.0 and r[1] > 0.0):
            raise ValueError(f"{path}: [gnss_faults] latency_spike {r}: needs t_s > 0, "
                             "extra_s > 0")
        spikes.append({"t_s": r[0], "extra_s": r[1]})
    return {"jumps": jumps, "freeze": freeze, "latency_spike": spikes}


# tables a scenario with `base` merges key by key over its base's (the rest: replaced)
_MERGED_TABLES = ("start", "vehicle", "sim", "imu_mounting", "odometer", "initialization",
                  "calibration", "gnss_faults", "gnss_raw")
# top-level keys that belong to the file itself, never inherited
_OWN_KEYS = ("name", "description", "base")


def base_path(path, base: str) -> Path:
    """The file a scenario's `base = "..."` names: a scenario name (NAME.toml next to the
    file) or a .toml path relative to the file's folder."""
    b = Path(base)
    if b.suffix != ".toml":
        b = b.with_name(b.name + ".toml")
    return b if b.is_absolute() else Path(path).resolve().parent / b


def read_scenario_toml(path, _chain=()) -> dict:
    """A scenario file's TOML with its `base` resolved (not yet validated): the base's
    content (itself resolved, recursively), then this file's over it. Tables of
    _MERGED_TABLES are merged key by key (this file's keys win); arrays of tables
    ([[segment]], [[outage]]) are replaced as a whole when this file has the key
    (`outage = []` drops the base's outages); name, description and base are this file's
    own (name defaults to the file's stem)."""
    path = Path(path).resolve()
    if path in _chain:
        raise ValueError(f"{path}: base cycle: {' -> '.join(p.name for p in _chain + (path,))}")
    try:
        with open(path, "rb") as fh:
            own = tomllib.load(fh)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise ValueError(f"{path}: not TOML: {e}") from None
    except OSError as e:
        raise ValueError(f"{path}: {e.strerror or e}") from None
    if "base" not in own:
        return own
    if not isinstance(own["base"], str) or not own["base"]:
        raise ValueError(f"{path}: base must be a scenario name or a .toml path")
    bp = base_path(path, own["base"])
    if not bp.exists():
        raise ValueError(f"{path}: base {own['base']!r}: no file {bp}")
    sc = {k: v for k, v in read_scenario_toml(bp, _chain + (path,)).items()
          if k not in _OWN_KEYS}
    for k, v in own.items():
        if k in _MERGED_TABLES and isinstance(v, dict) and isinstance(sc.get(k), dict):
            sc[k] = {**sc[k], **v}
        else:
            sc[k] = v
    sc["base"] = own["base"]
    return sc


def load_scenario(path) -> dict:
    """Read and validate a scenario TOML file (format in the module docstring), with its
    `base` scenario resolved (read_scenario_toml)."""
    path = Path(path)
    sc = read_scenario_toml(path)
    _check_numbers(sc, str(path))
    sc.setdefault("name", path.stem)
    sc.setdefault("description", "")
    start = sc.get("start", {})
    for key in START_KEYS:
        if key not in start:
            raise ValueError(f"{path}: [start] needs {key}")
        if not _is_number(start[key]):
            raise ValueError(f"{path}: [start] {key} must be a number, not {start[key]!r}")
    unknown = set(start) - set(START_KEYS)
    if unknown:
        raise ValueError(f"{path}: unknown [start] keys {sorted(unknown)}")
    veh = dict(VEHICLE_DEFAULTS)
    unknown = set(sc.get("vehicle", {})) - set(VEHICLE_DEFAULTS)
    if unknown:
        raise ValueError(f"{path}: unknown [vehicle] keys {sorted(unknown)}")
    veh.update(sc.get("vehicle", {}))
    sc["vehicle"] = veh
    segs = sc.get("segment", [])
    if not segs:
        raise ValueError(f"{path}: no [[segment]]")
    for i, seg in enumerate(segs):
        kind = seg.get("kind")
        if kind not in _SEG_KEYS:
            raise ValueError(f"{path}: segment {i}: unknown kind {kind!r}")
        unknown = set(seg) - _SEG_KEYS[kind] - {"kind", "note"}
        if unknown:
            raise ValueError(f"{path}: segment {i} ({kind}): unknown keys {sorted(unknown)}")
        for key in _SEG_KEYS[kind] & set(seg):
            v = seg[key]
            if not _is_number(v) or (key in _SEG_NOT_NEGATIVE and v < 0):
                raise ValueError(f"{path}: segment {i} ({kind}): {key} must be a "
                                 f"{'non-negative ' if key in _SEG_NOT_NEGATIVE else ''}"
                                 f"number, not {v!r}")
    sc["segment"] = segs
    outs = []
    for o in sc.get("outage", []):
        s0, s1 = float(o["start_s"]), float(o["end_s"])
        if not s1 > s0:
            raise ValueError(f"{path}: outage {o} ends before it starts")
        outs.append({"start_s": s0, "end_s": s1, "label": str(o.get("label", "outage"))})
    sc["outage"] = outs
    for table, known in _OPTIONAL_TABLES.items():
        unknown = set(sc.get(table, {})) - known
        if unknown:
            raise ValueError(f"{path}: unknown [{table}] keys {sorted(unknown)}")
    mnt = dict(MOUNTING_DEFAULTS)
    mnt.update({k: (bool(v) if k in ("configured", "automatic") else float(v))
                for k, v in sc.get("imu_mounting", {}).items()})
    sc["imu_mounting"] = mnt
    sc["odometer"] = dict(sc.get("odometer", {}))
    ini = dict(INITIALIZATION_DEFAULTS)
    ini.update(sc.get("initialization", {}))
    if ini["heading_reference"] not in ("car", "imu"):
        raise ValueError(f"{path}: [initialization] heading_reference must be 'car' or 'imu'")
    ini["heading_error_deg"] = float(ini["heading_error_deg"])
    sc["initialization"] = ini
    if "calibration" in sc:
        cal = {"source": "known_position", "gnss": "standalone"}
        cal.update(sc["calibration"])
        if "at_s" not in cal or not float(cal["at_s"]) > 0.0:
            raise ValueError(f"{path}: [calibration] needs at_s > 0")
        cal["at_s"] = float(cal["at_s"])
        if cal["source"] not in ("known_position", "gnss"):
            raise ValueError(f"{path}: [calibration] source must be 'known_position' or 'gnss'")
        sc["calibration"] = cal
    if "gnss_faults" in sc:
        sc["gnss_faults"] = _gnss_faults(path, sc["gnss_faults"])
    if "gnss_raw" in sc:
        from tools.sim import receiver   # its figures checked now, not when a run uses them
        try:
            receiver.spec_of(sc["gnss_raw"])
        except ValueError as e:
            raise ValueError(f"{path}: {e}") from None
    return sc


def stationary(duration_s: float, folder, name: str = "still") -> dict:
    """A scenario standing still for duration_s at 45 deg N 10 deg E, 100 m, heading north,
    without road roughness, written to folder/still.toml and loaded."""
    path = Path(folder) / "still.toml"
    path.write_text(f"""name = "{name}"
[start]
lat_deg = 45.0
lon_deg = 10.0
h_m = 100.0
heading_deg = 0.0
[vehicle]
roughness_deg = 0.0
[[segment]]
kind = "stop"
duration_s = {duration_s}
""")
    return load_scenario(path)


# --- what a scenario sets beyond the motion --------------------------------------------------
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


def load(name: str) -> dict:
    """The scenario of this name or .toml path (scenario_path), loaded (load_scenario);
    for the command-line tools a scenario that does not load is SystemExit with the
    reason, as an unknown name is."""
    try:
        return load_scenario(scenario_path(name))
    except ValueError as e:
        raise SystemExit(f"scenario: {e}") from None


def preset_names(scen: dict, imu: str | None = None, gnss: str | None = None) -> tuple:
    """(IMU preset, GNSS preset) of a drive: the names given (a command line's --imu,
    --gnss), else the scenario's [sim] imu and gnss, else mid-grade and standalone."""
    sim = scen.get("sim", {})
    return imu or sim.get("imu", "mid-grade"), gnss or sim.get("gnss", "standalone")


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
        ini = scen.get("initialization", INITIALIZATION_DEFAULTS)
        if ini.get("heading_reference", "car") == "imu":
            h += float(scen.get("imu_mounting", {}).get("yaw_deg", 0.0))
        h += float(ini.get("heading_error_deg", 0.0))
    return (round(h % 360.0 * 100.0) % 36000) / 100.0


def sensor_specs(scen: dict, imu_name: str, vehicle: dict):
    """(ImuSpec, OdoSpec) of a scenario: the IMU preset with the scenario's [imu_mounting]
    (the car's installation, whatever the IMU grade), the odometer with the [vehicle]'s
    track and wheelbase and the [odometer] table's fields (e.g. mu)."""
    m = dict(MOUNTING_DEFAULTS)
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
    ini = dict(INITIALIZATION_DEFAULTS)
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
