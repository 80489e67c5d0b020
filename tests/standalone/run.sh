#!/usr/bin/env bash
# The project on its own (issue 14): no tracked file names a path outside the repository; each
# make goal installs only what it needs (make run no test, benchmark or fuzzing tool); a
# clone of the repository alone, with nothing beside it, builds and serves its page; the daemon
# serves the compiled-in page with no flags (every file the page loads, the icon, ETag and 304)
# or a directory with --web DIR; every problem type openapi.json lists is a page of the running
# server. One "ok"/"not ok" line per check.
#   BUILD=build tests/standalone/run.sh
set -u
cd "$(dirname "$0")/../.."
ROOT=$PWD
BUILD=${BUILD:-build}
BIN=$ROOT/$BUILD/ljgapd
. tests/lib/daemon.sh # tmp, pids, cleanup; check, start, req, hdr, json

# ---- nothing outside the repository ----
# The team's notes and the paper's text sit beside the repository, in a directory named below;
# the pattern is put together here so that this file does not name those paths itself.
outside=shared
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    hits=$(git grep -n -I -E "$outside/(docs|seed)|\\.\\./$outside" -- . | head -n 5)
    check "no tracked file names a path outside the repository${hits:+ ($hits)}" [ -z "$hits" ]
else
    echo "not ok - not a git checkout: cannot list the tracked files"
fi

# ---- checks that can fail ----
# check DESC eval '... $? ...' tests the status of check's own shift, not the command before the
# check (always 0): such a check cannot fail. The suites keep the status in a variable instead.
dead=$(grep -n -E "eval +['\"] *\[ *\"?\\\$\?" tests/*.sh tests/*/*.sh bench/*.sh 2>/dev/null | head -n 3)
check "no shell check tests \$? inside its own eval${dead:+ ($dead)}" [ -z "$dead" ]

# ---- dependencies by goal: make run installs only what building and serving need ----
# What each goal would install (the Makefile's GOAL_DEBS.G and GOAL_CMDS.G, package names after
# the colon), printed by make itself without installing anything.
goal_pkgs() { # goal_pkgs G: the Debian packages goal G installs when they are missing
    env -u MAKEFLAGS -u MAKELEVEL make -s --no-print-directory -C "$ROOT" \
        --eval 'print-deps-%: ; @echo $(GOAL_DEBS.$*) $(foreach c,$(GOAL_CMDS.$*),$(word 2,$(subst :, ,$(c))))' \
        "print-deps-$1" | tr ' ' '\n' | sed '/^$/d' | sort -u
}
has_all() { # has_all LIST WORD...: every WORD is a line of LIST
    local w
    for w in "${@:2}"; do grep -qx -- "$w" <<<"$1" || return 1; done
}
has_none() { # has_none LIST WORD...: no WORD is a line of LIST
    local w
    for w in "${@:2}"; do grep -qx -- "$w" <<<"$1" && return 1; done
    return 0
}
run_deps=$(goal_pkgs run)
check "make run installs the build and serve libraries and npm only ($(echo $run_deps))" \
    eval 'has_all "$run_deps" libmicrohttpd-dev libcjson-dev libgsl-dev libfftw3-dev \
        libsqlite3-dev libpq-dev npm && has_none "$run_deps" chromium clang libclang-rt-14-dev \
        valgrind wrk gnuplot-nox libcmocka-dev postgresql postgresql-client nginx groff-base \
        python3-requests python3-pandas curl jq'
test_deps=$(goal_pkgs test)
check "make test adds the test tools (cmocka, chromium, valgrind, postgresql, nginx, groff, ...)" \
    eval 'has_all "$test_deps" $run_deps libcmocka-dev chromium valgrind postgresql nginx \
        groff-base python3-requests python3-pandas curl jq && has_none "$test_deps" clang wrk gnuplot-nox'
bench_deps=$(goal_pkgs bench)
check "make bench adds the benchmark tools (gnuplot, wrk, valgrind, jq, nginx), not the test ones" \
    eval 'has_all "$bench_deps" $run_deps gnuplot-nox wrk valgrind jq curl python3 nginx &&
        has_none "$bench_deps" chromium clang libcmocka-dev postgresql'
fuzz_deps=$(goal_pkgs fuzz)
check "make fuzz adds clang and its fuzzer runtime only" \
    eval 'has_all "$fuzz_deps" $run_deps clang libclang-rt-14-dev &&
        [ "$(comm -13 <(echo "$run_deps") <(echo "$fuzz_deps") | tr "\n" " ")" = "clang libclang-rt-14-dev " ]'
all_deps=$(goal_pkgs all)
check "make deps installs everything the other goals do" \
    eval '[ -z "$(comm -13 <(echo "$all_deps") <(printf "%s\n" $test_deps $bench_deps $fuzz_deps | sort -u))" ]'
# every command the benchmarks call is one make bench installs (or the base system has)
missing=""
for c in gnuplot valgrind wrk jq curl python3 nginx; do
    if grep -lqw -- "$c" bench/*.sh bench/run.sh 2>/dev/null &&
        ! env -u MAKEFLAGS -u MAKELEVEL make -s --no-print-directory -C "$ROOT" \
            --eval 'print-cmds: ; @echo $(GOAL_CMDS.bench)' print-cmds | tr ' ' '\n' |
            grep -q "^$c:"; then
        missing="$missing $c"
    fi
done
check "every tool bench/*.sh calls is one make bench installs${missing:+ (not:$missing)}" [ -z "$missing" ]

# ---- the page compiled in: started from an empty directory, no flags ----
mkdir -p "$tmp/empty"
cd "$tmp/empty"
if ! start embedded; then
    echo "not ok - ljgapd did not start: $(head -c 300 "$tmp/embedded.err")"
    exit 1
fi
cd "$ROOT"
req GET /
check "GET / with no --web, from an empty directory: the page (web/index.html)" \
    eval '[ "$STATUS" = 200 ] && [[ "$(hdr Content-Type)" == text/html* ]] &&
        cmp -s "$tmp/body" web/index.html'
# every local file the page loads (src= and href=), and the icon browsers ask for by themselves
refs=$(grep -o -E '(src|href)="[^"#:]+"' web/index.html | sed -E 's/^(src|href)="//; s/"$//' |
    grep -v '^/openapi.json$' | sort -u)
bad=""
n=0
for f in $refs favicon.ico; do
    req GET "/${f#/}"
    n=$((n + 1))
    [ "$STATUS" = 200 ] && cmp -s "$tmp/body" "web/${f#/}" || bad="$bad $f($STATUS)"
done
check "every file the page loads ($n, icons included) is served with its bytes${bad:+ (not:$bad)}" \
    eval '[ -z "$bad" ] && [ "$n" -ge 8 ]'
req GET /favicon.ico
check "GET /favicon.ico: 200 image/x-icon (no 404 in the browser's console)" \
    eval '[ "$STATUS" = 200 ] && [ "$(hdr Content-Type)" = image/x-icon ]'
req GET /app.js
etag=$(hdr ETag)
check "compiled-in files carry an ETag and Cache-Control: no-cache" \
    eval '[[ "$etag" =~ ^\"[0-9a-f]{16}\"$ ]] && [ "$(hdr Cache-Control)" = no-cache ]'
rm -f "$tmp/body" # curl leaves an empty answer's file as it was
req GET /app.js -H "If-None-Match: $etag"
check "If-None-Match with the ETag: 304, no body" eval '[ "$STATUS" = 304 ] && [ ! -s "$tmp/body" ]'
req GET /app.js -H 'If-None-Match: "0000000000000000"'
check "another ETag: 200 with the file" eval '[ "$STATUS" = 200 ] && cmp -s "$tmp/body" web/app.js'
for p in /secret.txt /package.json /.x.js /vendor/deeper/x.js /../Makefile /%2e%2e/Makefile; do
    req GET "$p" --path-as-is
    check "GET $p: 404 problem" eval '[ "$STATUS" = 404 ] &&
        [ "$(hdr Content-Type)" = application/problem+json ]'
done

# ---- problem types are pages of this server ----
req GET /openapi.json
types=$(jq -r '.components.schemas.Problem.properties.type.enum[]' "$tmp/body")
bad=""
n=0
for t in $types; do
    n=$((n + 1))
    req GET "$t"
    [ "$STATUS" = 200 ] && [[ "$(hdr Content-Type)" == text/html* ]] &&
        grep -q "<h1>" "$tmp/body" && grep -q "How to fix the request" "$tmp/body" ||
        bad="$bad $t($STATUS)"
done
check "each of the $n problem types in openapi.json resolves to a page${bad:+ (not:$bad)}" \
    eval '[ -z "$bad" ] && [ "$n" -ge 12 ]'
req GET /problems/
check "GET /problems/: the list, linking every type" eval '[ "$STATUS" = 200 ] &&
    [ "$(grep -c "href=\"/problems/[a-z-]*\"" "$tmp/body")" -ge "$n" ]'
req GET /problems/no-such-type
check "GET /problems/no-such-type: 404 problem" \
    eval '[ "$STATUS" = 404 ] && json ".type == \"/problems/not-found\""'
req POST /v1/adhesion -H 'Content-Type: application/json' -d '{"psd":{"kind":"power","D":2.5,"k1":0.3,"m0":0.5}}'
type=$(jq -r .type "$tmp/body")
req GET "$type"
check "a 422's type ($type) is a page of the server that sent it" \
    eval '[ "$STATUS" = 200 ] && grep -q "Invalid request" "$tmp/body"'
req POST /v1/adhesion -H 'Content-Type: text/plain' -d '{}'
type=$(jq -r .type "$tmp/body")
req GET "$type"
check "a 415's type ($type) is a page of the server that sent it" eval '[ "$STATUS" = 200 ]'
kill -TERM "$PID"
wait "$PID"

# ---- --web DIR serves a directory instead ----
mkdir -p "$tmp/web"
echo '<!doctype html><title>ljgap</title><p>edited' >"$tmp/web/index.html"
if start webdir --web "$tmp/web"; then
    req GET /
    check "--web DIR: GET / serves DIR/index.html" cmp -s "$tmp/body" "$tmp/web/index.html"
    req GET /app.js
    check "--web DIR: a file DIR lacks is 404 (the compiled-in copy is not mixed in)" \
        [ "$STATUS" = 404 ]
    kill -TERM "$PID"
    wait "$PID"
else
    echo "not ok - ljgapd --web DIR did not start"
fi

# ---- a clone of the repository alone builds and serves ----
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    mkdir -p "$tmp/alone"
    if git clone -q --no-hardlinks "$ROOT" "$tmp/alone/ljgap" 2>"$tmp/clone.err" &&
        env -u MAKEFLAGS -u MAKELEVEL nice make -s -C "$tmp/alone/ljgap" -j2 programs SANITIZE= BUILD=build \
            >"$tmp/clone.log" 2>&1; then
        echo "ok - a clone of the committed tree alone (nothing beside it) builds its programs"
        BIN=$tmp/alone/ljgap/build/ljgapd
        cd "$tmp/empty"
        if start clone; then
            req GET /
            check "the clone's ljgapd serves its page" eval '[ "$STATUS" = 200 ] &&
                grep -q "<title>ljgap</title>" "$tmp/body"'
            req GET /vendor/uPlot.iife.min.js
            check "... with uPlot from npm compiled in" \
                eval '[ "$STATUS" = 200 ] && [ "$(wc -c <"$tmp/body")" -gt 10000 ]'
            req POST /v1/adhesion -H 'Content-Type: application/json' \
                -d '{"psd":{"kind":"power","D":2.5,"k1":1,"m0":0.5}}'
            check "... and computes (Fig. 4: g_eq 2.6028)" \
                json '(.g_eq - 2.6028 | fabs) < 1e-4'
            kill -TERM "$PID"
            wait "$PID"
        else
            echo "not ok - the clone's ljgapd did not start"
        fi
        cd "$ROOT"
    else
        echo "not ok - a clone of the committed tree alone does not build: $(tail -c 400 \
            "$tmp/clone.err" "$tmp/clone.log")"
    fi
fi
