#!/bin/bash
# bench_long.sh [BUILD_DIR] [--frames N] [--exact-poses]: a long cloud traverse (default 2000
# frames, a loop of 6 m radius, about 250 frames a lap, over a 60 m terrain) through `rovermap
# replay` and through `rovermap serve` (every frame already in the inbox, so the daemon takes
# them as fast as it can; its journal, snapshots and publications included). Per run: the wall
# time per frame and the resident memory over the first and the last tenth of the frames,
# sampled from /proc every 0.25 s. Flat means neither grows with the sequence's length.
# --exact-poses: odometry without error and every increment taken from it
# (mapper.min_inlier_ratio=1), so that each lap maps the very ground of the first: what the
# maps hold when the trajectory does not drift (no registration runs, so the time per frame
# is not the mapper's).
set -euo pipefail

BUILD=build
N=2000
SIM_SETS=()
RUN_SETS=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --frames) N=$2; shift 2 ;;
    --exact-poses)
      for k in odom_scale_error odom_slip_mean odom_slip_sigma heading_bias_deg_s \
        heading_random_walk_deg_rt_s; do SIM_SETS+=(--set "sim.$k=0"); done
      RUN_SETS=(--set mapper.min_inlier_ratio=1)
      shift ;;
    *) BUILD=$1; shift ;;
  esac
done
R="$BUILD/apps/rovermap"
[[ -x "$R" ]] || { echo "bench_long: no $R (build first)" >&2; exit 2; }
W=$(mktemp -d /tmp/rovermap_bench_long.XXXXXX)
trap 'rm -rf "$W"' EXIT

now() { date +%s.%N; }

# sample PID LOG PATTERN OUT: "time frames_done rss_mb peak_rss_mb" until PID ends.
sample() {
  local pid=$1 log=$2 pattern=$3 out=$4
  while kill -0 "$pid" 2>/dev/null; do
    local rss hwm
    rss=$(awk '/^VmRSS/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
    hwm=$(awk '/^VmHWM/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
    [[ -n "$rss" ]] && echo "$(now) $(grep -c "$pattern" "$log" || true) $((rss / 1024)) $((hwm / 1024))" >>"$out"
    sleep 0.25
  done
}

# report NAME SAMPLES: per-frame wall time and memory over the first and the last tenth.
report() {
  awk -v n="$N" -v name="$1" '
    { t[NR] = $1; f[NR] = $2; rss[NR] = $3; hwm[NR] = $4 }
    END {
      a = n / 10; b = 2 * n / 10; c = n - n / 10
      for (i = 1; i <= NR; ++i) {
        if (!ta && f[i] >= 1) ta = i
        if (!tb && f[i] >= a) tb = i
        if (!tc && f[i] >= c) tc = i
        if (!td && f[i] >= n) td = i
      }
      if (!td) td = NR
      printf "%-8s %12.1f %12.1f %14d %14d %14d\n", name,
        1000 * (t[tb] - t[ta]) / (f[tb] - f[ta]), 1000 * (t[td] - t[tc]) / (f[td] - f[tc]),
        rss[tb], rss[td], hwm[td]
    }' "$2"
}

echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
"$R" simulate --out "$W/seq" --set sim.sensor=cloud --set sim.cloud_stride_px=3 \
  --set sim.frames="$N" --set sim.path=loop --set sim.terrain_size_m=60 ${SIM_SETS[@]+"${SIM_SETS[@]}"} \
  >/dev/null 2>&1

# replay
"$R" replay "$W/seq" --out "$W/replay" ${RUN_SETS[@]+"${RUN_SETS[@]}"} >/dev/null 2>"$W/replay.log" &
pid=$!
sample $pid "$W/replay.log" "^replay: frame " "$W/replay.samples"
wait $pid

# serve: an inbox holding every frame, as a producer leaves them (docs/design.md §7)
mkdir -p "$W/inbox/frames"
cp "$W/seq/sequence.yaml" "$W/inbox/"
awk '!/^#/' "$W/seq/odometry.tum" | split -l 1 -d -a 6 - "$W/inbox/frames/x"
for f in "$W"/inbox/frames/x*; do mv "$f" "$W/inbox/frames/${f##*/x}.odom"; done
for f in "$W"/seq/frames/*.ply; do ln "$f" "$W/inbox/frames/"; done
"$R" serve --inbox "$W/inbox" --out "$W/serve" ${RUN_SETS[@]+"${RUN_SETS[@]}"} 2>"$W/serve.log" &
pid=$!
( until grep -q "\"next_frame\": $N," "$W/serve/status.json" 2>/dev/null; do sleep 0.25; done
  kill -TERM $pid ) &
sample $pid "$W/serve.log" "^serve: frame " "$W/serve.samples"
wait $pid

printf '\n%d frames, sim cloud loop   ms per frame (wall)        resident memory [MB]\n' "$N"
printf '%-8s %12s %12s %14s %14s %14s\n' "command" "first 10 %" "last 10 %" "at 10 %" "at the end" "peak"
report replay "$W/replay.samples"
report serve "$W/serve.samples"
# What serve adds every 10 frames, at 10 % and at the end (awk, not head: under pipefail
# head's early exit would fail the pipe).
writes() { awk -v k="$1" '$0 ~ "after frame " k "," {sub(/.*after /, ""); print}' "$W/serve.log"; }
echo "serve, $(writes $((N / 10 - 1)))"
echo "serve, $(writes $((N - 1)))"
# The terrain layers of the last publication: computed only in the tiles that changed since
# the one before (docs/terrain.md).
terrain_line() { tr -d ' \n' <"$1" | grep -o '"terrain":{[^}]*}' | grep -o '"\(compute_ms\|tiles\|tiles_computed\|time_ms\)":[0-9.]*' | tr '\n' ' '; }
echo "terrain at the end: serve $(terrain_line "$W/serve/summary.json"); replay $(terrain_line "$W/replay/summary.json")"
echo "maps at the end (replay): $(grep -o '"cells": [0-9]*' "$W/replay/summary.json"), OctoMap $(grep -o '"leaves": [0-9]*' "$W/replay/summary.json")"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
