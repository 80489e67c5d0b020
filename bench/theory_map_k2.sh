#!/usr/bin/env bash
# make bench: skip (a study, not a benchmark: hours on 2 cores; run it by hand)
#
# The validity map extended where users are (issue 31): k2/k1 = 8, 16 and 32, and m0 up to 1,
# for the table the answers read (bench/validity_table.sh turns these results into
# core/validity_table.c; run it after this). Every run under nice -n 19, 4 realizations, k1 = 1.
#   1. k2/k1 = 8 and 16 at L = 4π on n = 128 and 256 (8 points per shortest wave), and 32 on
#      n = 256 (4 points per shortest wave: at k2/k1 = 8 going from 4 to 8 points changed no
#      summary, and n = 512 at 32 took too long on the shared cores), D 2.2, 2.5, 2.8, m0 0.01
#      0.02 0.05 0.1 0.2 0.3 0.5 0.7 1  ->  bench/results/theory_map_k2.csv (the L = 4π runs
#      are tied to the main map's L = 8π by the L bias at k2/k1 = 8: bench/validity_table.sh)
#   4. the grid at k2/k1 = 32: n = 512 (8 points per shortest wave), D = 2.2, m0 0.01 to 0.3
#      ->  bench/results/theory_map_k2_n512.csv
#   3. the square at k2/k1 = 32: L = 8π, n = 512, at (D, m0) = (2.5, 0.2), (2.8, 0.5), (2.2, 0.1)
#      ->  bench/results/theory_map_conv32.csv
#   2. the main map (k2/k1 = 8, L = 8π, n = 256, hybrids k_split 2 and 4 on 64 and 128 points)
#      at m0 0.7 and 1  ->  bench/results/theory_map_ext.csv
# Same columns as theory_map.csv (bench/theory_map.c). Measured (issue 31's run, 2 cores shared
# with other builds, 2 threads): stage 1 1500 s (k2/k1 = 8: 70 s, 16: 380 s, 32: 1050 s), 4 916 s,
# 3 880 s, 2 541 s; each file also ends with a "# ... s" line of its own when run by this script.
#   BUILD=build bench/theory_map_k2.sh [1|2|3|4 ...]   (the stages to run; default 1 3 2 4)
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
out=${OUT:-bench/results}
bin="$BUILD/bench/theory_map"
T=${THREADS:-2}
L4=12.566370614359172
L8=25.132741228718345
stages=${*:-1 3 2 4}
mkdir -p "$out"
hdr() { "$bin" --header --D 2.2 --m0 0.01 --no-full | head -n 1; }
run() { nice -n 19 "$bin" --threads "$T" "$@" | grep -v '^label'; }

for s in $stages; do
    start=$(date +%s)
    new=$(mktemp)
    case $s in
    1)
        f=theory_map_k2.csv
        hdr >"$new"
        for k2n in "8 128" "16 256" "32 256"; do
            set -- $k2n
            for D in 2.2 2.5 2.8; do
                for m0 in 0.01 0.02 0.05 0.1 0.2 0.3 0.5 0.7 1.0; do
                    run --D $D --m0 $m0 --k2 $1 --n $2 --L $L4 --R 4 --label k2_$1 >>"$new"
                done
            done
        done
        ;;
    2)
        f=theory_map_ext.csv
        hdr >"$new"
        for D in 2.2 2.5 2.8; do
            for m0 in 0.7 1.0; do
                run --D $D --m0 $m0 --n 256 --L $L8 --R 4 --k_split 2,4 --hyb-n 64,128 \
                    --label map >>"$new"
            done
        done
        ;;
    3)
        f=theory_map_conv32.csv
        hdr >"$new"
        for c in "2.5 0.2" "2.8 0.5" "2.2 0.1"; do
            set -- $c
            run --D $1 --m0 $2 --k2 32 --n 512 --L $L8 --R 4 --label k2_32_L8pi | grep -v ',theory,' >>"$new"
        done
        ;;
    4)
        f=theory_map_k2_n512.csv
        hdr >"$new"
        for m0 in 0.01 0.02 0.05 0.1 0.2 0.3; do
            run --D 2.2 --m0 $m0 --k2 32 --n 512 --L $L4 --R 4 --label k2_32 >>"$new"
        done
        ;;
    *) echo "unknown stage $s" >&2 && exit 2 ;;
    esac
    echo "# $(date -u +%Y-%m-%d): $(($(date +%s) - start)) s on $(nproc) cores" >>"$new"
    mv "$new" "$out/$f"
    echo "wrote $out/$f"
done
