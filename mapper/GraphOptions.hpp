#pragma once
// Options of the pose graph a replay solves over its frames (docs/graph.md); the `graph.` keys.

#include <vector>

namespace rovermap::mapper {

struct GraphOptions {
  /// Solve the graph when the recording has absolute fixes (gnss.csv beside a sequence) or a
  /// reference DEM is given; false: the frame-to-frame trajectory is the result, fixes or not.
  bool enabled = true;
  /// [s] a fix belongs to the frame whose timestamp is nearest, if within this; >= 0.
  double gnss_max_time_offset_s = 0.05;
  /// [m] the antenna in the body frame (x forward, y left, z up): the point the fixes locate.
  std::vector<double> gnss_antenna_m = {0.0, 0.0, 0.0};
  /// [χ², 3 dof] a fix farther than this from the solution is rejected (multipath) and the
  /// graph solved without it; > 0.
  double fix_gate_chi2 = 16.27;
  /// [σ] a fix's residual beyond this weighs linearly (Huber); > 0.
  double fix_huber_sigmas = 4.0;
  /// [count] fewer fixes left after the gate: the frame-to-frame trajectory is kept; >= 1.
  int min_gnss_fixes = 3;
  /// [count] solve-and-gate rounds at most; >= 1.
  int max_gate_rounds = 20;
  /// [frames] the graph's marginal covariances are computed up to this many frames (their cost
  /// grows with the square: 1000 frames 0.75 s, 3000 frames 7 s); beyond it drift.csv's σ and
  /// the DEM's stay the chain's, and summary.json says so; 0 = never; >= 0.
  int covariance_max_frames = 2000;
};

}  // namespace rovermap::mapper
