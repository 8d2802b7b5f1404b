#!/bin/bash
# Runs inside user-mode Linux (see deploy/demo.sh): starts the gateway on
# vcan0 with the EDS files of two nodes, then plays their traffic with
# cansend: node 5 is a CiA 402 drive (deploy/eds/cia402-drive.eds), node 10
# a CiA 401 I/O module (deploy/eds/cia401-io-module.eds). The gateway logs
# node states, decoded TPDO values by name, EMCYs and bus-state changes.
set -u
G=$BUILD_DIR/gateway/canopen-gateway
EDS=$SOURCE_DIR/deploy/eds
SECS=${CANOPEN_DEMO_SECONDS:-20}
le16() { printf '%02X%02X' $(( $1 & 255 )) $(( ($1 >> 8) & 255 )); }
le32() { printf '%s%s' "$(le16 $(( $1 & 65535 )))" "$(le16 $(( ($1 >> 16) & 65535 )))"; }

echo "demo: canopen-gateway --can vcan0 --eds 5=cia402-drive.eds --eds 10=cia401-io-module.eds, ${SECS}s"
"$G" --can vcan0 --eds 5="$EDS/cia402-drive.eds" --eds 10="$EDS/cia401-io-module.eds" --log-level info &
GW=$!
sleep 0.5
echo "demo: nodes 5 and 10 boot (boot-up 705#00, 70A#00)"
cansend vcan0 705#00; cansend vcan0 70A#00
echo "demo: NMT start all nodes (000#0100)"
cansend vcan0 000#0100
i=0
while [ $i -lt "$SECS" ]; do
  cansend vcan0 705#05; cansend vcan0 70A#05                        # heartbeats: operational
  cansend vcan0 385#3706$(le32 $(( i * 1000 )))                      # drive TPDO3: statusword, position
  cansend vcan0 18A#$(printf '%02X' $(( (i * 37) & 255 )))           # I/O TPDO1: digital inputs
  cansend vcan0 28A#$(le16 $(( 2150 + (i * 37) % 300 )))$(le16 $(( -100 - i )))00000000  # I/O TPDO2: analogue inputs
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
