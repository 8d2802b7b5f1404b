#!/bin/sh
# Controller error frames become bus-state changes: warning, passive,
# bus-off, restarted (back to error-active). vcan has no controller, so the
# error frames are injected with cansend (CAN_ERR_FLAG is bit 29 of the id).
. "$(dirname "$0")/lib.sh"

start_gateway --can vcan0
# CAN_ERR_CRTL (0x4) with data[1] = CAN_ERR_CRTL_TX_WARNING (0x08); CAN_ERR_CNT (0x200): tec 100, rec 5
cansend vcan0 20000204#0008000000006405
wait_for "$GW_LOG" "bus error-active -> error-warning \(error-frame, tec 100, rec 5\)"
# data[1] = CAN_ERR_CRTL_TX_PASSIVE (0x20)
cansend vcan0 20000204#0020000000008005
wait_for "$GW_LOG" "bus error-warning -> error-passive \(error-frame, tec 128"
# CAN_ERR_BUSOFF (0x40)
cansend vcan0 20000040#0000000000000000
wait_for "$GW_LOG" "bus error-passive -> bus-off \(error-frame"
# CAN_ERR_RESTARTED (0x100)
cansend vcan0 20000100#0000000000000000
wait_for "$GW_LOG" "bus bus-off -> error-active \(restarted"
stop_gateway
grep -q "error frames 4" "$GW_LOG" || fail "expected 4 error frames counted: $(grep 'vcan0: rx' "$GW_LOG")"
pass "warning, passive, bus-off and restart reported"
