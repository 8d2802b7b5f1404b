#!/usr/bin/env bash
# CAN frame -> MQTT: the gateway's path (mqtt_path_bench) against a
# python3-can + paho bridge, on the same frames, to a local mosquitto on a
# free loopback port. Prints both and the ratio of CPU per event.
#   bench/mqtt_compare.sh BUILD_DIR [EVENTS] [QOS]
set -euo pipefail
BUILD=${1:?usage: mqtt_compare.sh BUILD_DIR [EVENTS] [QOS]}
EVENTS=${2:-100000}
QOS=${3:-1}
DIR=$(mktemp -d /tmp/mqtt-compare.XXXXXX)
. "$(dirname "$0")/broker.sh"
start_broker "$DIR"
"$BUILD/bench/mqtt_path_bench" "tcp://127.0.0.1:$PORT" "$EVENTS" "$DIR/queue" "$QOS" | tee "$DIR/gw.txt"
/usr/bin/python3 "$(dirname "$0")/python_bridge.py" 127.0.0.1 "$PORT" "$EVENTS" "$QOS" | tee "$DIR/py.txt"
gw=$(grep -oP 'CPU per event \(all threads, until acked\): \K[0-9.]+' "$DIR/gw.txt")
py=$(grep -oP 'CPU per event \(all threads, until acked\): \K[0-9.]+' "$DIR/py.txt")
/usr/bin/python3 -c "print(f'ratio: the python bridge uses {float($py)/float($gw):.1f}x the CPU per event of the gateway')"
