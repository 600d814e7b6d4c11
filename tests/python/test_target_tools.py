"""The arithmetic of the M4F tools on inputs with known answers: the instruction counts of
tools/target/qemu_run.py from a trace, the memory accounting of tools/target/budget.py."""
from pathlib import Path

import pytest

from tools.target import budget, qemu_run


def write_trace(path: Path, n_steps: int, insn_per_tick: int = 6) -> None:
    lines = [f"calibration {2000 * insn_per_tick} 2000"]
    for k in range(n_steps):
        lines.append("100 10 0")                                  # IMU_Rate: 10 ticks
        lines.append(f"101 {100 if k % 10 else 1000} {1 if k % 10 == 0 else 0}")
        if k % 100 == 0:
            lines.append("120 50 0")
            lines.append("121 70 5")                              # the GNSS update
    lines += ["point mechanization 100 3000 31", "point prediction 10 8000 801",
              "point odometer_update 10 5000 500", "point gnss_update 1 60 60"]
    path.write_text("\n".join(lines) + "\n")


def test_bench_turns_ticks_into_instructions(tmp_path):
    trace = tmp_path / "trace.txt"
    write_trace(trace, 100)
    r = qemu_run.bench(trace, duration_s=1.0, imu_rate_hz=100.0)
    # steps: 90 of (10 + 100) ticks, 10 of (10 + 1000) ticks, 6 instructions a tick
    assert r["insn_per_tick_calibrated"] == 6.0
    assert r["insn_per_imu_step_mean"] == pytest.approx(6 * (90 * 110 + 10 * 1010) / 100)
    assert r["insn_per_imu_step_max"] == pytest.approx(6 * 1010)
    assert r["insn_per_bare_imu_step"] == pytest.approx(6 * 110)
    assert r["insn_per_prediction_mean"] == pytest.approx(6 * 800)
    assert r["insn_per_prediction_max"] == pytest.approx(6 * 801)
    assert r["insn_per_odo_update"] == pytest.approx(6 * 500)
    assert r["insn_per_gnss_update"] == pytest.approx(6 * 60)
    total = 6 * (90 * 110 + 10 * 1010 + 120)
    assert r["insn_per_s_measured"] == pytest.approx(total)
    # 200 Hz: 100 more bare steps a second; load = insn/s x CPI / 168 MHz
    assert r["insn_per_s_200hz"] == pytest.approx(total + 100 * 6 * 110)
    assert r["cpu_load_pct_200hz_168mhz"] == pytest.approx(
        100 * (total + 100 * 660) * qemu_run.CPI_ASSUMED / 168e6, abs=1e-3)


def test_first_difference_names_the_line(tmp_path):
    a, b = tmp_path / "host.log", tmp_path / "qemu.log"
    a.write_text("x\ny\nz\n")
    b.write_text("x\nY\nz\n")
    d = qemu_run.first_difference(a, b)
    assert "line 2" in d and "host.log: y" in d and "qemu.log: Y" in d


def test_memory_counts_data_in_flash_and_ram_once_each():
    sec = {".isr_vector": (392, 0x08000000), ".text": (30000, 0x0800C000),
           ".ARM.exidx": (8, 0x08013530), ".data": (12, 0x20000000), ".bss": (6000, 0x2000000C),
           ".comment": (50, 0), ".debug_info": (9999, 0)}
    flash, ram, detail = budget.memory_use(sec)
    assert flash == 392 + 30000 + 8 + 12
    assert ram == 12 + 6000
    assert ".debug_info" not in detail and detail[".data"]["in"].startswith("RAM")


def test_double_and_heap_symbols_are_recognised():
    for name in ("__aeabi_dmul", "__aeabi_f2d", "__aeabi_ul2d", "__muldf3", "__extendsfdf2"):
        assert budget.DOUBLE_SYMBOLS.match(name), name
    for name in ("__aeabi_fmul", "__aeabi_f2lz", "__aeabi_ul2f", "__aeabi_uldivmod", "roundf"):
        assert not budget.DOUBLE_SYMBOLS.match(name), name
    for name in ("malloc", "_malloc_r", "free", "_sbrk", "_sbrk_r", "realloc"):
        assert budget.HEAP_SYMBOLS.match(name), name
    assert not budget.HEAP_SYMBOLS.match("memset")


def _host_cc(tmp_path, name, *flags):
    import shutil
    import subprocess
    if shutil.which("gcc") is None or shutil.which("arm-none-eabi-readelf") is None:
        pytest.skip("needs gcc and arm-none-eabi-readelf")
    (tmp_path / f"{name}.c").write_text(f"int {name}(int x);\nint {name}(int x) {{ return x + 1; }}\n")
    subprocess.run(["gcc", "-O2", "-fstack-usage", "-fcallgraph-info=su", *flags, "-c",
                    f"{name}.c", "-o", f"{name}.o"], cwd=tmp_path, check=True,
                   capture_output=True)
    return tmp_path / f"{name}.o"


def test_call_graphs_of_lto_objects_come_from_the_link_or_nowhere(tmp_path):
    """An object compiled with -flto has no code, so no call graph of its own: the budget
    reads the link's (--ltrans), refuses without it, and refuses one older than the
    objects (a stale graph would check code that is not in the image)."""
    plain = _host_cc(tmp_path, "plain")
    lto = _host_cc(tmp_path, "inter", "-flto")
    assert budget.is_lto_object(lto) and not budget.is_lto_object(plain)
    elf = tmp_path / "image.elf"
    elf.write_text("")
    files, _ = budget.call_graphs(elf, [str(plain)], None)
    assert files == [plain.with_suffix(".ci")]
    with pytest.raises(SystemExit) as e:
        budget.call_graphs(elf, [str(plain), str(lto)], None)
    assert e.value.code == 2
    ltrans = tmp_path / "lto"
    ltrans.mkdir()
    with pytest.raises(SystemExit) as e:                 # no graph written at the link
        budget.call_graphs(elf, [str(plain), str(lto)], ltrans)
    assert e.value.code == 2
    ci = ltrans / "ltrans0.ltrans.ci"
    ci.write_text("graph: { title: \"/tmp/cc.ltrans0.o\"\n}\n")
    import os
    os.utime(ci, (lto.stat().st_mtime - 10, lto.stat().st_mtime - 10))
    with pytest.raises(SystemExit) as e:                 # older than an object: stale
        budget.call_graphs(elf, [str(plain), str(lto)], ltrans)
    assert e.value.code == 2
    os.utime(ci, None)
    os.utime(elf, None)
    files, notes = budget.call_graphs(elf, [str(plain), str(lto)], ltrans)
    assert files == [plain.with_suffix(".ci"), ci] and notes
    with pytest.raises(SystemExit) as e:                 # a link graph without -flto objects
        budget.call_graphs(elf, [str(plain)], ltrans)
    assert e.value.code == 2


def test_alias_groups_from_the_symbol_table(tmp_path, monkeypatch):
    nm = ("0800d4dc t app_count\n0800d4dc t count\n0800d500 T single\n"
          "08010d11 t enc_y\n08010d10 t enc_x\n0800c000 t $t\n0800c000 t other\n")

    class R:
        stdout = nm
    monkeypatch.setattr(budget.subprocess, "run", lambda *a, **k: R())
    assert budget.alias_groups(Path("x.elf")) == [["app_count", "count"], ["enc_x", "enc_y"]]


def test_bench_finds_the_imu_where_the_profile_moved_it(tmp_path):
    """A profile that moves navecu's identifiers (vw_mqb: all of them from 0x6C0) moves the
    IMU frames the bench times: the same trace with the profile's identifiers gives the same
    step counts (make VEHICLE=vw_mqb target-check failed with an IndexError on the stock
    0x100/0x101), and the car's own wheel-speed message (ESP_19) is the wheel frame."""
    stock = tmp_path / "stock.txt"
    write_trace(stock, 100)
    fids = qemu_run.frame_ids("vw_mqb")
    assert fids["imu_rate"] == 0x6C0 and fids["imu_accel"] == 0x6C1
    move = {0x100: fids["imu_rate"], 0x101: fids["imu_accel"], 0x120: min(fids["gnss"]),
            0x121: min(fids["gnss"]) + 1}
    lines = stock.read_text().splitlines()
    moved = [lines[0]] + [f"{move[int(ln.split()[0], 16)]:x} {ln.split(' ', 1)[1]}"
                          if not ln.startswith("point") else ln for ln in lines[1:]]
    moved.append("b2 7 0")                                        # ESP_19, 0x0B2
    trace = tmp_path / "vw.txt"
    trace.write_text("\n".join(moved) + "\n")
    r = qemu_run.bench(trace, duration_s=1.0, imu_rate_hz=100.0, fids=fids)
    ref = qemu_run.bench(stock, duration_s=1.0, imu_rate_hz=100.0)
    for k in ("n_imu_steps", "insn_per_imu_step_mean", "insn_per_bare_imu_step",
              "insn_per_gnss_frame_max"):
        assert r[k] == ref[k], k
    assert r["insn_per_wheel_frame_mean"] == 6 * 7
    assert qemu_run.frame_ids("toyota_rav4_2017")["gnss"] == {0x120, 0x121, 0x122, 0x124}
    # wheel speeds in two messages: both are wheel frames (the front axle's, the rear's)
    assert qemu_run.frame_ids("nissan_x_trail_2017")["wheels"] == {0x29A, 0x285}
