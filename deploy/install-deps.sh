#!/usr/bin/env bash
# Installs every Debian 12 package the build, the demo and the tests need.
# Idempotent and non-interactive: packages already present are skipped, and
# `apt-get update` runs only when something is missing.
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build ccache pkg-config git clang libclang-rt-14-dev
  lld  # links the Clang builds (sanitizers, fuzzing) ~4x faster than ld.bfd
  # libraries (Boost 1.81 from Debian's versioned packages; never libboost-all-dev, which is 1.74)
  libboost1.81-dev libboost-json1.81-dev libboost-url1.81-dev
  libpaho-mqtt-dev libpaho-mqttpp-dev  # the MQTT tests' reference client only
  libprotobuf-dev protobuf-compiler
  libgtest-dev libgmock-dev libbenchmark-dev
  libyaml-cpp-dev libssl-dev openssl
  # broker and CAN tools for tests and the demo
  mosquitto mosquitto-clients can-utils iproute2 python3 python3-can python3-paho-mqtt
  rabbitmq-server  # a second broker, MQTT 3.1.1 only (tests/host/test_mqtt_brokers.sh)
  python3-protobuf  # tests/tools/sparkplug_check.py decodes Sparkplug payloads with code protoc generates
  # SocketCAN without host kernel support: user-mode Linux ships vcan & co.
  user-mode-linux kmod
  # dashboard browser test (tests/browser): Debian's headless Chromium, driven by playwright-core from npm
  chromium chromium-driver
  # the Debian package's test (tests/host/test_deb_package.sh) checks it with lintian
  lintian
)
# Node.js and npm only where there are none: a machine with another Node.js
# build (NodeSource's nodejs bundles npm) must not get Debian's npm, which
# conflicts with it. playwright-core needs Node.js 20 or newer.
command -v node >/dev/null 2>&1 || PACKAGES+=(nodejs)
command -v npm >/dev/null 2>&1 || PACKAGES+=(npm)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed"; then
    missing+=("$p")
  fi
done

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
else
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
  # The mosquitto package starts a system broker on :1883; tests run their own
  # brokers on private ports, so the system one is left as the admin set it.
fi

# The browser test's npm packages, exactly as locked (playwright-core only; it
# drives /usr/bin/chromium and never downloads a browser). Skipped when
# node_modules was installed from the current lock, so repeated runs stay offline.
browser_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/tests/browser"
if [ -f "$browser_dir/package-lock.json" ]; then
  installed="$browser_dir/node_modules/.package-lock.json"
  if [ ! -f "$installed" ] || [ "$browser_dir/package-lock.json" -nt "$installed" ]; then
    echo "install-deps: npm ci in tests/browser"
    (cd "$browser_dir" && PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund)
  fi
fi
