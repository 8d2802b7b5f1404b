#!/bin/sh
# A CANopen device on real SocketCAN as a Sparkplug B device (contract
# "Sparkplug B"; facts A in ../shared/ref/sparkplug-ascii-lss-facts.md),
# checked by a second implementation: tests/tools/sparkplug_check.py decodes
# every message on spBv1.0/# with code protoc generates from
# proto/sparkplug_b.proto and checks the specification's rules over the
# whole run (births first, seq, bdSeq, QoS/retain, types, properties).
# An I/O module (canopen-sim, CiA 401 EDS) on vcan0 named io-rack, with
# `sparkplug-metrics: [1017h]`; the gateway configured by `sparkplug:`:
#  1. DBIRTH of io-rack with its PDO-mapped objects (6000h:1 in a TPDO,
#     6200h:1 in an RPDO) and 1017h (read by SDO for the birth), each with
#     index/subIndex;
#  2. DDATA on its TPDOs;
#  3. DCMD on 1017h (in no PDO): an SDO download, then a DDATA with the value;
#  4. the device process killed: DDEATH;
#  5. the device back: DBIRTH again, DDATA again.
# uml-run: --timeout 200
. "$(dirname "$0")/lib.sh"
SP_POLL_PER_S=2  # python starts slowly in UML
TOOLS=${SOURCE_DIR:-$(dirname "$0")/../..}/tests/tools
CHECK="/usr/bin/python3 $TOOLS/sparkplug_check.py"
GROUP=plant
GW=gw1
DEV=io-rack
CAP=$T/sparkplug.cap
IO_EDS=$EDS_DIR/cia401-io-module.eds
# The broker before the gateway: a CONNECT that fails would take a bdSeq too.
start_mosquitto
$CHECK --port $MOSQ_PORT --record "$CAP" --ready-file "$T/check.ready" > "$T/check-live.log" 2>&1 &
CHECK_PID=$!
i=0
until [ -e "$T/check.ready" ]; do
  [ $i -lt 150 ] || fail "the checker did not subscribe: $(cat "$T/check-live.log")"
  sleep 0.1
  i=$((i + 1))
done


cat > "$T/gw.yaml" <<YAML
gateway: {id: $GW, state-dir: $T/state}
networks:
  - interface: vcan0
    heartbeat-ms: 500
    nodes:
      - id: 10
        name: $DEV
        eds: $IO_EDS
        heartbeat-consumer-ms: 800
        boot: {start: true}
        sparkplug-metrics: ["1017h"]
mqtt:
  uri: tcp://127.0.0.1:$MOSQ_PORT
sparkplug:
  group-id: $GROUP
YAML
start_gateway --config "$T/gw.yaml" --log-level debug
sp_wait 20 "NBIRTH" --min-nbirths 1 --expect-birth-metric "/Network 1/Bus State"
pass "NBIRTH: $(tail -n 1 "$T/check.out")"

# ---- 1, 2: the device is heard: DBIRTH, then DDATA on its TPDOs ------------
start_sim "$T/sim.log" --node 10="$IO_EDS" --heartbeat 200 --tpdo-period 100
sp_wait 30 "DBIRTH of $DEV and DDATA" --expect-dbirth $DEV --expect-birth-object $DEV/6000h:1 \
  --expect-birth-object $DEV/6200h:1 --expect-birth-object $DEV/1017h:0=200 --expect-data-object $DEV/6000h:1 \
  --expect-birth-metric "$DEV/Node/State" --expect-birth-metric "$DEV/EMCY/Error Code" \
  --expect-birth-metric "$DEV/Device Control/Rebirth"
pass "DBIRTH of $DEV with 6000h:1 (TPDO), 6200h:1 (RPDO), 1017h = 200 (read by SDO), then DDATA on its TPDO"

# ---- 3: DCMD on an object in no PDO: SDO download ---------------------------
METRIC=$($CHECK --capture "$CAP" --lookup $DEV/1017h:0) || fail "no metric for 1017h in the DBIRTH of $DEV"
n=$(lines)
/usr/bin/python3 "$TOOLS/sparkplug_command.py" "$T/write.bin" "$METRIC:300"
mosquitto_pub -h 127.0.0.1 -p $MOSQ_PORT -t "spBv1.0/$GROUP/DCMD/$GW/$DEV" -f "$T/write.bin"
sp_wait 10 "DCMD ${METRIC%=*} = 300" --from-line "$n" --expect-data-object $DEV/1017h:0=300
grep -q "audit: SDO write by .*: net 1 node 10 .* = 300: ok" "$GW_LOG" || fail "no audit line for the DCMD's SDO write"
pass "DCMD ${METRIC%=*} = 300: SDO download (audited), the value came back in a DDATA"

# ---- 4: the device process dies: DDEATH -------------------------------------
n=$(lines)
kill -KILL "$SIM_PID"
wait "$SIM_PID" 2>/dev/null || true
sp_wait 10 "DDEATH of $DEV" --from-line "$n" --min-ddeaths 1
pass "device killed: DDEATH of $DEV"

# ---- 5: back: DBIRTH again --------------------------------------------------
n=$(lines)
start_sim "$T/sim2.log" --node 10="$IO_EDS" --heartbeat 200 --tpdo-period 100
sp_wait 30 "DBIRTH of $DEV again" --from-line "$n" --expect-dbirth $DEV --expect-data-object $DEV/6000h:1
pass "device back: DBIRTH of $DEV again, DDATA again"

n=$(lines)
stop_gateway
sp_wait 10 "NDEATH at the stop" --from-line "$n" --expect-ndeath
pass "clean stop: NDEATH"
kill -KILL "$SIM_PID" 2>/dev/null || true
kill -TERM "$CHECK_PID"
rc=0
wait "$CHECK_PID" || rc=$?
[ $rc -eq 0 ] || fail "live checker (status $rc): $(grep -E '"violation"|sparkplug_check' "$T/check-live.log" | head -10)"
pass "every Sparkplug rule held over the whole run: $(tail -n 1 "$T/check-live.log")"
stop_mosquitto
