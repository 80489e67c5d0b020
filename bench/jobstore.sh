#!/usr/bin/env bash
# How long the simulation job routes keep a request, and the job store's calls under them
# (SQLite in a temporary --state-dir). Writes bench/results/jobstore.txt:
#   - build/bench/jobstore: median and p99 of each store call (create, get + status JSON,
#     cancel, claim, renew, finish) over 400 calls;
#   - over HTTP on loopback (curl's time_total, so with the connection): the median and p99 of
#     200 POST /v1/simulations (validate, commit, status) while the one worker runs them, and of
#     200 GET /v1/simulations/ID of a finished job and of a running one, and of 200 GET /healthz
#     (no store: the HTTP and curl part of those figures).
#   BUILD=build bench/jobstore.sh
set -u
cd "$(dirname "$0")/.."
out=bench/results/jobstore.txt
mkdir -p bench/results
WRAP=
. tests/lib/daemon.sh # start, req; the scratch directory $tmp
[ -x "$BIN" ] && [ -x "$BUILD/bench/jobstore" ] || { echo "jobstore.sh: not built" >&2; exit 1; }

PSD='"psd":{"kind":"power","D":2.2,"k1":1,"k2":8,"m0":0.1}'
SMALL="{$PSD,\"n\":32,\"realizations\":2,\"seed\":7,\"g_ave\":[2,3,4]}"
LONG="{$PSD,\"n\":256,\"realizations\":16,\"g_ave\":{\"min\":1.2,\"max\":4,\"n\":150}}"
# stats FILE: median and p99 of the seconds in FILE, in ms
stats() {
    sort -g "$1" | awk '{ v[NR] = $1 } END {
        m = NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
        printf "median %.3f ms  p99 %.3f ms  (%d requests)\n", 1e3 * m, 1e3 * v[int(NR * 0.99)], NR }'
}
timed() { # timed FILE CURL-ARGS...: one request, its time_total appended to FILE
    local f=$1
    shift
    curl -s -o "$tmp/body" -w '%{time_total}\n' "$@" >>"$f"
}
{
    echo "# job routes and job store, $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m)"
    "$BUILD/bench/jobstore" 400
    start bench --job-workers 1 --job-queue 1000 || { echo "ljgapd did not start" >&2; exit 1; }
    for _ in $(seq 200); do
        timed "$tmp/post" -H 'Content-Type: application/json' --data-binary "$SMALL" \
            "$URL/v1/simulations"
    done
    id=$(jq -r .id "$tmp/body")
    for _ in $(seq 100); do # until the last small job is done
        req GET "/v1/simulations/$id"
        json '.status == "done"' && break
        sleep 0.1
    done
    for _ in $(seq 200); do timed "$tmp/get_done" "$URL/v1/simulations/$id"; done
    req POST /v1/simulations -H 'Content-Type: application/json' --data-binary "$LONG"
    long=$(jq -r .id "$tmp/body")
    sleep 1
    for _ in $(seq 200); do timed "$tmp/get_running" "$URL/v1/simulations/$long"; done
    req DELETE "/v1/simulations/$long"
    for _ in $(seq 200); do timed "$tmp/healthz" "$URL/healthz"; done
    printf '%-34s %s\n' "HTTP POST /v1/simulations" "$(stats "$tmp/post")"
    printf '%-34s %s\n' "HTTP GET, a finished job" "$(stats "$tmp/get_done")"
    printf '%-34s %s\n' "HTTP GET, a running job" "$(stats "$tmp/get_running")"
    printf '%-34s %s\n' "HTTP GET /healthz (no store)" "$(stats "$tmp/healthz")"
    kill -TERM "$PID"
    wait "$PID"
} | tee "$out"
