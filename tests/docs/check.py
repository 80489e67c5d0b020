#!/usr/bin/env python3
"""check.py -- the documentation against what it documents. Standard library only.

  check.py api OPENAPI.json API.md   every path and method of the OpenAPI document has its section
                                     in the reference ("### `METHOD PATH`") and the reverse; each
                                     section's "Statuses:" line lists exactly the operation's
                                     statuses; every field name of the document's schemas appears
                                     in a code span of the reference; every problem type appears,
                                     and every /problems/ type in the reference is in the document
  check.py links FILE.md...          every relative link resolves to a file of the repository,
                                     and every #anchor to a heading of its target
Prints one "ok - ..." or "not ok - ..." line per check (TAP style).
"""
import json
import os
import re
import sys

METHODS = ("get", "put", "post", "delete", "patch", "head", "options")


def report(ok, what, detail=""):
    print(("ok - " if ok else "not ok - ") + what + (f" ({detail})" if detail and not ok else ""))


def props(node, out):
    if isinstance(node, dict):
        for k, v in node.items():
            if k == "properties" and isinstance(v, dict):
                out.update(v.keys())
            props(v, out)
    elif isinstance(node, list):
        for v in node:
            props(v, out)


def check_api(openapi_path, md_path):
    doc = json.load(open(openapi_path))
    md = open(md_path, encoding="utf-8").read()
    sections = {}
    for m in re.finditer(r"^### `([A-Z]+) (/[^`]*)`\n(.*?)(?=^#{1,3} |\Z)", md, re.M | re.S):
        sections[(m.group(1), m.group(2))] = m.group(3)
    ops = {(meth.upper(), path): op for path, item in doc["paths"].items()
           for meth, op in item.items() if meth in METHODS}
    missing = [f"{m} {p}" for (m, p) in ops if (m, p) not in sections]
    report(not missing, f"every operation of openapi.json ({len(ops)}) has a section in api.md",
           "missing: " + ", ".join(missing))
    extra = [f"{m} {p}" for (m, p) in sections if (m, p) not in ops]
    report(not extra, f"every section of api.md ({len(sections)}) is an operation of openapi.json",
           "not in openapi.json: " + ", ".join(extra))
    wrong = []
    for key, op in ops.items():
        text = sections.get(key, "")
        m = re.search(r"^Statuses: (.*)\.$", text, re.M)
        listed = set(re.findall(r"\d{3}", m.group(1))) if m else set()
        if listed != set(op["responses"].keys()):
            wrong.append(f"{key[0]} {key[1]}: api.md {sorted(listed)}, openapi "
                         f"{sorted(op['responses'].keys())}")
    report(not wrong, "each section's statuses are exactly the operation's", "; ".join(wrong))
    names = set()
    props(doc, names)
    spans = set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", " ".join(re.findall(r"`([^`\n]+)`", md))))
    missing = sorted(names - spans)
    report(not missing, f"every field name of openapi.json's schemas ({len(names)}) is in api.md",
           "missing: " + ", ".join(missing))
    types = set(doc["components"]["schemas"]["Problem"]["properties"]["type"]["enum"])
    in_md = set(re.findall(r"`(/problems/[a-z-]+)`", md))
    report(types == in_md, f"api.md lists exactly openapi.json's {len(types)} problem types",
           f"only in openapi.json: {sorted(types - in_md)}; only in api.md: {sorted(in_md - types)}")


def slug(heading):
    s = re.sub(r"[`*_]", "", heading.strip().lower())
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def anchors(path):
    text = open(path, encoding="utf-8").read()
    text = re.sub(r"^```.*?^```", "", text, flags=re.M | re.S)
    return {slug(m.group(1)) for m in re.finditer(r"^#{1,6} (.*)$", text, re.M)}


def check_links(files):
    for f in files:
        text = open(f, encoding="utf-8").read()
        text = re.sub(r"^```.*?^```", "", text, flags=re.M | re.S)
        bad = []
        n = 0
        for target in re.findall(r"\]\(([^)\s]+)\)", text):
            if re.match(r"[a-z]+:", target):
                continue
            n += 1
            path, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(f), path)) if path else f
            if not os.path.exists(dest):
                bad.append(target)
            elif anchor and dest.endswith(".md") and anchor not in anchors(dest):
                bad.append(target)
        report(not bad, f"{f}: its {n} relative links resolve", "broken: " + ", ".join(bad))


if __name__ == "__main__":
    if sys.argv[1] == "api":
        check_api(sys.argv[2], sys.argv[3])
    else:
        check_links(sys.argv[2:])
