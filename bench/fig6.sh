#!/usr/bin/env bash
# The paper's Fig. 6: discrete numerical model (core/sim/sim.c) vs statistical theory (PDE) for
# D = 2.2, k1 = 1, k2 = 8, m0 = 0.1, 0.218, 0.3, four realizations. Writes
#   bench/results/fig6.csv              per L, m0 and mean gap: numerical sigma (mean, std,
#                                       error), theory (value, error), difference, residual, jump
#   bench/results/fig6_convergence.csv  m0 = 0.218 at five gaps vs n, realizations and L
#   bench/results/fig6.png              the figure (gnuplot)
# Timings are in the '#' lines of fig6.csv and the seconds column of the convergence table.
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
out=bench/results
mkdir -p "$out"
bin="$BUILD/bench/fig6"
{
    "$bin" --n 128                       # L = 2π/k1: one period of the longest wave (the paper's)
    "$bin" --n 256 --L 25.132741228718345 --no-header # L = 8π: 16 times the area
} >"$out/fig6.csv"
"$bin" --convergence >"$out/fig6_convergence.csv"
grep '^#' "$out/fig6.csv"
cut -d, -f1-5 "$out/fig6_convergence.csv"
if command -v gnuplot >/dev/null; then
    gnuplot <<GP
set terminal pngcairo size 900,640 font ",11"
set output "$out/fig6.png"
set datafile separator ","
set datafile commentschars "#L"
set xlabel "mean gap g_{ave} / ε"
set ylabel "mean traction σ̄ / σ_0"
set xrange [0.95:3.05]
set yrange [-1.6:1.05]
set key bottom right
set grid
set title "Fig. 6: D = 2.2, k_1 = 1, k_2 = 8; lines: statistical theory (PDE); points: numerical model, 4 realizations ± std"
m(x) = x == 0.1 ? 1 : x == 0.218 ? 2 : 3
f = "$out/fig6.csv"
plot for [i=1:3] f using 3:(m(\$2) == i && \$1 < 7 ? \$7 : 1/0) with lines lw 2 lc i title sprintf("theory, m_0 = %s", word("0.1 0.218 0.3", i)), \
     for [i=1:3] f using 3:(m(\$2) == i && \$1 < 7 ? \$4 : 1/0):5 with yerrorbars pt 7 ps 0.8 lc i title sprintf("numerical L = 2π, m_0 = %s", word("0.1 0.218 0.3", i)), \
     for [i=1:3] f using 3:(m(\$2) == i && \$1 > 7 ? \$4 : 1/0):5 with yerrorbars pt 4 ps 0.8 lc i title sprintf("numerical L = 8π, m_0 = %s", word("0.1 0.218 0.3", i))
GP
    echo "wrote $out/fig6.png"
else
    echo "gnuplot missing (make deps installs gnuplot-nox): no plot" >&2
fi
