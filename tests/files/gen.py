#!/usr/bin/python3
"""gen.py -- small test files of the instrument formats, written from each format's
documentation (not from our readers), and what a reader must find in them.

    gen.py KIND OUT      writes OUT and OUT.expected (files_dump's layout: "key value" lines,
                         then "z" and the heights in metres, row after row from the top)

KIND: nanoscope16, nanoscope32 (three channels: Height, an amplitude in V, ZSensor), gsf,
gwy (two channels, the first with a mask of a 4 x 3 hole), xyz (a hole of 5 points, lines
shuffled). tests/files/run.sh runs each and compares; files2/files3 add their kinds here.
"""
import os
import struct
import sys

import numpy as np

# not square: a transposed reader shows (GEN_NX, GEN_NY change it: the fuzz seeds are smaller)
NX, NY = int(os.environ.get("GEN_NX", 40)), int(os.environ.get("GEN_NY", 24))


def expected(path, fields, z):
    with open(path + ".expected", "w") as f:
        for k, v in fields.items():
            f.write(f"{k} {v}\n")
        f.write("z\n")
        for v in np.asarray(z, dtype=float).ravel():
            f.write("nan\n" if np.isnan(v) else f"{v:.17g}\n")


def nanoscope(out, bpp):
    """Bruker NanoScope v5 ("Nanoscope Command Reference", file format appendix)."""
    rng = np.random.default_rng(7 + bpp)
    top = 2 ** (8 * bpp - 1) - 1
    images = [  # title, quantity in brackets (or None), Z scale value V, sens, raw range
        ("Height", "Sens. Zsens", 440.0, "V 18.3 nm/V", 0.6),
        ("Amplitude Error", None, 20.0, None, 0.3),
        ("ZSensor", "Sens. ZsensSens", 100.0, "V 2500.5 nm/V", 0.5),
    ]
    raws = [rng.integers(-int(top * r), int(top * r), size=(NY, NX), dtype=np.int64)
            for *_, r in images]
    hdr_len = 4096
    offs, lines = [], []
    lines += ["\\*File list", f"\\Version: {'0x09200201' if bpp == 4 else '0x05120005'}", f"\\Data length: {hdr_len}",
              "\\Date: 02:44:18 PM Fri Sep 25 2009", "\\*Equipment list",
              "\\Microscope: Dimension Icon", "\\*Scanner list", "\\Serial Number: 1234",
              "\\@Sens. Zsens: V 18.3 nm/V", "\\@Sens. ZsensSens: V 2500.5 nm/V",
              "\\*Ciao scan list", "\\Scan Size: 500 300 nm", f"\\Samps/line: {NX}", f"\\Lines: {NY}",
              "\\@Sens. Deflection: V 61.2 nm/V"]
    off = hdr_len
    for (title, q, zval, _, _), raw in zip(images, raws):
        n = NX * NY * bpp
        lines += ["\\*Ciao image list", f"\\Data offset: {off}", f"\\Data length: {n}",
                  f"\\Bytes/pixel: {bpp}", f"\\Samps/line: {NX}", f"\\Number of lines: {NY}",
                  "\\Scan Size: 500 300 nm", "\\Aspect ratio: 5:3", "\\Line direction: Retrace",
                  f"\\@2:Image Data: S [{title.split()[0]}] \"{title}\"",
                  f"\\@2:Z scale: V {'[' + q + '] ' if q else ''}({zval / 65536:.9g} V/LSB) "
                  f"{zval} V", "\\@2:Z offset: V [Sens. Zsens] (0 V/LSB) 0 V"]
        offs.append(off)
        off += n
    lines.append("\\*File list end")
    head = "\r\n".join(lines).encode("latin-1") + b"\r\n\x1a"
    assert len(head) < hdr_len
    head += b"\0" * (hdr_len - len(head))
    body = b"".join(r.astype("<i2" if bpp == 2 else "<i4").tobytes() for r in raws)
    with open(out, "wb") as f:
        f.write(head + body)
    # the height: raw * (value / 65536) [/ 65536 for 4 bytes] * sensitivity, nm -> m; the file's
    # first row is the bottom of the scan
    scale = 440.0 / 65536 / (65536 if bpp == 4 else 1) * 18.3e-9
    z = (raws[0] * scale)[::-1]
    expected(out, {"format": "nanoscope", "channel": "Height", "channels":
                   "Height|Amplitude Error|ZSensor", "nx": NX, "ny": NY, "size_x": 500e-9,
                   "size_y": 300e-9, "z_unit": "nm", "missing": 0,
                   "acquired": "2009-09-25T14:44:18"}, z)


def gsf(out):
    """Gwyddion Simple Field (Gwyddion user guide, "GSF")."""
    rng = np.random.default_rng(3)
    z = rng.normal(0, 2e-9, size=(NY, NX)).astype("<f4")
    z[5, 7] = np.nan
    head = (f"Gwyddion Simple Field 1.0\nXRes = {NX}\nYRes = {NY}\nXReal = 4e-06\n"
            "YReal = 2.4e-06\nXYUnits = m\nZUnits = m\nTitle = Topography\n").encode()
    head += b"\0" * (4 - len(head) % 4)
    with open(out, "wb") as f:
        f.write(head + z.tobytes())
    expected(out, {"format": "gsf", "channel": "Topography", "nx": NX, "ny": NY,
                   "size_x": 4e-6, "size_y": 2.4e-6, "z_unit": "m", "missing": 1},
             z.astype(float))


def gwy_str(s):
    return s.encode() + b"\0"


def gwy_obj(name, comps):
    body = b"".join(comps)
    return gwy_str(name) + struct.pack("<I", len(body)) + body


def gwy_comp(name, t, value):
    return gwy_str(name) + t.encode() + value


def gwy_field(z, xreal, yreal, uz):
    ny, nx = z.shape
    unit = lambda u: gwy_obj("GwySIUnit", [gwy_comp("unitstr", "s", gwy_str(u))])
    return gwy_obj("GwyDataField", [
        gwy_comp("xres", "i", struct.pack("<i", nx)), gwy_comp("yres", "i", struct.pack("<i", ny)),
        gwy_comp("xreal", "d", struct.pack("<d", xreal)),
        gwy_comp("yreal", "d", struct.pack("<d", yreal)),
        gwy_comp("xoff", "d", struct.pack("<d", 0.0)),
        gwy_comp("si_unit_xy", "o", unit("m")), gwy_comp("si_unit_z", "o", unit(uz)),
        gwy_comp("data", "D", struct.pack("<I", nx * ny) + z.astype("<f8").tobytes())])


def gwy(out):
    """Gwyddion native (Gwyddion user guide, "GWY File Format")."""
    rng = np.random.default_rng(5)
    h = rng.normal(0, 1e-8, size=(NY, NX))
    phase = rng.normal(0, 3, size=(NY, NX))
    mask = np.zeros((NY, NX))
    mask[NY // 2 - 1:NY // 2 + 2, NX // 2:NX // 2 + 4] = 1
    comps = [gwy_comp("/0/data/title", "s", gwy_str("Phase")),
             gwy_comp("/0/data", "o", gwy_field(phase, 2e-6, 1.2e-6, "deg")),
             gwy_comp("/3/data", "o", gwy_field(h, 2e-6, 1.2e-6, "m")),
             gwy_comp("/3/data/title", "s", gwy_str("Height")),
             gwy_comp("/3/mask", "o", gwy_field(mask, 2e-6, 1.2e-6, "")),
             gwy_comp("/3/base/palette", "s", gwy_str("Gray")),
             gwy_comp("/0/data/visible", "b", b"\1"),
             gwy_comp("/3/meta", "o", gwy_obj("GwyContainer", [
                 gwy_comp("Date", "s", gwy_str("2024-01-02"))]))]
    with open(out, "wb") as f:
        f.write(b"GWYP" + gwy_obj("GwyContainer", comps))
    z = h.copy()
    z[mask > 0.5] = np.nan
    expected(out, {"format": "gwy", "channel": "Height", "channels": "Phase|Height", "nx": NX,
                   "ny": NY, "size_x": 2e-6, "size_y": 1.2e-6, "z_unit": "m", "missing": int(mask.sum())}, z)


def xyz(out):
    """x y z columns on a regular grid, with a hole of 5 points and lines in any order."""
    rng = np.random.default_rng(11)
    dx, dy = 2.5e-8, 4e-8
    z = rng.normal(0, 1e-9, size=(NY, NX))
    hole = [(3, 4), (3, 5), (4, 4), (4, 5), (NY - 2, NX - 3)]
    rows = []
    for j in range(NY):
        for i in range(NX):
            if (j, i) not in hole:
                rows.append(f"{1e-6 + i * dx:.9e}\t{-2e-6 + j * dy:.9e}\t{z[j, i]:.17g}")
    order = rng.permutation(len(rows))
    with open(out, "w") as f:
        f.write("# x y z in m\nx\ty\tz\n" + "\n".join(rows[k] for k in order) + "\n")
    for j, i in hole:
        z[j, i] = np.nan
    expected(out, {"format": "xyz", "channel": "Height", "nx": NX, "ny": NY,
                   "size_x": NX * dx, "size_y": NY * dy, "z_unit": "m", "missing": len(hole)}, z)


KINDS = {"nanoscope16": lambda o: nanoscope(o, 2), "nanoscope32": lambda o: nanoscope(o, 4),
         "gsf": gsf, "gwy": gwy, "xyz": xyz}

if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in KINDS:
        sys.exit(f"usage: gen.py {'|'.join(KINDS)} OUT")
    KINDS[sys.argv[1]](sys.argv[2])
