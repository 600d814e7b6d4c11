#!/usr/bin/env python3
"""Run the libFuzzer harnesses one after the other (make fuzz).

For each harness NAME: copy its committed seed corpus tests/fuzz/corpus/NAME/ to
BUILD/corpus/NAME/ (so a run never modifies the repository), run BUILD/NAME on it for
--seconds with -print_final_stats=1 (log in BUILD/logs/NAME.log, crash files in
BUILD/crashes/NAME/), and print one summary line:

    fuzz: fuzz_codec  60 s  12345678 runs  205761 exec/s  cov 312  ft 904  corpus 230  OK

exec/s is stat::number_of_executed_units / the seconds the run took. The same figures go
to --json. Exit status 1 if any harness crashed (or timed out, ran out of memory, or
failed to start), each with the path of its crash file; else 0. Standard library only.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time

# per-harness libFuzzer options: the log reader wants whole files, the app long sequences
OPTIONS = {
    "fuzz_candump": ["-max_len=2048", "-dict=tests/fuzz/candump.dict"],
    "fuzz_app": ["-max_len=4096"],
    "fuzz_options": ["-max_len=4096"],
    "fuzz_calstore": ["-max_len=300"],
    "fuzz_codec": ["-max_len=512"],
    "fuzz_isotp": ["-max_len=4096"],
}


def run_one(name, build, corpus_root, seconds):
    binary = os.path.join(build, name)
    corpus = os.path.join(build, "corpus", name)
    crashes = os.path.join(build, "crashes", name)
    logs = os.path.join(build, "logs")
    shutil.rmtree(corpus, ignore_errors=True)
    seeds = os.path.join(corpus_root, name)
    if os.path.isdir(seeds):
        shutil.copytree(seeds, corpus)
    else:
        os.makedirs(corpus)
    os.makedirs(crashes, exist_ok=True)
    os.makedirs(logs, exist_ok=True)
    log_path = os.path.join(logs, name + ".log")
    opts = [o for o in OPTIONS.get(name, []) if not o.startswith("-dict=") or os.path.exists(o[6:])]
    cmd = [binary, f"-max_total_time={seconds}", "-print_final_stats=1", "-timeout=25",
           "-rss_limit_mb=2560", f"-artifact_prefix={crashes}/", *opts, corpus]
    t0 = time.monotonic()
    with open(log_path, "w", encoding="utf-8", errors="replace") as log:
        rc = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT)
    elapsed = time.monotonic() - t0
    text = open(log_path, encoding="utf-8", errors="replace").read()
    units = re.findall(r"stat::number_of_executed_units:\s*(\d+)", text)
    units = int(units[-1]) if units else 0
    cov = re.findall(r"cov: (\d+) ft: (\d+) corp: (\d+)", text)
    crash = re.findall(r"Test unit written to (\S+)", text)
    reason = re.findall(r"(ERROR: (?:AddressSanitizer|libFuzzer|UndefinedBehaviorSanitizer)[^\n]*"
                        r"|SUMMARY: [^\n]*|runtime error: [^\n]*|FUZZ INVARIANT VIOLATED: [^\n]*)",
                        text)
    run_s = max(min(elapsed, float(seconds) + 5.0), 1e-3)
    return {
        "name": name,
        "seconds": round(elapsed, 1),
        "units": units,
        "exec_per_s": round(units / run_s, 1),
        "cov": int(cov[-1][0]) if cov else None,
        "ft": int(cov[-1][1]) if cov else None,
        "corpus": int(cov[-1][2]) if cov else None,
        "exit_code": rc,
        "ok": rc == 0 and not crash,
        "crash_file": crash[-1] if crash else None,
        "reason": reason[0] if reason else None,
        "log": log_path,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", required=True, help="directory of the harness binaries")
    ap.add_argument("--corpus", required=True, help="root of the committed seed corpora")
    ap.add_argument("--seconds", type=int, default=60)
    ap.add_argument("--json", required=True)
    ap.add_argument("names", nargs="+")
    a = ap.parse_args()
    results = []
    for name in a.names:
        r = run_one(name, a.build, a.corpus, a.seconds)
        results.append(r)
        status = "OK" if r["ok"] else f"CRASH: {r['crash_file'] or 'exit ' + str(r['exit_code'])}"
        print(f"fuzz: {name:14s} {r['seconds']:5.0f} s {r['units']:10d} runs "
              f"{r['exec_per_s']:10.0f} exec/s  cov {r['cov']}  ft {r['ft']}  "
              f"corpus {r['corpus']}  {status}", flush=True)
        if not r["ok"]:
            print(f"fuzz: {name}: {r['reason'] or 'see ' + r['log']}", flush=True)
    os.makedirs(os.path.dirname(os.path.abspath(a.json)), exist_ok=True)
    with open(a.json, "w", encoding="utf-8") as f:
        json.dump({"seconds_each": a.seconds, "harnesses": results}, f, indent=2)
        f.write("\n")
    bad = [r for r in results if not r["ok"]]
    if bad:
        for r in bad:
            print(f"fuzz: FAILED {r['name']}: crash file {r['crash_file'] or '(none)'} "
                  f"(log {r['log']}); replay: {os.path.join(a.build, r['name'])} "
                  f"{r['crash_file'] or ''}")
        return 1
    print(f"fuzz: all {len(results)} harnesses ran {a.seconds} s without a crash "
          f"({a.json})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
