#!/bin/bash
# bench_graph.sh [BUILD_DIR] [--lengths "100 300 600"] [--sigma 0.5]: the pose graph with GNSS
# fixes against the frame-to-frame trajectory (docs/graph.md), on simulated cloud loops of each
# length (2 m a frame at 1 Hz, a 40 m turn radius, dead reckoning 5 % short in scale), fixes
# every 10 m of σ `--sigma` with 5 % multipath jumps of 10 m. One row per length: ATE
# (SE(3)-aligned) and final position error of dead reckoning, frame to frame and the graph, the
# fixes used and rejected, and the solve's time. 20 cm DEM cells (the table is about poses).
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

printf "| length | dead reckoning ATE / final | frame to frame ATE / final | graph ATE / final | fixes used / rejected | solve |\n"
printf "| ---: | ---: | ---: | ---: | ---: | ---: |\n"
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
    --set dem.cell_size_m=0.2 >/dev/null 2>&1
  "$R" replay "$seq" --out "$W/out_$L" --set dem.cell_size_m=0.2 --set octomap.enabled=false \
    >"$W/summary_$L.json" 2>/dev/null
  /usr/bin/python3 - "$W/summary_$L.json" "$L" \
    "$(final_error "$seq/odometry.tum" "$seq/groundtruth.tum")" \
    "$(final_error "$W/out_$L/trajectory_f2f.tum" "$seq/groundtruth.tum")" \
    "$(final_error "$W/out_$L/trajectory.tum" "$seq/groundtruth.tum")" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
m, g = s["metrics"], s["graph"]
ate = lambda k: m[k]["ate_rmse_m"]
print(f"| {sys.argv[2]} m | {ate('odometry'):.3f} / {sys.argv[3]} m | "
      f"{ate('frame_to_frame'):.3f} / {sys.argv[4]} m | {ate('registered'):.3f} / {sys.argv[5]} m | "
      f"{g['gnss_used']} / {g['gnss_rejected']} | {g['solve_ms']:.0f} ms |")
PY
done
