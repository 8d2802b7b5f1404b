#!/bin/sh
# The CiA 309-3 ASCII interface of the real canopen-gateway process
# (contract "CiA 309-3 ASCII interface"; facts B in
# ../shared/ref/sparkplug-ascii-lss-facts.md), driven as scripts drive
# CANopenNode's gateway: command lines over a socket, answers read back.
# cocomm itself is not packaged in Debian; Debian's python3 sends the bytes.
#  1. --ascii 127.0.0.1:0: the start-up line names the bound address;
#  2. a read of node 5's 1018h:1 (vendor-ID 5A1h), a write and its read back,
#     NMT stop and start (the node's state follows, seen over REST), an SDO
#     abort and an unknown command, answered as CANopenNode does;
#  3. a unix socket (mode 0660), removed at a clean stop;
#  4. off loopback without ascii.allow-remote: refused at start, exit 2.
# On the host: the gateway's simulated network; no broker needed.
TMPDIR=$(mktemp -d /tmp/host-test.XXXXXX)
export TMPDIR
trap 'kill $GW_PID 2>/dev/null || true; rm -rf "$TMPDIR"' EXIT
. "$(dirname "$0")/../system/lib.sh"
PY=/usr/bin/python3

# ascii WHERE: sends stdin to the ASCII server at WHERE (127.0.0.1:PORT or
# unix:/path), closes its side and prints every byte of the answers.
ascii() {
  $PY -c '
import socket, sys
where = sys.argv[1]
if where.startswith("unix:"):
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.connect(where[5:])
else:
    host, port = where.rsplit(":", 1)
    s = socket.create_connection((host, int(port)))
s.settimeout(15)
s.sendall(sys.stdin.buffer.read())
s.shutdown(socket.SHUT_WR)
out = b""
while True:
    d = s.recv(65536)
    if not d:
        break
    out += d
sys.stdout.buffer.write(out)
' "$1"
}

# node_state NODE: the node's NMT state as the REST API reports it.
node_state() {
  $PY -c '
import json, sys, urllib.request
d = json.load(urllib.request.urlopen("http://%s/api/v1/networks/1/nodes/%s" % (sys.argv[1], sys.argv[2])))
print(d.get("state", ""))
' "$HTTP" "$1"
}

# ---- 1: the start-up line ------------------------------------------------------
start_gateway --demo --http 127.0.0.1:0 --ascii 127.0.0.1:0
wait_for "$GW_LOG" "CiA 309-3 ASCII on 127\.0\.0\.1:[0-9]+ \(this machine only; clients act as admin\)"
WHERE=$(sed -n 's/.*CiA 309-3 ASCII on \(127\.0\.0\.1:[0-9]*\) .*/\1/p' "$GW_LOG" | head -1)
HTTP=$(sed -n 's|.*HTTP/WebSocket on http://\([^ ]*\) .*|\1|p' "$GW_LOG" | head -1)
[ -n "$WHERE" ] && [ "${WHERE##*:}" != 0 ] || fail "no bound ASCII port in: $(grep ASCII "$GW_LOG")"
pass "listening: $(grep -o 'CiA 309-3 ASCII on .*' "$GW_LOG")"
wait_for "$GW_LOG" "node 5 operational" 20

# ---- 2: commands and answers ------------------------------------------------------
printf '[1] 5 read 0x1018 1 u32\r\n[2] 5 w 0x1017 0 u16 800\n[3] 5 r 0x1017 0 u16\n' | ascii "$WHERE" > "$T/a1"
printf '[1] 1441\r\n[2] OK\r\n[3] 800\r\n' | cmp -s - "$T/a1" || fail "read/write answers: $(od -c "$T/a1" | head)"
pass "read 1018h:1 = 1441, write 1017h = 800 and read back"

printf '[4] 5 stop\n' | ascii "$WHERE" > "$T/a2"
printf '[4] OK\r\n' | cmp -s - "$T/a2" || fail "stop: $(cat "$T/a2")"
i=0
while [ "$(node_state 5)" != stopped ] && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
[ "$(node_state 5)" = stopped ] || fail "node 5 did not stop: $(node_state 5)"
printf '[5] 5 start\n' | ascii "$WHERE" > "$T/a3"
printf '[5] OK\r\n' | cmp -s - "$T/a3" || fail "start: $(cat "$T/a3")"
i=0
while [ "$(node_state 5)" != operational ] && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
[ "$(node_state 5)" = operational ] || fail "node 5 did not start: $(node_state 5)"
pass "NMT stop and start: node 5 stopped, then operational again"

printf '[6] 5 r 0x6543 0 u8\n[7] 5 jump\nno sequence\n' | ascii "$WHERE" > "$T/a4"
grep -q '^\[6\] ERROR:0x06020000 #' "$T/a4" || fail "SDO abort: $(cat "$T/a4")"
grep -q '^\[7\] ERROR:100 #Request not supported\.' "$T/a4" || fail "unknown command: $(cat "$T/a4")"
grep -q '^\[7\] ERROR:101 #Syntax error\.' "$T/a4" || fail "no sequence: $(cat "$T/a4")"
pass "errors: $(tr -d '\r' < "$T/a4" | tr '\n' '|')"

# Issue 28 items 6 and 7: no tokens and a loopback port, so admin as REST is:
# cocomm's reset node works; lss_store with nothing selected is ERROR:102 at once.
printf '[8] 5 reset node\n[9] lss_store\n' | ascii "$WHERE" > "$T/a5"
printf '[8] OK\r\n[9] ERROR:102 #Request not processed due to internal state.\r\n' | cmp -s - "$T/a5" ||
  fail "reset node / lss_store: $(cat "$T/a5")"
wait_for "$GW_LOG" "node 5 boot-up" 20
pass "default role admin: reset node OK, lss_store with nothing selected ERROR:102"
stop_gateway

# With tokens, the default is operator and a refusal says which role and key.
HASH=$(printf 'secret' | sha256sum | cut -d' ' -f1)
printf 'http:\n  tokens:\n    - {name: t, role: admin, sha256: %s}\n' "$HASH" > "$T/tokens.yaml"
start_gateway --config "$T/tokens.yaml" --demo --http 127.0.0.1:0 --ascii 127.0.0.1:0
wait_for "$GW_LOG" "clients act as operator\)"
WHERE=$(sed -n 's/.*CiA 309-3 ASCII on \(127\.0\.0\.1:[0-9]*\) .*/\1/p' "$GW_LOG" | head -1)
printf '[1] 5 reset node\n' | ascii "$WHERE" > "$T/a6"
grep -q '^\[1\] ERROR:100 #Request not supported\. role operator may not do this (needs admin); ascii\.role' "$T/a6" ||
  fail "refusal by role: $(cat "$T/a6")"
pass "with tokens: operator, refusal: $(tr -d '\r' < "$T/a6")"
stop_gateway

# ---- 3: a unix socket ---------------------------------------------------------------
SOCK=$T/co_command.sock
start_gateway --demo --http 127.0.0.1:0 --ascii "unix:$SOCK"
wait_for "$GW_LOG" "CiA 309-3 ASCII on unix:$SOCK \(unix socket, mode 0660"
[ -S "$SOCK" ] || fail "no socket at $SOCK"
[ "$(stat -c %a "$SOCK")" = 660 ] || fail "mode $(stat -c %a "$SOCK"), not 660"
wait_for "$GW_LOG" "node 5 operational" 20
printf '[1] 5 r 0x1018 1 x32\n' | ascii "unix:$SOCK" > "$T/u1"
printf '[1] 0x000005A1\r\n' | cmp -s - "$T/u1" || fail "over the unix socket: $(cat "$T/u1")"
stop_gateway
[ ! -e "$SOCK" ] || fail "socket left behind after a clean stop"
pass "unix socket: mode 660, answers, removed at stop"

# ---- 4: off loopback needs ascii.allow-remote --------------------------------------
RC=0
timeout 20 "$GATEWAY" --demo --http 127.0.0.1:0 --ascii 0.0.0.0:0 > "$T/out" 2> "$T/err" || RC=$?
[ "$RC" -eq 2 ] || fail "--ascii 0.0.0.0:0: exit $RC (expected 2): $(cat "$T/err")"
[ "$(wc -l < "$T/err")" -eq 1 ] || fail "expected one line on stderr: $(cat "$T/err")"
grep -q "ascii.allow-remote: true" "$T/err" || fail "the error does not say how: $(cat "$T/err")"
pass "off loopback refused: $(cat "$T/err")"
