#!/bin/bash
# Runs inside user-mode Linux (see deploy/demo-vcan.sh): canopen-sim plays a
# CiA 402 drive (node 5) and a CiA 401 I/O module (node 10) on vcan0; the
# gateway watches them by heartbeat, identifies and starts them at boot-up
# and logs node states, decoded TPDO values by name, EMCYs and bus-state
# changes (vcan0 goes down and up once).
set -u
G=$BUILD_DIR/gateway/canopen-gateway
SIM=$BUILD_DIR/gateway/canopen-sim
EDS=$SOURCE_DIR/deploy/eds
SECS=${CANOPEN_DEMO_SECONDS:-20}
T=$(mktemp -d)
cat > "$T/gw.yaml" <<YAML
gateway: {id: demo, state-dir: $T}
networks:
  - interface: vcan0
    nodes:
      - {id: 5, name: drive, eds: $EDS/cia402-drive.eds, heartbeat-consumer-ms: 1500, boot: {start: true}}
      - {id: 10, name: io, eds: $EDS/cia401-io-module.eds, heartbeat-consumer-ms: 1500, boot: {start: true}}
YAML
echo "demo: canopen-gateway --config gw.yaml (nodes 5 and 10 on vcan0), ${SECS}s"
"$G" --config "$T/gw.yaml" --log-level debug 2>&1 | grep -vE " rx |heartbeat" &
sleep 0.5
"$SIM" --can vcan0 --node 5="$EDS/cia402-drive.eds" --node 10="$EDS/cia401-io-module.eds" \
  --heartbeat 500 --tpdo-period 1000 --emcy-period 7000 > /dev/null &
SIMPID=$!
sleep $(( SECS / 2 ))
echo "demo: vcan0 goes down for 2 s and comes back"
ip link set vcan0 down; sleep 2; ip link set vcan0 up
sleep $(( SECS / 2 ))
kill -INT $SIMPID
pkill -INT -x canopen-gateway
wait
echo "demo: done"
