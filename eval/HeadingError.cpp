#include "eval/HeadingError.hpp"

#include <cmath>

namespace rovermap::eval {

double YawDeg(const Eigen::Matrix3d& R) { return std::atan2(R(1, 0), R(0, 0)) * 180.0 / M_PI; }

HeadingErrors CompareHeadings(const std::vector<Eigen::Isometry3d>& estimate,
                              const std::vector<Eigen::Isometry3d>& truth) {
  HeadingErrors out;
  if (estimate.size() != truth.size() || truth.size() < 2) return out;
  double sum = 0.0, sum_sq = 0.0;
  for (std::size_t i = 1; i < truth.size(); ++i) {
    const Eigen::Isometry3d step_est = estimate[i - 1].inverse() * estimate[i];
    const Eigen::Isometry3d step_true = truth[i - 1].inverse() * truth[i];
    const double e = YawDeg(step_true.linear().transpose() * step_est.linear());
    out.per_frame_deg.push_back(e);
    sum += e;
    sum_sq += e * e;
  }
  const auto n = static_cast<double>(out.per_frame_deg.size());
  out.mean_deg = sum / n;
  out.rms_deg = std::sqrt(sum_sq / n);
  out.final_deg = YawDeg(truth.back().linear().transpose() * estimate.back().linear());
  return out;
}

}  // namespace rovermap::eval
