#!/usr/bin/env bash
# Serving a lab (issues 13 and 21), end to end over HTTP on loopback: the wait queue, fairness
# between clients, cancel on disconnect, the queue's limits, connections that cost no thread,
# the per-client connection limit, slow senders, and --trust-proxy. Clients come from distinct
# loopback addresses (curl --interface 127.0.0.2 / 127.0.0.3; tests/serve/clients.py for idle,
# dripping and probing connections). Every daemon is stopped by PID on every path (daemon.sh).
#   BUILD=build tests/serve/run.sh
set -u
cd "$(dirname "$0")/../.."
SLOW_WRAPPED=5 # the time bounds' multiplier under WRAP
CLIENTS="python3 tests/serve/clients.py"

. tests/lib/daemon.sh # tmp, pids, cleanup; check, start, req, hdr, json, elapsed, lt

if [ ! -x "$BIN" ]; then
    echo "not ok - $BIN is not built"
    exit 1
fi

H='Content-Type: application/json'
fast() { echo "{\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"m0\":$1}}"; }
# ~1.5 s of work each, distinct by C (no cache hits); the fairness check needs one to outlast
# the 0.3 s between the two clients (k2 = 8 at tol 1e-9 took 0.5 s before issue 19, 0.04 s after)
slow() { echo "{\"psd\":{\"kind\":\"power\",\"D\":2.5,\"k1\":1,\"C\":$1},\"tol\":1e-12}"; }
# Monte Carlo with 1e6 samples: ~18 s. A client holds a slot with it for exactly as long as it
# likes by giving up (curl --max-time): the computation is cancelled then (the first checks
# show it), so the holders below do not depend on the machine's speed.
LONG='{"psd":{"kind":"power","D":2.5,"k1":1,"m0":0.5},"method":"montecarlo","samples":1000000}'
post() { # post BODY [CURL ARGS...]: POST to /v1/adhesion; sets STATUS
    local b=$1
    shift
    req POST /v1/adhesion -H "$H" --data-binary "$b" "$@"
}
bg_post() { # bg_post OUTFILE BODY [CURL ARGS...]: in the background, "STATUS END_TIME" to OUTFILE
    local out=$1 b=$2
    shift 2
    (
        s=$(curl -s --max-time $((40 * SLOW)) -o /dev/null -w '%{http_code}' -H "$H" \
            --data-binary "$b" "$@" "$URL/v1/adhesion")
        echo "$s $(date +%s.%N)" >"$out"
    ) &
}
stop() { # stop: SIGTERM the current daemon, wait; sets RC
    kill -TERM "$PID" 2>/dev/null
    wait "$PID"
    RC=$?
}
wait_health() { # wait_health SECONDS JQ-CONDITION: until /healthz satisfies it (bounded)
    for _ in $(seq 1 $(($1 * SLOW * 20))); do
        req GET /healthz
        json "$2" && return 0
        sleep 0.05
    done
    return 1
}
wait_grep() { # wait_grep SECONDS PATTERN FILE: until grep -q finds it (bounded)
    for _ in $(seq 1 $(($1 * SLOW * 20))); do
        grep -q -- "$2" "$3" && return 0
        sleep 0.05
    done
    return 1
}
wait_files() { # wait_files SECONDS FILE...: until every file exists (bounded)
    local s=$1
    shift
    for _ in $(seq 1 $((s * 20))); do
        local all=1
        for f in "$@"; do [ -s "$f" ] || all=0; done
        [ $all = 1 ] && return 0
        sleep 0.05
    done
    return 1
}

# ================= one slot: the queue, cancel on disconnect =================
# (--queue-wait 60: the fairness check's six slow requests must all get the slot, also in the
# sanitizer and valgrind runs, where each takes seconds)
if ! start one --compute-slots 1 --queue-wait 60; then
    echo "not ok - ljgapd did not start: $(head -c 300 "$tmp/one.err")"
    exit 1
fi

for i in 1 2 3 4 5 6; do bg_post "$tmp/six.$i" "$(fast 0.1$i)"; done
wait_files 30 "$tmp"/six.{1,2,3,4,5,6}
ok6=$(cat "$tmp"/six.* 2>/dev/null | grep -c '^200 ')
check "6 parallel requests on 1 slot: all 200 ($ok6 of 6)" [ "$ok6" = 6 ]

# A client that gives up on a long computation after 0.5 s frees the slot at once.
curl -s --max-time 0.5 -o /dev/null -H "$H" --data-binary "$LONG" "$URL/v1/adhesion"
t0=$(date +%s.%N)
post "$(fast 0.21)"
took=$(elapsed "$t0")
cp "$tmp/body" "$tmp/first.json"
check "an abandoned 1e6-sample request frees its slot: the next answers 200 in ${took} s (< 1 s)" \
    eval '[ "$STATUS" = 200 ] && lt "$took" $((1 * SLOW))'
check "the log says the client went away and the computation was cancelled" \
    wait_grep 2 'client went away after [0-9.]*s, computation cancelled' "$tmp/one.err"

# A request still waiting for the slot leaves the queue when its client goes away.
bg_post "$tmp/hold" "$LONG" --max-time $((2 * SLOW))
check "/healthz shows the holder running" wait_health 5 '.compute.running == 1'
curl -s --max-time "$(awk -v s="$SLOW" 'BEGIN { print 0.5 * s }')" -o /dev/null -H "$H" \
    --data-binary "$(fast 0.22)" "$URL/v1/adhesion" &
waiter=$!
check "/healthz shows one request waiting, then none once its client gave up" \
    eval 'wait_health 5 ".compute.waiting == 1" && wait "$waiter"; wait_health 2 ".compute.waiting == 0"'
check "/healthz: slots, queue and connections" \
    json '.compute.slots == 1 and .compute.queue == 64 and .connections.open >= 1
        and .connections.limit == 1024'

t0=$(date +%s.%N)
req GET /healthz
hz=$(elapsed "$t0")
check "/healthz while the slot is busy and the queue is not empty: 200 in ${hz} s (< 1 s)" \
    eval '[ "$STATUS" = 200 ] && lt "$hz" $((1 * SLOW))'
post "$(fast 0.21)"
check "a cached answer while the slot is busy: 200 at once, meta.cached" \
    eval '[ "$STATUS" = 200 ] && json ".meta.cached == true"'
check "the cached answer is the first one but for meta.cached" \
    eval '[ "$(jq -S "del(.meta.cached)" "$tmp/body")" = "$(jq -S "del(.meta.cached)" "$tmp/first.json")" ] &&
        jq -e ".meta.cached == false" "$tmp/first.json" >/dev/null'
check "a waiting request whose client went away left the queue without running" \
    eval 'wait_grep 2 "went away after [0-9.]*s)" "$tmp/one.err"'
wait_files $((10 * SLOW)) "$tmp/hold"
cancelled() { [ "$(grep -c 'went away after [0-9.]*s, computation cancelled' "$tmp/one.err")" = 2 ]; }
check "the slot holder was cancelled when its client gave up" \
    eval 'for _ in $(seq 1 $((100 * SLOW))); do cancelled && break; sleep 0.05; done; cancelled'
# A client that shuts down its sending side counts as gone: the computation is cancelled, and
# the answer it may still read says so (problem type unavailable, not busy).
half=$($CLIENTS half "${URL##*:}" "$LONG")
check "a client that shuts down its sending side is cancelled: 503 unavailable ($half)" \
    [ "$half" = "503 /problems/unavailable" ]

# ---- fairness: 127.0.0.2 sends five slow requests, 127.0.0.3 one just after ----
# (not under valgrind: thirty times slower, the six take minutes; the paths they take are the
# queue's, which the checks above exercise)
if [ -z "$WRAP" ]; then
    for i in 1 2 3 4 5; do bg_post "$tmp/fa.$i" "$(slow 0.07$i)" --interface 127.0.0.2; done
    sleep 0.3
    bg_post "$tmp/fb" "$(slow 0.081)" --interface 127.0.0.3
    wait_files 60 "$tmp"/fa.{1,2,3,4,5} "$tmp/fb"
    tb=$(cut -d' ' -f2 "$tmp/fb")
    before=0
    for i in 1 2 3 4 5; do
        ta=$(cut -d' ' -f2 "$tmp/fa.$i")
        lt "$ta" "$tb" && before=$((before + 1))
    done
    okf=$(cat "$tmp"/fa.* "$tmp/fb" | grep -c '^200 ')
    check "fair shares: the single request of 127.0.0.3 waited for $before of the five of 127.0.0.2 (<= 1)" \
        eval '[ "$okf" = 6 ] && [ "$before" -le 1 ]'
fi
stop
check "SIGTERM: exit 0 ($RC)" [ "$RC" = 0 ]

# ================= the queue's limits =================
if start limits --compute-slots 1 --queue 1 --queue-wait $((2 * SLOW)); then
    bg_post "$tmp/l1" "$LONG" --max-time $((8 * SLOW))
    wait_health 5 '.compute.running == 1'
    bg_post "$tmp/l2" "$(fast 0.31)" -D "$tmp/l2.hdrs"
    wait_health 5 '.compute.waiting == 1'
    t0=$(date +%s.%N)
    post "$(fast 0.32)"
    took=$(elapsed "$t0")
    check "a third request with 1 running and 1 waiting (--queue 1): 503 at once (${took} s)" \
        eval '[ "$STATUS" = 503 ] && lt "$took" $((1 * SLOW)) &&
            [[ "$(hdr Retry-After)" =~ ^[0-9]+$ ]] && json ".type | endswith(\"/busy\")" &&
            json ".detail | test(\"queue is full\")"'
    wait_files 10 "$tmp/l2"
    check "the waiting one gets 503 + Retry-After after --queue-wait ($(cat "$tmp/l2" | cut -d' ' -f1))" \
        eval 'grep -q "^503 " "$tmp/l2" && grep -qi "^Retry-After: [0-9][0-9]*" "$tmp/l2.hdrs"'
    check "the log says how long it waited" wait_grep 2 ' 503 .* waited=[0-9.]*s' "$tmp/limits.err"
    wait_files $((12 * SLOW)) "$tmp/l1"
    stop
    check "SIGTERM: exit 0 ($RC)" [ "$RC" = 0 ]
else
    echo "not ok - ljgapd --queue 1 did not start"
fi

# ================= connections that cost no thread =================
if start flood --client-connections 1000; then
    port=${URL##*:}
    $CLIENTS hold "$port" 127.0.0.2 500 100 $((30 * SLOW)) >"$tmp/hold.out" 2>&1 &
    holder=$!
    pids+=("$holder")
    wait_files $((20 * SLOW)) "$tmp/hold.out"
    check "500 idle and 100 dripping connections from 127.0.0.2 are open ($(cat "$tmp/hold.out"))" \
        grep -q '^open 600 closed 0$' "$tmp/hold.out"
    threads=$(ls "/proc/$PID/task" | wc -l)
    check "with 600 connections open the daemon has $threads threads (< 24)" [ "$threads" -lt 24 ]
    t0=$(date +%s.%N)
    req GET /healthz --interface 127.0.0.3
    hz=$(elapsed "$t0")
    check "127.0.0.3 still gets /healthz in ${hz} s (< 1 s)" \
        eval '[ "$STATUS" = 200 ] && lt "$hz" $((1 * SLOW))'
    post "$(fast 0.41)" --interface 127.0.0.3
    check "127.0.0.3 still gets an adhesion answer (200)" [ "$STATUS" = 200 ]
    kill "$holder" 2>/dev/null
    wait "$holder" 2>/dev/null
    stop
    check "SIGTERM with 600 connections held: exit 0 ($RC)" [ "$RC" = 0 ]
else
    echo "not ok - ljgapd --client-connections 1000 did not start"
fi

# ================= the per-client connection limit (default 32) =================
if start perclient; then
    port=${URL##*:}
    check "--help gives the per-client limit's default" \
        eval '"$BIN" --help | grep -q -- "--client-connections N.*default 32"'
    $CLIENTS hold "$port" 127.0.0.2 40 0 $((20 * SLOW)) >"$tmp/pc.out" 2>&1 &
    holder=$!
    pids+=("$holder")
    wait_files $((10 * SLOW)) "$tmp/pc.out"
    check "40 connections from 127.0.0.2: 32 kept, the 33rd and later refused ($(cat "$tmp/pc.out"))" \
        grep -q '^open 32 closed 8$' "$tmp/pc.out"
    req GET /healthz --interface 127.0.0.3
    check "meanwhile 127.0.0.3 is served (200)" [ "$STATUS" = 200 ]
    kill "$holder" 2>/dev/null
    wait "$holder" 2>/dev/null
    stop
    check "SIGTERM: exit 0 ($RC)" [ "$RC" = 0 ]
else
    echo "not ok - ljgapd did not start with its defaults"
fi

# ================= slow senders =================
if start slowsend --receive-timeout 2; then
    port=${URL##*:}
    cut_after=$($CLIENTS drip "$port" 127.0.0.2 0.5 $((10 * SLOW)))
    check "a client sending its headers a byte every 0.5 s is cut after ${cut_after} s (--receive-timeout 2)" \
        eval '[ "$cut_after" != open ] && lt 1.5 "$cut_after" && lt "$cut_after" $((4 * SLOW))'
    req GET /healthz
    check "a whole request in time is served (200)" [ "$STATUS" = 200 ]
    stop
    check "SIGTERM: exit 0 ($RC)" [ "$RC" = 0 ]
else
    echo "not ok - ljgapd --receive-timeout 2 did not start"
fi

# ================= behind a proxy: clients named by X-Forwarded-For =================
if start proxy --trust-proxy --client-connections 2 --compute-slots 1; then
    bg_post "$tmp/p1" "$LONG" -H 'X-Forwarded-For: 10.1.1.1' --max-time $((3 * SLOW))
    wait_health 5 '.compute.running == 1'
    bg_post "$tmp/p2" "$(fast 0.51)" -H 'X-Forwarded-For: 10.1.1.1'
    wait_health 5 '.compute.waiting == 1'
    req GET /healthz -H 'X-Forwarded-For: 10.1.1.1'
    check "--trust-proxy: a third request of 10.1.1.1 (2 in progress) gets 503 naming the limit" \
        eval '[ "$STATUS" = 503 ] && json ".detail | test(\"client-connections\")" &&
            [[ "$(hdr Retry-After)" =~ ^[0-9]+$ ]]'
    req GET /healthz -H 'X-Forwarded-For: 10.9.9.9, 10.2.2.2'
    check "--trust-proxy: another forwarded client (the last address counts) is served" \
        [ "$STATUS" = 200 ]
    wait_files $((10 * SLOW)) "$tmp/p1" "$tmp/p2"
    stop
    check "SIGTERM: exit 0 ($RC)" [ "$RC" = 0 ]
else
    echo "not ok - ljgapd --trust-proxy did not start"
fi
if start noproxy --client-connections 2; then
    $CLIENTS hold "${URL##*:}" 127.0.0.2 2 0 $((10 * SLOW)) >"$tmp/np.out" 2>&1 &
    holder=$!
    pids+=("$holder")
    wait_files $((10 * SLOW)) "$tmp/np.out"
    req GET /healthz --interface 127.0.0.2 -H 'X-Forwarded-For: 10.3.3.3'
    check "without --trust-proxy a forged X-Forwarded-For does not escape the address's limit" \
        eval 'grep -q "^open 2 closed 0$" "$tmp/np.out" && [ "$STATUS" = 000 ]'
    kill "$holder" 2>/dev/null
    wait "$holder" 2>/dev/null
    stop
    check "SIGTERM: exit 0 ($RC)" [ "$RC" = 0 ]
else
    echo "not ok - ljgapd --client-connections 2 did not start"
fi

# ================= the open-file limit =================
# The soft limit is raised to the hard one at start (the log says so), and the connection
# limit fits inside it. (Not under valgrind, which keeps descriptors of its own.)
if [ -z "$WRAP" ]; then
    fdlimit() { # fdlimit NAME SOFT:HARD CONNECTIONS LOG-TEXT: start under prlimit, check, stop
        local name=$1 lim=$2 conns=$3 text=$4
        WRAP="prlimit --nofile=$lim" start "$name"
        req GET /healthz
        check "open-file limit $lim: '$text' in the log, connections.limit $conns" \
            eval 'grep -qF "$text" "$tmp/$name.err" && json ".connections.limit == $conns"'
        stop
        check "SIGTERM: exit 0 ($RC)" [ "$RC" = 0 ]
    }
    fdlimit files-raised 256:4096 1024 "open-file limit 4096 (raised from 256)"
    fdlimit files-fitted 256:256 192 "192 connections (32 per client), open-file limit 256,"
fi

# ================= the memory budget (issue 26) =================
# 20 concurrent 8 MB height maps against --max-memory 64M: bodies that do not fit are refused
# unread (503 + Retry-After), computations wait for memory like for a slot; every answer is 200
# or 503 with Retry-After, the peak resident memory (VmHWM) stays within the budget plus the
# daemon's base (its VmRSS once warm), and /healthz is fine afterwards. A chunked upload that
# crosses the budget is 503; a simulation whose grid does not fit is 413 at submission. (The
# RSS bound is not checked under a wrapper or a sanitizer: both keep memory of their own.)
python3 -c '
import random
random.seed(26)
n = 700  # ~8 MB of "%.9e" values: 490000 heights
rows = (" ".join("%.9e" % random.gauss(0, 1e-6) for _ in range(n)) for _ in range(n))
open("'"$tmp"'/map8.txt", "w").write("\n".join(rows) + "\n")
'
rss_kb() { awk -v k="$2:" '$1 == k { print $2 }' "/proc/$1/status"; }
sanitized() { [ -n "$WRAP" ] || ldd "$BIN" 2>/dev/null | grep -q 'libasan\|libtsan'; }
if start mem --max-memory 64M --compute-slots 2 --queue-wait $((10 * SLOW)); then
    req POST '/v1/psd?dx=1e-6' -H 'Content-Type: text/plain' --data-binary "@$tmp/map8.txt"
    check "budget 64M: one 8 MB map alone computes (200)" [ "$STATUS" = 200 ]
    req GET /healthz
    check "/healthz reports the budget: limit, use back to the cache's bound, a peak" \
        json '.memory.limit == 67108864 and .memory.used == .memory.cache
              and .memory.peak > 8000000 and .memory.bodies == 0
              and .memory.bodies_limit < .memory.limit / 2 + 1'
    base=$(rss_kb "$PID" VmRSS)
    for i in $(seq 1 20); do
        curl -s --max-time $((60 * SLOW)) -o /dev/null -D "$tmp/mem.h$i" -w '%{http_code}' \
            -H 'Content-Type: text/plain' --data-binary "@$tmp/map8.txt" \
            "$URL/v1/psd?dx=1e-6" >"$tmp/mst.$i" &
    done
    wait_files $((70 * SLOW)) $(for i in $(seq 1 20); do echo "$tmp/mst.$i"; done)
    statuses=$(for i in $(seq 1 20); do cat "$tmp/mst.$i"; echo; done | sort | uniq -c |
        awk '{ printf "%s%s x %s", (NR > 1 ? ", " : ""), $1, $2 }')
    only_200_503() {
        for i in $(seq 1 20); do
            case $(cat "$tmp/mst.$i") in
            200) ;;
            503) grep -qi '^Retry-After: [0-9]' "$tmp/mem.h$i" || return 1 ;;
            *) return 1 ;;
            esac
        done
        grep -q 200 "$tmp"/mst.*
    }
    check "20 concurrent 8 MB uploads: each 200 or 503 + Retry-After, some 200 ($statuses)" \
        only_200_503
    hwm=$(rss_kb "$PID" VmHWM)
    echo "# budget 64M: base ${base} kB, peak VmHWM ${hwm} kB ($statuses)"
    if ! sanitized; then
        check "peak RSS ${hwm} kB within the budget (65536 kB) + base ${base} kB" \
            [ "$hwm" -le $((65536 + base)) ]
    fi
    req GET /healthz
    check "/healthz fine afterwards: nothing held but the cache's bound" \
        json '.status == "pass" and .memory.used == .memory.cache and .compute.running == 0'
    # chunked: no Content-Length, so the body is reserved as it grows and dropped past the
    # bodies' share (~30 MB); the 503 goes out when it ends
    head -c 40000000 /dev/zero | tr '\0' '7' | sed 's/7\{99\}/&\n/g' >"$tmp/big.txt"
    req POST '/v1/psd?dx=1' -H 'Content-Type: text/plain' -H 'Transfer-Encoding: chunked' \
        --data-binary "@$tmp/big.txt"
    check "a chunked upload crossing the budget: 503 + Retry-After naming --max-memory" \
        eval '[ "$STATUS" = 503 ] && [ -n "$(hdr Retry-After)" ] && json ".detail | test(\"max-memory\")"'
    req GET /healthz
    check "... and its bytes are given back" json '.memory.used == .memory.cache'
    req POST '/v1/psd?dx=1' -H 'Content-Type: text/plain' --data-binary "@$tmp/big.txt"
    check "a 40 MB body with Content-Length: 413 before it is read, the limit named" \
        eval '[ "$STATUS" = 413 ] && json ".detail | test(\"--max-memory 64 MiB\")"'
    SIMPSD='"psd":{"kind":"power","D":2.2,"k1":1,"k2":8,"m0":0.1}'
    req POST /v1/simulations -H "$H" --data-binary "{$SIMPSD,\"n\":512,\"realizations\":2,\"g_ave\":[2,3]}"
    check "a simulation whose 512² grid does not fit: 413 at submission, the limit named" \
        eval '[ "$STATUS" = 413 ] && json ".detail | test(\"n x n grid\") and test(\"max-memory\")"'
    req POST /v1/simulations -H "$H" --data-binary "{$SIMPSD,\"n\":32,\"realizations\":2,\"g_ave\":[2,3]}"
    check "a small simulation is taken (202)" [ "$STATUS" = 202 ]
    stop
    check "SIGTERM: exit 0 ($RC)" [ "$RC" = 0 ]
else
    echo "not ok - ljgapd --max-memory 64M did not start"
fi
# A computation that does not fit waits for memory as for a slot, and gets 503 after
# --queue-wait: three Monte Carlo requests (16 MiB each with 4 slots) hold 48 of the 60 MiB the
# cache's bound leaves, so an 8 MB map (its body and 23 MiB) waits although a slot is free;
# once they are cancelled (their clients hang up), the map computes. (--max-seconds 600: under
# valgrind the Monte Carlo would otherwise stop early at its time cap. Not under a wrapper: there
# the three busy threads leave the I/O thread so little time that the upload alone can outlast
# any bound; the sanitizer build runs it.)
if [ -n "$WRAP" ]; then
    echo "# waiting for memory: not under $WRAP"
elif start memq --max-memory 64M --compute-slots 4 --queue-wait "$SLOW" --max-seconds 600; then
    holders=()
    for seed in 1 2 3; do
        curl -s --max-time $((30 * SLOW)) -o /dev/null -H "$H" \
            --data-binary "${LONG%\}},\"seed\":$seed}" "$URL/v1/adhesion" &
        holders+=($!)
    done
    check "three long computations hold three of four slots and their memory" \
        wait_health 5 '.compute.running == 3 and .memory.used > .memory.cache + 50000000'
    req POST '/v1/psd?dx=1e-6' -H 'Content-Type: text/plain' --data-binary "@$tmp/map8.txt"
    check "a map that does not fit beside them waits, then 503 + Retry-After naming the memory" \
        eval '[ "$STATUS" = 503 ] && [ -n "$(hdr Retry-After)" ] &&
              json ".detail | test(\"memory\") and test(\"max-memory\")"'
    kill "${holders[@]}" 2>/dev/null
    wait "${holders[@]}" 2>/dev/null
    check "once they are gone it computes (200)" eval \
        'wait_health 5 ".compute.running == 0" &&
         req POST "/v1/psd?dx=1e-6" -H "Content-Type: text/plain" --data-binary "@$tmp/map8.txt" &&
         [ "$STATUS" = 200 ]'
    stop
    check "SIGTERM: exit 0 ($RC)" [ "$RC" = 0 ]
else
    echo "not ok - ljgapd --max-memory 64M --compute-slots 4 did not start"
fi
check "bad --max-memory is refused with status 2" \
    eval '"$BIN" --max-memory 1T >/dev/null 2>&1; [ $? = 2 ] &&
          "$BIN" --max-memory 1M >/dev/null 2>&1; [ $? = 2 ]'

check "bad --queue-wait is refused with status 2" \
    eval '"$BIN" --queue-wait 0 >/dev/null 2>&1; [ $? = 2 ]'
check "bad --client-connections is refused with status 2" \
    eval '"$BIN" --client-connections 0 >/dev/null 2>&1; [ $? = 2 ]'
help_lists() { # every limit's flag is in --help
    "$BIN" --help >"$tmp/help" || return 1
    for f in --compute-slots --queue --queue-wait --max-seconds --connections \
        --client-connections --trust-proxy --idle-timeout --receive-timeout --io-threads \
        --max-body --max-memory; do
        grep -q -- "$f" "$tmp/help" || return 1
    done
}
check "--help lists every limit" help_lists
