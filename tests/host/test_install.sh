#!/bin/sh
# The install from source as the README says, into a temporary root:
#   cmake --install build --prefix /usr/local
#   mkdir -p /etc/canopen-gateway
#   cp /usr/local/share/canopen-gateway/gateway.example.yaml /etc/canopen-gateway/gateway.yaml
#   systemctl enable --now canopen-gateway
# gives the programs, their manual pages, the dashboard, the EDS files and a
# unit that systemd-analyze accepts; the unit's command with the copied
# example starts a simulated network as an unprivileged user, whose REST API
# answers and whose dashboard is the installed one; the example's real-bus
# half (can0) finds its EDS files.
TMPDIR=$(mktemp -d /tmp/host-test.XXXXXX)
export TMPDIR
trap 'kill $GW_PID 2>/dev/null || true; rm -rf "$TMPDIR"' EXIT
. "$(dirname "$0")/../system/lib.sh"
. "$(dirname "$0")/../system/installed.sh"
: "${SOURCE_DIR:?}"
R=$T/root            # stands for /
P=$R/usr/local       # the prefix
chmod 755 "$T"       # the service's user reads the installation

cmake --install "$BUILD_DIR" --prefix "$P" > "$T/install.log" 2>&1 || fail "install: $(tail -5 "$T/install.log")"
for f in bin/canopen-gateway bin/canopen-sim bin/canopen-eds share/canopen-gateway/web/index.html \
         $(for m in api app auth charts config dcf dom emcy events format header lss network nodes od state trace util values; do
             echo "share/canopen-gateway/web/$m.js"; done) \
         share/canopen-gateway/gateway.example.yaml share/canopen-gateway/eds/cia402-drive.eds \
         share/canopen-gateway/eds/cia401-io-module.eds lib/systemd/system/canopen-gateway.service \
         share/man/man1/canopen-gateway.1.gz share/man/man1/canopen-eds.1.gz share/man/man1/canopen-sim.1.gz \
         share/doc/canopen-gateway/README.md share/doc/canopen-gateway/copyright; do
  [ -e "$P/$f" ] || fail "not installed: $f"
done
UNIT=$P/lib/systemd/system/canopen-gateway.service
grep -q "^ExecStart=$P/bin/canopen-gateway --config /etc/canopen-gateway/gateway.yaml$" "$UNIT" ||
  fail "unit's ExecStart is not the installed binary with /etc/canopen-gateway/gateway.yaml: $(grep ExecStart "$UNIT")"
# The manual page is the program's --help.
zcat "$P/share/man/man1/canopen-gateway.1.gz" | grep -q -- '\\-\\-config' || fail "canopen-gateway(1) lacks --help's --config"
pass "installed files, unit ExecStart $P/bin/canopen-gateway"
# The installed checker accepts the installed example EDS files.
"$P/bin/canopen-eds" check "$P/share/canopen-gateway/eds/"*.eds > "$T/check.log" 2>&1 ||
  fail "installed canopen-eds refused the installed EDS files: $(cat "$T/check.log")"

# The README's copy; every file it names is one the install made.
mkdir -p "$R/etc/canopen-gateway"
cp "$P/share/canopen-gateway/gateway.example.yaml" "$R/etc/canopen-gateway/gateway.yaml"
for f in $(grep -oE "/[^ ]*/share/canopen-gateway/[^ ]*" "$R/etc/canopen-gateway/gateway.yaml"); do
  case $f in "$P"/*) ;; *) fail "the example names $f, outside the prefix $P" ;; esac
  [ -e "$f" ] || fail "the example names $f, which the install did not make"
done

# The unit's command (and the unit's StateDirectory), ports of this test.
echo "<!-- installed copy -->" >> "$P/share/canopen-gateway/web/index.html"
service_state_dir "$R/var/lib/canopen-gateway"
CMD=$(unit_command "$UNIT" "$R")
PORT=$(free_port)
export STATE_DIRECTORY=$R/var/lib/canopen-gateway
# shellcheck disable=SC2086 # CMD is the unit's command line, split as systemd does
$AS_SERVICE $CMD --http "127.0.0.1:$PORT" --mqtt tcp://127.0.0.1:1 > "$T/gw.log" 2>&1 &
GW_PID=$!
GW_LOG=$T/gw.log
wait_for "$GW_LOG" "canopen-gateway started" 20
grep -q "net 1 demo" "$GW_LOG" || fail "the example's network 1 is not the simulated one"
wait_for "$GW_LOG" "node 5 operational" 20
check_served "$P" "$PORT"
pass "the unit's command with the installed example: simulated network, REST, dashboard from $P/share/canopen-gateway/web"
stop_gateway
[ -s "$STATE_DIRECTORY/seq-net1" ] || fail "no seq-net1 in the StateDirectory"
check_can0_variant "$R/etc/canopen-gateway/gateway.yaml" "$P/bin/canopen-gateway"

check_unit "$UNIT"
