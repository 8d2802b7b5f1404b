#!/bin/sh
# The gateway on real SocketCAN publishing to a real mosquitto
# (../shared/api-contract.md, "MQTT topics"): simulated CiA 402/401 devices
# (canopen-sim) boot, are identified and started by the gateway (CiA 302
# spirit), and their heartbeats, decoded TPDOs, EMCYs and NMT states reach an
# MQTT subscriber with per-network seq without gaps; a WebSocket client gets
# the same events through its filter; SDO read/write and NMT requests over
# MQTT 5 and 3.1.1 get their replies (tokenless: mqtt.requests-role), while
# a request asking for a reply on the gateway's own status topic is dropped
# unanswered; a killed device is reported lost; after a clean stop nothing
# retained claims a node runs.
# uml-run: --timeout 200
. "$(dirname "$0")/lib.sh"
GW=gw1
start_mosquitto
mosquitto_sub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv311 -q 1 -v -t "canopen/#" > "$T/mqtt.log" 2>&1 &
SUB_PID=$!
mosquitto_sub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv5 -v -t "reply/#" > "$T/replies.log" 2>&1 &
sleep 0.5

cat > "$T/gw.yaml" <<YAML
gateway: {id: $GW, state-dir: $T/state}
networks:
  - interface: vcan0
    heartbeat-ms: 500
    nodes:
      - {id: 5, name: drive-x, eds: $EDS_DIR/cia402-drive.eds, heartbeat-consumer-ms: 800, boot: {start: true}}
      - {id: 10, name: io-rack, eds: $EDS_DIR/cia401-io-module.eds, heartbeat-consumer-ms: 800, boot: {start: true}}
mqtt:
  uri: tcp://127.0.0.1:$MOSQ_PORT
  qos: {default: 1}
  requests-role: operator   # tokenless requests are refused without it
YAML
start_gateway --config "$T/gw.yaml" --log-level debug
wait_for "$T/mqtt.log" "^canopen/$GW/status .*\"state\": ?\"online\"" 10
pass "retained online status"

start_sim "$T/sim.log" --node 5="$EDS_DIR/cia402-drive.eds" --node 10="$EDS_DIR/cia401-io-module.eds" \
  --heartbeat 200 --tpdo-period 100 --emcy-period 1500
wait_for "$T/mqtt.log" "^canopen/$GW/1/5/state .*\"state\": ?\"initialising\".*\"cause\": ?\"boot-up\"" 15
wait_for "$T/mqtt.log" "^canopen/$GW/1/5/boot .*\"done\"" 15
wait_for "$T/mqtt.log" "^canopen/$GW/1/5/state .*\"operational\"" 10
wait_for "$T/mqtt.log" "^canopen/$GW/1/10/state .*\"operational\"" 10
pass "nodes 5 and 10 identified, started, operational"
wait_for "$T/mqtt.log" "^canopen/$GW/1/5/heartbeat " 5
wait_for "$T/mqtt.log" "^canopen/$GW/1/5/tpdo/1 .*\"name\": ?\"Statusword\".*\"type\": ?\"u16\"" 10
wait_for "$T/mqtt.log" "^canopen/$GW/1/10/tpdo/1 " 10
pass "TPDOs decoded by name and type: $(payloads "$T/mqtt.log" "canopen/$GW/1/5/tpdo/1" | head -1)"
wait_for "$T/mqtt.log" "^canopen/$GW/1/5/emcy .*\"description\": ?\"[A-Za-z]" 10
pass "EMCY with description: $(payloads "$T/mqtt.log" "canopen/$GW/1/5/emcy" | head -1)"

# WebSocket: only node 5's TPDOs, through the client's filter.
/usr/bin/python3 "$(dirname "$0")/ws_client.py" 127.0.0.1 8080 '{"networks":[1],"nodes":[5],"kinds":["tpdo"]}' 10 \
  > "$T/ws.log" 2>&1 || fail "WebSocket client: $(cat "$T/ws.log")"
[ "$(grep -c '"tpdo"' "$T/ws.log")" -ge 10 ] || fail "WebSocket: expected 10 tpdo events: $(cat "$T/ws.log")"
grep -v '^#' "$T/ws.log" | grep -v '"node": *5[,}]' | grep -q . && fail "WebSocket filter let other nodes through: $(grep -v '"node": *5[,}]' "$T/ws.log" | head -3)"
pass "WebSocket client got node 5 TPDOs only"

# SDO read over MQTT 5 (response topic + correlation data) and 3.1.1 (in the body).
mosquitto_pub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv5 -t "canopen/$GW/1/5/sdo/read" \
  -m '{"index": "0x1018", "subIndex": 1}' -D publish response-topic reply/v5 -D publish correlation-data abc
wait_for "$T/replies.log" '^reply/v5 .*"value"' 10
pass "SDO read over MQTT 5: $(grep '^reply/v5' "$T/replies.log" | head -1)"
mosquitto_pub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv311 -t "canopen/$GW/1/10/sdo/read" \
  -m '{"index": "1000", "subIndex": 0, "replyTo": "reply/v311", "correlationId": "c1"}'
wait_for "$T/replies.log" '^reply/v311 .*"value".*' 10
grep '^reply/v311' "$T/replies.log" | grep -q '"c1"' || fail "3.1.1 reply without the correlation id"
pass "SDO read over MQTT 3.1.1: $(grep '^reply/v311' "$T/replies.log" | head -1)"
mosquitto_pub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv5 -t "canopen/$GW/1/5/sdo/write" \
  -m '{"index": "0x6060", "subIndex": 0, "value": 3}' -D publish response-topic reply/write
wait_for "$T/replies.log" '^reply/write ' 10
grep '^reply/write' "$T/replies.log" | grep -q 'abortCode\|"value"' || fail "no SDO write reply"
grep -q "audit: SDO write" "$GW_LOG" || fail "no audit line for the SDO write"
pass "SDO write over MQTT: $(grep '^reply/write' "$T/replies.log" | head -1)"

mosquitto_pub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv5 -t "canopen/$GW/1/5/nmt" -m '{"command": "stop"}' \
  -D publish response-topic reply/nmt
wait_for "$T/replies.log" '^reply/nmt ' 10
wait_for "$T/mqtt.log" "^canopen/$GW/1/5/state .*\"stopped\"" 10
pass "NMT stop over MQTT: node 5 stopped"

# A reply must not land in the gateway's own topics (contract, "MQTT topics").
mosquitto_pub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv5 -t "canopen/$GW/1/10/sdo/read" \
  -m '{"index": "0x1018", "subIndex": 1}' -D publish response-topic "canopen/$GW/status"
wait_for "$GW_LOG" "dropped unanswered: reply topic 'canopen/$GW/status'" 10
grep "^canopen/$GW/status " "$T/mqtt.log" | grep -q '"value"' && fail "a reply was published to canopen/$GW/status"
pass "reply to canopen/$GW/status refused, nothing published there"

# The same gateway over REST and /metrics (issue 6 builds on these).
http_get() { /usr/bin/python3 -c 'import sys, urllib.request; print(urllib.request.urlopen(sys.argv[1], timeout=10).read().decode())' "$1"; }
# Node 10: node 5 is stopped, and a stopped node has no SDO (7.3.2.2.5).
http_get http://127.0.0.1:8080/api/v1/networks/1/nodes/10/sdo/1018/1 > "$T/rest.out" 2>&1 || fail "REST SDO read: $(cat "$T/rest.out")"
grep -q '"value"' "$T/rest.out" || fail "REST SDO read: $(cat "$T/rest.out")"
http_get http://127.0.0.1:8080/metrics > "$T/metrics.out" 2>&1 || fail "/metrics: $(cat "$T/metrics.out")"
grep -qE '^canopen_gateway_can_frames_total\{network="1",interface="vcan0",direction="rx"\} [1-9]' "$T/metrics.out" ||
  fail "/metrics has no received frames: $(head -20 "$T/metrics.out")"
grep -qE '^canopen_gateway_mqtt_connected 1' "$T/metrics.out" || fail "/metrics: MQTT not connected"
pass "REST SDO read and /metrics: $(cat "$T/rest.out")"

kill -KILL "$SIM_PID"
wait "$SIM_PID" 2>/dev/null || true
wait_for "$T/mqtt.log" "^canopen/$GW/1/5/state .*\"lost\"" 10
wait_for "$T/mqtt.log" "^canopen/$GW/1/10/state .*\"lost\"" 10
pass "nodes lost after the simulator was killed"

stop_gateway
sleep 0.5
kill "$SUB_PID" 2>/dev/null || true
/usr/bin/python3 - "$T/mqtt.log" "$GW" <<'PY' || fail "seq check failed"
import json, sys
seqs = []
for line in open(sys.argv[1]):
    topic, _, payload = line.partition(" ")
    parts = topic.split("/")
    if len(parts) < 3 or parts[1] != sys.argv[2] or parts[2] != "1":
        continue
    if topic.endswith(("/sdo/read", "/sdo/write", "/nmt")):
        continue  # the requests this test published
    if payload.strip() == "(null)":
        continue  # an empty message: a retained state deleted at the stop
    seqs.append(int(json.loads(payload)["seq"]))
seqs.sort()
gaps = [(a, b) for a, b in zip(seqs, seqs[1:]) if b != a + 1]
print(f"{len(seqs)} events of network 1, seq {seqs[0]}..{seqs[-1]}, gaps {gaps[:5]}")
sys.exit(1 if gaps or len(seqs) < 50 else 0)
PY
pass "seq of network 1 without gaps"

# After the clean stop (issue 12 item 13): what a new subscriber finds
# retained. No node state (deleted: none may claim a node runs), the bus
# down, and the offline status of the stop, with the real uptime.
mosquitto_sub -h 127.0.0.1 -p $MOSQ_PORT -v -t "canopen/$GW/#" -W 2 > "$T/retained.log" 2>/dev/null || true
grep -E "^canopen/$GW/1/[0-9]+/state " "$T/retained.log" && fail "node states still retained after the stop"
grep -qE "^canopen/$GW/1/bus .*\"state\": ?\"down\"" "$T/retained.log" || fail "bus not down: $(cat "$T/retained.log")"
grep -qE "^canopen/$GW/status .*\"state\": ?\"offline\"" "$T/retained.log" || fail "no offline status: $(cat "$T/retained.log")"
grep -qE "^canopen/$GW/status .*\"uptimeMs\": ?\"0\"" "$T/retained.log" && fail "offline status with uptime 0: $(cat "$T/retained.log")"
pass "after the stop: $(grep "^canopen/$GW/status " "$T/retained.log")"
stop_mosquitto
