#!/usr/bin/env bash
# make install into a DESTDIR, and what a user then does with it: build fig4.c against the
# installed library through pkg-config (shared and --static) and run it (the paper's Fig. 4
# adhesion), run the installed programs (ljgapd from an empty directory serves its page), check
# the manual pages (groff -man -ww, and every --flag of --help is in them), check the systemd
# unit (its directives, its flags against ljgapd --help, systemd-analyze verify where systemd is
# there), then make uninstall leaves nothing. One "ok"/"not ok" line per check.
#   BUILD=build tests/install/run.sh
# It builds its own copy in a scratch directory (plain, whatever SANITIZE the suite runs with:
# a program outside the project does not link the sanitizers' runtime).
set -u
cd "$(dirname "$0")/../.."
ROOT=$PWD
BIN= WRAP= SLOW=1
. tests/lib/daemon.sh # tmp, pids, cleanup; check, start, req, hdr

dest=$tmp/root
prefix=/usr/local
mk() { env -u MAKEFLAGS -u MAKELEVEL make -s --no-print-directory -C "$ROOT" BUILD="$tmp/build" \
    SANITIZE= PREFIX=$prefix DESTDIR="$dest" "$@"; }

if ! mk install >"$tmp/install.log" 2>&1; then
    echo "not ok - make install DESTDIR=...: $(tail -n 5 "$tmp/install.log")"
    exit 1
fi
version=$(sed -n 's/^#define LJGAP_VERSION "\(.*\)"/\1/p' include/ljgap.h)
files=(bin/ljgap sbin/ljgapd include/ljgap.h include/ljgap_sim.h include/ljgap_units.h
    lib/libljgap.a "lib/libljgap.so.$version" lib/pkgconfig/ljgap.pc share/man/man1/ljgap.1
    share/man/man8/ljgapd.8 lib/systemd/system/ljgapd.service)
missing=""
for f in "${files[@]}"; do [ -f "$dest$prefix/$f" ] || missing="$missing $f"; done
check "make install puts every file under DESTDIR\$PREFIX${missing:+ (missing:$missing)}" \
    [ -z "$missing" ]
check "libljgap.so -> libljgap.so.0 -> libljgap.so.$version, soname libljgap.so.0" eval '
    [ "$(readlink "$dest$prefix/lib/libljgap.so")" = libljgap.so.0 ] &&
    [ "$(readlink "$dest$prefix/lib/libljgap.so.0")" = "libljgap.so.$version" ] &&
    readelf -d "$dest$prefix/lib/libljgap.so.$version" | grep -q "SONAME.*\[libljgap\.so\.0\]"'
check "the installed headers need nothing from the source tree" eval '
    echo "#include <ljgap.h>
#include <ljgap_sim.h>
#include <ljgap_units.h>" | cc -fsyntax-only -I"$dest$prefix/include" -x c -'
check "nothing outside DESTDIR was written (the paths inside are \$PREFIX's)" eval '
    grep -q "^prefix=$prefix$" "$dest$prefix/lib/pkgconfig/ljgap.pc" &&
    grep -q "^ExecStart=$prefix/sbin/ljgapd " "$dest$prefix/lib/systemd/system/ljgapd.service"'

# ---- the library through pkg-config, as a program outside the project uses it ----
export PKG_CONFIG_PATH=$dest$prefix/lib/pkgconfig PKG_CONFIG_SYSROOT_DIR=$dest
check "pkg-config --modversion ljgap is $version" [ "$(pkg-config --modversion ljgap)" = "$version" ]
flags=$(pkg-config --cflags --libs ljgap)
check "pkg-config --cflags --libs ljgap: $flags" eval '[[ "$flags" == *"-I$dest$prefix/include"* &&
    "$flags" == *"-L$dest$prefix/lib"* && "$flags" == *-lljgap* ]]'
sflags=$(pkg-config --cflags --libs --static ljgap)
check "pkg-config --libs --static adds GSL and FFTW3" eval '[[ "$sflags" == *-lgsl* &&
    "$sflags" == *-lfftw3* && "$sflags" == *-lm* ]]'
cd "$tmp"
# shellcheck disable=SC2086
if cc "$ROOT/tests/install/fig4.c" $flags -o fig4-shared 2>"$tmp/cc.err"; then
    LD_LIBRARY_PATH=$dest$prefix/lib ./fig4-shared >"$tmp/fig4-shared.out"
    rc=$?
    check "shared: fig4 against the installed libljgap.so: $(tr '\n' ' ' <"$tmp/fig4-shared.out")" \
        [ $rc = 0 ]
    check "shared: the program loads libljgap.so.0 from DESTDIR" eval \
        'LD_LIBRARY_PATH=$dest$prefix/lib ldd ./fig4-shared | grep -q "libljgap\.so\.0 => $dest$prefix/lib/"'
else
    echo "not ok - shared: fig4.c does not build: $(head -c 400 "$tmp/cc.err")"
fi
# shellcheck disable=SC2086
if cc -static "$ROOT/tests/install/fig4.c" $sflags -o fig4-static 2>"$tmp/cc.err"; then
    ./fig4-static >"$tmp/fig4-static.out"
    rc=$?
    check "static: fig4 against the installed libljgap.a: $(tr '\n' ' ' <"$tmp/fig4-static.out")" \
        [ $rc = 0 ]
    check "static: the program needs no shared library" eval '! readelf -d ./fig4-static 2>/dev/null |
        grep -q NEEDED'
else
    echo "not ok - static: fig4.c does not build with --static: $(head -c 400 "$tmp/cc.err")"
fi
# the library's example in docs/serving.md, built the same way
awk '/^\*\*The library\.\*\*/ { on = 1 } on && /^```c/ { c = 1; next } c && /^```/ { exit }
     c { print }' "$ROOT/docs/serving.md" >readme.c
# shellcheck disable=SC2086
if [ -s readme.c ] && cc readme.c $flags -o readme-example 2>"$tmp/cc.err"; then
    out=$(LD_LIBRARY_PATH=$dest$prefix/lib ./readme-example)
    check "docs/serving.md's library example builds and prints $out" \
        eval '[[ "$out" =~ ^dgamma_eff\ =\ 0\.20149[89]\ ± ]]'
else
    echo "not ok - docs/serving.md's library example does not build: $(head -c 400 "$tmp/cc.err")"
fi
cd "$ROOT"

# ---- the installed programs ----
check "installed ljgap --version says $version" \
    eval '[ "$("$dest$prefix/bin/ljgap" --version)" = "ljgap $version" ]'
check "installed ljgap answers a request" eval 'echo "{\"psd\":{\"kind\":\"power\",\"D\":2.5,
    \"k1\":1,\"m0\":0.5}}" | "$dest$prefix/bin/ljgap" adhesion | jq -e ".g_eq > 2.6" >/dev/null'
mkdir -p "$tmp/empty"
BIN=$dest$prefix/sbin/ljgapd
cd "$tmp/empty"
if start installed; then
    req GET /
    check "installed ljgapd, started in an empty directory with no flags, serves the page" \
        eval '[ "$STATUS" = 200 ] && cmp -s "$tmp/body" "$ROOT/web/index.html"'
    req GET /vendor/uPlot.iife.min.js
    check "... and uPlot" eval '[ "$STATUS" = 200 ] && cmp -s "$tmp/body" "$ROOT/web/vendor/uPlot.iife.min.js"'
    kill -TERM "$PID"
    wait "$PID"
else
    echo "not ok - the installed ljgapd did not start: $(head -c 300 "$tmp/installed.err")"
fi
cd "$ROOT"

# ---- manual pages ----
for page in share/man/man1/ljgap.1 share/man/man8/ljgapd.8; do
    for dev in utf8 ascii; do
        out=$(groff -man -ww -z -T$dev "$dest$prefix/$page" 2>&1)
        check "groff -man -ww -T$dev $page: no warning${out:+ ($out)}" [ -z "$out" ]
    done
done
# every --flag the programs' --help names is in their manual page
flags_missing() { # flags_missing PROGRAM PAGE
    local f missing=""
    for f in $("$1" --help | grep -o -- '--[a-z][a-z-]*' | sort -u); do
        # roff writes - as \- in option names
        grep -qF -- "$(printf '%s' "$f" | sed 's/-/\\-/g')" "$2" || missing="$missing $f"
    done
    echo "$missing"
}
m=$(flags_missing "$dest$prefix/bin/ljgap" "$dest$prefix/share/man/man1/ljgap.1")
check "every --flag of ljgap --help is in ljgap(1)${m:+ (missing:$m)}" [ -z "$m" ]
m=$(flags_missing "$dest$prefix/sbin/ljgapd" "$dest$prefix/share/man/man8/ljgapd.8")
check "every --flag of ljgapd --help is in ljgapd(8)${m:+ (missing:$m)}" [ -z "$m" ]

# ---- the systemd unit ----
unit=$dest$prefix/lib/systemd/system/ljgapd.service
for d in DynamicUser=yes StateDirectory=ljgapd ProtectSystem=strict NoNewPrivileges=yes \
    PrivateTmp=yes Restart=on-failure; do
    check "ljgapd.service: $d" grep -qx "$d" "$unit"
done
if "$dest$prefix/sbin/ljgapd" --help | grep -q -- --state-dir; then
    check "ljgapd.service passes the state directory: --state-dir \${STATE_DIRECTORY}" \
        grep -q '^ExecStart=.* --state-dir \${STATE_DIRECTORY}$' "$unit"
else
    check "ljgapd.service: this ljgapd has no --state-dir (the job store's), so the unit passes none" \
        eval '! grep -q "^ExecStart=.*--state-dir" "$unit"'
fi
# the unit's memory bound and the daemon's budget agree: MemoryMax above --max-memory, by at
# most 512 MiB (what the budget does not count: the program, threads, connection buffers)
mib() { # mib SIZE: a --max-memory or MemoryMax= size (K, M, G suffixes) in MiB
    awk -v s="$1" 'BEGIN { n = s + 0; u = toupper(substr(s, length(s)));
        print (u == "G" ? n * 1024 : u == "M" ? n : u == "K" ? n / 1024 : n / 1048576) }'
}
budget=$(sed -n 's/^ExecStart=.* --max-memory \([0-9]*[KMG]\).*/\1/p' "$unit")
memmax=$(sed -n 's/^MemoryMax=//p' "$unit")
check "ljgapd.service: MemoryMax=$memmax a little above its --max-memory $budget" \
    eval '[ -n "$budget" ] && [ -n "$memmax" ] &&
          awk -v b="$(mib "$budget")" -v m="$(mib "$memmax")" "BEGIN { exit !(m > b && m <= b + 512) }"'
m=""
for f in $(sed -n 's/^ExecStart=//p' "$unit" | grep -o -- '--[a-z][a-z-]*'); do
    "$dest$prefix/sbin/ljgapd" --help | grep -q -- "$f" || m="$m $f"
done
check "every flag of the unit's ExecStart is one ljgapd --help lists${m:+ (not:$m)}" [ -z "$m" ]
if command -v systemd-analyze >/dev/null; then
    # verify wants the program where ExecStart says, and the manual page Documentation= names
    # (it runs man): point both into DESTDIR for the check
    mkdir -p "$tmp/unit"
    sed "s|^ExecStart=$prefix|ExecStart=$dest$prefix|" "$unit" >"$tmp/unit/ljgapd.service"
    out=$(MANPATH=$dest$prefix/share/man systemd-analyze verify "$tmp/unit/ljgapd.service" 2>&1)
    rc=$?
    check "systemd-analyze verify ljgapd.service: no complaint${out:+ ($out)}" \
        eval '[ $rc = 0 ] && [ -z "$out" ]'
else
    echo "ok - systemd-analyze verify ljgapd.service # SKIP no systemd-analyze on this machine"
fi

# ---- uninstall ----
mk uninstall >"$tmp/uninstall.log" 2>&1
left=$(find "$dest" \( -type f -o -type l \) | sed "s|^$dest||" | tr '\n' ' ')
check "make uninstall removes every file it installed${left:+ (left: $left)}" [ -z "$left" ]
