#!/usr/bin/env python3
"""favicon.py -- writes web/favicon.ico: web/favicon.svg drawn at 32 x 32 by hand, as a PNG
inside an ICO file (browsers ask for /favicon.ico even when the page names favicon.svg).

Run once when the icon changes (standard library only): python3 tools/favicon.py
The shapes below are those of web/favicon.svg; each pixel is 4 x 4 samples.
"""
import math
import struct
import zlib

SIZE, SS = 32, 4
BLUE, WHITE = (0x1F, 0x5F, 0xBF), (0xFF, 0xFF, 0xFF)
FLAT = [((5, 10), (27, 10))], 1.5
ROUGH = [((5, 23), (9, 18)), ((9, 18), (12, 22)), ((12, 22), (16, 15.5)), ((16, 15.5), (19, 21)),
         ((19, 21), (23, 17)), ((23, 17), (27, 21))], 1.25


def seg_dist(p, a, b):
    (px, py), (ax, ay), (bx, by) = p, a, b
    dx, dy = bx - ax, by - ay
    t = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)))
    return math.hypot(px - ax - t * dx, py - ay - t * dy)


def inside_rounded(x, y, r=6):
    cx, cy = min(max(x, r), SIZE - r), min(max(y, r), SIZE - r)
    return math.hypot(x - cx, y - cy) <= r


def pixel(i, j):
    acc, alpha = [0.0, 0.0, 0.0], 0.0
    for si in range(SS):
        for sj in range(SS):
            x, y = j + (sj + 0.5) / SS, i + (si + 0.5) / SS
            if not inside_rounded(x, y):
                continue
            col = BLUE
            for segs, half in (FLAT, ROUGH):
                if any(seg_dist((x, y), a, b) <= half for a, b in segs):
                    col = WHITE
            acc = [acc[k] + col[k] for k in range(3)]
            alpha += 1
    if alpha == 0:
        return (0, 0, 0, 0)
    return tuple(round(c / alpha) for c in acc) + (round(255 * alpha / SS ** 2),)


def png():
    raw = b"".join(b"\0" + b"".join(bytes(pixel(i, j)) for j in range(SIZE)) for i in range(SIZE))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", SIZE, SIZE, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def main():
    image = png()
    header = struct.pack("<HHH", 0, 1, 1)
    entry = struct.pack("<BBBBHHII", SIZE, SIZE, 0, 0, 1, 32, len(image), 6 + 16)
    with open("web/favicon.ico", "wb") as f:
        f.write(header + entry + image)


if __name__ == "__main__":
    main()
