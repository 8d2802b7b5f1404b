#!/usr/bin/env bash
# SDO block and segmented transfer throughput over a real SocketCAN bus
# (vcan0), between two processes: sdo_tool serve and sdo_tool upload/download.
# This machine's kernel may have no CAN, so the bus runs inside user-mode
# Linux, where every syscall is far slower than on a real kernel: the numbers
# are a lower bound. Not a test; prints MB/s.
#   bench/sdo_vcan.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
export BUILD_DIR=$(realpath "${1:-build}")
exec tests/system/uml-run.sh --timeout 600 -- bash -c '
SDO=$BUILD_DIR/tests/sdo_tool
$SDO serve vcan0 5 > $TMPDIR/server.out 2>&1 &
sleep 1
head -c 1048576 /dev/urandom > $TMPDIR/data.bin
run() {
  local label=$1; shift
  local t0=$(date +%s.%N)
  "$@" > $TMPDIR/out || { cat $TMPDIR/out; exit 1; }
  local t1=$(date +%s.%N)
  python3 -c "import sys; s=float(sys.argv[2])-float(sys.argv[1]); print(f\"%-34s %6.2f s  %6.3f MB/s\" % (sys.argv[3], s, 1.048576/s))" $t0 $t1 "$label"
}
for i in 1 2 3; do
  run "block download 1 MiB (run $i)" $SDO download vcan0 5 0x2000 0 --file $TMPDIR/data.bin --mode block
  run "block upload 1 MiB (run $i)" $SDO upload vcan0 5 0x2000 0 --mode block --out $TMPDIR/up.bin
done
run "segmented upload 1 MiB" $SDO upload vcan0 5 0x2000 0 --mode segmented --out $TMPDIR/up.bin
kill $!
'
