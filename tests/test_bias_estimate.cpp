// Dead reckoning's bias estimate (mapper/BiasEstimate): the information filter against its
// closed form, computed by brute force over every frame at once.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>
#include <vector>

#include "mapper/BiasEstimate.hpp"

namespace rovermap::mapper {
namespace {

// A covariance of these σ (rad, m).
Matrix6d Diagonal(double rotation_sigma, double translation_sigma) {
  Matrix6d c = Matrix6d::Zero();
  c.diagonal() << Eigen::Vector3d::Constant(rotation_sigma * rotation_sigma),
      Eigen::Vector3d::Constant(translation_sigma * translation_sigma);
  return c;
}

// A random symmetric positive semi-definite information of rank `rank`.
Matrix6d RandomInformation(std::mt19937* rng, int rank) {
  std::normal_distribution<double> n(0.0, 1.0);
  Matrix6d m = Matrix6d::Zero();
  for (int i = 0; i < rank; ++i) {
    Vector6d v;
    for (int j = 0; j < 6; ++j) v(j) = n(*rng);
    m += (1.0 + 10.0 * std::abs(n(*rng))) * v * v.transpose();
  }
  return m;
}

Vector6d RandomVector(std::mt19937* rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  Vector6d v;
  for (int j = 0; j < 6; ++j) v(j) = n(*rng);
  return v;
}

struct Frame {
  Vector6d correction;
  Matrix6d information;
};

// b_n = (W_0 + Σ_k (1−α)^{n−k} W_k)⁻¹ Σ_k (1−α)^{n−k} W_k z_k.
Vector6d ClosedForm(const std::vector<Frame>& frames, const Matrix6d& prior, double forgetting) {
  Matrix6d information = prior;
  Vector6d eta = Vector6d::Zero();
  const std::size_t n = frames.size();
  for (std::size_t k = 0; k < n; ++k) {
    const double w = std::pow(1.0 - forgetting, static_cast<double>(n - 1 - k));
    information += w * frames[k].information;
    eta += w * frames[k].information * frames[k].correction;
  }
  return information.ldlt().solve(eta);
}

TEST(BiasEstimate, MatchesTheInformationWeightedMeanWithPriorAndForgetting) {
  std::mt19937 rng(7);
  const Matrix6d wide = Diagonal(1e3, 1e3);  // a model so loose that the bound never acts
  for (const double forgetting : {0.0, 0.02, 0.3}) {
    for (const double prior_scale : {1e-3, 1.0, 50.0}) {
      const Matrix6d prior = prior_scale * Matrix6d::Identity();
      std::vector<Frame> frames;
      BiasEstimate estimate;
      for (int k = 0; k < 40; ++k) {
        frames.push_back({RandomVector(&rng, 0.1), RandomInformation(&rng, 1 + k % 6)});
        estimate = UpdateBias(estimate, frames.back().correction, frames.back().information, prior,
                              forgetting, wide);
      }
      const Vector6d expected = ClosedForm(frames, prior, forgetting);
      EXPECT_LT((estimate.bias - expected).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + expected.norm()))
          << "forgetting " << forgetting << ", prior " << prior_scale;
    }
  }
}

// The weighting is the point: on gently rolling ground a frame's weak yaw is a degree off and
// its information says so. One such frame must not pull the estimate as a precise one does.
TEST(BiasEstimate, ANoisyCorrectionMovesTheEstimateLessThanAPreciseOne) {
  const Matrix6d odometry = Diagonal(0.01, 0.02);
  const Matrix6d prior = (0.07 * 0.07 * odometry).inverse();
  Vector6d yaw_correction = Vector6d::Zero();
  yaw_correction(2) = 0.004;  // rad
  Matrix6d precise = Matrix6d::Zero();
  precise(2, 2) = 1.0 / (0.0005 * 0.0005);  // σ 0.03°
  Matrix6d noisy = Matrix6d::Zero();
  noisy(2, 2) = 1.0 / (0.02 * 0.02);  // σ 1.1°
  const BiasEstimate from_precise = UpdateBias({}, yaw_correction, precise, prior, 0.02, odometry);
  const BiasEstimate from_noisy = UpdateBias({}, yaw_correction, noisy, prior, 0.02, odometry);
  EXPECT_GT(from_precise.bias(2), 0.5 * yaw_correction(2));
  EXPECT_LT(from_noisy.bias(2), 0.01 * yaw_correction(2));
  EXPECT_GT(from_noisy.bias(2), 0.0);
  // Only the informed direction moves.
  EXPECT_EQ(from_precise.bias(3), 0.0);
  // Many precise frames that agree: the estimate reaches their mean.
  BiasEstimate many;
  for (int k = 0; k < 50; ++k)
    many = UpdateBias(many, yaw_correction, precise, prior, 0.02, odometry);
  EXPECT_NEAR(many.bias(2), yaw_correction(2), 0.05 * yaw_correction(2));
}

TEST(BiasEstimate, NoInformationOrNonFiniteInputLeavesItAsItIs) {
  BiasEstimate start;
  start.bias << 0.001, 0, 0.002, 0.003, 0, 0;
  start.information = 5.0 * Matrix6d::Identity();
  const Matrix6d prior = Matrix6d::Identity();
  const Matrix6d odometry = Diagonal(0.1, 0.1);
  const Vector6d z = Vector6d::Constant(0.01);
  const BiasEstimate none = UpdateBias(start, z, Matrix6d::Zero(), prior, 0.02, odometry);
  EXPECT_EQ(none.bias, start.bias);
  EXPECT_EQ(none.information, start.information);
  Vector6d nan = z;
  nan(1) = std::nan("");
  EXPECT_EQ(UpdateBias(start, nan, Matrix6d::Identity(), prior, 0.02, odometry).bias, start.bias);
  const Matrix6d infinite_prior = Matrix6d::Identity() / 0.0;
  EXPECT_EQ(UpdateBias(start, z, Matrix6d::Identity(), infinite_prior, 0.02, odometry).bias,
            start.bias);
}

TEST(BiasEstimate, StaysWithinDeadReckoningsErrorModel) {
  const Matrix6d odometry = Diagonal(0.01, 0.02);
  Vector6d small;
  small << 0.001, 0, 0.002, 0.005, 0, 0;
  EXPECT_EQ(BoundedBias(small, odometry), small);
  Vector6d large;
  large << 0, 0, 0.03, 0.04, 0, 0;  // 5σ: shrunk onto the 1σ ellipsoid, same direction
  const Vector6d bounded = BoundedBias(large, odometry);
  EXPECT_NEAR(bounded.dot(odometry.inverse() * bounded), 1.0, 1e-12);
  EXPECT_NEAR(bounded(2) / bounded(3), 0.75, 1e-12);
  EXPECT_EQ(BoundedBias(large, Matrix6d::Zero()), large);  // no model: left alone
  // Through the update: corrections far beyond the model, precisely measured, still end on
  // the ellipsoid.
  BiasEstimate e;
  for (int k = 0; k < 20; ++k) {
    e = UpdateBias(e, large * 3.0, 1e6 * Matrix6d::Identity(), Matrix6d::Identity(), 0.02,
                   odometry);
  }
  EXPECT_NEAR(e.bias.dot(odometry.inverse() * e.bias), 1.0, 1e-9);
}

}  // namespace
}  // namespace rovermap::mapper
