#!/usr/bin/env bash
# Installs every Debian 12 package the build, the demo and the tests need.
# Idempotent and non-interactive: packages already present are skipped, and
# `apt-get update` runs only when something is missing.
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build ccache pkg-config git clang libclang-rt-14-dev
  # libraries (Boost 1.81 from Debian's versioned packages; never libboost-all-dev, which is 1.74)
  libboost1.81-dev libboost-json1.81-dev libboost-url1.81-dev
  libpaho-mqtt-dev libpaho-mqttpp-dev  # the MQTT tests' reference client only
  libprotobuf-dev protobuf-compiler
  libgtest-dev libgmock-dev libbenchmark-dev
  libyaml-cpp-dev libssl-dev
  # broker and CAN tools for tests and the demo
  mosquitto mosquitto-clients can-utils iproute2 python3 python3-can python3-paho-mqtt
  # SocketCAN without host kernel support: user-mode Linux ships vcan & co.
  user-mode-linux kmod
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
# The mosquitto package starts a system broker on :1883; tests run their own
# brokers on private ports, so the system one is left as the admin set it.
