#!/usr/bin/env python3
"""gwy_read_c.py -- a small reader of Gwyddion's native .gwy files (what `gwyddion
--convert-to-gwy` writes), written from Gwyddion's description of its serialization:

    "GWYP", then one serialized object: its type name (NUL-terminated), a u32 size of its
    components, then the components: a name (NUL-terminated), a type character and the value.
    b bool (1 byte), c char, i int32, q int64, d double, s string (NUL-terminated), o an object;
    the capitals C I Q D S O are arrays: a u32 count, then the items. Little endian throughout.

A GwyContainer holds its items under keys such as "/0/data" (a GwyDataField: xres, yres, xreal,
yreal, si_unit_xy and si_unit_z (GwySIUnit: unitstr), data), "/0/data/title" and "/0/mask".

    python3 tests/files/gwy_read_c.py FILE.gwy [ID]

prints channel ID (default 0): "xres yres xreal yreal unit_z title" on one line, then one line a
point "value mask" (row 0 first; mask 1 where Gwyddion masked the point, else 0).
"""
import struct
import sys


class Reader:
    def __init__(self, data):
        self.d, self.p = data, 0

    def take(self, n):
        if self.p + n > len(self.d):
            raise ValueError("truncated .gwy at %d" % self.p)
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
        size = struct.unpack("<I", self.take(4))[0]
        end = self.p + size
        comps = {}
        while self.p < end:
            key = self.cstr()
            comps[key] = self.value(self.take(1).decode())
        if self.p != end:
            raise ValueError("object %s overran its size" % name)
        return {"__type__": name, **comps}

    def value(self, t):
        scalar = {"b": ("<B", 1), "c": ("<c", 1), "i": ("<i", 4), "q": ("<q", 8),
                  "d": ("<d", 8)}
        if t in scalar:
            f, n = scalar[t]
            return struct.unpack(f, self.take(n))[0]
        if t == "s":
            return self.cstr()
        if t == "o":
            return self.obj()
        n = struct.unpack("<I", self.take(4))[0]
        if t.lower() in scalar:
            f, k = scalar[t.lower()]
            return list(struct.unpack("<%d%s" % (n, f[1]), self.take(n * k)))
        if t == "S":
            return [self.cstr() for _ in range(n)]
        if t == "O":
            return [self.obj() for _ in range(n)]
        raise ValueError("unknown component type %r" % t)


def load(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] != b"GWYP":
        raise ValueError("not a GWYP file")
    r = Reader(data)
    r.p = 4
    return r.obj()


def main():
    top = load(sys.argv[1])
    i = sys.argv[2] if len(sys.argv) > 2 else "0"
    f = top["/%s/data" % i]
    mask = top.get("/%s/mask" % i)
    title = top.get("/%s/data/title" % i, "")
    unit = f.get("si_unit_z", {}).get("unitstr", "")
    print(f["xres"], f["yres"], repr(f["xreal"]), repr(f["yreal"]), unit or "-",
          title.replace(" ", "_") or "-")
    m = mask["data"] if mask else [0.0] * len(f["data"])
    for v, k in zip(f["data"], m):
        print(repr(v), 1 if k > 0.5 else 0)


if __name__ == "__main__":
    main()
