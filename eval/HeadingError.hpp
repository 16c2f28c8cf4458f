#pragma once
// Heading error of a trajectory against the truth, frame by frame: how much of a seed's heading
// error registration leaves in each increment, which an ATE hides until it has grown.

#include <Eigen/Geometry>
#include <vector>

namespace rovermap::eval {

struct HeadingErrors {
  /// Yaw of (true increment)⁻¹·(estimated increment), body frame, frames 1…N−1 [deg].
  std::vector<double> per_frame_deg;
  double mean_deg = 0.0;   ///< mean of per_frame_deg [deg]
  double rms_deg = 0.0;    ///< root mean square of per_frame_deg [deg]
  double final_deg = 0.0;  ///< yaw of (true last pose)⁻¹·(estimated last pose) [deg]
};

/// Compares `estimate[i]` with `truth[i]` (associated by index, T_world_body). Fewer than two
/// poses in either, or different counts: all zero and per_frame_deg empty. Never throws.
HeadingErrors CompareHeadings(const std::vector<Eigen::Isometry3d>& estimate,
                              const std::vector<Eigen::Isometry3d>& truth);

/// Yaw of a rotation about z, from its x column projected on the xy plane, in (−180, 180] [deg].
double YawDeg(const Eigen::Matrix3d& R);

}  // namespace rovermap::eval
