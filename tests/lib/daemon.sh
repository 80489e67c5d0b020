# daemon.sh -- helpers for the shell suites that drive build/ljgapd with curl (sourced, not run).
# The suite may set, before sourcing: BIN (the daemon; default $BUILD/ljgapd), CLI (the CLI;
# default $BUILD/ljgap), WRAP (a wrapper such as valgrind; default the environment's, else none),
# SLOW (a multiplier for time bounds; default 1), SLOW_WRAPPED (SLOW when WRAP is set) and
# CHECK_PREFIX (put before each check's description). Sourcing makes the scratch directory $tmp
# and the array pids, both cleaned up on exit.

BUILD=${BUILD:-build}
BIN=${BIN-$BUILD/ljgapd}
CLI=${CLI-$BUILD/ljgap}
WRAP=${WRAP-}
SLOW=${SLOW:-1}
[ -n "$WRAP" ] && [ -n "${SLOW_WRAPPED:-}" ] && SLOW=$SLOW_WRAPPED

tmp=$(mktemp -d)
pids=()
cleanup() {
    for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null; done
    [ -n "${KEEP_TMP:-}" ] && echo "# kept $tmp" || rm -rf "$tmp"
}
trap cleanup EXIT

check() { # check DESCRIPTION COMMAND...: ok if the command succeeds
    local desc=$1
    shift
    if "$@"; then echo "ok - ${CHECK_PREFIX:-}$desc"; else echo "not ok - ${CHECK_PREFIX:-}$desc"; fi
}

# start NAME ARGS...: run the daemon, wait for its first line, set URL and PID. Its jobs go to
# the state directory $tmp/NAME.state unless ARGS give a --state-dir (or NO_STATE_DIR is set:
# then the daemon picks its default).
start() {
    local name=$1
    shift
    case " $* " in
    *" --state-dir "*) ;;
    *) [ -n "${NO_STATE_DIR:-}" ] || set -- --state-dir "$tmp/$name.state" "$@" ;;
    esac
    : >"$tmp/$name.out" # exists before the first look below, however slow the start
    $WRAP "$BIN" --port 0 "$@" >"$tmp/$name.out" 2>"$tmp/$name.err" &
    PID=$!
    pids+=("$PID")
    URL=
    for _ in $(seq 1 $((100 * SLOW))); do
        URL=$(sed -n '1s|^listening on \(http://127\.0\.0\.1:[0-9]*\)/$|\1|p' "$tmp/$name.out")
        [ -n "$URL" ] && return 0
        sleep 0.05
    done
    return 1
}

# req METHOD PATH [CURL ARGS...]: sets STATUS; the body is in $tmp/body, headers in $tmp/hdrs
req() {
    local m=$1 p=$2
    shift 2
    if [ "$m" = HEAD ]; then set -- -I "$@"; else set -- -X "$m" "$@"; fi
    STATUS=$(curl -s --max-time $((30 * SLOW)) -o "$tmp/body" -D "$tmp/hdrs" -w '%{http_code}' \
        "$@" "$URL$p")
}
hdr() { # the value of header $1 of the last answer
    grep -i "^$1:" "$tmp/hdrs" | head -n 1 | cut -d: -f2- | tr -d '\r' | sed 's/^ *//'
}
json() { # json ARGS... : jq -e over the last body
    jq -e "$@" "$tmp/body" >/dev/null 2>&1
}
elapsed() { # elapsed T0: seconds since T0 (from date +%s.%N)
    awk -v a="$1" -v b="$(date +%s.%N)" 'BEGIN { printf "%.3f", b - a }'
}
lt() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a < b) }'; }
