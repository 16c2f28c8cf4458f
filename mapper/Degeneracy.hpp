#pragma once
// Step 5 of the pipeline: per-direction fallback. On flat or featureless ground the
// registration constrains only some directions (on a plane: z, roll and pitch); in the others
// its answer is noise, so those keep the dead-reckoning prediction, corrected by dead
// reckoning's systematic error per frame (a heading-rate bias, a wheel-scale error) as the
// registration's corrections in the directions they do inform estimate it.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

#include "mapper/PoseChain.hpp"  // Matrix6d
#include "registration/Directions.hpp"

namespace rovermap::mapper {

/// Directions of an increment, in the registration's target frame (x forward, y left, z up).
using registration::Direction;
using registration::DirectionNames;
using registration::kPitch;
using registration::kRoll;
using registration::kX;
using registration::kY;
using registration::kYaw;
using registration::kZ;

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// The increment kept after the per-direction test.
struct BlendedIncrement {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();  ///< blended T_target_source
  /// Directions taken from the prediction (Direction bits): one per unconstrained eigenvector,
  /// named by its largest component.
  unsigned odometry_directions = 0;
  int constrained = 0;  ///< eigen-directions taken from the registration (0..6)
  /// Smallest eigenvalue / largest of the scaled information (the registration's
  /// `conditioning`).
  double min_ratio = 0.0;
  /// Covariance of T for a left perturbation [rx ry rz tx ty tz] (rad, m), target frame: the
  /// registration's in the constrained directions, `odometry_covariance` in the others.
  Matrix6d covariance = Matrix6d::Zero();
  /// The registration's part of `covariance` alone (its constrained directions).
  Matrix6d covariance_registered = Matrix6d::Zero();
  /// The registration's information in its constrained directions ([rad, m], target frame):
  /// the pseudo-inverse of `covariance_registered`.
  Matrix6d information_registered = Matrix6d::Zero();
  /// P_u: maps a covariance of the prediction onto the directions taken from it, so that
  /// `covariance` = covariance_registered + P_u · odometry_covariance · P_uᵀ (zero when the
  /// registration is kept whole).
  Matrix6d prediction_projector = Matrix6d::Zero();
  /// What this frame tells of dead reckoning's bias (UpdateBias): the registration's
  /// correction of the prediction in the directions with at least `bias_min_information`, and
  /// the registration's information there (unscaled, [rad, m]); both zero elsewhere, and
  /// everywhere when that correction is beyond 3σ of `odometry_covariance`.
  Vector6d bias_correction = Vector6d::Zero();
  Matrix6d bias_information = Matrix6d::Zero();
};

/// Blends `T_registered` and `T_predicted` (both T_target_source) per eigen-direction of the
/// registration's `information` (left perturbation p' = Exp(δr)·p + δt in the target frame, as
/// RegistrationResult). Rotations are scaled by `extent_m` (the cloud's radius) so that their
/// eigenvalues compare with the translations' in metres, as `conditioning` does. Directions
/// whose eigenvalue is below `min_information` × the largest keep the prediction, moved by
/// `odometry_bias` (dead reckoning's estimated error per increment, same parameterisation) in
/// those directions; min_information <= 0 keeps the registration whole. An eigen-direction v
/// must also hold `min_information_over_noise` × the information `noise_information` gives it
/// (vᵀIv >= k·vᵀNv, N = RegistrationResult::noise_information: what the errors of the matched
/// normals alone produce on featureless ground; 0 = no such test). The bias is informed by
/// the directions passing both tests with bias_min_information. A zero information keeps the
/// prediction whole. Never throws.
BlendedIncrement BlendIncrement(const Eigen::Isometry3d& T_predicted,
                                const Eigen::Isometry3d& T_registered, const Matrix6d& information,
                                double extent_m, double min_information,
                                const Matrix6d& odometry_covariance,
                                const Vector6d& odometry_bias = Vector6d::Zero(),
                                double bias_min_information = 1e-6,
                                const Matrix6d& noise_information = Matrix6d::Zero(),
                                double min_information_over_noise = 0.0);

/// δ with T_a = (Exp(δr), δt) ∘ T_b: a left perturbation [rx ry rz (rad) tx ty tz (m)] in the
/// frame T_a and T_b map into, the parameterisation of the registration's information.
Vector6d LeftDifference(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b);
/// (Exp(δr), δt) ∘ T.
Eigen::Isometry3d ApplyLeft(const Vector6d& delta, const Eigen::Isometry3d& T);

}  // namespace rovermap::mapper
