#!/bin/sh
# SDO over real SocketCAN between two processes (CiA 301 7.2.4): the stack's
# server (sdo_tool serve) and client (sdo_tool upload/download) on vcan0.
# Expedited, segmented and block transfers both ways, including 1 MiB block
# transfers whose CRC (7.2.4.3.16) matches the data, and a remote abort.
. "$(dirname "$0")/lib.sh"
SDO=$BUILD_DIR/tests/sdo_tool

"$SDO" serve vcan0 5 > "$T/server.out" 2>&1 &
SERVER=$!
wait_for "$T/server.out" "^ready"

expect() {  # expect PATTERN COMMAND...: runs COMMAND, checks its output
  local pattern=$1; shift
  "$@" > "$T/out" 2>&1 || true
  grep -qE -- "$pattern" "$T/out" || fail "'$*' printed: $(head -c 300 "$T/out"), expected /$pattern/"
}

# 7.2.4.3.3 / 7.2.4.3.6 expedited
expect "^ok 4 " "$SDO" download vcan0 5 0x2002 0 --hex 78563412 --mode expedited
expect "^data 78563412$" "$SDO" upload vcan0 5 0x2002 0 --mode expedited
expect "^data 02$" "$SDO" upload vcan0 5 0x1200 0   # 1200h sub 0: highest sub-index, 2
pass "expedited download and upload"

# 7.2.4.3.4 / 7.2.4.3.7 segmented
text=$(printf 'segmented transfer over real SocketCAN' | od -An -tx1 | tr -d ' \n')
expect "^ok 38 " "$SDO" download vcan0 5 0x2001 0 --hex "$text" --mode segmented
expect "^data $text$" "$SDO" upload vcan0 5 0x2001 0 --mode segmented
pass "segmented download and upload"

crc_of() {  # CRC-16 of CiA 301 7.2.4.3.16: x^16+x^12+x^5+1, initial 0
  python3 - "$1" <<'PY'
import sys
crc = 0
for b in open(sys.argv[1], "rb").read():
    crc ^= b << 8
    for _ in range(8):
        crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
print(f"{crc:04x}")
PY
}

# 7.2.4.3.12-15 block upload of the server's 1 MiB pattern
expect "^ok 1048576 crc " "$SDO" upload vcan0 5 0x2000 0 --mode block --out "$T/up.bin"
[ "$(wc -c < "$T/up.bin")" -eq 1048576 ] || fail "block upload returned $(wc -c < "$T/up.bin") bytes"
want=$(crc_of "$T/up.bin")
grep -q "crc $want" "$T/out" || fail "CRC printed by the client ($(cat "$T/out")) differs from the data's CRC $want"
pass "1 MiB block upload, CRC $want"

# 7.2.4.3.8-11 block download of 1 MiB of other data, read back by block upload
head -c 1048576 /dev/urandom > "$T/down.bin"
expect "^ok 1048576 crc $(crc_of "$T/down.bin")" "$SDO" download vcan0 5 0x2000 0 --file "$T/down.bin" --mode block
expect "^ok 1048576 " "$SDO" upload vcan0 5 0x2000 0 --mode block --out "$T/back.bin"
cmp -s "$T/down.bin" "$T/back.bin" || fail "1 MiB written by block download did not read back identically"
pass "1 MiB block download read back identically"

# Auto mode picks block for large data and expedited for small, transparently.
expect "^ok 1048576 " "$SDO" upload vcan0 5 0x2000 0 --out "$T/auto.bin"
cmp -s "$T/down.bin" "$T/auto.bin" || fail "auto-mode upload differs"

# 7.2.4.3.17 abort: object does not exist, reported as the server's abort
expect "^abort 06020000 \(remote\): Object does not exist in the object dictionary" "$SDO" upload vcan0 5 0x6000 0
# a node nobody serves: local timeout 05040000h
expect "^abort 05040000 \(local\): SDO protocol timed out" "$SDO" upload vcan0 6 0x1000 0 --timeout 300
pass "remote abort and local timeout reported"

kill -TERM $SERVER
wait $SERVER || fail "server exited with an error"
