#!/usr/bin/env bash
# CTest smoke test of bench_cold's harness (not a timing): one run of `rovermap register` per
# bunny pair, each in a process of its own, must exit 0 and print each pair's row with the
# defaults' known accuracy (bench/README.md); a bad option must exit 2.
#   bash bench/smoke_cold.sh PATH/TO/bench_cold
set -euo pipefail
exe=$1
out=$(mktemp)
trap 'rm -f "$out"' EXIT

timeout 120 "$exe" --runs 1 --pause-ms 0 >"$out" 2>/dev/null
grep -q "one process each" "$out"
for pair in bun045 bun315; do
  row=$(grep "^| $pair->bun000 | rovermap register (defaults) |" "$out") ||
    { echo "no rovermap row for $pair" >&2; cat "$out" >&2; exit 1; }
  rot=$(echo "$row" | awk -F'|' '{gsub(/ /, "", $7); print $7}')
  trans=$(echo "$row" | awk -F'|' '{gsub(/ /, "", $8); print $8}')
  # The defaults land within 0.07 deg and 0.11 mm of Stanford's alignment from 10 deg off.
  awk -v r="$rot" -v t="$trans" 'BEGIN { exit !(r < 0.2 && t < 0.5) }' ||
    { echo "$pair: error $rot deg / $trans mm, expected < 0.2 deg / 0.5 mm" >&2; exit 1; }
done

set +e
"$exe" --runs 0 >/dev/null 2>&1
status=$?
set -e
[[ $status -eq 2 ]] || { echo "--runs 0 exited $status, expected 2" >&2; exit 1; }
echo "bench_cold smoke: ok"
