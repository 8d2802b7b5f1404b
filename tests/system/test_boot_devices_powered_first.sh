#!/bin/sh
# Issue 28 item 1, CiA 302-2: devices power up before the gateway (Linux boots
# slower), so their boot-up goes out before anyone listens. Against a device
# written for the test (tests/system/powered_device.py, python-can only):
# - up and pre-operational first: found by its heartbeat, identified by SDO
#   (1000h, 1018h), configured and started, as on a boot-up;
# - the gateway restarted under the running device: identified only; no
#   DCF write and no NMT command reaches it (nothing on 000h);
# - boot: {at-start: reset-communication}: the gateway resets the node's
#   communication at its start and configures it from its boot-up.
. "$(dirname "$0")/lib.sh"
DEV="/usr/bin/python3 $(dirname "$0")/powered_device.py"
EDS=$EDS_DIR/cia401-io-module.eds
PORT=$(free_port)

config() {  # config AT-START
  cat > "$T/gw.yaml" <<YAML
gateway: {id: gw1, state-dir: $T/state}
networks:
  - interface: vcan0
    boot: {at-start: $1}
    nodes:
      - {id: 10, name: io, eds: $EDS, boot: {check-identity: true, configure: true, start: true}}
YAML
}

$DEV vcan0 10 --heartbeat-ms 100 > "$T/dev.log" 2>&1 &
DEV_PID=$!
wait_for "$T/dev.log" "^ready" 20
sleep 0.3  # its boot-up and first heartbeats go out unheard

config as-found
start_gateway --config "$T/gw.yaml" --http "127.0.0.1:$PORT"
wait_for "$GW_LOG" "node 10 boot-up configuration: identify \(found in pre-operational without a boot-up" 10
wait_for "$GW_LOG" "node 10 boot-up configuration: done" 20
grep -q "node 10 boot-up configuration: FAILED" "$GW_LOG" && fail "the sequence failed"
wait_for "$T/dev.log" "^state operational" 5
grep -q "^sdo read 1000:00" "$T/dev.log" || fail "1000h not read"
grep -q "^sdo read 1018:04" "$T/dev.log" || fail "1018h sub 4 not read"
grep -q "^sdo write 1017:00" "$T/dev.log" || fail "the configuration (the EDS's 1017h) was not written"
grep -q "^sdo write 1A00:" "$T/dev.log" || fail "the PDO mapping was not written"
wait_for "$GW_LOG" "node 10 operational" 5
pass "a device pre-operational before the gateway started: $(grep -c '^sdo ' "$T/dev.log") SDO requests, then NMT start"
[ "$(grep -c '^boot-up' "$T/dev.log")" -eq 1 ] || fail "the device was reset (as-found must not)"
stop_gateway

# The gateway restarts under the running (operational) device.
: > "$T/dev.log"
start_candump vcan0 "$T/bus2.log"
start_gateway --config "$T/gw.yaml" --http "127.0.0.1:$PORT"
wait_for "$GW_LOG" "node 10 boot-up configuration: done \(already operational: identity checked, not configured or restarted" 20
sleep 0.5
stop_gateway
grep -q "^sdo read 1018:01" "$T/dev.log" || fail "the running device's identity was not checked"
grep -q "^sdo write" "$T/dev.log" && fail "wrote to a running device: $(grep '^sdo write' "$T/dev.log" | head -3)"
grep -q "^nmt" "$T/dev.log" && fail "sent NMT to a running device: $(grep '^nmt' "$T/dev.log")"
grep -qE "^\(.*\) vcan0 000#" "$T/bus2.log" && fail "an NMT frame on the bus: $(grep -E ' 000#' "$T/bus2.log")"
grep -q "^state" "$T/dev.log" && fail "the device changed state"
pass "a running device when the gateway restarts: identified ($(grep -c '^sdo read' "$T/dev.log") reads), not written, not restarted"

# at-start: reset-communication: reset, then configured from its boot-up.
: > "$T/dev.log"
config reset-communication
start_gateway --config "$T/gw.yaml" --http "127.0.0.1:$PORT"
wait_for "$GW_LOG" "boot at start: NMT reset-communication to node 10" 5
wait_for "$T/dev.log" "^nmt 0x82" 5
wait_for "$T/dev.log" "^boot-up" 5
wait_for "$GW_LOG" "node 10 initialising \(boot-up\)" 5
wait_for "$GW_LOG" "node 10 boot-up configuration: done" 20
grep -q "node 10 boot-up configuration: FAILED" "$GW_LOG" && fail "the sequence failed"
grep -q "^sdo write 1A00:" "$T/dev.log" || fail "not configured after the reset"
wait_for "$T/dev.log" "^state operational" 5
pass "at-start reset-communication: the node reset, booted, configured and started"
stop_gateway
kill "$DEV_PID" 2>/dev/null || true
