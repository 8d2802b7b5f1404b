#!/usr/bin/env bash
# The README's first command: installs what is missing, builds, starts a
# local mosquitto (unless one already listens on 127.0.0.1:1883) and runs
# `canopen-gateway --demo`: a simulated CAN network inside the process with a
# CiA 402 drive (node 5) and two CiA 401 I/O modules (nodes 10, 11). No CAN
# hardware, kernel CAN support or configuration needed.
#   deploy/demo.sh [SECONDS]     (default: until Ctrl-C)
set -euo pipefail
cd "$(dirname "$0")/.."
./deploy/install-deps.sh
cmake --preset default >/dev/null
cmake --build --preset default --target canopen-gateway canopen-sim

STATE=$(mktemp -d /tmp/canopen-demo.XXXXXX)
MOSQ_PID=
cleanup() {
  [ -n "$MOSQ_PID" ] && kill "$MOSQ_PID" 2>/dev/null || true
  rm -rf "$STATE"
}
trap cleanup EXIT

if ! mosquitto_pub -h 127.0.0.1 -p 1883 -t canopen/demo-probe -m x 2>/dev/null; then
  printf 'listener 1883 127.0.0.1\nallow_anonymous true\npersistence false\n' > "$STATE/mosquitto.conf"
  /usr/sbin/mosquitto -c "$STATE/mosquitto.conf" >"$STATE/mosquitto.log" 2>&1 &
  MOSQ_PID=$!
  for _ in $(seq 50); do mosquitto_pub -h 127.0.0.1 -p 1883 -t canopen/demo-probe -m x 2>/dev/null && break; sleep 0.1; done
fi

cat <<TXT

  canopen-gateway demo: simulated network 1 with nodes 5 (drive), 10 and 11 (I/O).
  Dashboard:               http://127.0.0.1:8080/
  REST (SDO read):         curl http://127.0.0.1:8080/api/v1/networks/1/nodes/5/sdo/1018/1
  API description:         http://127.0.0.1:8080/api/v1/openapi.json
  Live MQTT events:        mosquitto_sub -h 127.0.0.1 -v -t 'canopen/#'
  WebSocket events:        ws://127.0.0.1:8080/api/v1/events
  SDO read over MQTT:      first, in another terminal, subscribe to the reply topic:
                           mosquitto_sub -h 127.0.0.1 -v -t demo/reply
                           then send the request:
                           mosquitto_pub -h 127.0.0.1 -t canopen/demo/1/5/sdo/read \\
                             -m '{"index":"0x1018","subIndex":1,"replyTo":"demo/reply","correlationId":"1"}'
  Stop with Ctrl-C.

TXT
printf 'gateway: {state-dir: %s}\n' "$STATE" > "$STATE/demo.yaml"
args=(--demo --gateway-id demo --mqtt tcp://127.0.0.1:1883 --http 127.0.0.1:8080 --config "$STATE/demo.yaml")
if [ -n "${1:-}" ]; then
  timeout --signal=INT "$1" build/gateway/canopen-gateway "${args[@]}" || [ $? -eq 124 ]
else
  build/gateway/canopen-gateway "${args[@]}"
fi
