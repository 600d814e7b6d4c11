"""Replay regression: the firmware's output on committed CAN logs against the expected
(`make regression`, `make regression-update`; docs/regression.md).

    python -m tools.regression check  [--case NAME ...] [--navecu build/host/navecu]
    python -m tools.regression update [--navecu build/host/navecu]

tests/regression/cases.json lists the cases (written by tools/regression_inputs.py): per
case an input log (xz-compressed candump, decompressed into build/regression/), navecu's
options (one shell-quoted string) and the NVM it boots with (none; "fresh": a file it creates; or a committed image,
copied first, since the firmware writes into it). Each case is run as

    navecu --can-log IN --out OUT [--nvm NVM] OPTIONS

and recorded: the input's SHA-256, the options, the exit status, the SHA-256 of the output
log, of the output log without the time-driven NAV_Heartbeat (the data-driven frames alone:
deterministic in a file run too, the heartbeat's HAL time being the log's timestamps, but
left out there so that a change to it is told from one to the navigation outputs) and of
the NVM afterwards, and a summary decoded from the output through the DBC
(frames per message, NAV_Status page-0 frames per Mode, when Mode and the calibration
state changed, the HealthFlags and CalStatus values seen, the last values of every output
message, the last value of every NAV_Status counter) with navecu's stderr summary.

check: every case's record against tests/regression/expected.json; on a difference it
names the case and what differs and prints the summary diff. Exit status 0 if all agree,
1 otherwise, 2 if there is no firmware or cases.json, expected.json or an input cannot be
read (named, with the line of a JSON error). The outputs stay in build/regression/<case>/ (out.log, nvm.bin, stderr.txt).

update: runs every case twice, refuses to write if the two runs differ (a non-deterministic
output cannot be a reference), and rewrites expected.json. A change that alters the
firmware's output on purpose commits the new expected.json with it and says why.
"""
from __future__ import annotations

import argparse
import difflib
import hashlib
import json
import lzma
import shlex
import shutil
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

from tools import navecu_can as nc

ROOT = Path(__file__).resolve().parents[1]
CASES_DIR = ROOT / "tests" / "regression"
WORK = ROOT / "build" / "regression"
NAVECU = ROOT / "build" / "host" / "navecu"
UPDATE_HINT = ("If the change is intended: make regression-update, and commit "
               "tests/regression/expected.json in the same commit, saying in its message why "
               "the output changed (docs/regression.md).")


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def data_sha256(out_log: Path) -> str:
    """The SHA-256 of the output log without the time-driven NAV_Heartbeat lines
    (navecu_can.data_driven): the data-driven outputs alone, which no heartbeat changes."""
    lines = out_log.read_text().splitlines(keepends=True)
    return hashlib.sha256("".join(nc.data_driven(lines)).encode()).hexdigest()


class CaseFileError(ValueError):
    """cases.json, expected.json or a case's input that cannot be read: exit status 2."""


def read_json(path: Path) -> dict:
    """A JSON file of the regression (cases.json, expected.json) as a dict, or
    CaseFileError naming the file and, for a syntax error, its line and column."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise CaseFileError(f"{path}: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise CaseFileError(f"{path}: not UTF-8 text: {e}") from None
    except json.JSONDecodeError as e:
        raise CaseFileError(f"{path}:{e.lineno}:{e.colno}: not JSON: {e.msg}") from None
    if not isinstance(data, dict):
        raise CaseFileError(f"{path}: not a JSON object")
    return data


def load_cases(cases_dir: Path) -> list:
    """cases.json's cases, each with a name, an input and its options (CaseFileError
    otherwise)."""
    path = cases_dir / "cases.json"
    cases = read_json(path).get("cases")
    if not isinstance(cases, list):
        raise CaseFileError(f"{path}: no list \"cases\"")
    for i, c in enumerate(cases):
        if not (isinstance(c, dict) and all(isinstance(c.get(k), str)
                                            for k in ("name", "input", "args"))):
            raise CaseFileError(f"{path}: case {i + 1} needs the strings name, input and args")
    return cases


def to_json(x, indent: int = 0, width: int = 96) -> str:
    """JSON as json.dumps(indent=2) writes it, but a list of numbers and strings that fits
    in width goes on one line (navecu options, timelines stay readable)."""
    pad, inner = " " * indent, " " * (indent + 2)
    if isinstance(x, dict) and x:
        items = [f"{inner}{json.dumps(k)}: {to_json(v, indent + 2, width).lstrip()}"
                 for k, v in x.items()]
        return pad + "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(x, list) and x:
        flat = json.dumps(x)
        if all(not isinstance(v, (dict, list)) for v in x) and indent + len(flat) <= width:
            return pad + flat
        return pad + "[\n" + ",\n".join(to_json(v, indent + 2, width) for v in x) + "\n" + pad + "]"
    return pad + json.dumps(x)


# ==================================================================== the output decoded
def _raw(sig, word: int) -> int:
    """A little-endian DBC signal's raw value (unsigned) from the payload as an integer."""
    return (word >> sig.start) & ((1 << sig.length) - 1)


def _physical(sig, value):
    """A decoded value as the summary shows it: choice names as they are, numbers rounded
    to the signal's resolution (so that 45.00000001 reads 45.0)."""
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return str(value)
    scale = sig.conversion.scale
    if float(scale).is_integer() and float(sig.conversion.offset).is_integer():
        return int(value)
    decimals = max(0, -int(f"{scale:e}".split("e")[1])) + 1
    return round(float(value), decimals)


def _decode(db, msg_def, data: bytes) -> dict:
    sig = db.decode_message(msg_def.frame_id, data, decode_choices=True)
    out = {}
    for name, value in sig.items():
        if name.endswith(("Counter", "Crc")) or name == "StatusPage":
            continue
        out[name] = _physical(msg_def.get_signal_by_name(name), value)
    return out


TIMELINE_MAX = 40


def _timeline(entries: list) -> list:
    """At most TIMELINE_MAX entries: a summary stays small whatever the firmware does."""
    if len(entries) <= TIMELINE_MAX:
        return entries
    return entries[:TIMELINE_MAX] + [f"... and {len(entries) - TIMELINE_MAX} more changes"]


def _flag_names(bits: dict, value: int) -> list:
    return [bits.get(b, (f"BIT{b}", ""))[0] for b in range(16) if value >> b & 1]


def summarize(out_log: Path, db=None) -> dict:
    """The summary of a navecu output log (module docstring)."""
    db = db if db is not None else nc.DEFAULT_DB
    defs = {m.frame_id: m for m in db.messages}
    st_def = db.get_message_by_name("NAV_Status")
    cal_def = db.get_message_by_name("NAV_Calibration")
    pos_id = db.get_message_by_name("NAV_Position").frame_id
    page_sig, mode_sig, flags_sig = (st_def.get_signal_by_name(n)
                                     for n in ("StatusPage", "Mode", "HealthFlags"))
    cal_sigs = [cal_def.get_signal_by_name(n)
                for n in ("CalStatus", "CalSource", "CalCount", "CalStored")]
    cal_page_sig = cal_def.get_signal_by_name("CalPage")
    counts, last, modes = Counter(), {}, Counter()
    flags_seen, cal_seen = 0, set()
    t_first_nav = t_last = None
    mode_changes, cal_changes = [], []      # (t, raw value(s)) where they change
    with open(out_log) as f:
        for line in f:
            parts = line.split()
            if len(parts) < 3:
                continue
            t = float(parts[0].strip("()"))
            fid_s, data_s = parts[2].split("#")
            fid, data = int(fid_s, 16), bytes.fromhex(data_s)
            counts[fid] += 1
            t_last = t
            key = fid
            word = int.from_bytes(data, "little")
            if fid == st_def.frame_id:
                page = _raw(page_sig, word)
                key = (fid, page)
                if page == 0:
                    mode = _raw(mode_sig, word)
                    modes[mode] += 1
                    flags_seen |= _raw(flags_sig, word)
                    if not mode_changes or mode_changes[-1][1] != mode:
                        mode_changes.append((t, mode))
            elif fid == cal_def.frame_id:
                # pages 1 and 2 (the automatic mounting estimate) are not the calibration
                page = _raw(cal_page_sig, word)
                if page != 0:
                    key = (fid, page)  # left out of "final" (page 0 keeps its place)
                else:
                    cal = tuple(_raw(s, word) for s in cal_sigs)
                    cal_seen.add(cal[0])
                    if not cal_changes or cal_changes[-1][1] != cal:
                        cal_changes.append((t, cal))
            elif fid == pos_id and t_first_nav is None:
                t_first_nav = t
            last[key] = data
    bits = nc.health_bits(db)
    mode_names = nc.choices(db, "NAV_Status", "Mode")
    cal_names = nc.choices(db, "NAV_Calibration", "CalStatus")
    src_names = nc.choices(db, "NAV_Calibration", "CalSource")
    final = {}
    for key, data in sorted(last.items(), key=lambda kv: str(kv[0])):
        fid = key[0] if isinstance(key, tuple) else key
        if fid not in defs or (isinstance(key, tuple) and key[1] != 0):
            continue
        values = _decode(db, defs[fid], data)
        if fid == st_def.frame_id:
            values["HealthFlags"] = _flag_names(bits, _raw(flags_sig,
                                                           int.from_bytes(data, "little")))
        if fid == cal_def.frame_id:
            values.pop("CalPage", None)  # page 0, the frame of before the pages
        final[defs[fid].name] = values
    counters = {}
    pages = nc.status_signals(db)
    for name in sorted(pages, key=lambda n: (pages[n], st_def.get_signal_by_name(n).start)):
        data = last.get((st_def.frame_id, pages[name]))
        if data is not None:
            counters[name] = int(db.decode_message(st_def.frame_id, data)[name])
    return {
        "frames": {defs[fid].name if fid in defs else f"0x{fid:03X}": n
                   for fid, n in sorted(counts.items())},
        "first_nav_position_s": t_first_nav, "last_frame_s": t_last,
        "status_modes": {mode_names.get(m, str(m)): n for m, n in sorted(modes.items())},
        "mode_timeline": _timeline([f"{t:g} {mode_names.get(m, m)}" for t, m in mode_changes]),
        "calibration_timeline": _timeline([
            f"{t:g} {cal_names.get(c[0], c[0])}, source {src_names.get(c[1], c[1])}, count "
            f"{c[2]}, stored {c[3]}" for t, c in cal_changes]),
        "health_flags_seen": _flag_names(bits, flags_seen),
        "cal_status_seen": [cal_names.get(c, str(c)) for c in sorted(cal_seen)],
        "final": final,
        "counters": counters,
    }


# ==================================================================== running a case
def input_log(case: dict, cases_dir: Path, work: Path) -> Path:
    """The case's input, decompressed into work/inputs/ (once per content)."""
    src = cases_dir / case["input"]
    name = src.name[:-3] if src.name.endswith(".xz") else src.name
    dst = work / "inputs" / name
    stamp = dst.with_name(dst.name + ".src-sha256")
    if not src.is_file():
        raise CaseFileError(f"{src}: case {case['name']}'s input is missing")
    src_sha = sha256(src)
    if not (dst.exists() and stamp.exists() and stamp.read_text() == src_sha):
        dst.parent.mkdir(parents=True, exist_ok=True)
        data = src.read_bytes()
        try:
            dst.write_bytes(lzma.decompress(data) if src.name.endswith(".xz") else data)
        except lzma.LZMAError as e:
            raise CaseFileError(f"{src}: case {case['name']}'s input does not decompress: "
                                f"{e}") from None
        stamp.write_text(src_sha)
    return dst


def run_case(case: dict, navecu: Path, cases_dir: Path, work: Path, tag: str = "") -> dict:
    """Run one case; its record (module docstring)."""
    log = input_log(case, cases_dir, work)
    out_dir = work / (case["name"] + tag)
    if out_dir.exists():
        shutil.rmtree(out_dir)
    out_dir.mkdir(parents=True)
    out = out_dir / "out.log"
    cmd = [str(navecu), "--can-log", str(log), "--out", str(out)] + shlex.split(case["args"])
    nvm = None
    if case.get("nvm"):
        nvm = out_dir / "nvm.bin"
        if case["nvm"] != "fresh":
            shutil.copyfile(cases_dir / case["nvm"], nvm)
        cmd += ["--nvm", str(nvm)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    (out_dir / "stderr.txt").write_text(res.stderr)
    rec = {"input": case["input"], "input_sha256": sha256(log),
           "args": case["args"], "nvm": case.get("nvm"), "exit_status": res.returncode,
           "output_sha256": sha256(out) if out.exists() else None,
           "data_output_sha256": data_sha256(out) if out.exists() else None,
           "nvm_sha256": sha256(nvm) if nvm is not None and nvm.exists() else None}
    summary = summarize(out) if out.exists() else {}
    summary["navecu"] = [ln.removeprefix("navecu: ") for ln in res.stderr.strip().splitlines()]
    rec["summary"] = summary
    return rec


# ==================================================================== comparing
def _lines(x) -> list:
    return json.dumps(x, indent=2, sort_keys=False).splitlines()


def differences(expected: dict, got: dict) -> list:
    """The lines that tell a reader how a case's record differs from the expected one
    (empty if it does not)."""
    if expected == got:
        return []
    out = []
    for key in ("input_sha256", "args", "nvm"):
        if expected.get(key) != got.get(key):
            out.append(f"  {key}: the case itself changed (expected {expected.get(key)!r}, now "
                       f"{got.get(key)!r}): not a firmware change; regenerate the expected "
                       "file if the case was changed on purpose")
    for key, what in (("exit_status", "navecu's exit status"),
                      ("output_sha256", "the output log (sha256)"),
                      ("data_output_sha256", "the output log without NAV_Heartbeat (sha256)"),
                      ("nvm_sha256", "the NVM after the run (sha256)")):
        if expected.get(key) != got.get(key):
            out.append(f"  {what}: expected {expected.get(key)}, now {got.get(key)}")
    diff = list(difflib.unified_diff(_lines(expected.get("summary")), _lines(got.get("summary")),
                                     "expected summary", "this firmware's summary", lineterm="",
                                     n=2))
    if diff:
        out.append("  summary diff:")
        out += ["    " + d for d in diff]
    elif expected.get("output_sha256") != got.get("output_sha256"):
        out.append("  the summary is the same: frames differ that it does not show (values "
                   "in the middle of the drive; compare build/regression/<case>/out.log with "
                   "a run of the previous firmware)")
    other = sorted(k for k in set(expected) | set(got)
                   if expected.get(k) != got.get(k) and k not in (
                       "input_sha256", "args", "nvm", "exit_status", "output_sha256",
                       "data_output_sha256", "nvm_sha256", "summary"))
    if other:
        out.append(f"  also differs: {', '.join(other)}")
    return out


def check(cases: list, expected: dict, navecu: Path, cases_dir: Path, work: Path,
          only=None) -> int:
    names = [c["name"] for c in cases]
    failed = []
    for name in sorted(set(expected) - set(names)):
        if not only:
            print(f"regression: {name}: in expected.json but not in cases.json")
            failed.append(name)
    for case in cases:
        if only and case["name"] not in only:
            continue
        t = time.monotonic()
        got = run_case(case, navecu, cases_dir, work)
        exp = expected.get(case["name"])
        if exp is None:
            print(f"regression: {case['name']}: FAIL, no expected record (make "
                  "regression-update)")
            failed.append(case["name"])
            continue
        diff = differences(exp, got)
        if diff:
            print(f"regression: {case['name']}: FAIL (output in {work / case['name']})")
            print("\n".join(diff))
            failed.append(case["name"])
        else:
            print(f"regression: {case['name']}: ok ({time.monotonic() - t:.2f} s, output "
                  f"{got['output_sha256'][:12]})")
    if failed:
        print(f"regression: FAILED: {', '.join(failed)} differ from "
              f"{cases_dir / 'expected.json'}.\n{UPDATE_HINT}")
        return 1
    print(f"regression: PASS, {len(cases) if not only else len(only)} cases identical to "
          f"{cases_dir.relative_to(ROOT) if cases_dir.is_relative_to(ROOT) else cases_dir}"
          "/expected.json")
    return 0


def update(cases: list, navecu: Path, cases_dir: Path, work: Path) -> int:
    records = {}
    for case in cases:
        a = run_case(case, navecu, cases_dir, work)
        b = run_case(case, navecu, cases_dir, work, tag=".again")
        diff = differences(a, b)
        if diff:
            print(f"regression: {case['name']}: two runs differ, the output is not "
                  "deterministic; expected.json not written:\n" + "\n".join(diff))
            return 1
        shutil.rmtree(work / (case["name"] + ".again"))
        records[case["name"]] = a
        print(f"regression: {case['name']}: output {a['output_sha256'][:12]}, exit "
              f"{a['exit_status']} (twice the same)")
    path = cases_dir / "expected.json"
    old = json.loads(path.read_text()) if path.exists() else {}
    path.write_text(to_json(records) + "\n")
    changed = sorted(n for n in records if old.get(n) != records[n])
    print(f"regression: {path} written; changed: {', '.join(changed) if changed else 'none'}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("command", choices=("check", "update"))
    ap.add_argument("--case", nargs="+", default=None, metavar="NAME",
                    help="check only these cases")
    ap.add_argument("--navecu", default=str(NAVECU))
    ap.add_argument("--cases-dir", default=str(CASES_DIR),
                    help="the folder of cases.json, expected.json and inputs/")
    ap.add_argument("--work", default=str(WORK), help="where inputs and outputs go")
    a = ap.parse_args(argv)
    navecu, cases_dir, work = Path(a.navecu), Path(a.cases_dir), Path(a.work)
    if not navecu.exists():
        print(f"regression: no firmware at {navecu} (make build/host/navecu)", file=sys.stderr)
        return 2
    try:
        return _main(a, ap, navecu, cases_dir, work)
    except CaseFileError as e:
        print(f"regression: {e}", file=sys.stderr)
        return 2


def _main(a, ap, navecu: Path, cases_dir: Path, work: Path) -> int:
    cases = load_cases(cases_dir)
    if a.case:
        unknown = set(a.case) - {c["name"] for c in cases}
        if unknown:
            ap.error(f"no case {', '.join(sorted(unknown))} (cases: "
                     + ", ".join(c["name"] for c in cases) + ")")
    if a.command == "update":
        if a.case:
            ap.error("update rewrites every case: no --case")
        return update(cases, navecu, cases_dir, work)
    path = cases_dir / "expected.json"
    expected = read_json(path) if path.exists() else {}
    return check(cases, expected, navecu, cases_dir, work, a.case)


if __name__ == "__main__":
    sys.exit(main())
