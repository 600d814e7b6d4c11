#!/usr/bin/env bash
# Benchmark (not a test): how fast the firmware takes a CAN log over vcan0 without losing a
# frame. A stationary log of N seconds is replayed with tools/can_replay.py --fastest (flow
# control on the firmware's NAV_Status page 0) into build/host/navecu --can vcan0 while a
# recorder keeps its output (inside User-Mode Linux where the host kernel has no CAN), R
# times. Writes out/bench/fastest_vcan.json, one line per run: frames/s, waits, the longest
# pause, and the firmware's losses. Usage: tools/bench/fastest_vcan.sh [seconds] [runs]
set -euo pipefail
cd "$(dirname "$0")/../.."
dur=${1:-300}
runs=${2:-3}
mkdir -p out/bench
log=out/bench/fastest_input.log
.venv/bin/python -m tools.gen_stationary_log --out "$log" --duration-s "$dur" >/dev/null
: > out/bench/fastest_vcan.json
for _ in $(seq "$runs"); do
    tools/vcan/with_vcan.sh .venv/bin/python -m tools.vcan.live_check --fastest --no-frames \
        --log "$log" 2>/dev/null | tail -1 | .venv/bin/python -c '
import json, re, sys
r = json.loads(sys.stdin.read())
rp = r["replay"]
m = re.search(r"rejected: (.*)", r["firmware_summary"])
print(json.dumps({"frames": rp["sent"], "seconds": round(rp["seconds"], 2),
                  "frames_per_s": round(rp["sent"] / rp["seconds"]), "window": rp["window"],
                  "waits": rp["waits"], "max_wait_ms": rp["max_wait_ms"],
                  "keepalives": rp["keepalives"], "max_ack_gap_ms": rp["max_ack_gap_ms"],
                  "stale_status": rp["stale_status"], "recorded": r["recorded"],
                  "firmware_rejected": m.group(1) if m else None}))' \
        | tee -a out/bench/fastest_vcan.json
done
