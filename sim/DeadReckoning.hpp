#pragma once
// Dead reckoning made from a ground truth: what a wheeled or skid-steer rover's odometry gives
// over the same path (a heading that drifts with distance, a wheel-scale error, noise), to test
// registration with a seed as biased as a real one rather than the kinder bundled odometry.

#include <cstdint>
#include <vector>

#include "io/Tum.hpp"

namespace rovermap::sim {

/// Error model of dead reckoning, per frame step. Defaults: no error.
struct DeadReckoningModel {
  /// Heading error added per metre of the true step [deg/m] (skid-steer: tenths of a degree).
  double heading_bias_deg_per_m = 0.0;
  /// Heading noise per step, σ [deg].
  double heading_noise_deg = 0.0;
  /// Translation of each step scaled by (1 + scale_error) [ratio].
  double scale_error = 0.0;
  /// Translation noise per step and axis, σ [m].
  double translation_noise_m = 0.0;
  /// Seeds the noise; the same seed gives the same poses.
  std::uint64_t seed = 1;
};

/// The dead-reckoning poses over `truth`: the first pose is the true one; each later pose
/// chains the true increment (in the body frame) with its heading turned by
/// bias·|t| + N(0, heading_noise) about body z and its translation scaled and perturbed.
/// Timestamps are the truth's. Never throws.
std::vector<io::StampedPose> DeadReckoningFromTruth(const std::vector<io::StampedPose>& truth,
                                                    const DeadReckoningModel& model);

}  // namespace rovermap::sim
