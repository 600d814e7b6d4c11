#!/usr/bin/env bash
# Benchmark (not a test): latency from an IMU sample's last frame (IMU_Accel) to the
# NAV_Position it causes, both stamped by the kernel on a receiving socket, over vcan0 at
# real-time replay (inside User-Mode Linux where the host kernel has no CAN).
# Writes out/bench/latency_vcan.json. Usage: tools/bench/latency_vcan.sh [seconds]
set -euo pipefail
cd "$(dirname "$0")/../.."
dur=${1:-60}
mkdir -p out/bench
log=out/bench/latency_input.log
.venv/bin/python -m tools.gen_stationary_log --out "$log" --duration-s "$dur" >/dev/null
tools/vcan/with_vcan.sh sh -c ".venv/bin/python -m tools.vcan.live_check --latency --log $log" \
    | tail -1 > out/bench/latency_vcan.json
cat out/bench/latency_vcan.json
