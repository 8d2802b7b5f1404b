#!/bin/sh
# Runs inside user-mode Linux (see deploy/demo.sh): starts the gateway on
# vcan0 and plays CANopen-shaped traffic from two simulated nodes with
# cansend, so the gateway's log shows what it receives.
set -u
G=$BUILD_DIR/gateway/canopen-gateway
SECS=${CANOPEN_DEMO_SECONDS:-20}
echo "demo: starting canopen-gateway --can vcan0 --log-level debug for ${SECS}s"
"$G" --can vcan0 --log-level debug &
GW=$!
sleep 0.5
echo "demo: nodes 5 and 10 boot (boot-up 705#00, 70A#00)"
cansend vcan0 705#00; cansend vcan0 70A#00
i=0
while [ $i -lt "$SECS" ]; do
  cansend vcan0 080#                                   # SYNC
  temp=$(printf '%04X' $((2150 + (i * 37) % 300)))     # TPDO1 of node 5: counter + temperature
  cansend vcan0 185#$(printf '%02X' $((i % 256)))00${temp#??}${temp%??}
  cansend vcan0 18A#$(printf '%02X' $(( (i * 7) % 256)))  # TPDO1 of node 10: digital inputs
  cansend vcan0 705#05                                 # heartbeats: 5 operational,
  cansend vcan0 70A#7F                                 # 10 pre-operational
  if [ $i -eq 5 ]; then
    echo "demo: node 10 sends an EMCY (3210h, DC link over-voltage)"
    cansend vcan0 08A#1032040000000000
  fi
  if [ $i -eq 8 ]; then
    echo "demo: vcan0 goes down for 2 s and comes back"
    ip link set vcan0 down; sleep 2; ip link set vcan0 up
  fi
  sleep 1
  i=$((i + 1))
done
kill -INT $GW
wait $GW
echo "demo: gateway exited with status $?"
