#!/usr/bin/env bash
# Durable simulation jobs through build/ljgapd --state-dir (SQLite): SIGKILL in the middle of a
# job, restart on the same directory, and the job completes under its id with the numbers an
# uninterrupted run gives (the CLI's); a finished job's status is byte-identical across the
# restart; a queued job survives too; SIGTERM puts the running job back and the next start runs
# it; and every start-up error of the state directory is exit status 2 with a message naming
# the path and the reason (unwritable, uncreatable, corrupt, in use, none at all), while the
# default directory ($STATE_DIRECTORY) is used without the flag.
# One "ok ..." / "not ok ..." line per check (summed by tests/run.sh).
#   BUILD=build/h-durable tests/durable/run.sh
set -u
cd "$(dirname "$0")/../.."
SLOW_WRAPPED=10 # the time bounds' multiplier under WRAP

CHECK_PREFIX="durable: "
. tests/lib/daemon.sh # tmp, pids, cleanup; check, start, req, hdr, json, elapsed, lt
. tests/lib/jobs.sh   # submit, wait_for, wait_state, jq_ok

STATE=$tmp/state
stop() { # stop SIGNAL: stop the daemon $PID with SIGNAL, wait for it; sets RC
    kill "-$1" "$PID" 2>/dev/null
    wait "$PID" 2>/dev/null
    RC=$?
}
# refused NAME WHY ARGS...: ljgapd ARGS exits 2 before listening, naming $tmp/NAME and WHY
refused() {
    local name=$1 why=$2
    shift 2
    timeout $((20 * SLOW)) "$@" --port 0 >"$tmp/refused.out" 2>"$tmp/refused.err"
    local rc=$?
    if [ "$rc" = 2 ] && grep -qF "$tmp/$name" "$tmp/refused.err" &&
        grep -qF "$why" "$tmp/refused.err" && ! grep -q listening "$tmp/refused.out"; then
        return 0
    fi
    echo "# exit $rc: $(head -c 300 "$tmp/refused.err")"
    return 1
}

PSD='"psd":{"kind":"power","D":2.2,"k1":1,"k2":8,"m0":0.1}'
SMALL="{$PSD,\"n\":32,\"realizations\":2,\"seed\":7,\"g_ave\":[2,3,4]}"
QUEUED="{$PSD,\"n\":32,\"realizations\":2,\"seed\":8,\"g_ave\":[2,3]}"
# about 2.5 s of work on one core: killed in the middle, then run again in full
MEDIUM="{$PSD,\"n\":256,\"realizations\":4,\"seed\":3,\"g_ave\":{\"min\":1.2,\"max\":4,\"n\":40}}"
# about 0.7 s
SHORT="{$PSD,\"n\":256,\"realizations\":2,\"seed\":3,\"g_ave\":{\"min\":1.2,\"max\":4,\"n\":20}}"

# ================= SIGKILL in the middle of a job =================
if ! start first --state-dir "$STATE" --job-workers 1 --job-queue 4; then
    echo "not ok - durable: ljgapd did not start: $(head -c 300 "$tmp/first.err")"
    exit 1
fi
check "the log names the job store" grep -qF "jobs kept in $STATE/jobs.sqlite" "$tmp/first.err"
submit "$SMALL"
small=$ID
check "a small job ends done" wait_for "$small" '.status == "done"'
cp "$tmp/body" "$tmp/small.before"
check "its status has created, started and finished times (RFC 3339 UTC)" json '
    [.created, .started, .finished] | all(test("^[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9:]{8}\\.[0-9]{3}Z$"))'
submit "$MEDIUM"
medium=$ID
check "a longer job runs and makes progress" wait_for "$medium" \
    '.status == "running" and .progress > 0'
submit "$QUEUED"
queued=$ID
check "a third job waits behind it" json '.status == "queued"'
stop KILL
check "SIGKILL ends ljgapd (status 137)" eval '[ "$RC" = 137 ]'

if ! start second --state-dir "$STATE" --job-workers 1 --job-queue 4; then
    echo "not ok - durable: ljgapd did not restart: $(head -c 300 "$tmp/second.err")"
    exit 1
fi
check "restarted on the same --state-dir: the log counts 2 queued jobs" \
    grep -qF "(2 queued)" "$tmp/second.err"
req GET "/v1/simulations/$small"
cp "$tmp/body" "$tmp/small.after"
check "the finished job's status is byte-identical after the restart" \
    eval '[ "$STATUS" = 200 ] && cmp -s "$tmp/small.before" "$tmp/small.after"'
check "the killed job runs again and completes under its id" wait_for "$medium" \
    '.status == "done" and .progress == 1'
cp "$tmp/body" "$tmp/medium.json"
check "its id is the one given at submission" json --arg id "$medium" '.id == $id'
echo "$MEDIUM" >"$tmp/medium.req"
"$CLI" simulations "$tmp/medium.req" >"$tmp/cli.json" 2>"$tmp/cli.err"
check "its result is the uninterrupted run's (the CLI's, same seed): run from the start" \
    jq_ok --slurpfile h "$tmp/medium.json" '($h[0].result | del(.elapsed_ms, .meta.elapsed_ms))
        == del(.elapsed_ms, .meta.elapsed_ms)' "$tmp/cli.json"
check "the job queued at the kill completes too" wait_for "$queued" '.status == "done"'

# ================= SIGTERM: the running job goes back to the queue =================
submit "$SHORT"
short=$ID
wait_for "$short" '.status == "running"'
stop TERM
check "SIGTERM with a job running: exit 0" eval '[ "$RC" = 0 ]'
if start third --state-dir "$STATE"; then
    check "the next start runs the stopped job under its id" wait_for "$short" \
        '.status == "done"'
    # ---- a second daemon on the same directory is refused ----
    check "a second ljgapd on the same --state-dir: exit 2, 'in use by another process (pid N)'" \
        refused state "in use by another process (pid $PID" "$BIN" --state-dir "$STATE"
    stop TERM
else
    echo "not ok - durable: ljgapd did not start a third time: $(head -c 300 "$tmp/third.err")"
fi

# ================= state directories that cannot be used: exit 2 =================
mkdir "$tmp/ro" && chmod 0555 "$tmp/ro"
if [ "$(id -u)" = 0 ]; then
    # root writes anywhere: run as nobody, who may pass through $tmp but not write in ro/
    chmod 0711 "$tmp"
    AS=(setpriv --reuid=65534 --regid=65534 --clear-groups)
    if ! "${AS[@]}" test -x "$BIN"; then
        echo "not ok - durable: nobody cannot run $BIN (a parent directory is closed to others)"
    fi
else
    AS=()
fi
check "an unwritable state directory: exit 2 naming the path, 'not writable'" \
    refused ro "not writable" "${AS[@]}" "$BIN" --state-dir "$tmp/ro"
check "one that cannot be created: exit 2 naming the path, 'Permission denied'" \
    refused ro/sub "Permission denied" "${AS[@]}" "$BIN" --state-dir "$tmp/ro/sub"
: >"$tmp/file"
check "one under a regular file: exit 2 naming the path, 'Not a directory'" \
    refused file/state "Not a directory" "$BIN" --state-dir "$tmp/file/state"
mkdir "$tmp/corrupt" && head -c 8192 /dev/urandom >"$tmp/corrupt/jobs.sqlite"
check "a corrupt jobs.sqlite: exit 2 naming it, 'not a database'" \
    refused corrupt/jobs.sqlite "not a database" "$BIN" --state-dir "$tmp/corrupt"
check "no --state-dir and no default (no HOME, XDG_STATE_HOME, STATE_DIRECTORY): exit 2" eval '
    env -u HOME -u XDG_STATE_HOME -u STATE_DIRECTORY "$BIN" --port 0 >/dev/null 2>"$tmp/nodef.err";
    [ $? = 2 ] && grep -q "no state directory" "$tmp/nodef.err"'
check "--state-dir '': exit 2" eval '"$BIN" --state-dir "" >/dev/null 2>&1; [ $? = 2 ]'

# ================= the default: systemd's STATE_DIRECTORY =================
if NO_STATE_DIR=1 STATE_DIRECTORY="$tmp/systemd:$tmp/other" start default; then
    check "without --state-dir, \$STATE_DIRECTORY (its first path) holds the jobs" eval '
        grep -qF "jobs kept in $tmp/systemd/jobs.sqlite" "$tmp/default.err" &&
        [ -f "$tmp/systemd/jobs.sqlite" ] && [ ! -e "$tmp/other" ]'
    stop TERM
else
    echo "not ok - durable: ljgapd did not start with STATE_DIRECTORY: $(head -c 300 "$tmp/default.err")"
fi
check "--help explains --state-dir" eval '"$BIN" --help | grep -q -- "--state-dir DIR"'
