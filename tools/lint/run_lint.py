#!/usr/bin/env python3
"""
run_lint.py - the static analysis behind `make lint` (docs/misra.md).

Runs three analysers over the firmware's C sources (firmware/ without the generated codec
firmware/can/gen/, hal/ and boards/; never tests/):

  cppcheck   2.10 with its MISRA C:2012 addon, for the ECU's configuration: the float32
             variant (NAV_REAL_DOUBLE undefined), __ARM_EABI__, the Cortex-M4F platform
             tools/lint/cortex-m4f.xml, --std=c11, include paths FW_INC + hal/common +
             hal/cortex_m4f;
  clang-tidy 14 with bugprone-*, cert-*, clang-analyzer-* (tools/lint/clang-tidy.yaml),
             compiled as for the host (CFLAGS_BASE, -D_DEFAULT_SOURCE) and, for
             hal/cortex_m4f/, also with --target=arm-none-eabi and the M4F flags;
  gcc        -fanalyzer with CFLAGS_BASE: the host gcc for what the host builds,
             arm-none-eabi-gcc (the same GCC 12) for hal/cortex_m4f/.

Every finding is normalised to  file:check:function  (function "-" outside any function),
so that a line shift does not change it, and then classified:

  excluded   in a file that cppcheck-suppressions.txt takes out as a whole (`*:glob`:
             the generated codec, whose header the application includes);
  deviation  matched by tools/lint/cppcheck-suppressions.txt (cppcheck's own format:
             `id`, `id:file-glob` or `id:file-glob:line`): a MISRA rule the project
             deviates from, project-wide or for the files named;
  accepted   listed in tools/lint/<tool>-accepted.txt as file:check:function: one
             finding (or the findings of one check in one function) judged and kept;
  new        anything else: `make lint` fails.

Each rule or check of a deviation or accepted entry must be named in docs/misra.md with its
reason, or the run fails too ("unexplained"). Entries that match nothing any more are
reported as stale (--strict makes them fail). Options: --counts prints the per-rule table
of docs/misra.md; --update rewrites the accepted lists to the current findings (new entries
marked for review; their reasons still have to be written in docs/misra.md).

Only the Python standard library; exit status 0 (pass), 1 (a new or unexplained finding),
2 (a tool is missing or failed).
"""

import argparse
import bisect
import concurrent.futures
import fnmatch
import os
import re
import shlex
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
LINT_DIR = os.path.join("tools", "lint")
SUPPRESSIONS = os.path.join(LINT_DIR, "cppcheck-suppressions.txt")
ACCEPTED = {
    "cppcheck": os.path.join(LINT_DIR, "cppcheck-accepted.txt"),
    "clang-tidy": os.path.join(LINT_DIR, "clang-tidy-accepted.txt"),
    "gcc-analyzer": os.path.join(LINT_DIR, "gcc-analyzer-accepted.txt"),
}
DOC = os.path.join("docs", "misra.md")
TOOLS = ("cppcheck", "clang-tidy", "gcc-analyzer")

# Defaults equal to the Makefile's; `make lint` passes its own values.
DEFAULT_CFLAGS = ("-std=c11 -O2 -g -Wall -Wextra -Werror -Wpedantic -Wconversion "
                  "-Wdouble-promotion -Wfloat-equal -Wshadow -Wstrict-prototypes "
                  "-Wmissing-prototypes -ffp-contract=off -fno-math-errno")
DEFAULT_FW_INC = ("-Ifirmware/nav -Ifirmware/can -Ifirmware/can/gen -Ifirmware/diag -Ifirmware/app "
                  "-Ifirmware/vehicle -Ihal")
DEFAULT_M4_FLAGS = "-mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard -mthumb"
# hal/cortex_m4f/ drivers the host also compiles (their tests run against register blocks
# in RAM: TESTS_M4_HAL); the rest of hal/cortex_m4f/ builds for the M4F only
DEFAULT_HOST_M4 = ("hal/cortex_m4f/bxcan.c hal/cortex_m4f/stm32_flash.c "
                   "hal/cortex_m4f/stm32_iwdg.c hal/cortex_m4f/stm32_clock.c "
                   "hal/cortex_m4f/stm32_timebase.c hal/cortex_m4f/f2l.c hal/cortex_m4f/u64div.c")
ARM_SYSROOT_INC = "/usr/lib/arm-none-eabi/include"  # newlib's headers, for clang-tidy


class Finding:
    __slots__ = ("tool", "file", "line", "col", "check", "message", "function", "status")

    def __init__(self, tool, file, line, col, check, message):
        self.tool = tool
        self.file = file
        self.line = line
        self.col = col
        self.check = check
        self.message = message
        self.function = "-"
        self.status = "new"

    def key(self):
        return (self.tool, self.file, self.check, self.function)

    def where(self):
        return "%s:%d:%d" % (self.file, self.line, self.col)


# ---------------------------------------------------------------- source files, functions

def find_sources():
    out = []
    for top in ("firmware", "hal", "boards"):
        for dirpath, dirnames, filenames in os.walk(os.path.join(ROOT, top)):
            dirnames.sort()
            rel = os.path.relpath(dirpath, ROOT)
            if rel.replace(os.sep, "/").startswith("firmware/can/gen"):
                dirnames[:] = []
                continue
            for f in sorted(filenames):
                if f.endswith(".c"):
                    out.append(os.path.join(rel, f).replace(os.sep, "/"))
    return out


def relpath(path):
    p = os.path.normpath(path if os.path.isabs(path) else os.path.join(ROOT, path))
    return os.path.relpath(p, ROOT).replace(os.sep, "/")


def _blank_comments_strings(text):
    """Comments, string and character literals and preprocessor lines replaced by blanks
    (newlines kept), so that braces and parentheses can be counted."""
    out = []
    i, n = 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c in " \t":
            out.append(c)
            i += 1
            continue
        if line_start and c == "#":
            # a directive, with its backslash continuations
            while i < n and text[i] != "\n":
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out.append(" \n")
                    i += 2
                    continue
                out.append(" ")
                i += 1
            continue
        line_start = False
        if c == "\n":
            line_start = True
            out.append(c)
            i += 1
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


_IDENT_END = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\s*$")


def _function_name_before(code, pos):
    """Name of the function whose body opens at code[pos] == '{' (depth 0), or None."""
    j = pos - 1
    for _ in range(4):  # skip up to a few trailing __attribute__((...)) groups
        while j >= 0 and code[j].isspace():
            j -= 1
        if j < 0 or code[j] != ")":
            return None, None
        depth = 0
        while j >= 0:
            if code[j] == ")":
                depth += 1
            elif code[j] == "(":
                depth -= 1
                if depth == 0:
                    break
            j -= 1
        if j < 0:
            return None, None
        m = _IDENT_END.search(code, 0, j)
        if m is None:
            return None, None
        name = m.group(1)
        if name in ("__attribute__", "__attribute", "__asm__", "asm"):
            j = m.start(1) - 1
            continue
        if name in ("if", "while", "for", "switch", "return", "sizeof"):
            return None, None
        return name, m.start(1)
    return None, None


_FUNC_CACHE = {}


def functions_of(path):
    """[(first line, last line, name)] of the function definitions in path."""
    if path in _FUNC_CACHE:
        return _FUNC_CACHE[path]
    try:
        with open(os.path.join(ROOT, path), encoding="utf-8", errors="replace") as fh:
            code = _blank_comments_strings(fh.read())
    except OSError:
        _FUNC_CACHE[path] = []
        return []
    funcs = []
    depth = 0
    cur = None
    for pos, c in enumerate(code):
        if c == "{":
            if depth == 0:
                name, at = _function_name_before(code, pos)
                cur = (code.count("\n", 0, at) + 1, name) if name else None
            depth += 1
        elif c == "}":
            depth = max(depth - 1, 0)
            if depth == 0 and cur is not None:
                funcs.append((cur[0], code.count("\n", 0, pos) + 1, cur[1]))
                cur = None
    _FUNC_CACHE[path] = funcs
    return funcs


def function_at(path, line):
    funcs = functions_of(path)
    starts = [f[0] for f in funcs]
    k = bisect.bisect_right(starts, line) - 1
    if k >= 0 and funcs[k][0] <= line <= funcs[k][1]:
        return funcs[k][2]
    return "-"


# ---------------------------------------------------------------- running the tools

def run(cmd, cwd=ROOT):
    p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       universal_newlines=True, errors="replace")
    return p.returncode, p.stdout


def tool_version(cmd):
    try:
        rc, out = run(cmd)
    except OSError:
        return None
    for line in out.splitlines():
        m = re.search(r"(\d+\.\d+(\.\d+)?)", line)
        if m:
            return m.group(1)
    return None


_CPPCHECK_SEP = "@@"


def cppcheck_cmd(files, cfg):
    tmpl = _CPPCHECK_SEP.join(["{file}", "{line}", "{column}", "{severity}", "{id}", "{message}"])
    # a fresh build directory each run: cppcheck keeps its whole-program (CTU) data there,
    # and data left from an older version of a file would give stale findings
    build_dir = os.path.join(cfg.build_dir, "cppcheck")
    shutil.rmtree(os.path.join(ROOT, build_dir), ignore_errors=True)
    os.makedirs(os.path.join(ROOT, build_dir))
    return (["cppcheck", "--quiet", "--std=c11", "--language=c",
             "--platform=" + os.path.join(LINT_DIR, "cortex-m4f.xml"),
             "--addon=misra",
             "--enable=warning,style,performance,portability",
             # the float32 firmware on the M4F: NAV_REAL_DOUBLE (the double reference
             # variant of the tests) and NAV_ACC_PLAIN (the numerics study) undefined
             "-D__ARM_EABI__=1", "-D__arm__=1", "-UNAV_REAL_DOUBLE", "-UNAV_ACC_PLAIN",
             "-U__cplusplus",
             "--cppcheck-build-dir=" + build_dir,
             "-j", str(cfg.jobs),
             "--template=" + tmpl]
            + shlex.split(cfg.fw_inc) + ["-Ihal/common", "-Ihal/cortex_m4f", "-Iboards/qemu"]
            + files)


def parse_cppcheck(out):
    found = []
    other = []
    for line in out.splitlines():
        parts = line.split(_CPPCHECK_SEP)
        if len(parts) != 6:
            if line.strip():
                other.append(line)
            continue
        file, ln, col, sev, cid, msg = parts
        if not file or file == "nofile":
            file = "-"
        found.append(Finding("cppcheck", relpath(file) if file != "-" else "-",
                             int(ln or 0), int(col or 0), cid, msg))
    return found, other


_CLANG_DIAG = re.compile(r"^(.+?):(\d+):(\d+): (warning|error): (.*) \[([^\]]+)\]$")


def parse_clang_tidy(out, tag):
    found = []
    for line in out.splitlines():
        m = _CLANG_DIAG.match(line)
        if not m:
            continue
        file, ln, col, sev, msg, checks = m.groups()
        check = checks.split(",")[0]
        f = Finding("clang-tidy", relpath(file), int(ln), int(col), check, msg)
        f.message = "%s (%s)" % (msg, tag)
        found.append(f)
    return found


_GCC_DIAG = re.compile(r"^(.+?):(\d+):(\d+): (warning|error): (.*?)(?: \[(-W[^\]]+)\])?$")


def parse_gcc(out, tag):
    found = []
    for line in out.splitlines():
        m = _GCC_DIAG.match(line)
        if not m:
            continue
        file, ln, col, sev, msg, opt = m.groups()
        check = opt if opt else ("error" if sev == "error" else "warning")
        # the analyser's CWE tag ("[CWE-775]") is part of the message, not of the check
        msg = re.sub(r"\s*\[CWE-\d+\]$", "", msg)
        found.append(Finding("gcc-analyzer", relpath(file), int(ln), int(col), check,
                             "%s (%s)" % (msg, tag)))
    return found


def clang_tidy_job(path, flags, tag):
    cmd = ["clang-tidy", "--quiet", "--config-file=" + os.path.join(LINT_DIR, "clang-tidy.yaml"),
           path, "--"] + flags
    rc, out = run(cmd)
    found = parse_clang_tidy(out, tag)
    if rc != 0 and not found:
        return found, "clang-tidy failed on %s (%s):\n%s" % (path, tag, out[-2000:])
    return found, None


def gcc_job(cc, path, flags, tag):
    cmd = [cc] + flags + ["-fanalyzer", "-fdiagnostics-plain-output",
                          "-fdiagnostics-path-format=none", "-c", path, "-o", os.devnull]
    rc, out = run(cmd)
    found = parse_gcc(out, tag)
    if rc != 0 and not found:
        return found, "%s failed on %s:\n%s" % (cc, path, out[-2000:])
    return found, None


# ---------------------------------------------------------------- baselines

def read_suppressions(path):
    """cppcheck suppressions: [(id glob, file glob or None, line or None, line no.)]"""
    out = []
    try:
        with open(os.path.join(ROOT, path), encoding="utf-8") as fh:
            lines = fh.readlines()
    except OSError:
        return out
    for no, raw in enumerate(lines, 1):
        s = raw.strip()
        if not s or s.startswith("#") or s.startswith("//"):
            continue
        parts = s.split(":")
        cid = parts[0]
        fglob = parts[1] if len(parts) > 1 and parts[1] else None
        line = int(parts[2]) if len(parts) > 2 and parts[2].isdigit() else None
        out.append((cid, fglob, line, no))
    return out


def read_accepted(path):
    """accepted findings: {(file, check, function): comment}"""
    out = {}
    try:
        with open(os.path.join(ROOT, path), encoding="utf-8") as fh:
            lines = fh.readlines()
    except OSError:
        return out
    for raw in lines:
        s = raw.rstrip("\n")
        body, _, comment = s.partition("#")
        body = body.strip()
        if not body:
            continue
        parts = body.split(":")
        if len(parts) != 3:
            raise SystemExit("lint: %s: not file:check:function: %r" % (path, s))
        out[tuple(p.strip() for p in parts)] = comment.strip()
    return out


def classify(findings, suppressions, accepted):
    used_supp = set()
    used_acc = set()
    for f in findings:
        if f.tool == "cppcheck":
            for sup in suppressions:
                cid, fglob, line, no = sup
                if not fnmatch.fnmatchcase(f.check, cid):
                    continue
                if fglob is not None and not fnmatch.fnmatchcase(f.file, fglob):
                    continue
                if line is not None and line != f.line:
                    continue
                # "*:glob" takes files out of the analysis (the generated codec)
                f.status = "excluded" if cid == "*" else "deviation"
                used_supp.add(no)
                break
            if f.status != "new":
                continue
        k = (f.file, f.check, f.function)
        if k in accepted.get(f.tool, {}):
            f.status = "accepted"
            used_acc.add((f.tool,) + k)
    return used_supp, used_acc


def doc_text():
    """docs/misra.md without its generated counts table (naming a rule there explains
    nothing)."""
    try:
        with open(os.path.join(ROOT, DOC), encoding="utf-8") as fh:
            return fh.read().split("\n## Counts", 1)[0]
    except OSError:
        return ""


def explained(check, doc):
    """A MISRA rule needs its row in a rule table ("| 15.5 (A) | ..."), any other check its
    name in backquotes."""
    m = re.match(r"misra-c2012-(\d+\.\d+)$", check)
    if m:
        return re.search(r"^\|\s*%s \([RA]\)\s*\|" % re.escape(m.group(1)), doc, re.M) is not None
    return ("`%s`" % check) in doc


def unexplained(suppressions, accepted):
    """Rules and checks of the suppression and accepted lists that docs/misra.md does not
    explain."""
    doc = doc_text()
    missing = []
    for cid, fglob, line, no in suppressions:
        if cid == "*":
            if fglob and ("`*:%s`" % fglob) not in doc:
                missing.append("%s:%d: %s:%s (the exclusion of %s)" % (SUPPRESSIONS, no, cid, fglob, fglob))
            continue
        if not explained(cid, doc):
            missing.append("%s:%d: %s" % (SUPPRESSIONS, no, cid))
    for tool, entries in accepted.items():
        for (file, check, func), comment in sorted(entries.items()):
            if not explained(check, doc):
                missing.append("%s: %s:%s:%s (check %s)" % (ACCEPTED[tool], file, check, func, check))
            elif not comment or comment.startswith("REVIEW"):
                missing.append("%s: %s:%s:%s (no reason after '#')" % (ACCEPTED[tool], file, check, func))
    return missing


def write_accepted(tool, findings, old):
    path = os.path.join(ROOT, ACCEPTED[tool])
    with open(path, encoding="utf-8") as fh:
        header = [l for l in fh.readlines() if l.startswith("#") and not l.startswith("#  ")]
    keys = {}
    for f in findings:
        if f.tool == tool and f.status in ("new", "accepted"):
            keys.setdefault((f.file, f.check, f.function), 0)
            keys[(f.file, f.check, f.function)] += 1
    with open(path, "w", encoding="utf-8") as fh:
        fh.writelines(header)
        for k in sorted(keys):
            comment = old.get(k) or "REVIEW: new; give the reason in docs/misra.md"
            fh.write("%s:%s:%s  # %s\n" % (k[0], k[1], k[2], comment))


# ---------------------------------------------------------------- reports

def rule_sort_key(check):
    m = re.match(r"misra-c2012-(\d+)\.(\d+)$", check)
    if m:
        return (0, int(m.group(1)), int(m.group(2)), check)
    return (1, 0, 0, check)


def print_counts(findings):
    rows = {}
    for f in findings:
        if f.status == "excluded":
            continue
        r = rows.setdefault((f.tool, f.check), {"deviation": 0, "accepted": 0, "new": 0, "files": {}})
        r[f.status] += 1
        r["files"][f.file] = r["files"].get(f.file, 0) + 1
    print("| tool | rule / check | findings | deviation | accepted | new | files (findings) |")
    print("|---|---|---:|---:|---:|---:|---|")
    for tool in TOOLS:
        for (t, check) in sorted((k for k in rows if k[0] == tool), key=lambda k: rule_sort_key(k[1])):
            r = rows[(t, check)]
            files = ", ".join("%s (%d)" % (fn, n) for fn, n in sorted(r["files"].items()))
            total = r["deviation"] + r["accepted"] + r["new"]
            print("| %s | %s | %d | %d | %d | %d | %s |" % (tool, check, total, r["deviation"],
                                                          r["accepted"], r["new"], files))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cflags", default=DEFAULT_CFLAGS, help="CFLAGS_BASE of the Makefile")
    ap.add_argument("--fw-inc", default=DEFAULT_FW_INC, help="FW_INC of the Makefile")
    ap.add_argument("--m4-flags", default=DEFAULT_M4_FLAGS, help="M4_FLAGS of the Makefile")
    ap.add_argument("--host-m4", default=DEFAULT_HOST_M4,
                    help="hal/cortex_m4f sources the host also compiles")
    ap.add_argument("--host-cc", default="gcc")
    ap.add_argument("--arm-cc", default="arm-none-eabi-gcc")
    ap.add_argument("--build-dir", default="build/lint")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--tools", default=",".join(TOOLS), help="comma-separated subset of " + ",".join(TOOLS))
    ap.add_argument("--counts", action="store_true", help="print the per-rule table (docs/misra.md)")
    ap.add_argument("--list", action="store_true", help="print every finding with its status")
    ap.add_argument("--update", action="store_true", help="rewrite the accepted lists to the current findings")
    ap.add_argument("--strict", action="store_true", help="stale baseline entries fail too")
    ap.add_argument("files", nargs="*", help="sources (default: firmware/, hal/ and boards/ without firmware/can/gen/)")
    cfg = ap.parse_args()
    os.chdir(ROOT)
    tools = [t.strip() for t in cfg.tools.split(",") if t.strip()]
    for t in tools:
        if t not in TOOLS:
            ap.error("unknown tool %s" % t)

    needed = {"cppcheck": ["cppcheck"], "clang-tidy": ["clang-tidy"],
              "gcc-analyzer": [cfg.host_cc, cfg.arm_cc]}
    missing = sorted({exe for t in tools for exe in needed[t] if shutil.which(exe) is None})
    if missing:
        print("lint: missing %s (Debian: apt-get install cppcheck clang-tidy gcc-arm-none-eabi; "
              "make deps installs them as root)" % " ".join(missing), file=sys.stderr)
        return 2

    files = [relpath(f) for f in cfg.files] if cfg.files else find_sources()
    m4_only = ("hal/cortex_m4f/", "boards/")
    m4 = [f for f in files if f.startswith(m4_only)]
    host_m4 = set(shlex.split(cfg.host_m4))
    host = [f for f in files if not f.startswith(m4_only) or f in host_m4]

    cflags = [x for x in shlex.split(cfg.cflags) if x != "-Werror"]
    fw_inc = shlex.split(cfg.fw_inc)
    inc = fw_inc + ["-Ihal/common", "-Ihal/cortex_m4f", "-Iboards/qemu"]
    host_flags = cflags + ["-D_DEFAULT_SOURCE"] + inc + ["-Ihal/linux"]
    arm_flags = cflags + shlex.split(cfg.m4_flags) + inc
    # clang-tidy: the same, without GCC's warning options (the build enforces those) and
    # with clang's target for the M4F
    tidy_common = [x for x in cflags if not x.startswith("-W")]
    tidy_host = tidy_common + ["-D_DEFAULT_SOURCE"] + inc + ["-Ihal/linux"]
    tidy_arm = (["--target=arm-none-eabi"] + tidy_common + shlex.split(cfg.m4_flags)
                + ["-isystem", ARM_SYSROOT_INC] + inc)

    t0 = time.monotonic()
    findings = []
    failures = []
    cpp_proc = None
    if "cppcheck" in tools:
        # its output to a file: a pipe read only at the end would stall it when full
        cmd = cppcheck_cmd(files, cfg)
        cpp_out = open(os.path.join(ROOT, cfg.build_dir, "cppcheck.out"), "w+", encoding="utf-8",
                       errors="replace")
        cpp_proc = subprocess.Popen(cmd, cwd=ROOT, stdout=cpp_out, stderr=subprocess.STDOUT)
    jobs = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(cfg.jobs, 1)) as pool:
        if "clang-tidy" in tools:
            jobs += [pool.submit(clang_tidy_job, f, tidy_host, "host") for f in host]
            jobs += [pool.submit(clang_tidy_job, f, tidy_arm, "arm-none-eabi") for f in m4]
        if "gcc-analyzer" in tools:
            jobs += [pool.submit(gcc_job, cfg.host_cc, f, host_flags, "host gcc") for f in host]
            jobs += [pool.submit(gcc_job, cfg.arm_cc, f, arm_flags, "arm-none-eabi-gcc") for f in m4]
        for j in jobs:
            found, err = j.result()
            findings += found
            if err:
                failures.append(err)
    if cpp_proc is not None:
        cpp_proc.wait()
        cpp_out.seek(0)
        found, other = parse_cppcheck(cpp_out.read())
        cpp_out.close()
        if other and cpp_proc.returncode == 0 and cfg.jobs > 1:
            # cppcheck's parallel workers can interleave their lines in one output (seen on a
            # loaded machine): run it again on one worker, whose output cannot interleave
            print("lint: cppcheck's output interleaved (-j %d); once more with -j 1" % cfg.jobs,
                  file=sys.stderr)
            cmd1 = cppcheck_cmd(files, cfg)
            cmd1[cmd1.index("-j") + 1] = "1"
            res = subprocess.run(cmd1, cwd=ROOT, stdout=subprocess.PIPE,
                                 stderr=subprocess.STDOUT, text=True, errors="replace")
            found, other = parse_cppcheck(res.stdout)
            cpp_proc.returncode = res.returncode
        findings += found
        if cpp_proc.returncode != 0:
            failures.append("cppcheck exited with %d:\n%s" % (cpp_proc.returncode, "\n".join(other[-40:])))
        elif other:
            # cppcheck's messages outside the template (an addon's traceback, say)
            failures.append("cppcheck said:\n" + "\n".join(other[-40:]))

    # one finding per place and check (a header is seen once per file that includes it;
    # a hal/cortex_m4f/ driver by the host and the ARM pass alike)
    uniq = {}
    for f in findings:
        f.function = function_at(f.file, f.line) if f.file != "-" else "-"
        uniq.setdefault((f.tool, f.file, f.line, f.col, f.check), f)
    findings = sorted(uniq.values(), key=lambda f: (TOOLS.index(f.tool), f.file, f.line, f.col, f.check))

    suppressions = read_suppressions(SUPPRESSIONS)
    accepted = {t: read_accepted(p) for t, p in ACCEPTED.items()}
    used_supp, used_acc = classify(findings, suppressions, accepted)

    if cfg.update:
        for t in tools:
            write_accepted(t, findings, accepted[t])
        accepted = {t: read_accepted(p) for t, p in ACCEPTED.items()}
        for f in findings:
            f.status = "new"
        used_supp, used_acc = classify(findings, suppressions, accepted)
        print("lint: accepted lists rewritten; give every REVIEW entry its reason in %s" % DOC)

    if cfg.list:
        for f in findings:
            print("%-9s %-12s %s: %s in %s: %s" % (f.status, f.tool, f.where(), f.check,
                                                  f.function, f.message))
    if cfg.counts:
        print_counts(findings)

    # ---- verdict
    versions = {
        "cppcheck": "cppcheck %s + MISRA C:2012 addon" % (tool_version(["cppcheck", "--version"]) or "?"),
        "clang-tidy": "clang-tidy %s" % (tool_version(["clang-tidy", "--version"]) or "?"),
        "gcc-analyzer": "gcc %s / arm-none-eabi-gcc %s -fanalyzer" % (
            tool_version([cfg.host_cc, "-dumpfullversion"]) or "?",
            tool_version([cfg.arm_cc, "-dumpfullversion"]) or "?"),
    }
    new = [f for f in findings if f.status == "new"]
    for t in tools:
        fs = [f for f in findings if f.tool == t and f.status != "excluded"]
        n_dev = sum(1 for f in fs if f.status == "deviation")
        n_acc = sum(1 for f in fs if f.status == "accepted")
        n_new = sum(1 for f in fs if f.status == "new")
        print("lint: %-45s %4d findings: %4d under a documented deviation, %3d accepted, %d new"
              % (versions[t], len(fs), n_dev, n_acc, n_new))

    stale = []
    if "cppcheck" in tools and not cfg.files:
        stale += ["%s:%d: %s%s" % (SUPPRESSIONS, no, cid, ":" + fg if fg else "")
                  for cid, fg, line, no in suppressions if no not in used_supp]
    if not cfg.files:
        for t in tools:
            stale += ["%s: %s:%s:%s" % (ACCEPTED[t], k[0], k[1], k[2])
                      for k in sorted(accepted.get(t, {})) if (t,) + k not in used_acc]
    for s in stale:
        print("lint: stale (matches no finding any more, remove it): %s" % s)

    why = unexplained(suppressions, {t: accepted[t] for t in tools})
    for s in why:
        print("lint: UNEXPLAINED suppression (name its rule/check and the reason in %s): %s" % (DOC, s))
    for f in new:
        print("lint: NEW %s: %s: %s [%s] in %s" % (f.tool, f.where(), f.check, f.message, f.function))
    for err in failures:
        print("lint: TOOL FAILURE: %s" % err, file=sys.stderr)

    print("lint: %.0f s" % (time.monotonic() - t0))
    if failures:
        print("lint: FAIL (an analyser did not run through)")
        return 2
    if new or why or (cfg.strict and stale):
        print("lint: FAIL: %d new finding(s), %d unexplained suppression(s)%s - fix the code, "
              "or document a deviation in %s and list it in %s/"
              % (len(new), len(why), ", %d stale entr(ies)" % len(stale) if cfg.strict and stale else "",
                 DOC, LINT_DIR))
        return 1
    print("lint: PASS, no finding without a documented reason")
    return 0


if __name__ == "__main__":
    sys.exit(main())
