#!/usr/bin/env bash
# The command line build/ljgap against its contract (docs/api.md): exit status (0 for a 2xx answer,
# 1 for a problem, 2 for usage or read errors), one line of JSON on stdout, the same answer
# from a file as from stdin. Prints one "ok ..." or "not ok ..." line per check.
set -u
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
LJGAP=$BUILD/ljgap
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

n=0
check() { # check DESCRIPTION COMMAND...: ok when the command succeeds
    local what=$1
    shift
    n=$((n + 1))
    if "$@"; then echo "ok $n - cli: $what"; else echo "not ok $n - cli: $what"; fi
}

# run NAME ARGS...: runs the CLI with stdin from $tmp/in, keeps stdout and the exit status
run() {
    "$LJGAP" "$@" <"$tmp/in" >"$tmp/out" 2>"$tmp/err"
    echo $? >"$tmp/rc"
}
rc_is() { [ "$(cat "$tmp/rc")" = "$1" ]; }
jq_true() { jq -e "$1" "$tmp/out" >/dev/null 2>&1; }
one_line() { [ "$(wc -l <"$tmp/out")" = 1 ]; }

if [ ! -x "$LJGAP" ]; then
    echo "not ok 1 - cli: $LJGAP is not built"
    exit 1
fi

psd='{"kind":"power","D":2.5,"k1":1,"k2":4,"m0":0.01}'

: >"$tmp/in"
run --version
check "--version exits 0" rc_is 0
check "--version prints the version" grep -q '^ljgap [0-9]' "$tmp/out"
run --help
check "--help exits 0" rc_is 0
check "--help prints usage" grep -q 'usage: ljgap \[--csv\] NAME' "$tmp/out"
run
check "no endpoint is a usage error (2)" rc_is 2
run adhesion "$tmp/no-such-file"
check "unreadable file exits 2" rc_is 2

echo "{\"psd\":$psd,\"tol\":1e-4}" >"$tmp/in"
run adhesion
check "adhesion from stdin exits 0" rc_is 0
check "adhesion answer is one line" one_line
check "adhesion has the summary fields" jq_true \
    '[.g_eq,.sigma_max,.g_at_max,.dgamma_eff,.m0,.k0] | all(type == "number")'
check "adhesion has error estimates" jq_true '.error | [.g_eq,.sigma_max,.g_at_max,.dgamma_eff] | all(. >= 0)'
check "adhesion meta" jq_true '.meta.method == "pde" and (.meta.version | type == "string")
    and (.meta.elapsed_ms >= 0) and (.meta.warnings | type == "array") and .meta.cached == false'
check "small roughness: sigma_max near 1" jq_true '.sigma_max > 0.9 and .sigma_max <= 1.000001'
cp "$tmp/out" "$tmp/stdin.json"
cp "$tmp/in" "$tmp/req.json"
: >"$tmp/in"
run adhesion "$tmp/req.json"
check "adhesion from FILE exits 0" rc_is 0
same_answer() {
    jq -e --slurpfile a "$tmp/stdin.json" \
        'del(.meta.elapsed_ms) == ($a[0] | del(.meta.elapsed_ms))' "$tmp/out" >/dev/null
}
check "FILE and stdin give the same answer" same_answer

echo "{\"psd\":$psd,\"g_ave\":{\"min\":1,\"max\":3,\"n\":5},\"tol\":1e-4}" >"$tmp/in"
run traction
check "traction exits 0" rc_is 0
check "traction has n points and errors" jq_true \
    '(.g_ave | length) == 5 and (.sigma | length) == 5 and (.error.sigma | length) == 5'
check "traction summary" jq_true '.summary.g_eq > 0 and .error.summary.g_eq >= 0'

echo '{"psd":{"kind":"power","D":2.5,"k1":0.3,"m0":0.5},"tol":1,"bogus":1}' >"$tmp/in"
run adhesion
check "validation problem exits 1" rc_is 1
check "validation problem is one line" one_line
check "validation problem lists every bad field" jq_true \
    '.status == 422 and ([.errors[].pointer] | sort) == ["/bogus","/psd/k1","/tol"]'
check "problem has type, title, detail" jq_true \
    '(.type | endswith("/validation")) and (.title | length > 0) and (.detail | length > 0)'

echo '{"psd":' >"$tmp/in"
run adhesion
check "malformed JSON exits 1" rc_is 1
check "malformed JSON is a 400 problem" jq_true '.status == 400 and .errors == []'

echo '{}' >"$tmp/in"
run nosuch
check "unknown endpoint exits 1" rc_is 1
check "unknown endpoint is a 404 problem" jq_true '.status == 404'

echo "{\"psd\":$psd,\"vary\":\"m0\",\"values\":[0.01,0.02],\"tol\":1e-4}" >"$tmp/in"
run sweep
check "sweep exits 0" rc_is 0
check "sweep answers one result per value" jq_true \
    '.vary == "m0" and (.results | length) == 2 and (.results[1].m0 == 0.02)
     and (.results[0].error.g_eq >= 0)'

mat='"material":{"E1":2e9,"nu1":0.5,"E2":2e9,"nu2":0.5,"dgamma":0.05,"epsilon":3e-10}'
echo "{\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"m0\":0.5},$mat,\"R\":1e-6,\"tol\":1e-4}" >"$tmp/in"
run contact
check "contact exits 0" rc_is 0
check "contact answers pull-off forces, Tabor, lambda, regime" jq_true \
    '(.pull_off_N | [.jkr_smooth,.jkr,.dmt,.maugis_dugdale] | all(type == "number" and . > 0))
     and .pull_off_N.jkr <= .pull_off_N.maugis_dugdale
     and .pull_off_N.maugis_dugdale <= .pull_off_N.dmt
     and (.tabor.smooth > 0) and (.tabor.effective > 0) and (.maugis_lambda > 0)
     and (.regime | IN("jkr","transition","dmt")) and (.error.pull_off_N.maugis_dugdale >= 0)'
check "contact answers si scales" jq_true \
    '.si.chi_m > 0 and .si.sigma0_Pa > 0 and (.si.g_eq_m - .g_eq * 3e-10 | fabs) < 1e-20
     and (.si.dgamma_eff_J_m2 - .dgamma_eff * 0.05 | fabs) < 1e-15'

echo "{\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"m0\":0.5},\"R\":1e-6}" >"$tmp/in"
run contact
check "contact without material is a 422 at /material" jq_true \
    '.status == 422 and [.errors[].pointer] == ["/material"]'

echo "{\"psd\":$psd,\"units\":\"SI\"}" >"$tmp/in"
run adhesion
check "SI units without material is a 422 at /units" jq_true \
    '.status == 422 and [.errors[].pointer] == ["/units"]'

echo "{\"psd\":$psd,\"material\":{\"E_star\":1e9,\"dgamma\":-1,\"epsilon\":3e-10}}" >"$tmp/in"
run adhesion
check "negative dgamma is a 422 at /material/dgamma" jq_true \
    '.status == 422 and [.errors[].pointer] == ["/material/dgamma"]'

# ---- psd: a height matrix as text (the options are the query) or a JSON topography ----
awk 'BEGIN { for (j = 0; j < 32; j++) { for (i = 0; i < 32; i++)
    printf "%s%.17g", i ? " " : "", 1e-9 * (sin(0.37 * i + 0.11 * j * j) + 0.3 * cos(1.7 * i * j));
    printf "\n" } }' >"$tmp/map.txt"
awk 'BEGIN { printf "{\"topography\":{\"dx\":1e-8,\"heights\":[" }
    { printf "%s[", (NR > 1 ? "," : ""); for (i = 1; i <= NF; i++) printf "%s%s", (i > 1 ? "," : ""), $i;
      printf "]" } END { printf "]}}" }' "$tmp/map.txt" >"$tmp/map.json"
cp "$tmp/map.txt" "$tmp/in"
run psd --dx 1e-8
check "psd --dx from stdin exits 0 with one line" eval 'rc_is 0 && one_line'
check "psd: bins, errors, fit, a psd table for adhesion" jq_true \
    '(.k | length) > 5 and (.P | length) == (.k | length) and (.error.P | length) == (.k | length)
     and .h_rms > 0 and .error.h_rms > 0 and (.fit == null or .error.fit.D > 0)
     and .psd.kind == "table" and .meta.method == "periodogram" and .grid.window == "hann"'
cp "$tmp/out" "$tmp/psd-text.json"
: >"$tmp/in"
run psd "$tmp/map.json"
check "psd: the JSON topography gives the same answer as the text" eval \
    'jq -e --slurpfile a "$tmp/psd-text.json" "del(.meta) == (\$a[0] | del(.meta))" "$tmp/out" >/dev/null'
run psd --dx=1e-8 "$tmp/map.txt" --periodic
check "psd: FILE after options, --periodic, --dx=V" jq_true \
    '.grid.periodic == true and .grid.window == "none" and .grid.dx == 1e-8'
run psd --dx 1e-8 --E_star 1e11 --dgamma 0.05 --epsilon 3e-10 "$tmp/map.txt"
check "psd: a material in the options gives the domain" jq_true \
    '.domain.k0 > 0 and (.domain.inside | IN("all","part","none")) and .si.chi_m > 0'
printf '1 2 3\n4 five 6\n' >"$tmp/in"
run psd --dx 1e-8 --bogus 1
check "psd: bad text is exit 1, 422 with line and column, unknown option at its pointer" eval \
    'rc_is 1 && jq_true ".status == 422 and any(.errors[]; .pointer == \"/topography/heights/1/1\"
     and (.detail | startswith(\"line 2, column 3\"))) and any(.errors[]; .pointer == \"/bogus\")"'
run psd --dx
check "psd: an option without its value is a usage error (2)" rc_is 2
run adhesion --dx 1e-8
check "options for an endpoint without a text form are a usage error (2)" rc_is 2
run psd --dx 1e-8 "$tmp/no-such-file"
check "psd: an unreadable file exits 2" rc_is 2

# ---- combine: several PSDs as one (POST /v1/psd/combine) ----
# a second map of the same law at half the pixel (its band reaches twice as far)
awk 'BEGIN { for (j = 0; j < 64; j++) { for (i = 0; i < 64; i++)
    printf "%s%.17g", i ? " " : "", 1e-9 * (sin(0.21 * i + 0.05 * j * j) + 0.3 * cos(0.9 * i * j));
    printf "\n" } }' >"$tmp/map2.txt"
"$LJGAP" psd --dx 5e-9 "$tmp/map2.txt" >"$tmp/psd2.json"
: >"$tmp/in"
run combine "$tmp/psd-text.json" "$tmp/psd2.json"
check "combine of two /v1/psd answers exits 0 with one line" eval 'rc_is 0 && one_line'
check "combine: k, P, errors, two sources, a psd table with P_err" jq_true \
    '(.k | length) > 5 and (.P | length) == (.k | length) and (.error.P | length) == (.k | length)
     and (.sources | length) == 2 and (.psd.P_err | length) == (.k | length)
     and .meta.method == "inverse-variance"'
jq -c '{k: .k, P: .P, P_err: .error.P}' "$tmp/psd2.json" >"$tmp/obj2.json"
run combine --points-per-decade 5 "$tmp/psd-text.json" "$tmp/obj2.json"
check "combine: a psd object and an answer, --points-per-decade" jq_true \
    '.k | length > 2 and (.[1] / .[0] - 1.5849 | fabs) < 1e-3'
run combine --request "$tmp/psd-text.json" "$tmp/obj2.json"
check "combine --request prints the request" jq_true '(.psds | length) == 2 and (.psds[1].P_err | length) > 2'
run combine --request "$tmp/psd-text.json" "$tmp/psd2.json"
jq -c .psd "$tmp/psd2.json" >"$tmp/psd2-obj.json"
check "combine --request: each answer's psd object as it is (its first knot below its first bin)" \
    eval 'jq -e --slurpfile p "$tmp/psd2-obj.json" --slurpfile a "$tmp/psd2.json" \
        ".psds[1] == \$p[0] and .psds[1].k[0] < ([\$a[0].k[] | select(. >= \$a[0].reliable.k_min)][0])" "$tmp/out" >/dev/null'
jq -c '.psd = null' "$tmp/psd2.json" >"$tmp/null2.json"
run combine "$tmp/psd-text.json" "$tmp/null2.json"
check "combine: an answer whose psd is null exits 2 and says so" eval 'rc_is 2 &&
    grep -q "document 2: its \"psd\" is null" "$tmp/err"'
jq -c 'del(.psd.P_err)' "$tmp/psd2.json" >"$tmp/noerr2.json"
run combine "$tmp/psd-text.json" "$tmp/noerr2.json"
check "combine: an answer whose psd object has no P_err exits 2 and says so" eval 'rc_is 2 &&
    grep -q "has no P_err" "$tmp/err"'
jq -c '.P_err[1] = -1' "$tmp/obj2.json" >"$tmp/bad2.json"
run combine "$tmp/psd-text.json" "$tmp/bad2.json"
check "combine: a negative P_err is exit 1, 422 at /psds/1/P_err/1" eval 'rc_is 1 &&
    jq_true ".status == 422 and [.errors[].pointer] == [\"/psds/1/P_err/1\"]"'
run combine "$tmp/psd-text.json"
check "combine of one file is a usage error (2)" rc_is 2
echo '{"a":1}' >"$tmp/junk.json"
run combine "$tmp/psd-text.json" "$tmp/junk.json"
check "combine: a file that is no PSD exits 2" rc_is 2

# ---- simulations: one numerical-model job in the foreground ----
sim='"psd":{"kind":"power","D":2.2,"k1":1,"k2":8,"m0":0.1},"n":32,"realizations":2'
echo "{$sim,\"g_ave\":[2,3]}" >"$tmp/in"
cp "$tmp/in" "$tmp/sim.json"
run simulations
check "simulations exits 0 with one line" eval 'rc_is 0 && one_line'
check "simulations prints the result: sigma, error.sigma, m0_realized, meta" jq_true \
    '(.sigma | length) == 2 and (.error.sigma | all(. >= 0)) and (.m0_realized | length) == 2
     and .g_ave == [2,3] and .meta.method == "numerical" and .elapsed_ms >= 0'
check "simulations: no progress bar when stderr is not a terminal" eval '[ ! -s "$tmp/err" ]'
script -qec "$LJGAP simulations $tmp/sim.json >$tmp/tty.out" /dev/null >"$tmp/tty" 2>&1
check "simulations: a progress bar up to 100% when stderr is a terminal" \
    eval 'grep -q "100%" "$tmp/tty" && jq -e ".sigma | length == 2" "$tmp/tty.out" >/dev/null'
echo '{"psd":{"kind":"power","D":2.2,"k1":1,"k2":8,"m0":0.1},"n":16,"realizations":2,
    "k_split":3,"g_ave":[1.5,3]}' >"$tmp/in"
run simulations
check "simulations with k_split (the hybrid): k_split and the fine band's law in the result" \
    eval 'rc_is 0 && jq_true ".k_split == 3 and (.sigma | length) == 2 and .fine.m0 > 0 and
    .fine.dgamma_eff < 1 and .fine.error.dgamma_eff >= 0"'
echo "{$sim,\"n\":33,\"g_ave\":[2]}" >"$tmp/in"
run simulations
check "simulations: odd n is a 422 at /n, exit 1" eval 'rc_is 1 &&
    jq_true ".status == 422 and [.errors[].pointer] == [\"/n\"]"'
echo "{\"psd\":{\"kind\":\"power\",\"D\":2.2,\"k1\":1,\"k2\":8,\"m0\":0.1},\"n\":256,
    \"realizations\":16,\"g_ave\":{\"min\":1.2,\"max\":4,\"n\":150}}" >"$tmp/long.json"
"$LJGAP" simulations "$tmp/long.json" >"$tmp/out" 2>/dev/null &
pid=$!
sleep 0.5
kill -INT "$pid"
wait "$pid"
echo $? >"$tmp/rc"
check "simulations: SIGINT cancels the run: exit 1, a 503 problem" eval 'rc_is 1 &&
    jq_true ".status == 503 and (.type | endswith(\"/unavailable\"))"'
