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

PoseSigmas SigmasOf(const ChainStep& step) {
  const Eigen::Matrix3d R = step.T_world_body.linear();
  const Eigen::Matrix3d position = R * step.covariance.bottomRightCorner<3, 3>() * R.transpose();
  const Eigen::Matrix3d attitude_world = R * step.covariance.topLeftCorner<3, 3>() * R.transpose();
  auto sd = [](double variance) { return std::sqrt(std::max(0.0, variance)); };
  PoseSigmas s;
  s.x_m = sd(position(0, 0));
  s.y_m = sd(position(1, 1));
  s.z_m = sd(position(2, 2));
  s.roll_deg = sd(step.covariance(0, 0)) * kRadToDeg;
  s.pitch_deg = sd(step.covariance(1, 1)) * kRadToDeg;
  s.yaw_deg = sd(attitude_world(2, 2)) * kRadToDeg;
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
    if (std::isfinite(value)) nees.push_back(value);
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
  std::nth_element(nees.begin(), nees.begin() + static_cast<long>(nees.size() / 2), nees.end());
  out.nees_median = nees[nees.size() / 2];
  return out;
}

}  // namespace rovermap::mapper
