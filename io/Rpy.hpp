#pragma once
// Roll, pitch, yaw in degrees as sequence.yaml (`rotation_rpy_deg`) and the `bag.` config give
// them. Header-only: config/ uses it without linking io/.

#include <Eigen/Geometry>

namespace rovermap::io {

/// R = Rz(yaw)·Ry(pitch)·Rx(roll), angles in degrees.
inline Eigen::Matrix3d RotationFromRpyDeg(double roll_deg, double pitch_deg, double yaw_deg) {
  constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
  return (Eigen::AngleAxisd(yaw_deg * kDegToRad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch_deg * kDegToRad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll_deg * kDegToRad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

}  // namespace rovermap::io
