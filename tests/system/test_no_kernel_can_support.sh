#!/bin/sh
# uml-run: --no-can
# On a kernel without SocketCAN the gateway says so in one line, exit code 3.
. "$(dirname "$0")/lib.sh"

rc=0
"$GATEWAY" --can vcan0 2> "$T/err" || rc=$?
[ "$rc" -eq 3 ] || fail "exited $rc, expected 3"
[ "$(wc -l < "$T/err")" -eq 1 ] || fail "stderr has $(wc -l < "$T/err") lines: $(cat "$T/err")"
grep -q "this kernel has no SocketCAN support" "$T/err" || fail "said: $(cat "$T/err")"
pass "$(cat "$T/err")"
