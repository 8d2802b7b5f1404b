#!/bin/sh
# The Debian package as the README builds it (cpack -G DEB in the build
# directory; here into a temporary directory, from the existing build):
#  1. its control data: name, version, Depends from the binaries' libraries
#     (dpkg-shlibdeps) plus adduser, the conffile, the maintainer scripts;
#  2. its files: the programs (stripped) with manual pages, the dashboard,
#     the EDS files, the unit, /etc/canopen-gateway/gateway.yaml (the example,
#     every file it names in the package), the copyright file, nothing else;
#  3. unpacked (dpkg-deb -x), the unit's command runs with the packaged
#     configuration, its paths moved under the unpacked root and nothing
#     else changed, as an unprivileged user: a simulated network whose events
#     reach a broker, whose REST API answers and whose dashboard is the
#     packaged one; the configuration's real-bus half finds its EDS files;
#  4. systemd-analyze verify accepts the packaged unit; lintian (when
#     installed) reports no error or warning.
TMPDIR=$(mktemp -d /tmp/host-test.XXXXXX)
export TMPDIR
trap 'kill $MOSQ_PID $SUB_PID $GW_PID 2>/dev/null || true; rm -rf "$TMPDIR"' EXIT
. "$(dirname "$0")/../system/lib.sh"
. "$(dirname "$0")/../system/installed.sh"
chmod 755 "$T"  # the service's user reads the unpacked package

# ---- 1: build it, control data --------------------------------------------------
cpack -G DEB --config "$BUILD_DIR/CPackConfig.cmake" -B "$T/pkg" > "$T/cpack.log" 2>&1 ||
  fail "cpack: $(tail -20 "$T/cpack.log")"
DEB=$(ls "$T"/pkg/canopen-gateway_*.deb 2>/dev/null) || fail "no canopen-gateway_*.deb: $(tail -5 "$T/cpack.log")"
VERSION=$("$BUILD_DIR/gateway/canopen-gateway" --version | sed -n 's/^canopen-gateway //p')
[ "$(basename "$DEB")" = "canopen-gateway_${VERSION}_$(dpkg --print-architecture).deb" ] ||
  fail "package file $(basename "$DEB"), expected canopen-gateway_${VERSION}_<arch>.deb"
field() { dpkg-deb -f "$DEB" "$1"; }
[ "$(field Package)" = canopen-gateway ] || fail "Package: $(field Package)"
[ "$(field Version)" = "$VERSION" ] || fail "Version: $(field Version), the gateway says $VERSION"
# Every library the gateway links (from its ELF NEEDED entries) is a
# dependency, found by dpkg-shlibdeps, not a hand-kept list.
DEPENDS=$(field Depends)
for lib in libyaml-cpp libssl3 libboost-json libboost-url libstdc++6 libc6 adduser; do
  echo "$DEPENDS" | grep -q "$lib" || fail "Depends lacks $lib: $DEPENDS"
done
echo "$(field Recommends)" | grep -q mosquitto || fail "Recommends lacks mosquitto (the shipped config's broker)"
dpkg-deb -e "$DEB" "$T/control" || fail "cannot read the control archive"
[ "$(cat "$T/control/conffiles")" = /etc/canopen-gateway/gateway.yaml ] ||
  fail "conffiles: $(cat "$T/control/conffiles")"
for s in postinst prerm postrm; do
  [ -x "$T/control/$s" ] || fail "no executable $s"
  sh -n "$T/control/$s" || fail "$s is not valid sh"
done
grep -q "adduser --quiet --system" "$T/control/postinst" || fail "postinst makes no system user"
grep -q "deb-systemd-helper enable canopen-gateway.service" "$T/control/postinst" || fail "postinst does not enable the unit"
pass "control: $(field Package) $(field Version), Depends: $DEPENDS; conffile /etc/canopen-gateway/gateway.yaml"

# ---- 2: files ---------------------------------------------------------------------
dpkg-deb -c "$DEB" | awk '{print $6}' | sed 's|^\./|/|; s|/$||' | sort > "$T/files"
cat > "$T/expected" <<EOF
/etc/canopen-gateway/gateway.yaml
/usr/bin/canopen-eds
/usr/bin/canopen-gateway
/usr/bin/canopen-sim
/usr/lib/systemd/system/canopen-gateway.service
/usr/share/canopen-gateway/eds/cia401-io-module.eds
/usr/share/canopen-gateway/eds/cia402-drive.eds
/usr/share/canopen-gateway/gateway.example.yaml
/usr/share/canopen-gateway/web/api.js
/usr/share/canopen-gateway/web/app.js
/usr/share/canopen-gateway/web/auth.js
/usr/share/canopen-gateway/web/charts.js
/usr/share/canopen-gateway/web/config.js
/usr/share/canopen-gateway/web/dcf.js
/usr/share/canopen-gateway/web/dom.js
/usr/share/canopen-gateway/web/emcy.js
/usr/share/canopen-gateway/web/events.js
/usr/share/canopen-gateway/web/format.js
/usr/share/canopen-gateway/web/header.js
/usr/share/canopen-gateway/web/index.html
/usr/share/canopen-gateway/web/lss.js
/usr/share/canopen-gateway/web/network.js
/usr/share/canopen-gateway/web/nodes.js
/usr/share/canopen-gateway/web/od.js
/usr/share/canopen-gateway/web/state.js
/usr/share/canopen-gateway/web/trace.js
/usr/share/canopen-gateway/web/util.js
/usr/share/canopen-gateway/web/values.js
/usr/share/doc/canopen-gateway/changelog.gz
/usr/share/doc/canopen-gateway/copyright
/usr/share/lintian/overrides/canopen-gateway
/usr/share/man/man1/canopen-eds.1.gz
/usr/share/man/man1/canopen-gateway.1.gz
/usr/share/man/man1/canopen-sim.1.gz
EOF
missing=$(sort "$T/expected" | comm -23 - "$T/files")
[ -z "$missing" ] || fail "not in the package: $missing"
# Nothing from the build or the source tree beyond what is installed.
stray=$(grep -vE '^/(etc/canopen-gateway|usr/bin|usr/lib/systemd/system|usr/share/(canopen-gateway|doc/canopen-gateway|man/man1|lintian/overrides))(/|$)' "$T/files" |
        grep -vxE '/|/etc|/usr|/usr/lib|/usr/lib/systemd|/usr/share|/usr/share/doc|/usr/share/man|/usr/share/lintian' || true)
[ -z "$stray" ] || fail "unexpected files in the package: $stray"
dpkg-deb -c "$DEB" | grep -vE '^(d|-)[rwx-]{9} root/root ' && fail "a file not owned by root or of an odd type (above)"

X=$T/unpacked
dpkg-deb -x "$DEB" "$X" || fail "dpkg-deb -x"
chmod 755 "$X"
for b in canopen-gateway canopen-eds canopen-sim; do
  readelf -S "$X/usr/bin/$b" | grep -q '\.debug_info' && fail "$b is not stripped"
done
cmp -s "$X/etc/canopen-gateway/gateway.yaml" "$X/usr/share/canopen-gateway/gateway.example.yaml" ||
  fail "/etc/canopen-gateway/gateway.yaml is not the example"
for f in $(grep -oE "/usr/share/canopen-gateway/[^ ]*" "$X/etc/canopen-gateway/gateway.yaml"); do
  [ -e "$X$f" ] || fail "the packaged configuration names $f, which is not in the package"
done
"$X/usr/bin/canopen-eds" check "$X"/usr/share/canopen-gateway/eds/*.eds > "$T/check.log" 2>&1 ||
  fail "packaged canopen-eds refused the packaged EDS files: $(cat "$T/check.log")"
pass "files: $(wc -l < "$T/files") entries, programs stripped, every file the configuration names is packaged"

# ---- 3: the unit's command, unpacked ------------------------------------------------
# Paths under the unpacked root; ports of this test (flags, as an
# administrator would not need to).
sed "s|/usr/share/canopen-gateway/|$X/usr/share/canopen-gateway/|g" "$X/etc/canopen-gateway/gateway.yaml" > "$T/gateway.yaml"
mv "$T/gateway.yaml" "$X/etc/canopen-gateway/gateway.yaml"
UNIT=$X/usr/lib/systemd/system/canopen-gateway.service
grep -q "^ExecStart=/usr/bin/canopen-gateway --config /etc/canopen-gateway/gateway.yaml$" "$UNIT" ||
  fail "unit's ExecStart: $(grep ExecStart "$UNIT")"
CMD=$(unit_command "$UNIT" "$X" | sed "s|^/usr/bin/|$X/usr/bin/|")
echo "<!-- installed copy -->" >> "$X/usr/share/canopen-gateway/web/index.html"
service_state_dir "$T/state"
export STATE_DIRECTORY=$T/state
MOSQ_PORT=$(free_port)
start_mosquitto
GW=$(sed -n 's/^  id: *\([^ ]*\).*/\1/p' "$X/etc/canopen-gateway/gateway.yaml" | head -1)
mosquitto_sub -h 127.0.0.1 -p "$MOSQ_PORT" -v -t "canopen/$GW/#" > "$T/mqtt.log" 2>&1 &
SUB_PID=$!
PORT=$(free_port)
GW_LOG=$T/gw.log
# shellcheck disable=SC2086 # CMD is the unit's command line, split as systemd does
$AS_SERVICE $CMD --http "127.0.0.1:$PORT" --mqtt "tcp://127.0.0.1:$MOSQ_PORT" > "$GW_LOG" 2>&1 &
GW_PID=$!
wait_for "$GW_LOG" "canopen-gateway started" 20
wait_for "$GW_LOG" "node 5 operational" 20
check_served "$X/usr" "$PORT"
wait_for "$T/mqtt.log" "^canopen/$GW/1/5/" 20
pass "the packaged configuration runs: simulated network, MQTT canopen/$GW/1/5/..., REST, dashboard from the package"
stop_gateway
stop_mosquitto
check_can0_variant "$X/etc/canopen-gateway/gateway.yaml" "$X/usr/bin/canopen-gateway"

# ---- 4: unit and lintian -------------------------------------------------------------
# The binary named by the unit is the unpacked one (systemd-analyze checks it).
sed "s|^ExecStart=/usr/bin/|ExecStart=$X/usr/bin/|" "$UNIT" > "$T/canopen-gateway.service"
check_unit "$T/canopen-gateway.service"
if command -v lintian > /dev/null; then
  lintian --fail-on error,warning "$DEB" > "$T/lintian.log" 2>&1 || fail "lintian: $(cat "$T/lintian.log")"
  pass "lintian: no error or warning"
else
  echo "SKIP: no lintian (deploy/install-deps.sh installs it)"
fi
