#!/bin/sh
# CiA 302-3 program download over REST on real SocketCAN (issue 17 item 5,
# contract "Remote configuration and maintenance"): a 256 KiB image PUT to
# a canopen-sim I/O module (node 10) on vcan0. The gateway stops the
# program, clears it, block-downloads the image to 1F50h sub 1, reads 1F56h
# and starts it; the request answers when done with the identification.
# Its progress arrives as `transfer` events on MQTT
# (canopen/<gw>/<net>/<node>/transfer): running with bytes done/total, then
# done. Afterwards GET .../sdo/1F56/1 shows the new identification (the
# simulated device's is the image's CRC-32) and 1F51h sub 1 the program
# running.
# uml-run: --timeout 220
. "$(dirname "$0")/lib.sh"
PORT=$(free_port)
NODE=http://127.0.0.1:$PORT/api/v1/networks/1/nodes/10
CALL="/usr/bin/python3 $(dirname "$0")/maint_call.py"

start_mosquitto
mosquitto_sub -h 127.0.0.1 -p $MOSQ_PORT -q 1 -v -t "canopen/gw1/1/10/transfer" > "$T/mqtt.log" 2>&1 &
SUB_PID=$!
cat > "$T/gw.yaml" <<YAML
gateway: {id: gw1, state-dir: $T/state}
networks:
  - interface: vcan0
    nodes:
      - {id: 10, name: io, eds: $EDS_DIR/cia401-io-module.eds, boot: {start: true}}
mqtt:
  uri: tcp://127.0.0.1:$MOSQ_PORT
YAML
# The gateway first: it starts the device when it hears its boot-up.
start_gateway --config "$T/gw.yaml" --http "127.0.0.1:$PORT"
start_sim "$T/sim.log" --node 10="$EDS_DIR/cia401-io-module.eds" --heartbeat 200
wait_for "$GW_LOG" "node 10 operational" 20

head -c 262144 /dev/urandom > "$T/app.bin"
CRC=$(/usr/bin/python3 -c 'import sys, zlib; print(zlib.crc32(open(sys.argv[1], "rb").read()))' "$T/app.bin")

$CALL PUT "$NODE/program/1" "$T/app.bin" > "$T/put.out"
head -n 1 "$T/put.out" | grep -q '^200$' || fail "PUT program/1: $(cat "$T/put.out")"
grep -q "\"bytes\":262144,\"started\":true,\"identification\":$CRC," "$T/put.out" \
  || fail "answer without bytes, start or identification $CRC: $(tail -n 1 "$T/put.out")"
grep -q "audit: program download by .*net 1 node 10 program 1, 262144 bytes: ok, started" "$GW_LOG" \
  || fail "no audit line for the download"
pass "PUT program/1: 262144 bytes, started, identification $CRC"

# The events: published with QoS 1 as they happen; the last one is done.
wait_for "$T/mqtt.log" '"status": ?"done"' 20
kill "$SUB_PID" 2>/dev/null || true
/usr/bin/python3 - "$T/mqtt.log" <<'PY' || fail "transfer events out of order: $(cat "$T/mqtt.log" | head -n 20)"
import json, sys
events = []
for line in open(sys.argv[1]):
    topic, _, payload = line.partition(" ")
    if topic != "canopen/gw1/1/10/transfer":
        continue
    ev = json.loads(payload)
    ev = ev.get("transfer", ev)
    events.append(ev)
assert events, "no events"
assert all(e["operation"] == "program-download" for e in events), events
assert [e["status"] for e in events[:-1]] == ["running"] * (len(events) - 1), events
assert events[-1]["status"] == "done", events[-1]
done = [int(e["done"]) for e in events if e.get("unit") == "bytes" and "done" in e]
assert done == sorted(done), done
assert any(0 < d < 262144 for d in done), done
assert done[-1] == 262144 and int(events[-1]["total"]) == 262144, events[-1]
print(len(events), "events, bytes", done[:3], "...", done[-1])
PY
pass "MQTT canopen/gw1/1/10/transfer: running with bytes in order, then done"

$CALL GET "$NODE/sdo/1F56/1" > "$T/id.out"
grep -q "\"value\":$CRC" "$T/id.out" || fail "1F56h sub 1: $(tail -n 1 "$T/id.out"), expected $CRC"
$CALL GET "$NODE/sdo/1F51/1" > "$T/state.out"
grep -q '"value":1' "$T/state.out" || fail "1F51h sub 1 (program state): $(tail -n 1 "$T/state.out")"
pass "GET sdo/1F56/1 = $CRC (CRC-32 of the image), 1F51h sub 1 = 1 (running)"

kill -TERM "$SIM_PID"
wait "$SIM_PID" 2>/dev/null || true
stop_gateway
stop_mosquitto
