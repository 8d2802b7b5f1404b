#!/bin/sh
# Frames sent through the SocketCAN channel appear on the bus byte for byte:
# the gateway's own boot-up message (CiA 301 7.2.8.3.3: COB-ID 700h+node-ID,
# data 00h), and a mix of standard, extended, remote, empty and CAN FD frames
# sent by can_tool through the same channel code. The text form is candump's
# (FD flags nibble includes FDF = 4), so the comparison is exact.
. "$(dirname "$0")/lib.sh"

start_candump vcan0 "$T/boot.dump" -n 1
start_gateway --can vcan0 --node-id 5
wait_candump
stop_gateway
boot=$(awk '{print $3}' "$T/boot.dump")
[ "$boot" = "705#00" ] || fail "boot-up frame on the bus was '$boot', expected 705#00"
pass "boot-up frame 705#00"

python3 - > "$T/frames.txt" <<'PY'
import random
r = random.Random(42)
fd_lens = [0, 1, 8, 12, 16, 20, 24, 32, 48, 64]
for i in range(3000):
    k = i % 6
    if k == 0:   print(f"{r.randrange(0x800):03X}#" + bytes(r.randrange(256) for _ in range(r.randrange(9))).hex().upper())
    elif k == 1: print(f"{r.randrange(0x20000000):08X}#" + bytes(r.randrange(256) for _ in range(8)).hex().upper())
    elif k == 2: print(f"{r.randrange(0x800):03X}#R" + (str(r.randrange(1, 9))))
    elif k == 3: print(f"{r.randrange(0x800):03X}#")
    elif k == 4: print(f"{r.randrange(0x800):03X}##{4 | r.randrange(4)}" + bytes(r.randrange(256) for _ in range(r.choice(fd_lens))).hex().upper())
    else:        print(f"{r.randrange(0x20000000):08X}##5" + bytes(r.randrange(256) for _ in range(64)).hex().upper())
PY
n=$(wc -l < "$T/frames.txt")
start_candump vcan0 "$T/tx.dump" -n "$n"
"$CAN_TOOL" send vcan0 < "$T/frames.txt" || fail "can_tool send failed"
wait_candump
awk '{print $3}' "$T/tx.dump" > "$T/seen.txt"
if ! cmp -s "$T/frames.txt" "$T/seen.txt"; then
  diff "$T/frames.txt" "$T/seen.txt" | head -n 10
  fail "candump saw different frames than were sent"
fi
pass "$n frames seen by candump byte for byte, in order"
