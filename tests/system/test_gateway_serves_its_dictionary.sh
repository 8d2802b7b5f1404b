#!/bin/sh
# The gateway is a CANopen device on each network: its own object dictionary
# (CiA 301 7.5) is readable and writable over SDO, with the standard's rules.
. "$(dirname "$0")/lib.sh"
SDO=$BUILD_DIR/tests/sdo_tool

start_gateway --can vcan0 --can vcan1 --node-id 100
hex() { printf '%s' "$1" | od -An -tx1 | tr -d ' \n'; }
expect() {
  local pattern=$1; shift
  "$@" > "$T/out" 2>&1 || true
  grep -qE -- "$pattern" "$T/out" || fail "'$*' printed: $(cat "$T/out"), expected /$pattern/"
}
# 1008h manufacturer device name (segmented: longer than 4 bytes)
expect "^data $(hex canopen-gateway)$" "$SDO" upload vcan0 100 0x1008 0
# 1018h identity: sub 0 = 4 entries
expect "^data 04$" "$SDO" upload vcan0 100 0x1018 0
# issue 28 item 4: a device type (309, the CiA 309 gateway series) and the
# product code 43475700h ("CGW"), so masters can tell the gateway apart
expect "^data 35010000$" "$SDO" upload vcan0 100 0x1000 0
expect "^data 00574743$" "$SDO" upload vcan1 100 0x1018 2
# 1200h sub 1/2: the server's own COB-IDs 600h+100 = 664h, 580h+100 = 5E4h
expect "^data 64060000$" "$SDO" upload vcan0 100 0x1200 1
expect "^data e4050000$" "$SDO" upload vcan1 100 0x1200 2
# 1017h producer heartbeat time: write 500 ms, read it back
expect "^ok 2 " "$SDO" download vcan0 100 0x1017 0 --hex f401
expect "^data f401$" "$SDO" upload vcan0 100 0x1017 0
# each network has its own dictionary: vcan1 keeps the default 1000 ms
# (the gateway produces a heartbeat unless configured otherwise)
expect "^data e803$" "$SDO" upload vcan1 100 0x1017 0
# 7.5.2.4: 1003h sub 0 accepts only 0
expect "^abort 06090030 \(remote\)" "$SDO" download vcan0 100 0x1003 0 --hex 01
# read-only object
expect "^abort 06010002 \(remote\)" "$SDO" download vcan0 100 0x1018 1 --hex 01000000
stop_gateway
pass "gateway dictionary served over SDO on both networks"
