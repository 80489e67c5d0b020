#!/usr/bin/env bash
# The hybrid model against the fully resolved discrete model, its speed, and the discrete
# model's seconds per mean gap (bench/hybrid.c; a few minutes on 2 cores). Writes
#   bench/results/hybrid_validation.csv  max |hybrid - full| (with error bar, at which gap) for
#                                        m0 = 0.1, 0.218, 0.3 and k_split = 2, 3, 4 in three
#                                        settings, the theory's distance, times and their ratio
#   bench/results/hybrid_curves.csv      the curves behind it
#   bench/results/hybrid_fine_alone.csv  the band (3, 8] alone: full model against the theory
#   bench/results/hybrid_validation.png  L = 8π: full model, hybrid, theory (gnuplot)
#   bench/results/hybrid_speed.txt       the hybrid at k_split = k2/4 against the full model at
#                                        the same resolution of its band (median times, ratio),
#                                        and seconds per mean gap at n = 256 and 512
#   BUILD=build bench/hybrid.sh [--plot]   (--plot: only redraw the figure)
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
out=bench/results
mkdir -p "$out"
bin="$BUILD/bench/hybrid"
if [ "${1:-}" != --plot ]; then
    nice -n 19 "$bin" --validation --curves "$out/hybrid_curves.csv" >"$out/hybrid_validation.csv"
    nice -n 19 "$bin" --fine-alone >"$out/hybrid_fine_alone.csv"
    {
        echo "# $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m); load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
        echo "# the hybrid at k_split = k2/4 = 2 against the full model, same points per shortest wave"
        nice -n 19 "$bin" --speed
        echo "# the plain model: Fig. 6 spectrum, m0 = 0.218, gaps 3.0 .. 1.0 (11), 4 realizations"
        nice -n 19 "$bin" --discrete
        echo "# FFTW planner flags (the model plans with FFTW_ESTIMATE: deterministic)"
        nice -n 19 "$bin" --fftw
    } >"$out/hybrid_speed.txt"
fi
column -s, -t <"$out/hybrid_validation.csv"
cat "$out/hybrid_speed.txt"
if command -v gnuplot >/dev/null; then
    gnuplot <<GP
set terminal pngcairo size 1200,900 font ",10"
set output "$out/hybrid_validation.png"
set datafile separator ","
set multiplot layout 3,3 title "Hybrid (k_{split} on the grid, the finer band through its statistical law) against the full discrete model, L = 8π: D = 2.2, k_1 = 1, k_2 = 8" font ",12"
set xrange [0.85:3.25]
set grid
set key bottom right font ",8"
f = "$out/hybrid_curves.csv"
do for [m in "0.1 0.218 0.3"] {
    do for [k in "2 3 4"] {
        set title sprintf("m_0 = %s, k_{split} = %s", m, k)
        set xlabel "mean gap g_{ave} / ε"
        set ylabel "σ̄ / σ_0"
        set yrange [-1.8:0.8]
        plot f using 4:((strcol(1) eq "L=8pi" && \$2 == m + 0 && \$3 == k + 0) ? \$9 : 1/0) with lines lw 2 lc rgb "#1f5fbf" title "theory", \
             f using 4:((strcol(1) eq "L=8pi" && \$2 == m + 0 && \$3 == k + 0) ? \$5 : 1/0):6 with yerrorbars pt 7 ps 0.6 lc rgb "#333333" title "full (n = 256)", \
             f using 4:((strcol(1) eq "L=8pi" && \$2 == m + 0 && \$3 == k + 0) ? \$7 : 1/0) with linespoints pt 4 ps 0.6 lc rgb "#d1495b" title "hybrid (n = 64)"
    }
}
unset multiplot
GP
    echo "wrote $out/hybrid_validation.png"
else
    echo "gnuplot missing (make deps installs gnuplot-nox): no plot" >&2
fi
