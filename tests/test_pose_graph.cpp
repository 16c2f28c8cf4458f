// graph::SolvePoseGraph: the conventions of its factors (a relative factor's covariance is a left
// perturbation in its `from` frame, as the chain's), drift bounded by position fixes, outliers
// gated, and the chained trajectory kept when there is nothing absolute.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "graph/PoseGraph.hpp"
#include "tests/support/Poses.hpp"

using namespace rovermap;
using graph::Matrix6d;

namespace {

const auto& Pose = rovermap::testing::PlanarPose;
const auto& Diagonal = rovermap::testing::DiagonalCovariance;

// A 100 m arc of 201 nodes, 0.5 m apart, turning 0.3°/m. Its increments are measured with
// noise drawn from the covariance they are given (0.6° and 2 cm a step: the chain's heading
// wanders by degrees and its end by metres), and chained into the initial trajectory, which
// starts `offset` away from the truth. An error that repeats from step to step is no white
// noise; the pipeline gives it its own σ (docs/graph.md), so it is left out here.
struct Traverse {
  std::vector<Eigen::Isometry3d> truth, chained;
  std::vector<graph::RelativeFactor> relative;
};

Traverse MakeTraverse(const Eigen::Isometry3d& offset = Eigen::Isometry3d::Identity()) {
  Traverse t;
  const int nodes = 201;
  const double turn = 0.3 * M_PI / 180.0;  // rad/m
  for (int k = 0; k < nodes; ++k) {
    const double s = 0.5 * k;
    t.truth.push_back(Pose(std::sin(turn * s) / turn, (1.0 - std::cos(turn * s)) / turn,
                           turn * s * 180.0 / M_PI));
  }
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  const double sigma_rad = 0.6 * M_PI / 180.0, sigma_m = 0.02;
  t.chained.push_back(offset * t.truth.front());
  for (int k = 1; k < nodes; ++k) {
    Eigen::Isometry3d step = t.truth[k - 1].inverse() * t.truth[k];
    // A left perturbation (Exp(r), δt) ∘ step, as the factor's covariance describes.
    const Eigen::Vector3d r(sigma_rad * normal(rng), sigma_rad * normal(rng),
                            sigma_rad * normal(rng));
    Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
    D.linear() = Eigen::AngleAxisd(r.norm(), r.normalized()).matrix();
    D.translation() = sigma_m * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    step = D * step;
    t.chained.push_back(t.chained.back() * step);
    t.relative.push_back({static_cast<std::size_t>(k - 1), static_cast<std::size_t>(k), step,
                          Diagonal(sigma_rad, sigma_m)});
  }
  return t;
}

std::vector<graph::PositionFactor> Fixes(const Traverse& t, double sigma_m, int every,
                                         unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_m);
  std::vector<graph::PositionFactor> fixes;
  for (std::size_t k = 0; k < t.truth.size(); k += every) {
    graph::PositionFactor f;
    f.node = k;
    f.position_world =
        t.truth[k].translation() + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    f.covariance = Eigen::Matrix3d::Identity() * sigma_m * sigma_m;
    fixes.push_back(f);
  }
  return fixes;
}

double HeadingErrorDeg(const Eigen::Isometry3d& T, const Eigen::Isometry3d& truth) {
  auto heading = [](const Eigen::Isometry3d& P) { return std::atan2(P(1, 0), P(0, 0)); };
  return std::remainder(heading(T) - heading(truth), 2.0 * M_PI) * 180.0 / M_PI;
}

double MaxPositionError(const std::vector<Eigen::Isometry3d>& a,
                        const std::vector<Eigen::Isometry3d>& b) {
  double worst = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k)
    worst = std::max(worst, (a[k].translation() - b[k].translation()).norm());
  return worst;
}

}  // namespace

TEST(PoseGraph, WithoutAbsoluteFactorsTheChainIsKeptAsItIs) {
  const Traverse t = MakeTraverse();
  const graph::PoseGraphResult r = graph::SolvePoseGraph(t.chained, t.relative, {});
  EXPECT_FALSE(r.solved);
  ASSERT_EQ(r.T_world_body.size(), t.chained.size());
  for (std::size_t k = 0; k < t.chained.size(); ++k)
    EXPECT_TRUE(r.T_world_body[k].matrix() == t.chained[k].matrix()) << k;
}

TEST(PoseGraph, PositionFixesBoundTheDrift) {
  const Traverse t = MakeTraverse();
  const double chained_error = MaxPositionError(t.chained, t.truth);
  ASSERT_GT(chained_error, 3.0);
  const graph::PoseGraphResult r =
      graph::SolvePoseGraph(t.chained, t.relative, Fixes(t, 0.5, 10, 1));
  ASSERT_TRUE(r.solved) << r.message;
  EXPECT_EQ(r.fixes_rejected, 0u);
  // Within 2σ of one fix's 3-D error at the end, and nowhere near the chain's error.
  const double final_error =
      (r.T_world_body.back().translation() - t.truth.back().translation()).norm();
  EXPECT_LT(final_error, 2.0 * 0.5 * std::sqrt(3.0)) << final_error;
  EXPECT_LT(MaxPositionError(r.T_world_body, t.truth), 0.25 * chained_error);
  // The heading follows: the fixes' track turns the chain's wandering heading back.
  EXPECT_LT(std::abs(HeadingErrorDeg(r.T_world_body.back(), t.truth.back())), 2.0);
  EXPECT_GT(std::abs(HeadingErrorDeg(t.chained.back(), t.truth.back())), 4.0);
}

// A chain that starts 30 m and 20° away from where the fixes put it: 60σ of every fix, where a
// plain least-squares gate would see nothing but outliers. The robust loss pulls it in.
TEST(PoseGraph, AChainStartingFarAwayIsPulledOntoTheFixes) {
  Eigen::Isometry3d offset = Pose(30.0, -10.0, 20.0);
  const Traverse t = MakeTraverse(offset);
  ASSERT_GT(MaxPositionError(t.chained, t.truth), 30.0);
  const graph::PoseGraphResult r =
      graph::SolvePoseGraph(t.chained, t.relative, Fixes(t, 0.5, 10, 3));
  ASSERT_TRUE(r.solved) << r.message;
  EXPECT_EQ(r.fixes_rejected, 0u);
  EXPECT_LT(MaxPositionError(r.T_world_body, t.truth), 1.0);
}

// Three fixes jump 15 m (multipath): they are rejected, and the solution is the one without
// them, to the solver's tolerance.
TEST(PoseGraph, MultipathJumpsAreRejectedAndLeaveNoTrace) {
  const Traverse t = MakeTraverse();
  const std::vector<graph::PositionFactor> good = Fixes(t, 0.5, 10, 2);
  const std::vector<std::size_t> jumps = {3, 9, 15};
  std::vector<graph::PositionFactor> fixes = good, without;
  for (std::size_t k = 0; k < good.size(); ++k) {
    if (std::find(jumps.begin(), jumps.end(), k) == jumps.end())
      without.push_back(good[k]);
    else
      fixes[k].position_world += Eigen::Vector3d(12.0, -8.0, 3.0);
  }
  const graph::PoseGraphResult clean = graph::SolvePoseGraph(t.chained, t.relative, without);
  ASSERT_TRUE(clean.solved);
  EXPECT_EQ(clean.fixes_rejected, 0u);
  const graph::PoseGraphResult r = graph::SolvePoseGraph(t.chained, t.relative, fixes);
  ASSERT_TRUE(r.solved) << r.message;
  EXPECT_EQ(r.fixes_rejected, jumps.size());
  for (const std::size_t k : jumps) {
    EXPECT_FALSE(r.fix_used[k]) << k;
    EXPECT_GT(r.fix_chi2[k], 100.0) << k;
  }
  EXPECT_LT(MaxPositionError(r.T_world_body, clean.T_world_body), 1e-3);
}

// Every fix thrown 1 km off in its own direction: they disagree with one another and the chain,
// so they are rejected until too few are left to trust, and the chain is kept.
TEST(PoseGraph, EveryFixAnOutlierKeepsTheChain) {
  const Traverse t = MakeTraverse();
  std::vector<graph::PositionFactor> fixes = Fixes(t, 0.5, 10, 4);
  for (std::size_t k = 0; k < fixes.size(); ++k) {
    const double angle = 2.4 * static_cast<double>(k);
    fixes[k].position_world += 1000.0 * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
  }
  const graph::PoseGraphResult r = graph::SolvePoseGraph(t.chained, t.relative, fixes);
  EXPECT_FALSE(r.solved);
  EXPECT_EQ(r.fixes_used, 0u);
  EXPECT_EQ(r.fixes_rejected, fixes.size());
  EXPECT_NE(r.message.find("fewer than 3"), std::string::npos) << r.message;
  for (std::size_t k = 0; k < t.chained.size(); ++k)
    EXPECT_TRUE(r.T_world_body[k].matrix() == t.chained[k].matrix()) << k;
}

// The relative factor's covariance is a left perturbation in its `from` frame, [r; t]: node 0
// faces +y (yaw 90°), the increment is 1 m ahead, firm along it (1 mm) and loose across it
// (1 m). A fix pulling node 1 by (+0.5, +0.5) m in the world moves it across its `from` frame
// (world x) and not along it (world y).
TEST(PoseGraph, RelativeCovarianceIsALeftPerturbationInTheFromFrame) {
  const std::vector<Eigen::Isometry3d> initial = {Pose(0, 0, 90), Pose(0, 1, 90)};
  graph::RelativeFactor f{0, 1, Pose(1, 0, 0), Matrix6d::Zero()};
  f.covariance.diagonal() << 1e-12, 1e-12, 1e-12, 1e-6, 1.0, 1e-6;
  graph::PositionFactor hold{0, Eigen::Vector3d(0, 0, 0), Eigen::Matrix3d::Identity() * 1e-6};
  graph::PositionFactor pull{1, Eigen::Vector3d(0.5, 1.5, 0), Eigen::Matrix3d::Identity() * 0.01};
  graph::PoseGraphOptions options;
  options.first_pose_sigma_deg = 1e-4;
  options.min_fixes = 1;
  options.fix_gate_chi2 = 1e6;
  options.fix_huber_sigmas = 1e3;  // least squares: the pull's residual along y stays at 5σ
  const graph::PoseGraphResult r = graph::SolvePoseGraph(initial, {f}, {hold, pull}, options);
  ASSERT_TRUE(r.solved) << r.message;
  const Eigen::Vector3d moved = r.T_world_body[1].translation() - initial[1].translation();
  EXPECT_NEAR(moved.x(), 0.5 * 1.0 / (1.0 + 0.01), 1e-4);
  EXPECT_NEAR(moved.y(), 0.0, 1e-4);
}

// The lever arm: a fix of an antenna 1 m to the left of a body facing +x is the body 1 m right.
TEST(PoseGraph, LeverArmIsInTheBodyFrame) {
  const std::vector<Eigen::Isometry3d> initial = {Pose(0, 0, 0), Pose(1, 0, 0)};
  graph::RelativeFactor f{0, 1, Pose(1, 0, 0), Diagonal(1e-3, 1e-3)};
  graph::PositionFactor antenna{1, Eigen::Vector3d(1.0, 1.0, 0.0),
                                Eigen::Matrix3d::Identity() * 1e-4, Eigen::Vector3d(0, 1, 0)};
  graph::PoseGraphOptions options;
  options.min_fixes = 1;
  const graph::PoseGraphResult r = graph::SolvePoseGraph(initial, {f}, {antenna}, options);
  ASSERT_TRUE(r.solved);
  EXPECT_LT((r.T_world_body[1].translation() - Eigen::Vector3d(1, 0, 0)).norm(), 1e-3);
  EXPECT_LT(r.fix_chi2[0], 1e-3);
}

TEST(PoseGraph, BadFactorsAndOptionsAreRefusedNamingThem) {
  const std::vector<Eigen::Isometry3d> initial = {Pose(0, 0, 0), Pose(1, 0, 0)};
  const graph::RelativeFactor good{0, 1, Pose(1, 0, 0), Diagonal(1e-3, 1e-3)};
  graph::RelativeFactor missing = good;
  missing.to = 2;
  EXPECT_THROW(graph::SolvePoseGraph(initial, {missing}, {}), std::invalid_argument);
  graph::RelativeFactor nan = good;
  nan.covariance(0, 0) = std::nan("");
  try {
    graph::SolvePoseGraph(initial, {good, nan}, {});
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("relative factor 1"), std::string::npos) << e.what();
  }
  graph::PositionFactor negative{1, Eigen::Vector3d::Zero(), -Eigen::Matrix3d::Identity()};
  EXPECT_THROW(graph::SolvePoseGraph(initial, {good}, {negative}), std::invalid_argument);
  graph::PoseGraphOptions bad;
  bad.fix_gate_chi2 = 0.0;
  try {
    graph::SolvePoseGraph(initial, {good}, {}, bad);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("graph.fix_gate_chi2"), std::string::npos) << e.what();
  }
}

namespace {

// Pose factors as a reference-DEM match gives them: heading, x, y and z of `every`-th node,
// z on another vertical datum `datum_m` above the truth's.
std::vector<graph::PoseFactor> Matches(const Traverse& t, int every, double datum_m) {
  std::vector<graph::PoseFactor> out;
  for (std::size_t k = every; k < t.truth.size(); k += every) {
    graph::PoseFactor f;
    f.node = k;
    f.T_world_body = t.truth[k];
    f.T_world_body.translation().z() += datum_m;
    f.information(2, 2) = 1.0 / std::pow(0.2 * M_PI / 180.0, 2);
    f.information(3, 3) = f.information(4, 4) = 1.0 / (0.1 * 0.1);
    f.information(5, 5) = 1.0 / (0.05 * 0.05);
    f.z_offset = true;
    out.push_back(f);
  }
  return out;
}

}  // namespace

// A match holds heading, x, y and a height on the reference's own vertical datum: the graph
// holds the chain to them and finds the datum's offset, the same for every match.
TEST(PoseGraph, PoseFactorsHoldPositionHeadingAndFindTheirVerticalOffset) {
  const Traverse t = MakeTraverse();
  const double chained_error = MaxPositionError(t.chained, t.truth);
  ASSERT_GT(chained_error, 3.0);
  const graph::PoseGraphResult r =
      graph::SolvePoseGraph(t.chained, t.relative, {}, Matches(t, 40, 7.0));
  ASSERT_TRUE(r.solved) << r.message;
  EXPECT_EQ(r.poses_used, 5u);
  EXPECT_EQ(r.poses_rejected, 0u);
  // Heights: the offset and the trajectory's level are one freedom (frame 0's weak prior holds
  // it), so every node's height error is 7 m less the offset found.
  for (std::size_t k = 40; k < t.truth.size(); k += 40) {
    const double dz = r.T_world_body[k].translation().z() - t.truth[k].translation().z();
    EXPECT_NEAR(dz, 7.0 - r.z_offset_m, 0.15) << k;
  }
  EXPECT_LT(std::abs(r.z_offset_m - 7.0), 1.0);
  Eigen::Vector2d horizontal_worst(0, 0);
  for (std::size_t k = 0; k < t.truth.size(); ++k) {
    const Eigen::Vector2d d =
        (r.T_world_body[k].translation() - t.truth[k].translation()).head<2>().cwiseAbs();
    horizontal_worst = horizontal_worst.cwiseMax(d);
  }
  EXPECT_LT(horizontal_worst.norm(), 0.15 * chained_error) << horizontal_worst.transpose();
  EXPECT_LT(std::abs(HeadingErrorDeg(r.T_world_body[160], t.truth[160])), 0.6);
}

TEST(PoseGraph, AWrongMatchIsRejectedAndPriorsAreNeitherGatedNorCounted) {
  const Traverse t = MakeTraverse();
  std::vector<graph::PoseFactor> poses = Matches(t, 40, 0.0);
  poses[2].T_world_body.translation().x() += 5.0;  // 50σ: a match on the wrong crater
  const graph::PoseGraphResult r = graph::SolvePoseGraph(t.chained, t.relative, {}, poses);
  ASSERT_TRUE(r.solved) << r.message;
  EXPECT_EQ(r.poses_rejected, 1u);
  EXPECT_FALSE(r.pose_used[2]);
  // A prior alone (the chain's own tilt) is no absolute factor: nothing is solved.
  graph::PoseFactor prior;
  prior.node = 10;
  prior.T_world_body = t.chained[10];
  prior.information(0, 0) = prior.information(1, 1) = 1e4;
  prior.gated = false;
  const graph::PoseGraphResult alone = graph::SolvePoseGraph(t.chained, t.relative, {}, {prior});
  EXPECT_FALSE(alone.solved);
  EXPECT_EQ(alone.poses_used + alone.poses_rejected, 0u);
}

// A revisit: the last node measured against the first (the arc's ends, 100 m apart along it,
// seen as one place). The loop pulls the chain's end back; a loop wrong by 40 m, alone,
// is rejected and the chain kept.
TEST(PoseGraph, ALoopFactorPullsTheChainsEndAndAWrongOneIsRejected) {
  const Traverse t = MakeTraverse();
  graph::LoopFactor loop;
  loop.from = 0;
  loop.to = t.truth.size() - 1;
  loop.T_from_to = t.truth.front().inverse() * t.truth.back();
  loop.information = Diagonal(0.1 * M_PI / 180.0, 0.05).inverse();
  const double chained_end = (t.chained.back().translation() - t.truth.back().translation()).norm();
  ASSERT_GT(chained_end, 2.0);
  graph::PoseGraphOptions one;  // as the pipeline asks with revisits: one loop is enough
  one.min_fixes = 1;
  const graph::PoseGraphResult r =
      graph::SolvePoseGraph(t.chained, t.relative, {}, {}, one, {loop});
  ASSERT_TRUE(r.solved) << r.message;
  EXPECT_EQ(r.loops_used, 1u);
  const double end = (r.T_world_body.back().translation() - t.truth.back().translation()).norm();
  EXPECT_LT(end, 0.2 * chained_end) << end;
  graph::LoopFactor wrong = loop;
  wrong.T_from_to.translation().x() += 40.0;  // far beyond what the chain can drift
  const graph::PoseGraphResult w =
      graph::SolvePoseGraph(t.chained, t.relative, {}, {}, one, {wrong});
  EXPECT_FALSE(w.solved);
  EXPECT_EQ(w.loops_rejected, 1u);
}

// The marginal covariance of a node in the chain's convention (a right perturbation in the body
// frame): one relative factor of covariance Σ (left, in frame 0) onto node 1, a fix too loose to
// matter and node 0 held by a tight prior give Σ₁ = Ad(T₀₁⁻¹) Σ Ad(T₀₁⁻¹)ᵀ, rotation and cross
// terms included.
TEST(PoseGraph, MarginalCovarianceIsTheChainsConvention) {
  Eigen::Isometry3d T01 = Pose(2.0, 1.0, 35.0);
  T01.linear() =
      T01.linear() * Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 0).normalized()).matrix();
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Random();
  const Matrix6d sigma = 1e-3 * (A * A.transpose() + 0.1 * Matrix6d::Identity());
  graph::RelativeFactor f{0, 1, T01, sigma};
  graph::PositionFactor loose{1, T01.translation(), Eigen::Matrix3d::Identity() * 1e8};
  graph::PoseGraphOptions options;
  options.min_fixes = 1;
  options.first_pose_sigma_deg = 1e-7;
  options.first_pose_sigma_m = 1e-9;
  const graph::PoseGraphResult r =
      graph::SolvePoseGraph({Eigen::Isometry3d::Identity(), T01}, {f}, {loose}, options);
  ASSERT_TRUE(r.solved) << r.message;
  ASSERT_EQ(r.covariance.size(), 2u) << r.covariance_message;
  EXPECT_LT(r.covariance[0].norm(), 1e-12);
  const Eigen::Isometry3d inv = T01.inverse();
  Matrix6d Ad = Matrix6d::Zero();  // [[R, 0], [[t]×R, R]] of T01⁻¹
  Eigen::Matrix3d tx;
  tx << 0, -inv.translation().z(), inv.translation().y(), inv.translation().z(), 0,
      -inv.translation().x(), -inv.translation().y(), inv.translation().x(), 0;
  Ad.topLeftCorner<3, 3>() = inv.linear();
  Ad.bottomLeftCorner<3, 3>() = tx * inv.linear();
  Ad.bottomRightCorner<3, 3>() = inv.linear();
  const Matrix6d expected = Ad * sigma * Ad.transpose();
  EXPECT_LT((r.covariance[1] - expected).norm(), 1e-6 * expected.norm())
      << "got\n"
      << r.covariance[1] << "\nexpected\n"
      << expected;
}

// Calibrated: over noisy arcs with fixes every 20 nodes (σ 0.3 m), the true pose of every node
// lies within the 6-D 2σ bound of the graph's marginal covariance about as often as it should
// (95 %), and the covariance shrinks where the fixes hold the chain.
TEST(PoseGraph, MarginalCovarianceHoldsTheTruthAsOftenAsItSays) {
  std::size_t within = 0, count = 0;
  double nees_sum = 0.0;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const Traverse t = MakeTraverse();
    const auto fixes = Fixes(t, 0.3, 20, seed);
    graph::PoseGraphOptions options;
    const graph::PoseGraphResult r = graph::SolvePoseGraph(t.chained, t.relative, fixes, options);
    ASSERT_TRUE(r.solved) << r.message;
    ASSERT_EQ(r.covariance.size(), t.truth.size()) << r.covariance_message;
    // With fixes the covariance is against the world: the truth as it is.
    EXPECT_FALSE(r.covariance_given_first);
    for (std::size_t k = 0; k < t.truth.size(); ++k) {
      const Eigen::Isometry3d D = r.T_world_body[k].inverse() * t.truth[k];
      const Eigen::AngleAxisd aa(D.linear());
      Eigen::Matrix<double, 6, 1> xi;
      xi << aa.angle() * aa.axis(), D.translation();
      const double nees = xi.dot(r.covariance[k].ldlt().solve(xi));
      nees_sum += nees;
      within += nees <= 12.85;
      ++count;
    }
    // Far from the start the fixes hold the position: σ about the fixes', not the chain's.
    const Eigen::Matrix3d R = r.T_world_body.back().linear();
    const Eigen::Matrix3d P = R * r.covariance.back().bottomRightCorner<3, 3>() * R.transpose();
    EXPECT_LT(std::sqrt(P(0, 0) + P(1, 1)), 0.6);
  }
  const double fraction = static_cast<double>(within) / static_cast<double>(count);
  std::printf("within 2 sigma %.3f, mean NEES %.2f (6 expected)\n", fraction,
              nees_sum / static_cast<double>(count));
  EXPECT_GT(fraction, 0.85);
  EXPECT_LT(nees_sum / static_cast<double>(count), 9.0);
  EXPECT_GT(nees_sum / static_cast<double>(count), 3.0);
}

// A window (a daemon's bounded solve): the nodes before PoseGraphOptions::first_free_node held
// at the full solution, the window's first node held by its marginal, leave the free nodes near
// the full solution, with a covariance near the full graph's marginal.
TEST(PoseGraph, AWindowAfterHeldNodesKeepsTheFullSolutionAndItsUncertainty) {
  const Traverse t = MakeTraverse();
  const auto fixes = Fixes(t, 0.3, 20, 3);
  const graph::PoseGraphResult full =
      graph::SolvePoseGraph(t.chained, t.relative, fixes, graph::PoseGraphOptions{});
  ASSERT_TRUE(full.solved) << full.message;
  ASSERT_EQ(full.covariance.size(), t.truth.size());
  graph::PoseGraphOptions options;
  options.first_free_node = 150;
  options.held_covariance = full.covariance[150];
  const graph::PoseGraphResult window =
      graph::SolvePoseGraph(full.T_world_body, t.relative, fixes, options);
  ASSERT_TRUE(window.solved) << window.message;
  // The window's first node is held by the full graph's marginal, which already counts the
  // window's own fixes: counted twice, they move the window by centimetres (fixes of σ 0.3 m).
  EXPECT_LT(MaxPositionError(window.T_world_body, full.T_world_body), 0.15);
  for (std::size_t k = 0; k < 150; ++k) EXPECT_TRUE(window.covariance[k].isZero()) << k;
  for (std::size_t k = 150; k < t.truth.size(); k += 10) {
    const double ratio = window.covariance[k].bottomRightCorner<3, 3>().trace() /
                         full.covariance[k].bottomRightCorner<3, 3>().trace();
    std::printf("node %zu: window / full position variance %.2f\n", k, ratio);
    EXPECT_GT(ratio, 0.5) << k;
    EXPECT_LT(ratio, 1.5) << k;
  }
  options.first_free_node = t.truth.size();
  EXPECT_THROW(graph::SolvePoseGraph(full.T_world_body, t.relative, fixes, options),
               std::invalid_argument);
}
