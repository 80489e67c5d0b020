#!/usr/bin/env bash
# Does a pool of I/O threads pay? wrk on 1000 connections against requests that cost the
# daemon no computation (/healthz and a cached adhesion answer, alternately), with
# --io-threads 1 and 2, three alternating rounds of IO_SECONDS (5) each; prints the median
# requests/s and p99 of each setting and their ratio. Writes bench/results/iothreads.txt.
#   BUILD=build bench/iothreads.sh
set -u
cd "$(dirname "$0")/.."
SECS=${IO_SECONDS:-5}
out=bench/results/iothreads.txt
WRAP=
. tests/lib/daemon.sh # start; the scratch directory $tmp
command -v wrk >/dev/null || { echo "iothreads.sh: wrk is not installed (make deps)" >&2; exit 1; }
cat >"$tmp/io.lua" <<'LUA'
local i = 0
local body = '{"psd":{"kind":"power","D":2.5,"k1":1,"m0":0.5}}'
function request()
    i = i + 1
    if i % 2 == 0 then return wrk.format("GET", "/healthz") end
    return wrk.format("POST", "/v1/adhesion", { ["Content-Type"] = "application/json" }, body)
end
function done(summary, latency, requests)
    io.write(string.format("rps %.1f p99_ms %.2f errors %d\n",
        summary.requests / (summary.duration / 1e6), latency:percentile(99) / 1e3,
        summary.errors.status + summary.errors.connect + summary.errors.read))
end
LUA
for round in 1 2 3; do
    for n in 1 2; do
        start "io$n-$round" --io-threads "$n" --client-connections 1000 || exit 1
        curl -s -o /dev/null -H 'Content-Type: application/json' \
            -d '{"psd":{"kind":"power","D":2.5,"k1":1,"m0":0.5}}' "$URL/v1/adhesion" # cache it
        wrk -t2 -c1000 -d"${SECS}s" -s "$tmp/io.lua" "$URL" | tail -n 1 | sed "s/^/io_threads $n /" \
            >>"$tmp/results"
        kill -TERM "$PID"
        wait "$PID"
    done
done
med() { sort -n | awk '{ a[NR] = $1 } END { print a[int((NR + 1) / 2)] }'; }
{
    echo "# ljgapd I/O threads, $(date -u +%Y-%m-%d), $(nproc) cores, loopback, wrk -t2 -c1000" \
        "-d${SECS}s, /healthz and a cached adhesion alternately, 3 rounds"
    cat "$tmp/results"
    r1=$(awk '$2 == 1 { print $4 }' "$tmp/results" | med)
    r2=$(awk '$2 == 2 { print $4 }' "$tmp/results" | med)
    echo "median_rps io_threads_1 $r1 io_threads_2 $r2 ratio $(awk -v a="$r2" -v b="$r1" 'BEGIN { printf "%.2f", a / b }')"
} | tee "$out"
