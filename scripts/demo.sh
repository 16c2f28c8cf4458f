#!/usr/bin/env bash
# The main job on bundled data. Until the mapper exists this is `rovermap register` on a real
# scan pair: Stanford bunny bun045 -> bun000, started 10° and 5 mm off the reference alignment.
set -euo pipefail
bin=${1:?usage: demo.sh ROVERMAP_BINARY OUT_DIR}
out=${2:?usage: demo.sh ROVERMAP_BINARY OUT_DIR}
data="$(dirname "$0")/../datasets/stanford_bunny"
mkdir -p "$out"

# Reference (datasets/stanford_bunny/gt_pairs.txt): rotation vector (-0.011134 0.598152
# 0.007827) rad, translation (-0.052021 -0.000384 -0.010922) m. Initial estimate: rotation
# turned 10° about (1,2,3), translation moved 5 mm.
init="-0.007382 0.689405 0.158762 -0.047939 -0.002425 -0.008881"
result="$out/register_bun045_bun000.json"
"$bin" register "$data/bun045.ply" "$data/bun000.ply" --init "$init" \
  --preview "$out/register_bun045_bun000.png" > "$result.tmp"
mv "$result.tmp" "$result"

python3 - "$result" <<'PY' 2>/dev/null || cat "$result"
import json, math, sys
r = json.load(open(sys.argv[1]))
ref_rv = (-0.011134, 0.598152, 0.007827); ref_t = (-0.052021, -0.000384, -0.010922)
def rot(rv):
    a = math.sqrt(sum(x * x for x in rv)); k = [x / a for x in rv]
    c, s, v = math.cos(a), math.sin(a), 1 - math.cos(a)
    return [[c + k[0]*k[0]*v, k[0]*k[1]*v - k[2]*s, k[0]*k[2]*v + k[1]*s],
            [k[1]*k[0]*v + k[2]*s, c + k[1]*k[1]*v, k[1]*k[2]*v - k[0]*s],
            [k[2]*k[0]*v - k[1]*s, k[2]*k[1]*v + k[0]*s, c + k[2]*k[2]*v]]
R = [row[:3] for row in r["matrix"][:3]]; Rr = rot(ref_rv)
tr = sum(R[i][j] * Rr[i][j] for i in range(3) for j in range(3))
err_deg = math.degrees(math.acos(max(-1.0, min(1.0, (tr - 1) / 2))))
err_mm = 1000 * math.dist(r["translation"], ref_t)
print(f"rovermap register bun045 -> bun000: {r['status']} after {r['iterations']} iterations, "
      f"{r['inliers']} inliers, rms {1000 * r['rms']:.3f} mm, {r['time_ms']:.0f} ms")
print(f"  error against the reference alignment: {err_deg:.3f} deg, {err_mm:.3f} mm "
      f"(started 10 deg / 5 mm off)")
PY
echo "  full result (JSON): $result"
echo "  picture of the alignment before and after: $out/register_bun045_bun000.png"

# A small synthetic rover traverse (stereo frames, dead reckoning, ground truth, true terrain),
# the input the mapper will consume.
"$bin" simulate --out "$out/sim" --force > /dev/null
echo "  simulated sequence (30 stereo frames, odometry.tum, groundtruth.tum, terrain.tif): $out/sim"
