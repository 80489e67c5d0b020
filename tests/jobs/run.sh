#!/usr/bin/env bash
# Simulation jobs through build/ljgapd (POST/GET/DELETE /v1/simulations) and build/ljgap: a small
# job of the real numerical model end to end (202, Location, polling, every field finite, m0 per
# realization, traction close to the continuum answer far from contact, the CLI printing the same
# numbers), a hybrid job (k_split: its fine band's fields; at k_split = k1 the theory's numbers), cancel of a running and of a queued job, the full queue (503 + Retry-After), the
# time cap (failed with a problem), validation (422 with pointers), unknown ids (404), wrong
# methods (405), /healthz while a job runs, and SIGTERM with a job running.
# One "ok ..." / "not ok ..." line per check (summed by tests/run.sh).
#   BUILD=build/h-jobs tests/jobs/run.sh
#   WRAP="valgrind --leak-check=full --error-exitcode=99" tests/jobs/run.sh   (slow bounds relax)
set -u
cd "$(dirname "$0")/../.."
SLOW_WRAPPED=10 # the time bounds' multiplier under WRAP

CHECK_PREFIX="jobs: "
. tests/lib/daemon.sh # tmp, pids, cleanup; check, start, req, hdr, json, elapsed, lt
. tests/lib/jobs.sh   # submit, wait_for, wait_state, jq_ok

problem() { # problem STATUS: the last answer is an RFC 9457 problem with that status
    [ "$STATUS" = "$1" ] && [ "$(hdr Content-Type)" = application/problem+json ] &&
        json --argjson s "$1" '.status == $s and (.type | startswith("/problems/"))
            and (.title | type == "string") and (.detail | type == "string")'
}

PSD='"psd":{"kind":"power","D":2.2,"k1":1,"k2":8,"m0":0.1}'
SMALL="{$PSD,\"n\":32,\"realizations\":2,\"seed\":7,\"g_ave\":[2,3,4]}"
# minutes of work: stays running until cancelled
LONG="{$PSD,\"n\":256,\"realizations\":16,\"g_ave\":{\"min\":1.2,\"max\":4,\"n\":150}}"

# ================= one worker, a queue of two =================
if ! start main --job-workers 1 --job-threads 2 --job-queue 2 --compute-slots 1; then
    echo "not ok - jobs: ljgapd did not start: $(head -c 300 "$tmp/main.err")"
    exit 1
fi

# ---- a small job end to end ----
submit "$SMALL"
check "POST /v1/simulations: 202 with id, status and progress" eval '[ "$STATUS" = 202 ] &&
    [ "$(hdr Content-Type)" = application/json ] &&
    json ".status == \"queued\" or .status == \"running\" or .status == \"done\"" &&
    json "(.progress >= 0 and .progress <= 1) and (.id | test(\"^[0-9a-f]{32}$\"))"'
check "Location: /v1/simulations/ID" eval '[ "$(hdr Location)" = "/v1/simulations/$ID" ]'
small=$ID
check "the small job (n = 32, 2 realizations, 3 gaps) ends done" wait_state "$small" done failed
cp "$tmp/body" "$tmp/small.json"
check "GET: status done, progress 1, elapsed_ms, no problem" json '.status == "done" and
    .progress == 1 and .elapsed_ms >= 0 and .problem == null'
check "result: g_ave as asked, sigma, sigma_std, sigma_out, error.sigma, residual: 3 finite each" \
    json '.result as $r | $r.g_ave == [2,3,4] and
    ([$r.sigma, $r.sigma_std, $r.sigma_out, $r.error.sigma, $r.residual] |
     all(length == 3 and all(type == "number")))
    and ($r.sigma_std | all(. >= 0)) and ($r.error.sigma | all(. >= 0))
    and ($r.residual | all(. >= 0)) and ($r.jump | length == 3 and all(type == "boolean"))'
check "result: m0_realized, one per realization, equal to m0 = 0.1 (scaled to the PSD's m0)" \
    json '.result | (.m0_realized | length == 2) and .m0 == 0.1 and
    (.m0_realized | all(. - 0.1 | fabs < 1e-9))'
check "result: grid, L = 2π/k1, realizations, seed, elapsed_ms, m0_grid" json '.result |
    .n == 32 and (.L - 6.283185307179586 | fabs < 1e-12) and .realizations == 2 and .seed == 7
    and .elapsed_ms >= 0 and .m0_grid > 0'
check "result: meta (method numerical, version, warnings)" json '.result.meta |
    .method == "numerical" and (.version | type == "string") and (.warnings | type == "array")
    and .elapsed_ms >= 0'
check "sigma falls with the gap on the tensile side (0 < sigma[2] < sigma[1] < sigma[0])" \
    json '.result.sigma | .[0] > .[1] and .[1] > .[2] and .[2] > 0'
# Far from contact the discrete model and the statistical theory (method pde) agree closely.
req POST /v1/traction -H 'Content-Type: application/json' --data-binary "{$PSD,\"g_ave\":[3,4]}"
cp "$tmp/body" "$tmp/traction.json"
check "sigma at g_ave = 3 and 4 within 2 % of POST /v1/traction (the continuum theory)" \
    jq_ok --slurpfile t "$tmp/traction.json" '[.result.sigma[1:3], $t[0].sigma] | transpose |
        all(((.[0] - .[1]) | fabs) < 0.02 * (.[1] | fabs))' "$tmp/small.json"
req HEAD "/v1/simulations/$small"
check "HEAD /v1/simulations/ID: 200" eval '[ "$STATUS" = 200 ]'

# ---- the CLI runs the same job in the foreground: the same numbers ----
echo "$SMALL" >"$tmp/small.req"
"$CLI" simulations "$tmp/small.req" >"$tmp/cli.json" 2>"$tmp/cli.err"
rc=$?
check "CLI simulations: exit 0, one line" eval '[ $rc = 0 ] && [ "$(wc -l <"$tmp/cli.json")" = 1 ]'
check "CLI prints the result object of the HTTP job (same seed, same numbers)" \
    jq_ok --slurpfile h "$tmp/small.json" '($h[0].result | del(.elapsed_ms, .meta.elapsed_ms))
        == del(.elapsed_ms, .meta.elapsed_ms)' "$tmp/cli.json"

# ---- a hybrid job: the fine band (k_split, k2] through its law; k_split = k1 is the theory ----
submit "{$PSD,\"n\":16,\"realizations\":2,\"k_split\":3,\"g_ave\":[1.5,3]}"
check "a hybrid job (k_split = 3 on 16 points) ends done" wait_state "$ID" done failed
check "hybrid result: k_split, the fine band's m0 and its law's g_eq, sigma_max, dgamma_eff with errors" json '.result as $r | $r.k_split == 3 and ($r.sigma | length == 2) and
    ($r.fine | (.m0 - 0.01416 | fabs) < 1e-4 and .g_eq > 1 and .sigma_max < 1 and
     .dgamma_eff < 1 and (.error | .g_eq >= 0 and .sigma_max >= 0 and .dgamma_eff >= 0)
     and .law_error >= 0) and ($r.m0_realized | all(. - 0.08584 | fabs < 1e-4))'
submit "{$PSD,\"n\":8,\"realizations\":2,\"k_split\":1,\"g_ave\":[1.5,3]}"
check "a hybrid job at k_split = k1 ends done" wait_state "$ID" done failed
cp "$tmp/body" "$tmp/alone.json"
req POST /v1/traction -H 'Content-Type: application/json' --data-binary "{$PSD,\"g_ave\":[1.5,3]}"
check "k_split = k1 is the theory alone: sigma = POST /v1/traction within the errors" \
    jq_ok --slurpfile t "$tmp/body" '[.result.sigma, .result.error.sigma, $t[0].sigma,
        $t[0].error.sigma] | transpose | all(((.[0] - .[2]) | fabs) <= .[1] + .[3])' \
    "$tmp/alone.json"

# ---- cancel a running job ----
submit "$LONG"
long=$ID
check "a long job starts running" wait_state "$long" running
sleep 0.3
t0=$(date +%s.%N)
req DELETE "/v1/simulations/$long"
dt=$(elapsed "$t0")
check "DELETE a running job: 200 cancelled within ${dt} s (< 3 s), problem unavailable" eval '
    [ "$STATUS" = 200 ] && json ".status == \"cancelled\" and
        (.problem.type | endswith(\"/unavailable\"))" && lt "$dt" $((3 * SLOW))'
req GET "/v1/simulations/$long"
check "GET after DELETE: cancelled, progress below 1" \
    json '.status == "cancelled" and .progress < 1 and .result == null'
req DELETE "/v1/simulations/$long"
check "DELETE again: 200, still cancelled" eval '[ "$STATUS" = 200 ] && json ".status == \"cancelled\""'

# ---- the queue: one running, two waiting, the next refused ----
submit "$LONG"
a=$ID
wait_state "$a" running
submit "$LONG"
b=$ID
submit "$LONG"
c=$ID
check "two more jobs wait: queued" eval '[ -n "$b" ] && [ -n "$c" ] && json ".status == \"queued\""'
t0=$(date +%s.%N)
req GET /healthz
hz=$(elapsed "$t0")
check "/healthz while a job runs: 200 in ${hz} s (< 2 s)" \
    eval '[ "$STATUS" = 200 ] && lt "$hz" $((2 * SLOW))'
submit "$LONG"
check "a fourth job with the queue full: 503 problem busy with Retry-After" eval 'problem 503 &&
    json ".type | endswith(\"/busy\")" && [[ "$(hdr Retry-After)" =~ ^[0-9]+$ ]]'
req DELETE "/v1/simulations/$b"
check "DELETE a queued job: 200 cancelled at once, never ran (elapsed_ms 0)" eval '
    [ "$STATUS" = 200 ] && json ".status == \"cancelled\" and .elapsed_ms == 0 and .progress == 0"'
submit "$SMALL"
check "its place in the queue is free again: 202" eval '[ "$STATUS" = 202 ]'
d=$ID
req DELETE "/v1/simulations/$a"
check "cancel the running one: the next queued job starts" wait_state "$c" running
req DELETE "/v1/simulations/$c"
check "and the small one behind it is done" wait_state "$d" done

# ---- validation: 422 with a pointer per bad field ----
bad() { # bad DESCRIPTION BODY POINTER...: 422 validation with exactly these pointers
    local desc=$1 body=$2
    shift 2
    local want
    want=$(printf '%s\n' "$@" | jq -R . | jq -cs 'sort')
    submit "$body"
    check "422 $desc at $*" eval 'problem 422 && json ".type | endswith(\"/validation\")" &&
        [ "$(jq -c "[.errors[].pointer] | sort" "$tmp/body")" = "$want" ]'
}
G='"g_ave":[2]'
bad "odd n" "{$PSD,\"n\":33,$G}" /n
bad "n below 8" "{$PSD,\"n\":4,$G}" /n
bad "n over 512" "{$PSD,\"n\":1024,$G}" /n
bad "17 realizations" "{$PSD,\"realizations\":17,$G}" /realizations
bad "negative seed" "{$PSD,\"seed\":-1,$G}" /seed
bad "tol 1" "{$PSD,\"tol\":1,$G}" /tol
bad "L below 2π/k1" "{$PSD,\"L\":1,$G}" /L
bad "no k2 (the model needs a band-limited PSD)" \
    "{\"psd\":{\"kind\":\"power\",\"D\":2.2,\"k1\":1,\"m0\":0.1},$G}" /psd/k2
bad "a table with a tail" \
    "{\"psd\":{\"kind\":\"table\",\"k\":[1,4],\"P\":[1e-3,1e-5],\"tail\":{\"exponent\":-3}},$G}" \
    /psd/tail
bad "k1 below k0" "{\"psd\":{\"kind\":\"power\",\"D\":2.2,\"k1\":0.3,\"k2\":8,\"m0\":0.1},$G}" \
    /psd/k1
bad "no g_ave" "{$PSD}" /g_ave
bad "201 gaps in a range" "{$PSD,\"g_ave\":{\"min\":2,\"max\":4,\"n\":201}}" /g_ave/n
bad "201 gaps in a list" "{$PSD,\"g_ave\":[$(seq -s, 2 202)]}" /g_ave
bad "a negative gap" "{$PSD,\"g_ave\":[2,-1]}" /g_ave/1
bad "an unknown field and a method" "{$PSD,$G,\"method\":\"pde\",\"grid\":64}" /grid /method
bad "every field at once" \
    "{$PSD,\"n\":7,\"realizations\":0,\"seed\":0.5,\"tol\":0,\"g_ave\":\"x\"}" \
    /g_ave /n /realizations /seed /tol
submit "{$PSD,\"n\":16,\"g_ave\":[2],\"L\":12.566370614359172}"
check "k2 not resolved by the grid: 422 at /n naming the n that would do (32)" eval 'problem 422 &&
    json "[.errors[].pointer] == [\"/n\"] and (.errors[0].detail | test(\"n >= 32 \"))"'
submit "{\"psd\":{\"kind\":\"power\",\"D\":2.2,\"k1\":1,\"k2\":900,\"m0\":0.1},$G}"
check "k2 no grid up to 512 resolves: 422 at /psd/k2 naming the n it needs (1800)" eval '
    problem 422 && json "[.errors[].pointer] == [\"/psd/k2\"] and
        (.errors[0].detail | test(\"1800\"))"'
submit "{$PSD,$G"
check "malformed JSON: 400 problem" problem 400
req POST /v1/simulations -H 'Content-Type: text/plain' --data-binary "$SMALL"
check "text/plain: 415 problem" problem 415

# ---- ids and methods ----
req GET /v1/simulations/0123456789abcdef0123456789abcdef
check "GET an unknown id: 404 problem" problem 404
req DELETE /v1/simulations/nope
check "DELETE an unknown id: 404 problem" problem 404
req GET /v1/simulations
check "GET /v1/simulations: 405 with Allow: POST" eval 'problem 405 && [ "$(hdr Allow)" = POST ]'
req PUT "/v1/simulations/$small"
check "PUT /v1/simulations/ID: 405 with Allow: GET, HEAD, DELETE" \
    eval 'problem 405 && [ "$(hdr Allow)" = "GET, HEAD, DELETE" ]'
req GET /openapi.json
check "openapi: POST /v1/simulations answers 202, 422, 503; /{id} has GET and DELETE" \
    json '.paths["/v1/simulations"].post.responses | has("202") and has("422") and has("503")'
check "openapi: GET and DELETE /v1/simulations/{id} with 200 and 404" \
    json '.paths["/v1/simulations/{id}"] | (.get.responses | has("200") and has("404"))
        and (.delete.responses | has("200") and has("202") and has("404"))'

# ---- SIGTERM with a job running and one queued ----
submit "$LONG"
e=$ID
wait_state "$e" running
submit "$LONG"
t0=$(date +%s.%N)
kill -TERM "$PID"
wait "$PID"
rc=$?
down=$(elapsed "$t0")
check "SIGTERM with a job running: exit 0 in ${down} s (< 10 s)" \
    eval '[ "$rc" = 0 ] && lt "$down" $((10 * SLOW))'
check "the log says it stopped" grep -q "stopped" "$tmp/main.err"
if [ -n "$WRAP" ]; then
    summary=$(grep -E "in use at exit|ERROR SUMMARY" "$tmp/main.err" | cut -d' ' -f2- | tr '\n' ' ')
    check "valgrind: $summary" eval 'grep -q "All heap blocks were freed" "$tmp/main.err" &&
        grep -q "ERROR SUMMARY: 0 errors" "$tmp/main.err"'
fi

# ================= the time cap: a job over --job-seconds fails with a problem =================
if start capped --job-seconds 1; then
    submit "$LONG"
    check "a job over --job-seconds 1 ends failed" wait_state "$ID" failed cancelled done
    check "its problem is cap-exceeded (422) naming the cap" json '.status == "failed" and
        (.problem.type | endswith("/cap-exceeded")) and .problem.status == 422 and
        (.problem.detail | contains("1 s"))'
    kill -TERM "$PID"
    wait "$PID"
else
    echo "not ok - jobs: the capped server did not start"
fi
check "--job-workers 0 is refused with status 2" \
    eval '"$BIN" --job-workers 0 >/dev/null 2>&1; [ $? = 2 ]'
check "--help explains --job-queue" eval '"$BIN" --help | grep -q -- "--job-queue N"'
