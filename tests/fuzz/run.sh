#!/usr/bin/env bash
# Replays the fuzz corpus (tests/fuzz/corpus: seeds and every crasher found so far) through
# the fuzz target's contract checks, with the normal compiler's build of it ($BUILD/fuzz/replay,
# made by make test; sanitizers too in a SANITIZE= build). One "ok"/"not ok" line per input.
#   BUILD=build/h-harden tests/fuzz/run.sh
set -u
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
bin=$BUILD/fuzz/replay
if [ ! -x "$bin" ]; then
    echo "not ok - $bin is not built (make test builds it)"
    exit 1
fi
"$bin" tests/fuzz/corpus
rc=$?
# a sanitizer report or a crash ends the driver early: say so (a contract breach gives 1)
[ "$rc" -le 1 ] || echo "not ok - $bin ended with status $rc (see the report above)"
exit 0
