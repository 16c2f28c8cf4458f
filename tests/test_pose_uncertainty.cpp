// The chained pose's uncertainty as drift.csv reports it and as ground truth checks it: errors
// drawn from the stated covariance land within 2σ 95 % of the time with a NEES of 6; a
// covariance four times too small (σ halved) is caught.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>

#include "mapper/PoseUncertainty.hpp"

using namespace rovermap::mapper;

namespace {

Eigen::Isometry3d Exp(const Vector6d& xi) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const double angle = xi.head<3>().norm();
  if (angle > 0.0) T.linear() = Eigen::AngleAxisd(angle, xi.head<3>() / angle).matrix();
  T.translation() = xi.tail<3>();
  return T;
}

// A chain of `n` frames driving east and turning slowly, each with covariance `stated`, whose
// true poses differ from the chained ones by errors drawn from `actual`.
std::vector<FrameResult> Chain(std::size_t n, const Matrix6d& stated, const Matrix6d& actual,
                               unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const Eigen::LLT<Matrix6d> llt(actual);
  std::vector<FrameResult> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    FrameResult& r = out[k];
    r.index = k;
    r.step.index = k;
    r.step.T_world_body.linear() = Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d::UnitZ()).matrix();
    r.step.T_world_body.translation() = Eigen::Vector3d(0.5 * k, 0.02 * k * k, 0.1);
    Vector6d xi = Vector6d::Zero();
    if (k > 0) {
      r.step.covariance = stated;
      Vector6d z;
      for (int i = 0; i < 6; ++i) z(i) = unit(rng);
      xi = llt.matrixL() * z;
    }
    r.T_world_body_truth = r.step.T_world_body * Exp(xi);
  }
  return out;
}

Matrix6d Covariance() {
  Vector6d sd;
  sd << 0.002, 0.003, 0.01, 0.05, 0.04, 0.02;  // rad, m
  Matrix6d c = sd.cwiseProduct(sd).asDiagonal();
  c(2, 4) = c(4, 2) = 0.5 * sd(2) * sd(4);  // yaw and lateral position move together
  return c;
}

}  // namespace

TEST(PoseUncertainty, CalibratedCovarianceHoldsTheTruthWithin2Sigma) {
  const auto check = CheckCalibration(Chain(4001, Covariance(), Covariance(), 1));
  ASSERT_TRUE(check.has_value());
  EXPECT_EQ(check->frames, 4000u);
  EXPECT_NEAR(check->within_2sigma, 0.9545, 0.01);
  EXPECT_NEAR(check->nees_mean, 6.0, 0.3);
  EXPECT_NEAR(check->nees_median, 5.35, 0.3);  // χ²₆ median
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(check->axis_ratio(i), 1.0, 0.1) << "axis " << i;
}

TEST(PoseUncertainty, OptimisticCovarianceIsCaught) {
  const auto check = CheckCalibration(Chain(2001, 0.25 * Covariance(), Covariance(), 2));
  ASSERT_TRUE(check.has_value());
  EXPECT_LT(check->within_2sigma, 0.6);
  EXPECT_NEAR(check->nees_mean, 24.0, 2.0);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(check->axis_ratio(i), 4.0, 0.4) << "axis " << i;
}

// One axis too confident behind the others too cautious: the 6-D figures look calibrated, the
// axes do not. The height (the chain turns about z, so body z is world z) stated with half its
// σ, every other axis with twice its σ.
TEST(PoseUncertainty, AxisRatiosFindAnAxisTheWholeHides) {
  const Matrix6d actual = Covariance();
  Vector6d scale = Vector6d::Constant(2.0);
  scale(5) = 0.5;
  const Matrix6d stated = scale.asDiagonal() * actual * scale.asDiagonal();
  const auto check = CheckCalibration(Chain(4001, stated, actual, 4));
  ASSERT_TRUE(check.has_value());
  EXPECT_GT(check->within_2sigma, 0.85);  // the whole passes for calibrated
  EXPECT_NEAR(check->nees_mean, 5.25, 0.4);
  EXPECT_NEAR(check->axis_ratio(2), 4.0, 0.4);  // z: σ half what it should be
  for (const int axis : {0, 1, 3, 4, 5})
    EXPECT_NEAR(check->axis_ratio(axis), 0.25, 0.03) << "axis " << axis;
}

TEST(PoseUncertainty, NoTruthOrSingularCovarianceIsLeftOut) {
  std::vector<FrameResult> results = Chain(5, Covariance(), Covariance(), 3);
  results[2].step.covariance.setZero();  // singular: left out
  results[3].T_world_body_truth.reset();
  const auto check = CheckCalibration(results);
  ASSERT_TRUE(check.has_value());
  EXPECT_EQ(check->frames, 2u);  // frames 1 and 4
  for (auto& r : results) r.T_world_body_truth.reset();
  EXPECT_FALSE(CheckCalibration(results).has_value());
}

TEST(PoseUncertainty, SigmasAreTheCovariancesInWorldAxes) {
  ChainStep step;
  step.T_world_body.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).matrix();
  step.covariance.diagonal() << 1e-4, 4e-4, 9e-4, 0.01, 0.04, 0.09;
  const PoseSigmas s = SigmasOf(step);
  // Body x points north: its σ (0.1 m) is world y's, body y's (0.2 m) world x's.
  EXPECT_NEAR(s.x_m, 0.2, 1e-12);
  EXPECT_NEAR(s.y_m, 0.1, 1e-12);
  EXPECT_NEAR(s.z_m, 0.3, 1e-12);
  EXPECT_NEAR(s.roll_deg, 0.01 * 180 / M_PI, 1e-9);
  EXPECT_NEAR(s.pitch_deg, 0.02 * 180 / M_PI, 1e-9);
  EXPECT_NEAR(s.yaw_deg, 0.03 * 180 / M_PI, 1e-9);
}
