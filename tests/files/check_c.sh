#!/usr/bin/env bash
# check_c.sh -- the readers of Igor binary waves, Park Systems TIFF and Sensofar PLu
# (server/files/ibw.c, park_tiff.c, plu.c) against an independent reader, Gwyddion (2.62):
# tests/files/gen_c.py writes the files from the formats' documentation, Gwyddion converts each
# to its native .gwy (`gwyddion --convert-to-gwy`, headless), tests/files/gwy_dump.py --points
# reads that, and our reader's dump ($BUILD/tests/test_files_c --dump) must agree with it point by
# point (relative 1e-6), in grid, size and height unit, with our missing points exactly where
# Gwyddion masks points. One "ok"/"not ok" line per channel compared; without gwyddion
# "ok 1 # skip no gwyddion".
#   BUILD=build [SEED=28] tests/files/check_c.sh   (SEED: the generator's random heights)
set -u
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
bin=$BUILD/tests/test_files_c
py=
for p in /usr/bin/python3 python3; do # the generator needs numpy: the system's python has it
    if command -v "$p" >/dev/null 2>&1 && "$p" -c 'import numpy' 2>/dev/null; then
        py=$p
        break
    fi
done
n=0
say() { n=$((n + 1)); echo "$1 $n - $2"; }
if ! command -v gwyddion >/dev/null 2>&1; then
    echo "ok 1 # skip no gwyddion"
    exit 0
fi
if [ ! -x "$bin" ] || [ -z "$py" ]; then
    echo "not ok 1 - $bin is not built or no python3 has numpy"
    exit 0
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/home"
if ! "$py" tests/files/gen_c.py "$tmp" "${SEED:-28}"; then
    echo "not ok 1 - gen_c.py failed"
    exit 0
fi

# format, file, our channel, Gwyddion's channel id, whether the titles must agree
while read -r fmt file ch gid titles; do
    if [ ! -s "$tmp/$file.gwy" ]; then
        HOME=$tmp/home timeout 120 gwyddion --convert-to-gwy="$tmp/$file.gwy" "$tmp/$file" \
            >"$tmp/$file.log" 2>&1
    fi
    if [ ! -s "$tmp/$file.gwy" ]; then
        say "not ok" "$file: gwyddion wrote no .gwy ($(tail -1 "$tmp/$file.log"))"
        continue
    fi
    if ! "$bin" --dump "$fmt" "$tmp/$file" "$ch" >"$tmp/ours" 2>"$tmp/err"; then
        say "not ok" "$file channel $ch: our reader failed: $(cat "$tmp/err")"
        continue
    fi
    if ! "$py" tests/files/gwy_dump.py --points "$tmp/$file.gwy" "$gid" >"$tmp/theirs" \
        2>"$tmp/err"; then
        say "not ok" "$file: the .gwy does not parse: $(tail -1 "$tmp/err")"
        continue
    fi
    msg=$("$py" - "$tmp/ours" "$tmp/theirs" "$titles" <<'EOF'
import math, sys
ours = open(sys.argv[1]).read().split("\n")
theirs = open(sys.argv[2]).read().split("\n")
nx, ny, sx, sy, unit, missing, *title = ours[0].split(" ")
gx, gy, greal_x, greal_y, gunit, gtitle = theirs[0].split(" ")
nx, ny, missing = int(nx), int(ny), int(missing)
def close(a, b):
    return abs(a - b) <= 1e-6 * max(abs(a), abs(b)) or a == b
lengths = {"m", "mm", "um", "nm", "pm", "A"}
problems = []
if (nx, ny) != (int(gx), int(gy)):
    problems.append("grid %dx%d, Gwyddion %sx%s" % (nx, ny, gx, gy))
if not close(float(sx), float(greal_x)) or not close(float(sy), float(greal_y)):
    problems.append("size %s x %s, Gwyddion %s x %s" % (sx, sy, greal_x, greal_y))
if (unit in lengths and gunit != "m") or (unit not in lengths and unit != gunit):
    problems.append("unit %s, Gwyddion %s" % (unit, gunit))
if sys.argv[3] == "1" and "_".join(title) != gtitle:
    problems.append("title %s, Gwyddion %s" % (" ".join(title), gtitle))
bad = masked = 0
for k in range(nx * ny):
    a = float(ours[1 + k])
    b, m = theirs[1 + k].split(" ")
    masked += m == "1"
    if math.isnan(a):
        bad += m != "1"
    elif m == "1" or not close(a, float(b)):
        bad += 1
if bad:
    problems.append("%d of %d points differ" % (bad, nx * ny))
if masked != missing:
    problems.append("%d missing, Gwyddion masks %d" % (missing, masked))
print("; ".join(problems) if problems else "%dx%d points, %d missing, unit %s" % (nx, ny, missing, unit))
sys.exit(1 if problems else 0)
EOF
    ) && say ok "$file channel $ch agrees with Gwyddion: $msg" ||
        say "not ok" "$file channel $ch: $msg"
done <<'LIST'
ibw ibw_le.ibw 0 0 1
ibw ibw_le.ibw 1 1 1
ibw ibw_le.ibw 2 2 1
ibw ibw_be.ibw 0 0 1
ibw ibw_be.ibw 1 1 1
ibw ibw_i16.ibw 0 0 1
park-tiff park_v2.tiff 0 0 1
park-tiff park_v1.tiff 0 0 1
park-tiff park_swap.tiff 0 0 1
plu plu.plu 0 0 0
LIST
