#!/usr/bin/env bash
# The figures issue 14 compares before and after its refactor (bench/README.md,
# "Before and after issue 14"): PDO decode, event encode, CAN -> MQTT CPU per
# event, REST SDO added latency, and (where built) the 16-network benchmark.
# Raw outputs go to OUT_DIR, one file per measurement.
#   cmake --preset bench && cmake --build build-bench -j2 \
#     --target canopen_bench messages_bench mqtt_path_bench rest_bench many_networks_bench
#   bench/before_after.sh build-bench /tmp/bench-after
set -euo pipefail
BUILD=${1:?usage: before_after.sh BUILD_DIR OUT_DIR}
OUT=${2:?usage: before_after.sh BUILD_DIR OUT_DIR}
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
{
  date -u
  git -C "$HERE" rev-parse HEAD
  uptime
  lscpu | grep -E 'Model name|^CPU\(s\)|MHz' || true
  g++ --version | head -1
} > "$OUT/machine.txt"

agg=(--benchmark_repetitions=5 --benchmark_report_aggregates_only=true)
"$BUILD/bench/canopen_bench" --benchmark_filter=PdoDecode "${agg[@]}" > "$OUT/pdo_decode.txt"
"$BUILD/bench/messages_bench" "${agg[@]}" > "$OUT/event_encode.txt"
for i in 1 2 3; do
  "$HERE/mqtt_compare.sh" "$BUILD" 50000 0 > "$OUT/mqtt_qos0.$i.txt"
done
for i in 1 2 3; do
  "$HERE/mqtt_compare.sh" "$BUILD" 50000 1 > "$OUT/mqtt_qos1.$i.txt"
done
taskset -c 1 "$BUILD/bench/rest_bench" 20000 > "$OUT/rest_pinned.txt"
"$BUILD/bench/rest_bench" 20000 > "$OUT/rest_unpinned.txt"
if [[ -x "$BUILD/bench/many_networks_bench" ]]; then
  "$HERE/many_networks.sh" "$BUILD" 10 > "$OUT/many_networks.txt"
fi
uptime >> "$OUT/machine.txt"
grep -h -E 'mean|median' "$OUT/pdo_decode.txt" "$OUT/event_encode.txt" | grep -v stddev || true
grep -h 'CPU per event' "$OUT"/mqtt_qos*.txt || true
grep -h -E 'REST|direct|added|floor' "$OUT"/rest_*.txt || true
[[ -f "$OUT/many_networks.txt" ]] && tail -n 12 "$OUT/many_networks.txt"
exit 0
