"""The ECU images' resource budget (`make target-budget`, docs/target.md): the
application's and the bootloader's (issue #19: --flash-limit 16384 --sectors 0).

    python -m tools.target.budget --elf build/target/navecu.elf --objs OBJ.o ... \
        [--ltrans build/target/lto/navecu] [--entry Reset_Handler] [--isr CAN1_RX0_IRQHandler ...] [--indirect CALLER=C1,C2 ...]
        [--flash-limit B] [--flash-aim B] [--sectors 3,4] [--json out/target-budget.json]

Checks, each against the limit of issue #8 (exit status 1 if any is exceeded, 2 if a
check cannot be made):
* flash: the bytes programmed into flash (every loaded section: vectors, code, constants,
  the .data image) <= 64 KiB (aim 48 KiB), and only into the erase sectors --sectors
  allows (the application: 3-4 behind the bootloader; the bootloader: sector 0);
* static RAM: .data + .bss <= 16 KiB (aim 12 KiB);
* stack: the worst case over the call graph from -fstack-usage/-fcallgraph-info
  (tools/target/stack_usage.py) from the reset handler plus every interrupt handler
  nested, with their exception frames <= 2 KiB. The graph of an object is its .ci, written
  when it was compiled; for the objects compiled with -flto (intermediate code, detected
  from their .gnu.lto_ sections) it is the one the link wrote of the code it generated
  (--ltrans DIR: the link's -dumpdir, DIR/*ltrans*.ci), refused if missing or older than
  the objects; functions folded into one by the link (several symbols at one address in
  the image) are passed to stack_usage.py as --alias-group;
* no heap: none of malloc, calloc, realloc, free, _sbrk (or their reentrant _r forms) in
  the linked image;
* no double-precision software floating point: no __aeabi_d*, __aeabi_f2d, __aeabi_*2d
  or the GCC soft-float double helpers anywhere in the image (a stronger check than
  "not on the per-sample path": nothing can reach what is not linked).
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

LIMITS = {"flash_bytes": (64 * 1024, 48 * 1024), "ram_bytes": (16 * 1024, 12 * 1024),
          "stack_bytes": (2 * 1024, None)}
HEAP_SYMBOLS = re.compile(r"^_?(malloc|calloc|realloc|free|_sbrk|sbrk)(_r)?$|^_(malloc|free|"
                          r"calloc|realloc)_r$")
DOUBLE_SYMBOLS = re.compile(r"^__aeabi_(d[a-z0-9]+|f2d|i2d|ui2d|l2d|ul2d)$|^__(add|sub|mul|div|"
                            r"neg)df3$|^__(extendsfdf2|truncdfsf2|fix(uns)?dfsi|float(un)?sidf|"
                            r"(eq|ne|lt|le|gt|ge|un)df2)$")


def sections(elf: Path) -> dict:
    """{name: (size, vma)} of the allocated sections (arm-none-eabi-size -A)."""
    out = subprocess.run(["arm-none-eabi-size", "-A", str(elf)], check=True,
                         capture_output=True, text=True).stdout
    res = {}
    for line in out.splitlines():
        p = line.split()
        if len(p) == 3 and p[0].startswith(".") and p[1].isdigit():
            res[p[0]] = (int(p[1]), int(p[2]))
    return res


def symbols(elf: Path) -> set:
    out = subprocess.run(["arm-none-eabi-nm", str(elf)], check=True, capture_output=True,
                         text=True).stdout
    return {line.split()[-1] for line in out.splitlines() if line.strip()}


def alias_groups(elf: Path) -> list:
    """The names of the functions at one address, where there are several (identical code
    folding at the link, weak aliases): [[name, ...], ...]."""
    out = subprocess.run(["arm-none-eabi-nm", "--defined-only", str(elf)], check=True,
                         capture_output=True, text=True).stdout
    at: dict = {}
    for line in out.splitlines():
        p = line.split()
        if len(p) == 3 and p[1] in "tTwW" and not p[2].startswith("$"):
            at.setdefault(int(p[0], 16) & ~1, []).append(p[2])
    return [sorted(set(v)) for _, v in sorted(at.items()) if len(set(v)) > 1]


def memory_use(sec: dict) -> tuple[int, int, dict]:
    flash_start, flash_end = 0x08000000, 0x08100000
    ram_start, ram_end = 0x20000000, 0x20020000
    flash = 0
    ram = 0
    detail = {}
    for name, (size, vma) in sec.items():
        if size == 0:
            continue
        if flash_start <= vma < flash_end:
            flash += size
            detail[name] = {"bytes": size, "in": "flash"}
        elif ram_start <= vma < ram_end:
            ram += size
            detail[name] = {"bytes": size, "in": "RAM"}
            if name == ".data":
                flash += size  # its initial values are copied from flash
                detail[name]["in"] = "RAM (image in flash)"
    return flash, ram, detail


# STM32F405 flash sectors (RM0090 table 5): 4 x 16 KiB, 64 KiB, 7 x 128 KiB
SECTORS = ([(0x08000000 + k * 0x4000, 0x4000) for k in range(4)] + [(0x08010000, 0x10000)]
           + [(0x08020000 + k * 0x20000, 0x20000) for k in range(7)])
NVM_RANGE = (0x08004000, 0x0800C000)  # sectors 1 and 2 (stm32f405.ld)
APP_SECTORS = [3, 4]  # the application behind the bootloader (firmware/boot/boot_image.h)


def load_segments(elf: Path) -> list:
    """[(flash address, bytes)] of what is programmed: every loadable segment's file image
    (readelf -l), which also covers .data's initial values at their load address."""
    out = subprocess.run(["arm-none-eabi-readelf", "-lW", str(elf)], check=True,
                         capture_output=True, text=True).stdout
    segs = []
    for line in out.splitlines():
        p = line.split()
        if p and p[0] == "LOAD":
            paddr, filesz = int(p[3], 16), int(p[4], 16)
            if filesz > 0:
                segs.append((paddr, filesz))
    return segs


def sectors_touched(segs: list) -> tuple[int, list]:
    """Bytes of the erase sectors the image occupies, and which (index list)."""
    touched = [k for k, (a, n) in enumerate(SECTORS)
               if any(p < a + n and p + sz > a for p, sz in segs)]
    return sum(SECTORS[k][1] for k in touched), touched


def refuse(msg: str):
    """A check that cannot be made: exit status 2."""
    print(msg, file=sys.stderr)
    raise SystemExit(2)


def is_lto_object(obj: Path) -> bool:
    """An object compiled with -flto (slim): GCC's intermediate code, no machine code; its
    code, and the call graph of it, are generated at the link."""
    out = subprocess.run(["arm-none-eabi-readelf", "-SW", str(obj)], check=True,
                         capture_output=True, text=True).stdout
    return ".gnu.lto_" in out


def call_graphs(elf: Path, objs: list, ltrans: Path | None) -> tuple[list, list]:
    """The .ci files describing the code linked into elf: each object's own (written when
    it was compiled), except for the -flto objects, whose code the link generated: the
    link's partitions' (ltrans*.ltrans.ci in ltrans, the link's -dumpdir, written with
    -fcallgraph-info=su at the link). Refuses (exit 2) what would be stale or missing.
    Returns (files, notes)."""
    files, notes, lto = [], [], []
    for o in map(Path, objs):
        if is_lto_object(o):
            lto.append(o)
            continue
        ci = o.with_suffix(".ci")
        if not ci.exists():
            refuse(f"budget: {ci} missing (objects need -fcallgraph-info=su)")
        if ci.stat().st_mtime < o.stat().st_mtime - 1:
            refuse(f"budget: {ci} older than {o}")
        files.append(ci)
    if lto:
        if ltrans is None:
            refuse(f"budget: {len(lto)} objects compiled with -flto ({lto[0]}, ...): "
                             f"their code is generated at the link; give the link's -dumpdir "
                             f"with --ltrans (link with -fstack-usage -fcallgraph-info=su)")
        lt = sorted(ltrans.glob("*ltrans*.ci"))
        if not lt:
            refuse(f"budget: no link-time call graph (*ltrans*.ci) in {ltrans} "
                             f"(link with -flto -fcallgraph-info=su -dumpdir {ltrans}/)")
        newest = max(o.stat().st_mtime for o in lto)
        for ci in lt:
            if ci.stat().st_mtime < newest or ci.stat().st_mtime > elf.stat().st_mtime + 1:
                refuse(f"budget: {ci} is not from the link of {elf} (stale)")
        files += lt
        notes.append(f"{len(lto)} objects compiled with -flto: their call graph from the "
                     f"link, {', '.join(str(c) for c in lt)}")
    elif ltrans is not None:
        refuse(f"budget: --ltrans {ltrans} given but no object was compiled with -flto")
    return files, notes


def stack(cis: list, entries: list, isrs: list, indirect: list,
          stack_limit: int = LIMITS["stack_bytes"][0], aliases: list = ()) -> dict:
    """Run stack_usage.py over these .ci files only (not the QEMU image's)."""
    with tempfile.TemporaryDirectory() as d:
        for k, ci in enumerate(cis):
            (Path(d) / f"{k:03d}_{ci.name}").write_text(ci.read_text())
        js = Path(d) / "stack.json"
        # 108: the FPU exception frame (26 words) plus the 4-byte alignment pad (STKALIGN)
        cmd = [sys.executable, str(ROOT / "tools" / "target" / "stack_usage.py"), "--ci-dir", d,
               "--limit-bytes", str(stack_limit), "--exception-frame-bytes", "108",
               "--json", str(js)]
        for e in entries:
            cmd += ["--entry", e]
        for i in isrs:
            cmd += ["--isr", i]
        for i in indirect:
            cmd += ["--indirect", i]
        for grp in aliases:
            cmd += ["--alias-group", ",".join(grp)]
        r = subprocess.run(cmd, capture_output=True, text=True)
        print(r.stdout.rstrip())
        if r.returncode == 2 or not js.exists():
            print(r.stderr, file=sys.stderr)
            raise SystemExit(2)
        return json.loads(js.read_text())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--elf", type=Path, required=True)
    ap.add_argument("--objs", nargs="+", required=True)
    ap.add_argument("--entry", action="append", default=None)
    ap.add_argument("--isr", action="append", default=None)
    ap.add_argument("--indirect", action="append", default=[], metavar="CALLER=C1,C2",
                    help="callees of CALLER's calls through function pointers (stack_usage.py)")
    ap.add_argument("--ltrans", type=Path, default=None, metavar="DIR",
                    help="the link's -dumpdir: the call graphs of the code generated at the "
                         "link for the objects compiled with -flto")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--flash-limit", type=int, default=LIMITS["flash_bytes"][0])
    ap.add_argument("--flash-aim", type=int, default=LIMITS["flash_bytes"][1])
    ap.add_argument("--sectors", default=",".join(map(str, APP_SECTORS)),
                    help="the erase sectors the image may occupy")
    a = ap.parse_args(argv)
    limits = dict(LIMITS)
    limits["flash_bytes"] = (a.flash_limit, a.flash_aim or None)
    allowed = [int(k) for k in a.sectors.split(",")]
    entries = a.entry or ["Reset_Handler"]
    isrs = a.isr or []

    sec = sections(a.elf)
    flash, ram, detail = memory_use(sec)
    segs = load_segments(a.elf)
    flash_programmed = sum(n for _, n in segs)
    sector_bytes, sector_list = sectors_touched(segs)
    nvm_overlap = [hex(p) for p, n in segs if p < NVM_RANGE[1] and p + n > NVM_RANGE[0]]
    syms = symbols(a.elf)
    heap = sorted(s for s in syms if HEAP_SYMBOLS.match(s))
    dbl = sorted(s for s in syms if DOUBLE_SYMBOLS.match(s))
    cis, ci_notes = call_graphs(a.elf, a.objs, a.ltrans)
    for n in ci_notes:
        print(f"note: {n}")
    st = stack(cis, entries, isrs, a.indirect, limits["stack_bytes"][0], alias_groups(a.elf))
    stack_bytes = int(st["total_bytes"])

    rows = [("flash", flash, *limits["flash_bytes"]), ("static RAM", ram, *limits["ram_bytes"]),
            ("worst-case stack", stack_bytes, *limits["stack_bytes"])]
    failed = []
    print(f"budget of {a.elf}:")
    for name, used, limit, aim in rows:
        ok = used <= limit
        aim_txt = f", aim {aim} ({'met' if used <= aim else 'not met'})" if aim else ""
        print(f"  {name:17s} {used:7d} bytes  limit {limit}{aim_txt}  {'ok' if ok else 'EXCEEDED'}")
        if not ok:
            failed.append(name)
    print(f"  flash, programmed {flash_programmed:7d} bytes in erase sectors {sector_list} "
          f"({sector_bytes // 1024} KiB of sectors; NVM sectors 1-2 "
          f"{'untouched' if not nvm_overlap else 'OVERLAPPED at ' + ', '.join(nvm_overlap)})")
    print(f"  heap              {'none linked' if not heap else 'LINKED: ' + ', '.join(heap)}")
    print(f"  double precision  {'none linked' if not dbl else 'LINKED: ' + ', '.join(dbl)}")
    if flash_programmed != flash:
        failed.append("flash accounting (sections vs segments differ)")
    if nvm_overlap:
        failed.append("image overlaps the NVM sectors")
    outside = [k for k in sector_list if k not in allowed]
    if outside:
        failed.append(f"image in erase sectors {outside}, outside its own {allowed}")
    if heap:
        failed.append("heap")
    if dbl:
        failed.append("double")
    res = {"elf": str(a.elf), "flash_bytes": flash, "ram_bytes": ram, "stack_bytes": stack_bytes,
           "limits": {k: v[0] for k, v in limits.items()},
           "aims": {k: v[1] for k, v in limits.items() if v[1]},
           "sectors_allowed": allowed,
           "sections": detail, "heap_symbols": heap, "double_symbols": dbl,
           "flash_programmed_bytes": flash_programmed, "flash_sectors": sector_list,
           "flash_sector_bytes": sector_bytes,
           "stack": st, "command": "make target-budget", "ok": not failed}
    if a.json:
        a.json.parent.mkdir(parents=True, exist_ok=True)
        a.json.write_text(json.dumps(res, indent=2) + "\n")
    if failed:
        print(f"target-budget: FAIL ({', '.join(failed)})", file=sys.stderr)
        return 1
    print(f"target-budget: every limit of {a.elf.name} met")
    return 0


if __name__ == "__main__":
    sys.exit(main())
