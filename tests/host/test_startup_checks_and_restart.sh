#!/bin/sh
# The canopen-gateway process at start-up and across restarts (issue 12):
#  1. configuration it cannot run with is exit 2 and one line on stderr,
#     before anything listens: --demo off loopback without tokens (item 11),
#     a state directory that cannot be written, named by the key and where
#     it came from (item 6);
#  2. --demo with tokens configured requires them (item 11);
#  3. the seq of network 1 continues across a clean restart without a gap,
#     and after kill -9 no number comes twice (item 4);
#  4. more SIGTERMs while it stops (timeout(1) and systemd also signal the
#     process group) still end in a clean stop, exit 0.
# On the host: the gateway's simulated network, a real mosquitto.
TMPDIR=$(mktemp -d /tmp/host-test.XXXXXX)
export TMPDIR
trap 'kill $MOSQ_PID $SUB_PID $GW_PID 2>/dev/null || true; rm -rf "$TMPDIR"' EXIT
. "$(dirname "$0")/../system/lib.sh"
GW=gw-restart
listening() { /usr/bin/python3 -c 'import socket,sys; s=socket.socket(); sys.exit(s.connect_ex(("127.0.0.1",int(sys.argv[1]))))' "$1"; }
http_status() {
  /usr/bin/python3 - "$@" <<'PY'
import sys, urllib.request, urllib.error
req = urllib.request.Request(sys.argv[1])
if len(sys.argv) > 2:
    req.add_header("Authorization", "Bearer " + sys.argv[2])
try:
    print(urllib.request.urlopen(req, timeout=5).status)
except urllib.error.HTTPError as e:
    print(e.code)
PY
}

# expect_exit2 NAME PATTERN ARGS...: exit 2, one line on stderr matching
# PATTERN, and the HTTP port never listened.
expect_exit2() {
  local name=$1 pattern=$2 port rc=0; shift 2
  port=$(free_port)
  timeout 20 "$GATEWAY" "$@" --http "${HTTP_ADDR:-127.0.0.1}:$port" > "$T/out" 2> "$T/err" &
  local pid=$!
  # Whether it ever listened: probe until it exits.
  while kill -0 $pid 2>/dev/null; do
    listening "$port" && { kill $pid; fail "$name: the HTTP port listened before the exit"; }
    sleep 0.02
  done
  wait $pid || rc=$?
  [ "$rc" -eq 2 ] || fail "$name: exit $rc (expected 2): $(cat "$T/err")"
  [ "$(wc -l < "$T/err")" -eq 1 ] || fail "$name: expected one line on stderr: $(cat "$T/err")"
  grep -qE -- "$pattern" "$T/err" || fail "$name: stderr does not match /$pattern/: $(cat "$T/err")"
  pass "$name: $(cat "$T/err")"
}

# ---- 1: refused before anything listens ------------------------------------
HTTP_ADDR=0.0.0.0 expect_exit2 "--demo off loopback without tokens" \
  "--http 0.0.0.0:[0-9]+: not a loopback address, and no http.tokens are configured \(--demo turns authentication off on loopback only\)" \
  --demo
: > "$T/not-a-dir"
printf 'gateway:\n  state-dir: %s/not-a-dir/state\n' "$T" > "$T/bad-state.yaml"
expect_exit2 "state-dir below a file" \
  "^canopen-gateway: error: $T/bad-state.yaml:2: gateway.state-dir: '$T/not-a-dir/state' cannot be used: Not a directory" \
  --demo --config "$T/bad-state.yaml"
STATE_DIRECTORY=$T/not-a-dir/env expect_exit2 "state-dir from \$STATE_DIRECTORY below a file" \
  "gateway.state-dir from \\\$STATE_DIRECTORY \(systemd StateDirectory=\): '$T/not-a-dir/env' cannot be used" --demo
printf 'gateway: {state-dir: %s/state}\nmqtt:\n  uri: tcp://127.0.0.1:1\n  queue: {dir: %s/not-a-dir/q}\n' "$T" "$T" \
  > "$T/bad-queue.yaml"
expect_exit2 "mqtt.queue.dir below a file" "$T/bad-queue.yaml:4: mqtt.queue.dir: '$T/not-a-dir/q' cannot be used" \
  --demo --config "$T/bad-queue.yaml"

# ---- 2: --demo with tokens ----------------------------------------------------
TOKEN=demo-test-token
HASH=$(printf %s "$TOKEN" | sha256sum | cut -d' ' -f1)
printf 'gateway: {state-dir: %s/state}\nhttp:\n  tokens:\n    - {name: t, role: viewer, sha256: %s}\n' "$T" "$HASH" \
  > "$T/tokens.yaml"
GW_LOG=$T/gateway-tokens.log
start_gateway --demo --config "$T/tokens.yaml" --http 127.0.0.1:0
PORT=$(sed -n 's|.*HTTP/WebSocket on http://127.0.0.1:\([0-9]*\).*|\1|p' "$GW_LOG")
[ "$(http_status "http://127.0.0.1:$PORT/api/v1/gateway")" = 401 ] || fail "--demo with tokens: no token accepted"
[ "$(http_status "http://127.0.0.1:$PORT/api/v1/gateway" "$TOKEN")" = 200 ] || fail "--demo with tokens: token refused"
stop_gateway
pass "--demo with tokens configured: 401 without, 200 with a token"

# ---- 3: seq across restarts ------------------------------------------------------
MOSQ_PORT=$(free_port)
start_mosquitto
mosquitto_sub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv311 -q 1 -v -t "canopen/$GW/1/#" > "$T/mqtt.log" 2>&1 &
SUB_PID=$!
sleep 0.5
cat > "$T/gw.yaml" <<YAML
gateway: {id: $GW, state-dir: $T/state}
networks:
  - simulated: true
    simulation: {tpdo-period-ms: 20, heartbeat-ms: 200, emcy-period-ms: 0}
mqtt:
  uri: tcp://127.0.0.1:$MOSQ_PORT
  qos: {default: 1}
YAML
# run N: the gateway until 100 more events reached the subscriber.
run() {
  GW_LOG=$T/gateway-run$1.log
  start_gateway --config "$T/gw.yaml" --http 127.0.0.1:0
  wait_count "$T/mqtt.log" "^canopen/$GW/1/" $(( $(grep -c "^canopen/$GW/1/" "$T/mqtt.log") + 100 )) 20
}
run 1
stop_gateway
run 2
stop_gateway
run 3
kill_time=$(date +%s.%N)
kill -KILL "$GW_PID"; wait "$GW_PID" 2>/dev/null || true
run 4
stop_gateway
sleep 0.5
/usr/bin/python3 - "$T/mqtt.log" "$kill_time" <<'PY' || fail "seq across restarts (see above)"
import datetime, json, sys
kill = float(sys.argv[2])
before, after = [], []  # seq of events stamped before the kill (runs 1-3), after it (run 4)
for line in open(sys.argv[1]):
    topic, _, payload = line.partition(" ")
    if "/" not in topic or payload.strip() in ("", "(null)"):
        continue  # (null): a retained state deleted at a stop
    ev = json.loads(payload)
    ts = datetime.datetime.fromisoformat(ev["timestamp"].replace("Z", "+00:00")).timestamp()
    (before if ts <= kill else after).append(int(ev["seq"]))
old = sorted(set(before))
gaps = [(a, b) for a, b in zip(old, old[1:]) if b != a + 1]
print(f"runs 1-3 (two clean restarts): {len(before)} events, seq {old[0]}..{old[-1]}, gaps {gaps[:5]}; "
      f"run 4 (after kill -9): seq {min(after)}..{max(after)}")
# Clean restarts: one sequence without a gap (a restart at 1, or anywhere
# else, would leave one). kill -9: every new number is above every old one.
ok = not gaps and min(after) > old[-1] and min(after) - old[-1] <= (1 << 20) + 1
sys.exit(0 if ok else 1)
PY
pass "seq continues across clean restarts and never repeats after kill -9"
stop_mosquitto

# ---- 4: SIGTERM again and again while stopping ------------------------------
for i in 1 2 3; do
  GW_LOG=$T/term$i.log
  "$GATEWAY" --demo --http 127.0.0.1:0 > "$GW_LOG" 2>&1 &
  GW_PID=$!
  wait_for "$GW_LOG" "canopen-gateway started" 20
  kill -TERM "$GW_PID"
  while kill -TERM "$GW_PID" 2>/dev/null; do :; done
  rc=0; wait "$GW_PID" || rc=$?
  [ "$rc" -eq 0 ] || fail "exit $rc with SIGTERMs during the stop (run $i), expected 0"
  grep -q "stopped" "$GW_LOG" || fail "no 'stopped' line (run $i)"
done
pass "SIGTERMs during the stop: a clean stop, exit 0 (3 runs)"
