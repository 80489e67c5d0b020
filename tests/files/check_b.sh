#!/bin/sh
# check_b.sh -- the X3P, Digital Surf, MetroPro and netCDF readers (server/files/) against
# independent readers, point by point (issue 28). tests/files/gen_b.py writes X3P, .sur and
# MetroPro files from the formats' descriptions and Gwyddion (2.62, headless:
# gwyddion --convert-to-gwy) converts each to .gwy, which gwy_dump.py --json parses; gen_nc.py
# writes netCDF files with python3-netcdf4 and reads them back with it. compare_b.py holds ljgap's
# reading (dump_b, built here from the readers' sources) against the generator's values and
# Gwyddion's: grid, size, unit, every height (relative 1e-12), the missing points, the
# metadata. Then every file cut short at several lengths must be refused as bad (exit 2), and
# a netCDF-4 (HDF5) file must be refused with a message. TAP output.
#   BUILD=build tests/files/check_b.sh
set -u
cd "$(dirname "$0")/../.." || exit 1
BUILD=${BUILD:-build}
OUT=$BUILD/files_b
CC=${CC:-cc}
rm -rf "$OUT" && mkdir -p "$OUT/gen" || exit 1
n=0
fails=0
ok() { n=$((n + 1)); echo "ok $n - $1"; }
notok() { n=$((n + 1)); fails=$((fails + 1)); echo "not ok $n - $1"; }

# python3 with netCDF4 (Debian's python3-netcdf4 is in /usr/bin's python3)
PY=python3
/usr/bin/python3 -c 'import netCDF4' 2>/dev/null && PY=/usr/bin/python3

# (every reader's source: files.c's registry and shared helpers name them all)
if ! $CC -std=c11 -D_GNU_SOURCE -O1 -g -Wall -Wextra -Iserver/files tests/files/dump_b.c \
       server/files/*.c $(pkg-config --libs zlib 2>/dev/null || echo -lz) -lm \
       -o "$OUT/dump_b"; then
    notok "dump_b builds"
    echo "1..$n"
    exit 1
fi
ok "dump_b builds"

$PY tests/files/gen_b.py "$OUT/gen" && ok "gen_b.py writes the X3P, .sur and MetroPro files" \
    || notok "gen_b.py writes the X3P, .sur and MetroPro files"
$PY tests/files/gen_nc.py "$OUT/gen" && ok "gen_nc.py writes the netCDF files" \
    || notok "gen_nc.py writes the netCDF files"

have_gwy=0
command -v gwyddion >/dev/null && have_gwy=1

# check FILE FORMAT [GWY_CHANNEL HOLES [OUR_CHANNEL]]
check() {
    f=$OUT/gen/$1 b=$OUT/gen/${1%.*}
    chan=${5:-}
    if ! "$OUT/dump_b" "$2" "$f" $chan > "$b.ours$chan" 2> "$b.err"; then
        notok "$1 read as $2: $(cat "$b.err")"
        return
    fi
    if "$PY" tests/files/compare_b.py "$b.ours$chan" "$b.json" > "$b.cmp" 2>&1; then
        ok "$1${chan:+ channel $chan}: ljgap's reading matches the generated values"
    else
        notok "$1${chan:+ channel $chan}: ljgap's reading differs from the generated values"
        sed 's/^/# /' "$b.cmp"
    fi
    [ $# -ge 3 ] || return
    if [ $have_gwy = 0 ]; then
        notok "$1: gwyddion is not installed (the Gwyddion cross-check cannot run)"
        return
    fi
    if [ ! -s "$b.gwy" ]; then
        timeout 120 gwyddion --convert-to-gwy="$b.gwy" "$f" > "$b.gwylog" 2>&1
    fi
    if [ ! -s "$b.gwy" ] || ! "$PY" tests/files/gwy_dump.py --json "$b.gwy" > "$b.gwy.json"; then
        notok "$1: Gwyddion converts it ($(head -c 200 "$b.gwylog"))"
        return
    fi
    if "$PY" tests/files/compare_b.py "$b.ours$chan" "$b.json" "$b.gwy.json" "$3" "$4" \
        > "$b.cmp" 2>&1; then
        ok "$1${chan:+ channel $chan}: Gwyddion's reading agrees point by point"
    else
        notok "$1${chan:+ channel $chan}: Gwyddion's reading differs"
        sed 's/^/# /' "$b.cmp"
    fi
}

for f in x3p_d x3p_d_nan x3p_f_nan_deflate x3p_i_valid x3p_l; do check $f.x3p x3p 0 mask; done
for f in sur16 sur32_holes sur32_zones sur32_offset; do check $f.sur sur 0 min; done
for f in sur16_inverted sur16_flip sur16_flop; do check $f.sur sur 0 min,offset; done
check surz.sur sur   # DSCOMPRESSED: Gwyddion 2.62 does not read it
for f in mp1 mp2_intensity mp3 mp2_sign; do check $f.dat metropro 0 mask; done
for f in nc_map nc_fill nc_mask nc_profile nc_cdf5_yx; do check $f.nc netcdf; done

# MetroPro's intensity frame against Gwyddion's second channel
if "$OUT/dump_b" metropro "$OUT/gen/mp2_intensity.dat" Intensity > "$OUT/gen/mp2i.ours" &&
   [ -s "$OUT/gen/mp2_intensity.gwy.json" ] &&
   "$PY" -c '
import json, sys
o = json.load(open(sys.argv[1])); g = json.load(open(sys.argv[2]))["1"]
flat = [v for row in g["data"] for v in row]
sys.exit(0 if o["z"] == flat and o["channel"] == "Intensity" else 1)' \
       "$OUT/gen/mp2i.ours" "$OUT/gen/mp2_intensity.gwy.json"; then
    ok "mp2_intensity.dat: the Intensity channel equals Gwyddion's"
else
    notok "mp2_intensity.dat: the Intensity channel equals Gwyddion's"
fi

# netCDF-4 (HDF5) is refused as bad, with a message that says what to do
if "$OUT/dump_b" netcdf "$OUT/gen/nc4.nc" > /dev/null 2> "$OUT/gen/nc4.err"; then
    notok "nc4.nc (HDF5) is refused"
else
    rc=$?
    [ $rc = 2 ] && grep -q NETCDF3 "$OUT/gen/nc4.err" && ok "nc4.nc (HDF5) is refused as bad" \
        || notok "nc4.nc (HDF5) is refused as bad (exit $rc: $(cat "$OUT/gen/nc4.err"))"
fi

# every file cut short at 1/8 .. 7/8 of its length and one byte short: refused as bad (2)
for f in "$OUT"/gen/*.x3p "$OUT"/gen/*.sur "$OUT"/gen/*.dat "$OUT"/gen/nc_*.nc; do
    case $f in *.x3p) F=x3p ;; *.sur) F=sur ;; *.dat) F=metropro ;; *) F=netcdf ;; esac
    size=$(wc -c < "$f")
    bad=""
    for cut in $((size / 8)) $((size / 4)) $((size * 3 / 8)) $((size / 2)) $((size * 5 / 8)) \
               $((size * 3 / 4)) $((size * 7 / 8)) $((size - 1)); do
        head -c "$cut" "$f" > "$OUT/cut"
        "$OUT/dump_b" $F "$OUT/cut" > /dev/null 2>&1
        rc=$?
        [ $rc = 2 ] || bad="$bad $cut:$rc"
    done
    [ -z "$bad" ] && ok "$(basename "$f") cut short at 8 lengths: refused as bad each time" \
        || notok "$(basename "$f") cut short: not refused as bad at (length:exit)$bad"
done

echo "1..$n"
[ $fails = 0 ]
