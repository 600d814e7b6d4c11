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
EXIT_OK, EXIT_LIMIT, EXIT_ERROR = 0, 1, 2

_BYTES_RE = re.compile(r"^(\d+) bytes \((static|dynamic|dynamic,bounded)\)$")
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

    def _get(self, title: str) -> Func:
        f = self.funcs.get(title)
        if f is None:
            f = self.funcs[title] = Func(title)
        return f

    def add_ci(self, path: Path) -> None:
        self.ci_files.append(path)
        nodes, edges = parse_vcg(path.read_text(errors="replace"))
        for n in nodes:
            title = n.get("title")
            if title is None:
                continue
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

    def resolve(self, name: str) -> str | None:
        """Title for a user-given function name: exact title, a static's plain name if
        unique, or a path suffix like "app.c:send"."""
        if name in self.funcs:
            return name
        cands = [t for t in self.funcs
                 if ":" in t and (t.rsplit(":", 1)[1] == name or t.endswith("/" + name))]
        if len(cands) == 1:
            return cands[0]
        if len(cands) > 1:
            raise AnalysisError(f"{name!r} is ambiguous: {', '.join(sorted(cands))}")
        return None


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
            extra: dict[str, int], unknown_bytes: int) -> Result:
    errors: list[str] = []
    notes = g.link_weak()

    def res(name: str, what: str) -> str | None:
        try:
            t = g.resolve(name)
        except AnalysisError as e:
            errors.append(f"{what}: {e}")
            return None
        if t is None and name in extra:
            g.funcs[name] = Func(name)     # e.g. an asm function known only by assumption
            t = name
        if t is None:
            errors.append(f"{what} {name!r}: not found in the call graph")
        return t

    ind: dict[str, list[str]] = {}
    for caller, callees in indirect.items():
        tc = res(caller, "--indirect caller")
        if tc is None:
            continue
        if INDIRECT not in g.funcs[tc].callees:
            notes.append(f"--indirect {caller}: it makes no indirect call (ignored)")
        ind[tc] = [t for t in (res(c, f"--indirect {caller} callee") for c in callees) if t]

    ext: dict[str, int] = {}
    for name, n in extra.items():
        t = res(name, "--extra-bytes")
        if t is not None:
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
        r = analyse(g, thread + isrs, indirect, extra, a.unknown_bytes)
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
