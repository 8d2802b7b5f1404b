#!/bin/sh
# `cmake --install` into a temporary prefix gives a gateway that finds its
# dashboard in <prefix>/share/canopen-gateway/web (not the source tree), the
# example config that parses, the EDS files, and a systemd unit that
# systemd-analyze accepts (when systemd-analyze is there).
set -eu
: "${BUILD_DIR:?}" "${SOURCE_DIR:?}"
P=$(mktemp -d)
GW_PID=
cleanup() { [ -n "$GW_PID" ] && kill "$GW_PID" 2>/dev/null; rm -rf "$P"; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; [ -f "$P/gw.log" ] && tail -20 "$P/gw.log"; exit 1; }

cmake --install "$BUILD_DIR" --prefix "$P/usr" > "$P/install.log" 2>&1 || fail "install: $(tail -5 "$P/install.log")"
for f in bin/canopen-gateway bin/canopen-sim bin/canopen-eds share/canopen-gateway/web/index.html \
         share/canopen-gateway/gateway.example.yaml share/canopen-gateway/eds/cia402-drive.eds \
         lib/systemd/system/canopen-gateway.service; do
  [ -e "$P/usr/$f" ] || fail "not installed: $f"
done
grep -q "^ExecStart=$P/usr/bin/canopen-gateway " "$P/usr/lib/systemd/system/canopen-gateway.service" ||
  fail "unit's ExecStart does not point at the installed binary"
echo "PASS: installed files"
# The installed checker accepts the installed example EDS files.
"$P/usr/bin/canopen-eds" check "$P/usr/share/canopen-gateway/eds/"*.eds > "$P/check.log" 2>&1 ||
  fail "installed canopen-eds refused the installed EDS files: $(cat "$P/check.log")"

# The installed dashboard is served, not the source one: mark the copy.
echo "<!-- installed copy -->" >> "$P/usr/share/canopen-gateway/web/index.html"
PORT=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
HOME=$P STATE_DIRECTORY=$P/state "$P/usr/bin/canopen-gateway" --demo --http "127.0.0.1:$PORT" > "$P/gw.log" 2>&1 &
GW_PID=$!
i=0
until grep -q "canopen-gateway started" "$P/gw.log"; do
  i=$((i + 1)); [ $i -lt 100 ] || fail "gateway did not start"; sleep 0.1
done
/usr/bin/python3 - "$PORT" <<'PY' || fail "dashboard not served from the installed prefix"
import sys, urllib.request
body = urllib.request.urlopen(f"http://127.0.0.1:{sys.argv[1]}/", timeout=5).read().decode()
sys.exit(0 if "installed copy" in body else 1)
PY
echo "PASS: dashboard served from <prefix>/share/canopen-gateway/web"
kill "$GW_PID"; wait "$GW_PID" || fail "gateway exit status $?"; GW_PID=

if command -v systemd-analyze > /dev/null; then
  # Only the unit's own problems count; the machine may lack systemd as PID 1.
  systemd-analyze verify "$P/usr/lib/systemd/system/canopen-gateway.service" > "$P/verify.log" 2>&1 || true
  grep -E "canopen-gateway.service:[0-9]+:" "$P/verify.log" && fail "systemd-analyze: $(cat "$P/verify.log")"
  echo "PASS: systemd-analyze verify: no problem in the unit"
fi
