#!/usr/bin/env bash
# The cost of input_error (issue 29: at most 20 times the answer without it, the Fig. 4 adhesion
# within 30 ms): bench/uncert.c's medians with and without, whole handler. Writes
# bench/results/uncert.txt. `BUILD=build nice -n 19 bench/uncert.sh` (make bench runs it).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
mkdir -p bench/results
{
    echo "# input_error, $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m), load $(cut -d' ' -f1-3 /proc/loadavg)"
    "$BUILD/bench/uncert" 21
} | tee bench/results/uncert.txt
