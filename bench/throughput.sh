#!/usr/bin/env bash
# Answers per second of distinct (uncached) Fig. 4 adhesion requests through ljgapd, against
# the time of one request alone: wrk on 1 connection (one request at a time: its rate is
# 1 / single-request time) and on 2 connections per core (the compute slots full, the wait
# queue in use), THROUGHPUT_ROUNDS (5) alternating rounds of THROUGHPUT_SECONDS (4) each.
# Prints the medians, the efficiency rate / (cores / single-request time) and the answers that
# were not 200 or never came (wrk's socket errors; none are expected: the wait queue takes the
# excess). wrk runs on the same cores as the daemon, so the efficiency includes the load
# generator's share.
# Writes bench/results/throughput.txt.
#   BUILD=build bench/throughput.sh
set -u
cd "$(dirname "$0")/.."
SECS=${THROUGHPUT_SECONDS:-4}
ROUNDS=${THROUGHPUT_ROUNDS:-5}
CORES=$(nproc)
out=bench/results/throughput.txt
WRAP=
. tests/lib/daemon.sh # start; the scratch directory $tmp
command -v wrk >/dev/null || { echo "throughput.sh: wrk is not installed (make deps)" >&2; exit 1; }
cat >"$tmp/distinct.lua" <<'LUA'
-- every request distinct (C varies in its 12th digit): no cache hits; the answers stay Fig. 4's
local n = 0
local json = { ["Content-Type"] = "application/json" }
function init(args) n = math.random(1, 1e9) end
function request()
    n = n + 1
    return wrk.format("POST", "/v1/adhesion", json, string.format(
        '{"psd":{"kind":"power","D":2.5,"k1":1,"C":%.15g}}', 0.0795774715459477 * (1 + n * 1e-12)))
end
function done(summary, latency, requests)
    local e = summary.errors
    io.write(string.format("rps %.1f p50_ms %.2f p99_ms %.2f not_200 %d socket_errors %d\n",
        summary.requests / (summary.duration / 1e6), latency:percentile(50) / 1e3,
        latency:percentile(99) / 1e3, e.status, e.connect + e.read + e.write + e.timeout))
end
LUA
start tp || { echo "throughput.sh: ljgapd did not start" >&2; exit 1; }
wrk -t1 -c1 -d1s -s "$tmp/distinct.lua" "$URL" >/dev/null 2>&1 # warm up
for r in $(seq 1 "$ROUNDS"); do
    wrk -t1 -c1 -d"${SECS}s" -s "$tmp/distinct.lua" "$URL" | tail -n 1 | sed 's/^/one /' >>"$tmp/res"
    wrk -t2 -c$((2 * CORES)) -d"${SECS}s" -s "$tmp/distinct.lua" "$URL" | tail -n 1 |
        sed 's/^/full /' >>"$tmp/res"
done
kill -TERM "$PID"
wait "$PID"
med() { sort -n | awk '{ a[NR] = $1 } END { print a[int((NR + 1) / 2)] }'; }
one=$(awk '$1 == "one" { print $3 }' "$tmp/res" | med)
full=$(awk '$1 == "full" { print $3 }' "$tmp/res" | med)
# answers that were not 200, and requests that got no answer at all (refused, reset, timed out)
bad=$(awk '{ s += $9 + $11 } END { print s + 0 }' "$tmp/res")
{
    echo "# ljgapd throughput, $(date -u +%Y-%m-%d), $CORES cores, loopback, distinct Fig. 4" \
        "adhesion requests, $ROUNDS rounds of ${SECS} s, default daemon settings"
    cat "$tmp/res"
    awk -v o="$one" -v f="$full" -v c="$CORES" -v b="$bad" 'BEGIN {
        printf "median_single_request_ms %.3f\n", 1e3 / o
        printf "median_answers_per_s_at_%d_connections %.1f\n", 2 * c, f
        printf "efficiency %.2f (answers/s over cores / single-request time)\n", f / (c * o)
        printf "answers_not_200 %d (with the requests that got no answer)\n", b
        printf "ratio_to_before_issue_19 %.2f (273 answers/s, efficiency 0.88, thread per connection)\n", f / 273 }'
} | tee "$out"
