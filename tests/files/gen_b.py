#!/usr/bin/env python3
"""gen_b.py -- writes test files of the X3P, Digital Surf (.sur) and Zygo MetroPro (.dat)
formats from the formats' descriptions (not from ljgap's readers), each with a JSON file of
the heights it holds, for tests/files/check_b.sh.

  X3P (ISO 5436-2 / ISO 25178-72): a zip (Python's zipfile) with main.xml (Record1 FeatureType
      and Axes CX CY CZ, Record2 Date and Instrument, Record3 MatrixDimension and DataLink),
      bindata/data.bin (little endian, x fastest), optional bindata/valid.bin (one bit a point,
      least significant first, 1 = valid) and md5checksum.hex.
  .sur (Digital Surf): a 512-byte little-endian header (the fields at their documented
      offsets), the comment and private zones, then 16- or 32-bit points, x fastest; height =
      value * dz + z_offset in dz's unit; with the non-measured flag, value zmin - 2 is a hole;
      "DSCOMPRESSED" files hold the points as zlib streams behind a directory.
  MetroPro (Zygo's reference guide): a big-endian header of 834 (formats 1, 2) or 4096 bytes
      (format 3), the intensity frames (uint16), the phase (int32, >= 2147483640 invalid);
      height = phase * intf_scale_factor * obliquity * wavelength / (4096 or 32768).

usage: gen_b.py OUTDIR      writes NAME.{x3p,sur,dat} and NAME.json for every case
"""
import hashlib
import io
import json
import math
import os
import random
import struct
import sys
import zipfile
import zlib


def truth(path, nx, ny, z, sx, sy, unit="m", extra=None):
    """z: row-major list (x fastest), heights in metres, None where missing."""
    d = {"nx": nx, "ny": ny, "size_x": sx, "size_y": sy, "z_unit": unit,
         "missing": sum(v is None for v in z), "z": z}
    d.update(extra or {})
    with open(path, "w") as f:
        json.dump(d, f)


# ---- X3P ----

def x3p(path, nx, ny, dtype, dx, dy, holes=(), zinc=1.0, zoff=0.0, valid_bits=False,
        deflate=False, layers=1, seed=1):
    rng = random.Random(seed)
    raw, z = [], []
    code = {"I": "<h", "L": "<i", "F": "<f", "D": "<d"}[dtype]
    for k in range(nx * ny * layers):
        if dtype in "IL":
            v = rng.randint(-3000, 3000) if dtype == "I" else rng.randint(-2000000, 2000000)
            h = zoff + zinc * v
        else:
            h = rng.uniform(-2e-7, 2e-7)
            v = struct.unpack(code, struct.pack(code, h))[0]
            h = v
        hole = k in holes
        if hole and dtype in "FD" and not valid_bits:
            v = float("nan")
        raw.append(v)
        z.append(None if hole else h)
    data = b"".join(struct.pack(code, v) for v in raw)
    valid = None
    if valid_bits:
        bits = bytearray((nx * ny * layers + 7) // 8)
        for k in range(nx * ny * layers):
            if k not in holes:
                bits[k // 8] |= 1 << (k % 8)
        valid = bytes(bits)
    axis = lambda name, inc: (
        "<%s><AxisType>I</AxisType><DataType>D</DataType><Increment>%r</Increment>"
        "<Offset>0</Offset></%s>" % (name, inc, name))
    czinc = "<Increment>%r</Increment><Offset>%r</Offset>" % (zinc, zoff) if dtype in "IL" else ""
    link = "<PointDataLink>bindata/data.bin</PointDataLink>" \
           "<MD5ChecksumPointData>%s</MD5ChecksumPointData>" % hashlib.md5(data).hexdigest()
    if valid:
        link += "<ValidPointsLink>bindata/valid.bin</ValidPointsLink>" \
                "<MD5ChecksumValidPoints>%s</MD5ChecksumValidPoints>" % \
                hashlib.md5(valid).hexdigest()
    xml = ('<?xml version="1.0" encoding="UTF-8"?>\n'
           '<p:ISO5436_2 xmlns:p="http://www.opengps.eu/2008/ISO5436_2" '
           'xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance">\n'
           '<Record1><Revision>ISO5436 - 2000</Revision><FeatureType>SUR</FeatureType>\n'
           '<Axes>%s%s<CZ><AxisType>A</AxisType><DataType>%s</DataType>%s</CZ></Axes>'
           '</Record1>\n'
           '<Record2><Date>2024-03-05T14:07:09.0+01:00</Date><Creator>gen_b.py</Creator>'
           '<Instrument><Manufacturer>ACME &amp; Sons</Manufacturer><Model>Profiler 9</Model>'
           '<Serial>42</Serial><Version>1.0</Version></Instrument>'
           '<CalibrationDate>2024-01-01T00:00:00.0+01:00</CalibrationDate>'
           '<ProbingSystem><Type>NonContacting</Type><Identification>white light'
           '</Identification></ProbingSystem><Comment>test</Comment></Record2>\n'
           '<Record3><MatrixDimension><SizeX>%d</SizeX><SizeY>%d</SizeY><SizeZ>%d</SizeZ>'
           '</MatrixDimension><DataLink>%s</DataLink></Record3>\n'
           '<Record4><ChecksumFile>md5checksum.hex</ChecksumFile></Record4>\n'
           '</p:ISO5436_2>\n' % (axis("CX", dx), axis("CY", dy), dtype, czinc, nx, ny, layers,
                                 link)).encode()
    method = zipfile.ZIP_DEFLATED if deflate else zipfile.ZIP_STORED
    with zipfile.ZipFile(path, "w", method) as zf:
        zf.writestr("main.xml", xml)
        zf.writestr("bindata/data.bin", data)
        if valid:
            zf.writestr("bindata/valid.bin", valid)
        zf.writestr("md5checksum.hex", hashlib.md5(xml).hexdigest() + " *main.xml\n")
    return z[:nx * ny]


# ---- Digital Surf ----

def sur(path, nx, ny, bits, dx, dy, dz, ux, uy, uz, zoff=0.0, holes=(), comment=b"",
        private=b"", compressed=False, inversion=0, seed=2):
    rng = random.Random(seed)
    lim = 30000 if bits == 16 else 5000000
    vals = [rng.randint(-lim, lim) for _ in range(nx * ny)]
    zmin = min(vals)
    special = 1 if holes else 0
    for k in holes:
        vals[k] = zmin - 2
    zmax = max(vals)
    code = "<h" if bits == 16 else "<i"
    data = b"".join(struct.pack(code, v) for v in vals)
    f32 = lambda x: struct.unpack("<f", struct.pack("<f", x))[0]
    unit = {"nm": 1e-9, "um": 1e-6, "\xb5m": 1e-6, "mm": 1e-3, "m": 1.0}
    # inversion: 1 inverts z, 2 also mirrors x, 3 also mirrors y (Gwyddion's reading)
    sign = -1 if inversion in (1, 2, 3) else 1
    z = [None if k in holes else sign * (v * f32(dz) + f32(zoff)) * unit[uz] for k, v in
         enumerate(vals)]
    rows = [z[r * nx:(r + 1) * nx] for r in range(ny)]
    if inversion == 2:
        rows = [r[::-1] for r in rows]
    if inversion == 3:
        rows = rows[::-1]
    z = [v for r in rows for v in r]
    csize = 0
    if compressed:
        zipped = zlib.compress(data)
        block = struct.pack("<I", 1) + struct.pack("<II", len(data), len(zipped)) + zipped
        csize = len(block)
        data = block
    h = bytearray(512)
    s = lambda off, txt, n: h.__setitem__(slice(off, off + n), txt.encode("latin-1")[:n].ljust(n, b"\0"))
    s(0, "DSCOMPRESSED" if compressed else "DIGITAL SURF", 12)
    struct.pack_into("<HHHH", h, 12, 0, 1, 1, 2)    # format PC, 1 object, version 1, surface
    s(20, "gen_b surface", 30)
    s(50, "operator", 30)
    struct.pack_into("<HHHHH", h, 80, 0, 6, 0, special, 1)   # material, AFM, range, special, abs
    struct.pack_into("<H", h, 98, bits)
    struct.pack_into("<iiiiI", h, 100, zmin, zmax, nx, ny, nx * ny)
    struct.pack_into("<fff", h, 120, dx, dy, dz)
    for i, t in enumerate(["X", "Y", "Z", ux, uy, uz, ux, uy, uz]):
        s(132 + 16 * i, t, 16)
    struct.pack_into("<fff", h, 276, 1.0, 1.0, 1.0)
    struct.pack_into("<H", h, 290, inversion)
    struct.pack_into("<HHHHHHH", h, 306, 9, 8, 7, 6, 5, 2023, 2)  # s, min, h, day, month, year
    struct.pack_into("<I", h, 324, csize)
    struct.pack_into("<HH", h, 334, len(comment), len(private))
    struct.pack_into("<fff", h, 466, 0.0, 0.0, zoff)
    with open(path, "wb") as f:
        f.write(bytes(h) + comment + private + data)
    return z


# ---- MetroPro ----

def metropro(path, fmt, nx, ny, phase_res, nbuckets=0, holes=(), wavelength=632.8e-9,
             scale=0.5, obliquity=1.0, lateral=2.5e-7, sign=0, seed=3):
    rng = random.Random(seed)
    hsize = 4096 if fmt == 3 else 834
    magic = {1: 0x881B036F, 2: 0x881B0370, 3: 0x881B0371}[fmt]
    R = {0: 4096, 1: 32768}[phase_res]
    phase = [rng.randint(-200000, 200000) for _ in range(nx * ny)]
    for k in holes:
        phase[k] = 2147483647
    inten = [rng.randint(0, 60000) for _ in range(nx * ny * nbuckets)]
    h = bytearray(hsize)
    struct.pack_into(">IHI", h, 0, magic, fmt, hsize)
    struct.pack_into(">HHHHHhI", h, 48, 0, 0, nx if nbuckets else 0, ny if nbuckets else 0,
                     nbuckets, 0, 2 * nx * ny * nbuckets)
    struct.pack_into(">hhHHIi", h, 64, 0, 0, nx, ny, 4 * nx * ny, 1700000000)
    struct.pack_into(">ffffff", h, 164, scale, wavelength, 0.3, obliquity, 50.0, lateral)
    struct.pack_into(">h", h, 218, phase_res)
    struct.pack_into(">h", h, 232, sign)
    struct.pack_into(">hhh", h, 238, 5, 1, 1234)       # NewView, board, serial
    f32 = lambda x: struct.unpack(">f", struct.pack(">f", x))[0]
    q = f32(scale) * f32(obliquity) * f32(wavelength) / R * (-1 if sign == 1 else 1)
    z = [None if v >= 2147483640 else v * q for v in phase]
    with open(path, "wb") as f:
        f.write(bytes(h))
        f.write(b"".join(struct.pack(">H", v) for v in inten))
        f.write(b"".join(struct.pack(">i", v) for v in phase))
    return z, f32(lateral)


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    j = lambda name: os.path.join(out, name)
    # X3P
    for name, nx, ny, dt, kw in [
            ("x3p_d", 13, 7, "D", {}),
            ("x3p_f_nan_deflate", 16, 9, "F", {"holes": (3, 40, 77), "deflate": True}),
            ("x3p_i_valid", 11, 10, "I", {"holes": (0, 9, 50, 109), "zinc": 1e-9,
                                          "zoff": 2e-8, "valid_bits": True}),
            ("x3p_l", 9, 12, "L", {"zinc": 1e-12, "zoff": -1e-7}),
            ("x3p_d_nan", 10, 10, "D", {"holes": (5, 55)})]:
        dx, dy = 1.25e-7, 2.5e-7
        z = x3p(j(name + ".x3p"), nx, ny, dt, dx, dy, **kw)
        truth(j(name + ".json"), nx, ny, z, nx * dx, ny * dy, "m",
              {"instrument": "ACME & Sons Profiler 9",
               "acquired": "2024-03-05T14:07:09.0+01:00"})
    # Digital Surf
    for name, nx, ny, bits, kw in [
            ("sur16", 17, 11, 16, dict(dx=0.5, dy=0.25, dz=2.0, ux="\xb5m", uy="\xb5m", uz="nm")),
            ("sur32_holes", 12, 14, 32, dict(dx=10.0, dy=20.0, dz=0.001, ux="nm", uy="nm",
                                             uz="nm", holes=(4, 100, 167))),
            ("sur32_zones", 10, 10, 32, dict(dx=1.0, dy=1.0, dz=1e-5, ux="um", uy="um",
                                             uz="um", comment=b"a comment",
                                             private=b"\x01\x02\x03\x04\x05\x06")),
            ("sur32_offset", 8, 9, 32, dict(dx=1.0, dy=2.0, dz=1e-4, ux="um", uy="um",
                                            uz="um", zoff=3.5)),
            ("sur16_inverted", 10, 6, 16, dict(dx=1.0, dy=1.0, dz=1.0, ux="um", uy="um",
                                               uz="nm", inversion=1, zoff=0.0)),
            ("sur16_flip", 7, 5, 16, dict(dx=1.0, dy=1.0, dz=1.0, ux="um", uy="um",
                                          uz="nm", inversion=2)),
            ("sur16_flop", 6, 8, 16, dict(dx=1.0, dy=1.0, dz=1.0, ux="um", uy="um",
                                          uz="nm", inversion=3)),
            ("surz", 15, 6, 32, dict(dx=0.1, dy=0.1, dz=1e-3, ux="mm", uy="mm", uz="um",
                                     compressed=True))]:
        z = sur(j(name + ".sur"), nx, ny, bits, **kw)
        f32 = lambda x: struct.unpack("<f", struct.pack("<f", x))[0]
        unit = {"nm": 1e-9, "um": 1e-6, "\xb5m": 1e-6, "mm": 1e-3, "m": 1.0}
        truth(j(name + ".json"), nx, ny, z, nx * f32(kw["dx"]) * unit[kw["ux"]],
              ny * f32(kw["dy"]) * unit[kw["uy"]], kw["uz"].replace("\xb5", "\u00b5"),
              {"acquired": "2023-05-06T07:08:09", "instrument": "AFM"})
    # MetroPro
    for name, fmt, nx, ny, res, nb, holes, sign in [
            ("mp1", 1, 20, 15, 0, 0, (7, 100, 299), 0),
            ("mp2_intensity", 2, 12, 10, 1, 1, (0, 119), 0),
            ("mp3", 3, 9, 16, 1, 0, (50,), 0),
            ("mp2_sign", 2, 8, 8, 1, 0, (9,), 1)]:
        z, lat = metropro(j(name + ".dat"), fmt, nx, ny, res, nb, holes, sign=sign)
        truth(j(name + ".json"), nx, ny, z, nx * lat, ny * lat, "m",
              {"acquired": "2023-11-14T22:13:20Z", "instrument": "Zygo NewView, serial 1234"})


if __name__ == "__main__":
    main()
