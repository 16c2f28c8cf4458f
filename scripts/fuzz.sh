#!/usr/bin/env bash
# Runs the libFuzzer targets of a ROVERMAP_FUZZ=ON build one at a time (single process, at low
# priority), each for SECONDS on its seed corpus tests/fuzz/corpus/<target>/. New inputs go to
# BUILD/fuzz-corpus/<target>/ (the seeds in git stay as they are), crashing, hanging or OOM
# inputs to BUILD/fuzz-artifacts/<target>/, each run's log to BUILD/fuzz-logs/<target>.log.
# Exits 1 if any target found a problem.
set -euo pipefail
build=${1:?usage: fuzz.sh BUILD_DIR SECONDS [TARGET...]}
seconds=${2:?usage: fuzz.sh BUILD_DIR SECONDS [TARGET...]}
shift 2
root="$(cd "$(dirname "$0")/.." && pwd)"
targets=("$@")
if [[ ${#targets[@]} -eq 0 ]]; then
  for src in "$root"/tests/fuzz/fuzz_*.cpp; do targets+=("$(basename "$src" .cpp)"); done
fi

failed=()
for target in "${targets[@]}"; do
  name=${target#fuzz_}
  bin="$build/tests/fuzz/fuzz_$name"
  [[ -x "$bin" ]] || { echo "fuzz.sh: $bin not built (make fuzz-build)" >&2; exit 2; }
  work="$build/fuzz-corpus/$name"
  artifacts="$build/fuzz-artifacts/$name"
  log="$build/fuzz-logs/$name.log"
  mkdir -p "$work" "$artifacts" "$(dirname "$log")"
  echo "== fuzz_$name: ${seconds} s on tests/fuzz/corpus/$name (log: $log)"
  # -timeout: one input taking over 10 s counts as a hang.
  if nice -n 15 "$bin" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 \
      -print_final_stats=1 -artifact_prefix="$artifacts/" \
      "$work" "$root/tests/fuzz/corpus/$name" >"$log" 2>&1; then
    grep -E '^(#[0-9]+[[:space:]]+DONE|Done [0-9]+ runs)' "$log" | sed 's/^/   /' || true
  else
    echo "   FAILED: see $log; inputs in $artifacts" >&2
    grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error)' "$log" | head -5 | sed 's/^/   /' >&2 ||
      true
    failed+=("fuzz_$name")
  fi
done
if [[ ${#failed[@]} -gt 0 ]]; then
  echo "fuzz.sh: problems found by ${failed[*]}" >&2
  exit 1
fi
