#!/usr/bin/python3
"""gwy_dump.py -- a small, independent reader of Gwyddion's .gwy files for the cross-check of
tests/files/run.sh (Gwyddion converts a test file to .gwy; this reads what Gwyddion made of it).

    gwy_dump.py FILE.gwy [CHANNEL]    prints files_dump's layout: "key value" lines (channel,
                                      channels, nx, ny, size_x, size_y, z_unit, missing), "z",
                                      then the heights (in the SI unit Gwyddion stores, "m" for
                                      heights), row after row; masked points (mask > 0.5) nan

CHANNEL is an index among the channels in order of their numbers, or a title; without one,
the first whose title says height or topography, else the first.
Written from the GWY format's description (Gwyddion user guide, "GWY File Format"); it shares
nothing with server/files/gwy.c.
"""
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


def main():
    data = open(sys.argv[1], "rb").read()
    if data[:4] != b"GWYP":
        sys.exit("not a GWYP file")
    name, top = Reader(data[4:]).obj()
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
