#pragma once
// The cross-product matrix: Skew(v) · w = v × w; the Adjoint of a rigid transform.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rovermap::core {

inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

/// Adjoint of `T` for perturbations ordered [rx ry rz tx ty tz], left ones (Exp(δr), δt) ∘ T:
/// a right perturbation ξ of T is the left perturbation Ad(T)·ξ. Ad = [[R, 0], [[t]×R, R]].
inline Eigen::Matrix<double, 6, 6> Adjoint(const Eigen::Isometry3d& T) {
  Eigen::Matrix<double, 6, 6> ad = Eigen::Matrix<double, 6, 6>::Zero();
  ad.topLeftCorner<3, 3>() = T.linear();
  ad.bottomLeftCorner<3, 3>() = Skew(T.translation()) * T.linear();
  ad.bottomRightCorner<3, 3>() = T.linear();
  return ad;
}

}  // namespace rovermap::core
