#!/usr/bin/env bash
# The README's second command: installs what is missing, builds, and runs
# every test: unit tests, system tests over real SocketCAN inside user-mode
# Linux, host and browser tests, a benchmark smoke run; then the unit tests
# again under ASan/UBSan (Clang), then the libFuzzer targets for a fixed
# number of inputs each. Each phase prints its wall time, and a table of all
# of them closes the run (also when a phase fails); CONTRIBUTING.md has the
# table of a fresh machine.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)

phases=()
run_start=$(date +%s)
mmss() { printf '%dm%02ds' $(($1 / 60)) $(($1 % 60)); }
summary() {
  local rc=$? p name secs status
  [ ${#phases[@]} -gt 0 ] || exit $rc
  echo
  echo "== phases (wall time, $jobs cores)"
  for p in "${phases[@]}"; do
    IFS='|' read -r name secs status <<<"$p"
    printf '  %-66s %8s  %s\n' "$name" "$(mmss "$secs")" "$status"
  done
  printf '  %-66s %8s\n' "total" "$(mmss $(($(date +%s) - run_start)))"
  exit $rc
}
trap summary EXIT

# phase NAME COMMAND...: runs COMMAND and records its wall time.
phase() {
  local name=$1 start rc=0 secs
  shift
  echo "== $name"
  start=$(date +%s)
  "$@" || rc=$?
  secs=$(($(date +%s) - start))
  phases+=("$name|$secs|$([ $rc -eq 0 ] && echo ok || echo "FAILED ($rc)")")
  echo "== $name: $(mmss $secs)$([ $rc -eq 0 ] || echo ", FAILED ($rc)")"
  return $rc
}

# The slowest tests of a run, from CTest's own record of it: where the time goes.
slowest() {
  local costs=$1/Testing/Temporary/CTestCostData.txt
  [ -f "$costs" ] || return 0
  echo "   slowest tests (s):"
  awk 'NF == 3 { printf "   %8.1f  %s\n", $3, $1 }' "$costs" | sort -rn | head -n 8
}
ctest_and_slowest() {
  local dir=$1 rc=0
  shift
  ctest "$@" || rc=$?
  slowest "$dir"
  return $rc
}
build() { cmake --preset "$1" && cmake --build --preset "$1" -j "$jobs"; }
# Clang's allocations in transparent huge pages where the kernel gives them
# on request (THP "madvise", Debian's default): Clang compiles ~12 % faster
# (fewer page faults, fewer TLB misses); GCC got slower with it, so the GCC
# build goes without.
clang_build() { GLIBC_TUNABLES=glibc.malloc.hugetlb=1 build "$1"; }

phase "packages (deploy/install-deps.sh)" ./deploy/install-deps.sh
phase "build: GCC RelWithDebInfo -g1, warnings are errors (build/)" build ci
phase "tests: unit, system (UML + vcan), host, browser, bench smoke" ctest_and_slowest build --preset ci -j "$jobs"
phase "build: Clang ASan + UBSan, the unit tests only (build-asan/)" clang_build asan
phase "tests: unit under ASan + UBSan" ctest_and_slowest build-asan --preset asan -j "$jobs"
phase "build: Clang libFuzzer + ASan + UBSan, fuzz targets (build-fuzz/)" clang_build fuzz
# EDS reader, SDO server, SDO client, NMT/EMCY/PDO decoding, MQTT codec,
# REST/WebSocket request decoding, Sparkplug commands, ASCII lines.
phase "fuzz: each target a fixed number of inputs" ctest --preset fuzz -j "$jobs"
