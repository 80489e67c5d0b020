#!/usr/bin/env bash
# CSV over HTTP: traction, pdf, sweep and a finished simulation answer text/csv when the Accept
# header asks for it, and the CSV, read by Python's csv module (tests/csv/compare.py), carries
# the JSON answer's numbers (the SI errors too, and those equal to the dimensionless errors times
# the answer's scales); q-values and wildcards; 406 problems for an Accept nothing
# satisfies; CSV answers do not mix with cached JSON ones. One "ok"/"not ok" line per check.
#   BUILD=build tests/csv/run.sh
set -u
cd "$(dirname "$0")/../.."
PY=${PY:-python3}
. tests/lib/daemon.sh # tmp, pids, cleanup; check, start, req, hdr, json

if ! start csv --compute-slots 2; then
    echo "not ok - ljgapd did not start: $(head -c 300 "$tmp/csv.err")"
    exit 1
fi
post() { # post ENDPOINT BODY [CURL ARGS...]
    local e=$1 b=$2
    shift 2
    req POST "/v1/$e" -H 'Content-Type: application/json' --data-binary "$b" "$@"
}
csv_type() { [[ "$(hdr Content-Type)" == text/csv* ]]; }
json_type() { [ "$(hdr Content-Type)" = application/json ]; }

PSD='"psd":{"kind":"power","D":2.5,"k1":1,"m0":0.5}'
MAT='"material":{"E_star":1e9,"dgamma":0.05,"epsilon":3e-10}'
declare -A body=(
    [traction]="{$PSD,\"g_ave\":{\"min\":1.5,\"max\":5,\"n\":12},$MAT}"
    [pdf]="{$PSD,\"g_ave\":0.98,\"k2\":[5,null],\"grid\":{\"min\":0.6,\"max\":1.6,\"n\":21},$MAT}"
    [sweep]="{$PSD,\"vary\":\"D\",\"values\":[2.3,2.5,2.7],$MAT}"
)
# with the measurement's uncertainty (issue 29): input_error columns and # lines
PSDE='"psd":{"kind":"power","D":2.5,"k1":1,"m0":0.5,"D_err":0.02,"m0_err":0.02}'
body[traction-ie]="{$PSDE,\"g_ave\":{\"min\":1.5,\"max\":5,\"n\":12},$MAT}"
body[pdf-ie]="{$PSDE,\"g_ave\":0.98,\"k2\":[5,null],\"grid\":{\"min\":0.6,\"max\":1.6,\"n\":21},$MAT}"
body[sweep-ie]="{$PSDE,\"vary\":\"k2\",\"values\":[5,50],$MAT}"
for e in traction pdf sweep traction-ie pdf-ie sweep-ie; do
    post "${e%-ie}" "${body[$e]}"
    cp "$tmp/body" "$tmp/$e.json"
    post "${e%-ie}" "${body[$e]}" -H 'Accept: text/csv'
    cp "$tmp/body" "$tmp/$e.csv"
    check "POST /v1/${e%-ie} ($e) with Accept: text/csv: 200 text/csv; charset=utf-8; header=present" \
        eval '[ "$STATUS" = 200 ] && [ "$(hdr Content-Type)" = "text/csv; charset=utf-8; header=present" ]'
    out=$("$PY" tests/csv/compare.py "${e%-ie}" "$tmp/$e.json" "$tmp/$e.csv" 2>&1)
    rc=$?
    check "$e: the CSV parses and equals the JSON numbers ($(echo "$out" | tail -n 1))" \
        eval '[ "$rc" = 0 ]'
done
check "traction CSV: units in the header, an error column beside the values, SI columns" \
    grep -qx 'g_ave \[eps\],sigma \[sigma0\],sigma_err \[sigma0\],g_ave_m \[m\],sigma_Pa \[Pa\],sigma_Pa_err \[Pa\]' \
    "$tmp/traction.csv"
check "traction CSV: the summary and meta as # lines" eval 'grep -q "^# summary.g_eq \[eps\] = .* ± " \
    "$tmp/traction.csv" && grep -q "^# meta.method = pde$" "$tmp/traction.csv"'
check "pdf CSV: k2 = null is inf" grep -q '^1,inf,' "$tmp/pdf.csv"
check "traction CSV: the SI summary with its errors (si.error.summary)" \
    grep -q '^# si.summary.sigma_max_Pa \[Pa\] = .* ± ' "$tmp/traction.csv"
check "pdf CSV: each PDF's sigma_Pa with its error, and its phi_l1 (si.error.pdfs)" eval 'grep -q \
    "^# si.pdfs\[1\].sigma_Pa \[Pa\] = .* ± " "$tmp/pdf.csv" &&
    grep -q "^# si.error.pdfs\[1\].phi_l1 = " "$tmp/pdf.csv"'
check "sweep CSV: an error column beside each SI value (si.results[i].error)" grep -q \
    ',g_eq_m \[m\],g_eq_m_err \[m\],sigma_max_Pa \[Pa\],sigma_max_Pa_err \[Pa\],g_at_max_m \[m\],g_at_max_m_err \[m\],dgamma_eff_J_m2 \[J/m^2\],dgamma_eff_J_m2_err \[J/m^2\],m0_m2 \[m^2\]$' \
    "$tmp/sweep.csv"

check "traction CSV with input_error: its columns beside the errors" \
    grep -qx 'g_ave \[eps\],sigma \[sigma0\],sigma_err \[sigma0\],sigma_input_err \[sigma0\],g_ave_m \[m\],sigma_Pa \[Pa\],sigma_Pa_err \[Pa\],sigma_Pa_input_err \[Pa\]' \
    "$tmp/traction-ie.csv"
check "traction CSV with input_error: the summary's as # lines, meta.input_error.method" eval 'grep -q \
    "^# input_error.summary.dgamma_eff \[dgamma\] = [0-9]" "$tmp/traction-ie.csv" &&
    grep -q "^# meta.input_error.method = linear$" "$tmp/traction-ie.csv"'
check "pdf CSV with input_error: each PDF's sigma" \
    grep -q "^# input_error.pdfs\[1\].sigma \[sigma0\] = [0-9]" "$tmp/pdf-ie.csv"
check "sweep CSV with input_error: NAME_input_err after NAME_err, values of k2 in 1/chi" grep -q \
    '^values \[1/chi\],g_eq \[eps\],g_eq_err \[eps\],g_eq_input_err \[eps\],sigma_max' "$tmp/sweep-ie.csv"

# ---- negotiation ----
TR="{$PSD,\"g_ave\":[2,3]}"
post traction "$TR" -H 'Accept: */*'
check "Accept: */* gives JSON" eval '[ "$STATUS" = 200 ] && json_type'
post traction "$TR" -H 'Accept: text/csv;q=0.5, application/json'
check "Accept: text/csv;q=0.5, application/json gives JSON (the higher q)" json_type
post traction "$TR" -H 'Accept: application/json;q=0.1, text/*'
check "Accept: application/json;q=0.1, text/* gives CSV" eval '[ "$STATUS" = 200 ] && csv_type'
post traction "$TR" -H 'Accept: text/csv, application/json'
check "Accept: text/csv, application/json gives CSV (a tie: the client's order)" csv_type
post traction "$TR" -H 'Accept: image/png'
check "Accept: image/png: 406 not-acceptable problem" eval '[ "$STATUS" = 406 ] &&
    [ "$(hdr Content-Type)" = application/problem+json ] &&
    json ".type == \"/problems/not-acceptable\" and .status == 406"'
post traction "$TR" -H 'Accept: text/csv;q=0'
check "Accept: text/csv;q=0 (refuses the only one asked for): 406" [ "$STATUS" = 406 ]
post adhesion "{$PSD}" -H 'Accept: text/csv'
check "adhesion has no CSV form: Accept: text/csv is 406" [ "$STATUS" = 406 ]
post adhesion "{$PSD}" -H 'Accept: text/csv, */*;q=0.1'
check "adhesion with Accept: text/csv, */*;q=0.1: JSON" eval '[ "$STATUS" = 200 ] && json_type'
post traction '{"psd":{"kind":"power","D":2.5,"k1":0.3,"m0":0.5},"g_ave":[2]}' -H 'Accept: text/csv'
check "a bad request asking for CSV: the 422 problem, as JSON" eval '[ "$STATUS" = 422 ] &&
    [ "$(hdr Content-Type)" = application/problem+json ]'

# ---- the answer cache keeps the forms apart ----
C="{$PSD,\"g_ave\":[2.25,3.5]}"
post traction "$C"
post traction "$C"
check "the same JSON request again: from the cache" json '.meta.cached == true'
post traction "$C" -H 'Accept: text/csv'
check "then with Accept: text/csv: CSV, not the cached JSON" \
    eval 'csv_type && grep -q "^# meta.cached = false$" "$tmp/body"'

# ---- a finished simulation's result ----
req POST /v1/simulations -H 'Content-Type: application/json' --data-binary \
    '{"psd":{"kind":"power","D":2.2,"k1":1,"k2":4,"m0":0.05},"n":16,"realizations":2,"g_ave":[2,3]}'
loc=$(hdr Location)
check "simulation submitted: 202 with a Location" eval '[ "$STATUS" = 202 ] && [ -n "$loc" ]'
got=""
for _ in $(seq 1 $((300 * SLOW))); do
    req GET "$loc" -H 'Accept: text/csv, application/json;q=0.5'
    if csv_type; then
        got=csv
        break
    fi
    json '.status == "queued" or .status == "running"' || break
    sleep 0.1
done
cp "$tmp/body" "$tmp/sim.csv"
check "polled with Accept: text/csv, application/json;q=0.5: JSON status while it runs, then CSV" \
    [ "$got" = csv ]
req GET "$loc"
jq .result "$tmp/body" >"$tmp/sim.json"
out=$("$PY" tests/csv/compare.py simulations "$tmp/sim.json" "$tmp/sim.csv" 2>&1)
check "simulation: the CSV equals the JSON result ($(echo "$out" | tail -n 1))" \
    eval '"$PY" tests/csv/compare.py simulations "$tmp/sim.json" "$tmp/sim.csv" >/dev/null'
req GET "$loc" -H 'Accept: application/xml'
check "GET a job with Accept: application/xml: 406" [ "$STATUS" = 406 ]

kill -TERM "$PID"
wait "$PID"
check "the daemon exits 0" [ $? = 0 ]
