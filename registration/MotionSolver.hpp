#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace rovermap::registration {

/// One matched pair for the closed-form solvers: target ≈ R·source + t.
struct WeightedPair {
  Eigen::Vector3d source;  ///< x_i, in the source frame [m]
  Eigen::Vector3d target;  ///< y_i, in the target frame [m]
  double weight = 1.0;     ///< w_i > 0
};

/// Result of a closed-form motion estimate.
struct MotionEstimate {
  bool valid = false;  ///< false: fewer than 3 pairs, zero total weight or non-finite input
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
};

/// Weighted least-squares rigid motion minimising Σ w‖R x + t − y‖² / Σ w by SVD of the
/// cross-covariance (Arun 1987, Umeyama 1991; Zhang 1994 Appendix A). The
/// diag(1, 1, det(V Uᵀ)) guard means the result is never a reflection, also for planar
/// or collinear inputs.
MotionEstimate SolveMotionSvd(const std::vector<WeightedPair>& pairs);

/// The same minimum by dual quaternions (Walker, Shao & Volz 1991; Zhang 1994 Appendix B):
/// the rotation quaternion is the eigenvector of the largest eigenvalue of the 4×4 matrix A.
MotionEstimate SolveMotionDualQuaternion(const std::vector<WeightedPair>& pairs);

}  // namespace rovermap::registration
