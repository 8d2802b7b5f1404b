# Helpers for tests of the gateway as a user gets it (cmake --install, or the
# .deb unpacked: tests/host/test_install.sh, test_deb_package.sh; its example
# configuration on can0: test_installed_example_on_can0.sh), started the way
# its systemd unit starts it. Sourced after tests/system/lib.sh; uses $T.

# $AS_SERVICE CMD...: CMD as the unit runs it, a user without capabilities
# or a way to gain them (User=, CapabilityBoundingSet=, NoNewPrivileges=):
# the installed files must be readable by another user, CAN and the
# listeners must need no privilege. As a non-root tester: CMD as is.
AS_SERVICE=
[ "$(id -u)" -ne 0 ] ||
  AS_SERVICE="setpriv --reuid=65534 --regid=65534 --clear-groups --inh-caps=-all --bounding-set=-all --no-new-privs --"

# service_state_dir DIR: a fresh StateDirectory= for $AS_SERVICE.
service_state_dir() {
  mkdir -p "$1"
  [ "$(id -u)" -ne 0 ] || chown 65534:65534 "$1"
}

# unit_command UNIT ROOT: the unit's ExecStart with /etc moved under ROOT
# (the binary's path is the installed one already).
unit_command() {
  sed -n 's/^ExecStart=//p' "$1" | sed "s| /etc/| $2/etc/|g"
}

# check_served ROOT PORT: the REST API answers an SDO read of the simulated
# drive (node 5, identity 1018h sub 1: its vendor-ID), and the dashboard comes
# from ROOT's share/canopen-gateway/web (marked by the caller), not the source.
check_served() {
  /usr/bin/python3 - "$2" <<'PY' || fail "REST API: no SDO read of node 5 on network 1"
import json, sys, urllib.request
r = json.load(urllib.request.urlopen(f"http://127.0.0.1:{sys.argv[1]}/api/v1/networks/1/nodes/5/sdo/1018/1", timeout=10))
print("REST: node 5 1018h/1 =", r)
sys.exit(0 if r.get("value") == 0x5A1 else 1)
PY
  /usr/bin/python3 - "$2" <<'PY' || fail "dashboard not served from $1"
import sys, urllib.request
body = urllib.request.urlopen(f"http://127.0.0.1:{sys.argv[1]}/", timeout=5).read().decode()
sys.exit(0 if "installed copy" in body else 1)
PY
}

# real_bus_config CONFIG OUT: the example made a real-bus configuration as
# its comments say: the simulated network deleted, the can0 network
# uncommented.
real_bus_config() {
  awk '
    /^  - simulated: true/ { skip = 1; next }
    skip && /^  [^ ]/ { skip = 0 }
    skip && /^$/ { skip = 0 }
    skip { next }
    /^  # - interface: can0/ { on = 1 }
    on && /^$/ { on = 0 }
    on { sub(/^  # /, "  ") }
    { print }
  ' "$1" > "$2"
  grep -q "^  - interface: can0" "$2" || fail "no can0 network to uncomment in $1"
  grep -q "^  - simulated: true" "$2" && fail "the simulated network is still in $2"
  return 0
}

# check_can0_variant CONFIG GATEWAY: the example's real-bus configuration is
# accepted up to opening can0: its EDS files are found and read (a bad one
# is a configuration error), so the gateway stops with exit 3 (CAN
# unavailable: no can0 here, or no SocketCAN in this kernel), not 2.
# On can0 itself: tests/system/test_installed_example_on_can0.sh.
check_can0_variant() {
  local gateway=$2 real=$T/real-bus.yaml rc=0
  real_bus_config "$1" "$real"
  if ip link show can0 > /dev/null 2>&1; then
    echo "SKIP: this machine has a can0; the real-bus example is not started"
    return 0
  fi
  $AS_SERVICE "$gateway" --config "$real" > "$T/real-bus.out" 2> "$T/real-bus.err" || rc=$?
  [ "$rc" -eq 3 ] || fail "the example with its can0 network: exit $rc (expected 3): $(cat "$T/real-bus.err")"
  pass "the example's can0 network parses, its EDS files load; then: $(cat "$T/real-bus.err")"
}

# check_unit UNIT: systemd-analyze verify finds nothing wrong with it (only
# lines naming the unit count; the machine may lack systemd as PID 1).
check_unit() {
  if ! command -v systemd-analyze > /dev/null; then
    echo "SKIP: no systemd-analyze"
    return 0
  fi
  systemd-analyze verify "$1" > "$T/verify.log" 2>&1 || true
  grep -F "$(basename "$1")" "$T/verify.log" && fail "systemd-analyze verify: $(cat "$T/verify.log")"
  pass "systemd-analyze verify: no problem in $(basename "$1")"
}
