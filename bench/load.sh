#!/usr/bin/env bash
# Bounded load test of $BUILD/ljgapd on loopback: wrk (bench/load.lua: good requests, most
# of them missing the cache, and bad ones of every kind, in a cycle) for LOAD_SECONDS (20) with
# LOAD_CONNECTIONS (16) connections on 2 threads, against a daemon with its default compute
# slots. Writes bench/results/load.txt: requests/s, latency percentiles, the answers by status,
# the daemon's resident memory (RSS) before, during (max) and after, and a verdict line:
#   verdict ok       no 5xx other than 503, the daemon still answers /healthz and exits 0 on
#                    SIGTERM, and RSS grew by less than the answer cache's byte bound + 32 MiB
# Exit status 1 when the verdict is not ok. Needs wrk (Debian package wrk; make deps).
#   BUILD=build/h-harden bench/load.sh
set -u
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
BIN=$BUILD/ljgapd
SECS=${LOAD_SECONDS:-20}
CONNS=${LOAD_CONNECTIONS:-16}
CACHE_MIB=64 # ljgapd's default --cache-bytes bound, in MiB
out=bench/results/load.txt
mkdir -p bench/results
WRAP=
SLOW=1
. tests/lib/daemon.sh # start; the scratch directory $tmp
command -v wrk >/dev/null || { echo "load.sh: wrk is not installed (make deps)" >&2; exit 1; }
[ -x "$BIN" ] || { echo "load.sh: $BIN is not built" >&2; exit 1; }

start load || { echo "load.sh: ljgapd did not start" >&2; exit 1; }
rss() { awk '/^VmRSS/ { print $2 }' "/proc/$PID/status" 2>/dev/null || echo 0; } # KiB
# warm up: one request of each kind, so "before" includes the libraries' first allocations
wrk -t1 -c1 -d1s -s bench/load.lua "$URL" >/dev/null 2>&1
rss0=$(rss)
(while kill -0 "$PID" 2>/dev/null; do rss; sleep 0.5; done) >"$tmp/rss" &
sampler=$!
wrk -t2 -c"$CONNS" -d"${SECS}s" --timeout 30s -s bench/load.lua "$URL" >"$tmp/wrk" 2>&1
sleep 1
rss1=$(rss)
kill "$sampler" 2>/dev/null
wait "$sampler" 2>/dev/null
health=$(curl -s --max-time 5 -o /dev/null -w '%{http_code}' "$URL/healthz")
kill -TERM "$PID"
wait "$PID"
rc=$?
rssmax=$(sort -n "$tmp/rss" | tail -n 1)
bad5xx=$(awk '$1 == "status" && $2 >= 500 && $2 != 503 { s += $3 } END { print s + 0 }' "$tmp/wrk")
growth=$(((rss1 - rss0) / 1024))
verdict=ok
[ "$bad5xx" = 0 ] || verdict="not ok: $bad5xx answers 5xx other than 503"
[ "$health" = 200 ] || verdict="not ok: /healthz answered $health after the load"
[ "$rc" = 0 ] || verdict="not ok: exit status $rc on SIGTERM"
[ "$growth" -lt $((CACHE_MIB + 32)) ] || verdict="not ok: RSS grew by $growth MiB"
grep -q '^requests ' "$tmp/wrk" || verdict="not ok: wrk failed: $(head -c 300 "$tmp/wrk")"
{
    echo "# ljgapd load test, $(date -u +%Y-%m-%d), $(nproc) cores, loopback, wrk -t2 -c$CONNS" \
        "-d${SECS}s, bench/load.lua (12 kinds of request in a cycle, good and bad)"
    grep -E '^(status|requests|seconds|latency|socket_errors)' "$tmp/wrk"
    echo "rss_before_kib $rss0"
    echo "rss_max_kib ${rssmax:-0}"
    echo "rss_after_kib $rss1"
    echo "rss_growth_mib $growth (bound: cache ${CACHE_MIB} MiB + 32)"
    echo "healthz_after $health"
    echo "exit_status_on_sigterm $rc"
    echo "verdict $verdict"
} | tee "$out"
[ "$verdict" = ok ]
