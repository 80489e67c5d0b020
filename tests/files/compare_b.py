#!/usr/bin/env python3
"""compare_b.py -- point-by-point comparison for tests/files/check_b.sh: what ljgap's reader
gave (dump_b's JSON) against the generator's truth (gen_b.py, gen_nc.py) and, where given,
against Gwyddion's reading (gwy_dump.py --json of the .gwy file Gwyddion wrote).

usage: compare_b.py OURS.json TRUTH.json [GWY.json GWY_CHANNEL [HOLES[,offset]]]
  HOLES mask: Gwyddion marks our missing points in its mask (X3P, MetroPro)
  HOLES min:  Gwyddion keeps the "no data" value, the smallest of the map (Digital Surf)
  offset:     Gwyddion's heights may differ from ours by one constant (an inverted .sur:
              Gwyddion reflects z about the mean, ljgap negates it); the constant is taken
              from the first point and every other point must agree with it
Prints nothing and exits 0 when all agree; else one line a disagreement, exit 1.
"""
import json
import math
import sys

REL = 1e-12


def close(a, b, scale):
    return abs(a - b) <= REL * max(abs(a), abs(b), scale)


def main():
    ours = json.load(open(sys.argv[1]))
    truth = json.load(open(sys.argv[2]))
    bad = []
    for key in ("nx", "ny", "missing", "z_unit"):
        if ours[key] != truth[key]:
            bad.append("%s: ours %r, truth %r" % (key, ours[key], truth[key]))
    for key in ("size_x", "size_y"):
        if not close(ours[key], truth[key], 0):
            bad.append("%s: ours %r, truth %r" % (key, ours[key], truth[key]))
    for key in ("instrument", "acquired", "periodic"):
        if key in truth and ours[key] != truth[key]:
            bad.append("%s: ours %r, truth %r" % (key, ours[key], truth[key]))
    if "tip_radius" in truth and not close(ours["tip_radius"], truth["tip_radius"], 0):
        bad.append("tip_radius: ours %r, truth %r" % (ours["tip_radius"], truth["tip_radius"]))
    zs, zt = ours["z"], truth["z"]
    scale = max([abs(v) for v in zt if v is not None] or [1.0])
    for k, (a, b) in enumerate(zip(zs, zt)):
        if (a is None) != (b is None) or (a is not None and not close(a, b, scale * 1e-3)):
            bad.append("point %d: ours %r, truth %r" % (k, a, b))
    if len(sys.argv) > 3:
        g = json.load(open(sys.argv[3]))[sys.argv[4]]
        opts = (sys.argv[5] if len(sys.argv) > 5 else "mask").split(",")
        holes = opts[0]
        nx, ny = ours["nx"], ours["ny"]
        if (g["xres"], g["yres"]) != (nx, ny):
            bad.append("Gwyddion's grid %dx%d, ours %dx%d" % (g["xres"], g["yres"], nx, ny))
        else:
            for key, gk in (("size_x", "xreal"), ("size_y", "yreal")):
                if not close(ours[key], g[gk], 0):
                    bad.append("%s: ours %r, Gwyddion %r" % (key, ours[key], g[gk]))
            if ours["z_unit"] in ("m",) and g["unit_z"] != "m":
                bad.append("Gwyddion's z unit %r" % g["unit_z"])
            gmin = min(v for row in g["data"] for v in row)
            shift = 0.0
            if "offset" in opts:
                k0 = next(k for k, v in enumerate(zs) if v is not None)
                shift = zs[k0] - g["data"][k0 // nx][k0 % nx]
            for j in range(ny):
                for i in range(nx):
                    a, b = zs[j * nx + i], g["data"][j][i] + shift
                    m = g.get("mask")
                    masked = m is not None and m[j][i] != 0
                    if a is None:
                        ok = masked or math.isnan(b) if holes == "mask" else b == gmin
                        if not ok:
                            bad.append("(%d,%d): missing in ours, %r in Gwyddion" % (i, j, b))
                    elif masked or not close(a, b, scale * 1e-3):
                        bad.append("(%d,%d): ours %r, Gwyddion %r%s" %
                                   (i, j, a, b, " (masked)" if masked else ""))
    for line in bad[:10]:
        print(line)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
