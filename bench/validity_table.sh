#!/usr/bin/env bash
# make bench: skip (turns the validity map's results into a table; no computation of its own)
#
# The validity map as data: reads the discrete model's and the theory's adhesion summaries that
# bench/theory_map.sh and bench/theory_map_k2.sh wrote, and writes
#   core/validity_table.c                     the table the answers read (include/ljgap_validity.h)
#   bench/results/theory_map_validity.csv     the same rows, for reading and plotting
# One command regenerates both from whatever results are there:
#   bench/validity_table.sh
# Each row: k2/k1 (8, 16, 32, or the continuum k2 = ∞), D, m0, and for g_eq, sigma_max and
# dgamma_eff the relative difference (theory - discrete)/discrete with its error:
#   k2 = 8    the main map (L = 8π, n = 256, 4 realizations: theory_map.csv, with
#             theory_map_ext.csv for m0 0.7 and 1); where L = 8π is missing, the L = 4π run plus
#             the L bias of the nearest m0 that has both, that bias added to the error;
#   k2 = 16, 32  the L = 4π runs (n = 256 for both: 8 and 4 points per shortest wave, 4 realizations,
#             theory_map_k2.csv) corrected by the L bias seen at k2 = 8:
#             rel_k2(4π) - rel_8(4π) + rel_8(8π), errors added;
#   continuum rel = a + b s, s = (k1/k2)^p, p = 2(3 - D) (the variance beyond k2 goes as
#             k2^(2D-6)), a and b through the k2 = 16 and 32 points; the error is theirs
#             propagated plus the L bias's plus |fit at k2 = 8 - rel_8(4π)| (the check). Until
#             k2 = 32 is complete: through 8 and 16, the check replaced by the whole
#             extrapolated step |a - rel_16| (no third level to test the form with).
# A k2 level is written only when every D and m0 of it is there (the continuum needs 16 and 32).
set -eu
cd "$(dirname "$0")/.."
res=${RESULTS:-bench/results}
out=${OUT:-core/validity_table.c}
csv=${CSV:-$res/theory_map_validity.csv}
ext="$res/theory_map_ext.csv"
k2f="$res/theory_map_k2.csv"
[ -f "$ext" ] || ext=/dev/null
[ -f "$k2f" ] || k2f=/dev/null
tmp=$(mktemp)

cont=$(mktemp)
trap 'rm -f "$tmp" "$cont"' EXIT
awk -F, -v OFS=, -v csv="$csv" -v cont="$cont" '
    function abs(x) { return x < 0 ? -x : x }
    /^#/ || $1 == "label" { next }
    {
        # which run: the main map at 8π (label map) or a k2 run at 4π (label k2_K)
        if ($1 == "map") set = "M8"; else if ($1 ~ /^k2_/) set = "K" substr($1, 4); else next
        key = set SUBSEP $2 SUBSEP ($3 + 0)
        Ds[$2] = 1; m0s[$3 + 0] = 1
        if ($1 ~ /^k2_/) levels[substr($1, 4) + 0] = 1
        for (q = 0; q < 3; q++) {
            c = q == 2 ? 16 : 10 + 2 * q # g_eq, sigma_max, dgamma_eff
            v = $c; e = $(c + 1)
            if ($4 == "theory") { th[key, q] = v; the[key, q] = e; have_t[key] = 1 }
            else if ($4 == "discrete") { ds[key, q] = v; dse[key, q] = e; have_d[key] = 1 }
            else if ($4 == "hybrid") { hy[key, $5 + 0, q] = v; hye[key, $5 + 0, q] = e }
        }
    }
    # relative difference and its error of run key, quantity q (1: ok)
    function rel(key, q) {
        if (!(key in have_t) || !(key in have_d)) return 0
        R = th[key, q] / ds[key, q] - 1
        RE = (abs(1 + R) * dse[key, q] + the[key, q]) / abs(ds[key, q])
        return 1
    }
    # the indices of arr, numerically ascending, into out[1..]; returns their number
    function sortnum(arr, out,    n, x, i, t) {
        n = 0
        for (x in arr) { out[++n] = x; for (i = n; i > 1 && out[i - 1] + 0 > out[i] + 0; i--) { t = out[i]; out[i] = out[i - 1]; out[i - 1] = t } }
        return n
    }
    function hrel(key, ks, q) {
        if (!((key, ks, q) in hy)) return "NAN"
        return sprintf("%.6f", hy[key, ks, q] / ds[key, q] - 1)
    }
    END {
        nD = sortnum(Ds, D); nm = sortnum(m0s, M); nk = sortnum(levels, K)
        # the L bias at k2 = 8 per D, m0, q: rel_8(8π) - rel_8(4π), or the nearest measured m0
        for (i = 1; i <= nD; i++) for (q = 0; q < 3; q++) {
            for (j = 1; j <= nm; j++) {
                a = "M8" SUBSEP D[i] SUBSEP M[j]; b = "K8" SUBSEP D[i] SUBSEP M[j]
                if (rel(a, q)) { r8 = R; e8 = RE; if (rel(b, q)) { bias[i, j, q] = r8 - R; biase[i, j, q] = e8 + RE; meas[i, j, q] = 1 } }
            }
            for (j = 1; j <= nm; j++) if (!((i, j, q) in meas)) {
                best = 0
                for (jj = 1; jj <= nm; jj++) if ((i, jj, q) in meas && (!best || abs(jj - j) < abs(best - j) || (abs(jj - j) == abs(best - j) && jj > best))) best = jj
                if (best) { bias[i, j, q] = bias[i, best, q]; biase[i, j, q] = biase[i, best, q] + abs(bias[i, best, q]); fb[i, j] = 1 }
            }
        }
        print "k2_over_k1,D,m0,quantity,rel,rel_err,L_bias,L_bias_err,L_bias_from,hyb2_rel,hyb4_rel" > csv
        n = 0
        # k2 = 8: the main map where it is, else 4π + bias
        for (kk = 1; kk <= nk + 1; kk++) {
            k = kk <= nk ? K[kk] : "inf"
            if (k == "inf") { # the pair of levels to extrapolate from, and the level to check with
                if (done[16] && done[32]) { lo = 16; hi = 32; ck = 8 }
                else if (done[8] && done[16]) { lo = 8; hi = 16; ck = 0 }
                else continue
            }
            complete = 1; buf = ""
            for (i = 1; i <= nD && complete; i++) for (j = 1; j <= nm && complete; j++) {
                row = ""
                for (q = 0; q < 3 && complete; q++) {
                    if (!((i, j, q) in bias)) { complete = 0; break }
                    bf = fb[i, j] ? "nearest m0" : "measured"
                    if (k == 8 && rel("M8" SUBSEP D[i] SUBSEP M[j], q)) { r = R; e = RE; bf = "main map (8π)" }
                    else if (k != "inf") {
                        if (!rel("K" k SUBSEP D[i] SUBSEP M[j], q)) { complete = 0; break }
                        r = R + bias[i, j, q]; e = RE + biase[i, j, q]
                    } else {
                        # rel = a + b s, s = (k1/k2)^p, through the levels lo and hi (at 4π)
                        p = 2 * (3 - D[i]); sl_ = lo ^ -p; sh = hi ^ -p
                        if (!rel("K" lo SUBSEP D[i] SUBSEP M[j], q)) { complete = 0; break }; rl = R; el = RE
                        if (!rel("K" hi SUBSEP D[i] SUBSEP M[j], q)) { complete = 0; break }; rh = R; eh = RE
                        b = (rl - rh) / (sl_ - sh); a = rh - b * sh
                        if (ck) { # the check: the fit at the third level against its point
                            if (!rel("K" ck SUBSEP D[i] SUBSEP M[j], q)) { complete = 0; break }
                            chk = abs(a + b * ck ^ -p - R)
                        } else chk = abs(a - rh) # no third level: the whole extrapolated step
                        r = a + bias[i, j, q]
                        e = (el * sh + eh * sl_) / (sl_ - sh) + biase[i, j, q] + chk
                    }
                    vr[q] = r; ve[q] = e
                    h2 = k == 8 ? hrel("M8" SUBSEP D[i] SUBSEP M[j], 2, q) : "NAN"
                    h4 = k == 8 ? hrel("M8" SUBSEP D[i] SUBSEP M[j], 4, q) : "NAN"
                    vh2[q] = h2; vh4[q] = h4
                    row = row sprintf("%s,%s,%s,%s,%.6f,%.6f,%.6f,%.6f,%s,%s,%s\n", k, D[i], M[j], q == 0 ? "g_eq" : q == 1 ? "sigma_max" : "dgamma_eff", r, e, bias[i, j, q], biase[i, j, q], bf, h2, h4)
                }
                if (!complete) break
                buf = buf sprintf("    {%s, %s, %s, {%.6f, %.6f, %.6f}, {%.6f, %.6f, %.6f}, {%.6f, %.6f, %.6f}, {%s, %s, %s}, {%s, %s, %s}},\n",
                                  k == "inf" ? "INFINITY" : k, D[i], M[j], vr[0], vr[1], vr[2], ve[0], ve[1], ve[2],
                                  bias[i, j, 0], bias[i, j, 1], bias[i, j, 2], vh2[0], vh2[1], vh2[2], vh4[0], vh4[1], vh4[2])
                csvbuf = csvbuf row
            }
            if (complete) { printf "%s", buf; printf "%s", csvbuf >> csv; n++; done[k] = 1 }
            if (complete && k == "inf")
                printf "%s", (ck ? "through k2/k1 = " lo " and " hi ", checked at " ck ": the error adds |the fit at " ck " - its point|" \
                                 : "through k2/k1 = " lo " and " hi " only (no third level yet to check the form): the error adds the whole extrapolated step |rel(inf) - rel(" hi ")|") > cont
            csvbuf = ""
        }
    }' bench/results/theory_map.csv "$ext" "$k2f" >"$tmp"
continuum=$(cat "$cont" 2>/dev/null || echo "not extrapolated: the map lacks two complete k2/k1 levels")

levels=$(cut -d, -f1 "$csv" | sed 1d | sort -u | sort -g | tr '\n' ' ')
# How far the discrete model is converged: the largest relative change of g_eq, sigma_max and
# dgamma_eff over the convergence cases, per case label, against the runs they repeat.
conv() { # conv BASE_FILE BASE_LABEL CONV_FILE [NAME]: "label x %, ..." (nothing when absent;
    # NAME replaces the convergence rows' label)
    [ -f "$1" ] && [ -f "$3" ] || return 0
    awk -F, -v base="$2" -v name="${4:-}" '
        /^#/ || $1 == "label" || $4 != "discrete" { next }
        FILENAME == ARGV[1] { if ($1 == base) for (q = 10; q <= 16; q += 2) b[$2, $3 + 0, q] = $q; next }
        { if (name != "") $1 = name
          for (q = 10; q <= 16; q += 2) { if (q == 14 || !(($2, $3 + 0, q) in b)) continue
              d = ($q - b[$2, $3 + 0, q]) / b[$2, $3 + 0, q]; d = d < 0 ? -d : d
              if (!($1 in mx)) order[++n] = $1
              if (d > mx[$1]) mx[$1] = d; cases[$1, $2 "/" $3] = 1 } }
        END { for (i = 1; i <= n; i++) printf "%s%s %.1f %%", (i > 1 ? ", " : ""), order[i], 100 * mx[order[i]] }' "$1" "$3"
}
c8=$(conv "$res/theory_map.csv" map "$res/theory_map_convergence.csv")
c32=$(conv "$k2f" k2_32 "$res/theory_map_conv32.csv" "L8pi (n = 512)")
n32=$(conv "$k2f" k2_32 "$res/theory_map_k2_n512.csv" "n512 (D = 2.2, m0 0.01 to 0.2)")
[ -n "$n32" ] && c32="${c32:+$c32, }$n32"
# the grid of each level, from the runs themselves: "k2/k1 = K: L = 4π, n = N"
grids=$(awk -F, '$4 == "discrete" && $1 ~ /^k2_/ { k = substr($1, 4); if (!((k, $6) in seen)) { seen[k, $6] = 1; g[k] = g[k] (g[k] ? "/" : "") $6 } }
    END { for (k in g) print k, g[k] }' "$k2f" | sort -n |
    awk '{ printf "%s%s on n = %s (%s points per shortest wave)", (NR > 1 ? ", " : ""), $1, $2, $2 / (2 * $1) }')
convergence="largest change of g_eq, sigma_max, dgamma_eff over the convergence cases (D, m0 = 2.2, 0.1; 2.5, 0.2; 2.8, 0.5 at k2/k1 = 8"
convergence="$convergence against L = 8π, n = 256: ${c8:-not run}; at k2/k1 = 32 against L = 4π, n = 256: ${c32:-not yet run}"
convergence="$convergence; in L at every point: each row's L_bias, rel(8π) - rel(4π) at k2/k1 = 8 (n512: twice the points; R8: 8 realizations; L4pi, L8pi, L16pi: the square)"
rows=$(grep -c '^    {' "$tmp" || true)
{
    cat <<EOF
/* validity_table.c -- GENERATED by bench/validity_table.sh; do not edit. Regenerate with
 *   bench/validity_table.sh
 * from bench/results/theory_map.csv (the main map: k2/k1 = 8, L = 8π, n = 256), theory_map_ext.csv
 * (the same at m0 0.7 and 1) and theory_map_k2.csv (k2/k1 = 8, 16, 32 at L = 4π, n = 128, 256,
 * 256), every case with 4 realizations (bench/theory_map.sh,
 * bench/theory_map_k2.sh). k2/k1 levels present: $levels(inf: the continuum k2 = ∞ by
 * extrapolation in k2). Rows: $rows. What each column means: include/ljgap_validity.h.
 */
#include "ljgap_validity.h"

#include <math.h>
#include <stddef.h>

const ljgap_validity_row ljgap_validity_rows[] = {
EOF
    cat "$tmp"
    cat <<EOF
};
const size_t ljgap_validity_nrows = sizeof ljgap_validity_rows / sizeof ljgap_validity_rows[0];

const ljgap_validity_how_info ljgap_validity_how = {
    "BUILD=build bench/theory_map.sh; BUILD=build bench/theory_map_k2.sh; bench/validity_table.sh",
    "the discrete model of docs/model.md, k1 = 1: k2/k1 = 8 on L = 8π, n = 256 (4 points per "
    "shortest wave; the main map), and on L = 4π k2/k1 = ${grids:-none}, "
    "tied to the main map by the L bias at k2/k1 = 8; the theory by the PDE at tol 1e-6",
    4,
    "$convergence",
    "rel = a + b (k1/k2)^p, p = 2(3 - D), plus the L bias; $continuum; and the two points' errors propagated and the L bias's"};
EOF
} >"$out"
echo "wrote $out ($rows rows; k2/k1 levels: $levels) and $csv"
