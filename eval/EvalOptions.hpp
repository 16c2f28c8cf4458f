#pragma once
// Options of the trajectory metrics (docs/design.md §8); config keys `eval.*` (config/Keys.cpp).

#include <vector>

namespace rovermap::eval {

struct EvalOptions {
  /// Largest |t_estimate − t_groundtruth| of an associated pair [s] (TUM benchmark's
  /// associate.py: 0.02). Only used when both files carry timestamps.
  double association_tolerance_s = 0.02;
  /// Travelled ground-truth distance between the two poses of an RPE pair [m].
  double rpe_delta_m = 1.0;
  /// KITTI-style segment lengths [m] (the KITTI devkit uses 100..800 m for cars; these suit
  /// rover traverses).
  std::vector<double> segment_lengths_m = {5.0, 10.0, 20.0, 50.0};
};

}  // namespace rovermap::eval
