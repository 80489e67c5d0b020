#!/usr/bin/env python3
"""check.py -- the source layout holds (issue 27). Standard library only.

  check.py cycles    the include graph of core/, include/ and server/ between modules (a module:
                     NAME.c with NAME.h in one folder; an #include "x.h" is resolved as the
                     compiler does, the including file's folder first, then the Makefile's -I
                     folders) has no cycle; core/ and include/ include nothing from server/;
                     server/api/ and server/uncert/ include nothing from jobs/, ljgapd/ or cli/,
                     and server/jobs/ nothing from ljgapd/ or cli/ (the daemon and the CLI sit on
                     top); server/files/ (the instrument-file readers) nothing but its own headers
  check.py names     the names say public or private: an identifier ljgap_NAME (one underscore)
                     declared or defined outside include/ is one of the installed headers' (the
                     library's API); internals are ljgap__NAME (core/ and server/) or carry their
                     module's prefix, and the daemon's (server/ljgapd/) are ljgapd_NAME
  check.py sizes     no .c or .h file of core/, include/, server/ or tools/ is over 900 lines
                     (but those in PENDING, which may not grow) and no folder holds more than
                     16 .c files
Prints one "ok - ..." or "not ok - ..." line per check (TAP style).
"""
import os
import re
import sys

ROOTS = ["core", "include", "server", "tools"]
# the Makefile's -I folders, in its order
INCLUDE_DIRS = ["include", "core", "core/sim", "core/topo", "server/api", "server/uncert", "server/jobs",
                "server/files", "server/ljgapd"]
MAX_LINES = 900
MAX_C_FILES = 16
# Files over MAX_LINES that wait for their split along their seams, with the length they may not
# pass meanwhile (none now: issue 27 split the last ones).
PENDING = {}


def report(ok, what, detail=""):
    print(("ok - " if ok else "not ok - ") + what + (f" ({detail})" if detail and not ok else ""))


def sources():
    out = []
    for root in ROOTS:
        for d, _, files in os.walk(root):
            out += [os.path.join(d, f) for f in sorted(files) if f.endswith((".c", ".h"))]
    return sorted(out)


def module(path):
    return os.path.splitext(path)[0]


def resolve(src, name):
    for d in [os.path.dirname(src)] + INCLUDE_DIRS:
        p = os.path.normpath(os.path.join(d, name))
        if os.path.exists(p):
            return p
    return None


def check_cycles():
    files = [f for f in sources() if not f.startswith("tools/")]
    edges = {}
    upward = []
    for f in files:
        m = module(f)
        for name in re.findall(r'^\s*#\s*include\s+"([^"]+)"', open(f, encoding="utf-8").read(), re.M):
            h = resolve(f, name)
            if h is None:
                continue
            if module(h) != m:
                edges.setdefault(m, set()).add(module(h))
            top = lambda p: p.split("/")[0] if not p.startswith("server/") else "/".join(p.split("/")[:2])
            a, b = top(f), top(h)
            bad = (a in ("core", "include") and b.startswith("server")) or \
                  (a in ("server/api", "server/uncert") and b in ("server/jobs", "server/ljgapd", "server/cli")) or \
                  (a == "server/jobs" and b in ("server/ljgapd", "server/cli")) or \
                  (a == "server/files" and b != "server/files")
            if bad:
                upward.append(f"{f} includes {h}")
    # cycles: depth-first search, reporting each cycle found once
    cycles, state, stack = [], {}, []

    def visit(m):
        state[m] = 1
        stack.append(m)
        for n in sorted(edges.get(m, ())):
            if state.get(n) == 1:
                cycles.append(" -> ".join(stack[stack.index(n):] + [n]))
            elif n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in sorted({module(f) for f in files}):
        if m not in state:
            visit(m)
    report(not cycles, f"no include cycle between the {len({module(f) for f in files})} modules "
           "of core/, include/ and server/", "; ".join(cycles))
    report(not upward, "no upward include (core/ of server/, api/ of jobs/ or the daemon, jobs/ "
           "of the daemon)", "; ".join(upward))


def check_names():
    public = set()
    for d, _, files in os.walk("include"):
        for f in files:
            public |= set(re.findall(r"\bljgap_[A-Za-z0-9]\w*", open(os.path.join(d, f), encoding="utf-8").read()))
    bad = {}
    for f in sources():
        if f.startswith(("include/", "tools/")):
            continue
        text = open(f, encoding="utf-8").read()
        text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)  # comments may name anything
        text = re.sub(r'"(?:[^"\\\n]|\\.)*"', '""', text)  # and so may strings
        names = set(re.findall(r"\bljgap_[A-Za-z0-9]\w*", text)) - public
        if f.endswith(".c"):  # a .c file's own statics may use any name: only its externs count
            externs = set()
            for m in re.finditer(r"^(?!static\b)[A-Za-z_][^;{()=]*?\b(ljgap_[A-Za-z0-9]\w*)\s*[\[(=;]", text, re.M):
                externs.add(m.group(1))
            names &= externs | {n for n in names if re.search(r"^\s*(typedef|extern)\b[^;]*\b" + n + r"\b", text, re.M)}
        for n in names:
            bad.setdefault(n, f)
    report(not bad, "internal names are ljgap__NAME, a module's prefix or ljgapd_NAME: ljgap_NAME "
           "is only the installed headers'", ", ".join(f"{n} ({f})" for n, f in sorted(bad.items())[:12]))


def check_sizes():
    big = []
    per_dir = {}
    for f in sources():
        n = sum(1 for _ in open(f, encoding="utf-8"))
        if n > MAX_LINES and n > PENDING.get(f, 0):
            big.append(f"{f} {n}" + (f" (pending split, was {PENDING[f]})" if f in PENDING else ""))
        elif n > MAX_LINES:
            print(f"# {f}: {n} lines, a split still pending")
        if f.endswith(".c"):
            per_dir[os.path.dirname(f)] = per_dir.get(os.path.dirname(f), 0) + 1
    pending = f" (but {len(PENDING)} pending splits, which may not grow)" if PENDING else ""
    report(not big, f"no source file over {MAX_LINES} lines{pending}", ", ".join(big))
    full = [f"{d} {n}" for d, n in sorted(per_dir.items()) if n > MAX_C_FILES]
    report(not full, f"no folder over {MAX_C_FILES} .c files", ", ".join(full))


if __name__ == "__main__":
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
    {"cycles": check_cycles, "names": check_names, "sizes": check_sizes}[sys.argv[1]]()
