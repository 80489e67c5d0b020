#!/usr/bin/env bash
# make bench: skip (a study, not a benchmark: about an hour on 2 cores; run it by hand)
#
# Where the statistical theory holds: the adhesion summary of the discrete model, of
# the theory and of the hybrid over D in {2.2, 2.5, 2.8} and m0 from 0.01 to 0.5 (k1 = 1, k2 = 8),
# with the discrete model's convergence in n, L and realizations checked on three cases.
# Everything runs under nice -n 19 (measured: 58 min for the map, 58 min for the convergence
# cases, on 2 cores shared with other work). Writes
#   bench/results/theory_map.csv              one row per D, m0 and model (bench/theory_map.c)
#   bench/results/theory_map_convergence.csv  three cases at other n, L and R
#   bench/results/theory_map_rel.csv          relative differences to the discrete model, with
#                                             error bars, "within 5 %" verdicts, and the share of
#                                             the difference the hybrid removes
#   bench/results/theory_map.txt              the same as a table
#   bench/results/theory_map.png              the differences against m0 (gnuplot)
#   BUILD=build bench/theory_map.sh [--report]   (--report: only redo the table and the plot)
# bench/theory_map_k2.sh extends the map to k2/k1 = 16, 32 and m0 up to 1, and
# bench/validity_table.sh turns both into the table every answer's "model" reads
# (core/validity_table.c, GET /v1/validity).
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
out=${OUT:-bench/results}
bin="$BUILD/bench/theory_map"
mkdir -p "$out"
L8=25.132741228718345 # 8π: 2π/L = 0.25 < k0, so the sweep also goes back out (jumps flagged)
L4=12.566370614359172
L16=50.26548245743669
T=${THREADS:-2}

if [ "${1:-}" != --report ]; then
    start=$(date +%s)
    # the map: n = 256 at L = 8π (4 points per shortest wave of k2 = 8), 4 realizations; the
    # hybrid at k_split = 2 and 4 on 64 and 128 points (the same points per wave of k_split)
    new=$(mktemp) # the map in progress (moved into place when complete)
    trap 'rm -f "$new"' EXIT
    "$bin" --header --D 2.2 --m0 0.01 --no-full | head -n 1 >"$new"
    for D in 2.2 2.5 2.8; do
        for m0 in 0.01 0.02 0.05 0.1 0.2 0.3 0.5; do
            nice -n 19 "$bin" --D "$D" --m0 "$m0" --n 256 --L "$L8" --R 4 --threads "$T" \
                --k_split 2,4 --hyb-n 64,128 >>"$new"
            tail -n 4 "$new" | cut -d, -f2-4,9-12,16,17
        done
    done
    mv "$new" "$out/theory_map.csv"
    # convergence: L (4π, 8π, 16π at a fixed spacing), n (512 at 8π: twice as fine), R (8)
    {
        head -n 1 "$out/theory_map.csv"
        for c in "2.2 0.1" "2.5 0.2" "2.8 0.5"; do
            set -- $c
            nice -n 19 "$bin" --D "$1" --m0 "$2" --n 128 --L "$L4" --R 4 --threads "$T" --label L4pi
            nice -n 19 "$bin" --D "$1" --m0 "$2" --n 512 --L "$L8" --R 4 --threads "$T" --label n512
            nice -n 19 "$bin" --D "$1" --m0 "$2" --n 256 --L "$L8" --R 8 --threads "$T" --label R8
            nice -n 19 "$bin" --D "$1" --m0 "$2" --n 512 --L "$L16" --R 4 --threads "$T" \
                --k_split 2 --hyb-n 128 --label L16pi
        done
    } | grep -v ',theory,' >"$out/theory_map_convergence.csv"
    echo "# $(date -u +%Y-%m-%d): $(($(date +%s) - start)) s on $(nproc) cores" >>"$out/theory_map_convergence.csv"
fi

# ---- relative differences to the discrete model, the table and the plot ----
# theory_map_rel.csv: per D, m0 and quantity: the discrete value and error, (theory - discrete)
# / discrete with the relative error bar and the 5 % verdict, the hybrid's relative differences
# at k_split = 2 and 4 with theirs, and the share of the theory's difference each removes.
awk -F, -v OFS=, '
    NR == 1 { next }
    { key = $2 "," $3 }
    $4 == "theory"   { for (q = 0; q < 4; q++) th[key, q] = $(10 + 2 * q) }
    $4 == "discrete" { for (q = 0; q < 4; q++) { ds[key, q] = $(10 + 2 * q); de[key, q] = $(11 + 2 * q) }
                       order[++n] = key; jumps[key] = $19 }
    $4 == "hybrid"   { for (q = 0; q < 4; q++) { hy[key, $5, q] = $(10 + 2 * q); he[key, $5, q] = $(11 + 2 * q) } }
    function abs(x) { return x < 0 ? -x : x }
    END {
        split("g_eq sigma_max g_at_max dgamma_eff", name, " ")
        print "D,m0,quantity,discrete,discrete_err,theory_rel,rel_err,within_5pc,hyb2_rel,hyb2_err,hyb4_rel,hyb4_err,removed2,removed4,jumps"
        for (i = 1; i <= n; i++) {
            key = order[i]
            for (q = 0; q < 4; q++) {
                d = ds[key, q]; e = de[key, q] / abs(d); rel = (th[key, q] - d) / d
                v = abs(rel) + e <= 0.05 ? "yes" : (abs(rel) - e > 0.05 ? "no" : "?")
                h2 = (hy[key, 2, q] - d) / d; h4 = (hy[key, 4, q] - d) / d
                e2 = (he[key, 2, q] + de[key, q]) / abs(d); e4 = (he[key, 4, q] + de[key, q]) / abs(d)
                r2 = rel == 0 ? 0 : 1 - abs(h2) / abs(rel); r4 = rel == 0 ? 0 : 1 - abs(h4) / abs(rel)
                printf "%s,%s,%.6g,%.2g,%.5f,%.5f,%s,%.5f,%.5f,%.5f,%.5f,%.3f,%.3f,%d\n", key, name[q + 1], d, de[key, q], rel, e, v, h2, e2, h4, e4, r2, r4, jumps[key]
            }
        }
    }' "$out/theory_map.csv" >"$out/theory_map_rel.csv"
awk -F, '
    NR == 1 { next }
    $3 == "g_at_max" { next }
    { key = $1 " " $2; if (!(key in seen)) { seen[key] = 1; order[++n] = key; jumps[key] = $15 }
      cell[key, $3] = sprintf("%+6.1f ± %3.1f %-3s %+6.1f %+6.1f %5.0f%%", 100 * $6, 100 * $7, $8, 100 * $9, 100 * $11, 100 * $13) }
    END {
        print "Where the theory holds: (model - discrete)/discrete in %, k1 = 1, k2 = 8; discrete: L = 8π,"
        print "n = 256, 4 realizations (error: jackknife over realizations + sweep sampling, relative);"
        print "5%: yes when |difference| + error <= 5 %, no when |difference| - error > 5 %, ? otherwise;"
        print "hyb2, hyb4: the hybrid at k_split = 2 (n = 64) and 4 (n = 128); rm2: share of the theory\047s"
        print "difference the hybrid at k_split = 2 removes, 1 - |hyb2|/|theory|."
        printf "%-4s %-5s", "D", "m0"
        split("g_eq sigma_max dgamma_eff", q, " ")
        for (k = 1; k <= 3; k++) printf " | %-10s %-16s %6s %6s %6s", q[k] ": theory", "", "hyb2", "hyb4", "rm2"
        printf "\n"
        for (i = 1; i <= n; i++) {
            printf "%-10s", order[i]
            for (k = 1; k <= 3; k++) printf " | %s", cell[order[i], q[k]]
            printf "%s\n", (jumps[order[i]] > 0 ? "  (jumps: " jumps[order[i]] ")" : "")
        }
    }' "$out/theory_map_rel.csv" >"$out/theory_map.txt"
# the convergence cases against the map's own runs (L = 8π, n = 256, 4 realizations)
awk -F, '
    FNR == 1 || /^#/ { next }
    FILENAME == ARGV[1] && $4 == "discrete" { for (q = 0; q < 4; q++) { base[$2 "," $3, q] = $(10 + 2 * q); berr[$2 "," $3, q] = $(11 + 2 * q) }; next }
    FILENAME == ARGV[2] && $4 == "discrete" && (($2 "," $3, 0) in base) {
        if (!hdr++) {
            print ""
            print "Convergence of the discrete model: (case - map)/map in % (the map: L = 8π, n = 256, 4 realizations;"
            print "L4pi: L = 4π, n = 128; n512: n = 512; R8: 8 realizations; L16pi: L = 16π, n = 512), ± both errors:"
        }
        printf "%-6s D = %s, m0 = %-4s", $1, $2, $3
        split("g_eq sigma_max g_at_max dgamma_eff", name, " ")
        for (q = 0; q < 4; q++) {
            if (q == 2) continue
            b = base[$2 "," $3, q]
            printf " | %s %+5.1f ± %3.1f", name[q + 1], 100 * ($(10 + 2 * q) - b) / b, 100 * ($(11 + 2 * q) + berr[$2 "," $3, q]) / b
        }
        printf "\n"
    }' "$out/theory_map.csv" "$out/theory_map_convergence.csv" >>"$out/theory_map.txt"
cat "$out/theory_map.txt"

if command -v gnuplot >/dev/null; then
    gnuplot <<GP
set terminal pngcairo size 1400,500 font ",10"
set output "$out/theory_map.png"
set datafile separator ","
set multiplot layout 1,3 title "Where the theory holds: (model - discrete)/discrete against m_0, k_1 = 1, k_2 = 8 (discrete: L = 8π, n = 256, 4 realizations; bars: its error)" font ",11"
set logscale x
set xrange [0.008:0.62]
set xlabel "m_0 (height variance / ε^2)"
set ylabel "relative difference (%)"
set grid
set key below maxrows 3 font ",8"
f = "$out/theory_map_rel.csv"
Ds = "2.2 2.5 2.8"
sel(q, D) = sprintf("< awk -F, '\$3 == \"%s\" && \$1 == \"%s\"' %s", q, D, f)
do for [q in "g_eq sigma_max dgamma_eff"] {
    set title (q eq "g_eq" ? "g_{eq}" : q eq "sigma_max" ? "σ̄_{max}" : "Δγ_{eff}")
    plot 5 with lines dt 2 lc rgb "#888888" notitle, -5 with lines dt 2 lc rgb "#888888" notitle, \
        for [i = 1:3] sel(q, word(Ds, i)) using 2:(100 * \$6):(100 * \$7) with yerrorlines lw 2 lc i pt 7 title sprintf("theory, D = %s", word(Ds, i)), \
        for [i = 1:3] sel(q, word(Ds, i)) using 2:(100 * \$9) with linespoints dt 2 lc i pt 4 title sprintf("hybrid k_{split} = 2, D = %s", word(Ds, i)), \
        for [i = 1:3] sel(q, word(Ds, i)) using 2:(100 * \$11) with linespoints dt 3 lc i pt 6 ps 0.7 title sprintf("hybrid k_{split} = 4, D = %s", word(Ds, i))
}
unset multiplot
GP
    echo "wrote $out/theory_map.png"
fi
