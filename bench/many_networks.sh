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
. "$(dirname "$0")/broker.sh"
start_broker "$DIR"
ticks() { awk '{print $14 + $15}' "/proc/$MOSQ/stat"; }
t0=$(ticks)
rc=0
"$BUILD/bench/many_networks_bench" "tcp://127.0.0.1:$PORT" "$SECONDS_" "$NETWORKS" "$RATE" || rc=$?
t1=$(ticks)
echo "mosquitto CPU over the whole run (both phases): $(( (t1 - t0) * 1000 / $(getconf CLK_TCK) )) ms"
exit $rc
