#!/usr/bin/env bash
# The page in web/ in headless Debian chromium: tests/web/page.test.js under `node --test`, with
# playwright-core from web/node_modules (installed by mk/web.mk, as are web/vendor/'s uPlot files).
# Relays node's TAP: one "ok N - ..." / "not ok N - ..." line per test, and the details of
# failures (indented). Screenshots: $BUILD/web-screenshot.png, $BUILD/web-screenshot-contact.png.
#   BUILD=build/h-web tests/web/run.sh
set -u
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
export BUILD
CHROMIUM=${CHROMIUM:-/usr/bin/chromium}
export CHROMIUM

missing=""
command -v node >/dev/null || missing="$missing node"
[ -x "$CHROMIUM" ] || missing="$missing $CHROMIUM"
[ -d web/node_modules/playwright-core ] || missing="$missing web/node_modules/playwright-core"
[ -f web/vendor/uPlot.iife.min.js ] || missing="$missing web/vendor/uPlot.iife.min.js"
[ -x "$BUILD/ljgapd" ] || missing="$missing $BUILD/ljgapd"
if [ -n "$missing" ]; then
    echo "not ok - web page tests: missing$missing (make test installs and builds them)"
    exit 1
fi

out=$(timeout 300 node --test --test-reporter=tap tests/web/page.test.js 2>&1)
rc=$?
# top-level results, and what node says about each failure
printf '%s\n' "$out" | awk '
    /^(not )?ok [0-9]/ { print; infail = /^not ok/; next }
    /^[0-9]+\.\.[0-9]+/ { infail = 0; next }
    infail && /^  / { print }
    /^# (tests|pass|fail) / { print }'
if [ "$rc" -ne 0 ] && ! printf '%s\n' "$out" | grep -q '^not ok'; then
    printf '%s\n' "$out" | tail -n 20
    echo "not ok - node --test exited with status $rc"
fi
exit "$rc"
