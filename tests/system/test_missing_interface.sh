#!/bin/sh
# A missing or non-CAN interface gives one clear line on stderr and exit code 3.
. "$(dirname "$0")/lib.sh"

check() {
  local expect=$1; shift
  rc=0
  "$GATEWAY" "$@" > "$T/out" 2> "$T/err" || rc=$?
  [ "$rc" -eq 3 ] || fail "'$*' exited $rc, expected 3"
  [ "$(wc -l < "$T/err")" -eq 1 ] || fail "'$*' printed $(wc -l < "$T/err") lines on stderr: $(cat "$T/err")"
  grep -qF "$expect" "$T/err" || fail "'$*' said: $(cat "$T/err")"
  [ ! -s "$T/out" ] || fail "'$*' printed on stdout: $(cat "$T/out")"
  echo "ok: $(cat "$T/err")"
}
check "canopen-gateway: error: CAN interface 'vcan9' does not exist" --can vcan9
check "canopen-gateway: error: interface 'lo' is not a CAN interface" --can lo
check "canopen-gateway: error: CAN interface 'vcan7' does not exist" --can vcan0 --can vcan7
pass "missing and non-CAN interfaces rejected with one line"
