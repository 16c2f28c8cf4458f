#!/usr/bin/env bash
# CTest smoke test of bench_register's harness (not a timing): one timed run of every method
# on the synthetic terrain pair, each in its own worker process, must end, exit 0 and print a
# row per rovermap method with the defaults' known accuracy; a bad option must exit 2.
#   bash bench/smoke_register.sh PATH/TO/bench_register
set -euo pipefail
exe=$1
out=$(mktemp)
trap 'rm -f "$out"' EXIT

# timeout: a worker whose pipes stayed open used to hang the parent in waitpid.
timeout 300 "$exe" --runs 1 --pairs terrain --pause-ms 0 >"$out"
grep -q "each method in its own process" "$out"
for method in "rovermap point-to-plane (default)" "rovermap fast preset" \
              "rovermap point-to-point (paper)"; do
  grep -q "^| terrain *| $method *|" "$out" || { echo "no row for '$method'" >&2; cat "$out" >&2; exit 1; }
done
# The defaults on the terrain with 15 % outliers: 0.011 deg, 0.54 mm (bench/README.md); a
# worker that returned garbage would not give these.
row=$(grep "^| terrain *| rovermap point-to-plane (default)" "$out")
rot=$(echo "$row" | awk -F'|' '{gsub(/[ *]/, "", $6); print $6}')
trans=$(echo "$row" | awk -F'|' '{gsub(/[ *]/, "", $7); print $7}')
awk -v r="$rot" -v t="$trans" 'BEGIN { exit !(r < 0.05 && t < 2.0) }' ||
  { echo "default terrain error $rot deg / $trans mm, expected < 0.05 deg / 2 mm" >&2; exit 1; }

set +e
"$exe" --runs 0 >/dev/null 2>&1
status=$?
set -e
[[ $status -eq 2 ]] || { echo "--runs 0 exited $status, expected 2" >&2; exit 1; }
echo "bench_register smoke: ok (default terrain $rot deg, $trans mm)"
