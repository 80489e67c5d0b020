#!/usr/bin/env bash
# Runs every test program and suite, then prints the closing line
#   tests: N passed, N failed
# Unit tests are cmocka programs in $BUILD/tests/; shell suites (tests/*/run.sh other than this
# one) print one "ok ..." or "not ok ..." line per check, TAP style.
set -u
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
export BUILD
pass=0
fail=0
for t in "$BUILD"/tests/*; do
    [ -x "$t" ] && [ -f "$t" ] || continue
    out=$("$t" 2>&1)
    rc=$?
    printf '%s\n' "$out"
    p=$(printf '%s\n' "$out" | sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' | awk '{s+=$1} END {print s+0}')
    f=$(printf '%s\n' "$out" | sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' | awk '{s+=$1} END {print s+0}')
    if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then
        echo "not ok $t exited with status $rc"
        f=1
    fi
    pass=$((pass + p))
    fail=$((fail + f))
done
for s in tests/*/run.sh; do
    [ -x "$s" ] || continue
    out=$("$s" 2>&1)
    rc=$?
    printf '%s\n' "$out"
    p=$(printf '%s\n' "$out" | grep -c '^ok ')
    f=$(printf '%s\n' "$out" | grep -c '^not ok ')
    if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then
        echo "not ok $s exited with status $rc"
        f=1
    fi
    pass=$((pass + p))
    fail=$((fail + f))
done
echo "tests: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
