#pragma once
// Rotations as sequence.yaml (`rotation_rpy_deg`, `quaternion`), the `bag.` config and a bag's
// transforms give them.

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

/// The rotation of a (nearly) unit quaternion: the one conversion of sequence.yaml's and a
/// bag's quaternions, so that the same quaternion always gives the same matrix, to the bit.
inline Eigen::Matrix3d RotationFromQuaternion(const Eigen::Quaterniond& q) {
  return q.normalized().toRotationMatrix();
}

}  // namespace rovermap::io
