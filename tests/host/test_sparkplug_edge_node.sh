#!/bin/sh
# The gateway as a Sparkplug B 3.0 edge node (contract "Sparkplug B"; facts
# A in ../shared/ref/sparkplug-ascii-lss-facts.md), seen by a second
# implementation: tests/tools/sparkplug_check.py decodes every message on
# spBv1.0/# with code protoc generates from proto/sparkplug_b.proto and
# checks the specification's rules on all of them, the whole run long
# (births first, one seq 0..255 without gaps, bdSeq pairs, QoS/retain,
# metric types and properties). On top of those rules, this run must show:
#  1. NBIRTH with `Network 1/Bus State`, then a DBIRTH for each simulated
#     device (by their names: drive-x, io-rack-1, io-rack-2), then DDATA;
#  2. NCMD `Node Control/Rebirth` = true: NBIRTH (seq 0, same bdSeq: still one
#     session) and every DBIRTH again (facts A.6);
#  3. DCMD on an RPDO-mapped object (the I/O module's 6200h:1): a DDATA with
#     the written value;
#  4. SIGTERM on MQTT 3.1.1, where DISCONNECT suppresses the Will: the
#     gateway's own NDEATH with the session's bdSeq (facts A.4.6);
#  5. a restart (MQTT 5 now): a new session with bdSeq + 1 (facts A.5, kept
#     in state-dir);
#  6. kill -9: the broker publishes the Will, an NDEATH with that bdSeq;
#  7. a restart and SIGTERM on MQTT 5: the NDEATH and, DISCONNECT being
#     "with Will Message" (facts A.4.6), the Will too: two, same bdSeq.
# Steps 1-4 configure Sparkplug in the file (`sparkplug:`), 5-7 by
# --sparkplug, with aliases (births with name and alias, DATA by alias only,
# aliases unique over the edge node: facts A.7).
# Runs on the host with a real mosquitto; the CAN side is the gateway's
# simulated network.
TMPDIR=$(mktemp -d /tmp/host-test.XXXXXX)
export TMPDIR
trap 'kill $MOSQ_PID $CHECK_PID $GW_PID 2>/dev/null || true; rm -rf "$TMPDIR"' EXIT
. "$(dirname "$0")/../system/lib.sh"
TOOLS=${SOURCE_DIR:-$(dirname "$0")/../..}/tests/tools
CHECK="/usr/bin/python3 $TOOLS/sparkplug_check.py"
GROUP=plant
GW=gw1
DEVICES="drive-x io-rack-1 io-rack-2"  # the simulated nodes 5, 10, 11 by their names
IO=io-rack-1
CAP=$T/sparkplug.cap
MOSQ_PORT=$(free_port)
start_mosquitto

# The checker, live, for the whole run: its own verdict at the end, and the
# capture the steps below check as it grows.
$CHECK --port $MOSQ_PORT --record "$CAP" --ready-file "$T/check.ready" > "$T/check-live.log" 2>&1 &
CHECK_PID=$!
wait_for_file() { i=0; until [ -e "$1" ]; do [ $i -lt 100 ] || fail "$2"; sleep 0.1; i=$((i + 1)); done; }
wait_for_file "$T/check.ready" "the checker did not subscribe: $(cat "$T/check-live.log")"

# summary FIELD: a field of the summary of the latest sp_wait, as JSON.
summary() { /usr/bin/python3 -c 'import json,sys; print(json.dumps([json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")][-1][sys.argv[2]]))' "$T/check.out" "$1"; }
each_dbirth() { for d in $DEVICES; do printf -- '--expect-dbirth %s ' "$d"; done; }

cat > "$T/gw.yaml" <<YAML
gateway: {id: $GW, state-dir: $T/state}
networks:
  - simulated: true
    simulation: {tpdo-period-ms: 100, heartbeat-ms: 200, emcy-period-ms: 3000}
mqtt:
  uri: tcp://127.0.0.1:$MOSQ_PORT
YAML
cp "$T/gw.yaml" "$T/gw311.yaml"
printf 'sparkplug: {group-id: %s, mqtt-version: "3.1.1"}\n' "$GROUP" >> "$T/gw311.yaml"
# Runs 2 and 3: aliases on; --sparkplug's group wins over the file's.
printf 'sparkplug: {group-id: other, aliases: true}\n' >> "$T/gw.yaml"
GW_ARGS="--config $T/gw.yaml --http 127.0.0.1:0 --sparkplug $GROUP"

# ---- 1: births, then data ---------------------------------------------------
start_gateway --config "$T/gw311.yaml" --http 127.0.0.1:0
# shellcheck disable=SC2046
sp_wait 30 "births and DDATA" --min-nbirths 1 $(each_dbirth) --min-ddata 20 \
  --expect-birth-metric "/Network 1/Bus State"
BD=$(summary sessions | /usr/bin/python3 -c 'import json,sys; print(list(json.load(sys.stdin).values())[0][0])')
pass "NBIRTH (bdSeq $BD), DBIRTH of $DEVICES, DDATA flowing: $(summary counts)"

# ---- 2: NCMD rebirth --------------------------------------------------------
n=$(lines)
/usr/bin/python3 "$TOOLS/sparkplug_command.py" "$T/rebirth.bin" 'Node Control/Rebirth=Boolean:true'
mosquitto_pub -h 127.0.0.1 -p $MOSQ_PORT -t "spBv1.0/$GROUP/NCMD/$GW" -f "$T/rebirth.bin"
# shellcheck disable=SC2046
sp_wait 15 "rebirth" --from-line "$n" --min-nbirths 1 $(each_dbirth) --min-ddata 1
[ "$(summary sessions)" = "{\"$GROUP/$GW\": [$BD]}" ] ||
  fail "a rebirth must stay in the session (same bdSeq, no NDEATH): sessions $(summary sessions)"
pass "NCMD Node Control/Rebirth: NBIRTH with seq 0 and bdSeq $BD again, every DBIRTH, then DDATA"

# ---- 3: DCMD on an RPDO-mapped object ---------------------------------------
# The metric's name and type as the I/O module's DBIRTH gives them (6200h:1).
METRIC=$($CHECK --capture "$CAP" --lookup $IO/6200h:1) ||
  fail "no metric with index 6200h subIndex 1 in the DBIRTH of $IO"
n=$(lines)
/usr/bin/python3 "$TOOLS/sparkplug_command.py" "$T/write.bin" "$METRIC:165"
mosquitto_pub -h 127.0.0.1 -p $MOSQ_PORT -t "spBv1.0/$GROUP/DCMD/$GW/$IO" -f "$T/write.bin"
sp_wait 10 "DCMD ${METRIC%=*} = 165" --from-line "$n" --expect-data-object $IO/6200h:1=165
grep -q "audit: RPDO write by .*: net 1 node 10 " "$GW_LOG" || fail "no audit line for the DCMD's RPDO write"
pass "DCMD ${METRIC%=*} (RPDO-mapped) = 165: an RPDO write (audited), the value came back in a DDATA"

# ---- 4: clean stop: the gateway's own NDEATH --------------------------------
grep -q "sparkplug: edge node $GROUP/$GW connected .* with MQTT 3.1.1" "$GW_LOG" ||
  fail "the first run's Sparkplug session is not on MQTT 3.1.1: $(grep 'sparkplug:' "$GW_LOG" | head -3)"
n=$(lines)
stop_gateway
sp_wait 10 "NDEATH at SIGTERM" --from-line "$n" --expect-ndeath
pass "SIGTERM (MQTT 3.1.1): the gateway's NDEATH with bdSeq $BD before the disconnect"

# ---- 5: restart: bdSeq + 1 --------------------------------------------------
n=$(lines)
GW_LOG=$T/gateway2.log
start_gateway $GW_ARGS
# shellcheck disable=SC2046
sp_wait 30 "births after the restart" --from-line "$n" --min-nbirths 1 $(each_dbirth) --min-ddata 5
NEXT=$(( (BD + 1) % 256 ))
[ "$(summary sessions)" = "{\"$GROUP/$GW\": [$BD, $NEXT]}" ] ||
  fail "after the restart the sessions' bdSeqs are $(summary sessions), not [$BD, $NEXT]"
tail -n +"$((n + 1))" "$CAP" | $CHECK --capture - --decode 2>&1 | grep -q '"born_name"' ||
  fail "no DDATA by alias in the run with sparkplug.aliases: true"
pass "restart: a new session with bdSeq $NEXT (--sparkplug over the file's group; DDATA by alias)"

# ---- 6: kill -9: the broker publishes the Will ------------------------------
n=$(lines)
kill -KILL "$GW_PID"
wait "$GW_PID" 2>/dev/null || true
sp_wait 10 "the Will after kill -9" --from-line "$n" --expect-ndeath
pass "kill -9: the broker published the Will, NDEATH with bdSeq $NEXT"

# ---- 7: MQTT 5 clean stop: NDEATH, and the Will by the DISCONNECT's reason ---
n=$(lines)
GW_LOG=$T/gateway3.log
start_gateway $GW_ARGS
sp_wait 30 "births after the second restart" --from-line "$n" --min-nbirths 1 --min-ddata 1
grep -q "sparkplug: edge node $GROUP/$GW connected .* with MQTT 5" "$GW_LOG" ||
  fail "the Sparkplug session is not on MQTT 5: $(grep 'sparkplug:' "$GW_LOG" | head -3)"
n=$(lines)
stop_gateway
sp_wait 10 "two NDEATHs at SIGTERM on MQTT 5" --from-line "$n" --min-ndeaths 2
pass "SIGTERM (MQTT 5): the NDEATH and the Will (DISCONNECT with Will Message), bdSeq $(( (BD + 2) % 256 ))"

# ---- the whole run, by the live checker -------------------------------------
kill -TERM "$CHECK_PID"
rc=0
wait "$CHECK_PID" || rc=$?
[ $rc -eq 0 ] || fail "live checker (status $rc): $(grep -E '"violation"|sparkplug_check' "$T/check-live.log" | head -10)"
pass "every Sparkplug rule held over the whole run: $(tail -n 1 "$T/check-live.log")"
stop_mosquitto
