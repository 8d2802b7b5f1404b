#!/bin/sh
# Interface down/up and removal/re-creation are reported as bus-state
# changes, and reception resumes without restarting the gateway.
. "$(dirname "$0")/lib.sh"

start_gateway --can vcan0 --log-level debug
cansend vcan0 101#01
wait_for "$GW_LOG" " rx 101#01"

ip link set vcan0 down
wait_for "$GW_LOG" "vcan0 bus error-active -> down \(link-down"
ip link set vcan0 up
wait_for "$GW_LOG" "vcan0 bus down -> error-active \(link-up"
cansend vcan0 102#02
wait_for "$GW_LOG" " rx 102#02"
pass "down/up reported, reception resumed"

ip link del vcan0
wait_for "$GW_LOG" "vcan0 bus error-active -> down \(link-removed"
ip link add dev vcan0 type vcan
sleep 0.3
grep -q "link-up" "$GW_LOG" && [ "$(grep -c 'down -> error-active' "$GW_LOG")" -eq 1 ] || fail "reported up while the new interface was still down"
ip link set vcan0 up
wait_count "$GW_LOG" "vcan0 bus down -> error-active \(link-up" 2
cansend vcan0 103#03
wait_for "$GW_LOG" " rx 103#03"
stop_gateway
grep -q "reopens 1" "$GW_LOG" || fail "expected exactly one socket reopen: $(grep 'vcan0: rx' "$GW_LOG")"
pass "removal and re-creation reported, socket reopened, reception resumed"
