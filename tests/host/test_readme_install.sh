#!/bin/sh
# The README as a user follows it, its commands taken from the README itself
# (the fenced blocks after `<!-- readme-test: NAME -->`, tests/host/readme_blocks.py),
# so a wrong change to the README fails here:
#  - "From source": every command of the install block, run into a temporary
#    root (/usr/local and /etc moved under it, sudo dropped); a command this
#    test does not know fails it. `systemctl enable --now` becomes the
#    installed unit's ExecStart, run as an unprivileged user as the unit does,
#    with the installed example configuration: its simulated network starts,
#    and the "check that it runs" block prints what the README shows.
#  - The tour: the demo started with the README's command from the installed
#    prefix, and every tour block (MQTT events and requests, REST, WebSocket)
#    prints the lines the README shows.
#  - Every flag of the installed `canopen-gateway --help` is in
#    docs/reference/command-line.md.
# Ports: the README's 8080 and 1883 become free ones (a private mosquitto).
TMPDIR=$(mktemp -d /tmp/readme-test.XXXXXX)
export TMPDIR
MOSQ_PID=
cleanup() {
  [ -z "${GW_PID:-}" ] || kill "$GW_PID" 2>/dev/null || true
  [ -z "$MOSQ_PID" ] || kill "$MOSQ_PID" 2>/dev/null || true
  rm -rf "$TMPDIR"
}
trap cleanup EXIT
. "$(dirname "$0")/../system/lib.sh"
. "$(dirname "$0")/../system/installed.sh"   # AS_SERVICE, service_state_dir, unit_command
: "${SOURCE_DIR:?}"
README=$SOURCE_DIR/README.md
BLOCKS="/usr/bin/python3 $SOURCE_DIR/tests/host/readme_blocks.py"
R=$T/root                     # stands for /
chmod 755 "$T"                # the service's user reads the installation

PORT=$(free_port)
MQTT_PORT=$(free_port)
printf 'listener %s 127.0.0.1\nallow_anonymous true\npersistence false\n' "$MQTT_PORT" > "$T/mosquitto.conf"
/usr/sbin/mosquitto -c "$T/mosquitto.conf" > "$T/mosquitto.log" 2>&1 &
MOSQ_PID=$!
wait_for "$T/mosquitto.log" "mosquitto version .* running" 10

# ---- "From source": the build block names what this test's build is --------
$BLOCKS block "$README" install-build > "$T/build.sh" || fail "README: no install-build block"
while IFS= read -r line; do
  case $line in
    ./deploy/install-deps.sh) [ -x "$SOURCE_DIR/deploy/install-deps.sh" ] || fail "README runs $line, which is not there" ;;
    "cmake --preset default && cmake --build --preset default")
      grep -q '"name": "default"' "$SOURCE_DIR/CMakePresets.json" || fail "README builds with preset default, which CMakePresets.json lacks" ;;
    "") ;;
    *) fail "README's build block has a step this test does not know: $line" ;;
  esac
done < "$T/build.sh"
# The install block's `build` is the default preset's build directory.
grep -q '"binaryDir": "${sourceDir}/build"' "$SOURCE_DIR/CMakePresets.json" ||
  fail "the default preset does not build into build/, which the README installs from"

# ---- "From source": the install block, into $R ------------------------------
start_service() {
  UNIT=$R/usr/local/lib/systemd/system/canopen-gateway.service
  [ -f "$UNIT" ] || fail "systemctl enable: no unit at $UNIT"
  CMD=$(unit_command "$UNIT" "$R")
  [ -n "$CMD" ] || fail "the unit has no ExecStart"
  service_state_dir "$R/var/lib/canopen-gateway"
  export STATE_DIRECTORY=$R/var/lib/canopen-gateway
  GW_LOG=$T/service.log
  # shellcheck disable=SC2086 # the unit's command line, split as systemd does; as its user
  $AS_SERVICE $CMD --http "127.0.0.1:$PORT" --mqtt "tcp://127.0.0.1:$MQTT_PORT" > "$GW_LOG" 2>&1 &
  GW_PID=$!
  wait_for "$GW_LOG" "canopen-gateway started" 20
  wait_for "$GW_LOG" "node 5 operational" 20
  pass "systemctl enable --now: the unit's command started with the installed example ($CMD)"
}

$BLOCKS block "$README" install-source > "$T/install.sh" || fail "README: no install-source block"
[ -s "$T/install.sh" ] || fail "README's install-source block is empty"
while IFS= read -r line; do
  cmd=${line#sudo }
  case $cmd in
    "") continue ;;
    "cmake --install build "*)
      cmd="cmake --install $BUILD_DIR ${cmd#cmake --install build }" ;;
    "mkdir "* | "cp "* | "install "*) ;;
    "systemctl daemon-reload")
      # The unit is where systemd looks for units (when systemd-analyze can say).
      if command -v systemd-analyze > /dev/null; then
        systemd-analyze unit-paths 2> /dev/null | grep -qx /usr/local/lib/systemd/system ||
          fail "systemd does not look in /usr/local/lib/systemd/system for units"
      fi
      continue ;;
    "systemctl enable --now canopen-gateway") start_service; continue ;;
    *) fail "README's install block has a step this test does not know: $line" ;;
  esac
  # Everything it names under / goes under $R.
  cmd=$(printf '%s\n' "$cmd" | sed "s| /usr/local| $R/usr/local|g; s| /etc/| $R/etc/|g")
  echo "+ $cmd"
  sh -ec "$cmd" > "$T/step.log" 2>&1 || fail "README install step failed: $line: $(tail -5 "$T/step.log")"
done < "$T/install.sh"
[ -n "${GW_PID:-}" ] || fail "the README's install steps never start the service"
P=$R/usr/local

# ---- "Check that it runs" ---------------------------------------------------
# `systemctl status`: the service is running; the rest as written.
kill -0 "$GW_PID" 2>/dev/null || fail "the service is not running"
$BLOCKS run "$README" install-check \
  --sub "systemctl status canopen-gateway=kill -0 $GW_PID" --sub "127.0.0.1:8080=127.0.0.1:$PORT" ||
  fail "the README's check of the installed service"
stop_gateway; GW_PID=
pass "the installed service stopped cleanly"

# ---- the tour, against the installed programs --------------------------------
$BLOCKS block "$README" tour-start > "$T/tour-start.sh" || fail "README: no tour-start block"
TOUR=$(grep '^canopen-gateway ' "$T/tour-start.sh" || true)
[ -n "$TOUR" ] || fail "the tour does not start canopen-gateway: $(cat "$T/tour-start.sh")"
TOUR=$(printf '%s\n' "$TOUR" | sed "s|^canopen-gateway |$P/bin/canopen-gateway |; s|tcp://localhost:1883|tcp://127.0.0.1:$MQTT_PORT|")
export STATE_DIRECTORY=$T/tour-state
mkdir -p "$STATE_DIRECTORY"
GW_LOG=$T/tour.log
# shellcheck disable=SC2086 # the README's command line
$TOUR --http "127.0.0.1:$PORT" > "$GW_LOG" 2>&1 &
GW_PID=$!
wait_for "$GW_LOG" "canopen-gateway started" 20
wait_for "$GW_LOG" "node 5 operational" 20
wait_for "$GW_LOG" "mqtt: connected" 20
pass "tour: started as the README says: $TOUR"
ran=0
for name in $(grep -o '<!-- readme-test: tour-[a-z0-9-]*' "$README" | sed 's/.*: //' | sort -u); do
  [ "$name" = tour-start ] && continue
  $BLOCKS run "$README" "$name" \
    --sub "127.0.0.1:8080=127.0.0.1:$PORT" \
    --sub "mosquitto_sub -h 127.0.0.1=mosquitto_sub -h 127.0.0.1 -p $MQTT_PORT" \
    --sub "mosquitto_pub -h 127.0.0.1=mosquitto_pub -h 127.0.0.1 -p $MQTT_PORT" ||
    fail "tour block $name"
  ran=$((ran + 1))
done
[ "$ran" -ge 5 ] || fail "only $ran tour blocks found in the README"
stop_gateway; GW_PID=
pass "tour: $ran blocks as the README shows"

# ---- every flag of --help is documented --------------------------------------
"$P/bin/canopen-gateway" --help > "$T/help.txt" 2>&1 || fail "canopen-gateway --help: $(cat "$T/help.txt")"
for flag in $(grep -oE -- '--[a-z][a-z-]+' "$T/help.txt" | sort -u); do
  grep -qF -- "\`$flag" "$SOURCE_DIR/docs/reference/command-line.md" ||
    fail "canopen-gateway --help has $flag, docs/reference/command-line.md does not"
done
pass "every flag of canopen-gateway --help is in docs/reference/command-line.md"
