#include "mapper/PoseUncertainty.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "core/Units.hpp"

namespace rovermap::mapper {
namespace {
using core::kRadToDeg;
// χ² with 6 degrees of freedom at the probability of ±2σ in one dimension (0.9545).
constexpr double kChi2Six2Sigma = 12.85;
}  // namespace

Matrix6d UserAxesJacobian(const Eigen::Isometry3d& T_world_body) {
  const Eigen::Matrix3d R = T_world_body.linear();
  Matrix6d J = Matrix6d::Zero();
  J.topRightCorner<3, 3>() = R;    // position: world axes
  J(3, 0) = 1.0;                   // roll: about the body's x
  J(4, 1) = 1.0;                   // pitch: about the body's y
  J.block<1, 3>(5, 0) = R.row(2);  // yaw: about the world's z
  return J;
}

PoseSigmas SigmasOf(const ChainStep& step) {
  const Matrix6d J = UserAxesJacobian(step.T_world_body);
  const Vector6d sd = (J * step.covariance * J.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  PoseSigmas s;
  s.x_m = sd(0);
  s.y_m = sd(1);
  s.z_m = sd(2);
  s.roll_deg = sd(3) * kRadToDeg;
  s.pitch_deg = sd(4) * kRadToDeg;
  s.yaw_deg = sd(5) * kRadToDeg;
  return s;
}

std::optional<CalibrationCheck> CheckCalibration(const std::vector<FrameResult>& results) {
  std::vector<ChainStep> steps;
  steps.reserve(results.size());
  for (const FrameResult& r : results) steps.push_back(r.step);
  return CheckCalibration(results, steps, false);
}

std::optional<CalibrationCheck> CheckCalibration(const std::vector<FrameResult>& results,
                                                 const std::vector<ChainStep>& steps,
                                                 bool against_world) {
  std::optional<std::size_t> first;
  std::vector<double> nees;
  Vector6d axis_sum = Vector6d::Zero();  // x, y, z, roll, pitch, yaw
  for (std::size_t k = 0; k < results.size() && k < steps.size(); ++k) {
    const FrameResult& r = results[k];
    if (!r.T_world_body_truth) continue;
    Eigen::Isometry3d T_true = *r.T_world_body_truth;
    if (!against_world) {
      if (!first) {
        first = k;
        continue;
      }
      T_true = steps[*first].T_world_body * results[*first].T_world_body_truth->inverse() * T_true;
    }
    const Eigen::Isometry3d D = steps[k].T_world_body.inverse() * T_true;
    const Eigen::AngleAxisd aa(D.linear());
    Eigen::Matrix<double, 6, 1> xi;
    xi << aa.angle() * aa.axis(), D.translation();
    const Eigen::LDLT<Matrix6d> ldlt(steps[k].covariance);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) continue;
    const double value = xi.dot(ldlt.solve(xi));
    if (!std::isfinite(value)) continue;
    nees.push_back(value);
    const Matrix6d J = UserAxesJacobian(steps[k].T_world_body);
    const Vector6d variance = (J * steps[k].covariance * J.transpose()).diagonal();
    axis_sum += (J * xi).cwiseAbs2().cwiseQuotient(variance);
  }
  if (nees.empty()) return std::nullopt;
  CalibrationCheck out;
  out.frames = nees.size();
  double sum = 0.0;
  std::size_t within = 0;
  for (const double v : nees) {
    sum += v;
    within += v <= kChi2Six2Sigma;
  }
  out.within_2sigma = static_cast<double>(within) / static_cast<double>(nees.size());
  out.nees_mean = sum / static_cast<double>(nees.size());
  out.axis_ratio = axis_sum / static_cast<double>(nees.size());
  std::nth_element(nees.begin(), nees.begin() + static_cast<long>(nees.size() / 2), nees.end());
  out.nees_median = nees[nees.size() / 2];
  return out;
}

}  // namespace rovermap::mapper
