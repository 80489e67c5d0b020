#!/usr/bin/env bash
# Instrument files in (issue 28): for each kind of test file, written by tests/files/gen.py
# from its format's documentation, the reader (build/tests/files/files_dump) must find exactly what
# the generator put in; every prefix of the file must be refused, never crash (the files_dump
# binary of a sanitizer build catches a read past the end: SANITIZE=address,undefined); and
# where Gwyddion reads the format, what Gwyddion made of it (converted headless to .gwy, read
# by the independent tests/files/gwy_dump.py) must agree point by point. Prints one "ok ..." or
# "not ok ..." line per check.
#
# A format joins with one line in KINDS: the generator's kind, the file's extension (Gwyddion
# picks its reader by content and extension), and the cross-check: "gwyddion" (convert, then
# compare), "self" (the file is .gwy: gwy_dump.py reads it directly) or "none: why" (said in
# a skip line).
set -u
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
DUMP=$BUILD/tests/files/files_dump
PY=/usr/bin/python3
T=tests/files
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

KINDS=(
    "nanoscope16 spm gwyddion"
    "nanoscope32 spm gwyddion"
    "gsf gsf gwyddion"
    "gwy gwy self"
    "xyz xyz none: Gwyddion 2.62 imports xyz points only through an interactive dialog"
)
# text formats: a prefix may be a smaller valid file (fewer lines), so only "never a crash"
TEXT_KINDS=" xyz "

n=0
ok() { n=$((n + 1)); echo "ok $n - files: $1"; }
fail() { n=$((n + 1)); echo "not ok $n - files: $1"; }
check() { # check DESCRIPTION COMMAND...
    local what=$1
    shift
    if "$@" >"$tmp/why" 2>&1; then ok "$what"; else fail "$what: $(head -3 "$tmp/why" | tr '\n' ' ')"; fi
}

if [ ! -x "$DUMP" ]; then
    fail "$DUMP is not built"
    exit 1
fi
if ! "$PY" -c 'import numpy' 2>/dev/null; then
    fail "$PY has no numpy (Debian python3-numpy, in make test's packages)"
    exit 1
fi
have_gwyddion=0
command -v gwyddion >/dev/null 2>&1 && have_gwyddion=1

for entry in "${KINDS[@]}"; do
    read -r kind ext cross <<<"$entry"
    f=$tmp/$kind.$ext
    if ! "$PY" $T/gen.py "$kind" "$f" 2>"$tmp/why"; then
        fail "$kind: the generator failed: $(head -2 "$tmp/why")"
        continue
    fi
    "$DUMP" "$f" >"$f.got" 2>&1
    check "$kind: read back exactly (grid, size, unit, channels, missing, every height)" \
        "$PY" $T/compare.py "$f.got" "$f.expected"
    "$DUMP" --truncate "$f" >"$f.trunc" 2>&1
    rc=$?
    if [ $rc -ne 0 ] || ! grep -q '^prefixes ' "$f.trunc"; then
        fail "$kind: every prefix read without a crash (exit $rc: $(tail -3 "$f.trunc" | tr '\n' ' '))"
    elif [[ "$TEXT_KINDS" == *" ${kind} "* ]]; then
        ok "$kind: every prefix read without a crash ($(cat "$f.trunc"))"
    else
        check "$kind: every prefix refused as bad or unknown, none read ($(cat "$f.trunc"))" \
            grep -Eq '^prefixes [0-9]+ ok 0 bad [0-9]+ unknown [0-9]+ other 0$' "$f.trunc"
    fi
    case $cross in
    self)
        "$PY" $T/gwy_dump.py "$f" >"$f.ref" 2>&1
        check "$kind: agrees point by point with the independent gwy_dump.py" \
            "$PY" $T/compare.py "$f.got" "$f.ref" nx ny size_x size_y missing channel channels
        # and Gwyddion reads the generated file as we do (it writes it out again, mask and all)
        if [ $have_gwyddion = 1 ]; then
            (cd "$tmp" && timeout 120 env -u DISPLAY gwyddion --convert-to-gwy="$kind.gwyddion.gwy" \
                "$kind.$ext") >/dev/null 2>&1
            "$PY" $T/gwy_dump.py "$tmp/$kind.gwyddion.gwy" >"$f.ref2" 2>&1
            check "$kind: Gwyddion loads the generated file and agrees point by point" \
                "$PY" $T/compare.py "$f.got" "$f.ref2" nx ny size_x size_y missing channel
        fi
        ;;
    gwyddion)
        if [ $have_gwyddion = 0 ]; then
            n=$((n + 1))
            echo "ok $n - files: $kind: agrees with Gwyddion # skip gwyddion is not installed"
            continue
        fi
        # headless: no display is needed for --convert-to-gwy
        (cd "$tmp" && timeout 120 env -u DISPLAY gwyddion --convert-to-gwy="$kind.gwyddion.gwy" \
            "$kind.$ext") >/dev/null 2>&1
        if [ ! -s "$f.gwyddion.gwy" ] && [ ! -s "$tmp/$kind.gwyddion.gwy" ]; then
            fail "$kind: Gwyddion converted it"
            continue
        fi
        "$PY" $T/gwy_dump.py "$tmp/$kind.gwyddion.gwy" >"$f.ref" 2>&1
        check "$kind: agrees point by point with Gwyddion's reading (heights, grid, size)" \
            "$PY" $T/compare.py "$f.got" "$f.ref" nx ny size_x size_y missing
        ;;
    *)
        n=$((n + 1))
        echo "ok $n - files: $kind: cross-check # skip ${entry#* * }"
        ;;
    esac
done

# detection, forcing a format, channels
f=$tmp/nanoscope16.spm
check "a channel by index" sh -c "'$DUMP' '$f' - 1 | grep -qx 'channel Amplitude Error'"
check "a channel by title" sh -c "'$DUMP' '$f' - ZSensor | grep -qx 'channel_index 2'"
check "a channel in V is read in V (not a height)" sh -c "'$DUMP' '$f' - 1 | grep -qx 'z_unit V'"
check "an unknown channel is status 3, listing the channels" \
    sh -c "'$DUMP' '$f' - Phase | grep -q '^error 3 .*0 \"Height\", 1 \"Amplitude Error\"'"
check "a forced format that does not fit is bad-file (2), not unknown" \
    sh -c "'$DUMP' '$f' gwy | grep -q '^error 2 format gwy offset 0'"
check "an unknown format name is status 1 listing the formats" \
    sh -c "'$DUMP' '$f' pdf | grep -q '^error 1 .*formats read are gwy, gsf, x3p, .*nanoscope, ibw, plu, xyz'"
head -c 3000 /dev/urandom >"$tmp/noise.bin"
printf '\x89PNG\r\n\x1a\n' | cat - "$tmp/noise.bin" >"$tmp/noise.png"
check "a PNG is unknown (1)" sh -c "'$DUMP' '$tmp/noise.png' | grep -q '^error 1 '"
check "an empty file is unknown (1)" sh -c ": >'$tmp/empty'; '$DUMP' '$tmp/empty' | grep -q '^error 1 '"
# the command line: ljgap psd FILE recognises the file; a text matrix with --dx stays text
LJGAP=$BUILD/ljgap
if [ -x "$LJGAP" ]; then
    "$LJGAP" psd "$tmp/gwy.gwy" >"$tmp/cli.json"
    check "ljgap psd FILE.gwy: exit 0, the answer's source names the format and the mask's points" \
        jq -e '.source.format == "gwy" and .source.channel == "Height" and .source.missing.count > 0
            and (.meta.warnings | any(test("largest complete rectangle")))' "$tmp/cli.json"
    "$LJGAP" psd --channel Phase "$tmp/nanoscope16.spm" >"$tmp/cli.json"
    check "ljgap psd --channel NAME: a channel the file lacks is exit 1, 422 at /channel" \
        sh -c "[ $? = 1 ] && jq -e '.errors[0].pointer == \"/channel\"' '$tmp/cli.json' >/dev/null"
    "$LJGAP" psd --format gsf "$tmp/nanoscope16.spm" >"$tmp/cli.json"
    check "ljgap psd --format: a file that is not that format is bad-file" \
        jq -e '.type == "/problems/bad-file" and .format == "gsf"' "$tmp/cli.json"
    awk 'BEGIN { for (j = 0; j < 16; j++) { for (i = 0; i < 16; i++) printf "%s%g", i ? " " : "",
        1e-9 * sin(0.7 * i + 1.3 * j); print "" } }' >"$tmp/matrix.txt"
    "$LJGAP" psd --dx 1e-8 "$tmp/matrix.txt" >"$tmp/cli.json"
    check "ljgap psd --dx M FILE: a text matrix is still read as text (no source)" \
        jq -e '.grid.nx == 16 and (has("source") | not)' "$tmp/cli.json"
else
    fail "$LJGAP is not built"
fi
# a hostile NanoScope map (found by fuzz_files) whose reliable bins carry no power: the answer
# has no psd object rather than a table with P = 0, which the PSD calls would refuse
if [ -x "$LJGAP" ]; then
    tail -c +3 tests/fuzz/files_corpus/crash-psd-table-refused >"$tmp/zero.spm"
    "$LJGAP" psd "$tmp/zero.spm" >"$tmp/cli.json"
    check "a map whose bins carry no power gets no psd table with P = 0" \
        jq -e '.source.format == "nanoscope" and (.psd == null or (.psd.P | all(. > 0)))' "$tmp/cli.json"
fi
# a tip radius the file stores feeds the reliable band (a 1 um tip on a 1 um map with 64 points
# a side ends the band below Nyquist), unless the query gives one
if [ -x "$LJGAP" ] && /usr/bin/python3 -c 'import netCDF4' 2>/dev/null; then
    /usr/bin/python3 tests/files/gen_tip_nc.py "$tmp/tip.nc" 1000
    "$LJGAP" psd "$tmp/tip.nc" >"$tmp/cli.json"
    check "a stored tip radius (netCDF json, 1 um) ends the reliable band: by tip" \
        jq -e '.source.tip_radius == 1e-6 and .reliable.by == "tip"' "$tmp/cli.json"
    "$LJGAP" psd --tip_radius 1e-10 "$tmp/tip.nc" >"$tmp/cli.json"
    check "the query's tip radius overrides the stored one: the band reaches Nyquist" \
        jq -e '.source.tip_radius == 1e-6 and .reliable.by == "nyquist"' "$tmp/cli.json"
else
    fail "a stored tip radius: $LJGAP or python3-netcdf4 missing"
fi
# the seed files of the formats generated by check_b.sh and check_c.sh are recognised by content,
# in the registry's order (files.c): no probe of another format claims them (the kinds above are
# recognised in their own checks)
for pair in dat_valid.dat:metropro ibw_valid.ibw:ibw nc_valid.nc:netcdf plu_valid.plu:plu \
    sur_valid.sur:sur sur_compressed.sur:sur tiff_park_valid.tiff:park-tiff x3p_valid.x3p:x3p; do
    f=tests/fuzz/files_corpus/${pair%%:*}
    check "${pair%%:*} is recognised as ${pair#*:}" sh -c "'$DUMP' '$f' | head -n 1 | grep -qx 'format ${pair#*:}'"
done
# the X3P, Digital Surf, MetroPro and netCDF readers (check_b.sh) and the Igor, Park TIFF and
# Sensofar readers (check_c.sh) against Gwyddion and python3-netcdf4, with their own generators
sh tests/files/check_b.sh
bash tests/files/check_c.sh
echo "$n checks"
