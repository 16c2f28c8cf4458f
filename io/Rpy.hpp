#pragma once
// Rotations as sequence.yaml (`rotation_rpy_deg`, `quaternion`), the `bag.` config, a bag's
// transforms, the simulator and the attitude prior give them.

#include <Eigen/Geometry>

#include "core/Units.hpp"

namespace rovermap::io {

/// R = Rz(yaw)·Ry(pitch)·Rx(roll), angles in radians: the one roll-pitch-yaw convention of
/// sequence.yaml, the simulator and the attitude prior. Never fails; non-finite angles give a
/// non-finite matrix.
inline Eigen::Matrix3d RotationFromRpy(double roll_rad, double pitch_rad, double yaw_rad) {
  return (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

/// The same from (roll, pitch, yaw) [rad].
inline Eigen::Matrix3d RotationFromRpy(const Eigen::Vector3d& rpy_rad) {
  return RotationFromRpy(rpy_rad.x(), rpy_rad.y(), rpy_rad.z());
}

/// The same, angles in degrees.
inline Eigen::Matrix3d RotationFromRpyDeg(double roll_deg, double pitch_deg, double yaw_deg) {
  using core::kDegToRad;
  return RotationFromRpy(roll_deg * kDegToRad, pitch_deg * kDegToRad, yaw_deg * kDegToRad);
}

/// The rotation of a (nearly) unit quaternion: the one conversion of sequence.yaml's and a
/// bag's quaternions, so that the same quaternion always gives the same matrix, to the bit.
inline Eigen::Matrix3d RotationFromQuaternion(const Eigen::Quaterniond& q) {
  return q.normalized().toRotationMatrix();
}

}  // namespace rovermap::io
