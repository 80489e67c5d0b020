#!/usr/bin/env bash
# Instrument files in (issue 28): a 2048² 32-bit NanoScope file (three channels, 48 MiB, written
# by tests/files/gen.py) to its PSD: the read alone and the whole handler (bench/files.c,
# medians of 7 runs), and the command line, `ljgap psd FILE`, wall time (median of 5). The
# issue asks for under 1 s. Writes bench/results/files.txt.
#   BUILD=build nice -n 19 bench/files.sh        (make bench runs it)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p bench/results
GEN_NX=2048 GEN_NY=2048 /usr/bin/python3 tests/files/gen.py nanoscope32 "$tmp/map.spm"
cli=()
for _ in 1 2 3 4 5; do
    t0=$(date +%s.%N)
    "$BUILD/ljgap" psd "$tmp/map.spm" >"$tmp/answer"
    cli+=("$(echo "$(date +%s.%N) - $t0" | bc -l)")
done
{
    echo "# instrument file to PSD, $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m), load $(cut -d' ' -f1-3 /proc/loadavg)"
    "$BUILD/bench/files" "$tmp/map.spm" 7
    printf '%s\n' "${cli[@]}" | sort -g | awk '{ t[NR] = $1 } END {
        printf "ljgap psd FILE (wall, the process):  median %.3f s (%.3f ... %.3f), %d runs\n", t[int((NR + 1) / 2)], t[1], t[NR], NR }'
    echo "the answer: $(jq -c '{source: .source | {format, nx, ny, z_unit}, grid: .grid | {dx, dy}, bins: (.k | length)}' "$tmp/answer")"
} | tee bench/results/files.txt
