#!/usr/bin/env bash
# The main job on bundled and simulated data: simulate a small rover traverse (30 stereo frames
# with dead reckoning, ground truth and the true terrain), replay it through the mapper, and
# judge the DEM against the true terrain. Then a real scan pair through `rovermap register`.
set -euo pipefail
bin=${1:?usage: demo.sh ROVERMAP_BINARY OUT_DIR}
out=${2:?usage: demo.sh ROVERMAP_BINARY OUT_DIR}
data="$(dirname "$0")/../datasets"
mkdir -p "$out"

echo "== simulate a traverse: $out/sim"
"$bin" simulate --out "$out/sim" --force > "$out/simulate.json"

echo "== replay it: $out/replay"
"$bin" replay "$out/sim" --out "$out/replay" --force > "$out/replay.json" 2> "$out/replay.log"
grep -v 'replay: frame ' "$out/replay.log" || true
"$bin" eval --dem "$out/replay/dem.tif" --reference "$out/sim/terrain.tif" \
  --plot "$out/replay" > "$out/replay/dem_vs_terrain.json"
echo "   DEM against the true terrain (json: $out/replay/dem_vs_terrain.json):"
grep -E '"(rmse_m|bias_m|p95_abs_m|coverage|within_2sigma)"' "$out/replay/dem_vs_terrain.json" |
  tr -d ' ,' | sed 's/^/     /'
echo "   (coverage: the fraction of the whole simulated terrain the traverse mapped; within_2sigma:"
echo "    the cells whose error lies within twice the DEM's stated sigma, about 0.95 if it is right)"
echo "   pictures: $out/replay/dem.png $out/replay/drift.png $out/replay/dem_error.png $out/replay/terrain.png"

# A real scan pair: Stanford bunny bun045 -> bun000, started 10° and 5 mm off the reference
# alignment (datasets/stanford_bunny/gt_pairs.txt: rotation vector (-0.011134 0.598152
# 0.007827) rad, translation (-0.052021 -0.000384 -0.010922) m).
echo "== register a real scan pair (Stanford bunny bun045 -> bun000, started 10 deg / 5 mm off)"
init="-0.007382 0.689405 0.158762 -0.047939 -0.002425 -0.008881"
result="$out/register_bun045_bun000.json"
"$bin" register "$data/stanford_bunny/bun045.ply" "$data/stanford_bunny/bun000.ply" \
  --init "$init" --preview "$out/register_bun045_bun000.png" > "$result.tmp"
mv "$result.tmp" "$result"
grep -E '^  "(status|iterations|rms|time_ms)"' "$result" | tr -d ' ,' | sed 's/^/     /'
echo "   full result: $result; picture: $out/register_bun045_bun000.png"
