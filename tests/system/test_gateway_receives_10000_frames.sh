#!/bin/sh
# The gateway receives 10,000 frames sent by cangen at full speed, none
# missing: count and order checked against cangen's incrementing payload.
. "$(dirname "$0")/lib.sh"

start_gateway --can vcan0 --log-level debug
cangen vcan0 -n 10000 -g 0 -I 123 -L 8 -D i -p 100
wait_count "$GW_LOG" " rx 123#" 10000 120
stop_gateway INT

grep -o ' rx 123#[0-9A-F]*' "$GW_LOG" | sed 's/.*#//' > "$T/payloads"
count=$(wc -l < "$T/payloads")
[ "$count" -eq 10000 ] || fail "received $count frames, expected 10000"
# cangen -D i puts a little-endian counter in the payload: check it is +1 per frame.
python3 - "$T/payloads" <<'PY' || fail "payload sequence has gaps or is out of order"
import sys
vals = [int.from_bytes(bytes.fromhex(l.strip()), "little") for l in open(sys.argv[1])]
bad = [i for i in range(1, len(vals)) if vals[i] != vals[i - 1] + 1]
if bad:
    print(f"first break at frame {bad[0]}: {vals[bad[0]-1]:#x} -> {vals[bad[0]]:#x}; {len(bad)} breaks")
    sys.exit(1)
print(f"sequence {vals[0]:#x}..{vals[-1]:#x} continuous")
PY
grep -q "vcan0: rx 10001 frames" "$GW_LOG" || grep "vcan0: rx" "$GW_LOG"
grep -q "rx dropped 0," "$GW_LOG" || fail "gateway reports dropped frames: $(grep 'vcan0: rx' "$GW_LOG")"
pass "10000 frames received in order, none dropped"
