#!/usr/bin/env bash
# 16 simulated CAN networks at 8,000 TPDO frames/s each through the gateway's
# whole path to a local mosquitto (QoS 0) on a free loopback port; prints the
# gateway's CPU per frame and per bus, and mosquitto's CPU over the run.
#   bench/many_networks.sh BUILD_DIR [SECONDS [NETWORKS [FRAMES_PER_SECOND_PER_BUS]]]
set -euo pipefail
BUILD=${1:?usage: many_networks.sh BUILD_DIR [SECONDS [NETWORKS [RATE]]]}
SECONDS_=${2:-10}
NETWORKS=${3:-16}
RATE=${4:-8000}
DIR=$(mktemp -d /tmp/many-networks.XXXXXX)
PORT=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
printf 'listener %s 127.0.0.1\nallow_anonymous true\npersistence false\nmax_queued_messages 0\n' "$PORT" > "$DIR/m.conf"
/usr/sbin/mosquitto -c "$DIR/m.conf" > "$DIR/m.log" 2>&1 &
MOSQ=$!
trap 'kill $MOSQ 2>/dev/null; wait $MOSQ 2>/dev/null; rm -rf "$DIR"' EXIT
for _ in $(seq 50); do mosquitto_pub -h 127.0.0.1 -p "$PORT" -t probe -m x 2>/dev/null && break; sleep 0.1; done
ticks() { awk '{print $14 + $15}' "/proc/$MOSQ/stat"; }
t0=$(ticks)
rc=0
"$BUILD/bench/many_networks_bench" "tcp://127.0.0.1:$PORT" "$SECONDS_" "$NETWORKS" "$RATE" || rc=$?
t1=$(ticks)
echo "mosquitto CPU over the whole run (both phases): $(( (t1 - t0) * 1000 / $(getconf CLK_TCK) )) ms"
exit $rc
