#!/usr/bin/env bash
# The source layout holds (issue 27, docs/source.md): no include cycle between the modules of
# core/, include/ and server/, no upward include (core/ of server/; server/api/ of jobs/, the
# daemon or the CLI; server/jobs/ of the daemon or the CLI), no source file over 900 lines and
# no folder over 16 .c files, and no internal name with the public prefix ljgap_ (tests/layout/check.py). One "ok"/"not ok" line per check; then
# each check is shown to fail on a scratch tree that breaks it.
set -u
cd "$(dirname "$0")/../.."
python3 tests/layout/check.py cycles
python3 tests/layout/check.py sizes
python3 tests/layout/check.py names

# the checks can fail: a copy of the tree with a cycle, an upward include, a long file, a full
# folder
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/tests/layout"
cp tests/layout/check.py "$tmp/tests/layout/"
cp -r core include server tools "$tmp/"
broken() { # broken CHECK: the check's output on the broken copy
    python3 "$tmp/tests/layout/check.py" "$1"
}
echo '#include "handler.h"' >>"$tmp/server/api/reply.h"
echo '#include "daemon.h"' >>"$tmp/server/api/csv.c"
out=$(broken cycles)
if grep -q '^not ok - no include cycle.*reply' <<<"$out" && grep -q '^not ok - no upward include.*csv.c' <<<"$out"; then
    echo "ok - the layout checks fail on a tree with an include cycle and an upward include"
else
    echo "not ok - the layout checks missed a cycle or an upward include: $out"
fi
seq 1 901 | sed 's|^|/* |; s|$| */|' >"$tmp/server/api/long.c"
for i in $(seq 1 17); do : >"$tmp/server/jobs/extra$i.c"; done
out=$(broken sizes)
if grep -q '^not ok - no source file over.*long.c' <<<"$out" && grep -q '^not ok - no folder over 16 .c files.*server/jobs' <<<"$out"; then
    echo "ok - the layout checks fail on a tree with a long file and a full folder"
else
    echo "not ok - the layout checks missed a long file or a full folder: $out"
fi
printf 'int ljgap_private_thing(void);\n' >>"$tmp/server/api/reply.h"
out=$(broken names)
if grep -q '^not ok - internal names.*ljgap_private_thing' <<<"$out"; then
    echo "ok - the names check fails on a tree with an internal name in the public prefix"
else
    echo "not ok - the names check missed an internal ljgap_ name: $out"
fi
