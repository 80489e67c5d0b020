#!/usr/bin/env bash
# Stiff and extreme inputs: bench/results/stability.csv (result, error estimate, actual error
# against a finer run, time) and the honesty summary in stability.txt. A few minutes.
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
{
    echo "# ljgap stability, $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m), load $(cut -d' ' -f1-3 /proc/loadavg)"
    "$BUILD/bench/stability" bench/results/stability.csv
} | tee bench/results/stability.txt
