#!/usr/bin/env bash
# Runs the test programs and suites, then prints the closing line
#   tests: N passed, N failed
# Unit tests are cmocka programs in $BUILD/tests/; shell suites (tests/*/run.sh other than this
# one) print one "ok ..." or "not ok ..." line per check, TAP style.
#
# The programs and suites are independent (each daemon listens on a port the kernel picks, each
# suite has its own scratch directory), so up to JOBS of them run at once (default: the number of
# cores). Each one's output is captured and printed whole, followed by a comment line with its
# time, in a fixed order (unit tests, then the suites by name) whatever order they end in; the
# closing line is always the last line printed. The longest suites start first; the lab-server
# suite, whose checks compare timings, and the memcheck suite run last, each alone.
#
#   tests/run.sh                    every unit test and suite but the memcheck suite
#   MEMCHECK=1 tests/run.sh         the memcheck suite too (valgrind over five suites, ~5 min on
#                                   its own: .ci/run's plain build and make memcheck run it)
#   tests/run.sh unit http csv      only these: "unit" is every unit test program, a name is
#                                   tests/NAME/run.sh, test_xxx is one unit test program
#   tests/run.sh unit -test_mc      a leading - leaves one out
#   JOBS=1 tests/run.sh             one at a time
set -u
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
export BUILD
JOBS=${JOBS:-$(nproc 2>/dev/null || echo 2)}
MEMCHECK=${MEMCHECK:-0}

# ---- what to run, in the order it is printed ----
names=() # a unit test program's path or a suite's run.sh
want() { # want NAME: whether the command line asks for it (everything when it names nothing)
    local s hit=0 any=0
    for s in "${sel[@]}"; do
        case "$s" in
        -*) [ "${s#-}" = "$(label "$1")" ] && return 1 ;;
        *) any=1; [ "$s" = "$(label "$1")" ] || { [ "$s" = unit ] && [ "${1#"$BUILD"/tests/}" != "$1" ]; } && hit=1 ;;
        esac
    done
    [ "$any" = 0 ] || [ "$hit" = 1 ]
}
label() { # label PATH: test_xxx for a unit test program, NAME for tests/NAME/run.sh
    case "$1" in
    tests/*/run.sh) basename "$(dirname "$1")" ;;
    *) basename "$1" ;;
    esac
}
sel=("$@")
for t in "$BUILD"/tests/*; do
    [ -x "$t" ] && [ -f "$t" ] || continue
    want "$t" && names+=("$t")
done
for s in tests/*/run.sh; do
    [ -x "$s" ] || continue
    # the memcheck suite only when asked for, by MEMCHECK=1 or by name
    if [ "$s" = tests/memcheck/run.sh ] && [ "$MEMCHECK" != 1 ] &&
        ! printf '%s\n' "${sel[@]}" | grep -qx memcheck; then
        continue
    fi
    want "$s" && names+=("$s")
done

# ---- the order they start in: the longest first (times on 2 cores), then the rest ----
first=(tests/memcheck/run.sh tests/scaleout/run.sh tests/serve/run.sh tests/standalone/run.sh
    tests/jobs/run.sh tests/web/run.sh tests/durable/run.sh tests/install/run.sh
    tests/cli/run.sh tests/http/run.sh)
order=()
for f in "${first[@]}"; do
    for i in "${!names[@]}"; do [ "${names[$i]}" = "$f" ] && order+=("$i"); done
done
for i in "${!names[@]}"; do
    case " ${first[*]} " in *" ${names[$i]} "*) ;; *) order+=("$i") ;; esac
done

out=$(mktemp -d)
jobpids=()
trap 'for p in "${jobpids[@]}"; do kill -TERM -- "$p" 2>/dev/null; done; rm -rf "$out"' EXIT
trap 'exit 143' INT TERM

run_one() { # run_one INDEX: the program or suite's output in $out/INDEX.out, status in .rc
    local t0 rc
    t0=$(date +%s)
    "${names[$1]}" >"$out/$1.out" 2>&1 </dev/null
    rc=$?
    echo "$(($(date +%s) - t0))" >"$out/$1.time"
    echo "$rc" >"$out/$1.rc"
}

pass=0
fail=0
next=0 # the next index to print
report() { # print every finished one from $next on, in order, until one still runs
    local i p f rc o
    while [ "$next" -lt "${#names[@]}" ] && [ -f "$out/$next.rc" ]; do
        i=$next
        o=$(cat "$out/$i.out")
        rc=$(cat "$out/$i.rc")
        printf '%s\n' "$o"
        case "${names[$i]}" in
        "$BUILD"/tests/*)
            p=$(printf '%s\n' "$o" | sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' | awk '{s+=$1} END {print s+0}')
            f=$(printf '%s\n' "$o" | sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' | awk '{s+=$1} END {print s+0}')
            ;;
        *)
            p=$(printf '%s\n' "$o" | grep -c '^ok ')
            f=$(printf '%s\n' "$o" | grep -c '^not ok ')
            ;;
        esac
        if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then
            echo "not ok ${names[$i]} exited with status $rc"
            f=1
        fi
        echo "# ${names[$i]}: $p passed, $f failed, $(cat "$out/$i.time") s"
        pass=$((pass + p))
        fail=$((fail + f))
        next=$((next + 1))
    done
}

# The lab-server suite times its fairness and queue checks against each other: it runs last, on
# its own (beside other suites on a loaded machine its fair-share check failed). So does the
# memcheck suite when asked for (it runs the lab-server suite again, under valgrind).
alone=(tests/serve/run.sh tests/memcheck/run.sh)
is_alone() { case " ${alone[*]} " in *" ${names[$1]} "*) return 0 ;; esac; return 1; }
running=0
for pass_ in shared alone; do
    for i in "${order[@]}"; do
        if is_alone "$i"; then [ "$pass_" = alone ] || continue; else [ "$pass_" = shared ] || continue; fi
        limit=$JOBS
        [ "$pass_" = alone ] && limit=1
        while [ "$running" -ge "$limit" ]; do
            wait -n
            running=$((running - 1))
            report
        done
        run_one "$i" &
        jobpids+=("$!")
        running=$((running + 1))
    done
    # before the suites that run alone, let every other one end
    while [ "$pass_" = shared ] && [ "$running" -gt 0 ]; do
        wait -n
        running=$((running - 1))
        report
    done
done
while [ "$running" -gt 0 ]; do
    wait -n
    running=$((running - 1))
    report
done
report
echo "tests: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
