#pragma once
// Poses and covariances the graph and map tests build by hand.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace rovermap::testing {

/// A pose on the plane: at (x, y, 0), turned `yaw_deg` about z.
inline Eigen::Isometry3d PlanarPose(double x, double y, double yaw_deg) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).matrix();
  T.translation() = Eigen::Vector3d(x, y, 0.0);
  return T;
}

/// A 6 × 6 pose covariance (order rx ry rz tx ty tz) of σ `sigma_rad` on each rotation and
/// `sigma_m` on each translation.
inline Eigen::Matrix<double, 6, 6> DiagonalCovariance(double sigma_rad, double sigma_m) {
  Eigen::Matrix<double, 6, 6> c = Eigen::Matrix<double, 6, 6>::Zero();
  c.diagonal() << Eigen::Vector3d::Constant(sigma_rad * sigma_rad),
      Eigen::Vector3d::Constant(sigma_m * sigma_m);
  return c;
}

}  // namespace rovermap::testing
