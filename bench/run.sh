#!/usr/bin/env bash
# Runs the benchmarks and writes their figures to bench/results/. Figures, not pass/fail.
#   bench/run.sh              all: speed.txt from here, then every other bench/*.sh in name order
#   bench/run.sh speed errtime   only those (speed is this script's part; NAME is bench/NAME.sh)
# speed.txt: wall-clock medians (build/bench/speed) and the instructions of one Fig. 4 adhesion
# and one 200-point traction curve under callgrind (ljgap_traction and all it calls, i.e. one
# request through the core API), each with its ratio to the figures before issue 19.
# A script marked "# make bench: skip" (a study of an hour or more) runs only when named.
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
export BUILD
mkdir -p bench/results
want() { [ $# -eq 0 ] || [[ " $* " == *" $name "* ]]; }

# Before issue 19 (main at 8d57763): instructions counted the same way with this driver, and the
# medians of that version's speed.txt (its 200-point curve spanned g_ave 0.8..6, which cost the
# same instructions as 1.5..6 within 1.2 %).
prev_ir_fig4=41469541
prev_ir_curve=176505584
prev_ms_fig4=7.62
prev_ms_curve=31.83

name=speed
if want "$@"; then
    out=bench/results/speed.txt
    {
        echo "# ljgap speed figures, $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m), load $(cut -d' ' -f1-3 /proc/loadavg)"
        "$BUILD/bench/speed" | awk -v pf="$prev_ms_fig4" -v pc="$prev_ms_curve" '
            { print }
            /^fig4_adhesion_ms_median/ { printf "fig4_adhesion_ms_ratio %.1f (previous %s ms / this)\n", pf / $2, pf }
            /^traction_200_points_ms_median/ { printf "traction_200_ms_ratio %.1f (previous %s ms / this)\n", pc / $2, pc }'
        if command -v valgrind >/dev/null; then
            for c in fig4 curve; do
                ir=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null \
                    --toggle-collect=ljgap_traction "$BUILD/bench/speed" --once $c 2>&1 |
                    sed -n 's/.*Collected : \([0-9]*\).*/\1/p')
                prev=$prev_ir_fig4 label=fig4_adhesion_instructions
                [ $c = curve ] && prev=$prev_ir_curve label=traction_200_instructions
                awk -v l=$label -v ir="${ir:-0}" -v p=$prev 'BEGIN {
                    if (ir > 0) printf "%s %d (callgrind, ljgap_traction inclusive); previous %d: %.1fx fewer\n", l, ir, p, p / ir
                    else printf "%s unknown (callgrind failed)\n", l }'
            done
        fi
    } | tee "$out"
fi
for s in bench/*.sh; do
    name=$(basename "$s" .sh)
    [ "$name" = run ] && continue
    want "$@" || continue
    if [ $# -eq 0 ] && grep -q '^# make bench: skip' "$s"; then
        echo "== $s: skipped (a study; run it by hand, or bench/run.sh $name)"
        continue
    fi
    echo "== $s"
    "$s"
done
