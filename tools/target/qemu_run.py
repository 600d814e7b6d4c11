"""The Cortex-M4F image on QEMU against the host float32 build (`make target-test`,
`make target-bench`; docs/target.md).

    python -m tools.target.qemu_run --check [--bench] [--json out/target-bench.json]
                                    [--scenario target10] [--out out/target]

1. The simulator writes the scenario's CAN log (tools/sim/run.py; default: target10, the
   10-minute figure-eight with a GNSS outage).
2. The host firmware replays it: build/host/navecu --can-log IN --out host.log (default
   configuration).
3. The M4F image replays it on QEMU's netduinoplus2 (an STM32F405 with a Cortex-M4F),
   reading IN and writing qemu.log through semihosting (build/target/navecu-qemu.elf).
--check: qemu.log must equal host.log line for line, byte for byte, in every frame but
   NAV_Heartbeat's, the one time-driven output (navecu_can.data_driven: in these file runs
   it follows the log's timestamps and agrees too, which is said, but it is not the
   identity checked). On a difference the first differing lines are printed and the exit
   status is 1.
--bench: the QEMU run uses -icount shift=0 (1 ns of virtual time per instruction) and the
   image writes the SysTick ticks spent on every frame; they become instruction counts per
   IMU step and per measurement update and an estimated CPU load, written to --json. Exit
   status 1 when the load at 200 Hz on a 168 MHz M4F exceeds --max-load-pct (5).
"""
from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from tools import navecu_can

ROOT = Path(__file__).resolve().parents[2]
TARGET_DIR = ROOT / "build" / "target"   # make VEHICLE=NAME: build/target-NAME
NAVECU = ROOT / "build" / "host" / "navecu"

GNSS_MESSAGES = ("GNSS_Position", "GNSS_Velocity", "GNSS_Status", "GNSS_Height")


def frame_ids(vehicle: str | None = None) -> dict:
    """The identifiers the bench times, as the build of vehicle profile `vehicle` (None:
    native) receives them: navecu's IMU_Rate, IMU_Accel and GNSS fix messages at the
    profile's identifiers (a profile may move them all: vw_mqb's base 0x6C0), and the wheel
    speeds: navecu's WheelSpeeds, or the car's own wheel-speed message(s) (one, or the front
    axle's and the rear's)."""
    ids = {m.name: m.frame_id for m in navecu_can.load_db(navecu_can.DBC_PATH).messages}
    wheels = {ids["WheelSpeeds"]}
    if vehicle not in (None, "native"):
        from tools import vehicle as veh
        profile = veh.load(vehicle)
        ids = profile.can_ids
        if profile.wheel_reads():
            wheels = {r.message.frame_id for r in profile.wheel_reads()}
    return {"imu_rate": ids["IMU_Rate"], "imu_accel": ids["IMU_Accel"], "wheels": wheels,
            "gnss": {ids[n] for n in GNSS_MESSAGES}}


# Cycles per instruction assumed for the STM32F405 at 168 MHz (docs/target.md): the M4's
# integer and single-precision FPU instructions issue in 1 cycle, loads/stores take 2 (1
# when pipelined back to back), taken branches 2-4 (pipeline refill), VDIV/VSQRT 14; flash
# runs with 5 wait states behind the ART accelerator (prefetch + 1 KiB instruction cache,
# which holds this loop-heavy code). 1.5 covers the branch and load/store mix of
# compiled float code with margin; the budget is also reported at a pessimistic 2.0.
CPI_ASSUMED = 1.5
CPI_PESSIMISTIC = 2.0
CPU_HZ = 168e6
IMU_HZ_BUDGET = 200.0


def run(cmd, **kw):
    return subprocess.run([str(c) for c in cmd], check=False, capture_output=True, text=True,
                          **kw)


APP_START = 0x0800C000  # firmware/boot/boot_image.h BOOT_APP_START


def machine(app_bin: Path, boot_elf: Path | None = None) -> list:
    """netduinoplus2 as the ECU's flash holds it (docs/target.md): the bootloader in sector 0
    (boot.elf, what the CPU's reset starts) and an application image at 0x0800C000 (QEMU's
    generic loader writes it into the flash before reset). The bootloader checks the
    image's marker and CRC-32 and starts it; an application image without its marker
    (navecu-qemu.bin instead of navecu-qemu-app.bin) is not started."""
    boot_elf = boot_elf or app_bin.parent / "boot.elf"
    return ["qemu-system-arm", "-M", "netduinoplus2", "-nographic", "-monitor", "none",
            "-serial", "none", "-kernel", str(boot_elf),
            "-device", f"loader,file={app_bin},addr=0x{APP_START:08X}"]


def qemu_cmd(app_bin: Path, in_log: Path, out_log: Path, trace: Path | None) -> list:
    args = ["navecu", in_log, out_log] + ([trace] if trace else [])
    semi = "enable=on,target=native," + ",".join(f"arg={a}" for a in args)
    cmd = machine(app_bin) + ["-semihosting-config", semi]
    if trace:
        cmd[1:1] = ["-icount", "shift=0"]
    return cmd


def first_difference(a: Path, b: Path, n_show: int = 3) -> str:
    la = navecu_can.data_driven(a.read_text().splitlines())
    lb = navecu_can.data_driven(b.read_text().splitlines())
    out = [f"{a.name}: {len(la)} lines, {b.name}: {len(lb)} lines"]
    shown = 0
    for i, (x, y) in enumerate(zip(la, lb)):
        if x != y:
            out.append(f"  line {i + 1}:\n    {a.name}: {x}\n    {b.name}: {y}")
            shown += 1
            if shown == n_show:
                break
    return "\n".join(out)


def boot_ecu(ecu_app: Path, seconds: float = 2.0) -> tuple[bool, str]:
    """The ECU image (build/target/navecu-app.bin behind boot.elf) booted on netduinoplus2 for `seconds` of wall
    time under -icount (virtual time runs from instructions, so a slow machine only runs
    fewer of them): QEMU emulates no RCC, so the clock setup times out and the board runs
    on without CAN, but startup, the drivers' bounded waits, the watchdog and the main loop
    with its SysTick wake-ups all run. It must take interrupts (IRQ entries and exception
    returns only) and no other exception: QEMU logs a fault as e.g. "[Data Abort]",
    "[Prefetch Abort]", "[Undefined Instruction]" or a v7M fault kind, and default_handler
    then resets the ECU (board_fault), which would show as a second boot."""
    cmd = machine(ecu_app) + ["-icount", "shift=0,sleep=off", "-d", "int"]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=seconds)
        log = r.stderr
    except subprocess.TimeoutExpired as e:
        log = (e.stderr or b"").decode(errors="replace") if isinstance(e.stderr, bytes) \
            else (e.stderr or "")
    taken = [ln.strip() for ln in log.splitlines() if "Taking exception" in ln]
    irqs = [ln for ln in taken if "[IRQ]" in ln]
    faults = [ln for ln in taken if "[IRQ]" not in ln and "exception exit" not in ln.lower()]
    # interrupts still coming in the last quarter of the log: the loop is alive at the end
    tail = taken[len(taken) * 3 // 4:]
    alive = any("[IRQ]" in ln for ln in tail)
    ok = not faults and len(irqs) >= 10 and alive
    return ok, (f"{len(irqs)} interrupts taken, {len(faults)} other exceptions"
                + (f" (first: {faults[0]})" if faults else "")
                + ("" if alive else ", no interrupt at the end"))


def read_trace(path: Path):
    """(instructions per tick, ids, ticks, updates) from the image's trace file."""
    lines = path.read_text().splitlines()
    head = lines[0].split()
    if head[0] != "calibration":
        raise SystemExit(f"{path}: no calibration line")
    insn_per_tick = int(head[1]) / int(head[2])
    points = {}
    frames = []
    for ln in lines[1:]:
        p = ln.split()
        if p[0] == "point":
            n, total, mx = int(p[2]), int(p[3]), int(p[4])
            points[p[1]] = {"n": n, "mean": insn_per_tick * total / max(n, 1),
                            "max": insn_per_tick * mx}
        else:
            frames.append([int(p[0], 16), int(p[1]), int(p[2])])
    rows = np.array(frames, dtype=np.int64)
    return insn_per_tick, rows[:, 0], rows[:, 1], rows[:, 2], points


def stats(x: np.ndarray) -> dict:
    return {"n": int(x.size), "mean": float(x.mean()) if x.size else 0.0,
            "max": float(x.max()) if x.size else 0.0,
            "p99": float(np.percentile(x, 99)) if x.size else 0.0}


def bench(trace: Path, duration_s: float, imu_rate_hz: float, fids: dict | None = None) -> dict:
    """The instruction counts of the trace; fids: frame_ids() of the build's profile
    (default: native's)."""
    fids = frame_ids() if fids is None else fids
    ipt, ids, ticks, upd, points = read_trace(trace)
    insn = ticks * ipt
    # IMU step: the IMU_Rate frame and the IMU_Accel frame that completes the sample (the
    # strapdown step; on every 10th the filter's prediction, odometer or standstill update
    # and feedback; the NAV outputs). The updates come from the profiling points of app.h
    # (app_trace), timed inside the image.
    acc = np.flatnonzero(ids == fids["imu_accel"])
    acc = acc[(acc > 0) & (ids[np.maximum(acc - 1, 0)] == fids["imu_rate"])]
    if acc.size == 0:
        raise SystemExit(f"{trace}: no IMU step (IMU_Rate 0x{fids['imu_rate']:03X} then "
                         f"IMU_Accel 0x{fids['imu_accel']:03X}): not the trace of this profile?")
    imu_step = insn[acc] + insn[acc - 1]
    wheel = insn[np.isin(ids, list(fids["wheels"]))]
    gnss_frames = insn[np.isin(ids, list(fids["gnss"]))]
    insn_per_s = float(insn.sum()) / duration_s
    step = stats(imu_step)

    # At 200 Hz with the same configuration (NAV outputs at 50 Hz, the filter at 10 Hz,
    # GNSS and wheel frames as they come), 100 more IMU samples a second, each a bare step
    # (decode, E2E, strapdown; no output, no filter work): the 25th percentile of the step
    # costs, which lies in that class (about half of the steps at 100 Hz). Also reported:
    # every per-sample cost doubled, outputs and filter included (an upper bound).
    bare_step = float(np.percentile(imu_step, 25))
    insn_per_s_200 = insn_per_s + (IMU_HZ_BUDGET - imu_rate_hz) * bare_step
    insn_per_s_200_doubled = insn_per_s + (IMU_HZ_BUDGET - imu_rate_hz) * step["mean"]

    def load(cpi: float, ips: float) -> float:
        return 100.0 * ips * cpi / CPU_HZ

    return {
        "insn_per_imu_step_mean": round(step["mean"], 1),
        "insn_per_imu_step_max": round(step["max"], 1),
        "insn_per_imu_step_p99": round(step["p99"], 1),
        "insn_per_gnss_update": round(points["gnss_update"]["mean"], 1),
        "insn_per_gnss_update_max": round(points["gnss_update"]["max"], 1),
        "insn_per_odo_update": round(points["odometer_update"]["mean"], 1),
        "insn_per_odo_update_max": round(points["odometer_update"]["max"], 1),
        "insn_per_mechanization_mean": round(points["mechanization"]["mean"], 1),
        "insn_per_mechanization_max": round(points["mechanization"]["max"], 1),
        "insn_per_prediction_mean": round(points["prediction"]["mean"], 1),
        "insn_per_prediction_max": round(points["prediction"]["max"], 1),
        "insn_per_wheel_frame_mean": round(float(wheel.mean()), 1) if wheel.size else None,
        "insn_per_gnss_frame_max": round(float(gnss_frames.max()), 1) if gnss_frames.size else None,
        "n_imu_steps": step["n"], "n_gnss_updates": points["gnss_update"]["n"],
        "n_odo_updates": points["odometer_update"]["n"],
        "n_predictions": points["prediction"]["n"],
        "insn_per_s_measured": round(insn_per_s, 0),
        "imu_rate_hz_measured": imu_rate_hz,
        "insn_per_bare_imu_step": round(bare_step, 1),
        "insn_per_s_200hz": round(insn_per_s_200, 0),
        "insn_per_s_200hz_all_doubled": round(insn_per_s_200_doubled, 0),
        "cpi_assumed": CPI_ASSUMED,
        "cpi_note": "cycles per instruction assumed for an STM32F405 at 168 MHz: 1-cycle "
                    "ALU/FPU ops, 2-cycle loads/stores, 2-4-cycle taken branches, 14-cycle "
                    "VDIV/VSQRT, flash wait states hidden by the ART cache; docs/target.md",
        "cpu_load_pct_200hz_168mhz": round(load(CPI_ASSUMED, insn_per_s_200), 3),
        "cpu_load_pct_200hz_168mhz_cpi2": round(load(CPI_PESSIMISTIC, insn_per_s_200), 3),
        "cpu_load_pct_200hz_168mhz_all_doubled": round(load(CPI_ASSUMED, insn_per_s_200_doubled), 3),
        "cpu_load_pct_measured_rate": round(load(CPI_ASSUMED, insn_per_s), 3),
        "insn_per_tick_calibrated": round(ipt, 4),
        "worst_frame_insn": round(float(insn.max()), 1),
        "worst_frame_id": hex(int(ids[int(np.argmax(insn))])),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default="target10")
    ap.add_argument("--out", default=str(ROOT / "out" / "target"))
    ap.add_argument("--check", action="store_true", help="QEMU output == host output")
    ap.add_argument("--bench", action="store_true", help="instruction counts (icount)")
    ap.add_argument("--json", default=None, help="bench results (with --bench)")
    ap.add_argument("--max-load-pct", type=float, default=5.0)
    ap.add_argument("--timeout-s", type=float, default=600.0)
    ap.add_argument("--target-dir", default=str(TARGET_DIR),
                    help="the images' folder (make VEHICLE=NAME: build/target-NAME)")
    ap.add_argument("--navecu", default=str(NAVECU), help="the host build of the same profile")
    ap.add_argument("--vehicle", default=None,
                    help="the vehicle profile of the build (default: the host executable's)")
    a = ap.parse_args(argv)
    qemu_app = Path(a.target_dir) / "navecu-qemu-app.bin"  # behind boot.elf
    ecu_app = Path(a.target_dir) / "navecu-app.bin"
    navecu = Path(a.navecu)
    vehicle = a.vehicle or (navecu.name.split("-", 1)[1] if "-" in navecu.name else None)
    if not (a.check or a.bench):
        ap.error("give --check and/or --bench")
    if shutil.which("qemu-system-arm") is None:
        print("qemu_run: qemu-system-arm not found (Debian: apt-get install qemu-system-arm)",
              file=sys.stderr)
        return 1
    for f in (qemu_app, navecu):
        if not f.exists():
            print(f"qemu_run: {f} missing (make target-qemu build/host/navecu)", file=sys.stderr)
            return 1
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    in_log = out / "can_in.log"

    from tools.sim import run as sim_run
    print(f"== scenario {a.scenario}: simulated CAN log")
    if sim_run.main(["--scenario", a.scenario, "--out", str(out), "--navecu", str(navecu)]
                    + (["--vehicle", vehicle] if vehicle else [])) != 0:
        return 1

    host_log = out / "host.log"
    r = run([navecu, "--can-log", in_log, "--out", host_log])
    if r.returncode != 0:
        print(r.stderr, file=sys.stderr)
        return 1
    print(f"== host float32: {r.stderr.splitlines()[0]}")
    # "... 61638 IMU samples (616.4 s), ...": samples and IMU time give the IMU rate
    head = r.stderr.split(" IMU samples (", 1)
    n_samples = int(head[0].split()[-1])
    duration_s = float(head[1].split(" s)", 1)[0])

    qemu_log = out / "qemu.log"
    trace = out / "trace.txt" if a.bench else None
    t0 = time.monotonic()
    r = run(qemu_cmd(qemu_app, in_log, qemu_log, trace), timeout=a.timeout_s)
    wall = time.monotonic() - t0
    print(f"== QEMU netduinoplus2 ({wall:.1f} s): {r.stderr.strip() or r.stdout.strip()}")
    if r.returncode != 0:
        print(f"qemu_run: QEMU exited with {r.returncode}", file=sys.stderr)
        return 1

    status = 0
    if a.check and ecu_app.exists():
        ok, what = boot_ecu(ecu_app)
        print(f"target-test: the ECU image on netduinoplus2 for 2 s (icount): {what}: "
              f"{'PASS' if ok else 'FAIL'}")
        status |= 0 if ok else 1
    if a.check:
        q_all, h_all = qemu_log.read_text().splitlines(), host_log.read_text().splitlines()
        q_data, h_data = navecu_can.data_driven(q_all), navecu_can.data_driven(h_all)
        if q_data == h_data:
            hb = (f"NAV_Heartbeat (time-driven) left out: {len(q_all) - len(q_data)} on QEMU, "
                  f"{len(h_all) - len(h_data)} on the host, "
                  + ("the same" if q_all == h_all else "not the same"))
            print(f"target-test: PASS, {len(q_data)} output frames of the Cortex-M4F (QEMU) "
                  f"identical byte for byte to the host float32 run ({hb})")
        else:
            print("target-test: FAIL, the QEMU output differs from the host's:\n"
                  + first_difference(host_log, qemu_log), file=sys.stderr)
            status = 1
    if a.bench:
        res = bench(trace, duration_s, round(n_samples / duration_s), frame_ids(vehicle))
        res.update({"scenario": a.scenario, "qemu_machine": "netduinoplus2",
                    "qemu_version": run(["qemu-system-arm", "--version"]).stdout.split("\n")[0],
                    "method": "QEMU -icount shift=0 (1 instruction = 1 ns of virtual time); "
                              "SysTick at 168 MHz read around app_handle_frame + app_poll "
                              "(per frame) and at the app_trace points (per step); ticks to "
                              "instructions by a calibration loop of 2e6 instructions "
                              "(one tick = 5.95 instructions: +-6 per reading)",
                    "command": "make target-bench"})
        print(json.dumps(res, indent=2))
        if a.json:
            Path(a.json).parent.mkdir(parents=True, exist_ok=True)
            Path(a.json).write_text(json.dumps(res, indent=2) + "\n")
            print(f"target-bench: written {a.json}")
        if res["cpu_load_pct_200hz_168mhz"] > a.max_load_pct:
            print(f"target-bench: FAIL, CPU load {res['cpu_load_pct_200hz_168mhz']} % at 200 Hz "
                  f"exceeds {a.max_load_pct} %", file=sys.stderr)
            status = 1
        else:
            print(f"target-bench: CPU load {res['cpu_load_pct_200hz_168mhz']} % at 200 Hz on a "
                  f"168 MHz M4F (CPI {CPI_ASSUMED}; {res['cpu_load_pct_200hz_168mhz_cpi2']} % at "
                  f"CPI {CPI_PESSIMISTIC}; {res['cpu_load_pct_200hz_168mhz_all_doubled']} % with "
                  f"every per-sample cost doubled), budget {a.max_load_pct} %")
    return status


if __name__ == "__main__":
    sys.exit(main())
