#!/usr/bin/env bash
# Flash wear of the MQTT queue (issue 12): storage bytes written per byte of
# MQTT payload, for the real gateway process (its simulated network, the
# demo's devices) against a local mosquitto, in steady state and during a
# broker outage, with the storage modes as configured by default (QoS 0
# kinds `outage`, QoS 1 kinds `disk`) and with every kind `disk` (what the
# gateway did before: every event through the disk queue, fdatasync every
# 100 ms).
#
# Storage bytes: write_bytes of /proc/<gateway pid>/io over the window: the
# bytes of page cache the process dirtied, which the kernel has to write to
# the device (a page counts again each time it is dirtied after being
# written back, so an fdatasync of a half-filled page followed by more
# appends counts that page twice: exactly the amplification in question).
# It leaves out the file system's own journal and metadata writes (ext4's
# jbd2 thread), so real device writes are somewhat higher; the device-wide
# /sys/block counters are not used because other processes share the disk.
# Also printed: the bytes the queue handed to the kernel and its fdatasync
# calls (canopen_gateway_mqtt_storage_written_bytes_total, _syncs_total).
# Payload bytes: the MQTT payloads of the events stamped inside the window,
# as a subscriber received them (for the outage: after the broker is back).
#
#   bench/storage_wear.sh BUILD_DIR [SECONDS [CASE...]]
# CASE: demo-default demo-all-disk busy-default busy-all-disk
# busy-outage-default busy-outage-all-disk (all by default); demo: the
# demo's devices (new values every 200 ms), busy: every 1 ms (~900 events/s).
# GATEWAY=path overrides the binary (an older build: use the *-default cases).
set -euo pipefail
BUILD=${1:?usage: storage_wear.sh BUILD_DIR [SECONDS [CASE...]]}
SECS=${2:-30}
shift $(($# > 1 ? 2 : 1))
CASES=${*:-demo-default demo-all-disk busy-default busy-all-disk busy-outage-default busy-outage-all-disk}
GATEWAY=${GATEWAY:-$BUILD/gateway/canopen-gateway}
DIR=$(mktemp -d /tmp/storage-wear.XXXXXX)
free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
PORT=$(free_port)
HTTP=$(free_port)
MOSQ= SUB= GW=
cleanup() {
  for p in $GW $SUB $MOSQ; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$DIR"
}
trap cleanup EXIT
mkdir -p "$DIR/mosq"
cat > "$DIR/m.conf" <<EOF
listener $PORT 127.0.0.1
allow_anonymous true
persistence true
persistence_location $DIR/mosq/
autosave_interval 0
queue_qos0_messages true
max_queued_messages 0
EOF
start_broker() {
  /usr/sbin/mosquitto -c "$DIR/m.conf" > "$DIR/m.log" 2>&1 &
  MOSQ=$!
  for _ in $(seq 50); do mosquitto_pub -h 127.0.0.1 -p "$PORT" -t probe -m x 2>/dev/null && return; sleep 0.1; done
  echo "mosquitto did not start" >&2
  exit 1
}
stop_broker() { kill "$MOSQ"; wait "$MOSQ" 2>/dev/null || true; MOSQ=; }
start_sub() {  # a persistent session: what comes while it reconnects is kept
  mosquitto_sub -h 127.0.0.1 -p "$PORT" -V mqttv311 -c -i "wear-$1" -q 1 -v -t "canopen/wear/#" >> "$DIR/sub-$1.log" 2>&1 &
  SUB=$!
  sleep 0.3
}
stop_sub() { kill "$SUB" 2>/dev/null || true; wait "$SUB" 2>/dev/null || true; SUB=; }
write_bytes() { awk '/^write_bytes/ {print $2}' "/proc/$GW/io"; }
metric() {  # 0 when the build has no such metric
  curl -s "http://127.0.0.1:$HTTP/metrics" | awk -v m="$1" '$1 == m {print $2; f = 1} END {if (!f) print 0}'
}

# run NAME TPDO_PERIOD_MS STORAGE(default|disk) steady|outage
run() {
  local name=$1 period=$2 storage=$3 mode=$4
  local state=$DIR/state-$name
  {
    echo "gateway: {id: wear, state-dir: $state}"
    echo "networks:"
    echo "  - simulated: true"
    echo "    simulation: {tpdo-period-ms: $period}"
    echo "mqtt:"
    echo "  uri: tcp://127.0.0.1:$PORT"
    [ "$storage" = disk ] && echo "  queue: {storage: {default: disk}}"
    echo "http: {listen: 127.0.0.1:$HTTP}"
  } > "$DIR/$name.yaml"
  start_broker
  start_sub "$name"
  "$GATEWAY" --config "$DIR/$name.yaml" > "$DIR/gw-$name.log" 2>&1 &
  GW=$!
  sleep 3  # start-up and first writes out of the way
  local w0 q0 s0 t0 w1 q1 s1 t1
  w0=$(write_bytes); q0=$(metric canopen_gateway_mqtt_storage_written_bytes_total)
  s0=$(metric canopen_gateway_mqtt_storage_syncs_total); t0=$(date +%s.%N)
  if [ "$mode" = outage ]; then stop_sub; stop_broker; fi
  sleep "$SECS"
  w1=$(write_bytes); q1=$(metric canopen_gateway_mqtt_storage_written_bytes_total)
  s1=$(metric canopen_gateway_mqtt_storage_syncs_total); t1=$(date +%s.%N)
  if [ "$mode" = outage ]; then
    start_broker
    start_sub "$name"
    for _ in $(seq 300); do [ "$(metric canopen_gateway_mqtt_queue_depth)" = 0 ] && break; sleep 0.1; done
  fi
  sleep 1
  kill "$GW"; wait "$GW" 2>/dev/null || true; GW=
  stop_sub
  stop_broker
  rm -rf "$DIR/mosq"/*
  /usr/bin/python3 - "$DIR/sub-$name.log" "$t0" "$t1" "$name" "$((w1 - w0))" "$((q1 - q0))" "$((s1 - s0))" <<'PY'
import datetime, json, sys
log, t0, t1, name = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
wb, qb, syncs = int(sys.argv[5]), int(sys.argv[6]), int(sys.argv[7])
payload = events = 0
for line in open(log, encoding="utf-8", errors="replace"):
    topic, _, body = line.rstrip("\n").partition(" ")
    try:
        ts = json.loads(body)["timestamp"]
    except Exception:
        continue
    t = datetime.datetime.fromisoformat(ts.replace("Z", "+00:00")).timestamp()
    if t0 <= t <= t1:
        payload += len(body.encode())
        events += 1
secs = t1 - t0
print(f"{name:<22} {events / secs:8.0f} ev/s {payload / secs / 1024:8.1f} KiB/s payload | "
      f"write_bytes {wb / secs / 1024:8.1f} KiB/s = {wb / max(payload, 1):5.2f} B/B | "
      f"queue wrote {qb / max(payload, 1):5.2f} B/B, {syncs / secs:5.1f} fdatasync/s")
PY
}

echo "window: $SECS s per case; ratios are storage bytes per MQTT payload byte (B/B)"
for c in $CASES; do
  case $c in
    demo-default) run "$c" 200 default steady ;;
    demo-all-disk) run "$c" 200 disk steady ;;
    busy-default) run "$c" 1 default steady ;;
    busy-all-disk) run "$c" 1 disk steady ;;
    busy-outage-default) run "$c" 1 default outage ;;
    busy-outage-all-disk) run "$c" 1 disk outage ;;
    *) echo "unknown case $c" >&2; exit 2 ;;
  esac
done
