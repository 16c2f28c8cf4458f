// The absolute-attitude prior: roll and pitch pulled towards dead reckoning's by a scalar
// Kalman gain, yaw and position untouched, off when its sigma is 0.
#include <gtest/gtest.h>

#include <cmath>

#include "core/Units.hpp"
#include "mapper/AttitudePrior.hpp"
#include "io/Rpy.hpp"
#include "mapper/PoseChain.hpp"

using namespace rovermap::mapper;
using rovermap::io::RotationFromRpy;

namespace {

constexpr double kDeg = rovermap::core::kDegToRad;

Eigen::Isometry3d Pose(double roll_deg, double pitch_deg, double yaw_deg) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = RotationFromRpy(Eigen::Vector3d(roll_deg, pitch_deg, yaw_deg) * kDeg);
  T.translation() = Eigen::Vector3d(3.0, -1.0, 0.5);
  return T;
}

// The registered increment's roll and pitch variances are raised to the step's σ², never
// lowered; yaw, translation and the cross terms stay the registration's.
TEST(FloorAttitudeVariance, RaisesRollAndPitchOnly) {
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Identity() * 1e-8;
  cov(0, 1) = cov(1, 0) = 2e-9;
  cov(1, 1) = 1.0;  // already above the floor
  const Eigen::Matrix<double, 6, 6> before = cov;
  FloorAttitudeVariance(&cov, 0.05);
  const double floor = std::pow(0.05 * M_PI / 180.0, 2.0);
  EXPECT_DOUBLE_EQ(cov(0, 0), floor);
  EXPECT_DOUBLE_EQ(cov(1, 1), 1.0);
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      if (i != j || i > 1) {
        EXPECT_EQ(cov(i, j), before(i, j)) << i << "," << j;
      }
    }
  }
  FloorAttitudeVariance(&cov, 0.0);  // 0 = the registration's covariance alone
  EXPECT_DOUBLE_EQ(cov(0, 0), floor);
}
}  // namespace

TEST(AttitudePrior, OffLeavesThePoseAlone) {
  AttitudePrior off(0.0, 0.05);
  EXPECT_FALSE(off.enabled());
  const Eigen::Isometry3d T = Pose(1.0, -2.0, 30.0);
  EXPECT_TRUE(off.Update(T, Pose(0.0, 0.0, 0.0)).isApprox(T));
}

TEST(AttitudePrior, KalmanGainOnRollAndPitchOnly) {
  // σ_odometry 0.2°, σ_step 0.1°: first gain 0.01 / (0.01 + 0.04) = 0.2.
  AttitudePrior prior(0.2, 0.1);
  const Eigen::Isometry3d chained = Pose(1.0, -1.0, 45.0);
  const Eigen::Isometry3d odometry = Pose(0.0, 0.0, 10.0);
  const Eigen::Isometry3d T = prior.Update(chained, odometry);
  const Eigen::Vector3d rpy = EulerRpyFromRotation(T.linear()) / kDeg;
  EXPECT_NEAR(rpy.x(), 0.8, 1e-9);
  EXPECT_NEAR(rpy.y(), -0.8, 1e-9);
  EXPECT_NEAR(rpy.z(), 45.0, 1e-9);  // yaw is the registration's
  EXPECT_TRUE(T.translation().isApprox(chained.translation()));
  EXPECT_NEAR(prior.variance(), 0.8 * 0.01 * kDeg * kDeg, 1e-15);
  // The gain settles: a chain that keeps its 1° roll error converges to dead reckoning's.
  Eigen::Isometry3d drifting = T;
  for (int k = 0; k < 200; ++k) drifting = prior.Update(drifting, odometry);
  EXPECT_NEAR(EulerRpyFromRotation(drifting.linear()).x() / kDeg, 0.0, 1e-3);
}
