#!/usr/bin/env bash
# Scaling out: two ljgapd behind nginx (deploy/nginx/ljgap.conf) sharing one PostgreSQL job
# store, all on loopback, all started here and stopped by PID on every path:
#   - a private PostgreSQL cluster (tests/lib/pg.sh: initdb and pg_ctl in the scratch
#     directory, as the user postgres when run as root, 127.0.0.1 on a free port, no Unix socket)
#     and the PostgreSQL backend's unit tests against it (the job store contract, two daemons on
#     one queue, concurrency, reconnection, opening errors: test_jobstore_pg);
#   - two ljgapd --jobs-db URL --trust-proxy --job-lease 2 and nginx in front of them
#     (tests/lib/nginx.sh): synchronous requests, X-Forwarded-For reaching ljgapd as the client,
#     the body limits (1 MiB, 64 MiB for /v1/psd); the deploy file's retries (idempotent only),
#     timeouts and body limit checked against ljgapd's defaults from its --help;
#   - jobs submitted through nginx: every id answers through either instance; one instance
#     SIGKILLed in the middle of a job, and every job still ends done (the killed one claimed by
#     the other once its lease lapsed, run from the start: the CLI's numbers), with no request
#     through nginx failing meanwhile;
#   - a cancel through nginx that reaches the job running on the other instance;
#   - rows damaged by hand with psql, shown as failed jobs with a job-damaged problem;
#   - the database stopped while the daemons run: job routes answer 503 job-store with
#     Retry-After at once, synchronous ones keep working; restarted, the daemons reconnect by
#     themselves and the job that ran meanwhile ends done;
#   - start-up with the database unreachable or missing: exit 2 with the reason, never the
#     password; --jobs-db with --state-dir or with another URL scheme: exit 2.
# One "ok ..." / "not ok ..." line per check (summed by tests/run.sh). With WRAP (valgrind, from
# tests/memcheck/run.sh) the daemons and the unit tests run under it, with smaller jobs and
# longer time bounds; each daemon stopped by SIGTERM must exit 0.
#   BUILD=build tests/scaleout/run.sh
set -u
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
UNIT=$BUILD/tests/scaleout/test_jobstore_pg
SLOW_WRAPPED=10 # the time bounds' multiplier under WRAP

CHECK_PREFIX="scaleout: "
. tests/lib/daemon.sh # tmp, pids, cleanup; check, start, req, hdr, json, elapsed, lt
. tests/lib/jobs.sh   # submit, wait_for, wait_state, jq_ok
. tests/lib/pg.sh     # pg_init, pg_start, pg_stop, pg_cleanup, pg_sql, free_port
. tests/lib/nginx.sh  # nginx_conf, nginx_check, nginx_start, nginx_stop
trap 'nginx_stop; pg_cleanup; cleanup' EXIT
trap 'exit 143' INT TERM # the EXIT trap stops everything on a signal too

for c in nginx psql curl jq python3; do
    if ! command -v "$c" >/dev/null; then
        echo "not ok - scaleout: $c is not installed (make test installs it)"
        exit 1
    fi
done
if [ ! -x "$UNIT" ]; then
    echo "not ok - scaleout: $UNIT is not built"
    exit 1
fi

PSD='"psd":{"kind":"power","D":2.2,"k1":1,"k2":8,"m0":0.1}'
SMALL="{$PSD,\"n\":32,\"realizations\":2,\"seed\":7,\"g_ave\":[2,3,4]}"
job() { # job SEED: a simulation of about 1 s on a core (0.3 s, under valgrind ~30x slower)
    if [ -n "$WRAP" ]; then
        echo "{$PSD,\"n\":128,\"realizations\":4,\"seed\":$1,\"g_ave\":{\"min\":1.2,\"max\":4,\"n\":20}}"
    else
        echo "{$PSD,\"n\":256,\"realizations\":2,\"seed\":$1,\"g_ave\":{\"min\":1.2,\"max\":4,\"n\":30}}"
    fi
}
LONG="{$PSD,\"n\":256,\"realizations\":16,\"g_ave\":{\"min\":1.2,\"max\":4,\"n\":150}}"
LEASE=2
[ -n "$WRAP" ] && LEASE=4

# ================= the cluster, and the backend's unit tests =================
if ! pg_init; then
    echo "not ok - scaleout: the private PostgreSQL cluster did not start (initdb in $PGBIN)"
    exit 1
fi
check "a private PostgreSQL cluster on 127.0.0.1:$PGPORT, no Unix socket" eval '
    [ "$(pg_sql "SHOW listen_addresses")" = 127.0.0.1 ] &&
    [ -z "$(pg_sql "SHOW unix_socket_directories")" ]'
LJGAP_TEST_PG_URL=$PGURL $WRAP "$UNIT" >"$tmp/unit.out" 2>&1
rc=$?
sed -n -e 's/^\[       OK \] \(.*\)/ok - scaleout: unit: \1/p' \
    -e 's/^\[  FAILED  \] \(test_[a-z0-9_]*\)$/not ok - scaleout: unit: \1/p' "$tmp/unit.out"
if [ "$rc" != 0 ]; then
    echo "not ok - scaleout: $UNIT exited with status $rc"
    grep -v '^\[' "$tmp/unit.out" | head -n 20 | sed 's/^/# /'
fi

# ================= two instances and nginx =================
startd() { # startd NAME [ARGS]: an instance on the shared job store; sets URL, PID
    NO_STATE_DIR=1 start "$@" --jobs-db "$PGURL" --trust-proxy --job-lease "$LEASE" \
        --job-workers 2 --job-queue 16
}
if ! startd a; then
    echo "not ok - scaleout: ljgapd a did not start: $(head -c 300 "$tmp/a.err")"
    exit 1
fi
A_URL=$URL A_PID=$PID A_PORT=${URL##*:}
if ! startd b; then
    echo "not ok - scaleout: ljgapd b did not start: $(head -c 300 "$tmp/b.err")"
    exit 1
fi
B_URL=$URL B_PID=$PID B_PORT=${URL##*:}
check "the log names the shared store, without a password, and the lease" \
    grep -qF "jobs kept in $PGURL, shared (0 queued, 0 running), lease $LEASE s" "$tmp/a.err"
if ! nginx_conf "$A_PORT" "$B_PORT"; then
    echo "not ok - scaleout: cannot write the nginx configuration"
    exit 1
fi
check "nginx -t accepts deploy/nginx/ljgap.conf" eval 'out=$(nginx_check) || { echo "# $out"; false; }'
# The deploy file's figures against ljgapd's own defaults (from its --help), so neither drifts
# alone: retries only for idempotent requests (no non_idempotent, no retry of ljgapd's own 5xx),
# the read timeout past --queue-wait + --max-seconds, the body limit --max-body, idle upstream
# connections closed before --idle-timeout, the client's address appended to X-Forwarded-For.
conf_matches_ljgapd() {
    local help conf qw ms mb it rt body ka nu
    help=$("$BIN" --help 2>&1)
    conf=deploy/nginx/ljgap.conf
    ljgapd_default() { printf '%s\n' "$help" | sed -n "s/^ *--$1 [A-Z]* .*(default \([0-9]*\)).*/\1/p"; }
    conf_value() { sed -n "s/^ *$1 \([0-9]*\)[a-z]*;.*/\1/p" "$conf" | head -n 1; }
    qw=$(ljgapd_default queue-wait) ms=$(ljgapd_default max-seconds)
    mb=$(ljgapd_default max-body) it=$(ljgapd_default idle-timeout)
    rt=$(conf_value proxy_read_timeout) body=$(conf_value client_max_body_size)
    ka=$(conf_value keepalive_timeout)
    nu=$(grep -E '^ *proxy_next_upstream ' "$conf")
    if [ -n "$qw" ] && [ -n "$ms" ] && [ -n "$mb" ] && [ -n "$it" ] && [ -n "$rt" ] &&
        [ -n "$body" ] && [ -n "$ka" ] && [ -n "$nu" ] &&
        [ "$rt" -gt $((qw + ms)) ] && [ $((body * 1024 * 1024)) = "$mb" ] && [ "$ka" -lt "$it" ] &&
        ! grep -q non_idempotent "$conf" && ! printf '%s' "$nu" | grep -q http_ &&
        grep -qE '^ *proxy_set_header X-Forwarded-For \$proxy_add_x_forwarded_for;' "$conf"; then
        return 0
    fi
    echo "# --queue-wait $qw --max-seconds $ms --max-body $mb --idle-timeout $it;" \
        "proxy_read_timeout $rt, client_max_body_size ${body}m, keepalive_timeout $ka;$nu"
    return 1
}
check "deploy/nginx/ljgap.conf matches ljgapd's defaults (idempotent retries, timeouts, body)" \
    conf_matches_ljgapd
if ! nginx_start; then
    echo "not ok - scaleout: nginx did not start"
    exit 1
fi

# where did the request with X-Request-Id $1 go? (a, b or none, from the instances' logs)
served_by() {
    local n
    for _ in $(seq 1 $((20 * SLOW))); do
        for n in a b a2; do
            [ -f "$tmp/$n.err" ] && grep -qE "id=$1( |$)" "$tmp/$n.err" && { echo "${n%2}"; return; }
        done
        sleep 0.05
    done
    echo none
}
URL=$NGINX_URL
req GET /healthz -H 'X-Request-Id: probe-1'
first=$(served_by probe-1)
req GET /healthz -H 'X-Request-Id: probe-2'
second=$(served_by probe-2)
check "nginx passes requests to both instances in turn (probes went to $first, $second)" \
    eval '[ "$first" != none ] && [ "$second" != none ] && [ "$first" != "$second" ]'
req POST /v1/adhesion -H 'Content-Type: application/json' --data-binary "{$PSD}"
check "POST /v1/adhesion through nginx: 200 with an answer" json ".g_eq > 0"
req GET /healthz --interface 127.0.0.2 -H 'X-Forwarded-For: 6.6.6.6' -H 'X-Request-Id: xff-1'
check "X-Forwarded-For: ljgapd --trust-proxy names the client nginx saw, not a forged one" \
    eval 'grep -h "id=xff-1 " "$tmp/a.err" "$tmp/b.err" | grep -q " client=127.0.0.2"'
head -c $((1024 * 1024 + 100)) /dev/zero | tr '\0' ' ' >"$tmp/big.json"
req POST /v1/adhesion -H 'Content-Type: application/json' --data-binary @"$tmp/big.json"
check "a JSON body over 1 MiB: nginx answers 413" [ "$STATUS" = 413 ]
{
    echo "# more than 1 MiB of heights for /v1/psd, one row too short"
    for _ in $(seq 1 5000); do echo "1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9 2e-9 3e-9 1e-9"; done
    echo "1e-9"
} >"$tmp/big.txt"
req POST '/v1/psd?dx=1e-8' -H 'Content-Type: text/plain' --data-binary @"$tmp/big.txt"
check "a $(($(stat -c %s "$tmp/big.txt") / 1024)) KiB text body reaches ljgapd through /v1/psd (its 422, not 413)" \
    eval '[ "$STATUS" = 422 ] && json ".type | test(\"/problems/\")"'

# ================= jobs through nginx: every id answers through either instance =================
ids=()
for seed in 11 12 13 14; do
    submit "$(job $seed)"
    [ "$STATUS" = 202 ] && ids+=("$ID")
done
check "4 jobs submitted through nginx: 202 each" [ ${#ids[@]} = 4 ]
answers_everywhere() {
    local id u
    for id in "${ids[@]}"; do
        for u in "$A_URL" "$B_URL" "$NGINX_URL"; do
            [ "$(curl -s --max-time $((5 * SLOW)) "$u/v1/simulations/$id" | jq -r .id)" = "$id" ] ||
                { echo "# $id not through $u"; return 1; }
        done
    done
}
check "every id answers through instance a, instance b and nginx" answers_everywhere

# ================= SIGKILL an instance in the middle of a job =================
all_done() { # all_done ID...: every one done (polled through nginx); counts answers not 200
    local id
    for id in "$@"; do
        req GET "/v1/simulations/$id"
        [ "$STATUS" = 200 ] || fails=$((fails + 1))
        json '.status == "done"' || return 1
    done
}
until_done() { # until_done ID...: poll until all_done (60 s x SLOW)
    for _ in $(seq 1 $((300 * SLOW))); do
        all_done "$@" && return 0
        sleep 0.2
    done
    return 1
}
fails=0
check "the 4 jobs end done (2 workers on each instance)" until_done "${ids[@]}"
# two more jobs: at most 2 of the 4 workers busy, so instance b has a free one when a dies
submit "$(job 15)"
ids+=("$ID")
submit "$(job 16)"
ids+=("$ID")
running_on() { # running_on PID: the id of a job running on that instance, or nothing
    pg_sql "SELECT id FROM ljgapd.jobs WHERE state = 'running' AND owner LIKE '%:$1' LIMIT 1"
}
killed=
for _ in $(seq 1 $((200 * SLOW))); do
    killed=$(running_on "$A_PID")
    [ -n "$killed" ] && break
    sleep 0.05
done
check "a job runs on instance a" [ -n "$killed" ]
run_before=$(pg_sql "SELECT run FROM ljgapd.jobs WHERE id = '$killed'")
kill -KILL "$A_PID"
wait "$A_PID" 2>/dev/null
t_kill=$(date +%s.%N)
reclaimed=
for _ in $(seq 1 $((20 * LEASE * SLOW))); do
    reclaimed=$(pg_sql "SELECT owner FROM ljgapd.jobs WHERE id = '$killed' AND run > $run_before")
    [ -n "$reclaimed" ] && break
    sleep 0.1
done
t_claim=$(elapsed "$t_kill")
check "instance b claims the killed job once its lease lapsed (${t_claim} s after the kill, lease $LEASE s)" \
    eval '[ "${reclaimed##*:}" = "$B_PID" ] && lt "$t_claim" $(((LEASE + 3) * SLOW))'
URL=$NGINX_URL
fails=0
check "every job ends done, the killed one too" until_done "${ids[@]}"
check "no request through nginx failed while an instance was dead ($fails not 200)" [ $fails = 0 ]
req GET "/v1/simulations/$killed"
jq .result "$tmp/body" >"$tmp/killed.json"
idx=0
for i in "${!ids[@]}"; do [ "${ids[$i]}" = "$killed" ] && idx=$i; done
job $((11 + idx)) >"$tmp/killed.req"
"$CLI" simulations "$tmp/killed.req" >"$tmp/cli.json" 2>/dev/null
check "the killed job ran again from the start under its id: the CLI's numbers" \
    jq_ok --slurpfile h "$tmp/killed.json" '($h[0] | del(.elapsed_ms, .meta.elapsed_ms))
        == del(.elapsed_ms, .meta.elapsed_ms)' "$tmp/cli.json"
check "the job store counted the lost run" \
    eval '[ "$(pg_sql "SELECT lost FROM ljgapd.jobs WHERE id = '"'$killed'"'")" = 1 ]'

# ================= a cancel through nginx reaches the job on the other instance =================
if startd a2 --port "$A_PORT"; then
    A_PID=$PID
else
    echo "not ok - scaleout: instance a did not start again: $(head -c 300 "$tmp/a2.err")"
fi
URL=$NGINX_URL
submit "$LONG"
long=$ID
runner=
for _ in $(seq 1 $((100 * SLOW))); do
    owner=$(pg_sql "SELECT owner FROM ljgapd.jobs WHERE id = '$long' AND state = 'running'")
    [ "${owner##*:}" = "$A_PID" ] && runner=a
    [ "${owner##*:}" = "$B_PID" ] && runner=b
    [ -n "$runner" ] && break
    sleep 0.1
done
check "the long job runs on an instance ($runner)" [ -n "$runner" ]
other=a
[ "$runner" = a ] && other=b
# nginx's round robin is strict with one worker: probe until two probes went to different
# instances, then send the DELETE where the next request goes, the instance not running it
last=none prev=none
for n in $(seq 1 $((20 * SLOW))); do
    req GET /healthz -H "X-Request-Id: rr-$n"
    prev=$last
    last=$(served_by "rr-$n")
    [ "$prev" != none ] && [ "$last" != none ] && [ "$prev" != "$last" ] && break
    sleep 0.3
done
if [ "$last" = "$other" ]; then req GET /healthz -H "X-Request-Id: rr-extra"; fi
t0=$(date +%s.%N)
req DELETE "/v1/simulations/$long" -H 'X-Request-Id: cancel-1'
check "DELETE through nginx answered by the instance not running the job ($other): $STATUS" \
    eval '[ "$(served_by cancel-1)" = "$other" ] && { [ "$STATUS" = 200 ] || [ "$STATUS" = 202 ]; }'
check "the job running on $runner ends cancelled ($(elapsed "$t0") s after the DELETE)" \
    wait_state "$long" cancelled

# ================= rows damaged by hand (psql) =================
submit "$SMALL"
damaged_id=$ID
wait_state "$damaged_id" done
pg_sql "ALTER TABLE ljgapd.jobs DROP CONSTRAINT IF EXISTS jobs_state_check;
        ALTER TABLE ljgapd.jobs DROP CONSTRAINT IF EXISTS jobs_progress_check" >/dev/null
damage() { # damage SET-CLAUSE: the job's row changed with psql, then read through nginx
    pg_sql "UPDATE ljgapd.jobs SET $1 WHERE id = '$damaged_id'" >/dev/null
    req GET "/v1/simulations/$damaged_id"
}
is_damaged() {
    [ "$STATUS" = 200 ] && json '.status == "failed" and (.problem.type | endswith("/problems/job-damaged"))
        and .problem.status == 500 and (.result == null)'
}
damage "state = 'weird'"
check "psql: an unknown state is shown as failed, job-damaged" is_damaged
damage "state = 'done', answer = '{\"sigma\": [1, 2'"
check "psql: a result that is not JSON: failed, job-damaged" is_damaged
damage "state = 'done', answer = '{\"sigma\": 1e999}'"
check "psql: a number that is not finite: failed, job-damaged" is_damaged
damage "state = 'failed', answer = '{\"type\":\"about:blank\"}'"
check "psql: a problem that is not ours: failed, job-damaged" is_damaged
damage "state = 'done', answer = '{\"x\": 1}', progress = 'NaN', created = 'infinity', started = '-infinity'"
check "psql: NaN progress and infinite times: done, progress 1, no such times shown" \
    eval '[ "$STATUS" = 200 ] && json ".status == \"done\" and .progress == 1 and .created == null
        and .started == null and .elapsed_ms == 0 and .result.x == 1"'

# ================= the database goes away and comes back =================
submit "$(job 21)"
during=$ID
wait_state "$during" running
pg_stop fast
worst=0 bad=0
for n in 1 2 3 4 5; do
    t0=$(date +%s.%N)
    req GET "/v1/simulations/$during"
    t=$(elapsed "$t0")
    lt "$worst" "$t" && worst=$t
    { [ "$STATUS" = 503 ] && json '.type | endswith("/problems/job-store")' &&
        [[ "$(hdr Retry-After)" =~ ^[0-9]+$ ]]; } || bad=$((bad + 1))
done
check "database stopped: GET of a job answers 503 job-store with Retry-After, within ${worst} s" \
    eval '[ $bad = 0 ] && lt "$worst" $((1 * SLOW))'
t0=$(date +%s.%N)
submit "$SMALL"
check "database stopped: POST /v1/simulations answers 503 at once ($(elapsed "$t0") s)" \
    eval '[ "$STATUS" = 503 ] && json ".type | endswith(\"/problems/job-store\")"'
req POST /v1/adhesion -H 'Content-Type: application/json' --data-binary "{$PSD,\"tol\":1e-5}"
check "database stopped: synchronous endpoints still answer (POST /v1/adhesion 200)" \
    eval '[ "$STATUS" = 200 ] && json ".g_eq > 0"'
req GET /healthz
check "database stopped: /healthz 200" [ "$STATUS" = 200 ]
sleep 1
pg_start
# no request for 3 s: the instances' job workers, which look at the store every second, make
# them reconnect (a failed connection is tried again after a second)
sleep $((3 * SLOW))
code() { curl -s -o /dev/null -w '%{http_code}' --max-time 5 "$1/v1/simulations/$during"; }
check "database back: both instances reconnected by themselves (the first GET through each: 200)" \
    eval '[ "$(code "$A_URL")" = 200 ] && [ "$(code "$B_URL")" = 200 ]'
URL=$NGINX_URL
check "the job that ran while the database was away ends done" wait_state "$during" done
submit "$SMALL"
check "a new job through nginx after the restart ends done" eval '[ "$STATUS" = 202 ] && wait_state "$ID" done'

# ================= start-up errors =================
closed=$(free_port)
refused() { # refused WHY ARGS...: ljgapd ARGS exits 2 before listening, saying WHY, no password
    local why=$1
    shift
    timeout $((20 * SLOW)) "$BIN" --port 0 "$@" >"$tmp/refused.out" 2>"$tmp/refused.err"
    local rc=$?
    if [ "$rc" = 2 ] && grep -qF -- "$why" "$tmp/refused.err" && ! grep -q s3cretpw "$tmp/refused.err" &&
        ! grep -q listening "$tmp/refused.out"; then
        return 0
    fi
    echo "# exit $rc: $(head -c 300 "$tmp/refused.err")"
    return 1
}
check "the database unreachable at start: exit 2 with the reason, the URL without its password" \
    refused "postgresql://ljgap@127.0.0.1:$closed/ljgap: connection to server at \"127.0.0.1\", port $closed failed: Connection refused" \
    --jobs-db "postgresql://ljgap:s3cretpw@127.0.0.1:$closed/ljgap"
check "a database that does not exist: exit 2, 'does not exist'" \
    refused 'database "nope" does not exist' --jobs-db "${PGURL%/*}/nope"
check "--jobs-db with another scheme: exit 2, the URL not echoed" \
    refused "wants a postgresql://" --jobs-db "mysql://root:s3cretpw@127.0.0.1/x"
check "--jobs-db with --state-dir: exit 2" refused "exclude each other" --jobs-db "$PGURL" \
    --state-dir "$tmp/state"

# ================= stopping =================
for n in a2 b; do
    p=$A_PID
    [ $n = b ] && p=$B_PID
    kill -TERM "$p"
    wait "$p"
    check "instance $n stops on SIGTERM with exit 0${WRAP:+ (no leak under valgrind)}" [ $? = 0 ]
done
