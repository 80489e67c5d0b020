#!/usr/bin/env bash
# Runs the benchmarks and writes their figures to bench/results/. Figures, not pass/fail.
# speed.txt comes from here; every other bench/*.sh is run after it, in name order, and writes
# its own files into bench/results/.
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
export BUILD
mkdir -p bench/results
out=bench/results/speed.txt
{
    echo "# ljgap speed figures, $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m)"
    "$BUILD/bench/speed"
    if command -v valgrind >/dev/null; then
        ir=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null "$BUILD/bench/speed" --once 2>&1 |
            sed -n 's/.*Collected : \([0-9]*\).*/\1/p')
        echo "fig4_adhesion_instructions ${ir:-unknown} (callgrind)"
    fi
} | tee "$out"
for s in bench/*.sh; do
    [ "$s" = bench/run.sh ] && continue
    echo "== $s"
    "$s"
done
