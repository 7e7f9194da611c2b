#!/usr/bin/env bash
# tools/demo, the README's first command, on the binary under test (no install, no build): the
# service comes up on the demo config, the stand-in PLC's picks come back right, and the run
# leaves its timing histogram and the last overlay. usage: test_demo.sh PIPELOC_BINARY
source "$(dirname "$0")/common.sh"
port="$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
rc=0
# A budget the picks never reach under a loaded test run (the demo's own 250 ms is the cell's).
PIPELOC_DEMO_SETUP=0 PIPELOC_BIN="$bin" PIPELOC_DEMO_OUT="$work/demo" PIPELOC_DEMO_PICKS=3 \
  PIPELOC_DEMO_PORT="$port" PIPELOC_DEMO_STATUS_PORT=0 PIPELOC_DEMO_BUDGET_MS=20000 "$here/tools/demo" \
  > "$work/out.txt" 2>&1 || rc=$?
[ "$rc" = 0 ] || { cat "$work/out.txt"; fail "tools/demo exited $rc"; }
# Each pick's line: REQ_ID, DONE_OK, ..., the distance from the nearest true pipe (mm) last.
picks="$(awk '$2 == "DONE_OK" { n++; if ($NF + 0 > 10) bad++ } END { print n + 0, bad + 0 }' "$work/out.txt")"
[ "$picks" = "3 0" ] || { cat "$work/out.txt"; fail "3 right picks expected (picks, wrong): $picks"; }
for png in "$work/demo/timing.png" "$work/demo/log/overlay-latest.png"; do
  [ "$(head -c 8 "$png" | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] || fail "no PNG at $png"
done
echo "tools/demo: 3 right picks on port $port, timing histogram and overlay written"
