#pragma once
// Elapsed wall time in milliseconds, as every stage timing of the pipeline, the daemon and the
// benchmarks reports it (steady clock: immune to the system clock being set).

#include <chrono>

namespace rovermap::core {

using Clock = std::chrono::steady_clock;

/// Milliseconds from `a` to `b`.
inline double MsBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

/// Milliseconds from `start` to now.
inline double MsSince(Clock::time_point start) { return MsBetween(start, Clock::now()); }

}  // namespace rovermap::core
