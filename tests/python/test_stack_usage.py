"""Tests of the worst-case stack-depth checker (tools/target/stack_usage.py).

Most tests compile tiny C files with the host gcc (-fstack-usage -fcallgraph-info=su, -O0
so every call stays a call) and compute the expected worst case from the frame sizes the
compiler wrote to the .su files, never from hard-coded numbers; the tool reads only the
.ci files, so the .su numbers are an independent check. Hand-written .ci snippets cover
what a host compile cannot produce on demand (dynamic,bounded frames, merging).
"""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tools.target import stack_usage as SU

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "target" / "stack_usage.py"


# ----------------------------------------------------------------------------- helpers
def _gcc_supports_callgraph_info() -> bool:
    gcc = shutil.which("gcc")
    if gcc is None:
        return False
    try:
        p = subprocess.run([gcc, "-fstack-usage", "-fcallgraph-info=su", "-x", "c", "-c",
                            "-", "-o", "/dev/null"], input="int f(void){return 0;}\n",
                           capture_output=True, text=True, cwd="/tmp", timeout=60)
    except (OSError, subprocess.SubprocessError):
        return False
    return p.returncode == 0


needs_gcc = pytest.mark.skipif(not _gcc_supports_callgraph_info(),
                               reason="host gcc without -fcallgraph-info=su")


def build(tmp: Path, files: dict[str, str], opt: str = "-O0") -> dict[tuple[str, str], int]:
    """Compile each file in tmp (relative names, as the firmware build does); return the
    frames from the .su files: {(file, function): bytes}."""
    frames = {}
    for name, src in files.items():
        (tmp / name).write_text(src)
        subprocess.run(["gcc", opt, "-fstack-usage", "-fcallgraph-info=su", "-c", name,
                        "-o", name[:-2] + ".o"], cwd=tmp, check=True, capture_output=True)
        for line in (tmp / (name[:-2] + ".su")).read_text().splitlines():
            where, size, _kind = line.rsplit("\t", 2)
            frames[(where.split(":")[0], where.rsplit(":", 1)[1])] = int(size)
    return frames


def fr(frames, fn, file=None):
    hits = [v for (f, n), v in frames.items() if n == fn and (file is None or f == file)]
    assert len(hits) == 1, (fn, file, frames)
    return hits[0]


def run(tmp: Path, *args: str):
    out = tmp / "out.json"
    p = subprocess.run([sys.executable, str(TOOL), "--ci-dir", str(tmp), "--json", str(out),
                        *args], capture_output=True, text=True, timeout=60)
    doc = json.loads(out.read_text()) if out.exists() else None
    return p.returncode, p.stdout + p.stderr, doc


def write_graph(path: Path, unit: str, nodes: list[tuple], edges: list[tuple],
                edge_file: str) -> None:
    """A .ci as GCC writes it: nodes (title, name, file, bytes or None, kind), edges
    (source, target) titles, each labelled at edge_file."""
    lines = [f'graph: {{ title: "{unit}"']
    for title, name, file, size, kind in nodes:
        if size is None:
            lines.append(f'node: {{ title: "{title}" label: "{name}\\n{file}:1:1" '
                         f'shape : ellipse }}')
        else:
            lines.append(f'node: {{ title: "{title}" label: "{name}\\n{file}:1:1\\n'
                         f'{size} bytes ({kind})" }}')
    for s, t in edges:
        lines.append(f'edge: {{ sourcename: "{s}" targetname: "{t}" label: "{edge_file}:2:3" }}')
    lines.append("}")
    path.write_text("\n".join(lines) + "\n")


def write_ci(path: Path, nodes: list[tuple], edges: list[tuple]) -> None:
    """nodes: (title, bytes or None, kind); edges: (source, target)."""
    src = f"{path.stem}.c"
    write_graph(path, src, [(t, t.rsplit(":", 1)[-1], "x.h" if n is None else src, n, k)
                            for t, n, k in nodes], edges, src)


CHAIN = """
int c(int x);
int b(int x);
int a(int x);
int c(int x) { volatile char buf[100]; buf[0] = (char)x; return buf[0]; }
int b(int x) { volatile char buf[40]; buf[0] = (char)x; return c(buf[0]) + 1; }
int a(int x) { volatile char buf[8]; buf[0] = (char)x; return b(buf[0]) + 2; }
"""


# ------------------------------------------------------------------------- compiled C
@needs_gcc
def test_chain_sums_the_frames(tmp_path):
    f = build(tmp_path, {"chain.c": CHAIN})
    rc, out, doc = run(tmp_path, "--entry", "a")
    assert rc == 0, out
    want = fr(f, "a") + fr(f, "b") + fr(f, "c")
    assert doc["entries"]["a"]["bytes"] == want
    assert doc["entries"]["a"]["path"] == [["a", fr(f, "a")], ["b", fr(f, "b")],
                                           ["c", fr(f, "c")]]
    assert doc["total_bytes"] == want and doc["isr_bytes"] == 0
    assert f"entry a: {want} bytes" in out
    # an inner function as entry: only its own subtree
    rc, _, doc = run(tmp_path, "--entry", "b")
    assert doc["entries"]["b"]["bytes"] == fr(f, "b") + fr(f, "c")


@needs_gcc
def test_frames_match_the_su_files(tmp_path):
    """The .ci parser reads the same frame for every compiled function as the .su."""
    f = build(tmp_path, {"chain.c": CHAIN, "s1.c": "static int h(int x) "
                         "{ volatile char b[24]; b[0] = (char)x; return b[0]; }\n"
                         "int s1(int x); int s1(int x) { return h(x); }\n"}, opt="-O2")
    g = SU.load([tmp_path])
    got = {}
    for t, fn in g.funcs.items():
        if fn.frame is not None:
            file, name = t.rsplit(":", 1) if ":" in t else (fn.location.split(":")[0], t)
            got[(file, name)] = fn.frame
    assert got == f


@needs_gcc
def test_max_over_branches(tmp_path):
    src = """
int small(int x); int mid(int x); int deep(int x); int big(int x); int top(int x);
int small(int x) { volatile char b[16]; b[0] = (char)x; return b[0]; }
int big(int x) { volatile char b[300]; b[0] = (char)x; return b[0]; }
int deep(int x) { volatile char b[24]; b[0] = (char)x; return small(b[0]); }
int mid(int x) { volatile char b[64]; b[0] = (char)x; return deep(b[0]); }
int top(int x) { return small(x) + mid(x) + big(x); }
"""
    f = build(tmp_path, {"br.c": src})
    rc, out, doc = run(tmp_path, "--entry", "top")
    assert rc == 0, out
    via_mid = fr(f, "top") + fr(f, "mid") + fr(f, "deep") + fr(f, "small")
    via_big = fr(f, "top") + fr(f, "big")
    assert via_big != via_mid               # the test can tell the branches apart
    assert doc["entries"]["top"]["bytes"] == max(via_mid, via_big, fr(f, "top") + fr(f, "small"))
    want_path = ["top", "big"] if via_big > via_mid else ["top", "mid", "deep", "small"]
    assert [p[0] for p in doc["entries"]["top"]["path"]] == want_path


@needs_gcc
def test_recursion_is_an_error_with_the_cycle(tmp_path):
    src = """
int ping(int n); int pong(int n); int start(int n);
int ping(int n) { return n ? pong(n - 1) : 0; }
int pong(int n) { return n ? ping(n - 1) : 1; }
int start(int n) { return ping(n); }
"""
    build(tmp_path, {"rec.c": src})
    rc, out, doc = run(tmp_path, "--entry", "start")
    assert rc == 2, out
    assert "recursion" in out and "ping -> pong -> ping" in out
    assert doc["errors"] and "entries" not in doc


@needs_gcc
def test_indirect_call_unresolved_then_resolved(tmp_path):
    src = """
typedef int (*cb_t)(int);
int cb_small(int x); int cb_big(int x); int dispatch(cb_t f, int x); int entry(int x);
int cb_small(int x) { volatile char b[8]; b[0] = (char)x; return b[0]; }
int cb_big(int x) { volatile char b[200]; b[0] = (char)x; return b[0]; }
int dispatch(cb_t f, int x) { volatile char b[32]; b[0] = (char)x; return f(b[0]); }
int entry(int x) { return dispatch(x ? cb_small : cb_big, x); }
"""
    f = build(tmp_path, {"ind.c": src})
    rc, out, _ = run(tmp_path, "--entry", "entry")
    assert rc == 2, out
    assert "indirect calls without --indirect" in out and "dispatch" in out
    rc, out, doc = run(tmp_path, "--entry", "entry", "--indirect", "dispatch=cb_small,cb_big")
    assert rc == 0, out
    assert doc["entries"]["entry"]["bytes"] == (fr(f, "entry") + fr(f, "dispatch")
                                                + max(fr(f, "cb_small"), fr(f, "cb_big")))
    rc, out, doc = run(tmp_path, "--entry", "entry", "--indirect", "dispatch=cb_small")
    assert doc["entries"]["entry"]["bytes"] == (fr(f, "entry") + fr(f, "dispatch")
                                                + fr(f, "cb_small"))
    rc, out, _ = run(tmp_path, "--entry", "entry", "--indirect", "dispatch=cb_typo")
    assert rc == 2 and "cb_typo" in out


@needs_gcc
def test_limit_exceeded_exit_1_and_boundary(tmp_path):
    f = build(tmp_path, {"chain.c": CHAIN})
    want = fr(f, "a") + fr(f, "b") + fr(f, "c")
    rc, out, doc = run(tmp_path, "--entry", "a", "--limit-bytes", str(want))
    assert rc == 0 and "OK" in out
    rc, out, doc = run(tmp_path, "--entry", "a", "--limit-bytes", str(want - 1))
    assert rc == 1 and "EXCEEDED by 1 bytes" in out
    assert doc["total_bytes"] == want and doc["limit_bytes"] == want - 1


@needs_gcc
def test_isr_sum_plus_exception_frames(tmp_path):
    src = """
int leaf(int x); int t1(int x); int t2(int x); void isr_a(void); void isr_b(void);
volatile int sink;
int leaf(int x) { volatile char b[48]; b[0] = (char)x; return b[0]; }
int t1(int x) { volatile char b[16]; b[0] = (char)x; return leaf(b[0]); }
int t2(int x) { volatile char b[400]; b[0] = (char)x; return b[0]; }
void isr_a(void) { volatile char b[40]; b[0] = 1; sink = leaf(b[0]); }
void isr_b(void) { volatile char b[72]; b[0] = 2; sink = b[0]; }
"""
    f = build(tmp_path, {"isr.c": src})
    thread = max(fr(f, "t1") + fr(f, "leaf"), fr(f, "t2"))
    isrs = fr(f, "isr_a") + fr(f, "leaf") + fr(f, "isr_b")
    rc, out, doc = run(tmp_path, "--entry", "t1", "--entry", "t2", "--isr", "isr_a",
                       "--isr", "isr_b")
    assert rc == 0, out
    assert doc["thread_bytes"] == thread
    assert doc["isr_bytes"] == isrs + 2 * 104
    assert doc["total_bytes"] == thread + isrs + 2 * 104
    assert doc["entries"]["isr_b"]["isr"] is True and doc["entries"]["t2"]["isr"] is False
    rc, out, doc = run(tmp_path, "--entry", "t1", "--entry", "t2", "--entry", "isr_a",
                       "--isr", "isr_a", "--exception-frame-bytes", "32")
    assert doc["total_bytes"] == thread + fr(f, "isr_a") + fr(f, "leaf") + 32
    # no ISR: no exception frame
    rc, out, doc = run(tmp_path, "--entry", "t1")
    assert doc["total_bytes"] == fr(f, "t1") + fr(f, "leaf")


@needs_gcc
def test_unknown_external_assumption_printed(tmp_path):
    src = """
#include <string.h>
int ext_fn(int x);
int user(char *d, const char *s, unsigned n);
int user(char *d, const char *s, unsigned n) { memcpy(d, s, n); return ext_fn((int)n); }
"""
    f = build(tmp_path, {"ext.c": src})
    rc, out, doc = run(tmp_path, "--entry", "user")
    assert rc == 0, out
    assert doc["assumed"] == {"ext_fn": 64, "memcpy": 64}
    assert "--unknown-bytes 64" in out and "ext_fn (default)" in out
    assert doc["entries"]["user"]["bytes"] == fr(f, "user") + 64
    rc, out, doc = run(tmp_path, "--entry", "user", "--unknown-bytes", "8",
                       "--extra-bytes", "ext_fn=200")
    assert doc["assumed"] == {"ext_fn": 200, "memcpy": 8}
    assert "ext_fn (--extra-bytes)" in out
    assert doc["entries"]["user"]["path"] == [["user", fr(f, "user")], ["ext_fn", 200]]
    assert doc["entries"]["user"]["bytes"] == fr(f, "user") + 200


@needs_gcc
def test_same_named_static_functions_stay_apart(tmp_path):
    one = """
static int helper(int x) { volatile char b[500]; b[0] = (char)x; return b[0]; }
int one(int x); int one(int x) { return helper(x); }
"""
    two = """
static int helper(int x) { volatile char b[12]; b[0] = (char)x; return b[0]; }
int two(int x); int two(int x) { return helper(x); }
"""
    f = build(tmp_path, {"one.c": one, "two.c": two})
    rc, out, doc = run(tmp_path, "--entry", "one", "--entry", "two")
    assert rc == 0, out
    assert doc["entries"]["one"]["path"] == [["one", fr(f, "one")],
                                             ["one.c:helper", fr(f, "helper", "one.c")]]
    assert doc["entries"]["two"]["bytes"] == fr(f, "two") + fr(f, "helper", "two.c")
    assert fr(f, "helper", "one.c") != fr(f, "helper", "two.c")
    # a static is named by its plain name only where that is unambiguous
    rc, out, _ = run(tmp_path, "--entry", "helper")
    assert rc == 2 and "ambiguous" in out
    rc, out, doc = run(tmp_path, "--entry", "two.c:helper")
    assert doc["entries"]["two.c:helper"]["bytes"] == fr(f, "helper", "two.c")


@needs_gcc
def test_calls_across_files_and_weak_definition(tmp_path):
    caller = """
int lib_fn(int x); void hook(int x); int app(int x);
int app(int x) { volatile char b[20]; b[0] = (char)x; hook(x); return lib_fn(b[0]); }
"""
    lib = """
int lib_fn(int x); void hook(int x);
int lib_fn(int x) { volatile char b[90]; b[0] = (char)x; return b[0]; }
__attribute__((weak)) void hook(int x) { volatile char b[160]; b[0] = (char)x; }
"""
    f = build(tmp_path, {"app.c": caller, "lib.c": lib})
    rc, out, doc = run(tmp_path, "--entry", "app")
    assert rc == 0, out
    assert doc["assumed"] == {}
    assert doc["entries"]["app"]["bytes"] == fr(f, "app") + max(fr(f, "lib_fn"), fr(f, "hook"))
    assert "linked to the only definition lib.c:hook" in out


@needs_gcc
def test_unbounded_dynamic_frame_is_an_error(tmp_path):
    src = """
int vla(int n); int calls_vla(int n);
int vla(int n) { volatile char b[n]; b[0] = 1; return b[0]; }
int calls_vla(int n) { return vla(n); }
"""
    build(tmp_path, {"vla.c": src})
    rc, out, _ = run(tmp_path, "--entry", "calls_vla")
    assert rc == 2 and "unbounded dynamic stack frame" in out and "vla" in out


@needs_gcc
def test_missing_entry_is_an_error(tmp_path):
    build(tmp_path, {"chain.c": CHAIN})
    rc, out, _ = run(tmp_path, "--entry", "a", "--entry", "no_such_fn")
    assert rc == 2 and "no_such_fn" in out


# --------------------------------------------------------------- hand-written .ci files
def test_ci_chain_and_merge_across_files(tmp_path):
    # x.c calls y (external there), y.c defines it and calls the libgcc helper
    write_ci(tmp_path / "x.ci", [("x", 24, "static"), ("y", None, None)], [("x", "y")])
    sub = tmp_path / "sub"
    sub.mkdir()
    write_ci(sub / "y.ci", [("y", 40, "static"), ("z", 16, "static"),
                            ("__aeabi_uldivmod", None, None)],
             [("y", "z"), ("y", "__aeabi_uldivmod")])
    rc, out, doc = run(tmp_path, "--entry", "x", "--extra-bytes", "__aeabi_uldivmod=8")
    assert rc == 0, out
    assert doc["entries"]["x"] == {"bytes": 24 + 40 + 16, "isr": False,
                                   "path": [["x", 24], ["y", 40], ["z", 16]]}
    assert doc["assumed"] == {"__aeabi_uldivmod": 8}
    rc, out, doc = run(tmp_path, "--entry", "x")        # default 64 > z's 16
    assert doc["entries"]["x"]["path"] == [["x", 24], ["y", 40], ["__aeabi_uldivmod", 64]]


def test_ci_real_format_line(tmp_path):
    (tmp_path / "r.ci").write_text(
        'graph: { title: "r.c"\n'
        'node: { title: "r.c:helper" label: "helper\\nr.c:1:38\\n40 bytes (static)" }\n'
        'node: { title: "api" label: "api\\nr.c:2:5\\n8 bytes (dynamic,bounded)" }\n'
        'edge: { sourcename: "api" targetname: "r.c:helper" label: "r.c:2:29" }\n'
        'node: { title: "memcpy" label: "__builtin_memcpy\\n<built-in>" shape : ellipse }\n'
        'edge: { sourcename: "api" targetname: "memcpy" }\n'
        '}\n')
    rc, out, doc = run(tmp_path, "--entry", "api", "--extra-bytes", "memcpy=16")
    assert rc == 0, out
    assert doc["entries"]["api"]["bytes"] == 8 + 40
    assert "dynamic,bounded" in out


def test_ci_self_recursion_and_long_cycle(tmp_path):
    write_ci(tmp_path / "c.ci", [("m", 8, "static"), ("r", 16, "static"), ("p", 8, "static"),
                                 ("q", 8, "static")],
             [("m", "r"), ("r", "r"), ("m", "p"), ("p", "q"), ("q", "p")])
    rc, out, doc = run(tmp_path, "--entry", "m")
    assert rc == 2
    assert "r -> r" in out and "p -> q -> p" in out


def test_ci_cycle_not_reachable_is_fine(tmp_path):
    write_ci(tmp_path / "c.ci", [("m", 8, "static"), ("n", 4, "static"), ("r", 16, "static")],
             [("m", "n"), ("r", "r")])
    rc, out, doc = run(tmp_path, "--entry", "m")
    assert rc == 0 and doc["entries"]["m"]["bytes"] == 12


def test_ci_indirect_callee_can_be_deep(tmp_path):
    write_ci(tmp_path / "i.ci", [("d", 8, "static"), ("__indirect_call", None, None),
                                 ("h1", 100, "static"), ("h2", 16, "static"),
                                 ("h3", 120, "static")],
             [("d", "__indirect_call"), ("h2", "h3")])
    rc, out, doc = run(tmp_path, "--entry", "d", "--indirect", "d=h1,h2")
    assert rc == 0, out
    assert doc["entries"]["d"]["path"] == [["d", 8], ["h2", 16], ["h3", 120]]
    assert doc["total_bytes"] == 144


def test_ci_diamond_shared_subtree_counted_per_path(tmp_path):
    write_ci(tmp_path / "d.ci", [("top", 10, "static"), ("l", 30, "static"),
                                 ("r", 20, "static"), ("s", 50, "static")],
             [("top", "l"), ("top", "r"), ("l", "s"), ("r", "s")])
    rc, out, doc = run(tmp_path, "--entry", "top", "--entry", "r")
    assert doc["entries"]["top"]["bytes"] == 90 and doc["entries"]["r"]["bytes"] == 70
    assert doc["thread_bytes"] == 90


def test_ci_extra_bytes_on_compiled_function_adds(tmp_path):
    write_ci(tmp_path / "e.ci", [("f", 40, "static")], [])
    rc, out, doc = run(tmp_path, "--entry", "f", "--extra-bytes", "f=8")
    assert doc["entries"]["f"]["bytes"] == 48 and doc["assumed"] == {}


# ------------------------------------------------------- code generated at the link (-flto)
def _gcc_supports_lto() -> bool:
    if not _gcc_supports_callgraph_info():
        return False
    try:
        p = subprocess.run(["gcc", "-O2", "-flto", "-x", "c", "-", "-o", "/dev/null"],
                           input="int main(void){return 0;}\n", capture_output=True,
                           text=True, cwd="/tmp", timeout=60)
    except (OSError, subprocess.SubprocessError):
        return False
    return p.returncode == 0


needs_lto = pytest.mark.skipif(not _gcc_supports_lto(), reason="host gcc without -flto")

LTO_ONE = """
int one(int x);
void (*volatile hook)(int);
__attribute__((noinline)) static int helper(int x)
{ volatile char b[400]; b[0] = (char)x; return b[0]; }
__attribute__((noinline)) static void dispatch(int x) { hook(x); }
__attribute__((noinline)) int one(int x) { dispatch(x); return helper(x); }
"""
LTO_TWO = """
int one(int x); void target(int x); extern void (*volatile hook)(int);
__attribute__((noinline)) static int helper(int x)
{ volatile char b[40]; b[0] = (char)x; return b[0] + 1; }
__attribute__((noinline)) void target(int x) { volatile char b[700]; b[0] = (char)x; }
int main(void) { hook = target; return one(3) + helper(4); }
"""


def build_lto(tmp: Path) -> tuple[Path, dict[tuple[str, str], int]]:
    """one.c and two.c compiled with -flto, linked with the call graph written at the link
    (-dumpdir lto/, as the Makefile links the images); returns (lto dir, the frames of the
    link's .su file: {(file, function as in the image): bytes})."""
    (tmp / "one.c").write_text(LTO_ONE)
    (tmp / "two.c").write_text(LTO_TWO)
    for n in ("one", "two"):
        subprocess.run(["gcc", "-O2", "-flto", "-c", f"{n}.c", "-o", f"{n}.o"], cwd=tmp,
                       check=True, capture_output=True)
    (tmp / "lto").mkdir()
    subprocess.run(["gcc", "-O2", "-flto", "-flto-partition=one", "-fstack-usage",
                    "-fcallgraph-info=su", "-dumpdir", "lto/", "one.o", "two.o", "-o", "prog"],
                   cwd=tmp, check=True, capture_output=True)
    su = sorted((tmp / "lto").glob("*.su"))
    assert len(su) == 1 and len(list((tmp / "lto").glob("*.ci"))) == 1
    frames = {}
    for line in su[0].read_text().splitlines():
        where, size, _kind = line.rsplit("\t", 2)
        frames[(where.split(":")[0], where.rsplit(":", 1)[1])] = int(size)
    return tmp / "lto", frames


def lto_frame(frames, file, base):
    """The frame of the function `base` of `file`, whichever clone the link made of it."""
    hits = [v for (f, n), v in frames.items() if f == file and n.split(".")[0] == base]
    assert len(hits) == 1, (file, base, frames)
    return hits[0]


@needs_lto
def test_lto_statics_titled_after_their_source_and_resolved_by_name(tmp_path):
    lto, f = build_lto(tmp_path)
    g = SU.load([lto])
    assert g.lto_units
    titles = [t for t, fn in g.funcs.items() if fn.frame is not None]
    # the link's temporary object names nothing: a static is file.c:name[.clone]
    assert not [t for t in titles if "ltrans" in t], titles
    assert [t for t in titles if t.startswith("one.c:helper")]
    assert [t for t in titles if t.startswith("two.c:helper")]
    rc, out, doc = run(lto, "--entry", "main", "--indirect", "one.c:dispatch=target")
    assert rc == 0, out
    want = lto_frame(f, "two.c", "main") + max(
        lto_frame(f, "two.c", "helper"),
        lto_frame(f, "one.c", "one") + max(lto_frame(f, "one.c", "helper"),
                                           lto_frame(f, "one.c", "dispatch")
                                           + lto_frame(f, "two.c", "target")))
    assert doc["entries"]["main"]["bytes"] == want
    # the indirect call must still be resolved: its caller is named in the output
    rc, out, _ = run(lto, "--entry", "main")
    assert rc == 2 and "one.c:dispatch" in out and "without --indirect" in out
    # a plain name that is two functions' is refused, not guessed
    rc, out, _ = run(lto, "--entry", "main", "--indirect", "one.c:dispatch=target",
                     "--extra-bytes", "helper=8")
    assert rc == 2 and "ambiguous" in out
    rc, out, doc = run(lto, "--entry", "main", "--indirect", "dispatch=two.c:target")
    assert rc == 0 and doc["entries"]["main"]["bytes"] == want


def write_ltrans_ci(path: Path, unit: str, nodes: list[tuple], edges: list[tuple]) -> None:
    """A link-time unit's .ci as GCC writes it: local functions titled unit:name; nodes:
    (name, file, bytes or None, local), edges: (source, target) titles."""
    write_graph(path, unit, [(f"{unit}:{name}" if local else name, name, file, n, "static")
                             for name, file, n, local in nodes], edges, "x.c")


def test_ci_lto_folded_alias_needs_its_group(tmp_path):
    """Identical code folding at the link: the unit calls app_count, which it does not
    define (an alias of count at the same address). Never assumed: an error, unless the
    image's symbols (--alias-group) name the function it is."""
    u = "/tmp/ccAbCdEf.ltrans0.o"
    write_ltrans_ci(tmp_path / "ltrans0.ltrans.ci", u,
                    [("Reset_Handler", "startup.c", 8, False), ("count", "uds.c", 300, True),
                     ("small", "app.c", 16, True)],
                    [("Reset_Handler", f"{u}:app_count"), ("Reset_Handler", f"{u}:small")])
    rc, out, _ = run(tmp_path, "--entry", "Reset_Handler")
    assert rc == 2 and "app_count" in out and "no alias" in out
    rc, out, doc = run(tmp_path, "--entry", "Reset_Handler", "--alias-group", "app_count,count")
    assert rc == 0, out
    assert doc["entries"]["Reset_Handler"]["path"] == [["Reset_Handler", 8], ["uds.c:count", 300]]
    assert doc["assumed"] == {}


def test_ci_lto_clones_of_one_function_all_resolved(tmp_path):
    """A name given as file.c:name resolves to every clone the link made of it (each gets
    the --indirect callees); names of two files' functions are ambiguous."""
    u = "/tmp/ccXyZ.ltrans0.o"
    write_ltrans_ci(tmp_path / "ltrans0.ltrans.ci", u,
                    [("Reset_Handler", "startup.c", 8, False),
                     ("serve.constprop.0", "app_uds.c", 40, True),
                     ("serve.part.0", "app_uds.c", 24, True),
                     ("serve", "boot.c", 10, True),
                     ("read_did", "app_uds.c", 100, True), ("__indirect_call", "", None, False)],
                    [("Reset_Handler", f"{u}:serve.constprop.0"), ("Reset_Handler", f"{u}:serve.part.0"),
                     (f"{u}:serve.constprop.0", "__indirect_call"),
                     (f"{u}:serve.part.0", "__indirect_call")])
    rc, out, doc = run(tmp_path, "--entry", "Reset_Handler", "--indirect",
                       "app_uds.c:serve=read_did")
    assert rc == 0, out
    assert doc["entries"]["Reset_Handler"]["bytes"] == 8 + 40 + 100
    rc, out, _ = run(tmp_path, "--entry", "Reset_Handler", "--indirect", "serve=read_did")
    assert rc == 2 and "ambiguous" in out
