#pragma once
// Dead reckoning's systematic error per increment (a heading-rate bias, a wheel-scale error),
// estimated from the registration's corrections. Each frame's correction is weighted by the
// registration's information in the directions it informs: on a plane's rolling neighbour the
// weak yaw of one frame is a degree off, on a rocky loop a twentieth of that, and an unweighted
// mean of the former is worse than no estimate. A zero-mean prior (a fraction of dead
// reckoning's per-step σ) keeps the estimate near zero until the evidence outweighs it;
// forgetting lets it follow a bias that changes. An information filter: b = Λ⁻¹η with
//   λ_k = (1 − α) λ_{k−1} + W_k,   η_k = (1 − α) η_{k−1} + W_k z_k,   Λ_k = W_0 + λ_k.

#include <Eigen/Core>

#include "mapper/PoseChain.hpp"  // Matrix6d

namespace rovermap::mapper {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// The estimate after some frames. Left perturbations [rx ry rz (rad) tx ty tz (m)] of an
/// increment in its target frame, as RegistrationResult's information.
struct BiasEstimate {
  Vector6d bias = Vector6d::Zero();  ///< dead reckoning's error per increment
  /// The corrections' accumulated information (forgetting applied), prior excluded.
  Matrix6d information = Matrix6d::Zero();
};

/// One frame's update. `correction`: the registration's increment against dead reckoning's
/// (T_registered = Exp(correction) ∘ T_predicted), `correction_information`: its information
/// (zero in the directions that inform nothing; all zero: the estimate stays as it is),
/// `prior_information`: W_0, `forgetting`: α in [0, 1). The bias is shrunk to the 1σ ellipsoid
/// of `odometry_covariance` (BoundedBias). Never throws.
BiasEstimate UpdateBias(const BiasEstimate& previous, const Vector6d& correction,
                        const Matrix6d& correction_information, const Matrix6d& prior_information,
                        double forgetting, const Matrix6d& odometry_covariance);

/// `bias` shrunk, if need be, to the 1σ ellipsoid of `odometry_covariance` (same
/// parameterisation): dead reckoning's error model bounds what a systematic error per increment
/// can be; the estimate never leaves it. A covariance that is not positive definite leaves the
/// bias as it is. Never throws.
Vector6d BoundedBias(const Vector6d& bias, const Matrix6d& odometry_covariance);

}  // namespace rovermap::mapper
