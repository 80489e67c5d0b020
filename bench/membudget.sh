#!/usr/bin/env bash
# The memory budget under a flood of uploads (issue 26): UPLOADS (100) height maps of about
# MB (60) MB each sent at once to POST /v1/psd from ADDRS (10) addresses (10 connections each,
# inside --client-connections 32), against ljgapd --max-memory BUDGET (1G), 2 compute slots,
# --queue-wait 60 (so that the uploads that fit are computed rather than timed out). Prints and
# writes to bench/results/membudget.txt: the daemon's peak resident size (VmHWM), its base (VmRSS
# when warm), the statuses (with how many carried Retry-After), the budget's own peak from
# /healthz, and the time. Target: peak RSS under 1.5 GiB, no status but 200 and 503.
#   BUILD=build bench/membudget.sh
set -u
cd "$(dirname "$0")/.."
UPLOADS=${UPLOADS:-100} MB=${MB:-60} ADDRS=${ADDRS:-10} BUDGET=${BUDGET:-1G}
out=bench/results/membudget.txt
WRAP=
. tests/lib/daemon.sh # start, req, json; the scratch directory $tmp
# a map of n x n heights as "%.9e" text (about 16 bytes a value), a random walk along rows
n=$(awk -v mb="$MB" 'BEGIN { printf "%d", sqrt(mb * 1e6 / 16.2) }')
python3 -c '
import random, sys
random.seed(26)
n = int(sys.argv[1])
with open(sys.argv[2], "w") as f:
    for j in range(n):
        h, row = 0.0, []
        for i in range(n):
            h += random.gauss(0, 1e-8)
            row.append("%.9e" % h)
        f.write(" ".join(row) + "\n")
' "$n" "$tmp/map.txt"
size=$(stat -c %s "$tmp/map.txt")
start bench --max-memory "$BUDGET" --compute-slots 2 --queue-wait 60 || exit 1
req GET /healthz
base=$(awk '$1 == "VmRSS:" { print $2 }' "/proc/$PID/status")
python3 bench/upload_clients.py "$URL/v1/psd?dx=1e-6" "$tmp/map.txt" "$UPLOADS" "$ADDRS" 600 \
    >"$tmp/clients.txt"
hwm=$(awk '$1 == "VmHWM:" { print $2 }' "/proc/$PID/status")
req GET /healthz
{
    echo "# ljgapd --max-memory $BUDGET: $UPLOADS uploads of $((size / 1000000)) MB ($n x $n heights) at once from $ADDRS addresses, $(date -u +%Y-%m-%d), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
    echo "peak_rss_mib $(awk -v k="$hwm" 'BEGIN { printf "%.0f", k / 1024 }') (VmHWM; target < 1536)"
    echo "base_rss_mib $(awk -v k="$base" 'BEGIN { printf "%.0f", k / 1024 }') (VmRSS warm, before the uploads)"
    echo "budget_peak_mib $(jq '.memory.peak / 1048576 | floor' "$tmp/body") (reserved at once, /healthz)"
    echo "budget_used_after_mib $(jq '.memory.used / 1048576 | floor' "$tmp/body") (the cache's bound)"
    sed 's/^\([0-9]*\) \([0-9]*\) /status \1: \2 answers, /' "$tmp/clients.txt"
    echo "log: $(grep -c '^POST /v1/psd 200 ' "$tmp/bench.err") computed, $(grep -c 'waited=' "$tmp/bench.err") of all waited for a slot or memory"
} | tee "$out"
kill -TERM "$PID"
wait "$PID"
