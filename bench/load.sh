#!/usr/bin/env bash
# Bounded load tests of $BUILD/ljgapd on loopback, three runs, each against a fresh daemon:
#   mixed        wrk (bench/load.lua: good requests, most missing the cache, and bad ones of
#                every kind, in a cycle) for LOAD_SECONDS (20) on LOAD_CONNECTIONS (16)
#                connections, default daemon settings
#   connections  the same mix on 1000 connections (wrk -c1000) for LOAD_SECONDS / 2, daemon
#                with --client-connections 1000 (one host stands in for many clients)
#   lab          bench/lab_clients.py for LOAD_SECONDS: three clients from 127.0.0.2-4 (a batch
#                of slow requests on 5 connections, one interactive user, one mixed), default
#                settings; per-client latency p50/p99 and statuses
# Writes bench/results/load.txt: per run requests/s, latency percentiles, the answers by
# status, the daemon's threads and resident memory (RSS) before, during (max) and after, and a
# verdict line:
#   verdict ok       no 5xx other than 503 in any run, the daemon still answers /healthz and
#                    exits 0 on SIGTERM, and RSS grew by less than the answer cache's byte
#                    bound + 32 MiB
# Exit status 1 when the verdict is not ok. Needs wrk and python3 (make deps).
#   BUILD=build bench/load.sh
set -u
cd "$(dirname "$0")/.."
SECS=${LOAD_SECONDS:-20}
CONNS=${LOAD_CONNECTIONS:-16}
CACHE_MIB=64 # ljgapd's default --cache-bytes bound, in MiB
out=bench/results/load.txt
mkdir -p bench/results
WRAP=
. tests/lib/daemon.sh # start; the scratch directory $tmp
command -v wrk >/dev/null || { echo "load.sh: wrk is not installed (make deps)" >&2; exit 1; }
[ -x "$BIN" ] || { echo "load.sh: $BIN is not built" >&2; exit 1; }

rss() { awk '/^VmRSS/ { print $2 }' "/proc/$PID/status" 2>/dev/null || echo 0; } # KiB
threads() { awk '/^Threads/ { print $2 }' "/proc/$PID/status" 2>/dev/null || echo 0; }
verdict=ok

# run NAME DAEMON-ARGS -- LOAD-COMMAND...: one load against a fresh daemon; figures to stdout
run() {
    local name=$1
    shift
    local args=()
    while [ "$1" != -- ]; do
        args+=("$1")
        shift
    done
    shift
    start "load-$name" "${args[@]}" || { verdict="not ok: ljgapd did not start ($name)"; return; }
    # warm up: one request of each kind, so "before" includes the libraries' first allocations
    wrk -t1 -c1 -d1s -s bench/load.lua "$URL" >/dev/null 2>&1
    local rss0 thr0 rss1 rssmax thrmax health rc growth bad5xx sampler
    rss0=$(rss)
    thr0=$(threads)
    (while kill -0 "$PID" 2>/dev/null; do echo "$(rss) $(threads)"; sleep 0.5; done) \
        >"$tmp/samples" &
    sampler=$!
    "$@" "$URL" >"$tmp/load" 2>&1
    sleep 1
    rss1=$(rss)
    kill "$sampler" 2>/dev/null
    wait "$sampler" 2>/dev/null
    health=$(curl -s --max-time 5 -o /dev/null -w '%{http_code}' "$URL/healthz")
    kill -TERM "$PID"
    wait "$PID"
    rc=$?
    rssmax=$(awk '{ print $1 }' "$tmp/samples" | sort -n | tail -n 1)
    thrmax=$(awk '{ print $2 }' "$tmp/samples" | sort -n | tail -n 1)
    bad5xx=$(awk '$1 == "status" && $2 >= 500 && $2 != 503 { s += $3 } END { print s + 0 }' \
        "$tmp/load")
    bad5xx=$((bad5xx + $(grep -o ' 5[0-9][0-9]:[0-9]*' "$tmp/load" | grep -v ' 503:' |
        cut -d: -f2 | awk '{ s += $1 } END { print s + 0 }')))
    growth=$(((rss1 - rss0) / 1024))
    [ "$bad5xx" = 0 ] || verdict="not ok: $bad5xx answers 5xx other than 503 ($name)"
    [ "$health" = 200 ] || verdict="not ok: /healthz answered $health after the load ($name)"
    [ "$rc" = 0 ] || verdict="not ok: exit status $rc on SIGTERM ($name)"
    [ "$growth" -lt $((CACHE_MIB + 32)) ] || verdict="not ok: RSS grew by $growth MiB ($name)"
    echo "## $name: ljgapd ${args[*]}; load: ${*##*/}"
    grep -E '^(status|requests|seconds|latency|socket_errors|client)' "$tmp/load"
    grep -q -E '^(requests|client) ' "$tmp/load" ||
        verdict="not ok: the load failed ($name): $(head -c 300 "$tmp/load")"
    echo "threads_before $thr0"
    echo "threads_max ${thrmax:-0}"
    echo "rss_before_kib $rss0"
    echo "rss_max_kib ${rssmax:-0}"
    echo "rss_after_kib $rss1"
    echo "rss_growth_mib $growth (bound: cache ${CACHE_MIB} MiB + 32)"
    echo "healthz_after $health"
    echo "exit_status_on_sigterm $rc"
}

{
    echo "# ljgapd load tests, $(date -u +%Y-%m-%d), $(nproc) cores, loopback"
    run mixed -- wrk -t2 -c"$CONNS" -d"${SECS}s" --timeout 30s -s bench/load.lua
    run connections --client-connections 1000 -- \
        wrk -t2 -c1000 -d"$((SECS / 2))s" --timeout 30s -s bench/load.lua
    run lab -- python3 bench/lab_clients.py "$((SECS))"
    echo "verdict $verdict"
} >"$tmp/report"
cat "$tmp/report" | tee "$out"
[ "$verdict" = ok ]
