#!/usr/bin/env bash
# The topography PSD (issue 15), figures only:
#   - a 2048² synthetic map written as text (~42 MiB): medians of the stages of POST /v1/psd
#     (text parse, core, whole handler: bench/topo.c time), the wall time and peak memory of
#     `ljgap psd` on it, and of the daemon answering it over loopback (its VmHWM);
#   - the accuracy of D, C, h_rms and P on synthetic surfaces, periodic and cropped, fixed and
#     Gaussian amplitudes, N = 128 ... 1024 (bench/topo.c accuracy).
# Writes bench/results/topo.txt and bench/results/topo_accuracy.csv. Run under nice on a shared
# machine: `BUILD=build nice -n 19 bench/topo.sh` (make bench runs it).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
tmp=$(mktemp -d)
pid=
cleanup() {
    [ -n "$pid" ] && kill "$pid" 2>/dev/null
    rm -rf "$tmp"
}
trap cleanup EXIT
mkdir -p bench/results
out=bench/results/topo.txt

"$BUILD/bench/topo" gen "$tmp/map.txt" 2048
{
    echo "# topography PSD, $(date -u +%Y-%m-%d), $(nproc) cores, $(uname -m), load $(cut -d' ' -f1-3 /proc/loadavg)"
    echo "# a 2048 x 2048 map as text (%.3e values), dx = 1e-8 m, not periodic (plane + Hann window)"
    "$BUILD/bench/topo" time "$tmp/map.txt" 1e-8
    # the command line: read the file, parse, compute, print (one run each; the median of three)
    for i in 1 2 3; do
        /usr/bin/time -f "%e %M" -o "$tmp/time.$i" "$BUILD/ljgap" psd --dx 1e-8 "$tmp/map.txt" >"$tmp/cli.json"
    done
    sort -n "$tmp"/time.* | sed -n 2p | awk '{ printf "cli_wall_s %.2f (median of 3)\ncli_peak_rss %.0f MiB\n", $1, $2 / 1024 }'
    # the daemon: three POSTs of the file as text/plain, its peak resident memory afterwards
    # its own state directory: the default one (~/.local/state/ljgapd) belongs to whatever
    # ljgapd the user runs, and a second daemon on it refuses to start
    "$BUILD/ljgapd" --port 0 --compute-slots 1 --state-dir "$tmp/state" >"$tmp/d.out" \
        2>"$tmp/d.err" &
    pid=$!
    # this block is a subshell (its output goes through tee): stop the daemon on its every exit
    trap 'if [ -n "$pid" ]; then kill "$pid" 2>/dev/null; fi' EXIT
    url=
    for _ in $(seq 1 100); do
        url=$(sed -n 's|^listening on \(http://127\.0\.0\.1:[0-9]*\)/$|\1|p' "$tmp/d.out")
        [ -n "$url" ] && break
        sleep 0.05
    done
    if [ -z "$url" ]; then
        echo "topo.sh: ljgapd did not start: $(head -c 300 "$tmp/d.err")" >&2
        exit 1
    fi
    rss0=$(awk '/VmHWM/ { print $2 }' "/proc/$pid/status")
    for i in 1 2 3; do
        curl -s -o "$tmp/d.json" -w '%{time_total}\n' --max-time 60 "$url/v1/psd?dx=1e-8" \
            -H 'Content-Type: text/plain' --data-binary @"$tmp/map.txt" >>"$tmp/d.times"
    done
    sort -n "$tmp/d.times" | sed -n 2p | awk '{ printf "daemon_request_s %.2f (median of 3: upload, parse, compute, answer)\n", $1 }'
    awk -v r0="$rss0" '/VmHWM/ { printf "daemon_peak_rss %.0f MiB (%.0f MiB at start)\n", $2 / 1024, r0 / 1024 }' "/proc/$pid/status"
    kill -TERM "$pid"
    wait "$pid" || true
    pid=
    jq -r '"answer: D = \(.fit.D) ± \(.error.fit.D), h_rms = \(.h_rms) ± \(.error.h_rms) m, \(.k | length) bins"' "$tmp/d.json"
    echo "targets (issue 15): parse + FFT + binning under 2 s, under 300 MiB"
} | tee "$out"

"$BUILD/bench/topo" accuracy >bench/results/topo_accuracy.csv
echo "bench/results/topo_accuracy.csv: $(($(wc -l <bench/results/topo_accuracy.csv) - 1)) cases"
