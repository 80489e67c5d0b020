# jobs.sh -- helpers for the shell suites that drive simulation jobs (sourced after daemon.sh).
# Checks that the suite's BIN and CLI are built (else one "not ok" and exit 1), and gives:
#   submit BODY        POST /v1/simulations; sets ID from the answer
#   wait_for ID JQ     poll GET /v1/simulations/ID until the jq condition holds (60 s x SLOW)
#   wait_state ID S... the same until its status is one of S
#   jq_ok ARGS...      jq -e quietly (so that a check's own ok line shows)

for b in "$BIN" "$CLI"; do
    if [ ! -x "$b" ]; then
        echo "not ok - ${CHECK_PREFIX:-}$b is not built"
        exit 1
    fi
done

submit() {
    req POST /v1/simulations -H 'Content-Type: application/json' --data-binary "$1"
    ID=$(jq -r '.id // empty' "$tmp/body" 2>/dev/null)
}
wait_for() {
    for _ in $(seq 1 $((600 * SLOW))); do
        req GET "/v1/simulations/$1"
        json "$2" && return 0
        sleep 0.1
    done
    return 1
}
wait_state() {
    local id=$1
    shift
    wait_for "$id" ".status as \$s | any($(printf '%s\n' "$@" | jq -R . | jq -cs .)[]; . == \$s)"
}
jq_ok() { jq -e "$@" >/dev/null 2>&1; }
