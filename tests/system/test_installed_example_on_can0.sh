#!/bin/sh
# uml-run: --vcan can0
# The example configuration's real-bus half, as its comments tell a user to
# make it (simulated network deleted, can0 network uncommented), on can0
# with devices that match its EDS files (canopen-sim with the same files):
# both nodes are identified, configured and started as the file asks, and
# the gateway does it as the systemd unit runs it, an unprivileged user
# without capabilities (SocketCAN raw sockets need none).
# Paths as installed: /usr/share/canopen-gateway is the source's deploy/.
. "$(dirname "$0")/lib.sh"
. "$(dirname "$0")/installed.sh"
SIM_PID=
# The service's user reads the configuration and owns its state: a directory
# it may enter (the harness's is private), on UML's tmpfs (the host file
# system it sees keeps no other owner).
D=$(mktemp -d /run/installed-example.XXXXXX)
chmod 755 "$D"
trap 'kill $SIM_PID 2>/dev/null || true; rm -rf "$D"' EXIT

sed "s|/usr/share/canopen-gateway/|$SOURCE_DIR/deploy/|g" "$SOURCE_DIR/deploy/gateway.example.yaml" > "$D/example.yaml"
real_bus_config "$D/example.yaml" "$D/gateway.yaml"
service_state_dir "$D/state"
export STATE_DIRECTORY=$D/state
PORT=$(free_port)
GW_LOG=$T/gateway.log
# --mqtt: no broker here; the example's localhost:1883 would only be retried.
$AS_SERVICE "$GATEWAY" --config "$D/gateway.yaml" --http "127.0.0.1:$PORT" > "$GW_LOG" 2>&1 &
GW_PID=$!
wait_for "$GW_LOG" "canopen-gateway started" 20
if [ -n "$AS_SERVICE" ]; then
  grep -qE '^Uid:\s+65534\s' "/proc/$GW_PID/status" || fail "the gateway does not run as uid 65534"
  grep -qE '^CapEff:\s+0+$' "/proc/$GW_PID/status" || fail "the gateway has capabilities: $(grep Cap "/proc/$GW_PID/status")"
fi
"$SIM" --can can0 --node 5="$SOURCE_DIR/deploy/eds/cia402-drive.eds" \
  --node 10="$SOURCE_DIR/deploy/eds/cia401-io-module.eds" --heartbeat 500 > "$T/sim.log" 2>&1 &
SIM_PID=$!
wait_for "$T/sim.log" "^ready" 20
for n in 5 10; do
  wait_for "$GW_LOG" "net 1 can0 node $n boot-up configuration: done" 30
done
wait_for "$GW_LOG" "net 1 can0 node 5 operational" 20
wait_for "$GW_LOG" "net 1 can0 node 10 operational" 20
grep -q "net 1 can0 node 5 boot-up configuration: identity checked" "$GW_LOG" || fail "node 5 not identified"
# Still there after twice node 5's heartbeat consumer time (1500 ms) and
# node 10's (3 x its EDS's 1017h, 1000 ms).
sleep 3.5
grep -E "net 1 can0 node [0-9]+ .*(lost|failed|error|mismatch)" "$GW_LOG" && fail "a node failed (above)"
/usr/bin/python3 - "$PORT" <<'PY' || fail "REST: SDO read of node 5 on can0"
import json, sys, urllib.request
r = json.load(urllib.request.urlopen(f"http://127.0.0.1:{sys.argv[1]}/api/v1/networks/1/nodes/5/sdo/1018/1", timeout=10))
sys.exit(0 if r.get("value") == 0x5A1 else 1)
PY
pass "the example on can0, as an unprivileged user without capabilities: nodes 5 and 10 identified, started and operational, SDO over REST"
stop_gateway
