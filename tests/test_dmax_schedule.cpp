// Zhang's adaptive Dmax, branch by branch (1994, §4.3), including the histogram valley,
// the 60 % condition and the non-increasing bound.
#include <gtest/gtest.h>

#include "registration/DmaxSchedule.hpp"

using namespace rovermap::registration;

namespace {

std::vector<double> Repeat(double value, int n) { return std::vector<double>(n, value); }

std::vector<double> Concat(std::vector<double> a, const std::vector<double>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace

TEST(DmaxSchedule, VeryGoodUsesMeanPlusThreeSigma) {
  // μ = 0.5, σ = 0.1 with D = 1.
  const DmaxUpdate u = UpdateDmax({0.4, 0.6}, 1.0, 10.0);
  EXPECT_EQ(u.branch, DmaxBranch::kVeryGood);
  EXPECT_NEAR(u.mean_m, 0.5, 1e-12);
  EXPECT_NEAR(u.stddev_m, 0.1, 1e-12);
  EXPECT_NEAR(u.dmax_m, 0.8, 1e-12);
  EXPECT_FALSE(u.clamped);
}

TEST(DmaxSchedule, GoodUsesMeanPlusTwoSigma) {
  const DmaxUpdate u = UpdateDmax({1.9, 2.1}, 1.0, 10.0);
  EXPECT_EQ(u.branch, DmaxBranch::kGood);
  EXPECT_NEAR(u.dmax_m, 2.2, 1e-12);
}

TEST(DmaxSchedule, AcceptableUsesMeanPlusOneSigma) {
  const DmaxUpdate u = UpdateDmax({4.9, 5.1}, 1.0, 10.0);
  EXPECT_EQ(u.branch, DmaxBranch::kAcceptable);
  EXPECT_NEAR(u.dmax_m, 5.1, 1e-12);
}

TEST(DmaxSchedule, BranchBoundariesAreStrict) {
  // μ = D exactly is not "very good", μ = 3D not "good", μ = 6D not "acceptable".
  EXPECT_EQ(UpdateDmax({1.0, 1.0}, 1.0, 10.0).branch, DmaxBranch::kGood);
  EXPECT_EQ(UpdateDmax({3.0, 3.0}, 1.0, 10.0).branch, DmaxBranch::kAcceptable);
  EXPECT_NE(UpdateDmax({6.0, 6.0}, 1.0, 10.0).branch, DmaxBranch::kAcceptable);
}

TEST(DmaxSchedule, PoorUsesHistogramValleyAfterHighestPeak) {
  // D = 0.1 so μ ≫ 6D. 20 bins over [0, 10] (width 0.5): 100 pairs in bin 2 (the peak),
  // 10 in bin 4, nothing in 5..16, 60 outliers in bin 19.
  const auto d = Concat(Concat(Repeat(1.1, 100), Repeat(2.2, 10)), Repeat(10.0, 60));
  const DmaxUpdate u = UpdateDmax(d, 0.1, 50.0, 20, 0.6);
  EXPECT_EQ(u.branch, DmaxBranch::kPoorValley);
  // Bin 3 (empty) is where the count stops falling: ξ = its upper edge, 2.0.
  EXPECT_NEAR(u.dmax_m, 2.0, 1e-12);
}

TEST(DmaxSchedule, PoorKeepsPreviousDmaxWhenValleyTooShallow) {
  // Peak 100 (bin 2), valley 70 (bin 3: 70 % > 60 %), rise to 80 (bin 4), outliers (bin 19).
  const auto d = Concat(Concat(Concat(Repeat(1.1, 100), Repeat(1.6, 70)), Repeat(2.1, 80)),
                        Repeat(10.0, 90));
  const DmaxUpdate u = UpdateDmax(d, 0.1, 50.0, 20, 0.6);
  EXPECT_EQ(u.branch, DmaxBranch::kPoorKeep);
  EXPECT_DOUBLE_EQ(u.dmax_m, 50.0);
}

TEST(DmaxSchedule, SixtyPercentConditionBoundary) {
  // Valley at exactly 60 % of the peak is accepted, 61 % is not.
  double xi = 0.0;
  const auto at60 = Concat(Concat(Concat(Repeat(1.1, 100), Repeat(1.6, 60)), Repeat(2.1, 80)),
                           Repeat(10.0, 80));
  EXPECT_TRUE(FindHistogramValley(at60, 20, 0.6, &xi));
  EXPECT_NEAR(xi, 2.0, 1e-12);
  const auto at61 = Concat(Concat(Concat(Repeat(1.1, 100), Repeat(1.6, 61)), Repeat(2.1, 80)),
                           Repeat(10.0, 80));
  EXPECT_FALSE(FindHistogramValley(at61, 20, 0.6, &xi));
}

TEST(DmaxSchedule, MonotoneTailHasNoValley) {
  // Counts only fall after the peak (or stay flat): no valley, previous Dmax kept.
  std::vector<double> d;
  for (int b = 0; b < 20; ++b)
    for (int k = 0; k < 40 - 2 * b; ++k) d.push_back(0.5 * b + 0.25);
  double xi = 0.0;
  EXPECT_FALSE(FindHistogramValley(d, 20, 0.6, &xi));
  const DmaxUpdate u = UpdateDmax(d, 0.01, 30.0);
  EXPECT_EQ(u.branch, DmaxBranch::kPoorKeep);
  EXPECT_DOUBLE_EQ(u.dmax_m, 30.0);
}

TEST(DmaxSchedule, NeverIncreases) {
  // μ + 3σ = 0.8 would exceed the previous Dmax 0.7: clamped.
  const DmaxUpdate u = UpdateDmax({0.4, 0.6}, 1.0, 0.7);
  EXPECT_EQ(u.branch, DmaxBranch::kVeryGood);
  EXPECT_TRUE(u.clamped);
  EXPECT_DOUBLE_EQ(u.dmax_m, 0.7);
}

TEST(DmaxSchedule, NoPairsKeepsPrevious) {
  const DmaxUpdate u = UpdateDmax({}, 1.0, 3.0);
  EXPECT_EQ(u.branch, DmaxBranch::kNoPairs);
  EXPECT_DOUBLE_EQ(u.dmax_m, 3.0);
}
