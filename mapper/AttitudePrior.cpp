#include "core/Units.hpp"
#include "mapper/AttitudePrior.hpp"

#include <algorithm>
#include <cmath>

#include "io/Rpy.hpp"
#include "mapper/PoseChain.hpp"

namespace rovermap::mapper {
namespace {

using core::kDegToRad;
using core::kPi;

double Wrap(double angle) { return std::remainder(angle, 2.0 * kPi); }

}  // namespace

AttitudePrior::AttitudePrior(double odometry_sigma_deg, double step_sigma_deg)
    : odometry_variance_(std::pow(std::max(0.0, odometry_sigma_deg) * kDegToRad, 2)),
      step_variance_(std::pow(std::max(0.0, step_sigma_deg) * kDegToRad, 2)) {}

Eigen::Isometry3d AttitudePrior::Update(const Eigen::Isometry3d& T_world_body,
                                        const Eigen::Isometry3d& T_world_body_odom) {
  if (!enabled()) return T_world_body;
  variance_ += step_variance_;
  const double gain = variance_ / (variance_ + odometry_variance_);
  variance_ *= 1.0 - gain;
  const Eigen::Vector3d rpy = EulerRpyFromRotation(T_world_body.linear());
  const Eigen::Vector3d rpy_odom = EulerRpyFromRotation(T_world_body_odom.linear());
  const Eigen::Vector3d updated(rpy.x() + gain * Wrap(rpy_odom.x() - rpy.x()),
                                rpy.y() + gain * Wrap(rpy_odom.y() - rpy.y()), rpy.z());
  Eigen::Isometry3d T = T_world_body;
  if (updated.allFinite()) T.linear() = io::RotationFromRpy(updated);
  return T;
}

void FloorAttitudeVariance(Eigen::Matrix<double, 6, 6>* covariance, double step_sigma_deg) {
  const double sigma = step_sigma_deg * M_PI / 180.0;
  for (int i = 0; i < 2; ++i) (*covariance)(i, i) = std::max((*covariance)(i, i), sigma * sigma);
}

}  // namespace rovermap::mapper
