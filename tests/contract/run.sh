#!/usr/bin/env bash
# The contract test: live answers of ljgapd against server/openapi.json (tests/contract/run.mjs:
# every path, method, status and media type the document declares, the declared headers, the
# examples of openapi.json and docs/api.md), with the validators of tests/contract/package.json
# (installed by make test: mk/contract.mk). One "ok"/"not ok" line per check.
#   BUILD=build tests/contract/run.sh
set -u
cd "$(dirname "$0")/../.."
. tests/lib/daemon.sh # tmp, pids, cleanup; check, start

missing=""
command -v node >/dev/null || missing="$missing node"
[ -d tests/contract/node_modules/ajv ] || missing="$missing tests/contract/node_modules"
[ -x "$BIN" ] || missing="$missing $BIN"
if [ -n "$missing" ]; then
    echo "not ok - contract test: missing$missing (make test installs and builds them)"
    exit 1
fi

mkdir -p "$tmp/emptyweb"
if ! start web --web "$tmp/emptyweb"; then
    echo "not ok - ljgapd --web did not start: $(head -c 300 "$tmp/web.err")"
    exit 1
fi
WEB_URL=$URL
WEB_PID=$PID
if ! start mem --max-memory 64M; then
    echo "not ok - ljgapd --max-memory 64M did not start: $(head -c 300 "$tmp/mem.err")"
    exit 1
fi
MEM_URL=$URL
MEM_PID=$PID
# one job worker and one waiting job: the third is refused (503); 64 connections for the
# shutdown's prepared connections
if ! start main --compute-slots 2 --job-workers 1 --job-queue 1 --client-connections 64; then
    echo "not ok - ljgapd did not start: $(head -c 300 "$tmp/main.err")"
    exit 1
fi
URL=$URL PID=$PID ERR=$tmp/main.err WEB_URL=$WEB_URL MEM_URL=$MEM_URL ROOT=$PWD timeout 120 \
    node tests/contract/run.mjs
rc=$?
# run.mjs stopped the main daemon with SIGTERM: it exits 0 within its 10 s
for _ in $(seq 1 200); do kill -0 "$PID" 2>/dev/null || break; sleep 0.05; done
wait "$PID"
check "ljgapd exits 0 after the SIGTERM of the shutdown checks" [ $? = 0 ]
kill -TERM "$WEB_PID" "$MEM_PID"
wait "$WEB_PID" "$MEM_PID"
[ "$rc" = 0 ] || [ "$rc" = 1 ] || echo "not ok - node tests/contract/run.mjs exited with status $rc"
