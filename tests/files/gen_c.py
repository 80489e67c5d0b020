#!/usr/bin/python3
"""gen_c.py -- writes test files of three instrument formats from their documentation alone
(no code shared with the C readers in server/files/): Igor binary waves (WaveMetrics' Technical
Note 003, IgorBin.h), Park Systems TIFF (the TIFF 6.0 layout plus Park's private tags 50432-50435
and its image header) and Sensofar PLu 2000 (its 500-byte header and float32 layers).

    /usr/bin/python3 tests/files/gen_c.py OUTDIR [SEED]
    /usr/bin/python3 tests/files/gen_c.py --seeds tests/fuzz/files_corpus

writes into OUTDIR: ibw_le.ibw (3 float32 layers, little endian, a NaN, Asylum's note),
ibw_be.ibw (big endian, float64, 2 layers), ibw_i16.ibw (int16, one layer, nm, µm steps), park_v2.tiff (float32),
park_v1.tiff (int16, z scale and offset), park_swap.tiff (version 2, int32, swap_xy), plu.plu
(one layer with points not measured). Heights are random (numpy, seeded), the grids are not
square so that a transposition shows. Each file is what the C readers must read and what
Gwyddion 2.62 reads independently (tests/files/check_c.sh compares the two).
"""
import struct
import sys

import numpy as np


# ---- Igor binary wave, version 5 ----
def ibw5(layers, titles, *, big=False, ntype=2, data_unit="m", dim_unit="m", step=(1e-8, 2e-8),
         note="", name="wave0", flat=False):
    """layers: list of 2-D arrays [y][x] in Igor's index order (x fastest on disk)."""
    e = ">" if big else "<"
    dt = {2: "f4", 4: "f8", 0x10: "i2", 0x20: "i4"}[ntype]
    ny, nx = layers[0].shape
    nl = len(layers)
    data = np.stack(layers).astype(np.dtype(dt).newbyteorder(e)).tobytes()
    npnts = nx * ny * nl
    ndim = [nx, ny, 0 if flat else nl, 0]
    note_b = note.encode("latin-1")
    labels = b""
    dim_labels = [0, 0, 0, 0]
    if titles:  # (nDim + 1) names of 32 bytes: the dimension's own, then one per layer
        labels = b"\0" * 32 + b"".join(t.encode().ljust(32, b"\0") for t in titles)
        dim_labels[2] = len(labels)
    wave = bytearray(320)
    struct.pack_into(e + "I", wave, 4, 3800000000)  # creationDate, seconds since 1904
    struct.pack_into(e + "iH", wave, 12, npnts, ntype)
    struct.pack_into(e + "H", wave, 26, 1)  # whVersion
    wave[28:28 + len(name)] = name.encode()
    struct.pack_into(e + "4i", wave, 68, *ndim)
    struct.pack_into(e + "4d", wave, 84, step[0], step[1], 1.0, 1.0)
    struct.pack_into(e + "4d", wave, 116, 0.0, 0.0, 0.0, 0.0)
    wave[148:148 + len(data_unit)] = data_unit.encode()
    for d in range(2):
        wave[152 + 4 * d:152 + 4 * d + len(dim_unit)] = dim_unit.encode()
    binh = bytearray(64)
    struct.pack_into(e + "hhiii", binh, 0, 5, 0, 320 + len(data), 0, len(note_b))
    struct.pack_into(e + "4i", binh, 36, *dim_labels)
    words = struct.unpack(e + "192H", bytes(binh) + bytes(wave))
    struct.pack_into(e + "H", binh, 2, (-sum(words)) & 0xFFFF)
    return bytes(binh) + bytes(wave) + data + note_b + labels


# ---- Park Systems TIFF ----
def utf16(s, n):
    return s.encode("utf-16-le").ljust(2 * n, b"\0")[:2 * n]


def park(raw, *, version=2, dtype=2, source="Topography", unit="um", size=(5.0, 2.5),
         gain=1.0, zscale=1.0, zoff=0.0, swap=0, date="2023:04:05 06:07:08"):
    """raw: 2-D array [row][x] as stored (first row stored first)."""
    yres, xres = raw.shape
    h = bytearray(580 if version == 2 else 356)
    struct.pack_into("<I", h, 0, 0)  # 2-D mapped image
    h[4:68] = utf16(source, 32)
    h[68:84] = utf16("NCM", 8)
    struct.pack_into("<II", h, 100, xres, yres)
    struct.pack_into("<III", h, 128, 1, 1, swap)  # forward, scan_up, swap_xy
    struct.pack_into("<dd", h, 140, *size)  # µm
    struct.pack_into("<ddd", h, 220, gain, zscale, zoff)
    h[244:260] = utf16(unit, 8)
    if version == 2:
        struct.pack_into("<I", h, 348, dtype)
    data = raw.astype({0: "<i2", 1: "<i4", 2: "<f4"}[dtype]).tobytes()
    thumb = bytes(((np.arange(xres * yres) * 7) % 256).astype(np.uint8))
    date_b = date.encode() + b"\0"
    # blobs after the 8-byte header, then the directory
    blobs = [thumb, bytes(h), data, date_b]
    offs, at = [], 8
    for bl in blobs:
        offs.append(at)
        at += len(bl) + (len(bl) & 1)
    ifd = at
    entries = [(256, 4, 1, xres), (257, 4, 1, yres), (258, 3, 1, 8), (259, 3, 1, 1),
               (262, 3, 1, 1), (273, 4, 1, offs[0]), (277, 3, 1, 1), (278, 4, 1, yres),
               (279, 4, 1, len(thumb)), (306, 2, len(date_b), offs[3]),
               (50432, 4, 1, 0x0E031301), (50433, 4, 1, 0x01000001 + (version == 2)),
               (50434, 1, len(data), offs[2]), (50435, 1, len(h), offs[1])]
    out = bytearray(b"II*\0" + struct.pack("<I", ifd))
    for bl in blobs:
        out += bl + b"\0" * (len(bl) & 1)
    out += struct.pack("<H", len(entries))
    for tag, typ, cnt, val in entries:
        if typ == 3:
            out += struct.pack("<HHIHH", tag, typ, cnt, val, 0)
        else:
            out += struct.pack("<HHII", tag, typ, cnt, val)
    out += struct.pack("<I", 0)
    return bytes(out)


# ---- Sensofar PLu 2000 ----
def plu(layers, *, mpp=(0.5, 0.75), mtype=3, hw=1, date="Tue Mar  5 14:03:09 2024"):
    """layers: list of 2-D arrays [row][x] in µm (1000001 = not measured)."""
    h = bytearray(500)
    h[0:24] = date.encode()
    struct.pack_into("<I", h, 128, 1709647389)
    h[132:150] = b"generated by gen_c"
    ny, nx = layers[0].shape
    struct.pack_into("<III7f", h, 388, ny, nx, 0, 1.0, mpp[0], mpp[1], 0, 0, 1.0, 0)
    struct.pack_into("<5I", h, 428, mtype, 0, 0, 5, 1)
    struct.pack_into("<5I", h, 448, nx, ny, nx, ny, 0)
    struct.pack_into("<dfII", h, 468, 0.1, 10.0, 100, 0)
    struct.pack_into("<6B", h, 488, 0, len(layers), 0, hw, 0, 0)
    out = bytes(h)
    for a in layers:
        a = a.astype("<f4")
        good = a[a != 1000001]
        out += struct.pack("<II", *a.shape) + a.tobytes()
        out += struct.pack("<ff", float(good.min()), float(good.max()))
    return out


def seeds(out):
    """Small seeds for the fuzzer (tests/fuzz/files_corpus): a valid file of each format and
    the same file cut inside its data (the TIFF's directory comes last), each under 4 KiB."""
    rng = np.random.default_rng(7)
    note = "ScanSize: 8e-08\rMicroscopeModel: MFP3D\rDate: 2024-05-06\rTime: 10:00:00\r"
    files = {
        "ibw_valid.ibw": ibw5([rng.normal(0, 1e-9, (6, 8)), rng.normal(0, 1.0, (6, 8))],
                              ["HeightRetrace", "PhaseRetrace"], note=note),
        "tiff_park_valid.tiff": park(rng.normal(0, 0.01, (6, 8)), size=(1.0, 0.75)),
        "plu_valid.plu": plu([rng.normal(0, 0.1, (6, 8))]),
    }
    for name, data in files.items():
        inside = {"ibw": 484, "tiff": len(data) * 2 // 3, "plu": 600}[name.split("_")[0]]
        for kind, cut in (("valid", len(data)), ("truncated", inside)):
            with open(f"{out}/{name.replace('valid', kind)}", "wb") as f:
                f.write(data[:cut])


def main():
    if sys.argv[1] == "--seeds":
        seeds(sys.argv[2])
        return
    out = sys.argv[1]
    rng = np.random.default_rng(int(sys.argv[2]) if len(sys.argv) > 2 else 28)

    def heights(ny, nx, scale):
        return rng.normal(0.0, scale, (ny, nx))

    note = ("ScanSize: 2.4e-07\rFastScanSize: 2.4e-07\rSlowScanSize: 3.2e-07\r"
            "MicroscopeModel: Cypher\rDate: 2024-05-06\rTime: 1:02:03 PM\rTipRadius: 8e-09\r")
    h = heights(16, 24, 3e-9)
    h[3, 5] = np.nan
    files = {
        "ibw_le.ibw": ibw5([h, heights(16, 24, 1e-9), heights(16, 24, 20.0)],
                           ["HeightRetrace", "AmplitudeRetrace", "PhaseRetrace"], note=note),
        "ibw_be.ibw": ibw5([heights(12, 20, 5e-9), heights(12, 20, 5e-9)],
                           ["ZSensorRetrace", "HeightRetrace"], big=True, ntype=4,
                           step=(3e-8, 1e-8)),
        "ibw_i16.ibw": ibw5([np.round(heights(10, 14, 3000.0))], ["Height"], ntype=0x10,
                            data_unit="nm", dim_unit="um", step=(0.05, 0.025)),
        "park_v2.tiff": park(heights(12, 18, 0.02), size=(9.0, 6.0)),
        "park_v1.tiff": park(np.round(heights(10, 16, 2000.0)), version=1, dtype=0, unit="nm",
                             gain=0.5, zscale=0.25, zoff=3.0, source="Z Height"),
        "park_swap.tiff": park(np.round(heights(8, 14, 1e5)), dtype=1, unit="nm", gain=1e-3,
                               swap=1, size=(7.0, 4.0)),
    }
    p = heights(14, 22, 0.3)
    p[0, 0] = p[5, 7] = p[13, 21] = 1000001
    files["plu.plu"] = plu([p])
    for name, data in files.items():
        with open(f"{out}/{name}", "wb") as f:
            f.write(data)


if __name__ == "__main__":
    main()
