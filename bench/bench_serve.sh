#!/bin/bash
# bench_serve.sh [BUILD_DIR] [--runs N] [--long N] [--sequence DIR ...]: the daemon's overhead
# and its restart time.
#
# Table 1: frames per second of `rovermap replay` and of `rovermap serve` (every frame already in
# the inbox, so the daemon never waits; serve.publish_every 1 and 10 at that cadence whatever it
# costs, and serve's default cadence, serve.publish_share 0.05) on the default simulated
# stereo traverse, a cloud traverse and a 300 m cloud loop with GNSS fixes (gnss.csv in the
# inbox: serve solves the pose graph at each publication, replay once at the end and fuses its
# maps again), and on each --sequence given (a recorded one, e.g.
# datasets/kitti_stereo51), runs interleaved, medians. Serve's time runs from its
# start until summary.json covers the last frame (its publishing and checkpoints included).
# Table 2: the pose graph's share of serve's time: serve (publish_every 10) on the GNSS loop with
# the graph on (solved at each publication over its last serve.graph_window_frames) and off.
# Table 3: the restart time after 100 and N (default 500) frames of a cloud loop, killed with
# -9 in the middle of the snapshot at that frame, so that the last checkpoint_every (10) frames
# must be re-applied from the journal: the worst case; against replaying those frames.
set -euo pipefail

BUILD=build
RUNS=3
LONG=500
SEQUENCES=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --runs) RUNS=$2; shift 2 ;;
    --long) LONG=$2; shift 2 ;;
    --sequence) SEQUENCES+=("$(cd "$2" && pwd)"); shift 2 ;;
    *) BUILD=$1; shift ;;
  esac
done
R="$BUILD/apps/rovermap"
[[ -x "$R" ]] || { echo "bench_serve: no $R (build first)" >&2; exit 2; }
W=$(mktemp -d /tmp/rovermap_bench_serve.XXXXXX)
trap 'rm -rf "$W"' EXIT

now() { date +%s.%N; }
calc() { awk "BEGIN { print $1 }"; }  # awk is in every Debian; bc is not
median() { sort -g | awk '{v[NR]=$1} END {print (NR%2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }

# An inbox holding frames 0..N-1 of SEQ, as a producer leaves them (docs/design.md §7).
make_inbox() {
  local seq=$1 inbox=$2 n=$3
  rm -rf "$inbox"; mkdir -p "$inbox/frames"
  cp "$seq/sequence.yaml" "$inbox/"
  [[ -f "$seq/gnss.csv" ]] && cp "$seq/gnss.csv" "$inbox/"
  # awk reads to the end (head would leave grep a SIGPIPE, fatal under pipefail).
  awk -v n="$n" '!/^#/ && ++k <= n' "$seq/odometry.tum" | split -l 1 -d -a 6 - "$inbox/frames/x"
  for f in "$inbox"/frames/x*; do mv "$f" "$inbox/frames/${f##*/x}.odom"; done
  for ((k = 0; k < n; k++)); do
    s=$(printf %06d $k)
    for ext in left.png right.png ply; do
      [[ -f "$seq/frames/$s.$ext" ]] && { ln "$seq/frames/$s.$ext" "$inbox/frames/" 2>/dev/null ||
        cp "$seq/frames/$s.$ext" "$inbox/frames/"; }
    done
  done
  return 0
}

frames_of() { grep -vc '^#' "$1/odometry.tum"; }

replay_s() {
  local t0; t0=$(now)
  "$R" replay "$1" --out "$W/replay" --force >/dev/null 2>&1
  calc "$(now) - $t0"
}

# Waits until FILE holds TEXT. Four looks a second, the file read by bash itself: a grep
# forked every 20 ms took enough of the two cores to make serve's frames 1.6x slower than
# replay's (registration 82 against 50 ms a frame on the GNSS loop, the same instructions;
# 52 ms with this wait), and the benchmark measured its own polling.
wait_for() {
  local file=$1 text=$2 lines
  while :; do
    if [[ -f "$file" ]] && mapfile -t lines <"$file" 2>/dev/null &&
      [[ "${lines[*]}" == *"$text"* ]]; then
      return 0
    fi
    sleep 0.25
  done
}

# Seconds until serve has done every frame of INBOX (N frames); extra args are --set options.
serve_s() {
  local inbox=$1 n=$2; shift 2
  rm -rf "$W/serve"
  local t0; t0=$(now)
  "$R" serve --inbox "$inbox" --out "$W/serve" "$@" 2>"$W/serve.log" &
  local pid=$!
  # Done when the outputs of the last frame are out (the publications run in the background):
  # when summary.json covering them was written (its time, not the look's, a quarter second
  # later at most).
  wait_for "$W/serve/summary.json" "\"frames\": $n,"
  local t1; t1=$(stat -c %.9Y "$W/serve/summary.json")
  kill -TERM $pid; wait $pid
  calc "$t1 - $t0"
}

echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
"$R" simulate --out "$W/stereo" >/dev/null 2>&1
"$R" simulate --out "$W/cloud" --set sim.sensor=cloud --set sim.cloud_stride_px=3 >/dev/null 2>&1
"$R" simulate --out "$W/gnss" --set sim.sensor=cloud --set sim.frames=150 \
  --set sim.frame_rate_hz=1 --set sim.speed_m_s=2 --set sim.terrain_size_m=400 \
  --set sim.terrain_cell_m=0.2 --set sim.turn_radius_m=40 --set sim.path=loop \
  --set sim.start_y_m=-40 --set sim.odom_scale_error=0.05 --set sim.gnss_every_frames=5 \
  --set sim.gnss_outlier_fraction=0.05 >/dev/null 2>&1
"$R" simulate --out "$W/long" --set sim.sensor=cloud --set sim.cloud_stride_px=3 \
  --set sim.frames="$LONG" --set sim.path=loop --set sim.terrain_size_m=60 >/dev/null 2>&1

# p=1 and p=10 publish at that cadence whatever it costs (serve.publish_share=0); "default" is
# serve's own cadence: every 10 frames, through a backlog at most 5 % of the frames' time.
printf '\n%-30s %8s %10s %12s %12s %12s %10s %10s %10s\n' "sequence" "frames" "replay f/s" \
  "serve p=1" "serve p=10" "serve dflt" "p=1/rep" "p=10/rep" "dflt/rep"
for seq in "$W/stereo" "$W/cloud" "$W/gnss" ${SEQUENCES[@]+"${SEQUENCES[@]}"}; do
  case "$seq" in "$W/"*) name="sim ${seq##*/}" ;; *) name=${seq##*/} ;; esac
  n=$(frames_of "$seq")
  make_inbox "$seq" "$W/inbox" "$n"
  rep=(); s1=(); s10=(); sd=()
  for ((i = 0; i < RUNS; i++)); do
    rep+=("$(replay_s "$seq")")
    s1+=("$(serve_s "$W/inbox" "$n" --set serve.publish_every=1 --set serve.publish_share=0)")
    s10+=("$(serve_s "$W/inbox" "$n" --set serve.publish_every=10 --set serve.publish_share=0)")
    sd+=("$(serve_s "$W/inbox" "$n")")
  done
  r=$(printf '%s\n' "${rep[@]}" | median)
  a=$(printf '%s\n' "${s1[@]}" | median)
  b=$(printf '%s\n' "${s10[@]}" | median)
  d=$(printf '%s\n' "${sd[@]}" | median)
  printf '%-30s %8d %10.2f %12.2f %12.2f %12.2f %10.2f %10.2f %10.2f\n' "$name" "$n" \
    "$(calc "$n / $r")" "$(calc "$n / $a")" "$(calc "$n / $b")" "$(calc "$n / $d")" \
    "$(calc "$r / $a")" "$(calc "$r / $b")" "$(calc "$r / $d")"
done

printf '\n%-30s %8s %14s %14s %10s\n' "pose graph in serve" "frames" "graph off f/s" \
  "graph on f/s" "on/off"
n=$(frames_of "$W/gnss")
make_inbox "$W/gnss" "$W/inbox" "$n"
off=(); on=()
for ((i = 0; i < RUNS; i++)); do
  off+=("$(serve_s "$W/inbox" "$n" --set graph.enabled=false)")
  on+=("$(serve_s "$W/inbox" "$n")")
done
a=$(printf '%s\n' "${off[@]}" | median)
b=$(printf '%s\n' "${on[@]}" | median)
printf '%-30s %8d %14.2f %14.2f %10.2f\n' "sim gnss loop, p=10" "$n" "$(calc "$n / $a")" \
  "$(calc "$n / $b")" "$(calc "$a / $b")"
grep -o 'pose graph over [0-9]* frames.*ms' "$W/serve.log" | tail -1 | sed 's/^/last solve: /'
# The last publication's DEM moved onto the graph's poses (summary.json graph.dem_moved).
tr -d ' \n' < "$W/serve/summary.json" | grep -o '"dem_moved":{[^}]*}' | sed 's/^/last DEM move: /'

printf '\n%-30s %10s %14s %14s %16s\n' "restart after" "frames" "restart [ms]" "snapshot [MB]" \
  "replay them [s]"
for n in 100 "$LONG"; do
  make_inbox "$W/long" "$W/inbox" "$n"
  rm -rf "$W/serve"
  # Snapshots exactly every 10 frames (checkpoint_share 0), so that the kill lands at frame n.
  ROVERMAP_FAULT_KILL="checkpoint:written:$((n / 10))" "$R" serve --inbox "$W/inbox" \
    --out "$W/serve" --set serve.checkpoint_share=0 2>/dev/null || true
  "$R" serve --inbox "$W/inbox" --out "$W/serve" --set serve.checkpoint_share=0 \
    2>"$W/serve.log" &
  pid=$!
  wait_for "$W/serve/status.json" "\"next_frame\": $n,"
  kill -TERM $pid; wait $pid
  ms=$(grep -o 'resumed at frame [0-9]* ([0-9]* journalled steps re-applied) in [0-9]* ms' \
    "$W/serve.log" | grep -o '[0-9]* ms' | grep -o '[0-9]*')
  mb=$(calc "$(stat -c %s "$W/serve/checkpoint/state.bin") / 1000000")
  # Replaying the same frames, for scale.
  rm -rf "$W/part"; mkdir -p "$W/part/frames"; cp "$W/long/sequence.yaml" "$W/part/"
  awk -v n="$n" '/^#/ || ++k <= n' "$W/long/odometry.tum" >"$W/part/odometry.tum"
  for ((k = 0; k < n; k++)); do ln "$W/long/frames/$(printf %06d $k).ply" "$W/part/frames/"; done
  printf '%-30s %10d %14s %14.1f %16.1f\n' "sim cloud loop, kill -9" "$n" "$ms" "$mb" \
    "$(replay_s "$W/part")"
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
