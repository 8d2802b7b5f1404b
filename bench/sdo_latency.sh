#!/usr/bin/env bash
# SDO round-trip latency through each front end (issue 28 item 5): N
# sequential expedited reads of one object (1017h) of a device on vcan0, one
# request at a time on one connection, all in one user-mode Linux guest so
# that the figures compare (UML makes every syscall slow: the absolute values
# are far above a real kernel's, the differences are what counts):
#   raw      the stack's SDO client on SocketCAN, no front end (sdo_tool --repeat)
#   rest     GET /api/v1/networks/1/nodes/5/sdo/1017/0?type=u16 (keep-alive)
#   ascii    "[k] 5 r 0x1017 0 u16" on the gateway's CiA 309-3 TCP socket
#   canopend the same request on CANopenNode's 309-3 gateway, when
#            CANOPEND=/path/to/canopend is set (it is not part of the project;
#            see bench/README.md "SDO latency")
# The device is sdo_tool serve (the stack's SDO server, a separate process).
# Each front end runs ROUNDS times, interleaved. Not a test; prints one line per run.
#   bench/sdo_latency.sh [BUILD_DIR] [N] [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")/.."
export BUILD_DIR=$(realpath "${1:-build}")
export SOURCE_DIR=$PWD CANOPEN_N=${2:-1000} CANOPEN_ROUNDS=${3:-3} CANOPEN_CANOPEND=${CANOPEND:-}  # uml-run passes CANOPEN_*
exec tests/system/uml-run.sh --timeout 900 -- bash -c '
set -eu
T=$TMPDIR
N=$CANOPEN_N ROUNDS=$CANOPEN_ROUNDS CANOPEND=$CANOPEN_CANOPEND
CLIENT="/usr/bin/python3 $SOURCE_DIR/bench/sdo_latency_client.py"
$BUILD_DIR/tests/sdo_tool serve vcan0 5 > $T/device.out 2>&1 &
DEV=$!
HTTP_PORT=18080 ASCII_PORT=60000 CON_PORT=60001
# No rate limit: the reads come as fast as the answers (0 = unlimited).
printf "http: {rate-limit: {requests-per-second: 0}}\n" > $T/gw.yaml
$BUILD_DIR/gateway/canopen-gateway --config $T/gw.yaml --can vcan0 --http 127.0.0.1:$HTTP_PORT \
  --ascii 127.0.0.1:$ASCII_PORT --log-level warn > $T/gw.log 2>&1 &
GW=$!
if [ -n "$CANOPEND" ]; then
  # Its stored parameters in $T; a file "-" means its defaults, without the
  # EMCY a missing file raises.
  printf -- "-\n" > $T/co3_od_comm.persist
  "$CANOPEND" vcan0 -i 3 -c "tcp-$CON_PORT" -s $T/co3_ > $T/canopend.log 2>&1 &
fi
for i in $(seq 100); do
  # --log-level warn hides the started line: ask the REST port instead.
  /usr/bin/python3 -c "import socket; socket.create_connection((\"127.0.0.1\", $HTTP_PORT), 0.2)" 2>/dev/null &&
    grep -q "^ready" $T/device.out && break
  sleep 0.1
done
sleep 1
for r in $(seq $ROUNDS); do
  echo "raw      $($BUILD_DIR/tests/sdo_tool upload vcan0 5 0x1017 0 --repeat $N | grep ^latency)"
  $CLIENT rest "rest     (round $r)" 127.0.0.1 $HTTP_PORT "/api/v1/networks/1/nodes/5/sdo/1017/0?type=u16" $N
  $CLIENT ascii "ascii    (round $r)" 127.0.0.1 $ASCII_PORT "5 r 0x1017 0 u16" $N
  if [ -n "$CANOPEND" ]; then
    $CLIENT ascii "canopend (round $r)" 127.0.0.1 $CON_PORT "5 r 0x1017 0 u16" $N
  fi
done
kill $GW $DEV 2>/dev/null || true
'
