#!/bin/sh
# Two interfaces at once: each is its own network (numbered from 1 in
# command-line order), both receive, both get the boot-up message.
. "$(dirname "$0")/lib.sh"

start_candump vcan1 "$T/boot1.dump" -n 1
start_gateway --can vcan0 --can vcan1 --log-level debug
wait_candump
grep -q "vcan1 77F#00" "$T/boot1.dump" || fail "no boot-up on vcan1: $(cat "$T/boot1.dump")"
for i in 1 2 3 4 5; do
  cansend vcan0 1A0#0$i
  cansend vcan1 2B0#0$i
done
wait_for "$GW_LOG" "net 1 vcan0 rx 1A0#05"
wait_for "$GW_LOG" "net 2 vcan1 rx 2B0#05"
[ "$(grep -c 'net 1 vcan0 rx 1A0' "$GW_LOG")" -eq 5 ] || fail "vcan0 frames missing"
[ "$(grep -c 'net 2 vcan1 rx 2B0' "$GW_LOG")" -eq 5 ] || fail "vcan1 frames missing"
grep -q 'vcan0 rx 2B0\|vcan1 rx 1A0' "$GW_LOG" && fail "frames crossed between networks"
ip link set vcan1 down
wait_for "$GW_LOG" "net 2 vcan1 bus error-active -> down"
cansend vcan0 1A0#06
wait_for "$GW_LOG" "net 1 vcan0 rx 1A0#06"
stop_gateway INT
pass "two networks received independently; one going down does not affect the other"
