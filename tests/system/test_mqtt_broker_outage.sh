#!/bin/sh
# Nothing accepted for QoS 1 is lost when the broker goes away (issue 5):
#  1. mosquitto stops for 30 s while PDOs flow at about 1,000 per second; when
#     it is back, every event of that window arrives, once, in order (seq
#     without gaps or repeats).
#  2. the gateway is killed with SIGKILL while the broker is down; after a
#     restart with the same state directory the events it had accepted
#     before the kill still arrive (disk-backed queue).
# uml-run: --timeout 280
. "$(dirname "$0")/lib.sh"
GW=gw1
PERSIST=$T/mosquitto-db
mkdir -p "$PERSIST"
start_mosquitto "$PERSIST"
# A persistent QoS 1 session: the broker keeps its messages across restarts.
start_sub() {
  mosquitto_sub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv311 -c -i outage-sub -q 1 -v -t "canopen/$GW/1/#" \
    >> "$T/mqtt.log" 2>&1 &
  SUB_PID=$!
  sleep 0.5
}
start_sub

cat > "$T/gw.yaml" <<YAML
gateway: {id: $GW, state-dir: $T/state}
networks:
  - interface: vcan0
    nodes:
      - {id: 10, eds: $EDS_DIR/cia401-io-module.eds, heartbeat-consumer-ms: 3000, boot: {start: true}}
mqtt:
  uri: tcp://127.0.0.1:$MOSQ_PORT
  qos: {default: 1}
  heartbeat: false
YAML
start_gateway --config "$T/gw.yaml"
start_sim "$T/sim.log" --node 10="$EDS_DIR/cia401-io-module.eds" --heartbeat 500 --tpdo-period 2
wait_count "$T/mqtt.log" "^canopen/$GW/1/10/tpdo/" 500 20
pass "PDOs flowing: $(grep -c "/tpdo/" "$T/mqtt.log") so far"

# ---- 1: a 30 s outage -------------------------------------------------------
stop_mosquitto
kill "$SUB_PID" 2>/dev/null || true
outage_start=$(date +%s.%N)
sleep 30
outage_end=$(date +%s.%N)
start_mosquitto "$PERSIST"
start_sub
# Let the backlog drain while traffic goes on, then stop the traffic.
sleep 25
kill -TERM "$SIM_PID"; wait "$SIM_PID" 2>/dev/null || true
sleep 10
/usr/bin/python3 - "$T/mqtt.log" "$outage_start" "$outage_end" <<'PY' || fail "outage check failed (see above)"
import json, sys, datetime
seqs, in_window = [], 0
start, end = float(sys.argv[2]), float(sys.argv[3])
for line in open(sys.argv[1]):
    topic, _, payload = line.partition(" ")
    if "/" not in topic or not payload.strip():
        continue
    ev = json.loads(payload)
    seqs.append(int(ev["seq"]))
    ts = datetime.datetime.fromisoformat(ev["timestamp"].replace("Z", "+00:00")).timestamp()
    if start <= ts <= end:
        in_window += 1
first = sorted(set(seqs))
gaps = [(a, b) for a, b in zip(first, first[1:]) if b != a + 1]
dups = len(seqs) - len(first)
order = sum(1 for a, b in zip(seqs, seqs[1:]) if b <= a)
print(f"{len(seqs)} messages, seq {first[0]}..{first[-1]}, {in_window} from the 30 s outage, "
      f"gaps {gaps[:5]}, repeats {dups}, out of order {order}")
ok = not gaps and dups == 0 and order == 0 and in_window >= 15000
sys.exit(0 if ok else 1)
PY
pass "30 s outage at ~1000 PDO/s: every event arrived once, in order"

# ---- 2: SIGKILL while the broker is down ---------------------------------
: > "$T/mqtt.log"
start_sim "$T/sim2.log" --node 10="$EDS_DIR/cia401-io-module.eds" --heartbeat 500 --tpdo-period 5
wait_count "$T/mqtt.log" "^canopen/$GW/1/10/tpdo/" 100 20
stop_mosquitto
kill "$SUB_PID" 2>/dev/null || true
sleep 5
kill_time=$(date +%s.%N)
kill -KILL "$GW_PID"; wait "$GW_PID" 2>/dev/null || true
kill -TERM "$SIM_PID"; wait "$SIM_PID" 2>/dev/null || true
start_mosquitto "$PERSIST"
start_sub
GW_LOG=$T/gateway2.log
start_gateway --config "$T/gw.yaml"
sleep 15
/usr/bin/python3 - "$T/mqtt.log" "$kill_time" <<'PY' || fail "kill -9 check failed (see above)"
import json, sys, datetime
kill = float(sys.argv[2])
run1, last_ts = [], 0.0
for line in open(sys.argv[1]):
    topic, _, payload = line.partition(" ")
    if "/" not in topic or not payload.strip():
        continue
    ev = json.loads(payload)
    ts = datetime.datetime.fromisoformat(ev["timestamp"].replace("Z", "+00:00")).timestamp()
    if ts > kill:
        continue  # the restarted gateway's own events
    run1.append(int(ev["seq"]))
    last_ts = max(last_ts, ts)
uniq = sorted(set(run1))
gaps = [(a, b) for a, b in zip(uniq, uniq[1:]) if b != a + 1]
print(f"before the kill: {len(run1)} messages, seq {uniq[0]}..{uniq[-1]}, gaps {gaps[:5]}, "
      f"newest {kill - last_ts:.2f} s before the kill")
sys.exit(0 if not gaps and kill - last_ts < 1.0 else 1)
PY
pass "events accepted before SIGKILL arrived after the restart"
stop_gateway
stop_mosquitto
