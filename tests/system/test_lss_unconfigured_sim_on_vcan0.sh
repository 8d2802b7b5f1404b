#!/bin/sh
# canopen-sim --node ff=EDS (issue 16 item 4) over real SocketCAN: the device
# starts unconfigured (CiA 305: no boot-up, no heartbeat, only LSS), answers
# the LSS frames of a master (here cansend: switch state selective by its
# LSS address, configure node-ID, switch state global to waiting; facts C.1)
# and then boots with the node-ID it was given (facts C.4 item 1).
. "$(dirname "$0")/lib.sh"
SIM_LOG=$T/sim.log
DUMP=$T/lss.dump

start_candump vcan0 "$DUMP"
start_sim "$SIM_LOG" --node 5="$EDS_DIR/cia402-drive.eds" --node ff="$EDS_DIR/cia401-io-module.eds" --heartbeat 200
wait_for "$SIM_LOG" "^node 5 boot-up" 10
sleep 0.5
grep -q "boot-up" "$SIM_LOG" && [ "$(grep -c boot-up "$SIM_LOG")" -eq 1 ] ||
  fail "expected only node 5's boot-up: $(grep boot-up "$SIM_LOG")"
pass "the unconfigured device is silent: only node 5 booted"

# Fastscan reset (BitChecked 80h): only the unconfigured device answers 4Fh.
cansend vcan0 7E5#5100000000800000
sleep 0.3
[ "$(grep -c '7E4#4F00000000000000' "$DUMP")" -eq 1 ] || fail "fastscan reset: expected one 4Fh answer: $(grep 7E4 "$DUMP")"
pass "fastscan reset answered by the one unconfigured device"

# Its LSS address: the I/O module's 1018h, serial 55000001h (the first unconfigured one).
cansend vcan0 7E5#40A1050000000000
cansend vcan0 7E5#4122880000000000
cansend vcan0 7E5#4203000100000000
cansend vcan0 7E5#4301000055000000
wait_for "$DUMP" "7E4#4400000000000000" 5
pass "switch state selective: 44h"

cansend vcan0 7E5#5E00000000000000
wait_for "$DUMP" "7E4#5EFF000000000000" 5
cansend vcan0 7E5#1114000000000000
wait_for "$DUMP" "7E4#1100000000000000" 5
pass "inquire node-ID FFh, configure node-ID 20: ok"

cansend vcan0 7E5#0400000000000000
wait_for "$SIM_LOG" "^node 20 boot-up" 10
wait_for "$DUMP" "714#00" 5
wait_for "$DUMP" "714#7F" 5
pass "switched to waiting, it booted as node 20 and sends its heartbeat"
kill -TERM "$SIM_PID"
wait "$SIM_PID" 2>/dev/null || true
