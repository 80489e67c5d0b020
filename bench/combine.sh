#!/usr/bin/env bash
# POST /v1/psd/combine (issue 25): the time to combine 4 PSDs (bench/combine.c; the issue asks
# for under 10 ms), medians and 99th percentiles of 2000 runs, core and whole handler. Writes
# bench/results/combine.txt. `BUILD=build nice -n 19 bench/combine.sh` (make bench runs it).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
mkdir -p bench/results
{
    echo "# psd/combine, $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m), load $(cut -d' ' -f1-3 /proc/loadavg)"
    "$BUILD/bench/combine" 2000
} | tee bench/results/combine.txt
