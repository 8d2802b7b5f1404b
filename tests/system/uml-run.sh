#!/usr/bin/env bash
# Runs a command inside a user-mode Linux kernel that has SocketCAN and vcan,
# for system tests on machines whose own kernel has no CAN support.
#
#   uml-run.sh [--timeout SECS] [--vcan "vcan0 vcan1"] [--no-can] [--mem SIZE] [--live] -- COMMAND [ARGS...]
#
# --live streams COMMAND's output as it runs (through UML's console) instead
# of printing it at the end; for the demo, not for tests.
# The host filesystem is UML's root, so COMMAND sees the checkout, the build
# and the host's tools. COMMAND runs in the current directory with PATH, HOME,
# BUILD_DIR, SOURCE_DIR and every CANOPEN_* / TEST_* variable passed through.
# Its output is printed; the exit status is COMMAND's, 124 when the time limit
# ran out, 125 when UML could not run it. Each run has its own umid and state
# directory, so runs can go in parallel. Nothing is left behind.
set -euo pipefail

timeout_s=120
vcans="vcan0 vcan1"
load_can=1
mem=768M
live=0
while [ $# -gt 0 ]; do
  case "$1" in
    --timeout) timeout_s=$2; shift 2 ;;
    --vcan) vcans=$2; shift 2 ;;
    --no-can) load_can=0; shift ;;
    --mem) mem=$2; shift 2 ;;
    --live) live=1; shift ;;
    --) shift; break ;;
    *) echo "uml-run: unknown option $1" >&2; exit 125 ;;
  esac
done
[ $# -gt 0 ] || { echo "uml-run: no command" >&2; exit 125; }
command -v linux.uml >/dev/null || { echo "uml-run: linux.uml not found (apt-get install user-mode-linux)" >&2; exit 125; }

work=$(mktemp -d "${TMPDIR:-/tmp}/uml-run.XXXXXX")
umid="canopen-$(basename "$work" | tr -c 'a-zA-Z0-9\n' '-')"
cleanup() { rm -rf "$work"; }
trap cleanup EXIT

# Quote the command and the environment for the init script.
{
  printf 'export PATH=%q\n' "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
  printf 'export HOME=%q\n' "${HOME:-/root}"
  printf 'export TMPDIR=%q\n' "$work/tmp"
  for v in BUILD_DIR SOURCE_DIR $(compgen -e | grep -E '^(CANOPEN_|TEST_)' || true); do
    [ -n "${!v+x}" ] && printf 'export %s=%q\n' "$v" "${!v}"
  done
  printf 'cd %q\n' "$PWD"
  printf 'set --'; printf ' %q' "$@"; printf '\n'
} > "$work/env.sh"
mkdir -p "$work/tmp"

cat > "$work/init.sh" <<INIT
#!/bin/bash
# PID 1 inside UML (bash: env.sh uses its quoting for arbitrary arguments): set up the kernel, run the test, record its status, halt.
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t tmpfs tmpfs /run 2>/dev/null
mount -t tmpfs tmpfs /dev/shm 2>/dev/null
ip link set lo up
if [ $load_can = 1 ]; then
  M=/usr/lib/uml/modules/\$(uname -r)/kernel
  for m in net/can/can.ko net/can/can-raw.ko net/can/can-bcm.ko drivers/net/can/dev/can-dev.ko drivers/net/can/vcan.ko; do
    insmod \$M/\$m || echo "uml-run: insmod \$m failed"
  done
  for v in $vcans; do ip link add dev \$v type vcan && ip link set up \$v; done
fi
. $work/env.sh
if [ $live = 1 ]; then out=/dev/console; else out=$work/output; fi
"\$@" > \$out 2>&1 < /dev/null
echo \$? > $work/rc
sync
poweroff -f
INIT
chmod +x "$work/init.sh"

# Kernel options that only shorten the boot (~2 s of ~4 s on a loaded 2-core
# machine): no legacy BSD ptys (pty_init made 256 pairs) and no zswap pool.
boot_opts="pty.legacy_count=0 zswap.enabled=0"

set +e
if [ $live = 1 ]; then
  # Only the command's own lines reach the terminal; kernel messages are filtered.
  timeout --kill-after=10 "$timeout_s" linux.uml umid="$umid" uml_dir="$work" mem="$mem" quiet \
    root=/dev/root rootfstype=hostfs rw init="$work/init.sh" $boot_opts con=null con0=null,fd:1 \
    </dev/null 2>&1 | tee "$work/console" | grep --line-buffered -E '^(20[0-9][0-9]-|demo:|  )'
  uml_status=${PIPESTATUS[0]}
else
  timeout --kill-after=10 "$timeout_s" linux.uml umid="$umid" uml_dir="$work" mem="$mem" \
    root=/dev/root rootfstype=hostfs rw init="$work/init.sh" $boot_opts con=null con0=null,fd:1 \
    </dev/null >"$work/console" 2>&1
  uml_status=$?
fi
set -e

[ -f "$work/output" ] && cat "$work/output"
if [ -f "$work/rc" ]; then
  exit "$(cat "$work/rc")"
fi
if [ $uml_status -eq 124 ] || [ $uml_status -eq 137 ]; then
  echo "uml-run: time limit of ${timeout_s}s reached" >&2
  exit 124
fi
echo "uml-run: the test did not run to completion (UML status $uml_status); console:" >&2
tail -n 30 "$work/console" >&2
exit 125
