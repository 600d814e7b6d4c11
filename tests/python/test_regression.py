"""The replay regression tool (tools/regression.py, make regression) can fail: a firmware
whose output differs by one byte, a changed expected record, a changed input or options,
and a firmware whose output differs between two runs are all caught. Each test runs the
real navecu on one committed case (sim-watchdog: the regress drive up to its stalled task
at 100 s, 0.1 s of firmware time), in a copy of tests/regression/ of that case alone."""
import json
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from tools import regression

ROOT = Path(__file__).resolve().parents[2]
NAVECU = Path(os.environ.get("NAVECU_BIN", ROOT / "build" / "host" / "navecu"))
CASES = ROOT / "tests" / "regression"
CASE = "sim-watchdog"

# A stand-in for navecu: runs the real one, then changes one hex digit of its output log
# (the high digit of payload byte 1: a signal in every NAV_* message, never a spare bit):
# of the first frame after the MIDDLE of the log, or of the LAST frame.
FLIPPER = """#!{python}
import subprocess, sys
argv = sys.argv[1:]
rc = subprocess.run([{navecu!r}] + argv).returncode
out = argv[argv.index("--out") + 1]
lines = open(out).read().splitlines(keepends=True)
k = {where}
head, data = lines[k].rsplit("#", 1)
lines[k] = head + "#" + data[:2] + ("1" if data[2] != "1" else "2") + data[3:]
open(out, "w").write("".join(lines))
sys.exit(rc)
"""

# A navecu whose output differs from run to run: a counter file decides which byte changes.
FLAKY = """#!{python}
import os, subprocess, sys
argv = sys.argv[1:]
rc = subprocess.run([{navecu!r}] + argv).returncode
state = {state!r}
n = int(open(state).read()) if os.path.exists(state) else 0
open(state, "w").write(str(n + 1))
out = argv[argv.index("--out") + 1]
if n % 2:
    with open(out, "a") as f:
        f.write("(0000009999.000000) can0 310#0000000000000000\\n")
sys.exit(rc)
"""


@pytest.fixture()
def one_case(tmp_path):
    """tests/regression/ with only CASE, in tmp_path/cases; the work folder tmp_path/work."""
    if not NAVECU.exists():
        pytest.fail(f"{NAVECU} not built: run 'make' first")
    cases = tmp_path / "cases"
    (cases / "inputs").mkdir(parents=True)
    case = next(c for c in regression.load_cases(CASES) if c["name"] == CASE)
    shutil.copyfile(CASES / case["input"], cases / case["input"])
    (cases / "cases.json").write_text(json.dumps({"cases": [case]}))
    expected = json.loads((CASES / "expected.json").read_text())
    (cases / "expected.json").write_text(json.dumps({CASE: expected[CASE]}))
    return cases, tmp_path / "work"


def tool(cases, work, command, navecu=NAVECU):
    return subprocess.run([sys.executable, "-m", "tools.regression", command, "--cases-dir",
                           str(cases), "--work", str(work), "--navecu", str(navecu)],
                          capture_output=True, text=True, cwd=ROOT)


def script(path: Path, text: str) -> Path:
    path.write_text(text)
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return path


def test_the_committed_case_passes(one_case):
    r = tool(*one_case, "check")
    assert r.returncode == 0, r.stdout + r.stderr
    assert f"{CASE}: ok" in r.stdout and "PASS" in r.stdout


@pytest.mark.parametrize("where", ["len(lines) // 2", "len(lines) - 1"])
def test_one_changed_output_byte_fails(one_case, tmp_path, where):
    cases, work = one_case
    fake = script(tmp_path / "navecu-flipped",
                  FLIPPER.format(python=sys.executable, navecu=str(NAVECU), where=where))
    r = tool(cases, work, "check", fake)
    assert r.returncode == 1, r.stdout
    assert f"regression: {CASE}: FAIL" in r.stdout
    assert "the output log (sha256)" in r.stdout
    assert "make regression-update" in r.stdout and "why" in r.stdout
    if where == "len(lines) - 1":       # the last frame is in the summary: its diff shows
        assert "summary diff:" in r.stdout and "+++ this firmware's summary" in r.stdout
    else:                               # a frame in the middle is not: said so
        assert "the summary is the same" in r.stdout


def test_a_changed_expected_record_fails(one_case):
    cases, work = one_case
    exp = json.loads((cases / "expected.json").read_text())
    exp[CASE]["summary"]["counters"]["CntTasksLate"] += 1
    (cases / "expected.json").write_text(json.dumps(exp))
    r = tool(cases, work, "check")
    assert r.returncode == 1
    assert '"CntTasksLate"' in r.stdout and "summary diff:" in r.stdout


def test_changed_options_are_named_as_a_change_of_the_case(one_case):
    cases, work = one_case
    doc = json.loads((cases / "cases.json").read_text())
    doc["cases"][0]["args"] = doc["cases"][0]["args"].replace("--test-stall-poll-s 100",
                                                              "--test-stall-poll-s 90")
    (cases / "cases.json").write_text(json.dumps(doc))
    r = tool(cases, work, "check")
    assert r.returncode == 1
    assert "args: the case itself changed" in r.stdout


def test_update_then_check_and_a_nondeterministic_firmware_is_refused(one_case, tmp_path):
    cases, work = one_case
    (cases / "expected.json").unlink()
    r = tool(cases, work, "check")
    assert r.returncode == 1 and "no expected record" in r.stdout
    r = tool(cases, work, "update")
    assert r.returncode == 0, r.stdout + r.stderr
    assert tool(cases, work, "check").returncode == 0
    written = (cases / "expected.json").read_text()
    fake = script(tmp_path / "navecu-flaky", FLAKY.format(
        python=sys.executable, navecu=str(NAVECU), state=str(tmp_path / "runs")))
    r = tool(cases, work, "update", fake)
    assert r.returncode == 1 and "not deterministic" in r.stdout
    assert (cases / "expected.json").read_text() == written


def test_to_json_round_trips():
    x = {"a": [1, 2.5, "x", None], "b": {"c": [], "d": {}, "e": [{"f": True}]},
         "g": ["y" * 60, "z" * 60]}
    text = regression.to_json(x)
    assert json.loads(text) == x
    assert '"a": [1, 2.5, "x", null]' in text          # short lists on one line
    assert '  "g": [\n' in text                         # long ones one item per line


def test_kingston_case_runs_the_kingston_runners_options():
    """kingston-900s is the Kingston drive as tools/kingston/run.py runs it: its committed
    options (cases.json, written by tools/regression_inputs.py) are the runner's RATES and
    SENSORS, so a change of the runner's sensor figures cannot leave the regression on the
    old ones unnoticed (regenerate with python -m tools.regression_inputs)."""
    from tools import regression_inputs
    from tools.kingston import run as kingston_run
    case = next(c for c in regression.load_cases(CASES) if c["name"] == "kingston-900s")
    assert case["args"] == regression_inputs.args_text(kingston_run.RATES + kingston_run.SENSORS)


def test_a_corrupt_case_file_or_input_is_named_not_a_traceback(one_case):
    """cases.json or expected.json cut short, a case without its input, or an input that
    does not decompress: one line naming the file (and the JSON error's line), exit 2;
    each was a Python traceback."""
    cases, work = one_case
    good = {p: p.read_bytes() for p in (cases / "cases.json", cases / "expected.json")}
    log = next((cases / "inputs").iterdir())
    for path, bad, what in (
            (cases / "cases.json", b'{"cases": [{"name": "x",\n "inp', "cases.json:2:2: not JSON"),
            (cases / "expected.json", b"{\n  \"sim\n", "expected.json:2:7: not JSON"),
            (cases / "cases.json", b'{"cases": [{"name": "x"}]}', "case 1 needs the strings"),
            (log, log.read_bytes()[:5000], "input does not decompress"),
            (log, None, "input is missing")):
        keep = path.read_bytes()
        if bad is None:
            path.unlink()
        else:
            path.write_bytes(bad)
        r = tool(cases, work, "check")
        assert r.returncode == 2 and what in r.stderr and "Traceback" not in r.stderr, r.stderr
        path.write_bytes(keep)
    assert {p: p.read_bytes() for p in good} == good
    assert tool(cases, work, "check").returncode == 0
