#!/usr/bin/python3
"""gwy_dump.py -- a small, independent reader of Gwyddion's .gwy files for the cross-checks of
tests/files/run.sh, check_b.sh and check_c.sh (Gwyddion converts a test file to .gwy; this reads
what Gwyddion made of it). The one .gwy parser of the tests; three ways to print:

    gwy_dump.py FILE.gwy [CHANNEL]    prints files_dump's layout: "key value" lines (channel,
                                      channels, nx, ny, size_x, size_y, z_unit, missing), "z",
                                      then the heights (in the SI unit Gwyddion stores, "m" for
                                      heights), row after row; masked points (mask > 0.5) nan
    gwy_dump.py --json FILE.gwy       (check_b.sh, compare_b.py) one JSON object, a member per
                                      channel id /N/data: xres, yres, xreal, yreal, unit_xy,
                                      unit_z, data (row by row), mask (rows, where there is one),
                                      title
    gwy_dump.py --points FILE.gwy [ID]  (check_c.sh) channel ID (default 0): "xres yres xreal
                                      yreal unit_z title" on one line ("-" for an empty unit or
                                      title, blanks in the title as "_"), then one line a point
                                      "value mask" (row 0 first; mask 1 where Gwyddion masked
                                      the point, else 0)

CHANNEL is an index among the channels in order of their numbers, or a title; without one,
the first whose title says height or topography, else the first.

The format: "GWYP", then one serialized object: its type name (NUL-terminated), a u32 size of
its components, then the components: a name (NUL-terminated), a type character and the value.
b bool (1 byte), c char, i int32, q int64, d double, s string (NUL-terminated), o an object;
the capitals C I Q D S O are arrays: a u32 count, then the items. Little endian throughout.
Written from the GWY format's description (Gwyddion user guide, "GWY File Format"); it shares
nothing with server/files/gwy.c.
"""
import json
import struct
import sys

import numpy as np


class Reader:
    def __init__(self, data):
        self.d, self.p = data, 0

    def take(self, n):
        if self.p + n > len(self.d):
            raise ValueError(f"truncated at {self.p}")
        s = self.d[self.p:self.p + n]
        self.p += n
        return s

    def cstr(self):
        e = self.d.index(b"\0", self.p)
        s = self.d[self.p:e].decode("utf-8", "replace")
        self.p = e + 1
        return s

    def obj(self):
        name = self.cstr()
        (size,) = struct.unpack("<I", self.take(4))
        end = self.p + size
        comps = {}
        while self.p < end:
            key = self.cstr()
            t = chr(self.take(1)[0])
            comps[key] = self.value(t)
        if self.p != end:
            raise ValueError(f"object {name} overran its size")
        return name, comps

    def value(self, t):
        fixed = {"b": ("<B", 1), "c": ("<B", 1), "i": ("<i", 4), "q": ("<q", 8), "d": ("<d", 8)}
        if t in fixed:
            f, n = fixed[t]
            return struct.unpack(f, self.take(n))[0]
        if t == "s":
            return self.cstr()
        if t == "o":
            return self.obj()
        (n,) = struct.unpack("<I", self.take(4))
        arrays = {"C": "u1", "I": "<i4", "Q": "<i8", "D": "<f8"}
        if t in arrays:
            dt = np.dtype(arrays[t])
            return np.frombuffer(self.take(n * dt.itemsize), dtype=dt)
        if t == "S":
            return [self.cstr() for _ in range(n)]
        if t == "O":
            return [self.obj() for _ in range(n)]
        raise ValueError(f"type {t!r} at {self.p}")


def load(path):
    """The top container's components of a .gwy file (each object a (type, components) pair)."""
    data = open(path, "rb").read()
    if data[:4] != b"GWYP":
        sys.exit("not a GWYP file")
    return Reader(data[4:]).obj()[1]


def unit(o):
    """The unit string of a GwySIUnit component ("" when there is none)."""
    return o[1].get("unitstr", "") if isinstance(o, tuple) else ""


def dump_json(top):
    out = {}
    for key, v in top.items():
        parts = key.split("/")
        if len(parts) == 3 and parts[2] == "data" and isinstance(v, tuple):
            f = v[1]
            xres, yres = f["xres"], f["yres"]
            rows = lambda d: [list(map(float, d[j * xres:(j + 1) * xres])) for j in range(yres)]
            ch = {"xres": xres, "yres": yres, "xreal": f["xreal"], "yreal": f["yreal"],
                  "unit_xy": unit(f.get("si_unit_xy")), "unit_z": unit(f.get("si_unit_z")),
                  "data": rows(f["data"])}
            m = top.get("/%s/mask" % parts[1])
            if isinstance(m, tuple):
                ch["mask"] = rows(m[1]["data"])
            ch["title"] = top.get("/%s/data/title" % parts[1], "")
            out[parts[1]] = ch
    json.dump(out, sys.stdout)


def dump_points(top, i):
    f = top["/%s/data" % i][1]
    mask = top.get("/%s/mask" % i)
    title = top.get("/%s/data/title" % i, "")
    print(f["xres"], f["yres"], repr(f["xreal"]), repr(f["yreal"]),
          unit(f.get("si_unit_z")) or "-", title.replace(" ", "_") or "-")
    m = mask[1]["data"] if mask else [0.0] * len(f["data"])
    for v, k in zip(f["data"], m):
        print(repr(float(v)), 1 if k > 0.5 else 0)


def main():
    if sys.argv[1] == "--json":
        dump_json(load(sys.argv[2]))
        return
    if sys.argv[1] == "--points":
        dump_points(load(sys.argv[2]), sys.argv[3] if len(sys.argv) > 3 else "0")
        return
    top = load(sys.argv[1])
    ids = sorted(int(k.split("/")[1]) for k, v in top.items()
                 if k.count("/") == 2 and k.endswith("/data") and isinstance(v, tuple))
    titles = [top.get(f"/{i}/data/title", f"channel {i}") for i in ids]
    want = sys.argv[2] if len(sys.argv) > 2 else None
    if want is None:
        pick = next((k for k, t in enumerate(titles)
                     if any(w in t.lower() for w in ("height", "topograph", "zsensor"))), 0)
    elif want.isdigit():
        pick = int(want)
    else:
        pick = titles.index(want)
    i = ids[pick]
    _, f = top[f"/{i}/data"]
    nx, ny = f["xres"], f["yres"]
    z = np.array(f["data"], dtype=float).reshape(ny, nx)
    z[~np.isfinite(z)] = np.nan
    if f"/{i}/mask" in top:
        m = np.array(top[f"/{i}/mask"][1]["data"]).reshape(ny, nx)
        z[m > 0.5] = np.nan
    uz = f["si_unit_z"][1].get("unitstr", "") if "si_unit_z" in f else ""
    print(f"channel {titles[pick]}\nchannels {'|'.join(titles)}\nnx {nx}\nny {ny}")
    print(f"size_x {f['xreal']!r}\nsize_y {f['yreal']!r}\nz_unit_si {uz}")
    print(f"missing {int(np.isnan(z).sum())}\nz")
    for v in z.ravel():
        print("nan" if np.isnan(v) else repr(float(v)))


if __name__ == "__main__":
    main()
