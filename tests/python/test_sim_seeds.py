"""tools/sim/seeds.py (make sim-seeds, issue #18): the sweep over seeds on a tiny drive (two
seeds, two at a time), the structure of seeds.json and its medians / worsts recomputed from
the per-seed values; the limits' PASS / FAIL, the seed lists and the sigma-follows-error
figures on made-up values. No accuracy is asserted.
"""
import json
import os
from pathlib import Path

import numpy as np
import pytest

from tools.sim import ideal, scenario, seeds

ROOT = Path(__file__).resolve().parents[2]
NAVECU = os.environ.get("NAVECU_BIN", str(ROOT / "build" / "host" / "navecu"))

# outage5's sensors (tactical IMU, differential GNSS, odometer) on a 2-min drive: the 30-s
# levelling, 12 m/s straight, a turn, and a 20-s GNSS outage
TINY = """base = "{base}"
name = "tiny"
description = "levelling, 12 m/s straight, a turn, a 20-s outage"

[[segment]]
kind = "stop"
duration_s = 35

[[segment]]
kind = "speed"
to_mps = 12
accel_mps2 = 1.5

[[segment]]
kind = "straight"
duration_s = 30

[[segment]]
kind = "turn"
radius_m = 80
angle_deg = 90

[[segment]]
kind = "straight"
duration_s = 30

[[outage]]
start_s = 60
end_s = 80
label = "tiny"
"""


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    d = tmp_path_factory.mktemp("seeds")
    toml = d / "tiny.toml"
    toml.write_text(TINY.format(base=scenario.scenario_path("outage5")))
    rc = seeds.main(["--scenarios", str(toml), "--seeds", "1,2", "--jobs", "2",
                     "--out", str(d / "out"), "--navecu", NAVECU])
    return rc, d / "out"


def test_sweep_writes_every_seed_and_its_summary(sweep):
    rc, out = sweep
    assert rc == 0
    res = json.loads((out / "seeds.json").read_text())
    assert res["seeds"] == [1, 2]
    assert list(res["scenarios"]) == ["tiny"]
    sc = res["scenarios"]["tiny"]
    assert [r["seed"] for r in sc["seeds"]] == [1, 2]
    for r in sc["seeds"]:
        assert r["error"] is None and r["rc"] == 0
        assert (out / "tiny" / f"seed{r['seed']}" / "report.json").exists()
        for k in ("rms_m", "outage_pct", "within_2sigma_pct", "hacc_spearman",
                  "hacc_cv_ratio", "epochs", "run_s", "ideal_rms_m", "height_rms_m",
                  "height_within_2sigma_pct"):
            assert k in r, k
        assert r["rms_m"] is not None and r["outage_pct"] is not None
        # the height's figures are its report.json's
        rep = json.loads((out / "tiny" / f"seed{r['seed']}" / "report.json").read_text())
        assert r["height_rms_m"] == rep["height"]["error_m"]["rms"] > 0.0
        assert r["height_within_2sigma_pct"] == pytest.approx(
            100.0 * rep["height"]["frac_within_2sigma"])
        assert 0.0 <= r["height_within_2sigma_pct"] <= 100.0
        assert r["ideal_rms_m"] is not None and r["ideal_rms_m"] > 0.0
        assert r["epochs"] > 0
    # the two seeds are different drives' sensor errors
    assert sc["seeds"][0]["rms_m"] != sc["seeds"][1]["rms_m"]
    # median and worst from the per-seed values (worst: largest error, smallest share)
    for fig, s in sc["summary"].items():
        vals = [r[fig] for r in sc["seeds"] if r[fig] is not None]
        assert s["seeds"] == len(vals)
        assert s["median"] == pytest.approx(float(np.median(vals)))
        worst = min(vals) if fig in ("within_2sigma_pct", "height_within_2sigma_pct",
                                     "hacc_spearman", "hacc_cv_ratio") else max(vals)
        assert s["worst"] == pytest.approx(worst)
        assert s["limits"] == {} and s["result"] is None   # no limits for this scenario
    assert {"rms_m", "outage_pct", "within_2sigma_pct", "height_rms_m",
            "height_within_2sigma_pct"} <= set(sc["summary"])
    a = sc["across_seeds"]
    assert a["seeds"] == 2
    assert a["rms_m"] == [pytest.approx(min(r["rms_m"] for r in sc["seeds"])),
                          pytest.approx(max(r["rms_m"] for r in sc["seeds"]))]
    assert a["cv_ratio"] is not None and a["cv_ratio"] >= 0.0
    assert res["wall_s"] > 0


def test_summary_limits_pass_and_fail():
    rows = [{"seed": s, "rms_m": v, "within_2sigma_pct": w}
            for s, v, w in ((1, 1.2, 99.0), (2, 1.6, 95.0), (3, 2.7, 91.0), (4, 1.4, 100.0))]
    s = seeds.summarise(rows, seeds.LIMITS["default"])
    assert s["rms_m"]["median"] == pytest.approx(1.5)       # mean of 1.4 and 1.6
    assert s["rms_m"]["worst"] == 2.7 and s["rms_m"]["worst_seed"] == 3
    assert s["rms_m"]["limits"]["median"]["result"] == "PASS"    # 1.5 <= 1.5
    assert s["rms_m"]["limits"]["worst"]["result"] == "FAIL"     # 2.7 > 2.5
    assert s["rms_m"]["result"] == "FAIL"
    assert s["within_2sigma_pct"]["worst"] == 91.0
    assert s["within_2sigma_pct"]["result"] == "PASS"
    # a seed that gave no figure fails the limit, whatever the others
    rows[0]["within_2sigma_pct"] = None
    s = seeds.summarise(rows, seeds.LIMITS["default"])
    assert s["within_2sigma_pct"]["seeds"] == 3
    assert s["within_2sigma_pct"]["result"] == "FAIL"


def test_parse_seeds():
    assert seeds.parse_seeds(["1-8"]) == list(range(1, 9))
    assert seeds.parse_seeds(["3,1", "5-6", "1"]) == [1, 3, 5, 6]
    assert seeds.parse_seeds(["1", "2", "3"]) == [1, 2, 3]
    with pytest.raises(ValueError):
        seeds.parse_seeds(["5-2"])


def test_a_constant_sigma_shows_as_a_number():
    err = np.abs(np.sin(np.linspace(0.0, 20.0, 500))) + 0.1
    f = seeds.sigma_follows_error(np.full(err.size, 1.5), err)
    assert f["hacc_spearman"] is None and f["hacc_cv_ratio"] == 0.0
    f = seeds.sigma_follows_error(2.0 * err + 0.5, err)
    assert f["hacc_spearman"] == pytest.approx(1.0)
    assert 0.0 < f["hacc_cv_ratio"] < 1.0
    # across seeds: the same sigma on every seed whatever its error is a ratio of 0
    a = seeds.across_seeds([{"sigma_mean_m": 1.6, "rms_m": v} for v in (0.7, 1.5, 3.3)])
    assert a["cv_ratio"] == pytest.approx(0.0, abs=1e-12) and a["rms_m"] == [0.7, 3.3]
    # ranks with ties as scipy.stats.rankdata
    assert list(seeds.rankdata([3, 1, 1, 2])) == [4.0, 1.5, 1.5, 3.0]


def test_a_failed_run_is_exit_1(tmp_path):
    toml = tmp_path / "tiny.toml"
    toml.write_text(TINY.format(base=scenario.scenario_path("outage5")))
    rc = seeds.main(["--scenarios", str(toml), "--seeds", "1", "--jobs", "1",
                     "--out", str(tmp_path / "out"), "--navecu", str(tmp_path / "no-navecu")])
    assert rc == 1
    res = json.loads((tmp_path / "out" / "seeds.json").read_text())
    assert "exit status" in res["scenarios"]["tiny"]["seeds"][0]["error"]


def test_merge_joins_the_seeds_of_several_sweeps(tmp_path):
    def sweep(path, rows):
        res = {"command": f"sweep {path}", "scenarios": {"default": {"seeds": rows}}}
        (tmp_path / path).write_text(json.dumps(res))
        return tmp_path / path
    a = sweep("a.json", [{"seed": 1, "rms_m": 1.0, "navigation_start_s": 30.0},
                         {"seed": 2, "rms_m": 3.0, "navigation_start_s": 30.0}])
    b = sweep("b.json", [{"seed": 2, "rms_m": 2.0, "navigation_start_s": 30.0},
                         {"seed": 5, "rms_m": 1.2, "navigation_start_s": 30.0}])
    res = seeds.merged([a, b])
    sc = res["scenarios"]["default"]
    assert [r["seed"] for r in sc["seeds"]] == [1, 2, 5]
    assert sc["seeds"][1]["rms_m"] == 2.0            # the later file's seed 2
    assert res["seeds"] == [1, 2, 5]
    assert sc["summary"]["rms_m"]["median"] == pytest.approx(1.2)
    assert sc["summary"]["rms_m"]["worst"] == 2.0 and sc["summary"]["rms_m"]["worst_seed"] == 2
    assert sc["summary"]["rms_m"]["limits"]["worst"]["result"] == "PASS"
    assert sc["summary"]["ideal_rms_m"]["seeds"] == 3
    # the reference is computed afresh for every row: these made-up rows name the built-in
    # default drive, so they get its seeds' perfect dead reckoning from 30 s on
    for r in sc["seeds"]:
        assert r["ideal_rms_m"] == pytest.approx(
            ideal.receiver_limited("default", r["seed"], 30.0)["rms_m"])
    assert res["commands"] == [f"sweep {a.name}", f"sweep {b.name}"]


def test_merge_survives_a_scenario_it_cannot_load(tmp_path, capsys):
    res = {"command": "c", "scenarios": {"tiny": {"seeds": [
        {"seed": 1, "rms_m": 1.0, "scenario_arg": str(tmp_path / "gone.toml"),
         "navigation_start_s": 30.0, "outage_pct": None, "within_2sigma_pct": 100.0,
         "hacc_spearman": 0.5, "hacc_cv_ratio": 0.1, "sigma_min_m": 1.0, "sigma_max_m": 2.0,
         "error_min_m": 0.0, "error_max_m": 3.0, "run_s": 1.0},
        {"seed": 2, "error": "tools.sim.run exit status 1"}]}}}
    (tmp_path / "s.json").write_text(json.dumps(res))
    sc = seeds.merged([tmp_path / "s.json"])["scenarios"]["tiny"]
    assert sc["seeds"][0]["ideal_rms_m"] is None and "no perfect dead reckoning" in \
        capsys.readouterr().err
    assert seeds.main(["--merge", str(tmp_path / "s.json"), "--md",
                       str(tmp_path / "new" / "t.md")]) == 1      # a failed run joined
    assert (tmp_path / "new" / "t.md").exists()
