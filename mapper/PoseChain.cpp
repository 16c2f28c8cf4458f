#include "mapper/PoseChain.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/Skew.hpp"
#include "core/Units.hpp"

namespace rovermap::mapper {
namespace {

using core::kRadToDeg;
// cos(pitch) below this is gimbal lock: cos(±π/2) in doubles is ~6e-17.
constexpr double kGimbalCos = 1e-12;

}  // namespace

Eigen::Vector3d EulerRpyFromRotation(const Eigen::Matrix3d& R) {
  // R = Rz(y)·Ry(p)·Rx(r): first column (cy·cp, sy·cp, −sp).
  const double cos_pitch = std::hypot(R(0, 0), R(1, 0));
  const double pitch = std::atan2(-R(2, 0), cos_pitch);
  if (cos_pitch < kGimbalCos) {
    // Rows 0-1 of column 1 are (−sin(y ∓ r), cos(y ∓ r)) at pitch ±π/2; take roll = 0.
    return {0.0, pitch, std::atan2(-R(0, 1), R(1, 1))};
  }
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  // Roll from Rz(yaw)ᵀ·R = Ry(p)·Rx(r), whose (1,1), (1,2) are (cos r, −sin r): consistent with
  // the yaw just taken, so the angles rebuild R accurately even close to gimbal lock.
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  const double m11 = -sy * R(0, 1) + cy * R(1, 1);
  const double m12 = -sy * R(0, 2) + cy * R(1, 2);
  return {std::atan2(-m12, m11), pitch, yaw};
}

TransformComponents CorrectionComponents(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d rpy = EulerRpyFromRotation(T.linear()) * kRadToDeg;
  const Eigen::Vector3d t = T.translation();
  return {t.x(), t.y(), t.z(), rpy.x(), rpy.y(), rpy.z()};
}

bool IsFiniteRigid(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d R = T.linear();
  if (!R.allFinite() || !T.translation().allFinite()) return false;
  const double orthogonality =
      (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  return orthogonality <= 1e-6 && R.determinant() > 0.0;
}

PoseChain::PoseChain(const Eigen::Isometry3d& T_world_body0_odom) {
  if (!IsFiniteRigid(T_world_body0_odom)) {
    throw std::invalid_argument("PoseChain: frame 0 odometry pose is not a finite rigid transform");
  }
  last_.T_world_body = T_world_body0_odom;
  last_.T_world_body_odom = T_world_body0_odom;
}

PoseChain::PoseChain(const std::vector<ChainStep>& steps) {
  if (steps.empty()) throw std::invalid_argument("PoseChain: no steps to restore");
  for (const ChainStep& step : steps) {
    path_length_m_ += step.used_increment.translation().norm();
    if (step.fallback) ++fallbacks_;
  }
  last_ = steps.back();
}

Eigen::Isometry3d PoseChain::PredictIncrement(const Eigen::Isometry3d& T_world_body_odom) const {
  return last_.T_world_body_odom.inverse() * T_world_body_odom;
}

ChainStep PoseChain::Add(const Eigen::Isometry3d& T_world_body_odom,
                         const std::optional<Eigen::Isometry3d>& T_prev_curr_registered,
                         const Matrix6d& increment_covariance, const SystematicError& systematic) {
  if (!IsFiniteRigid(T_world_body_odom)) {
    throw std::invalid_argument("PoseChain: frame " + std::to_string(size()) +
                                " odometry pose is not a finite rigid transform");
  }
  const ChainStep& prev = last_;
  ChainStep step;
  step.index = size();
  step.T_world_body_odom = T_world_body_odom;
  step.odom_increment = PredictIncrement(T_world_body_odom);
  step.fallback = !T_prev_curr_registered || !IsFiniteRigid(*T_prev_curr_registered);
  step.used_increment = step.fallback ? step.odom_increment : *T_prev_curr_registered;
  step.T_world_body = prev.T_world_body * step.used_increment;
  // Keep the chained rotation on SO(3): Isometry3d::inverse() assumes an orthonormal linear part,
  // and the rounding of each product, fed back through the next prediction and registration,
  // grew about five-fold per frame (1e-6 after 15 KITTI frames, when IsFiniteRigid refused
  // every registered increment).
  step.T_world_body.linear() =
      Eigen::Quaterniond(step.T_world_body.linear()).normalized().toRotationMatrix();
  step.increment_correction = step.odom_increment.inverse() * step.used_increment;
  step.cumulative_correction = T_world_body_odom.inverse() * step.T_world_body;
  // T̂(k−1)·Exp(ξ)·Exp(δ)·ΔT̂ ≈ T̂(k−1)·ΔT̂·Exp(Ad(ΔT̂⁻¹)(ξ + δ)) to first order.
  const Matrix6d A = Adjoint(step.used_increment.inverse());
  const Matrix6d L = systematic.sigma.asDiagonal();
  const double phi = systematic.persistence;
  const Matrix6d carried = phi * prev.systematic_cross;  // Cov(ξ_{k−1}, b_k)
  step.covariance = A *
                    (prev.covariance + increment_covariance + L * L.transpose() +
                     carried * L.transpose() + L * carried.transpose()) *
                    A.transpose();
  step.systematic_cross = A * (carried + L);

  path_length_m_ += step.used_increment.translation().norm();
  if (step.fallback) ++fallbacks_;
  last_ = step;
  return step;
}

}  // namespace rovermap::mapper
