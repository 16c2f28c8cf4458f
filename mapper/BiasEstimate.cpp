#include "mapper/BiasEstimate.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace rovermap::mapper {

BiasEstimate UpdateBias(const BiasEstimate& previous, const Vector6d& correction,
                        const Matrix6d& correction_information, const Matrix6d& prior_information,
                        double forgetting, const Matrix6d& odometry_covariance) {
  if (correction_information.isZero(0.0) || !correction_information.allFinite() ||
      !correction.allFinite() || !prior_information.allFinite()) {
    return previous;
  }
  const double keep = 1.0 - std::clamp(forgetting, 0.0, 1.0);
  // η_{k−1} from the stored bias: the prior's mean is zero, so η = (W_0 + λ) b.
  const Vector6d eta_previous = (prior_information + previous.information) * previous.bias;
  BiasEstimate out;
  out.information = keep * previous.information + correction_information;
  const Vector6d eta = keep * eta_previous + correction_information * correction;
  const Eigen::LDLT<Matrix6d> total(prior_information + out.information);
  if (total.info() != Eigen::Success) return previous;
  const Vector6d bias = total.solve(eta);
  out.bias = bias.allFinite() ? BoundedBias(bias, odometry_covariance) : previous.bias;
  return out;
}

Vector6d BoundedBias(const Vector6d& bias, const Matrix6d& odometry_covariance) {
  const Eigen::LDLT<Matrix6d> odometry(odometry_covariance);
  if (odometry.info() != Eigen::Success || !odometry.isPositive()) return bias;
  const double mahalanobis = std::sqrt(std::max(0.0, bias.dot(odometry.solve(bias))));
  return mahalanobis > 1.0 ? Vector6d(bias / mahalanobis) : bias;
}

}  // namespace rovermap::mapper
