#!/usr/bin/env bash
# Throughput of POST /v1/adhesion through nginx (deploy/nginx/ljgap.conf) with 1 and with 2
# ljgapd instances on this machine, as ratios measured in one run. Every request is distinct
# (bench/scaleout.lua: the tol differs in its 13th digit), so no answer comes from a cache.
# Three cases, each measured ROUNDS times (3) alternating 1 and 2 instances, SECONDS (8) of
# wrk -t2 -c8 each; figures are the medians of the rounds:
#   heavy, 1 slot each     Fig. 4's surface at tol 1e-7 (about 13 ms of computing), every
#                          ljgapd --compute-slots 1: one instance computes on one core, two on two
#   heavy, default slots   the same with the default slots (the cores: 2 here), so one instance
#                          already computes on both cores
#   light, 1 slot each     the same surface at the default tol (about 1.5 ms), where the HTTP
#                          path (nginx, ljgapd's I/O thread, wrk) weighs as much as computing
# The instances keep their jobs in their own --state-dir (no simulation runs here, so the job
# store plays no part). nginx, the instances and wrk share the machine's 2 cores: see the
# README ("Scaling out") for what the ratios can and cannot show. Everything runs under nice.
# Writes bench/results/scaleout.txt. Needs nginx and wrk (make bench installs them).
#   BUILD=build bench/scaleout.sh
set -u
cd "$(dirname "$0")/.."
ROUNDS=${ROUNDS:-3}
SECS=${SECONDS_EACH:-8}
out=bench/results/scaleout.txt
mkdir -p bench/results
WRAP="nice -n 19"
NGINX_WRAP="nice -n 19"
. tests/lib/daemon.sh # start; $tmp
. tests/lib/pg.sh     # free_port
. tests/lib/nginx.sh  # nginx_conf, nginx_start, nginx_stop
trap 'nginx_stop; cleanup' EXIT
trap 'exit 143' INT TERM # the EXIT trap stops everything on a signal too
for c in nginx wrk; do
    command -v $c >/dev/null || { echo "scaleout.sh: $c is not installed (make deps)" >&2; exit 1; }
done
[ -x "$BIN" ] || { echo "scaleout.sh: $BIN is not built" >&2; exit 1; }

# one CASE-NAME TOL SLOTS: ROUNDS rounds of 1 then 2 instances; prints the table rows
one() {
    local name=$1 tol=$2 slots=$3 n r rps
    local -a args=()
    [ "$slots" = default ] || args=(--compute-slots "$slots")
    start "$name-a" "${args[@]}" || { echo "ljgapd did not start" >&2; exit 1; }
    local pa=${URL##*:} pida=$PID
    start "$name-b" "${args[@]}" || { echo "ljgapd did not start" >&2; exit 1; }
    local pb=${URL##*:} pidb=$PID
    for r in $(seq 1 "$ROUNDS"); do
        for n in 1 2; do
            if [ $n = 1 ]; then nginx_conf "$pa"; else nginx_conf "$pa" "$pb"; fi || exit 1
            nginx_start || { echo "nginx did not start" >&2; exit 1; }
            runs=$((runs + 2))
            nice -n 19 wrk -t2 -c8 -d1s -s bench/scaleout.lua "$NGINX_URL" -- "$tol" $runs \
                >/dev/null 2>&1
            nice -n 19 wrk -t2 -c8 -d"${SECS}s" -s bench/scaleout.lua "$NGINX_URL" -- "$tol" \
                $((runs + 1)) >"$tmp/wrk" 2>&1
            nginx_stop
            rps=$(awk '$1 == "requests_per_s" { print $2 }' "$tmp/wrk")
            echo "$name $n $r $rps $(awk '$1 == "latency_p50_ms" { print $2 }' "$tmp/wrk") \
$(awk '$1 == "latency_p99_ms" { print $2 }' "$tmp/wrk") \
$(awk '$1 == "status" && $2 != 200 { s += $3 } END { print s + 0 }' "$tmp/wrk") \
$(awk '$1 == "cache_hits" { print $2 }' "$tmp/wrk") \
$(awk '$1 == "socket_errors" { print $2 }' "$tmp/wrk")" >>"$tmp/rows"
        done
    done
    kill -TERM "$pida" "$pidb"
    wait "$pida" "$pidb"
}

{
    echo "# POST /v1/adhesion through nginx, 1 vs 2 ljgapd, $(date -u +%Y-%m-%d), $(nproc) cores," \
        "$(uname -m), load $(cut -d' ' -f1-3 /proc/loadavg); wrk -t2 -c8 ${SECS} s x $ROUNDS rounds"
    : >"$tmp/rows"
    runs=0 # wrk runs so far: each gets its own requests
    one heavy-1slot 1e-7 1
    one heavy-defaultslots 1e-7 default
    one light-1slot 1e-6 1
    echo "# case instances round requests/s p50_ms p99_ms non200 cache_hits socket_errors"
    cat "$tmp/rows"
    echo "# medians over the rounds; ratio = 2 instances / 1 instance"
    awk '{ k = $1 " " $2; v[k] = v[k] " " $4; p50[k] = p50[k] " " $5; p99[k] = p99[k] " " $6
           bad += $7 + $9; hits += $8; cases[$1] = 1 }
         function median(s,   a, n, i, j, t) {
             n = split(s, a, " ")
             for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) if (a[j] + 0 < a[i] + 0) { t = a[i]; a[i] = a[j]; a[j] = t }
             return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2 }
         END {
             for (c in cases) {
                 one = median(v[c " 1"]); two = median(v[c " 2"])
                 printf "%-20s 1 instance %7.1f req/s (p50 %s ms)   2 instances %7.1f req/s (p50 %s ms)   ratio %.2f\n",
                     c, one, median(p50[c " 1"]), two, median(p50[c " 2"]), two / one
             }
             printf "answers other than 200 or socket errors: %d; cache hits: %d\n", bad, hits
         }' "$tmp/rows" | sort
} | tee "$out"
