#!/usr/bin/env bash
# Replays the fuzz corpora (tests/fuzz/corpus: seeds and every crasher found so far; and
# tests/fuzz/files_corpus, the instrument files' seeds, through fuzz_files.c) through
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
# the instrument files' target over its seeds (valid and truncated files of each format)
files=$BUILD/fuzz/replay_files
if [ ! -x "$files" ]; then
    echo "not ok - $files is not built (make test builds it)"
    exit 1
fi
"$files" tests/fuzz/files_corpus
rc=$?
[ "$rc" -le 1 ] || echo "not ok - $files ended with status $rc (see the report above)"
exit 0
