#!/usr/bin/env bash
# The README's second command: installs what is missing, builds, and runs
# every test: unit tests, system tests over real SocketCAN inside user-mode
# Linux, a benchmark smoke run, then the unit tests again under ASan/UBSan,
# then the libFuzzer targets for a fixed number of inputs each.
set -euo pipefail
cd "$(dirname "$0")/.."
./deploy/install-deps.sh
jobs=$(nproc)

echo "== build (RelWithDebInfo, warnings are errors)"
cmake --preset ci
cmake --build --preset ci -j "$jobs"
echo "== tests: unit, system (UML + vcan), benchmark smoke"
ctest --preset ci -j "$jobs"

echo "== build (ASan + UBSan)"
cmake --preset asan
cmake --build --preset asan -j "$jobs"
echo "== tests: unit under ASan + UBSan"
ctest --preset asan -j "$jobs"

echo "== build (clang, libFuzzer, ASan + UBSan)"
cmake --preset fuzz
cmake --build --preset fuzz -j "$jobs"
echo "== fuzz: EDS reader, SDO server, SDO client, NMT/EMCY/PDO decoding, MQTT codec, REST/WebSocket request decoding, Sparkplug commands, ASCII lines; a fixed number of inputs each"
ctest --preset fuzz -j "$jobs"
