#!/usr/bin/env python3
"""gwy_read_b.py -- a small reader of Gwyddion's native .gwy files (GWYP), for the cross-checks
of tests/files/check_b.sh: prints one JSON object with every channel /N/data of the file (xres,
yres, xreal, yreal, the x-y and z units, the data row by row) and its mask /N/mask where there
is one.

The format (Gwyddion's user guide, "Gwyddion native file format"): the magic "GWYP", then one
serialized object: its type name (NUL-terminated), a u32 size, then components, each a name
(NUL-terminated), a one-letter type and the value, little endian: b c (1 byte), i (int32),
q (int64), d (double), s (NUL-terminated string), o (a nested object); the capital letters are
arrays: a u32 count, then the items.

usage: gwy_read_b.py FILE.gwy
"""
import json
import struct
import sys


def cstr(buf, p):
    e = buf.index(b"\0", p)
    return buf[p:e].decode("utf-8", "replace"), e + 1


def obj(buf, p):
    name, p = cstr(buf, p)
    (size,) = struct.unpack_from("<I", buf, p)
    p += 4
    end = p + size
    comps = {}
    while p < end:
        key, p = cstr(buf, p)
        t = chr(buf[p])
        p += 1
        if t in "bc":
            v, p = buf[p], p + 1
        elif t == "i":
            (v,), p = struct.unpack_from("<i", buf, p), p + 4
        elif t == "q":
            (v,), p = struct.unpack_from("<q", buf, p), p + 8
        elif t == "d":
            (v,), p = struct.unpack_from("<d", buf, p), p + 8
        elif t == "s":
            v, p = cstr(buf, p)
        elif t == "o":
            v, p = obj(buf, p)
        elif t in "BCIQD":
            (n,) = struct.unpack_from("<I", buf, p)
            p += 4
            code, size1 = {"B": ("B", 1), "C": ("B", 1), "I": ("i", 4), "Q": ("q", 8),
                           "D": ("d", 8)}[t]
            v = list(struct.unpack_from("<%d%s" % (n, code), buf, p))
            p += n * size1
        elif t == "S":
            (n,) = struct.unpack_from("<I", buf, p)
            p += 4
            v = []
            for _ in range(n):
                s, p = cstr(buf, p)
                v.append(s)
        elif t == "O":
            (n,) = struct.unpack_from("<I", buf, p)
            p += 4
            v = []
            for _ in range(n):
                o, p = obj(buf, p)
                v.append(o)
        else:
            raise ValueError("unknown component type %r at %d" % (t, p))
        comps[key] = v
    if p != end:
        raise ValueError("object %s: size mismatch" % name)
    return {"__type__": name, **comps}, end


def field(f):
    unit = lambda u: u.get("unitstr", "") if isinstance(u, dict) else ""
    xres, yres = f["xres"], f["yres"]
    d = f["data"]
    return {"xres": xres, "yres": yres, "xreal": f["xreal"], "yreal": f["yreal"],
            "unit_xy": unit(f.get("si_unit_xy")), "unit_z": unit(f.get("si_unit_z")),
            "data": [d[j * xres:(j + 1) * xres] for j in range(yres)]}


def main():
    buf = open(sys.argv[1], "rb").read()
    if buf[:4] != b"GWYP":
        sys.exit("not a GWYP file")
    top, _ = obj(buf, 4)
    out = {}
    for key, v in top.items():
        parts = key.split("/")
        if len(parts) == 3 and parts[2] == "data" and isinstance(v, dict):
            ch = field(v)
            m = top.get("/%s/mask" % parts[1])
            if isinstance(m, dict):
                ch["mask"] = field(m)["data"]
            ch["title"] = top.get("/%s/data/title" % parts[1], "")
            out[parts[1]] = ch
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
