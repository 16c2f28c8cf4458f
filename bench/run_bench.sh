#!/usr/bin/env bash
# Runs the registration benchmark and prints its table.
#   bash bench/run_bench.sh BUILD_DIR [bench_register options, e.g. --runs 7 --pairs all]
# BUILD_DIR is a configured and built CMake tree (`make bench` passes $(BUILD)). Configure it
# with -DROVERMAP_BENCH_PEERS=ON to include PCL and Open3D in the table.
set -euo pipefail

if [[ $# -lt 1 || "$1" == "-h" || "$1" == "--help" ]]; then
  echo "usage: bash bench/run_bench.sh BUILD_DIR [--runs N] [--pairs bunny|terrain|all] [--threads N] [--gate-factor F]" >&2
  exit 2
fi
build_dir=$1
shift

exe="$build_dir/bench/bench_register"
if [[ ! -x "$exe" ]]; then
  echo "run_bench: $exe not found; build it first (cmake --build $build_dir --target bench_register)" >&2
  exit 1
fi
if ! grep -q '^ROVERMAP_BENCH_PEERS:BOOL=ON' "$build_dir/CMakeCache.txt" 2>/dev/null; then
  echo "run_bench: peers not built in $build_dir (reconfigure with -DROVERMAP_BENCH_PEERS=ON" \
       "to compare with PCL and Open3D)" >&2
fi
build_type=$(sed -n 's/^CMAKE_BUILD_TYPE:STRING=//p' "$build_dir/CMakeCache.txt" 2>/dev/null || true)
if [[ "$build_type" != "Release" ]]; then
  echo "run_bench: warning: $build_dir is a '${build_type:-unknown}' build; timings are meant for Release" >&2
fi

echo "# bench_register $* ($(uname -m), $(nproc) cores, $(date -u +%Y-%m-%dT%H:%MZ))"
exec "$exe" "$@"
