#!/bin/sh
# DCF round trip over REST on real SocketCAN (issue 17 item 3, contract
# "Remote configuration and maintenance"): a canopen-sim I/O module (CiA 401
# EDS) as node 10 on vcan0. GET .../dcf reads its configuration back by SDO
# (a DCF, CiA 306); one value changed in that file (6424h sub 1, analogue
# input interrupt upper limit) and POSTed back writes it to the device (one
# result per object); a second GET shows the new value, and an SDO read
# agrees.
# uml-run: --timeout 200
. "$(dirname "$0")/lib.sh"
PORT=$(free_port)
NODE=http://127.0.0.1:$PORT/api/v1/networks/1/nodes/10
CALL="/usr/bin/python3 $(dirname "$0")/maint_call.py"

cat > "$T/gw.yaml" <<YAML
gateway: {id: gw1, state-dir: $T/state}
networks:
  - interface: vcan0
    nodes:
      - {id: 10, name: io, eds: $EDS_DIR/cia401-io-module.eds, boot: {start: true}}
YAML
# The gateway first: it starts the device when it hears its boot-up.
start_gateway --config "$T/gw.yaml" --http "127.0.0.1:$PORT"
start_sim "$T/sim.log" --node 10="$EDS_DIR/cia401-io-module.eds" --heartbeat 200
wait_for "$GW_LOG" "node 10 operational" 20

# value_in FILE INDEX SUB: the ParameterValue of [INDEXsubSUB] (or [INDEX] for sub 0).
value_in() {
  /usr/bin/python3 - "$@" <<'PY'
import re, sys
text = open(sys.argv[1], encoding="latin-1").read()
text = text.split("\n\n", 1)[1] if text[:3].isdigit() else text  # skip status and headers
section = sys.argv[2] + ("sub" + sys.argv[3] if sys.argv[3] != "0" else "")
m = re.search(r"^\[" + section + r"\]\s*$(.*?)(?=^\[|\Z)", text, re.M | re.S | re.I)
v = m and re.search(r"^ParameterValue=(.*)$", m.group(1), re.M)
print(v.group(1).strip() if v else "missing")
PY
}

$CALL GET "$NODE/dcf" > "$T/read1.out"
head -n 1 "$T/read1.out" | grep -q '^200$' || fail "GET dcf: $(head -c 400 "$T/read1.out")"
grep -qi '^content-disposition: attachment; filename="node10.dcf"' "$T/read1.out" || fail "no file name: $(head -n 12 "$T/read1.out")"
grep -qi '^x-canopen-objects-read: [1-9]' "$T/read1.out" || fail "no objects read: $(head -n 12 "$T/read1.out")"
BEFORE=$(value_in "$T/read1.out" 6424 1)
[ "$BEFORE" = "32767" ] || fail "6424h sub 1 read back as '$BEFORE', expected the device's 32767"
HB=$(value_in "$T/read1.out" 1017 0)
pass "GET dcf: $(grep -i '^x-canopen-objects-read' "$T/read1.out"), 6424h sub 1 = $BEFORE, 1017h = $HB"

# Change the one value in the file read back and apply it.
sed -n '/^$/,$p' "$T/read1.out" | tail -n +2 > "$T/node10.dcf"
/usr/bin/python3 - "$T/node10.dcf" <<'PY'
import re, sys
p = sys.argv[1]
t = open(p, encoding="latin-1").read()
t, n = re.subn(r"(^\[6424sub1\]\s*$.*?^ParameterValue=)[^\n]*", r"\g<1>1234", t, count=1, flags=re.M | re.S | re.I)
assert n == 1, "no ParameterValue in [6424sub1]"
open(p, "w", encoding="latin-1").write(t)
PY
$CALL POST "$NODE/dcf" "$T/node10.dcf" > "$T/apply.out"
head -n 1 "$T/apply.out" | grep -q '^200$' || fail "POST dcf: $(cat "$T/apply.out")"
grep -q '{"index":25636,"subIndex":1,"ok":true}' "$T/apply.out" || fail "6424h sub 1 not written: $(tail -c 600 "$T/apply.out")"
grep -q '"failed":0' "$T/apply.out" || fail "objects failed: $(tail -c 600 "$T/apply.out")"
grep -q "audit: DCF apply by .*net 1 node 10: [0-9]* objects written, 0 failed" "$GW_LOG" || fail "no audit line for the apply"
pass "POST dcf: every object written ($(grep -o '"written":[0-9]*' "$T/apply.out"))"

$CALL GET "$NODE/dcf" > "$T/read2.out"
AFTER=$(value_in "$T/read2.out" 6424 1)
[ "$AFTER" = "1234" ] || fail "after the apply 6424h sub 1 reads back as '$AFTER'"
$CALL GET "$NODE/sdo/6424/1" > "$T/sdo.out"
grep -q '"value":1234' "$T/sdo.out" || fail "SDO read of 6424h sub 1: $(cat "$T/sdo.out")"
pass "GET dcf again: 6424h sub 1 = $AFTER (SDO agrees)"

# A file the EDS reader refuses (one entry with two values; a value that
# cannot be read is only left out): 400 FILE:LINE, nothing written.
sed 's/^ParameterValue=1234/ParameterValue=1234\nParameterValue=4321/' "$T/node10.dcf" > "$T/bad.dcf"
$CALL POST "$NODE/dcf" "$T/bad.dcf" > "$T/bad.out"
head -n 1 "$T/bad.out" | grep -q '^400$' || fail "bad DCF: $(cat "$T/bad.out")"
grep -q "node10.dcf:[0-9]*: key 'ParameterValue'" "$T/bad.out" || fail "no FILE:LINE in: $(cat "$T/bad.out")"
$CALL GET "$NODE/sdo/6424/1" > "$T/sdo2.out"
grep -q '"value":1234' "$T/sdo2.out" || fail "the refused file changed 6424h sub 1: $(tail -n 1 "$T/sdo2.out")"
pass "a malformed DCF is 400 with FILE:LINE"

kill -TERM "$SIM_PID"
wait "$SIM_PID" 2>/dev/null || true
stop_gateway
