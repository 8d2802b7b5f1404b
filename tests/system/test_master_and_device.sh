#!/bin/sh
# The gateway as NMT master against a CANopen device in another process
# (device_tool, built from the stack) over real SocketCAN: boot-up
# (CiA 301 7.2.8.3.3), NMT start (7.2.8.3.1), heartbeat (7.2.8.3.2) and its
# consumer configured over SDO in 1016h (7.5.2.19), event-driven TPDOs decoded
# by name from the device's EDS (7.2.2) and only while operational
# (7.3.2.2.5), EMCY (7.2.7), and a node lost when its heartbeats stop.
. "$(dirname "$0")/lib.sh"
SDO=$BUILD_DIR/tests/sdo_tool
DEVICE=$BUILD_DIR/tests/device_tool
EDS=${SOURCE_DIR:-$(dirname "$0")/../..}/deploy/eds/cia402-drive.eds
DEV_LOG=$T/device.log

# The gateway first, so it sees the device's boot-up message.
start_gateway --can vcan0 --eds 5="$EDS" --log-level debug
"$DEVICE" vcan0 5 "$EDS" --heartbeat 100 --emcy-after 1500 0x3210 --tpdo-period 200 > "$DEV_LOG" 2>&1 &
DEV_PID=$!
wait_for "$DEV_LOG" "^ready" 20

wait_for "$GW_LOG" "node 5 initialising \(boot-up\)" 10
wait_for "$GW_LOG" "node 5 pre-operational \(heartbeat\)" 10
pass "gateway saw node 5 boot up, then pre-operational"

# Pre-operational: no PDOs (7.3.2.2.5), so nothing decoded yet.
sleep 0.6
! grep -q "node 5 TPDO" "$GW_LOG" || fail "node 5 sent a TPDO while pre-operational"

# 1016h sub 1 = node 5, 300 ms (three device heartbeat periods): the gateway
# re-reads it into its heartbeat consumer.
"$SDO" download vcan0 127 0x1016 1 --hex 2c010500 > "$T/sdo.out" 2>&1 ||
  fail "writing the gateway's 1016h sub 1 failed: $(cat "$T/sdo.out")"
wait_for "$GW_LOG" "heartbeat consumers reconfigured from 1016h" 5

cansend vcan0 000#0105
wait_for "$GW_LOG" "node 5 operational \(heartbeat\)" 5
pass "NMT start: the gateway saw node 5 operational from its heartbeats"

wait_count "$GW_LOG" "node 5 TPDO1 6041h/00 Statusword=[0-9]+" 3 10
grep -q "^device_tool\|error" "$DEV_LOG" && fail "device reported: $(cat "$DEV_LOG")"
pass "TPDO1 decoded by name: $(grep -m1 -oE "node 5 TPDO1 .*" "$GW_LOG")"

wait_for "$GW_LOG" "node 5 EMCY 3210h, error register 01h: Voltage" 10
pass "EMCY: $(grep -m1 -oE "node 5 EMCY .*" "$GW_LOG")"

# Back to pre-operational: the TPDOs stop.
cansend vcan0 000#8005
wait_for "$GW_LOG" "node 5 pre-operational \(heartbeat\)" 5
sleep 0.3
before=$(grep -c "node 5 TPDO1" "$GW_LOG")
sleep 0.8
after=$(grep -c "node 5 TPDO1" "$GW_LOG")
[ "$before" -eq "$after" ] || fail "node 5 sent $((after - before)) TPDOs after entering pre-operational"
pass "no TPDOs in pre-operational"

grep -q "node 5 lost" "$GW_LOG" && fail "node 5 reported lost while it was sending heartbeats"
kill -KILL "$DEV_PID"
wait "$DEV_PID" 2>/dev/null || true
wait_for "$GW_LOG" "node 5 lost" 5
pass "node 5 lost after the device was killed"

stop_gateway
