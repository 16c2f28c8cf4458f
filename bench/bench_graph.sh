#!/bin/bash
# bench_graph.sh [BUILD_DIR] [--lengths "100 300 600"] [--sigma 0.5]: the pose graph with each
# absolute source (docs/graph.md) against the frame-to-frame trajectory, on simulated cloud
# loops of each length on cratered ground (2 m a frame at 1 Hz, a 40 m turn radius, dead
# reckoning 5 % short in scale): GNSS fixes every 10 m of σ `--sigma` with 5 % multipath jumps
# of 10 m; a 1 m/post reference DEM of σ 0.2 m misplaced 0.5 m east, matched every 20 m; the
# loop's revisits (laps after the first, from 300 m); all three.
# One row per length and source: ATE (SE(3)-aligned) and final position error, the factors used
# and rejected (refused), the frames within 2σ of the covariance the run states (the chain's,
# or the graph's marginals), and the solve's time (with the covariance). 20 cm DEM cells (the
# table is about poses).
set -euo pipefail

BUILD=build
LENGTHS="100 300 600"
SIGMA=0.5
while [[ $# -gt 0 ]]; do
  case "$1" in
    --lengths) LENGTHS=$2; shift 2 ;;
    --sigma) SIGMA=$2; shift 2 ;;
    *) BUILD=$1; shift ;;
  esac
done
R="$BUILD/apps/rovermap"
[[ -x "$R" ]] || { echo "bench_graph: no $R (build first)" >&2; exit 2; }
W=$(mktemp -d /tmp/rovermap_bench_graph.XXXXXX)
trap 'rm -rf "$W"' EXIT

# final_error TUM TRUTH: distance between the last poses.
final_error() {
  paste -d' ' <(grep -v '^#' "$1" | tail -1) <(grep -v '^#' "$2" | tail -1) |
    awk '{printf "%.3f", sqrt(($2-$10)^2 + ($3-$11)^2 + ($4-$12)^2)}'
}

printf "| length | source | ATE / final | used / rejected (refused) | within 2σ | solve |\n"
printf "| ---: | --- | ---: | ---: | ---: | ---: |\n"
for L in $LENGTHS; do
  frames=$((L / 2))
  seq="$W/seq_$L"
  # The loop's size follows the length so the terrain stays small: a 40 m radius (251 m a lap).
  size=$(( L > 250 ? 400 : 240 ))
  "$R" simulate --out "$seq" --set sim.sensor=cloud --set sim.frames=$frames \
    --set sim.frame_rate_hz=1 --set sim.speed_m_s=2 --set sim.terrain_size_m=$size \
    --set sim.terrain_cell_m=0.2 --set sim.turn_radius_m=40 --set sim.path=loop \
    --set sim.start_y_m=-40 --set sim.odom_scale_error=0.05 --set sim.gnss_every_frames=5 \
    --set sim.gnss_sigma_m="$SIGMA" --set sim.gnss_outlier_fraction=0.05 \
    --set sim.craters=$(( size * size / 200 )) --set sim.crater_max_radius_m=10 \
    --set sim.reference_post_m=1 --set dem.cell_size_m=0.2 >/dev/null 2>&1
  common=(--set dem.cell_size_m=0.2 --set octomap.enabled=false)
  alone=(--set revisit.enabled=false)  # one source at a time
  ref=(--reference-dem "$seq/reference_dem.tif")
  no_gnss=(--set graph.min_gnss_fixes=1000000)  # too few fixes: gnss.csv left out
  "$R" replay "$seq" --out "$W/f2f_$L" "${common[@]}" --set graph.enabled=false \
    >"$W/s_f2f_$L.json" 2>/dev/null
  "$R" replay "$seq" --out "$W/gnss_$L" "${common[@]}" "${alone[@]}" >"$W/s_gnss_$L.json" 2>/dev/null
  "$R" replay "$seq" --out "$W/ref_$L" "${common[@]}" "${alone[@]}" "${ref[@]}" "${no_gnss[@]}" \
    >"$W/s_ref_$L.json" 2>/dev/null
  "$R" replay "$seq" --out "$W/revisit_$L" "${common[@]}" "${no_gnss[@]}" >"$W/s_revisit_$L.json" \
    2>/dev/null
  "$R" replay "$seq" --out "$W/all_$L" "${common[@]}" "${ref[@]}" >"$W/s_all_$L.json" 2>/dev/null
  for source in odometry f2f gnss ref revisit all; do
    case $source in
      odometry) out=f2f; tum="$seq/odometry.tum" ;;
      *) out=$source; tum="$W/${source}_$L/trajectory.tum" ;;
    esac
    /usr/bin/python3 - "$W/s_${out}_$L.json" "$L" "$source" "$(final_error "$tum" "$seq/groundtruth.tum")" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
L, source, final = sys.argv[2], sys.argv[3], sys.argv[4]
m = s["metrics"]
name = {"odometry": "dead reckoning", "f2f": "frame to frame", "gnss": "GNSS",
        "ref": "reference DEM", "revisit": "revisits", "all": "all three"}[source]
ate = m["odometry" if source == "odometry" else "registered"]["ate_rmse_m"]
g = s.get("graph")
if source in ("odometry", "f2f") or g is None:
    used, solve = "", ""
else:
    parts = []
    if source in ("gnss", "all"):
        parts.append(f"{g['gnss_used']} / {g['gnss_rejected']} fixes")
    if source in ("ref", "all"):
        parts.append(f"{g['reference_used']} / {g['reference_rejected']} ({g['reference_refused']}) matches")
    if source in ("revisit", "all"):
        parts.append(f"{g['revisits_used']} / {g['revisits_rejected']} ({g['revisits_refused']}) revisits")
    used, solve = ", ".join(parts), f"{g['solve_ms']:.0f} ms"
u = s.get("pose_uncertainty")
within = "" if source == "odometry" or u is None else f"{u['within_2sigma']:.3f}"
print(f"| {L} m | {name} | {ate:.3f} / {final} m | {used} | {within} | {solve} |")
PY
  done
done
