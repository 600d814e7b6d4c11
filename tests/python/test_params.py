"""The parameter table (firmware/app/params.toml, docs/configuration.md): the host's options
are the table's, with its ranges; the IMU presets are the simulator's grades where both
name one."""
import math
import os
import subprocess
from pathlib import Path

import pytest

from tools import gen_params
from tools.sim import sensors

ROOT = Path(__file__).resolve().parents[2]
NAVECU = Path(os.environ.get("NAVECU_BIN", ROOT / "build/host/navecu"))


@pytest.fixture(scope="module")
def table():
    params = gen_params.load()
    return params, gen_params.presets(gen_params.read(), params)


@pytest.fixture(scope="module")
def one_frame_log(tmp_path_factory):
    p = tmp_path_factory.mktemp("params") / "in.log"
    p.write_text("(0.000000) can0 7FF#00\n")
    return p


def _run(log, *args):
    return subprocess.run([str(NAVECU), "--can-log", str(log), "--out", os.devnull, *args],
                          capture_output=True, text=True)


def _value(p, x):
    if p["type"] == "vec3":
        return f"{x:.12g},{x:.12g},{x:.12g}"
    if p["type"] == "u16":
        return str(int(x))
    return f"{x:.12g}"


def test_every_option_takes_its_range_and_refuses_beyond(table, one_frame_log):
    params, _ = table
    for p in params:
        opt = p["option"]
        extra = ["--imu-rate-hz", "400"] if p["name"].endswith("rate_hz") else []
        if p["type"] == "enum":
            for v in p["values"]:
                assert _run(one_frame_log, *extra, opt, v).returncode == 0, (opt, v)
            res = _run(one_frame_log, opt, "nonsense")
            assert res.returncode == 2 and f"bad or missing value for {opt}" in res.stderr
            continue
        lo, hi = float(p["min"]), float(p["max"])
        step = 1.0 if p["type"] == "u16" else (hi - lo) * 1e-3
        good = [hi] + ([] if p["min_exclusive"] else [lo])
        bad = [lo - step, hi + step] + ([lo] if p["min_exclusive"] else [])
        if p["name"] == "imu_rate_hz":   # the output rates' defaults follow it down
            extra = []
        for x in good:
            res = _run(one_frame_log, *extra, opt, _value(p, x))
            assert res.returncode == 0, (opt, x, res.stderr)
        for x in bad:
            res = _run(one_frame_log, *extra, opt, _value(p, x))
            assert res.returncode == 2, (opt, x)
            assert f"bad or missing value for {opt}" in res.stderr, res.stderr


def test_help_lists_every_parameter_and_preset(table):
    params, (_, lst, dflt) = table
    out = subprocess.run([str(NAVECU), "--help"], capture_output=True, text=True).stdout
    for p in params:
        assert p["option"] in out, p["option"]
    for name, *_ in lst:
        assert f"  {name} " in out
    assert f"default {dflt}" in out


def test_a_vec3_default_is_one_value_for_x_y_z(tmp_path):
    """app_param_t keeps one default a parameter (the ECU's flash): the generator refuses a
    vec3 whose default differs between the axes, and takes one that does not"""
    text = (ROOT / "firmware/app/params.toml").read_text(encoding="utf-8")
    same = "[0.0, 0.0, 0.0]"
    assert same in text
    p = tmp_path / "params.toml"
    p.write_text(text.replace(same, "[0.5, 0.5, 0.5]", 1), encoding="utf-8")
    assert any(q["type"] == "vec3" and q["default"] == [0.5] * 3 for q in gen_params.load(p))
    p.write_text(text.replace(same, "[0.0, 0.0, 0.5]", 1), encoding="utf-8")
    with pytest.raises(gen_params.TableError, match="one value for x, y and z"):
        gen_params.load(p)


def test_unknown_preset_refused(one_frame_log):
    res = _run(one_frame_log, "--imu-preset", "phone")
    assert res.returncode == 2 and "unknown --imu-preset 'phone'" in res.stderr
    assert _run(one_frame_log, "--imu-preset", "consumer").returncode == 0


# the firmware's presets against the simulator's truth models of the same grade
SIM_GRADE = {"automotive": "automotive", "tactical": "tactical", "navigation": "mid-grade"}


def test_presets_are_the_simulators_grades(table):
    params, (names, lst, _) = table
    by = {p["name"]: p for p in params}
    for name, _, _, vals in lst:
        if name not in SIM_GRADE:
            continue
        spec = sensors.PRESETS[SIM_GRADE[name]]
        si = {k: vals[k] * by[k]["factor"] for k in names}
        want = {"gyro_arw_rad_rts": spec.gyro_arw_deg_per_rth * math.pi / 180 / 60,
                "gyro_bias_rps": spec.gyro_bias_turnon_rps,
                "accel_bias_mps2": spec.accel_bias_turnon_mps2,
                # the instability's Allan floor, stored as B sqrt(2 / 300 s) (the x and y
                # gyros' walk; the z gyro's Gauss-Markov state takes B / 0.61736 from it)
                "gyro_bias_rw_rps_rts": spec.gyro_bias_instability_rps * math.sqrt(2 / 300),
                "gyro_bias_corr_time_s": spec.gyro_bias_corr_time_s,
                "accel_bias_rw_mps2_rts": spec.accel_bias_instability_mps2 * math.sqrt(2 / 300),
                # the forward axis's floor itself (its Gauss-Markov state, ekf.h state 25)
                "accel_fwd_instability_mps2": spec.accel_bias_instability_mps2}
        for k, w in want.items():
            assert si[k] == pytest.approx(w, rel=1e-5), (name, k)


def _f32(x):
    import struct
    return struct.unpack("<f", struct.pack("<f", float(x)))[0]


def test_uds_table_bounds_are_the_ecus_float32(table):
    """docs/can.md's parameter DIDs print each real bound so that the float32 a client sends
    for it is the ECU's bound itself (6 digits of 2.908882e-10 were below the ECU's minimum,
    and a write of the printed minimum was refused)."""
    import re
    doc = (ROOT / "docs/can.md").read_text()
    params, _ = table
    checked = 0
    for p in params:
        if p["type"] not in ("real", "vec3"):
            continue
        m = re.search(r"\| `0x%04X` \| `%s` \|[^\n]*?\| [\[(]([^,\]]+), ([^\],]+)\]" % (int(p["did"]), p["name"]), doc)
        assert m, p["name"]
        lo, hi = float(m.group(1)), float(m.group(2))
        assert _f32(lo) == _f32(p["min"] * p["factor"]), p["name"]
        assert _f32(hi) == _f32(p["max"] * p["factor"]), p["name"]
        checked += 1
    assert checked >= 20
