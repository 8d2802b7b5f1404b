#!/bin/sh
# Run-time node configuration over REST on real SocketCAN (issue 17 item 1,
# contract "Remote configuration and maintenance"): a canopen-sim device on
# vcan0 that the gateway was started WITHOUT an EDS for; its TPDOs arrive as
# PDOs nobody decodes. PUT .../nodes/10/eds with its EDS: from then on they
# are decoded with named values (GET .../nodes/10), without a restart; a
# broken EDS is refused with FILE:LINE and changes nothing; the upload is
# kept in state-dir, so a restarted gateway decodes at once.
. "$(dirname "$0")/lib.sh"
PORT=$(free_port)
NODE=http://127.0.0.1:$PORT/api/v1/networks/1/nodes/10
IO_EDS=$EDS_DIR/cia401-io-module.eds

# call METHOD URL [FILE [CONTENT-TYPE]]: prints "STATUS BODY"; loopback
# without tokens acts as admin (contract: an EDS upload needs admin).
call() {
  /usr/bin/python3 - "$@" <<'PY'
import sys, urllib.request, urllib.error
method, url = sys.argv[1], sys.argv[2]
data = open(sys.argv[3], "rb").read() if len(sys.argv) > 3 else None
req = urllib.request.Request(url, data=data, method=method)
if data is not None:
    req.add_header("Content-Type", sys.argv[4] if len(sys.argv) > 4 else "application/octet-stream")
try:
    with urllib.request.urlopen(req, timeout=30) as r:
        print(r.status, r.read().decode())
except urllib.error.HTTPError as e:
    print(e.code, e.read().decode())
PY
}

# named_values FILE: how many of node 10's values (GET .../nodes/10) carry a name.
named_values() {
  /usr/bin/python3 -c 'import json,sys; b=json.loads(open(sys.argv[1]).read().split(" ",1)[1]); print(sum(1 for v in b["values"] if v["name"]))' "$1"
}

start_gateway --can vcan0 --http "127.0.0.1:$PORT"
start_sim "$T/sim.log" --node 10="$IO_EDS" --heartbeat 200 --tpdo-period 100 --auto-start
wait_for "$GW_LOG" "node 10 operational" 10
sleep 0.5
call GET "$NODE" > "$T/before.out"
grep -q '^200 .*"eds":false' "$T/before.out" || fail "node 10 before the upload: $(cat "$T/before.out")"
[ "$(named_values "$T/before.out")" = 0 ] || fail "values decoded without an EDS: $(cat "$T/before.out")"
pass "without an EDS node 10's TPDOs are not decoded"

# A file the reader refuses: 400 FILE:LINE: reason, nothing changed.
{ cat "$IO_EDS"; printf '\n[6001]\nParameterName=X\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\nAccessType=rw\n'; } > "$T/broken.eds"
call PUT "$NODE/eds?name=broken.eds" "$T/broken.eds" > "$T/broken.out"
grep -q '^400 .*"detail":"broken.eds:[0-9]*: key .AccessType.' "$T/broken.out" || fail "broken EDS: $(cat "$T/broken.out")"
call GET "$NODE" | grep -q '"eds":false' || fail "the refused upload changed node 10"
pass "a broken EDS is 400 with FILE:LINE and changes nothing"

call PUT "$NODE/eds?name=cia401-io-module.eds" "$IO_EDS" > "$T/upload.out"
grep -q '^200 .*"source":"state-dir"' "$T/upload.out" || fail "upload: $(cat "$T/upload.out")"
grep -q "audit: node configuration: .*net 1 node 10: EDS/DCF cia401-io-module.eds uploaded" "$GW_LOG" ||
  fail "no audit line for the upload"
cmp -s "$IO_EDS" "$STATE_DIRECTORY/nodes/net1-node10.eds" || fail "the EDS is not kept in state-dir"
i=0
while :; do
  call GET "$NODE" > "$T/after.out"
  [ "$(named_values "$T/after.out")" -gt 0 ] && break
  i=$((i + 1)); [ $i -lt 50 ] || fail "no named values after the upload: $(cat "$T/after.out")"
  sleep 0.2
done
grep -q '"eds":true' "$T/after.out" || fail "GET node 10 says no EDS: $(cat "$T/after.out")"
kill -0 "$GW_PID" || fail "the gateway is gone"
pass "after the upload node 10's TPDOs are decoded with named values, no restart ($(named_values "$T/after.out") values)"

call GET "http://127.0.0.1:$PORT/api/v1/gateway" | grep -q '"node":10,"source":"state-dir"' ||
  fail "GET /api/v1/gateway does not name state-dir for node 10"
stop_gateway

# Kept: the next start decodes at once.
start_gateway --can vcan0 --http "127.0.0.1:$PORT"
grep -q "settings from .*net1-node10.yaml" "$GW_LOG" || fail "the restart did not take the kept settings"
i=0
while :; do
  call GET "$NODE" > "$T/restart.out"
  [ "$(named_values "$T/restart.out")" -gt 0 ] && break
  i=$((i + 1)); [ $i -lt 50 ] || fail "no named values after the restart: $(cat "$T/restart.out")"
  sleep 0.2
done
pass "after a restart the kept EDS decodes node 10 at once"

kill -KILL "$SIM_PID"
wait "$SIM_PID" 2>/dev/null || true
stop_gateway
