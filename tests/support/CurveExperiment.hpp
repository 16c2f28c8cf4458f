#pragma once
// Zhang 1994, §8 ("synthetic data"), rebuilt from the paper's description: a space curve of
// 200 points, a known rigid motion, Gaussian noise of standard deviation σ up to 8 cm added
// to both point sets, and the mean relative errors of the estimated rotation vector and
// translation over many noise draws, for the non-symmetric and the symmetric criterion.
// The paper's own curve, motion and initial estimate are not reproduced here (not found):
// the curve is a trefoil knot 3.9 m across (a non-planar closed curve along which nothing
// slides), sampled every 9.4 cm; both sets are the same samples, the source moved by the
// inverse motion, each with its own noise (noise-free, the answer is exact: with samples
// half a step apart, point-to-point pairing alone left 1.3° on a coarse sampling). The
// knot's size is the one free choice: at 3.9 m the paper's configuration (Θ = 45° plain
// test) gives 11.5 % and 9.2 % at σ = 8 cm, the paper's 11.35 % and 8.52 %, and test-off
// 7.9 % and 6.6 % (an earlier rebuild of the experiment measured 11.4 / 9.6 % and 7.8 /
// 5.7 %); at 1.2 m across the test-off errors were 3.4× larger, at 6 m 1.8× smaller.
// Used by tests/test_icp_curves.cpp and bench/bench_curves.cpp.

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "registration/Icp.hpp"
#include "registration/Options.hpp"

namespace rovermap::testing {

/// The motion of the experiment: a 17° rotation about a skew axis and 46 cm of translation.
inline Eigen::Isometry3d ZhangCurveMotion() {
  const Eigen::Vector3d r(0.05, 0.25, -0.15);  // rotation vector [rad]
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.20, 0.40, 0.10);  // [m]
  return T;
}

/// One draw: target = the curve, source = the curve in the source frame (T⁻¹ · curve), both
/// `points` samples with per-axis Gaussian noise `sigma_m`, one chain each.
inline void MakeZhangCurvePair(double sigma_m, unsigned seed, registration::PointCloud* source,
                               registration::PointCloud* target, int points = 200) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_m);
  const Eigen::Isometry3d T_source_target = ZhangCurveMotion().inverse();
  auto curve = [](double s) {  // [m]
    return Eigen::Vector3d(0.65 * (std::sin(s) + 2 * std::sin(2 * s)),
                           0.65 * (std::cos(s) - 2 * std::cos(2 * s)), -0.65 * std::sin(3 * s));
  };
  *source = registration::PointCloud{};
  *target = registration::PointCloud{};
  const double step = 2 * M_PI / points;
  for (int side = 0; side < 2; ++side) {
    registration::PointCloud& cloud = side == 0 ? *target : *source;
    for (int k = 0; k < points; ++k) {
      Eigen::Vector3d p = curve(k * step);
      if (side == 1) p = T_source_target * p;
      p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      cloud.points.push_back(p);
      cloud.chain_ids.push_back(0);
    }
  }
}

struct CurveExperimentResult {
  double rotation_error = 0.0;     ///< mean ‖r̂ − r‖ / ‖r‖ (rotation vectors)
  double translation_error = 0.0;  ///< mean ‖t̂ − t‖ / ‖t‖
  int failures = 0;  ///< registrations whose status was neither converged nor max_iterations
};

/// The initial estimate: the motion off by 5° and 5 cm (a rover's odometry seed; from the
/// identity, 17° and 46 cm away, the matcher often settles on a wrong alignment of the knot).
inline Eigen::Isometry3d ZhangCurveInitialEstimate() {
  Eigen::Isometry3d T = ZhangCurveMotion();
  T.linear() =
      Eigen::AngleAxisd(5.0 * M_PI / 180.0, Eigen::Vector3d(1, 2, 3).normalized()) * T.linear();
  T.translation() += 0.05 * Eigen::Vector3d(2, -1, 1).normalized();
  return T;
}

/// The mean relative errors over `trials` draws (seeds first_seed, first_seed + 1, ...),
/// each registered from ZhangCurveInitialEstimate().
inline CurveExperimentResult RunZhangCurveExperiment(
    const registration::RegistrationOptions& options, double sigma_m, int trials,
    unsigned first_seed = 1) {
  const Eigen::Isometry3d truth = ZhangCurveMotion();
  const Eigen::AngleAxisd true_aa(truth.linear());
  const Eigen::Vector3d r_true = true_aa.angle() * true_aa.axis();
  CurveExperimentResult out;
  for (int k = 0; k < trials; ++k) {
    registration::PointCloud source, target;
    MakeZhangCurvePair(sigma_m, first_seed + static_cast<unsigned>(k), &source, &target);
    const registration::RegistrationResult r =
        registration::Register(source, target, ZhangCurveInitialEstimate(), options);
    if (r.status != registration::RegistrationStatus::kConverged &&
        r.status != registration::RegistrationStatus::kMaxIterations)
      ++out.failures;
    const Eigen::AngleAxisd aa(r.T_target_source.linear());
    const Eigen::Vector3d r_est = aa.angle() * aa.axis();
    out.rotation_error += (r_est - r_true).norm() / r_true.norm();
    out.translation_error +=
        (r.T_target_source.translation() - truth.translation()).norm() / truth.translation().norm();
  }
  out.rotation_error /= trials;
  out.translation_error /= trials;
  return out;
}

}  // namespace rovermap::testing
