#!/bin/sh
# LSS (CiA 305) over REST on real SocketCAN (issue 16, contract "LSS master"):
# a canopen-sim device that starts without a node-ID (FFh: silent but for
# LSS) on vcan0; REST fastscan finds its identity (its 1018h), configure
# gives it node-ID 42 and stores; it leaves configuration state with the
# pending ID and boots with it (a normal boot-up the gateway sees: GET nodes
# lists 42), and an NMT start makes it operational.
. "$(dirname "$0")/lib.sh"
PORT=$(free_port)
BASE=http://127.0.0.1:$PORT/api/v1/networks/1

# call METHOD URL [BODY]: prints "STATUS BODY" (errors too); loopback without
# tokens acts as admin (contract: LSS needs admin).
call() {
  /usr/bin/python3 - "$@" <<'EOF'
import sys, urllib.request, urllib.error
method, url = sys.argv[1], sys.argv[2]
data = sys.argv[3].encode() if len(sys.argv) > 3 else None
req = urllib.request.Request(url, data=data, method=method)
if data is not None:
    req.add_header("Content-Type", "application/json")
try:
    with urllib.request.urlopen(req, timeout=60) as r:
        print(r.status, r.read().decode())
except urllib.error.HTTPError as e:
    print(e.code, e.read().decode())
EOF
}

start_gateway --can vcan0 --http "127.0.0.1:$PORT"
start_sim "$T/sim.log" --node ff="$EDS_DIR/cia401-io-module.eds" --heartbeat 200
sleep 0.5
grep -q "boot-up" "$GW_LOG" && fail "the unconfigured device booted before it had a node-ID"
pass "the unconfigured device is silent (no boot-up)"

# Fastscan with the default step window (100 ms: 133 windows, about 13 s).
call POST "$BASE/lss/fastscan" > "$T/scan.out"
grep -q '^200 ' "$T/scan.out" || fail "fastscan: $(cat "$T/scan.out")"
IDENTITY=$(/usr/bin/python3 -c 'import json,sys; print(json.dumps(json.loads(sys.stdin.read().split(" ",1)[1])["identity"]))' < "$T/scan.out")
echo "$IDENTITY" | grep -q '"vendorId": 1441' || fail "fastscan found another vendor: $IDENTITY"
echo "$IDENTITY" | grep -q '"serialNumber": 1426063361' || fail "not the unconfigured device's serial (55000001h): $IDENTITY"
pass "fastscan found the device: $IDENTITY"

call GET "$BASE/lss/devices" > "$T/devices.out"
grep -q '"nodeId":null' "$T/devices.out" || fail "GET lss/devices: $(cat "$T/devices.out")"

call POST "$BASE/lss/configure" "{\"identity\": $IDENTITY, \"nodeId\": 42, \"store\": true}" > "$T/configure.out"
grep -q '^200 .*"nodeId":42.*"stored":true' "$T/configure.out" || fail "configure: $(cat "$T/configure.out")"
grep -q "audit: LSS configure by .*-> node-ID 42, store: ok" "$GW_LOG" || fail "no audit line for the LSS configure"
pass "configure: node-ID 42 set and stored"

wait_for "$GW_LOG" "node 42 initialising \(boot-up\)" 10
call GET "$BASE/nodes" > "$T/nodes.out"
grep -q '"node":42' "$T/nodes.out" || fail "GET nodes does not list 42: $(cat "$T/nodes.out")"
pass "the device booted as node 42 and the gateway lists it"

call POST "$BASE/nodes/42/nmt" '{"command": "start"}' > "$T/nmt.out"
grep -q '^200 ' "$T/nmt.out" || fail "NMT start: $(cat "$T/nmt.out")"
wait_for "$GW_LOG" "node 42 operational \(heartbeat\)" 10
call GET "$BASE/nodes/42" > "$T/node.out"
grep -q '"state":"operational"' "$T/node.out" || fail "node 42 is not operational: $(cat "$T/node.out")"
pass "NMT start: node 42 operational"

# Nobody without a node-ID is left: 404 after one step window.
call POST "$BASE/lss/fastscan" > "$T/scan2.out"
grep -q '^404 .*no unconfigured device answered' "$T/scan2.out" || fail "second fastscan: $(cat "$T/scan2.out")"
pass "a second fastscan finds nobody unconfigured (404)"

kill -KILL "$SIM_PID"
wait "$SIM_PID" 2>/dev/null || true
stop_gateway
