#!/bin/sh
# canopen-eds check and the gateway agree on vendor-style files: what check
# accepts, the gateway starts with on a real SocketCAN network and serves
# as the same dictionary (`canopen-eds show` = GET .../od); what check
# refuses, the gateway refuses at start with the same file:line and reason.
. "$(dirname "$0")/lib.sh"
EDS=$BUILD_DIR/gateway/canopen-eds
SRC=${SOURCE_DIR:-$(dirname "$0")/../..}
Q=$SRC/tests/support/eds/quirks
CORPUS=$SRC/../shared/eds-corpus

files="$Q/limits.eds $Q/inline-comments.eds $Q/unreadable-objects.eds $Q/nodeid-ff.dcf $Q/duplicates-conflict.eds
       $SRC/deploy/eds/cia402-drive.eds"
# A few public vendor files where CI has ../shared (one refused, for a conflict).
for f in "christiansandberg+canopen/test/sensor.eds" "ros-industrial+ros_canopen/canopen_test_utils/config/Elmo.dcf" \
         "golems+socanmatic/eds/dsp301.eds"; do
  [ -f "$CORPUS/$f" ] && files="$files $CORPUS/$f"
done

accepted=0 refused=0
for f in $files; do
  rc=0
  "$EDS" check --node-id 5 "$f" > "$T/check" 2>&1 || rc=$?
  grc=0
  timeout 20 "$GATEWAY" --can vcan0 --eds "5=$f" --http 127.0.0.1:8080 > "$GW_LOG" 2>&1 &
  GW_PID=$!
  if [ "$rc" -eq 0 ]; then
    head -1 "$T/check" | grep -qE ": ok" || fail "check exited 0 but said: $(head -1 "$T/check")"
    wait_for "$GW_LOG" "canopen-gateway started" 15
    curl -sf http://127.0.0.1:8080/api/v1/networks/1/nodes/5/od > "$T/od.json" || fail "GET od for $f"
    "$EDS" show --node-id 5 "$f" > "$T/show.json" 2>/dev/null || fail "show $f"
    python3 - "$T/od.json" "$T/show.json" <<'PY' || fail "GET .../od and canopen-eds show differ for $f"
import json, sys
od, show = (json.load(open(p)) for p in sys.argv[1:3])
for key in ("vendorName", "productName", "dcf", "objects"):
    assert od[key] == show[key], key
assert od["network"] == 1 and od["node"] == 5
PY
    stop_gateway
    accepted=$((accepted + 1))
  else
    [ "$rc" -eq 1 ] || fail "check exited $rc for $f: $(cat "$T/check")"
    wait "$GW_PID" || grc=$?
    [ "$grc" -eq 2 ] || fail "gateway exited $grc for $f (expected 2), log: $(cat "$GW_LOG")"
    # the same file:line: reason, once as check's error line, once in the gateway's one line
    reason=$(sed -n 's/^\(.*\): error: \(.*\)$/\1: \2/p' "$T/check" | head -1)
    [ -n "$reason" ] || fail "no error line from check: $(cat "$T/check")"
    grep -qF -- "$reason" "$GW_LOG" || fail "gateway said '$(cat "$GW_LOG")', check said '$reason'"
    refused=$((refused + 1))
  fi
  echo "agree: $(head -1 "$T/check")"
done
[ "$accepted" -ge 5 ] && [ "$refused" -ge 1 ] || fail "accepted $accepted, refused $refused"
pass "canopen-eds check and the gateway agree on $accepted accepted and $refused refused files"
