#!/bin/sh
# Brokers nobody here wrote (issue 27 item 1; contract "Brokers"):
# RabbitMQ's MQTT plugin (Debian's rabbitmq-server 3.10) speaks MQTT 3.1.1
# only and closes the connection at an MQTT 5 CONNECT without a CONNACK.
# The gateway (default mqtt-version 5) tries 3.1.1 at once, says so in the
# log, and its events arrive. RabbitMQ runs as a plain process of this test
# (its own node name, ports, epmd port and directories; stopped by PID).
# Issue 27 item 2: with mqtt.uri the list [RabbitMQ, mosquitto] the gateway
# goes on to mosquitto when RabbitMQ goes, with MQTT 5 there (the version
# is found per broker), names it in GET /api/v1/gateway and publishes its
# retained topics there.
TMPDIR=$(mktemp -d /tmp/host-test.XXXXXX)
export TMPDIR
RMQ_PID=
SUB_PID=
SUB2_PID=
cleanup() {
  kill $SUB_PID $SUB2_PID $GW_PID 2>/dev/null || true
  [ -n "${MOSQ_PID:-}" ] && kill "$MOSQ_PID" 2>/dev/null
  if [ -n "$RMQ_PID" ]; then
    kill "$RMQ_PID" 2>/dev/null
    i=0  # epmd stops only once no node is registered with it
    while kill -0 "$RMQ_PID" 2>/dev/null && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
  fi
  [ -n "${ERL_EPMD_PORT:-}" ] && epmd -port "$ERL_EPMD_PORT" -kill >/dev/null 2>&1
  rm -rf "$TMPDIR"
}
trap cleanup EXIT
. "$(dirname "$0")/../system/lib.sh"
command -v /usr/lib/rabbitmq/bin/rabbitmq-server >/dev/null || fail "rabbitmq-server missing (deploy/install-deps.sh)"

GW=gwr
RMQ_MQTT=$(free_port)
R=$T/rabbitmq
mkdir -p "$R/mnesia" "$R/log"
cat > "$R/rabbitmq.conf" <<CONF
listeners.tcp.default = $(free_port)
mqtt.listeners.tcp.default = $RMQ_MQTT
mqtt.allow_anonymous = true
loopback_users = none
CONF
echo "[rabbitmq_mqtt]." > "$R/enabled_plugins"
# Run as this user (not the rabbitmq-server wrapper, which drops to the
# rabbitmq user): everything it writes stays under $R.
ERL_EPMD_PORT=$(free_port)
export ERL_EPMD_PORT
(
  export HOME="$R" RABBITMQ_NODENAME="gwtest$$@localhost" RABBITMQ_MNESIA_BASE="$R/mnesia" \
    RABBITMQ_LOG_BASE="$R/log" RABBITMQ_CONFIG_FILE="$R/rabbitmq.conf" \
    RABBITMQ_ENABLED_PLUGINS_FILE="$R/enabled_plugins" RABBITMQ_DIST_PORT="$(free_port)" \
    RABBITMQ_PID_FILE="$R/pid"
  exec /usr/lib/rabbitmq/bin/rabbitmq-server > "$R/out.log" 2>&1
) &
i=0
until mosquitto_pub -h 127.0.0.1 -p "$RMQ_MQTT" -V mqttv311 -t probe -m x 2>/dev/null; do
  i=$((i + 1))
  [ $i -lt 120 ] || { tail -20 "$R/out.log"; fail "rabbitmq did not start in 60 s"; }
  sleep 0.5
done
RMQ_PID=$(cat "$R/pid")
mosquitto_pub -h 127.0.0.1 -p "$RMQ_MQTT" -V mqttv5 -t probe -m x 2>/dev/null &&
  fail "this RabbitMQ took an MQTT 5 CONNECT: the test would show nothing"
pass "rabbitmq $(dpkg-query -W -f='${Version}' rabbitmq-server) up (pid $RMQ_PID): MQTT 3.1.1 only"

# RabbitMQ's plugin maps '.' in topic levels to '/', so the gateway id has none.
mosquitto_sub -h 127.0.0.1 -p "$RMQ_MQTT" -V mqttv311 -v -t "canopen/$GW/#" > "$T/mqtt.log" 2>&1 &
SUB_PID=$!
sleep 0.5
cat > "$T/gw.yaml" <<YAML
gateway: {id: $GW, state-dir: $T/state}
networks:
  - simulated: true
    simulation: {tpdo-period-ms: 100, heartbeat-ms: 500, emcy-period-ms: 0}
mqtt:
  uri: tcp://127.0.0.1:$RMQ_MQTT
YAML
start_gateway --config "$T/gw.yaml" --http 127.0.0.1:0
wait_for "$GW_LOG" "connected to tcp://127.0.0.1:$RMQ_MQTT with MQTT 3.1.1" 10
grep -q "closed the connection without a CONNACK to an MQTT 5 CONNECT" "$GW_LOG" ||
  fail "the fallback is not in the log"
wait_count "$T/mqtt.log" "^canopen/$GW/1/[0-9]+/tpdo/" 5 10
wait_for "$T/mqtt.log" "^canopen/$GW/status " 5
pass "MQTT 5 closed without CONNACK -> 3.1.1 at once: status and" \
  "$(grep -c "/tpdo/" "$T/mqtt.log") TPDOs through RabbitMQ"
stop_gateway

# ---- a list of brokers: RabbitMQ first, mosquitto second ---------------------
MOSQ_PORT=$(free_port)
start_mosquitto
mosquitto_sub -h 127.0.0.1 -p "$MOSQ_PORT" -v -t "canopen/$GW/#" > "$T/mosq.log" 2>&1 &
SUB2_PID=$!
HTTP_PORT=$(free_port)
cat > "$T/gw2.yaml" <<YAML
gateway: {id: $GW, state-dir: $T/state2}
networks:
  - simulated: true
    simulation: {tpdo-period-ms: 100, heartbeat-ms: 500, emcy-period-ms: 0}
mqtt:
  uri: [tcp://127.0.0.1:$RMQ_MQTT, mqtt://127.0.0.1:$MOSQ_PORT]
YAML
# broker_of: GET /api/v1/gateway's "mqtt" as "<broker> <mqttVersion>".
broker_of() {
  /usr/bin/python3 -c 'import json,sys,urllib.request
m = json.load(urllib.request.urlopen(sys.argv[1]))["mqtt"]
print(m["broker"], m["mqttVersion"])' "http://127.0.0.1:$HTTP_PORT/api/v1/gateway"
}
start_gateway --config "$T/gw2.yaml" --http "127.0.0.1:$HTTP_PORT"
wait_for "$GW_LOG" "connected to tcp://127.0.0.1:$RMQ_MQTT with MQTT 3.1.1" 10
[ "$(broker_of)" = "tcp://127.0.0.1:$RMQ_MQTT 3.1.1" ] || fail "GET /api/v1/gateway: $(broker_of)"
kill "$RMQ_PID"
i=0
while kill -0 "$RMQ_PID" 2>/dev/null && [ $i -lt 200 ]; do sleep 0.1; i=$((i + 1)); done
RMQ_PID=
wait_for "$GW_LOG" "connected to tcp://127.0.0.1:$MOSQ_PORT with MQTT 5" 20
[ "$(broker_of)" = "tcp://127.0.0.1:$MOSQ_PORT 5" ] || fail "GET /api/v1/gateway after the switch: $(broker_of)"
wait_for "$T/mosq.log" "^canopen/$GW/status " 5
wait_for "$T/mosq.log" "^canopen/$GW/1/bus " 5
wait_count "$T/mosq.log" "^canopen/$GW/1/[0-9]+/tpdo/" 5 10
pass "RabbitMQ (3.1.1) gone -> mosquitto (MQTT 5), named in GET /api/v1/gateway; status, bus and" \
  "$(grep -c "/tpdo/" "$T/mosq.log") TPDOs there"
stop_gateway
