#!/bin/sh
# Capture (issue 18, contract "Bus trace and capture"): the gateway on vcan0
# with a canopen-sim device; GET .../capture?last=S&format=candump gives
# candump -L lines of what was on the bus, both directions (the device's
# heartbeats and TPDOs received, the gateway's own heartbeat sent), every
# one of them seen on vcan0 by a real candump too; canplayer (can-utils)
# replays the file onto vcan1, where candump sees the identical frames
# (ids and data) in the same order.
. "$(dirname "$0")/lib.sh"
PORT=$(free_port)
BASE=http://127.0.0.1:$PORT/api/v1/networks/1

start_candump vcan0 "$T/bus.dump"
BUS_DUMP_PID=$CANDUMP_PID
start_gateway --can vcan0 --http "127.0.0.1:$PORT"
start_sim "$T/sim.log" --node 5="$EDS_DIR/cia401-io-module.eds" --heartbeat 100
sleep 3

/usr/bin/python3 - "$BASE/capture?last=2&format=candump" "$T/cap.log" "$T/cap.head" <<'PY'
import sys, urllib.request
with urllib.request.urlopen(sys.argv[1], timeout=30) as r:
    open(sys.argv[2], "wb").write(r.read())
    open(sys.argv[3], "w").write(f"{r.status}\n{r.headers}")
PY
grep -q '^200' "$T/cap.head" || fail "capture: $(cat "$T/cap.head")"
grep -qi '^Content-Disposition: attachment; filename="canopen-net1-.*\.log"' "$T/cap.head" || fail "no file name: $(cat "$T/cap.head")"
n=$(wc -l < "$T/cap.log")
[ "$n" -gt 10 ] || fail "only $n frames captured in 2 s: $(cat "$T/cap.log")"
grep -Eqv '^\([0-9]{10}\.[0-9]{6}\) vcan0 [0-9A-F]{3}#[0-9A-F]*$' "$T/cap.log" && fail "not candump -L lines: $(grep -Ev '^\([0-9]{10}\.[0-9]{6}\) vcan0 [0-9A-F]{3}#' "$T/cap.log" | head -3)"
grep -q ' 705#' "$T/cap.log" || fail "the device's heartbeat (received) is not in the capture"
grep -q ' 77F#' "$T/cap.log" || fail "the gateway's own heartbeat (sent) is not in the capture"
pass "$n frames captured as candump -L lines, received and sent"

stop_gateway
kill "$SIM_PID"; wait "$SIM_PID" 2>/dev/null || true
sleep 0.2
kill "$BUS_DUMP_PID" 2>/dev/null || true
wait "$BUS_DUMP_PID" 2>/dev/null || true
# Every captured frame was on the bus (candump saw at least as many of it).
awk '{print $3}' "$T/bus.dump" | sort | uniq -c | awk '{print $2, $1}' > "$T/bus.count"
awk '{print $3}' "$T/cap.log" | sort | uniq -c | awk '{print $2, $1}' | while read -r frame count; do
  seen=$(awk -v f="$frame" '$1 == f {print $2}' "$T/bus.count")
  [ "${seen:-0}" -ge "$count" ] || fail "captured $count x $frame, candump saw it ${seen:-0} times"
done
pass "every captured frame was seen on vcan0 by candump"

start_candump vcan1 "$T/replay.dump" -n "$n"
canplayer -I "$T/cap.log" -t -g 1 vcan1=vcan0 || fail "canplayer failed on the capture"
wait_candump
awk '{print $3}' "$T/cap.log" > "$T/cap.frames"
awk '{print $3}' "$T/replay.dump" > "$T/replay.frames"
if ! cmp -s "$T/cap.frames" "$T/replay.frames"; then
  diff "$T/cap.frames" "$T/replay.frames" | head -n 10
  fail "canplayer's replay on vcan1 differs from the capture"
fi
pass "canplayer replayed the capture onto vcan1: $n identical frames in order"
