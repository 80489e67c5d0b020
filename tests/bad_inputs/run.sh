#!/usr/bin/env bash
# The catalogue of bad requests: each must get its problem status, as application/problem+json
# with a matching "status" and, where the case names one, an errors[] entry at its JSON pointer,
# from the daemon ($BUILD/ljgapd over loopback) and, for what the handler decides (400, 404,
# 422), from the CLI ($BUILD/ljgap, exit status 1) too. One "ok"/"not ok" line per case.
#
# A case is tests/bad_inputs/cases/NAME.req: a first line
#   #> ENDPOINT STATUS POINTER [CONTENT-TYPE]
# (POINTER "-" for none to check, "" for the root; CONTENT-TYPE "none" sends no header, the
# default is application/json), then the body, byte for byte, up to the end of the file.
# ENDPOINT may carry a query (psd?dx=1e-8&periodic): a text/plain or text/csv case is a text
# upload, which the CLI gets as options (--dx=1e-8 --periodic=; a case without a query is left
# to the daemon: the CLI reads text only when given options).
# The big cases (deep nesting, giant arrays, over 1 MiB) are written here instead of committed.
#   BUILD=build/h-harden tests/bad_inputs/run.sh
#   WRAP="valgrind --error-exitcode=99 ..." tests/bad_inputs/run.sh   (daemon under a wrapper;
#                                                                      exit status checked)
set -u
cd "$(dirname "$0")/../.."
SLOW_WRAPPED=5 # the time bounds' multiplier under WRAP
. tests/lib/daemon.sh # start, req, hdr; the scratch directory $tmp

for b in "$BIN" "$CLI"; do
    if [ ! -x "$b" ]; then
        echo "not ok - $b is not built"
        exit 1
    fi
done

# ---- the generated cases ----
gen() { # gen NAME "HEADER" < body
    { printf '#> %s\n' "$2"; cat; } >"$tmp/gen/$1.req"
}
mkdir -p "$tmp/gen"
PSD='"psd":{"kind":"power","D":2.5,"k1":1,"k2":8,"C":0.0796}'
awk 'BEGIN { for (i = 0; i < 100000; i++) printf "["; }' | gen deep-nesting-100000 'adhesion 400 -'
awk -v p="$PSD" 'BEGIN { printf "{\"psd\":{\"kind\":\"power\",\"D\":"; for (i = 0; i < 500; i++)
    printf "["; for (i = 0; i < 500; i++) printf "]"; printf ",\"k1\":1,\"C\":0.1}}" }' |
    gen nesting-500-in-a-field 'adhesion 422 /psd/D'
awk -v p="$PSD" 'BEGIN { printf "{%s,\"g_ave\":[", p; for (i = 0; i < 20000; i++)
    printf "%s%d", i ? "," : "", 2 + i % 3; printf "]}" }' | gen giant-g_ave-array 'traction 422 /g_ave'
awk 'BEGIN { printf "{\"psd\":{\"kind\":\"table\",\"k\":["; for (i = 1; i <= 10001; i++)
    printf "%s%d", (i > 1 ? "," : ""), i; printf "],\"P\":["; for (i = 1; i <= 10001; i++)
    printf "%s%g", (i > 1 ? "," : ""), 1 / (i * i * i); printf "]}}" }' |
    gen giant-table 'adhesion 422 /psd/k'
awk -v p="$PSD" 'BEGIN { printf "{%s", p; for (i = 0; i < 300; i++) printf ",\"x%d\":%d", i, i;
    printf "}" }' | gen many-unknown-fields 'adhesion 422 /x0'
awk -v p="$PSD" 'BEGIN { printf "{%s,\"", p; for (i = 0; i < 200000; i++) printf "k";
    printf "\":1}" }' | gen long-field-name 'adhesion 422 -'
awk -v p="$PSD" 'BEGIN { printf "{%s,\"vary\":\"m0\",\"values\":[", p; for (i = 0; i < 50000; i++)
    printf "%s1e400", i ? "," : ""; printf "]}" }' | gen giant-values-overflowing 'sweep 422 /values'
{ head -c $((1024 * 1024)) /dev/zero | tr '\0' ' '; echo "{$PSD}"; } |
    gen over-1-MiB 'adhesion 413 -'
# a height matrix of 2900² values, over the 8 Mi cap of one map (too slow under a WRAP)
[ -z "$WRAP" ] && awk 'BEGIN { for (j = 0; j < 2900; j++) { for (i = 0; i < 2900; i++)
    printf "%s", (i ? " 1" : "1"); printf "\n" } }' |
    gen psd-text-over-the-points-cap 'psd?dx=1e-8 422 /topography/heights text/plain'

# ---- the daemon ----
if ! start d; then
    echo "not ok - ljgapd did not start: $(head -c 300 "$tmp/d.err")"
    exit 1
fi

# has_problem FILE STATUS POINTER: FILE is a problem with that status (and pointer)
has_problem() {
    jq -e --argjson s "$2" --arg p "$3" '.status == $s and (.type | type == "string")
        and (.title | type == "string") and (.detail | type == "string")
        and (.errors | type == "array")
        and ($p == "-" or any(.errors[]; .pointer == $p))' "$1" >/dev/null 2>&1
}

for f in tests/bad_inputs/cases/*.req "$tmp"/gen/*.req; do
    name=$(basename "$f" .req)
    read -r mark ep status ptr ctype < <(head -n 1 "$f")
    if [ "$mark" != "#>" ] || [ -z "${ptr:-}" ]; then
        echo "not ok - $name: no '#> ENDPOINT STATUS POINTER' line"
        continue
    fi
    [ "$ptr" = '""' ] && ptr=
    tail -n +2 "$f" >"$tmp/request"
    case ${ctype:-application/json} in
    none) hdr=(-H 'Content-Type:') ;;
    *) hdr=(-H "Content-Type: ${ctype:-application/json}") ;;
    esac
    req POST "/v1/$ep" "${hdr[@]}" --data-binary @"$tmp/request"
    type=$(hdr Content-Type)
    if [ "$STATUS" = "$status" ] && [ "$type" = application/problem+json ] &&
        has_problem "$tmp/body" "$status" "$ptr"; then
        echo "ok - bad input $name: HTTP $status${ptr:+ at $ptr}"
    else
        echo "not ok - bad input $name: HTTP $STATUS ($type), expected $status at '$ptr':" \
            "$(head -c 300 "$tmp/body")"
    fi
    case $status in 400 | 404 | 422) ;; *) continue ;; esac
    cli=("${ep%%\?*}")
    case ${ctype:-} in
    text/*)
        [[ $ep == *\?* ]] || continue
        IFS='&' read -ra kv <<<"${ep#*\?}"
        for a in "${kv[@]}"; do cli+=("--$a"); done
        ;;
    esac
    "$CLI" "${cli[@]}" "$tmp/request" >"$tmp/answer" 2>/dev/null
    rc=$?
    if [ "$rc" = 1 ] && has_problem "$tmp/answer" "$status" "$ptr"; then
        echo "ok - bad input $name: CLI $status${ptr:+ at $ptr}"
    else
        echo "not ok - bad input $name: CLI exit $rc, expected 1 with $status at '$ptr':" \
            "$(head -c 300 "$tmp/answer")"
    fi
done

req GET /healthz
req_ok=$STATUS
kill -TERM "$PID"
wait "$PID"
rc=$?
if [ "$req_ok" = 200 ] && [ "$rc" = 0 ]; then
    echo "ok - the daemon served /healthz after the catalogue and exited 0 on SIGTERM"
else
    echo "not ok - after the catalogue: /healthz $req_ok, exit status $rc:" \
        "$(grep -v "^[A-Z]* /" "$tmp/d.err" | tail -n 20)"
fi
