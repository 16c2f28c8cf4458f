// Pose chaining and drift corrections: exact odometry gives zero correction, a known odometry
// bias corrected by exact increments recovers ground truth and the accumulated bias,
// fallbacks follow dead reckoning, and the roll-pitch-yaw helpers round-trip.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>
#include <vector>

#include "core/Units.hpp"
#include "io/Rpy.hpp"
#include "mapper/PoseChain.hpp"

using namespace rovermap::mapper;
using rovermap::io::RotationFromRpy;

namespace {

constexpr double kPi = rovermap::core::kPi;
constexpr double kDeg = rovermap::core::kDegToRad;

Eigen::Isometry3d MakePose(const Eigen::Vector3d& rpy_rad, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = RotationFromRpy(rpy_rad);
  T.translation() = t;
  return T;
}

// Elementary rotations written out, as an oracle independent of Eigen's AngleAxis.
Eigen::Matrix3d Rx(double a) {
  Eigen::Matrix3d m;
  m << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  return m;
}
Eigen::Matrix3d Ry(double a) {
  Eigen::Matrix3d m;
  m << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  return m;
}
Eigen::Matrix3d Rz(double a) {
  Eigen::Matrix3d m;
  m << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return m;
}

double AngleDiff(double a, double b) { return std::remainder(a - b, 2.0 * kPi); }

double PoseError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

// A rover-like increment: forward 0.2-1 m, small lateral and vertical motion and rotations.
Eigen::Isometry3d RandomIncrement(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return MakePose(Eigen::Vector3d(3.0 * u(rng), 3.0 * u(rng), 10.0 * u(rng)) * kDeg,
                  Eigen::Vector3d(0.6 + 0.4 * u(rng), 0.1 * u(rng), 0.05 * u(rng)));
}

// The biased dead-reckoning increment of a true one: 1 % long on x, 0.5° extra yaw.
Eigen::Isometry3d Biased(const Eigen::Isometry3d& truth) {
  Eigen::Isometry3d odom = truth;
  odom.translation().x() *= 1.01;
  odom.linear() = truth.linear() * Rz(0.5 * kDeg);
  return odom;
}

}  // namespace

TEST(EulerRpy, MatchesTheDesignConvention) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-kPi, kPi);
  for (int i = 0; i < 200; ++i) {
    const double r = u(rng), p = u(rng) / 2.0, y = u(rng);
    const Eigen::Matrix3d expected = Rz(y) * Ry(p) * Rx(r);
    EXPECT_LT((RotationFromRpy({r, p, y}) - expected).cwiseAbs().maxCoeff(), 1e-14);
  }
  // Positive yaw turns x towards y; positive pitch turns x down (towards −z) about y.
  EXPECT_TRUE((RotationFromRpy({0, 0, 90 * kDeg}) * Eigen::Vector3d::UnitX())
                  .isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_TRUE((RotationFromRpy({0, 30 * kDeg, 0}) * Eigen::Vector3d::UnitX()).z() < 0.0);
  // docs/design.md §4: a level, forward-looking OpenCV camera is rpy [-90, 0, -90].
  const Eigen::Matrix3d R_body_camera = RotationFromRpy({-90 * kDeg, 0, -90 * kDeg});
  EXPECT_TRUE((R_body_camera * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE(
      (R_body_camera * Eigen::Vector3d::UnitX()).isApprox(-Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_TRUE(
      (R_body_camera * Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d::UnitZ(), 1e-12));
  const Eigen::Vector3d rpy = EulerRpyFromRotation(R_body_camera) / kDeg;
  EXPECT_NEAR(rpy.x(), -90.0, 1e-9);
  EXPECT_NEAR(rpy.y(), 0.0, 1e-9);
  EXPECT_NEAR(rpy.z(), -90.0, 1e-9);
}

TEST(EulerRpy, RoundTripAwayFromGimbalLock) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> angle(-180.0, 180.0);
  std::uniform_real_distribution<double> pitch(-89.0, 89.0);
  for (int i = 0; i < 5000; ++i) {
    const Eigen::Vector3d rpy(angle(rng) * kDeg, pitch(rng) * kDeg, angle(rng) * kDeg);
    const Eigen::Vector3d back = EulerRpyFromRotation(RotationFromRpy(rpy));
    EXPECT_NEAR(AngleDiff(back.x(), rpy.x()), 0.0, 1e-10) << i;
    EXPECT_NEAR(back.y(), rpy.y(), 1e-10) << i;
    EXPECT_NEAR(AngleDiff(back.z(), rpy.z()), 0.0, 1e-10) << i;
    EXPECT_LE(std::abs(back.x()), kPi);
    EXPECT_LE(std::abs(back.z()), kPi);
  }
}

TEST(EulerRpy, AnyRotationIsRebuilt) {
  // Uniform random rotations plus pitches within 1e-4 .. 1e-13 rad of ±90°.
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::vector<Eigen::Matrix3d> rotations;
  for (int i = 0; i < 2000; ++i) {
    rotations.push_back(
        Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix());
  }
  // Near gimbal lock, built through quaternions so that the small entries carry absolute
  // rounding noise as real data does: atan2 of two such entries alone would be far off.
  for (double offset : {1e-4, 1e-7, 1e-9, 1e-10, 1e-11, 1e-13, 0.0}) {
    for (double sign : {1.0, -1.0}) {
      const Eigen::Quaterniond q =
          Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(sign * (kPi / 2 - offset), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitX());
      rotations.push_back(q.toRotationMatrix());
    }
  }
  for (const Eigen::Matrix3d& R : rotations) {
    const Eigen::Vector3d rpy = EulerRpyFromRotation(R);
    EXPECT_LT((RotationFromRpy(rpy) - R).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LE(std::abs(rpy.y()), kPi / 2);
  }
}

TEST(EulerRpy, GimbalLockPutsEverythingInYaw) {
  for (double sign : {1.0, -1.0}) {
    const double roll = 30 * kDeg, yaw = 20 * kDeg;
    const Eigen::Matrix3d R = RotationFromRpy({roll, sign * kPi / 2, yaw});
    const Eigen::Vector3d rpy = EulerRpyFromRotation(R);
    EXPECT_EQ(rpy.x(), 0.0);
    EXPECT_NEAR(rpy.y(), sign * kPi / 2, 1e-12);
    // +90°: only yaw − roll is defined; −90°: only yaw + roll.
    EXPECT_NEAR(AngleDiff(rpy.z(), yaw - sign * roll), 0.0, 1e-12);
    EXPECT_LT((RotationFromRpy(rpy) - R).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(EulerRpy, NonFiniteGivesNonFinite) {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  R(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(EulerRpyFromRotation(R).allFinite());
}

TEST(CorrectionComponents, TranslationInMetresAnglesInDegrees) {
  const Eigen::Isometry3d T = MakePose(Eigen::Vector3d(10, -20, 30) * kDeg, {1.0, -2.0, 3.0});
  const TransformComponents c = CorrectionComponents(T);
  EXPECT_DOUBLE_EQ(c.dx_m, 1.0);
  EXPECT_DOUBLE_EQ(c.dy_m, -2.0);
  EXPECT_DOUBLE_EQ(c.dz_m, 3.0);
  EXPECT_NEAR(c.droll_deg, 10.0, 1e-10);
  EXPECT_NEAR(c.dpitch_deg, -20.0, 1e-10);
  EXPECT_NEAR(c.dyaw_deg, 30.0, 1e-10);
}

TEST(IsFiniteRigid, RejectsNonRigidAndNonFinite) {
  EXPECT_TRUE(IsFiniteRigid(Eigen::Isometry3d::Identity()));
  EXPECT_TRUE(IsFiniteRigid(MakePose({1, 2, 3}, {4, 5, 6})));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().x() = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(IsFiniteRigid(T));
  T = Eigen::Isometry3d::Identity();
  T.linear()(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(IsFiniteRigid(T));
  T = Eigen::Isometry3d::Identity();
  T.linear() *= 1.01;  // scaled
  EXPECT_FALSE(IsFiniteRigid(T));
  T = Eigen::Isometry3d::Identity();
  T.linear()(2, 2) = -1.0;  // reflection
  EXPECT_FALSE(IsFiniteRigid(T));
}

TEST(PoseChain, ExactOdometryGivesZeroCorrection) {
  std::mt19937 rng(4);
  const Eigen::Isometry3d T0 = MakePose(Eigen::Vector3d(2, -3, 40) * kDeg, {10.0, -5.0, 2.0});
  PoseChain chain(T0);
  ASSERT_EQ(chain.size(), 1u);
  EXPECT_EQ(chain.back().index, 0u);
  EXPECT_FALSE(chain.back().fallback);
  EXPECT_LT(PoseError(chain.back().T_world_body, T0), 1e-15);
  EXPECT_LT(PoseError(chain.back().cumulative_correction, Eigen::Isometry3d::Identity()), 1e-15);

  Eigen::Isometry3d T_odom = T0;
  double length = 0.0;
  for (std::size_t k = 1; k <= 200; ++k) {
    const Eigen::Isometry3d inc = RandomIncrement(rng);
    const Eigen::Isometry3d T_prev_odom = T_odom;
    T_odom = T_odom * inc;
    length += inc.translation().norm();
    // The registration seed is the odometry increment.
    EXPECT_LT(PoseError(chain.PredictIncrement(T_odom), T_prev_odom.inverse() * T_odom), 1e-15);
    const ChainStep step = chain.Add(T_odom, T_prev_odom.inverse() * T_odom);
    EXPECT_EQ(step.index, k);
    EXPECT_FALSE(step.fallback);
    EXPECT_LT(PoseError(step.T_world_body, T_odom), 1e-9);
    EXPECT_LT(PoseError(step.T_world_body_odom, T_odom), 1e-15);
    EXPECT_LT(PoseError(step.increment_correction, Eigen::Isometry3d::Identity()), 1e-12);
    EXPECT_LT(PoseError(step.cumulative_correction, Eigen::Isometry3d::Identity()), 1e-9);
    const TransformComponents c = CorrectionComponents(step.cumulative_correction);
    for (double v : {c.dx_m, c.dy_m, c.dz_m, c.droll_deg, c.dpitch_deg, c.dyaw_deg}) {
      EXPECT_NEAR(v, 0.0, 1e-7);
    }
  }
  EXPECT_EQ(chain.size(), 201u);
  EXPECT_EQ(chain.fallbacks(), 0u);
  EXPECT_NEAR(chain.path_length_m(), length, 1e-9);
}

TEST(PoseChain, BiasedOdometryOnAStraightLineMatchesTheClosedForm) {
  // Truth: 1 m steps along body x without turning. Odometry: 1.01 m and 0.5° left per step,
  // so it walks a circle; its error after k steps is known in closed form.
  const Eigen::Isometry3d T0 = MakePose(Eigen::Vector3d(0, 0, 25) * kDeg, {3.0, 4.0, -1.0});
  const double delta = 0.5 * kDeg;
  Eigen::Isometry3d truth_inc = Eigen::Isometry3d::Identity();
  truth_inc.translation().x() = 1.0;
  PoseChain chain(T0);
  Eigen::Isometry3d T_odom = T0, T_true = T0;
  for (int k = 1; k <= 100; ++k) {
    T_odom = T_odom * Biased(truth_inc);
    T_true = T_true * truth_inc;
    const ChainStep step = chain.Add(T_odom, truth_inc);
    EXPECT_LT(PoseError(step.T_world_body, T_true), 1e-9) << k;

    // Odometry relative to T0: heading k·δ, position Σ_{j<k} 1.01·(cos jδ, sin jδ).
    double ox = 0.0, oy = 0.0;
    for (int j = 0; j < k; ++j) {
      ox += 1.01 * std::cos(j * delta);
      oy += 1.01 * std::sin(j * delta);
    }
    const double ex = k - ox, ey = -oy, heading = k * delta;
    const TransformComponents cum = CorrectionComponents(step.cumulative_correction);
    EXPECT_NEAR(cum.dx_m, std::cos(heading) * ex + std::sin(heading) * ey, 1e-9) << k;
    EXPECT_NEAR(cum.dy_m, -std::sin(heading) * ex + std::cos(heading) * ey, 1e-9) << k;
    EXPECT_NEAR(cum.dz_m, 0.0, 1e-9);
    EXPECT_NEAR(cum.droll_deg, 0.0, 1e-9);
    EXPECT_NEAR(cum.dpitch_deg, 0.0, 1e-9);
    EXPECT_NEAR(cum.dyaw_deg, -0.5 * k, 1e-9) << k;

    // Each step undoes one step's bias: 0.5° right and 1 cm back, seen from the odometry body.
    const TransformComponents inc = CorrectionComponents(step.increment_correction);
    EXPECT_NEAR(inc.dx_m, -0.01 * std::cos(delta), 1e-12);
    EXPECT_NEAR(inc.dy_m, 0.01 * std::sin(delta), 1e-12);
    EXPECT_NEAR(inc.dz_m, 0.0, 1e-12);
    EXPECT_NEAR(inc.dyaw_deg, -0.5, 1e-10);
  }
  EXPECT_NEAR(chain.path_length_m(), 100.0, 1e-9);
}

TEST(PoseChain, BiasedOdometryIn3dRecoversGroundTruth) {
  std::mt19937 rng(5);
  const Eigen::Isometry3d T0 = MakePose(Eigen::Vector3d(-4, 6, -120) * kDeg, {-50.0, 20.0, 7.0});
  PoseChain chain(T0);
  Eigen::Isometry3d T_odom = T0, T_true = T0;
  for (int k = 1; k <= 300; ++k) {
    const Eigen::Isometry3d truth_inc = RandomIncrement(rng);
    const Eigen::Isometry3d odom_inc = Biased(truth_inc);
    T_odom = T_odom * odom_inc;
    T_true = T_true * truth_inc;
    const ChainStep prev = chain.back();
    const ChainStep step = chain.Add(T_odom, truth_inc);
    EXPECT_LT(PoseError(step.T_world_body, T_true), 1e-9) << k;
    EXPECT_LT(PoseError(step.odom_increment, odom_inc), 1e-9) << k;
    EXPECT_LT(PoseError(step.used_increment, truth_inc), 1e-15) << k;
    // The accumulated bias: the true pose seen from the odometry pose.
    EXPECT_LT(PoseError(step.cumulative_correction, T_odom.inverse() * T_true), 1e-9) << k;
    // Corrections compose: C_k = o_k⁻¹ · C_{k−1} · o_k · c_k.
    const Eigen::Isometry3d composed =
        odom_inc.inverse() * prev.cumulative_correction * odom_inc * step.increment_correction;
    EXPECT_LT(PoseError(step.cumulative_correction, composed), 1e-9) << k;
  }
  // After 300 steps the yaw bias alone is 150°: the correction is large and well away from 0.
  EXPECT_GT(chain.back().cumulative_correction.translation().norm(), 10.0);
}

TEST(PoseChain, FallbackStepsFollowOdometryAndAreFlagged) {
  std::mt19937 rng(6);
  const Eigen::Isometry3d T0 = MakePose(Eigen::Vector3d(1, 1, 10) * kDeg, {0.0, 0.0, 0.0});
  PoseChain chain(T0);
  Eigen::Isometry3d T_odom = T0;
  Eigen::Isometry3d bad_nan = Eigen::Isometry3d::Identity();
  bad_nan.translation().y() = std::numeric_limits<double>::quiet_NaN();
  Eigen::Isometry3d bad_scale = Eigen::Isometry3d::Identity();
  bad_scale.linear() *= 2.0;
  std::size_t expected_fallbacks = 0;
  double expected_length = 0.0;
  for (std::size_t k = 1; k <= 60; ++k) {
    const Eigen::Isometry3d truth_inc = RandomIncrement(rng);
    const Eigen::Isometry3d odom_inc = Biased(truth_inc);
    T_odom = T_odom * odom_inc;
    std::optional<Eigen::Isometry3d> registered = truth_inc;
    if (k % 5 == 0) registered = std::nullopt;
    if (k == 7) registered = bad_nan;  // not a usable increment: treated as a fallback
    if (k == 13) registered = bad_scale;
    const bool fallback = !registered || k == 7 || k == 13;

    const ChainStep prev = chain.back();
    const ChainStep step = chain.Add(T_odom, registered);
    EXPECT_EQ(step.fallback, fallback) << k;
    if (fallback) {
      ++expected_fallbacks;
      expected_length += odom_inc.translation().norm();
      EXPECT_LT(PoseError(step.used_increment, odom_inc), 1e-9) << k;
      EXPECT_LT(PoseError(step.increment_correction, Eigen::Isometry3d::Identity()), 1e-12) << k;
      EXPECT_LT(PoseError(step.T_world_body, prev.T_world_body * odom_inc), 1e-9) << k;
      // The correction is carried along unchanged in angle (it is only re-expressed).
      EXPECT_NEAR(Eigen::AngleAxisd(step.cumulative_correction.linear()).angle(),
                  Eigen::AngleAxisd(prev.cumulative_correction.linear()).angle(), 1e-9);
    } else {
      expected_length += truth_inc.translation().norm();
      EXPECT_LT(PoseError(step.T_world_body, prev.T_world_body * truth_inc), 1e-9) << k;
    }
  }
  EXPECT_EQ(chain.fallbacks(), expected_fallbacks);
  EXPECT_EQ(expected_fallbacks, 14u);
  EXPECT_NEAR(chain.path_length_m(), expected_length, 1e-9);
  EXPECT_EQ(chain.size(), 61u);
}

TEST(PoseChain, AllFallbacksIsDeadReckoning) {
  std::mt19937 rng(7);
  const Eigen::Isometry3d T0 = MakePose(Eigen::Vector3d(0, 0, -60) * kDeg, {1.0, 2.0, 3.0});
  PoseChain chain(T0);
  Eigen::Isometry3d T_odom = T0;
  for (int k = 1; k <= 100; ++k) {
    T_odom = T_odom * RandomIncrement(rng);
    const ChainStep step = chain.Add(T_odom, std::nullopt);
    EXPECT_TRUE(step.fallback);
    EXPECT_LT(PoseError(step.T_world_body, T_odom), 1e-9) << k;
    EXPECT_LT(PoseError(step.cumulative_correction, Eigen::Isometry3d::Identity()), 1e-9) << k;
  }
  EXPECT_EQ(chain.fallbacks(), 100u);
}

TEST(PoseChain, BadOdometryThrowsAndLeavesTheChainUnchanged) {
  Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
  bad.translation().z() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(PoseChain{bad}, std::invalid_argument);
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 0.5;
  EXPECT_THROW(PoseChain{scaled}, std::invalid_argument);

  PoseChain chain(Eigen::Isometry3d::Identity());
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.translation().x() = 1.0;
  chain.Add(step, step);
  EXPECT_THROW(chain.Add(bad, step), std::invalid_argument);
  EXPECT_THROW(chain.Add(scaled, std::nullopt), std::invalid_argument);
  EXPECT_EQ(chain.size(), 2u);
  EXPECT_EQ(chain.fallbacks(), 0u);
  EXPECT_DOUBLE_EQ(chain.path_length_m(), 1.0);
  // The chain carries on from the last good frame.
  Eigen::Isometry3d next = step;
  next.translation().x() = 2.0;
  const ChainStep s = chain.Add(next, step);
  EXPECT_EQ(s.index, 2u);
  EXPECT_LT(PoseError(s.T_world_body, next), 1e-15);
}

// ---- covariance -----------------------------------------------------------------------------

namespace {

// (Exp(δr), δt) ∘ T: the left perturbation of RegistrationResult.
Eigen::Isometry3d PerturbLeft(const Eigen::Matrix<double, 6, 1>& d, const Eigen::Isometry3d& T) {
  Eigen::Isometry3d P = Eigen::Isometry3d::Identity();
  if (d.head<3>().norm() > 0)
    P.linear() = Eigen::AngleAxisd(d.head<3>().norm(), d.head<3>().normalized()).toRotationMatrix();
  P.translation() = d.tail<3>();
  return P * T;
}

// T ∘ (Exp(ξr), ξt): a right perturbation.
Eigen::Isometry3d PerturbRight(const Eigen::Isometry3d& T, const Eigen::Matrix<double, 6, 1>& x) {
  return T * PerturbLeft(x, Eigen::Isometry3d::Identity());
}

// ξ with T = T̂ ∘ (Exp(ξr), ξt).
Eigen::Matrix<double, 6, 1> RightDifference(const Eigen::Isometry3d& T, const Eigen::Isometry3d& T_hat) {
  const Eigen::Isometry3d D = T_hat.inverse() * T;
  const Eigen::AngleAxisd aa(D.linear());
  Eigen::Matrix<double, 6, 1> x;
  x << aa.angle() * aa.axis(), D.translation();
  return x;
}

}  // namespace

TEST(Adjoint, MovesARightPerturbationToTheLeft) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1e-4);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Isometry3d T = RandomIncrement(rng) * RandomIncrement(rng);
    Eigen::Matrix<double, 6, 1> xi;
    for (int i = 0; i < 6; ++i) xi(i) = n(rng);
    const Eigen::Isometry3d right = PerturbRight(T, xi);
    const Eigen::Isometry3d left = PerturbLeft(Adjoint(T) * xi, T);
    // Equal to first order: the difference is O(|ξ|²) ~ 1e-8.
    EXPECT_LT(PoseError(right, left), 1e-7);
  }
}

TEST(PoseChain, CovarianceMatchesMonteCarloComposition) {
  // Three increments with their (left, previous-frame) covariances; sample them, chain, and
  // compare the spread of the last pose (right perturbation) with the propagated covariance.
  std::mt19937 rng(11);
  std::vector<Eigen::Isometry3d> increments;
  std::vector<Matrix6d> covariances;
  for (int k = 0; k < 3; ++k) {
    increments.push_back(RandomIncrement(rng));
    Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Random() * 1e-3;
    covariances.push_back(a * a.transpose() + Matrix6d::Identity() * 1e-7);
  }
  PoseChain chain(Eigen::Isometry3d::Identity());
  Eigen::Isometry3d odom = Eigen::Isometry3d::Identity();
  for (int k = 0; k < 3; ++k) {
    odom = odom * increments[k];
    chain.Add(odom, increments[k], covariances[k]);
  }
  const Eigen::Isometry3d T_hat = chain.back().T_world_body;

  std::normal_distribution<double> n(0.0, 1.0);
  const int samples = 20000;
  Matrix6d empirical = Matrix6d::Zero();
  for (int s = 0; s < samples; ++s) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (int k = 0; k < 3; ++k) {
      const Eigen::LLT<Matrix6d> llt(covariances[k]);
      Eigen::Matrix<double, 6, 1> z;
      for (int i = 0; i < 6; ++i) z(i) = n(rng);
      T = T * PerturbLeft(llt.matrixL() * z, increments[k]);
    }
    const Eigen::Matrix<double, 6, 1> x = RightDifference(T, T_hat);
    empirical += x * x.transpose() / samples;
  }
  const Matrix6d& propagated = chain.back().covariance;
  // Sampling error of a variance with 20000 samples is ~1 %; first-order error is smaller.
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      const double scale = std::sqrt(propagated(i, i) * propagated(j, j));
      EXPECT_NEAR(empirical(i, j), propagated(i, j), 0.05 * scale) << i << "," << j;
    }
  }
  EXPECT_TRUE(PoseChain(Eigen::Isometry3d::Identity()).back().covariance.isZero());
}

TEST(PoseChain, ChainedRotationsStayOrthonormal) {
  // Increments whose rotations are off SO(3) by 1e-9 (as products of many small rotations come
  // out); the chained poses are projected back, so their error does not accumulate.
  std::mt19937 rng(21);
  PoseChain chain(Eigen::Isometry3d::Identity());
  Eigen::Isometry3d odom = Eigen::Isometry3d::Identity();
  for (int k = 0; k < 2000; ++k) {
    Eigen::Isometry3d increment = RandomIncrement(rng);
    increment.linear() *= 1.0 + 1e-9;
    odom = odom * increment;
    odom.linear() = Eigen::Quaterniond(odom.linear()).normalized().toRotationMatrix();
    const ChainStep step = chain.Add(odom, increment);
    ASSERT_FALSE(step.fallback) << k;
    const Eigen::Matrix3d R = step.T_world_body.linear();
    ASSERT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-12) << k;
  }
}
