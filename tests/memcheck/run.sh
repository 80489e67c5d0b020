#!/usr/bin/env bash
# The daemon under valgrind memcheck: the whole curl suite (tests/http/run.sh), the bad-input
# catalogue (tests/bad_inputs/run.sh), the lab-server suite (tests/serve/run.sh: suspended
# connections, hang-ups, expiry, floods; all but its fairness timing), the simulation jobs
# suite (tests/jobs/run.sh: the job runner and its SQLite store) and the scale-out suite
# (tests/scaleout/run.sh: the PostgreSQL store's unit tests, two daemons on it behind nginx, one
# killed, the database stopped and started again; with smaller jobs) again, with every daemon
# they start (and there the unit tests) wrapped in
#   valgrind --leak-check=full --errors-for-leak-kinds=definite,indirect --error-exitcode=99
# Each daemon is stopped by SIGTERM; the suites check that it exits 0, which under this wrapper
# means no memory error and no definite or indirect leak (and the curl suite's main server
# must free every heap block). Their "ok"/"not ok" lines are repeated with a "memcheck:" prefix.
# It takes about four and a half minutes (valgrind is ~30 times slower: the suites' time bounds
# relax).
#   BUILD=build/h-harden tests/memcheck/run.sh      (also: make memcheck)
# Valgrind cannot run sanitizer builds: there (SANITIZE=...) this says so in a comment line and
# checks nothing; the sanitizers check the same suites in that build.
set -u
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
BIN=$BUILD/ljgapd
if [ ! -x "$BIN" ]; then
    echo "not ok - memcheck: $BIN is not built"
    exit 1
fi
if nm "$BIN" 2>/dev/null | grep -q '__asan_init\|__ubsan_handle'; then
    echo "# memcheck: $BIN is a sanitizer build; valgrind is not run on it"
    exit 0
fi
if ! command -v valgrind >/dev/null; then
    echo "not ok - memcheck: valgrind is not installed (make deps installs it)"
    exit 1
fi
export BUILD
export WRAP="valgrind --fair-sched=yes --leak-check=full --show-leak-kinds=definite,indirect \
--errors-for-leak-kinds=definite,indirect --error-exitcode=99"
for suite in tests/http/run.sh tests/bad_inputs/run.sh tests/serve/run.sh tests/jobs/run.sh \
    tests/scaleout/run.sh; do
    "$suite" 2>&1 | sed -e 's/^ok - /ok - memcheck: /' -e 's/^not ok - /not ok - memcheck: /'
    rc=${PIPESTATUS[0]}
    [ "$rc" = 0 ] || echo "not ok - memcheck: $suite exited with status $rc"
done
