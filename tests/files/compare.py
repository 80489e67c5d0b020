#!/usr/bin/python3
"""compare.py -- two dumps in files_dump's layout agree: every key of the second that the
first has (numbers to a relative 1e-6, text exactly; KEY... on the command line: only those
keys), the same count of heights, NaN at the same points and the others equal to a relative
1e-6 (of the value, or of a thousandth of the largest, for values near zero). Prints "ok" or
what differs (at most 6 lines) and exits 1.

    compare.py GOT WANT [KEY ...]
"""
import math
import sys


def load(path):
    kv, z, in_z = {}, [], False
    with open(path) as f:
        for line in f:
            line = line.rstrip("\n")
            if in_z:
                z.append(float(line))
            elif line == "z":
                in_z = True
            else:
                k, _, v = line.partition(" ")
                kv[k] = v
    return kv, z


def close(x, y, floor=0.0):
    return x == y or abs(x - y) <= 1e-6 * max(abs(x), abs(y), floor)


def main():
    (a, za), (b, zb) = load(sys.argv[1]), load(sys.argv[2])
    keys = sys.argv[3:] or list(b)
    bad = []
    for k in keys:
        if k not in b:
            continue
        if k not in a:
            bad.append(f"{k}: missing")
            continue
        try:
            if not close(float(a[k]), float(b[k])):
                bad.append(f"{k}: {a[k]} != {b[k]}")
        except ValueError:
            if a[k] != b[k]:
                bad.append(f"{k}: {a[k]!r} != {b[k]!r}")
    if len(za) != len(zb):
        bad.append(f"{len(za)} heights != {len(zb)}")
    else:
        floor = 1e-3 * max((abs(v) for v in zb if not math.isnan(v)), default=0)
        for i, (x, y) in enumerate(zip(za, zb)):
            if math.isnan(x) != math.isnan(y) or not (math.isnan(x) or close(x, y, floor)):
                bad.append(f"z[{i}]: {x!r} != {y!r}")
                if len(bad) > 5:
                    break
    print("ok" if not bad else "\n".join(bad[:6]))
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
