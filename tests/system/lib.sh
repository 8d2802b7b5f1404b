# Helpers for system test scripts; sourced inside UML (see uml-run.sh).
set -eu
: "${BUILD_DIR:?BUILD_DIR must point at the build tree}"
GATEWAY=$BUILD_DIR/gateway/canopen-gateway
CAN_TOOL=$BUILD_DIR/tests/can_tool
T=${TMPDIR:-/tmp}
GW_LOG=$T/gateway.log
GW_PID=
# A gateway without gateway.state-dir keeps its state (each network's seq)
# here, not in the machine's /var/lib/canopen-gateway.
export STATE_DIRECTORY="${STATE_DIRECTORY:-$T/state}"

fail() {
  echo "FAIL: $*"
  [ -f "$GW_LOG" ] && { echo "--- gateway log (last 40 lines)"; tail -n 40 "$GW_LOG"; }
  [ -f "$GW_LOG" ] && { echo "--- gateway mqtt lines"; grep -a "mqtt" "$GW_LOG" | grep -v " rx " | tail -n 25; }
  for extra in "$T/mosquitto.log" "$T/mqtt.log" "$T/sim.log"; do
    [ -s "$extra" ] && { echo "--- $extra (last 15 lines)"; tail -n 15 "$extra"; }
  done
  exit 1
}
pass() { echo "PASS: $*"; }

# wait_candump: waits for the candump started last; fails if it timed out.
wait_candump() {
  local rc=0
  wait "$CANDUMP_PID" || rc=$?
  [ "$rc" -eq 0 ] || fail "candump did not see all expected frames (status $rc)"
}

# wait_for FILE PATTERN [SECONDS]: until grep -E finds PATTERN in FILE.
wait_for() {
  local file=$1 pattern=$2 limit=${3:-20} i=0
  while [ $i -lt $((limit * 10)) ]; do
    grep -qE -- "$pattern" "$file" 2>/dev/null && return 0
    sleep 0.1; i=$((i + 1))
  done
  fail "timed out after ${limit}s waiting for /$pattern/ in $file"
}

# wait_count FILE PATTERN N [SECONDS]: until at least N lines match.
wait_count() {
  local file=$1 pattern=$2 n=$3 limit=${4:-30} i=0 c=0
  while [ $i -lt $((limit * 10)) ]; do
    c=$(grep -cE -- "$pattern" "$file" 2>/dev/null || true)
    [ "${c:-0}" -ge "$n" ] && return 0
    sleep 0.1; i=$((i + 1))
  done
  fail "timed out after ${limit}s: $c of $n lines matching /$pattern/ in $file"
}

start_gateway() {
  "$GATEWAY" "$@" > "$GW_LOG" 2>&1 &
  GW_PID=$!
  wait_for "$GW_LOG" "canopen-gateway started" 20
}

# Stops the gateway with SIGTERM (or $1) and checks it exits 0.
stop_gateway() {
  local sig=${1:-TERM} rc=0
  kill -"$sig" "$GW_PID"
  wait "$GW_PID" || rc=$?
  [ "$rc" -eq 0 ] || fail "gateway exited $rc after SIG$sig (expected 0)"
  grep -q "stopped" "$GW_LOG" || fail "gateway log has no clean 'stopped' line"
}

# Starts candump -L on IFACE writing to FILE; waits until it is listening.
# A large receive buffer (-r) so back-to-back bursts are not dropped by the
# observer itself; a time limit so a missing frame fails instead of hanging.
start_candump() {
  local iface=$1 file=$2; shift 2
  timeout 60 candump -L -r 16000000 "$@" "$iface" > "$file" 2>&1 &
  CANDUMP_PID=$!
  # Listening once candump (timeout's child) holds its CAN socket; the short
  # sleep after covers setsockopt/bind, which follow socket() at once.
  local i=0
  while [ $i -lt 100 ]; do
    for p in $(pgrep -P "$CANDUMP_PID" candump 2>/dev/null); do
      ls -l /proc/"$p"/fd 2>/dev/null | grep -q 'socket:' && { sleep 0.1; return 0; }
    done
    sleep 0.05; i=$((i + 1))
  done
  fail "candump on $iface did not start"
}

# free_port: a TCP port on 127.0.0.1 that nobody listens on now.
free_port() { /usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }

# ---- MQTT (a real mosquitto on loopback inside the UML kernel) -------------
SIM=$BUILD_DIR/gateway/canopen-sim
EDS_DIR=${SOURCE_DIR:-$(dirname "$0")/../..}/deploy/eds
MOSQ_PORT=1883
MOSQ_PID=

# start_mosquitto [persistence-dir]: listens on 127.0.0.1:$MOSQ_PORT.
start_mosquitto() {
  local conf=$T/mosquitto.conf
  {
    echo "listener $MOSQ_PORT 127.0.0.1"
    echo "allow_anonymous true"
    if [ -n "${1:-}" ]; then
      echo "persistence true"
      echo "persistence_location $1/"
      echo "autosave_interval 1"
    else
      echo "persistence false"
    fi
    echo "max_queued_messages 0"
    echo "log_dest file $T/mosquitto.log"
  } > "$conf"
  /usr/sbin/mosquitto -c "$conf" > /dev/null 2>&1 &
  MOSQ_PID=$!
  local i=0
  while [ $i -lt 100 ]; do
    mosquitto_pub -h 127.0.0.1 -p $MOSQ_PORT -t probe -m x 2>/dev/null && return 0
    sleep 0.1; i=$((i + 1))
  done
  fail "mosquitto did not start"
}

stop_mosquitto() {
  [ -n "$MOSQ_PID" ] || return 0
  kill -TERM "$MOSQ_PID" 2>/dev/null || true
  wait "$MOSQ_PID" 2>/dev/null || true
  MOSQ_PID=
}

# start_sim LOGFILE ARGS...: canopen-sim on vcan0, waits for "ready".
start_sim() {
  local log=$1; shift
  "$SIM" --can vcan0 "$@" > "$log" 2>&1 &
  SIM_PID=$!
  wait_for "$log" "^ready" 20
}

# json_field FILE TOPIC_REGEX: payloads (after the topic) of matching lines
# of a `mosquitto_sub -v` log.
payloads() { grep -E "^$2 " "$1" | cut -d' ' -f2-; }

# Sparkplug tests (tests/tools/sparkplug_check.py on a capture file):
# sp_wait SECONDS WHAT CHECKER-ARGS...: until the capture $CAP meets the
# expectations (the checker run as $CHECK); fails at once when a rule is
# broken (checker status 1). Polls SP_POLL_PER_S times a second (default 4).
sp_wait() {
  limit=$1 what=$2
  shift 2
  per_s=${SP_POLL_PER_S:-4}
  i=0
  while :; do
    rc=0
    $CHECK --capture "$CAP" "$@" > "$T/check.out" 2>&1 || rc=$?
    [ $rc -eq 0 ] && return 0
    [ $rc -eq 2 ] || fail "$what: $(grep -E '"violation"|sparkplug_check' "$T/check.out" | head -8)"
    [ $i -lt $((limit * per_s)) ] || fail "$what: timed out: $(tail -n 1 "$T/check.out")"
    sleep "$(awk "BEGIN { print 1 / $per_s }")"
    i=$((i + 1))
  done
}
# Lines in the capture so far (a later sp_wait can start after them).
lines() { wc -l < "$CAP"; }
