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
# to the daemon: the CLI reads text only when given options); an application/octet-stream case
# is an instrument file, which the CLI reads by content (its query as options).
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

# instrument files (issue 28): a GSF of 16 x 16 floats, 1 and 2 m alternating (Gwyddion Simple
# Field: header, NUL padding to a multiple of 4, little-endian floats), whole and broken
gsf16() { # gsf16 HEADER-LINES BYTES: the header, then the first BYTES bytes of the data
    local h="Gwyddion Simple Field 1.0
XRes = 16
YRes = 16
$1"
    printf '%s' "$h"
    head -c $((4 - ${#h} % 4)) /dev/zero
    for _ in $(seq 128); do printf '\x00\x00\x80\x3f\x00\x00\x00\x40'; done | head -c "$2"
}
OCT=application/octet-stream
gsf16 "XReal = 1.6e-7
YReal = 1.6e-7
" 1024 >"$tmp/gsf16"
gen psd-file-gsf-cut-short "psd 422 - $OCT" < <(gsf16 "XReal = 1.6e-7
" 1000)
gen psd-file-unknown-format "psd 415 - $OCT" < <(printf 'GIF89a\x10\x00\x10\x00\x80\x00\x00')
gen psd-file-format-no-such "psd?format=pdf 422 /format $OCT" <"$tmp/gsf16"
gen psd-file-channel-no-such "psd?channel=Phase 422 /channel $OCT" <"$tmp/gsf16"
gen psd-file-channel-index-out "psd?channel=3 422 /channel $OCT" <"$tmp/gsf16"
gen psd-file-dx-beside-size "psd?dx=1e-9 422 /topography/dx $OCT" <"$tmp/gsf16"
gen psd-file-no-size-no-dx "psd 422 /topography/dx $OCT" < <(gsf16 "" 1024)
gen psd-file-unknown-param "psd?bogus=1 422 /bogus $OCT" <"$tmp/gsf16"
gen psd-file-nanoscope-no-end "psd 422 - $OCT" < <(printf '\\*File list\r\n\\Version: 0x05120005\r\n')
gen psd-file-gwy-size-past-end "psd 422 - $OCT" < <(printf 'GWYP%s\x00\xff\xff\xff\x7f/0/data' GwyContainer)
gen psd-file-xyz-scattered "psd 422 - $OCT" < <(printf '0 0 1\n0.3 0.1 2\n0.7 0.35 1\n1 1 3\n')
gen psd-file-empty "psd 415 - $OCT" </dev/null

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
    application/octet-stream) # an instrument file: ljgap psd [--OPTION ...] FILE
        if [[ $ep == *\?* ]]; then
            IFS='&' read -ra kv <<<"${ep#*\?}"
            for a in "${kv[@]}"; do cli+=("--$a"); done
        fi
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
