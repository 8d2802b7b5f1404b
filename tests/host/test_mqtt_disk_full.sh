#!/bin/sh
# A full state-dir file system must not take the gateway down (issue 12,
# item 2). The state-dir is a small tmpfs:
#  1. with the broker connected, another file fills the disk: events keep
#     arriving (disk kinds included), the gateway logs the episode once, and
#     when the file goes it says storage works again;
#  2. the broker goes away: the queue fills the disk; the gateway keeps
#     running (CAN side and REST answer), drops what it cannot store
#     (counted in /metrics), logs once, not per message;
#  3. the broker comes back: it publishes again, the backlog's space is
#     freed, storage recovers by itself. The process never exited.
# Needs root for mount (the CI runs as root); skipped with a message
# otherwise.
TMPDIR=$(mktemp -d /tmp/host-test.XXXXXX)
export TMPDIR
STATE=$TMPDIR/state
cleanup() {
  kill ${MOSQ_PID:-} ${SUB_PID:-} ${GW_PID:-} 2>/dev/null || true
  umount "$STATE" 2>/dev/null || true
  rm -rf "$TMPDIR"
}
trap cleanup EXIT
. "$(dirname "$0")/../system/lib.sh"
mkdir -p "$STATE"
if ! mount -t tmpfs -o size=3m tmpfs "$STATE" 2>/dev/null; then
  echo "SKIP: cannot mount a tmpfs on $STATE (needs root); the disk-full test did not run"
  exit 0
fi
GW=gwfull
MOSQ_PORT=$(free_port)
HTTP_PORT=$(free_port)
PERSIST=$T/mosquitto-db
mkdir -p "$PERSIST"
start_mosquitto "$PERSIST"
start_sub() {
  mosquitto_sub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv311 -c -i "full-sub-$$" -q 1 -v -t "canopen/$GW/1/#" \
    >> "$T/mqtt.log" 2>&1 &
  SUB_PID=$!
  sleep 0.5
}
start_sub
metric() { curl -s "http://127.0.0.1:$HTTP_PORT/metrics" | grep -E "^$1 " | awk '{print $2}'; }
alive() { kill -0 "$GW_PID" 2>/dev/null || fail "the gateway exited"; }
used_kb() { df -k "$STATE" | awk 'NR==2 {print $3}'; }
# The queue's own files come and go while it fills the disk, so an episode can
# end and start again by itself: "storage works" means the latest storage line
# is a recovery, and it came after the AFTER-th one.
storage_lines() { grep -E "queue storage (in .* failing|writable again)" "$GW_LOG"; }
wait_storage_ok() {
  local after=$1 limit=$2 i=0
  while :; do
    if [ "$(storage_lines | grep -c "writable again")" -gt "$after" ] &&
       storage_lines | tail -n 1 | grep -q "writable again"; then
      return 0
    fi
    [ $i -lt $((limit * 10)) ] || fail "storage did not recover within ${limit}s"
    sleep 0.1; i=$((i + 1))
  done
}

cat > "$T/gw.yaml" <<YAML
gateway: {id: $GW, state-dir: $STATE}
networks:
  - simulated: true
    simulation: {tpdo-period-ms: 1, heartbeat-ms: 500, emcy-period-ms: 100}
mqtt:
  uri: tcp://127.0.0.1:$MOSQ_PORT
http: {listen: 127.0.0.1:$HTTP_PORT}
YAML
start_gateway --config "$T/gw.yaml"
wait_count "$T/mqtt.log" "^canopen/$GW/1/[0-9]+/emcy " 5 20
pass "events flowing (tpdo: outage, emcy: disk)"

# ---- 1: another file fills the disk while the broker is connected --------
dd if=/dev/zero of="$STATE/filler" bs=64k 2>/dev/null || true
wait_for "$GW_LOG" "queue storage in .* failing" 20
: > "$T/mqtt.log"
wait_count "$T/mqtt.log" "^canopen/$GW/1/[0-9]+/emcy " 20 20
wait_count "$T/mqtt.log" "^canopen/$GW/1/[0-9]+/tpdo/" 1000 20
alive
pass "disk full while connected: emcy and tpdo events still arrive"
rm -f "$STATE/filler"
wait_storage_ok 0 20
pass "storage writable again once the file is gone"

# ---- 2: the broker goes away; the queue fills the disk ---------------------
stop_mosquitto
kill "$SUB_PID" 2>/dev/null || true
episodes_before=$(grep -c "queue storage in .* failing" "$GW_LOG")
i=0
while [ "$(grep -c "queue storage in .* failing" "$GW_LOG")" -le "$episodes_before" ]; do
  [ $i -lt 600 ] || fail "the queue did not fill the 3 MB disk within 60 s (used $(used_kb) kB)"
  sleep 0.1; i=$((i + 1))
done
sleep 10  # a saturated bus keeps coming: still one line, not one per message
alive
lines=$(grep -c "mqtt" "$GW_LOG")
[ "$(grep -c "queue storage in .* failing" "$GW_LOG")" -eq $((episodes_before + 1)) ] || fail "the episode was logged more than once"
[ "$(grep -c "ERROR" "$GW_LOG")" -le 3 ] || fail "error lines per message: $(grep -c ERROR "$GW_LOG")"
[ "$(metric canopen_gateway_mqtt_storage_failing)" = 1 ] || fail "storage_failing is not 1 in /metrics"
dropped=$(metric 'canopen_gateway_mqtt_dropped_total\{reason="storage_full"\}')
[ "${dropped:-0}" -gt 0 ] || fail "no storage_full drops counted (got '$dropped')"
curl -sf "http://127.0.0.1:$HTTP_PORT/api/v1/networks/1/nodes/5/sdo/1017/0" > /dev/null || fail "REST does not answer"
pass "disk full with the broker away: running, REST answers, $dropped dropped and counted, one log line ($lines mqtt lines in all)"
full_kb=$(used_kb)

# ---- 3: the broker comes back ----------------------------------------------
recovered=$(grep -c "queue storage writable again" "$GW_LOG")
start_mosquitto "$PERSIST"
: > "$T/mqtt.log"
start_sub
back=$(date +%s)
# Earlier episodes' recovery lines are already in the log: wait for a new one.
wait_storage_ok "$recovered" 60
i=0
while [ "$(used_kb)" -ge $((full_kb / 2)) ]; do
  [ $i -lt 300 ] || fail "space not freed: $(used_kb) kB of $full_kb kB still used"
  sleep 0.1; i=$((i + 1))
done
i=0
until [ "$(metric canopen_gateway_mqtt_storage_failing)" = 0 ]; do
  [ $i -lt 100 ] || fail "storage_failing is still 1"
  sleep 0.1; i=$((i + 1))
done
# New events (stamped after the broker came back) arrive.
/usr/bin/python3 - "$T/mqtt.log" "$back" <<'PY' || fail "no new events after the broker came back"
import json, sys, datetime, time
deadline = time.time() + 20
while time.time() < deadline:
    new = 0
    for line in open(sys.argv[1]):
        topic, _, payload = line.partition(" ")
        if "/tpdo/" not in topic:
            continue
        try:
            ts = json.loads(payload)["timestamp"]
        except Exception:
            continue
        if datetime.datetime.fromisoformat(ts.replace("Z", "+00:00")).timestamp() > float(sys.argv[2]) + 1:
            new += 1
    if new >= 500:
        print(f"{new} new tpdo events after the broker came back")
        sys.exit(0)
    time.sleep(0.5)
sys.exit(1)
PY
alive
pass "broker back: publishing again, space freed ($full_kb kB -> $(used_kb) kB), storage recovered"
stop_gateway
pass "the process never exited; clean stop"
stop_mosquitto
