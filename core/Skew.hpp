#pragma once
// The cross-product matrix: Skew(v) · w = v × w.

#include <Eigen/Core>

namespace rovermap::core {

inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace rovermap::core
