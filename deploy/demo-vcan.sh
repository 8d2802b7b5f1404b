#!/usr/bin/env bash
# The gateway on a real (virtual) SocketCAN bus: installs what is missing,
# builds, and shows the gateway at work with two simulated devices. This machine's kernel need not have
# CAN support: the bus runs inside user-mode Linux with a vcan interface.
#   deploy/demo-vcan.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
./deploy/install-deps.sh
cmake --preset default >/dev/null
cmake --build --preset default --target canopen-gateway canopen-sim
export BUILD_DIR=$PWD/build SOURCE_DIR=$PWD CANOPEN_DEMO_SECONDS=${1:-20}
echo "demo: booting user-mode Linux with vcan0 ..."
exec tests/system/uml-run.sh --live --timeout $((CANOPEN_DEMO_SECONDS + 60)) -- deploy/demo-inside-uml.sh
