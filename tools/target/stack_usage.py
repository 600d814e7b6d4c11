#!/usr/bin/env python3
"""Worst-case stack depth of the firmware from GCC's call-graph output.

Compile every firmware object with `-fstack-usage -fcallgraph-info=su` (GCC >= 10; checked
with arm-none-eabi-gcc 12.2 and host gcc 12). Besides the object, GCC then writes
`<obj>.su` and `<obj>.ci`; this tool reads only the .ci files (VCG format), which carry
the same frame sizes as the .su files plus the calls:

    node: { title: "app_poll" label: "app_poll\\nfirmware/app/app.c:900:6\\n48 bytes (static)" }
    node: { title: "firmware/app/app.c:send" label: "send\\nfirmware/app/app.c:157:13\\n32 bytes (static)" }
    node: { title: "hal_can_send" label: "hal_can_send\\nhal/hal.h:40:5" shape : ellipse }
    node: { title: "memcpy" label: "__builtin_memcpy\\n<built-in>" shape : ellipse }
    node: { title: "__indirect_call" label: "Indirect Call Placeholder" shape : ellipse }
    edge: { sourcename: "app_poll" targetname: "firmware/app/app.c:send" label: "firmware/app/app.c:910:5" }

  * A function compiled in that object has "N bytes (static|dynamic|dynamic,bounded)" in
    its label. Functions with internal linkage (static) and also weak definitions are
    titled "<main source file as given to gcc>:<name>", so same-named static functions
    of different files stay apart (a static function defined in a header is qualified by
    the .c file that includes it). External functions are titled by their plain name.
  * A function only called, not defined, in that object has a label without a byte count
    and `shape : ellipse`; the .ci of the object that defines it gives its frame.
    Functions compiled without -fstack-usage (libgcc's __aeabi_*, newlib's memcpy, asm)
    never get a frame: they are "unknown".
  * Every call through a function pointer is an edge to the placeholder node
    "__indirect_call". Inlined calls (static inline, or inlined by -O2) are not calls: the
    callee's locals are in the caller's frame.

Code generated at the link (-flto): the objects hold GCC's intermediate code and no .ci;
linking with `-flto -fstack-usage -fcallgraph-info=su -dumpdir DIR/` writes one .ci per
partition (DIR/ltrans0.ltrans.ci ...), the frames and calls of the code in the image. Its
graph is titled after the partition's temporary object ("/tmp/ccXXXXXX.ltrans0.o"), and so
are its local functions (statics, and the globals the link made local):
"/tmp/ccXXXXXX.ltrans0.o:send.constprop.0". They are retitled after the source file of
their definition (the label's location), "firmware/app/output.c:send.constprop.0", like a
compiled object's statics. A function such a unit calls but does not define is an alias
made by identical code folding (several names at one address): --alias-group F1,F2,...
(the image's symbols at one address; tools/target/budget.py passes them) makes its calls
calls of the folded function that has a frame; one that no group resolves is an error,
never assumed.

Function names (--entry, --isr, --indirect, --extra-bytes) are "name" or "file.c:name"
(a path suffix will do): they match that function and the clones GCC made of it
(.constprop.N, .isra.N, .part.N, .lto_priv.N, .cold), in that file if one is given; an
--indirect list applies to each clone's indirect calls. A name that matches functions of
two files or two source functions is ambiguous (an error); "name.constprop.0" matches
only that clone.

Graphs of all .ci files under the --ci-dir directories (recursive) are merged by title.
For each entry the worst case is the maximum over call paths of the sum of the frames.
The analysis refuses (exit 2), listing every problem found on paths from the entries:
  * a cycle in the call graph (recursion: no finite worst case without a depth bound);
  * a function with a "dynamic" (unbounded: VLA, alloca) frame; "dynamic,bounded" is
    accepted with GCC's bound;
  * an indirect call whose possible callees are not given with
    --indirect CALLER=callee1,callee2 (these replace every indirect call site of CALLER);
  * an entry (or --indirect name) that is not found.
Unknown functions are assumed to be leaves using --extra-bytes NAME=N if given, else
--unknown-bytes (default 64); every assumption used is printed and written to the JSON.
For a function that does have a frame, --extra-bytes NAME=N adds N bytes to it (e.g.
for inline asm pushes the compiler does not count).

Interrupts (Cortex-M4F): thread-mode entries (--entry) run one at a time, so the thread
part is the maximum over them. Any interrupt can preempt the thread and, with distinct
priorities, also a lower-priority interrupt: the handlers nest, so the bound is
    total = max(thread entries) + sum(worst path of every --isr) + n_isr * frame
where `frame` (--exception-frame-bytes, default 104) is what the hardware stacks per
nesting level: with the FPU enabled and lazy stacking (FPCA set in the interrupted
context) the extended frame is 8 core words + S0-S15 + FPSCR + 1 reserved word =
26 words = 104 bytes (pass 108 to also cover the 4-byte alignment pad of CCR.STKALIGN).
Interrupts sharing a priority cannot preempt each other, so the sum over-estimates then
(pass only the worst handler of each priority level). Everything is assumed to run on one
stack (MSP); with an RTOS using PSP for threads this bound is for a thread's stack plus
the interrupt load, conservatively. An --isr name is also an entry.

    tools/target/stack_usage.py --ci-dir build/su --entry main --isr SysTick_Handler \\
        --indirect app_dispatch=on_imu,on_odo --extra-bytes memcpy=16 \\
        --limit-bytes 2048 --json out/stack.json

Exit status: 0 within the limit, 1 limit exceeded, 2 analysis error.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

INDIRECT = "__indirect_call"
# the title prefix of a link-time unit's local function that the unit calls but does not
# define (identical code folding made it an alias of another function)
LTO_LOCAL = "<ltrans>:"
EXIT_OK, EXIT_LIMIT, EXIT_ERROR = 0, 1, 2

_BYTES_RE = re.compile(r"^(\d+) bytes \((static|dynamic|dynamic,bounded)\)$")
_GRAPH_RE = re.compile(r'\s*graph:\s*\{\s*title:\s*"((?:[^"\\]|\\.)*)"')
# the temporary object of a link-time (-flto) partition: /tmp/ccXXXXXX.ltrans0.o
_LTRANS_RE = re.compile(r"(^|[./])ltrans\d+(\.ltrans)?\.o$")
_TOKEN_RE = re.compile(r'\s*(?:"((?:[^"\\]|\\.)*)"|([{}:])|([^\s{}:"]+))', re.S)


class AnalysisError(Exception):
    pass


@dataclass
class Func:
    title: str
    frame: int | None = None          # bytes; None: not compiled here (unknown)
    kind: str | None = None           # static | dynamic | dynamic,bounded
    location: str = ""                # file:line:col of the definition, if given
    callees: set[str] = field(default_factory=set)
    sources: list[str] = field(default_factory=list)   # .ci files defining it


# ------------------------------------------------------------------------------ parsing
def _unescape(s: str) -> str:
    return re.sub(r"\\(.)", lambda m: "\n" if m.group(1) == "n" else m.group(1), s)


def _tokens(text: str):
    pos = 0
    while pos < len(text):
        m = _TOKEN_RE.match(text, pos)
        if not m or m.end() == pos:
            if text[pos:].strip() == "":
                return
            raise AnalysisError(f"unparsable VCG near {text[pos:pos + 40]!r}")
        pos = m.end()
        if m.group(1) is not None:
            yield ("str", _unescape(m.group(1)))
        elif m.group(2) is not None:
            yield (m.group(2), m.group(2))
        else:
            yield ("word", m.group(3))


def parse_vcg(text: str) -> tuple[list[dict], list[dict]]:
    """Nodes and edges (attribute dicts) of a VCG text, nested graphs flattened."""
    nodes: list[dict] = []
    edges: list[dict] = []
    stack: list[tuple[str, dict]] = []
    toks = list(_tokens(text))
    i = 0
    while i < len(toks):
        kind, val = toks[i]
        if kind == "}":
            if not stack:
                raise AnalysisError("unbalanced '}' in VCG")
            what, attrs = stack.pop()
            if what == "node":
                nodes.append(attrs)
            elif what == "edge":
                edges.append(attrs)
            i += 1
            continue
        if kind in ("word", "str") and i + 1 < len(toks) and toks[i + 1][0] == ":":
            if i + 2 < len(toks) and toks[i + 2][0] == "{":
                stack.append((val, {}))
                i += 3
                continue
            if i + 2 < len(toks) and toks[i + 2][0] in ("word", "str"):
                if stack:
                    stack[-1][1][val] = toks[i + 2][1]
                i += 3
                continue
        raise AnalysisError(f"unexpected VCG token {val!r}")
    if stack:
        raise AnalysisError("unterminated '{' in VCG")
    return nodes, edges


class Graph:
    def __init__(self) -> None:
        self.funcs: dict[str, Func] = {}
        self.warnings: list[str] = []
        self.ci_files: list[Path] = []
        self.lto_units: list[str] = []

    def _get(self, title: str) -> Func:
        f = self.funcs.get(title)
        if f is None:
            f = self.funcs[title] = Func(title)
        return f

    def add_ci(self, path: Path) -> None:
        self.ci_files.append(path)
        text = path.read_text(errors="replace")
        nodes, edges = parse_vcg(text)
        m = _GRAPH_RE.match(text)
        unit = m.group(1) if m else ""
        rename: dict[str, str] = {}
        if _LTRANS_RE.search(unit):
            # a link-time (-flto) unit: its local functions are titled after the temporary
            # object it was compiled to; title them after the source file they were defined
            # in (their location), as a compiled object's statics are
            for n in nodes:
                title, lines = n.get("title"), n.get("label", "").split("\n")
                if title and title.startswith(unit + ":") and len(lines) >= 2 \
                        and lines[1].count(":") >= 2:
                    rename[title] = lines[1].rsplit(":", 2)[0] + title[len(unit):]
            # called there but not defined there: an alias (identical code folding) of a
            # function that is, resolved with --alias-group, or an error
            for t in [n.get("title") for n in nodes] + [e.get(k) for e in edges
                                                        for k in ("sourcename", "targetname")]:
                if t and t.startswith(unit + ":") and t not in rename:
                    rename[t] = LTO_LOCAL + t[len(unit) + 1:]
            self.lto_units.append(str(path))
        for n in nodes:
            title = n.get("title")
            if title is None:
                continue
            title = rename.get(title, title)
            f = self._get(title)
            lines = n.get("label", "").split("\n")
            size = next((m for m in (_BYTES_RE.match(x.strip()) for x in lines) if m), None)
            if size is None:
                if "shape" not in n and title != INDIRECT and len(lines) >= 2 \
                        and lines[1] != "<built-in>":
                    # defined here (no ellipse) but no size: -fcallgraph-info without =su
                    self.warnings.append(
                        f"{path}: {title} has no stack size (compile with "
                        f"-fcallgraph-info=su)")
                if not f.location and len(lines) >= 2:
                    f.location = lines[1]
                continue
            frame, kind = int(size.group(1)), size.group(2)
            if f.frame is not None and (f.frame, f.kind) != (frame, kind):
                self.warnings.append(
                    f"{title} defined twice with different frames ({f.frame} bytes "
                    f"{f.kind} in {', '.join(f.sources)}; {frame} bytes {kind} in {path}); "
                    f"using the larger frame and the worse kind")
            rank = {"static": 0, "dynamic,bounded": 1, "dynamic": 2}
            f.kind = kind if f.kind is None or rank[kind] > rank[f.kind] else f.kind
            f.frame = frame if f.frame is None else max(f.frame, frame)
            f.location = lines[1] if len(lines) >= 2 else f.location
            f.sources.append(str(path))
        for e in edges:
            src, dst = e.get("sourcename"), e.get("targetname")
            if src is None or dst is None:
                continue
            src, dst = rename.get(src, src), rename.get(dst, dst)
            self._get(src).callees.add(dst)
            self._get(dst)

    def link_weak(self) -> list[str]:
        """Calls by plain name to a function known only as "file.c:name" (a weak
        definition is titled like a static one) are linked to it; returns notes."""
        notes = []
        by_name: dict[str, list[str]] = {}
        for t, f in self.funcs.items():
            if ":" in t and f.frame is not None:
                by_name.setdefault(t.rsplit(":", 1)[1], []).append(t)
        alias: dict[str, str] = {}
        for t, f in self.funcs.items():
            if ":" not in t and f.frame is None and t != INDIRECT and \
                    len(by_name.get(t, [])) == 1:
                alias[t] = by_name[t][0]
                notes.append(f"call to external {t} linked to the only definition "
                             f"{alias[t]} (weak, or a same-named static: check)")
        if alias:
            for f in self.funcs.values():
                f.callees = {alias.get(c, c) for c in f.callees}
        return notes

    def link_aliases(self, groups: list[list[str]]) -> tuple[list[str], list[str]]:
        """Calls of a link-time unit's function it does not define (LTO_LOCAL: identical
        code folding made it an alias) become calls of the functions with a frame that
        share its address (groups: the symbol names at one address, from the image's
        symbol table). Returns (notes, errors): an error for each such function that no
        group resolves, so that none is assumed."""
        notes, errors = [], []
        by_asm: dict[str, list[str]] = {}
        for t, f in self.funcs.items():
            if f.frame is not None:
                by_asm.setdefault(t.rsplit(":", 1)[-1], []).append(t)
        alias: dict[str, list[str]] = {}
        for t, f in self.funcs.items():
            if not t.startswith(LTO_LOCAL) or f.frame is not None:
                continue
            asm = t[len(LTO_LOCAL):]
            targets = sorted({x for grp in groups if asm in grp for m in grp if m != asm
                              for x in by_asm.get(m, [])})
            if not targets:
                errors.append(f"{asm}: called in the code generated at the link but has no "
                              f"frame there and is no alias of a function that has one")
                continue
            alias[t] = targets
        folded: dict[str, list[str]] = {}
        for t, targets in sorted(alias.items()):
            folded.setdefault(", ".join(targets), []).append(t[len(LTO_LOCAL):])
        for targets, names in folded.items():
            notes.append(f"folded into {targets} (identical code): {', '.join(names)}")
        for f in self.funcs.values():
            if f.callees & alias.keys():
                f.callees = {x for c in f.callees for x in alias.get(c, [c])}
        return notes, errors

    def resolve(self, name: str) -> list[str]:
        """Titles for a user-given function name, "name" or "file.c:name" (a path suffix
        will do): the functions of that name, and their clones (GCC's suffixes .constprop.N,
        .isra.N, .part.N, .lto_priv.N, .cold: the link (-flto) makes them of static and
        global functions alike), in that file if one is given. Several only when they are
        one source function and its clones (one file, one name): else the name is
        ambiguous (an error). A name with a suffix ("f.constprop.0") only that function.
        [] when nothing matches."""
        want_file, want = name.rsplit(":", 1) if ":" in name else (None, name)
        exact = "." in want
        found: dict[tuple[str, str], list[str]] = {}
        for t, f in self.funcs.items():
            if t == INDIRECT:
                continue
            if ":" in t:
                file, asm = t.rsplit(":", 1)
            else:
                file, asm = (f.location.rsplit(":", 2)[0] if f.location.count(":") >= 2
                             else ""), t
            if (asm if exact else asm.split(".", 1)[0]) != want:
                continue
            if want_file is not None and not (file == want_file or
                                              file.endswith("/" + want_file)):
                continue
            found.setdefault((file, want), []).append(t)
        if len(found) > 1:
            raise AnalysisError(f"{name!r} is ambiguous: "
                                f"{', '.join(sorted(t for v in found.values() for t in v))}")
        return sorted(next(iter(found.values()))) if found else []


def load(dirs: list[Path]) -> Graph:
    g = Graph()
    for d in dirs:
        if not d.is_dir():
            raise AnalysisError(f"--ci-dir {d}: not a directory")
        files = sorted(d.rglob("*.ci"))
        if not files:
            raise AnalysisError(f"--ci-dir {d}: no .ci files (compile with "
                                f"-fstack-usage -fcallgraph-info=su)")
        for p in files:
            g.add_ci(p)
    return g


# ----------------------------------------------------------------------------- analysis
@dataclass
class Result:
    entries: dict[str, tuple[int, list[tuple[str, int]]]]
    assumed: dict[str, int]
    errors: list[str]
    notes: list[str]
    extra: dict[str, int]             # --extra-bytes by resolved title


def analyse(g: Graph, entries: list[str], indirect: dict[str, list[str]],
            extra: dict[str, int], unknown_bytes: int,
            alias_groups: list[list[str]] | None = None) -> Result:
    errors: list[str] = []
    notes = g.link_weak()
    n, e = g.link_aliases(alias_groups or [])
    notes += n
    errors += e

    def res_all(name: str, what: str) -> list[str]:
        try:
            ts = g.resolve(name)
        except AnalysisError as e:
            errors.append(f"{what}: {e}")
            return []
        if not ts and name in extra:
            g.funcs[name] = Func(name)     # e.g. an asm function known only by assumption
            ts = [name]
        if not ts:
            errors.append(f"{what} {name!r}: not found in the call graph")
        elif ts != [name]:
            notes.append(f"{what} {name!r} is {', '.join(ts)}")
        return ts

    def res(name: str, what: str) -> str | None:
        ts = res_all(name, what)
        if len(ts) > 1:
            errors.append(f"{what} {name!r}: several functions ({', '.join(ts)})")
            return None
        return ts[0] if ts else None

    ind: dict[str, list[str]] = {}
    for caller, callees in indirect.items():
        tcs = res_all(caller, "--indirect caller")
        targets = sorted({t for c in callees for t in res_all(c, f"--indirect {caller} callee")})
        for tc in tcs:
            if INDIRECT not in g.funcs[tc].callees:
                notes.append(f"--indirect {caller}: {tc} makes no indirect call (ignored)")
            ind[tc] = sorted(set(ind.get(tc, [])) | set(targets))

    ext: dict[str, int] = {}
    for name, n in extra.items():
        for t in res_all(name, "--extra-bytes"):
            ext[t] = n

    roots = []
    for e in entries:
        t = res(e, "entry")
        if t is not None:
            if g.funcs[t].frame is None and t not in ext:
                errors.append(f"entry {e!r}: no stack size (not compiled with "
                              f"-fstack-usage, or only declared)")
            else:
                roots.append(t)

    def callees(t: str) -> list[str]:
        out = []
        for c in sorted(g.funcs[t].callees):
            if c == INDIRECT:
                out.extend(ind.get(t, []))
            else:
                out.append(c)
        return sorted(set(out))

    assumed: dict[str, int] = {}

    def frame(t: str) -> int:
        f = g.funcs[t]
        if f.frame is None:
            n = ext.get(t, unknown_bytes)
            assumed[t] = n
            return n
        return f.frame + ext.get(t, 0)

    # iterative DFS, post-order; best[t] = (worst bytes from t, next callee on the path)
    best: dict[str, tuple[int, str | None]] = {}
    on_path: dict[str, int] = {}
    unresolved: set[str] = set()
    dynamic: set[str] = set()
    cycles: set[tuple[str, ...]] = set()
    for root in roots:
        if root in best:
            continue
        path: list[str] = [root]
        its = [iter(callees(root))]
        on_path[root] = 0
        while path:
            t = path[-1]
            c = next(its[-1], None)
            if c is None:
                f = g.funcs[t]
                if INDIRECT in f.callees and t not in ind:
                    unresolved.add(t)
                if f.kind == "dynamic":
                    dynamic.add(t)
                sub = [(best[x][0], x) for x in callees(t) if x in best]
                top = max(sub, key=lambda s: s[0], default=(0, None))  # first max
                best[t] = (frame(t) + top[0], top[1])
                del on_path[t]
                path.pop()
                its.pop()
                continue
            if c in on_path:
                cyc = path[on_path[c]:] + [c]
                k = cyc[:-1].index(min(cyc[:-1]))       # canonical rotation
                cycles.add(tuple(cyc[k:-1] + cyc[:k] + [cyc[k]]))
                continue
            if c in best:
                continue
            on_path[c] = len(path)
            path.append(c)
            its.append(iter(callees(c)))

    for cyc in sorted(cycles):
        errors.append("recursion, no finite worst case: " + " -> ".join(cyc))
    for t in sorted(dynamic):
        errors.append(f"unbounded dynamic stack frame (VLA/alloca): {t} "
                      f"({g.funcs[t].location}, {g.funcs[t].frame} bytes + dynamic)")
    if unresolved:
        errors.append("indirect calls without --indirect CALLER=callee,...: "
                      + ", ".join(sorted(unresolved)))
    for t in sorted(x for x in best if g.funcs[x].kind == "dynamic,bounded"):
        notes.append(f"{t}: dynamic,bounded frame, using GCC's bound {g.funcs[t].frame}")

    out: dict[str, tuple[int, list[tuple[str, int]]]] = {}
    if not errors:
        for e, root in zip(entries, roots):
            steps, t = [], root
            while t is not None:
                steps.append((t, frame(t)))
                t = best[t][1]
            out[e] = (best[root][0], steps)
    return Result(out, dict(sorted(assumed.items())), errors, notes, ext)


# ---------------------------------------------------------------------------------- CLI
def _kv(s: str, what: str) -> tuple[str, str]:
    if "=" not in s:
        raise argparse.ArgumentTypeError(f"{what} wants NAME=VALUE, got {s!r}")
    k, v = s.split("=", 1)
    return k.strip(), v.strip()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ci-dir", action="append", type=Path, required=True,
                    help="directory searched recursively for .ci files (repeatable)")
    ap.add_argument("--entry", action="append", default=[],
                    help="thread-mode entry function (repeatable)")
    ap.add_argument("--isr", action="append", default=[],
                    help="interrupt handler: an entry whose worst case adds to the total")
    ap.add_argument("--limit-bytes", type=int, default=2048)
    ap.add_argument("--indirect", action="append", default=[], metavar="CALLER=C1,C2",
                    help="possible callees of CALLER's indirect calls")
    ap.add_argument("--extra-bytes", action="append", default=[], metavar="NAME=N",
                    help="stack of an unknown function, or bytes added to a known frame")
    ap.add_argument("--unknown-bytes", type=int, default=64,
                    help="assumed stack of unknown (library leaf) functions (default 64)")
    ap.add_argument("--exception-frame-bytes", type=int, default=104,
                    help="hardware-stacked bytes per interrupt nesting level "
                         "(default 104: Cortex-M4F extended frame with FPU state)")
    ap.add_argument("--alias-group", action="append", default=[], metavar="F1,F2,...",
                    help="functions at one address (the image's symbols): a call of one "
                         "the code generated at the link does not define is a call of the "
                         "others (identical code folding)")
    ap.add_argument("--json", type=Path, help="write the results as JSON")
    a = ap.parse_args(argv)

    try:
        indirect = {}
        for s in a.indirect:
            k, v = _kv(s, "--indirect")
            indirect[k] = [x.strip() for x in v.split(",") if x.strip()]
            if not indirect[k]:
                ap.error(f"--indirect {s}: no callees")
        extra = {}
        for s in a.extra_bytes:
            k, v = _kv(s, "--extra-bytes")
            extra[k] = int(v)
    except (argparse.ArgumentTypeError, ValueError) as e:
        ap.error(str(e))

    isrs = list(dict.fromkeys(a.isr))
    thread = [e for e in dict.fromkeys(a.entry) if e not in isrs]
    if not thread and not isrs:
        ap.error("give at least one --entry or --isr")

    try:
        g = load(a.ci_dir)
        r = analyse(g, thread + isrs, indirect, extra, a.unknown_bytes,
                    [[x.strip() for x in grp.split(",") if x.strip()] for grp in a.alias_group])
    except AnalysisError as e:
        r = None
        errors = [str(e)]
    else:
        errors = r.errors

    doc: dict = {"ci_files": len(g.ci_files) if r else 0, "errors": errors}
    if r is not None:
        for w in g.warnings:
            print(f"warning: {w}")
        for n in r.notes:
            print(f"note: {n}")
    if errors:
        for e in errors:
            print(f"error: {e}", file=sys.stderr)
        print("stack analysis FAILED (see errors above)", file=sys.stderr)
        if a.json:
            a.json.parent.mkdir(parents=True, exist_ok=True)
            a.json.write_text(json.dumps(doc, indent=2) + "\n")
        return EXIT_ERROR

    assert r is not None
    print(f"{len(g.ci_files)} call-graph files, {sum(1 for f in g.funcs.values() if f.frame is not None)} functions with a stack size")
    for e in thread + isrs:
        total, steps = r.entries[e]
        kind = "isr" if e in isrs else "entry"
        print(f"{kind} {e}: {total} bytes")
        acc = 0
        for fn, b in steps:
            acc += b
            tag = " (assumed)" if fn in r.assumed else ""
            print(f"    {b:6d}  {acc:6d}  {fn}{tag}")
    if r.assumed:
        print(f"assumed stack of functions without stack information "
              f"(--unknown-bytes {a.unknown_bytes} unless --extra-bytes):")
        for fn, b in r.assumed.items():
            src = "--extra-bytes" if fn in r.extra else "default"
            print(f"    {b:6d}  {fn} ({src})")
    thread_bytes = max((r.entries[e][0] for e in thread), default=0)
    isr_sum = sum(r.entries[e][0] for e in isrs)
    exc = a.exception_frame_bytes * len(isrs)
    isr_bytes = isr_sum + exc
    total = thread_bytes + isr_bytes
    print(f"thread worst case {thread_bytes} bytes"
          + (f" + ISRs {isr_sum} bytes + {len(isrs)} x {a.exception_frame_bytes} bytes "
             f"exception frames" if isrs else ""))
    ok = total <= a.limit_bytes
    print(f"total worst case {total} bytes, limit {a.limit_bytes} bytes: "
          + ("OK" if ok else f"EXCEEDED by {total - a.limit_bytes} bytes"))

    doc.update({
        "entries": {e: {"bytes": r.entries[e][0], "path": [[fn, b] for fn, b in r.entries[e][1]],
                        "isr": e in isrs} for e in thread + isrs},
        "thread_bytes": thread_bytes,
        "isr_bytes": isr_bytes,
        "exception_frame_bytes": a.exception_frame_bytes,
        "total_bytes": total,
        "limit_bytes": a.limit_bytes,
        "assumed": r.assumed,
        "unknown_bytes": a.unknown_bytes,
        "notes": r.notes + g.warnings,
    })
    if a.json:
        a.json.parent.mkdir(parents=True, exist_ok=True)
        a.json.write_text(json.dumps(doc, indent=2) + "\n")
    return EXIT_OK if ok else EXIT_LIMIT


if __name__ == "__main__":
    sys.exit(main())
