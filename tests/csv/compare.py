#!/usr/bin/env python3
"""compare.py ENDPOINT ANSWER.json ANSWER.csv -- does the CSV answer carry the JSON answer's numbers?

Parsed with Python's csv module (comment lines skipped as pandas' comment="#" does): every column
is matched with its JSON array, every "# PATH [UNIT] = VALUE ± ERROR" line with the JSON value at
PATH and its error (error.PATH, or si.error.REST for si.REST: the outermost "error" that has it);
numbers must agree to within what JSON printing loses (2.3e-16 relative). The SI error columns
are also checked against the dimensionless errors times the answer's own scale.
The time in meta.elapsed_ms may differ between two requests and is not compared. Prints what
differs and exits 1, or exits 0. Standard library only.
"""
import csv
import json
import math
import re
import sys


def same(a, b):
    if b is None:
        return a in ("", "inf", "null")
    if isinstance(b, bool):
        return a == ("true" if b else "false")
    if isinstance(b, str):
        return a == b
    x = float(a)
    return x == b or abs(x - b) <= 2.3e-16 * abs(b)


def at(doc, path):
    for part in re.findall(r"[^.\[\]]+|\[\d+\]", path):
        doc = doc[int(part[1:-1])] if part.startswith("[") else doc[part]
    return doc


def error_of(doc, path):
    """The error of the field at path: error.PATH, else A.error.REST for each prefix A."""
    parts = path.split(".")
    for cut in range(len(parts)):
        try:
            return at(doc, ".".join(parts[:cut] + ["error"] + parts[cut:]))
        except (KeyError, IndexError, TypeError):
            continue
    raise KeyError("no error for " + path)


def main():
    endpoint, jpath, cpath = sys.argv[1:4]
    ans = json.load(open(jpath))
    text = open(cpath, encoding="utf-8").read()
    bad = []
    comments = [line for line in text.splitlines() if line.startswith("#")]
    for line in comments[1:]:
        m = re.match(r"# (\S+)(?: \[[^\]]*\])? = (.*?)(?: ± (\S+))?$", line)
        if not m:
            bad.append("comment line: " + line)
            continue
        path, value, err = m.groups()
        if path == "meta.elapsed_ms":
            continue
        if not same(value, at(ans, path)):
            bad.append(f"{path}: {value} against {at(ans, path)}")
        if err is not None and not same(err, error_of(ans, path)):
            bad.append(f"error of {path}: {err}")
    rows = list(csv.reader(line for line in text.splitlines() if not line.startswith("#")))
    head = [h.split(" [")[0] for h in rows[0]]
    body = rows[1:]
    col = {h: [r[i] for r in body] for i, h in enumerate(head)}
    want = {}
    if endpoint in ("traction", "simulations"):
        want = {h: ans[h] for h in head if h in ans}
        want["sigma_err"] = ans["error"]["sigma"]
        if "input_error" in ans:  # the measurement's uncertainty (issue 29)
            want["sigma_input_err"] = ans["input_error"]["sigma"]
            if "si" in ans:
                want["sigma_Pa_input_err"] = ans["si"]["input_error"]["sigma_Pa"]
        if "si" in ans:
            want["g_ave_m"], want["sigma_Pa"] = ans["si"]["g_ave_m"], ans["si"]["sigma_Pa"]
            if "error" in ans["si"]:
                want["sigma_Pa_err"] = ans["si"]["error"]["sigma_Pa"]
    elif endpoint == "sweep":
        want["values"] = ans["values"]
        for h in head[1:]:
            kind = "input_error" if h.endswith("_input_err") else "error" if h.endswith("_err") else None
            name = h[:-10] if kind == "input_error" else h[:-4] if kind else h
            src = ans["si"]["results"] if name.endswith(("_m", "_Pa", "_J_m2", "_m2")) else ans["results"]
            want[h] = [None if r is None else r[kind][name] if kind else r[name] for r in src]
    elif endpoint == "pdf":
        for key in ("k2", "g", "phi"):
            want[key] = []
        for p in ans["pdfs"]:
            want["k2"] += [p["k2"]] * len(p["g"])
            want["g"] += p["g"]
            want["phi"] += p["phi"]
        want["pdf"] = [i for i, p in enumerate(ans["pdfs"]) for _ in p["g"]]
        if "si" in ans:
            want["g_m"] = [x for p in ans["si"]["pdfs"] for x in p["g_m"]]
            want["phi_per_m"] = [x for p in ans["si"]["pdfs"] for x in p["phi_per_m"]]
    for h, values in want.items():
        got = col.get(h)
        if got is None or len(got) != len(values):
            bad.append(f"column {h}: {None if got is None else len(got)} cells, want {len(values)}")
            continue
        for i, (a, b) in enumerate(zip(got, values)):
            if h == "pdf":
                b = str(b)
            if not same(a, b):
                bad.append(f"{h}[{i}]: {a} against {b}")
                break
    if "si" in ans:  # the SI errors: the dimensionless ones times the answer's own scales
        si = ans["si"]
        s0 = si["sigma0_Pa"]
        eps = 3 * math.sqrt(3) * si["chi_m"] * s0 / si["E_star_Pa"]
        dg = 9 * math.sqrt(3) * eps * s0 / 16
        scale = {"g_eq_m": ("g_eq", eps), "sigma_max_Pa": ("sigma_max", s0),
                 "g_at_max_m": ("g_at_max", eps), "dgamma_eff_J_m2": ("dgamma_eff", dg)}
        pairs = []
        if endpoint == "traction":
            pairs = [("sigma_Pa_err", "sigma_err", s0)]
        elif endpoint == "sweep":
            pairs = [(n + "_err", d + "_err", f) for n, (d, f) in scale.items()]
        for h, dh, f in pairs:
            for i, (a, e) in enumerate(zip(col.get(h, []), col.get(dh, []))):
                if (a == "") != (e == "") or (a and not math.isclose(float(a), float(e) * f,
                                                                      rel_tol=1e-14)):
                    bad.append(f"{h}[{i}] {a} is not {dh} x scale = {e} x {f}")
                    break
    missing = [h for h in head if h not in want]
    if missing:
        bad.append("columns not checked: " + ", ".join(missing))
    for b in bad[:10]:
        print(b)
    print(f"{len(body)} rows, {len(head)} columns, {len(comments)} comment lines, "
          f"{len(bad)} differences")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
