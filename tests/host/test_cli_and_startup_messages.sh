#!/bin/sh
# What the canopen-gateway process says to a person (issue 13, items 2 and 3):
#  1. --help describes every flag of the contract's command line with its
#     default; --version prints the version; both exit 0;
#  2. at start-up one line per listener with a URL that works when pasted
#     (dashboard, REST API, WebSocket events, /metrics, MQTT broker/topics);
#  3. errors are one line on stderr with exit 2, without library internals,
#     blaming the flag or FILE:LINE the value came from: a port in use,
#     --http 0.0.0.0 with a file without tokens, a control character in the
#     YAML file (escaped as \xNN, never raw).
# On the host: the gateway's simulated network; no broker needed.
TMPDIR=$(mktemp -d /tmp/host-test.XXXXXX)
export TMPDIR
trap 'kill $GW_PID $HOLD_PID 2>/dev/null || true; rm -rf "$TMPDIR"' EXIT
. "$(dirname "$0")/../system/lib.sh"
: "${SOURCE_DIR:?}"
HOLD_PID=
# run_gateway ARGS...: runs it to its end; $T/out, $T/err, $RC.
run_gateway() {
  RC=0
  timeout 20 "$GATEWAY" "$@" > "$T/out" 2> "$T/err" || RC=$?
}

# expect_error NAME PATTERN ARGS...: exit 2, exactly one line on stderr,
# matching PATTERN (grep -E), without Boost's or the compiler's internals
# and without a raw control character.
expect_error() {
  local name=$1 pattern=$2; shift 2
  run_gateway "$@"
  [ "$RC" -eq 2 ] || fail "$name: exit $RC (expected 2): $(cat "$T/err")"
  [ "$(wc -l < "$T/err")" -eq 1 ] || fail "$name: expected one line on stderr: $(cat "$T/err")"
  grep -qE -- "$pattern" "$T/err" || fail "$name: stderr does not match /$pattern/: $(cat "$T/err")"
  ! grep -qiE 'boost|/usr/include|system:[0-9]' "$T/err" || fail "$name: library internals: $(cat "$T/err")"
  [ -z "$(tr -d '\n[:print:]' < "$T/err")" ] || fail "$name: raw control character: $(od -c "$T/err" | head -5)"
  pass "$name: $(cat "$T/err")"
}

# ---- 1: --help and --version ---------------------------------------------
run_gateway --help
[ "$RC" -eq 0 ] || fail "--help: exit $RC"
[ ! -s "$T/err" ] || fail "--help wrote to stderr: $(cat "$T/err")"
# Every flag of the contract's command line (api-contract.md) that the
# parser takes.
for flag in --config --can --node-id --eds --mqtt --mqtt-format --http --gateway-id --demo --log-level \
            --sparkplug --ascii --help --version; do
  grep -qE -- "^  (-h, )?$flag( |$)" "$T/out" || fail "--help does not describe $flag: $(cat "$T/out")"
done
# Their defaults, as the contract gives them.
for text in "127.0.0.1:8080" "else 127" "else json" "else info" "else the host" "else MQTT off"; do
  grep -qF -- "$text" "$T/out" || fail "--help does not give the default '$text'"
done
[ "$(awk 'length($0) > 80' "$T/out" | wc -l)" -eq 0 ] || fail "--help is wider than 80 columns"
pass "--help: every flag with its default, $(wc -l < "$T/out") lines"

VERSION=$(sed -n 's/^project([a-z_]* VERSION \([0-9.]*\).*/\1/p' "$SOURCE_DIR/CMakeLists.txt")
run_gateway --version
[ "$RC" -eq 0 ] || fail "--version: exit $RC"
[ "$(cat "$T/out")" = "canopen-gateway $VERSION" ] || fail "--version printed '$(cat "$T/out")', not $VERSION"
pass "--version: $(cat "$T/out")"

# ---- 2: where to look, with URLs that work when pasted ---------------------
GW_LOG=$T/gateway.log
start_gateway --demo --gateway-id cli-test --http 127.0.0.1:0 --mqtt tcp://127.0.0.1:1
BASE=$(sed -n 's|.* INFO  dashboard: \(http://127.0.0.1:[0-9]*\)/$|\1|p' "$GW_LOG")
[ -n "$BASE" ] || fail "no dashboard line with a URL"
PORT=${BASE##*:}
for line in "HTTP/WebSocket on $BASE (this machine only)" \
            "REST API: $BASE/api/v1/ (OpenAPI description: $BASE/api/v1/openapi.json)" \
            "events (WebSocket): ws://127.0.0.1:$PORT/api/v1/events" \
            "metrics: $BASE/metrics" \
            "MQTT: broker tcp://127.0.0.1:1, topic prefix canopen/cli-test/ (subscribe to canopen/cli-test/#)"; do
  grep -qF -- " INFO  $line" "$GW_LOG" || fail "no start-up line '$line'"
done
/usr/bin/python3 - "$BASE" <<'PY' || fail "a URL from the start-up lines does not work (see above)"
import base64, os, socket, sys, urllib.request
base = sys.argv[1]
for path, expect in (("/", b"<html"), ("/api/v1/openapi.json", b'"openapi"'), ("/metrics", b"# HELP"),
                     ("/api/v1/gateway", b'"version"')):
    body = urllib.request.urlopen(base + path, timeout=5).read()
    if expect not in body.lower() and expect not in body:
        sys.exit(f"{base + path}: {expect!r} not in the answer")
# The WebSocket URL: the upgrade is accepted (101).
host, port = base[len("http://"):].split(":")
s = socket.create_connection((host, int(port)), timeout=5)
key = base64.b64encode(os.urandom(16)).decode()
s.sendall(f"GET /api/v1/events HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
          f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n".encode())
status = s.recv(4096).split(b"\r\n")[0]
if b" 101 " not in status:
    sys.exit(f"WebSocket upgrade: {status!r}")
PY
# A value out of range over REST names the object and the type (6060h is i8).
/usr/bin/python3 - "$BASE" <<'PY' || fail "SDO range error (see above)"
import json, sys, urllib.error, urllib.request
req = urllib.request.Request(sys.argv[1] + "/api/v1/networks/1/nodes/5/sdo/6060/0", data=b'{"value": 300}',
                             method="PUT", headers={"Content-Type": "application/json"})
try:
    urllib.request.urlopen(req, timeout=5)
    sys.exit("accepted")
except urllib.error.HTTPError as e:
    detail = json.loads(e.read())["detail"]
    print(f"PASS: SDO range error over REST: {e.code} {detail}")
    sys.exit(0 if e.code == 400 and detail == "6060h sub 0: 300 is above 127 (i8)" else 1)
PY
stop_gateway
pass "start-up lines: dashboard, REST, WebSocket, metrics and MQTT, and the URLs answer"

# A wildcard listener prints a name a person can use, and says so.
HASH=$(printf %s cli-test-token | sha256sum | cut -d' ' -f1)
printf 'http:\n  plain-http: true\n  tokens:\n    - {name: t, role: viewer, sha256: %s}\n' "$HASH" > "$T/open.yaml"
GW_LOG=$T/gateway-open.log
start_gateway --demo --config "$T/open.yaml" --http 0.0.0.0:0
grep -qE " INFO  HTTP/WebSocket on http://[^ /:]+:[0-9]+ \(listening on 0.0.0.0, every IPv4 address of this machine\)" \
  "$GW_LOG" || fail "wildcard listener line: $(grep 'HTTP/WebSocket' "$GW_LOG")"
grep -q " INFO  dashboard: http://0.0.0.0:" "$GW_LOG" && fail "0.0.0.0 printed as a URL to open"
grep -qE " INFO  metrics: http://[^ ]+/metrics \(needs a bearer token\)" "$GW_LOG" || fail "no token note on metrics"
stop_gateway
pass "wildcard listener: $(sed -n 's/.* INFO  \(HTTP\/WebSocket on .*\)/\1/p' "$GW_LOG")"

# ---- 3: errors -----------------------------------------------------------------
# A port another process holds.
BUSY=$(free_port)
/usr/bin/python3 -c 'import socket,sys,time; s=socket.socket(); s.bind(("127.0.0.1",int(sys.argv[1]))); s.listen(); time.sleep(60)' \
  "$BUSY" &
HOLD_PID=$!
i=0
until /usr/bin/python3 -c 'import socket,sys; s=socket.socket(); sys.exit(s.connect_ex(("127.0.0.1",int(sys.argv[1]))))' "$BUSY"; do
  i=$((i + 1)); [ $i -lt 50 ] || fail "the port holder did not listen"; sleep 0.1
done
expect_error "port in use (flag)" \
  "^canopen-gateway: error: --http 127.0.0.1:$BUSY: address already in use \(is another gateway running\?\)$" \
  --demo --http "127.0.0.1:$BUSY"
printf 'gateway: {id: cli-test}\nhttp:\n  listen: 127.0.0.1:%s\n' "$BUSY" > "$T/busy.yaml"
expect_error "port in use (file)" \
  "^canopen-gateway: error: $T/busy.yaml:3: http.listen 127.0.0.1:$BUSY: address already in use" \
  --demo --config "$T/busy.yaml"
kill $HOLD_PID; wait $HOLD_PID 2>/dev/null || true; HOLD_PID=

# --http 0.0.0.0 with a file that has no tokens: the flag is to blame.
printf 'gateway:\n  id: cli-test\nhttp:\n  auth: true\n' > "$T/no-tokens.yaml"
expect_error "--http 0.0.0.0 blames the flag" \
  "^canopen-gateway: error: --http 0.0.0.0:8080: not a loopback address, and no http.tokens are configured in $T/no-tokens.yaml" \
  --can vcan0 --config "$T/no-tokens.yaml" --http 0.0.0.0:8080
grep -qE "no-tokens.yaml:[0-9]|http.tokens:" "$T/err" && fail "blames the file for the flag's address: $(cat "$T/err")"

# Control characters in the YAML file (raw, and from a double-quoted escape).
printf 'gateway:\n  id: ab\001cd\n' > "$T/ctl.yaml"
expect_error "control character in the file" \
  "^canopen-gateway: error: $T/ctl.yaml:2: gateway.id: 'ab\\\\x01cd' cannot be an MQTT topic level$" \
  --demo --config "$T/ctl.yaml"
printf 'gateway:\n  id: "red\\e[31m"\n' > "$T/esc.yaml"
expect_error "escape sequence in the file" "'red\\\\x1B\[31m'" --demo --config "$T/esc.yaml"
# ... and on the command line.
expect_error "control character in a flag" "--log-level: 'x\\\\x07y' is not one of" \
  --demo --log-level "$(printf 'x\007y')"
