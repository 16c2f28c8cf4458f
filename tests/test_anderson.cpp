// Anderson acceleration on fixed-point iterations with known solutions.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <random>

#include "registration/Anderson.hpp"

using rovermap::registration::AndersonAccelerator;
using Vector6 = AndersonAccelerator::Vector6;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

namespace {

// A linear contraction G(x) = A x + b with spectral radius `radius` (a random rotation of a
// diagonal), so plain iteration converges like radius^k to x* = (I − A)⁻¹ b.
struct LinearMap {
  Matrix6 a;
  Vector6 b;
  Vector6 Solution() const { return (Matrix6::Identity() - a).colPivHouseholderQr().solve(b); }
  Vector6 operator()(const Vector6& x) const { return a * x + b; }
};

LinearMap MakeContraction(double radius, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  Matrix6 m;
  for (int i = 0; i < 36; ++i) m(i) = n01(rng);
  const Matrix6 q = Eigen::HouseholderQR<Matrix6>(m).householderQ();
  Vector6 diagonal;
  diagonal << radius, 0.9 * radius, 0.5, 0.3, -0.2, 0.1;
  LinearMap map;
  map.a = q * diagonal.asDiagonal() * q.transpose();
  for (int i = 0; i < 6; ++i) map.b(i) = n01(rng);
  return map;
}

// Iterations until ‖x − x*‖ < tol, at most `limit`.
int IterationsToConverge(const LinearMap& g, int depth, double tol, int limit) {
  AndersonAccelerator aa(depth);
  Vector6 x = Vector6::Zero();
  const Vector6 solution = g.Solution();
  for (int k = 1; k <= limit; ++k) {
    x = aa.Next(x, g(x));
    if ((x - solution).norm() < tol) return k;
  }
  return limit + 1;
}

}  // namespace

TEST(Anderson, DepthZeroIsThePlainIteration) {
  const LinearMap g = MakeContraction(0.95, 1);
  AndersonAccelerator aa(0);
  Vector6 x = Vector6::Constant(0.3);
  for (int k = 0; k < 10; ++k) {
    const Vector6 plain = g(x);
    x = aa.Next(x, plain);
    EXPECT_EQ(x, plain);
  }
}

TEST(Anderson, FirstStepIsPlainThenItExtrapolates) {
  const LinearMap g = MakeContraction(0.95, 2);
  AndersonAccelerator aa(3);
  const Vector6 x0 = Vector6::Zero();
  const Vector6 x1 = aa.Next(x0, g(x0));
  EXPECT_EQ(x1, g(x0));  // no history yet
  const Vector6 x2 = aa.Next(x1, g(x1));
  EXPECT_NE(x2, g(x1));
}

TEST(Anderson, SolvesASlowLinearContractionFarFaster) {
  for (unsigned seed : {3u, 4u, 5u}) {
    const LinearMap g = MakeContraction(0.97, seed);
    const int plain = IterationsToConverge(g, 0, 1e-8, 5000);
    const int accelerated = IterationsToConverge(g, 5, 1e-8, 5000);
    // Plain: about log(1e-8)/log(0.97) ≈ 600 iterations. On a linear map in R⁶, Anderson with
    // depth ≥ 6 is exact after 7 steps (GMRES-equivalent); depth 5 needs a few more.
    EXPECT_GT(plain, 400) << "seed " << seed;
    EXPECT_LT(accelerated, 40) << "seed " << seed;
    EXPECT_LE(IterationsToConverge(g, 6, 1e-8, 5000), 9) << "seed " << seed;
  }
}

TEST(Anderson, ResetForgetsTheHistory) {
  const LinearMap g = MakeContraction(0.95, 6);
  AndersonAccelerator aa(4);
  Vector6 x = Vector6::Zero();
  for (int k = 0; k < 3; ++k) x = aa.Next(x, g(x));
  aa.Reset();
  EXPECT_EQ(aa.Next(x, g(x)), g(x));
}

TEST(Anderson, DegenerateHistoryFallsBackToThePlainStep) {
  // A fixed point reached exactly: every residual is zero, ΔF has rank 0.
  AndersonAccelerator aa(3);
  const Vector6 x = Vector6::Constant(1.0);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(aa.Next(x, x), x);
}
