#!/usr/bin/env bash
# Error against run time of the three methods: bench/results/error_vs_time.csv (columns
# method,setting,error,elapsed_ms), the printed reference, cross-check and equal-error ratios
# in error_vs_time.txt, and the log-log plot error_vs_time.png (gnuplot). A few minutes.
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
out=bench/results
csv=$out/error_vs_time.csv
{
    echo "# ljgap error against time, $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m), load $(cut -d' ' -f1-3 /proc/loadavg)"
    "$BUILD/bench/errtime" "$csv"
} | tee "$out/error_vs_time.txt"
command -v gnuplot >/dev/null || { echo "errtime.sh: gnuplot missing (make deps)"; exit 1; }
# one panel per quantity, one line per method (rows of a method are in ladder order)
panel() { # quantity, title, y label, then the four ladders' descriptions
    local q=$1 m
    echo "set title \"$2\""
    echo "set ylabel \"$3\""
    local sep='plot '
    shift 3
    for m in pde:7 pde_auto:5 paper:9 montecarlo:13; do
        printf '%s"< awk -F, '"'"'$1 == \\"%s\\" && $2 ~ /^%s:/'"'"' %s" using 4:3 with linespoints pt %s title "%s (%s)"' \
            "$sep" "${m%:*}" "$q" "$csv" "${m#*:}" "$(echo "${m%:*}" | tr _ ' ')" "$1"
        sep=', '
        shift
    done
    echo
}
{
    echo 'set terminal pngcairo size 1400,620 font ",11"'
    echo "set output \"$out/error_vs_time.png\""
    echo 'set datafile separator ","'
    echo 'set logscale xy; set format x "10^{%L}"; set format y "10^{%L}"; set grid'
    echo 'set key below; set xlabel "elapsed time per computation (ms, median)"'
    echo "set multiplot layout 1,2 title \"ljgap: error against run time ($(date -u +%Y-%m-%d), $(nproc) shared cores)\""
    panel dgamma "Fig. 4 case: Δγeff/Δγ, absolute error" "|Δγeff - reference|" \
        "one level, L = 0..7" "tol 1e-6..1e-9" "one level, Vmax = 1/25..1/3200" "250..4000 paths, RMS of 3 seeds"
    panel pdf "Fig. 2 case: gap PDF at g_{ave} = 0.98, k_2 = 5, L1 error" "∫|Φ - Φ_{ref}| dg" \
        "one level, L = 0..7" "tol 1e-4..1e-6" "one level, Vmax = 1/10..1/5120" "1e3..2.6e5 paths, RMS of 3 seeds"
    echo 'unset multiplot'
} | gnuplot
echo "wrote $csv and $out/error_vs_time.png"
