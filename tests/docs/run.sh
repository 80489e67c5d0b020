#!/usr/bin/env bash
# The documentation stays true: docs/api.md against server/openapi.json (every operation, status,
# field and problem type, both ways where it makes sense), the relative links of the README and
# docs/ (files and #anchors), and the README's "Use from Python" examples run against a server
# (standard library; requests + pandas reading the CSV), and the README's length (≤ 300 lines).
# One "ok"/"not ok" line per check.
#   BUILD=build tests/docs/run.sh
set -u
cd "$(dirname "$0")/../.."
. tests/lib/daemon.sh # tmp, pids, cleanup; check, start

python3 tests/docs/check.py api server/openapi.json docs/api.md
python3 tests/docs/check.py links README.md docs/*.md
# the README is a front door, not a manual (issue 27): at most 300 lines; the rest lives in docs/
lines=$(wc -l <README.md)
check "the README has at most 300 lines ($lines)" [ "$lines" -le 300 ]

# Debian's python3 has the python3-requests and python3-pandas that make test installs (a
# python3 earlier on PATH may be another installation without them).
PY=python3
[ -x /usr/bin/python3 ] && PY=/usr/bin/python3
# the README's ```python blocks of "Use from Python", one file each
awk '/^## Use from Python/ { on = 1; next } /^## / { on = 0 }
     on && /^```python/ { n++; f = sprintf("'"$tmp"'/example%d.py", n); inblock = 1; next }
     inblock && /^```/ { inblock = 0; next }
     inblock { print > f }' README.md
check "the README has two Python examples" [ -f "$tmp/example1.py" ] && [ -f "$tmp/example2.py" ]
if start docs; then
    for f in "$tmp"/example*.py; do
        sed -i "s|^BASE = \"http://localhost:8080\"|BASE = \"$URL\"|" "$f"
        out=$("$PY" "$f" 2>&1)
        rc=$?
        name=$(basename "$f")
        check "README $name runs against a server: $(echo "$out" | tr '\n' ' ' | cut -c1-120)" \
            eval '[ $rc = 0 ] && grep -q "BASE = \"$URL\"" "$f"'
    done
    check "README example1.py prints the Fig. 4 adhesion" \
        eval '"$PY" "$tmp/example1.py" | grep -q "g_eq = 2.60280 .* dgamma_eff = 0.20150"'
    check "README example2.py prints the traction maximum read from the CSV" \
        eval '"$PY" "$tmp/example2.py" | grep -q "^largest traction on the grid: 0\.1012"'
    kill -TERM "$PID"
    wait "$PID"
else
    echo "not ok - ljgapd did not start"
fi
