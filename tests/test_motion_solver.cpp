// Closed-form motion: both solvers recover known transforms exactly, agree on noisy
// weighted data, and never return a reflection.
#include <gtest/gtest.h>

#include <random>

#include "registration/MotionSolver.hpp"

using namespace rovermap::registration;

namespace {

Eigen::Isometry3d RandomTransform(std::mt19937& rng, double max_angle) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Vector3d axis(u(rng), u(rng), u(rng));
  axis.normalize();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(max_angle * std::abs(u(rng)), axis).toRotationMatrix();
  T.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 3.0;
  return T;
}

std::vector<WeightedPair> MakePairs(const std::vector<Eigen::Vector3d>& src,
                                    const Eigen::Isometry3d& T) {
  std::vector<WeightedPair> pairs;
  for (const auto& x : src) pairs.push_back({x, T * x, 1.0});
  return pairs;
}

double RotationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle();
}

void ExpectProperRotation(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d r = T.linear();
  EXPECT_NEAR(r.determinant(), 1.0, 1e-9);
  EXPECT_TRUE((r * r.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-9));
}

using SolverFn = MotionEstimate (*)(const std::vector<WeightedPair>&);

class BothSolvers : public ::testing::TestWithParam<SolverFn> {};

}  // namespace

TEST_P(BothSolvers, RecoversKnownTransformExactly) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<Eigen::Vector3d> src(20 + trial);
    for (auto& x : src) x = Eigen::Vector3d(u(rng), u(rng), u(rng));
    // Up to 179°: the dual-quaternion eigenvector and the SVD must both handle it.
    const Eigen::Isometry3d T = RandomTransform(rng, M_PI * 0.995);
    const MotionEstimate est = GetParam()(MakePairs(src, T));
    ASSERT_TRUE(est.valid);
    EXPECT_LT(RotationError(est.T_target_source, T), 1e-9);
    EXPECT_LT((est.T_target_source.translation() - T.translation()).norm(), 1e-9);
    ExpectProperRotation(est.T_target_source);
  }
}

TEST_P(BothSolvers, NoReflectionOnPlanarAndDegenerateInput) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (int trial = 0; trial < 30; ++trial) {
    const Eigen::Isometry3d T = RandomTransform(rng, M_PI * 0.9);
    // Planar source, noisy target: the unguarded SVD often returns a reflection here.
    std::vector<WeightedPair> planar;
    for (int i = 0; i < 30; ++i) {
      const Eigen::Vector3d x(u(rng), u(rng), 0.0);
      planar.push_back({x, T * x + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)), 1.0});
    }
    const MotionEstimate p = GetParam()(planar);
    ASSERT_TRUE(p.valid);
    ExpectProperRotation(p.T_target_source);
    // Noise-free planar input is still recovered exactly (a plane fixes the rotation).
    std::vector<WeightedPair> clean;
    for (const auto& pr : planar) clean.push_back({pr.source, T * pr.source, 1.0});
    const MotionEstimate c = GetParam()(clean);
    EXPECT_LT(RotationError(c.T_target_source, T), 1e-8);
    // Collinear and near-collinear input: rotation about the line is undetermined,
    // but the result must be a proper rotation mapping the line correctly.
    std::vector<WeightedPair> line;
    for (int i = 0; i < 10; ++i) {
      const Eigen::Vector3d x(0.1 * i, 0.2 * i + 1e-9 * (i % 2), 0.05 * i);
      line.push_back({x, T * x, 1.0});
    }
    const MotionEstimate l = GetParam()(line);
    ASSERT_TRUE(l.valid);
    ExpectProperRotation(l.T_target_source);
    for (const auto& pr : line) EXPECT_LT((l.T_target_source * pr.source - pr.target).norm(), 1e-6);
  }
}

TEST_P(BothSolvers, WeightsActLikeRepetition) {
  // Weight 3 on a pair = that pair three times.
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  const Eigen::Isometry3d T = RandomTransform(rng, 1.0);
  std::vector<WeightedPair> weighted, repeated;
  for (int i = 0; i < 40; ++i) {
    const Eigen::Vector3d x(u(rng), u(rng), u(rng));
    const Eigen::Vector3d y = T * x + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    const int w = 1 + i % 3;
    weighted.push_back({x, y, static_cast<double>(w)});
    for (int k = 0; k < w; ++k) repeated.push_back({x, y, 1.0});
  }
  const MotionEstimate a = GetParam()(weighted);
  const MotionEstimate b = GetParam()(repeated);
  EXPECT_TRUE(a.T_target_source.isApprox(b.T_target_source, 1e-9));
}

TEST_P(BothSolvers, RejectsInvalidInput) {
  const Eigen::Vector3d x(1, 2, 3);
  EXPECT_FALSE(GetParam()({}).valid);
  EXPECT_FALSE(GetParam()({{x, x, 1.0}, {x, x, 1.0}}).valid);
  EXPECT_FALSE(GetParam()({{x, x, 0.0}, {x, x, 0.0}, {x, x, 0.0}}).valid);
  const Eigen::Vector3d nan(std::nan(""), 0, 0);
  EXPECT_FALSE(GetParam()({{x, x, 1.0}, {nan, x, 1.0}, {x, x, 1.0}}).valid);
}

INSTANTIATE_TEST_SUITE_P(Solvers, BothSolvers,
                         ::testing::Values(&SolveMotionSvd, &SolveMotionDualQuaternion));

TEST(MotionSolver, SvdAndDualQuaternionAgreeOnNoisyWeightedData) {
  std::mt19937 rng(10);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  std::uniform_real_distribution<double> w(0.1, 5.0);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Isometry3d T = RandomTransform(rng, 2.5);
    std::vector<WeightedPair> pairs;
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector3d x(u(rng), u(rng), u(rng));
      pairs.push_back({x, T * x + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)), w(rng)});
    }
    const MotionEstimate svd = SolveMotionSvd(pairs);
    const MotionEstimate dq = SolveMotionDualQuaternion(pairs);
    ASSERT_TRUE(svd.valid && dq.valid);
    // Both minimise the same weighted cost: identical to rounding.
    EXPECT_LT(RotationError(svd.T_target_source, dq.T_target_source), 1e-10);
    EXPECT_LT((svd.T_target_source.translation() - dq.T_target_source.translation()).norm(), 1e-10);
  }
}
