// k-d tree against brute force: bounded closest point (including "no match") and k-NN,
// on random and adversarial sets.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

#include "registration/KdTree.hpp"

using rovermap::registration::KdTree;
using rovermap::registration::Neighbor;
using Points = std::vector<Eigen::Vector3d>;

namespace {

// Brute force: the closest squared distance strictly within the bound, or none.
Neighbor BruteClosest(const Points& pts, const Eigen::Vector3d& q, double bound) {
  Neighbor best;
  double best_sq = bound * bound;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const double d = (pts[i] - q).squaredNorm();
    if (d < best_sq) {
      best_sq = d;
      best = Neighbor{true, i, d};
    }
  }
  return best;
}

Points RandomCloud(std::mt19937& rng, std::size_t n, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Points p(n);
  for (auto& x : p) x = Eigen::Vector3d(u(rng), u(rng), u(rng));
  return p;
}

// Checks many queries (near the data and far from it) against brute force at several bounds.
void CheckAgainstBruteForce(const Points& pts, std::mt19937& rng, double query_scale) {
  const KdTree tree(pts);
  std::uniform_real_distribution<double> u(-query_scale, query_scale);
  for (int q = 0; q < 300; ++q) {
    const Eigen::Vector3d query(u(rng), u(rng), u(rng));
    for (double bound : {0.001, 0.05, 0.3, 1.0, 100.0}) {
      const Neighbor expected = BruteClosest(pts, query, bound);
      const Neighbor got = tree.FindClosest(query, bound);
      ASSERT_EQ(got.found, expected.found) << "bound " << bound;
      if (!expected.found) continue;
      // Ties (duplicates) may return another index at the same distance.
      EXPECT_DOUBLE_EQ(got.squared_distance, expected.squared_distance);
      EXPECT_DOUBLE_EQ((pts[got.index] - query).squaredNorm(), got.squared_distance);
    }
  }
}

}  // namespace

TEST(KdTree, RandomMatchesBruteForce) {
  std::mt19937 rng(1);
  CheckAgainstBruteForce(RandomCloud(rng, 2000, 1.0), rng, 1.5);
}

// Above 16 384 points the tree is built with parallel tasks: the same answers.
TEST(KdTree, LargeParallelBuiltTreeMatchesBruteForce) {
  std::mt19937 rng(7);
  Points pts = RandomCloud(rng, 50000, 1.0);
  // A dense clump as well, so subtrees differ in size and depth is uneven in space.
  std::normal_distribution<double> tight(0.0, 1e-3);
  for (int i = 0; i < 5000; ++i) pts.emplace_back(0.3 + tight(rng), -0.2 + tight(rng), tight(rng));
  const KdTree tree(pts);
  ASSERT_EQ(tree.size(), pts.size());
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  for (int q = 0; q < 200; ++q) {
    const Eigen::Vector3d random(u(rng), u(rng), u(rng));
    const Eigen::Vector3d query =
        q % 4 == 0 ? Eigen::Vector3d(0.3, -0.2, 0.0) + 0.002 * random : random;
    for (double bound : {0.01, 0.1, 10.0}) {
      const Neighbor expected = BruteClosest(pts, query, bound);
      const Neighbor got = tree.FindClosest(query, bound);
      ASSERT_EQ(got.found, expected.found);
      if (expected.found) {
        EXPECT_DOUBLE_EQ(got.squared_distance, expected.squared_distance);
      }
    }
    std::vector<double> all;
    for (const auto& p : pts) all.push_back((p - query).squaredNorm());
    std::partial_sort(all.begin(), all.begin() + 10, all.end());
    const auto knn = tree.FindKNearest(query, 10);
    ASSERT_EQ(knn.size(), 10u);
    for (std::size_t k = 0; k < 10; ++k) EXPECT_DOUBLE_EQ(knn[k].squared_distance, all[k]);
  }
}

TEST(KdTree, DuplicatesMatchBruteForce) {
  std::mt19937 rng(2);
  Points base = RandomCloud(rng, 50, 1.0);
  Points pts;
  for (int copy = 0; copy < 40; ++copy) pts.insert(pts.end(), base.begin(), base.end());
  CheckAgainstBruteForce(pts, rng, 1.2);
  // All points identical.
  CheckAgainstBruteForce(Points(500, Eigen::Vector3d(0.1, 0.2, 0.3)), rng, 0.5);
}

TEST(KdTree, CollinearMatchesBruteForce) {
  Points pts;
  for (int i = 0; i < 1000; ++i) pts.emplace_back(0.001 * i, 0.002 * i, -0.0005 * i);
  std::mt19937 rng(3);
  CheckAgainstBruteForce(pts, rng, 2.0);
}

TEST(KdTree, ClusteredMatchesBruteForce) {
  std::mt19937 rng(4);
  std::normal_distribution<double> tight(0.0, 1e-4);
  Points pts;
  for (const Eigen::Vector3d& c :
       {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(-1, 0.5, 0)})
    for (int i = 0; i < 700; ++i)
      pts.push_back(c + Eigen::Vector3d(tight(rng), tight(rng), tight(rng)));
  CheckAgainstBruteForce(pts, rng, 1.5);
}

TEST(KdTree, BoundedSearchReturnsNoMatch) {
  const Points pts = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0)};
  const KdTree tree(pts);
  EXPECT_FALSE(tree.FindClosest(Eigen::Vector3d(0.5, 0.5, 0), 0.5).found);
  const Neighbor n = tree.FindClosest(Eigen::Vector3d(0.9, 0, 0), 0.2);
  ASSERT_TRUE(n.found);
  EXPECT_EQ(n.index, 1u);
  EXPECT_NEAR(n.squared_distance, 0.01, 1e-15);
  // A point exactly at the bound is not "within" it.
  EXPECT_FALSE(tree.FindClosest(Eigen::Vector3d(0, 0, 2), 1.0).found);
  EXPECT_FALSE(tree.FindClosest(Eigen::Vector3d(0, 0, 0), 0.0).found);
  EXPECT_TRUE(
      tree.FindClosest(Eigen::Vector3d(50, 0, 0), std::numeric_limits<double>::infinity()).found);
}

TEST(KdTree, EmptyTreeNeverMatches) {
  const Points pts;
  const KdTree tree(pts);
  EXPECT_FALSE(tree.FindClosest(Eigen::Vector3d::Zero(), 10.0).found);
  EXPECT_TRUE(tree.FindKNearest(Eigen::Vector3d::Zero(), 5).empty());
}

TEST(KdTree, KNearestMatchesBruteForce) {
  std::mt19937 rng(5);
  const Points pts = RandomCloud(rng, 1500, 1.0);
  const KdTree tree(pts);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  for (int q = 0; q < 100; ++q) {
    const Eigen::Vector3d query(u(rng), u(rng), u(rng));
    std::vector<double> all;
    for (const auto& p : pts) all.push_back((p - query).squaredNorm());
    std::sort(all.begin(), all.end());
    const auto got = tree.FindKNearest(query, 8);
    ASSERT_EQ(got.size(), 8u);
    for (std::size_t k = 0; k < 8; ++k) EXPECT_DOUBLE_EQ(got[k].squared_distance, all[k]);
  }
  EXPECT_EQ(tree.FindKNearest(Eigen::Vector3d::Zero(), 5000).size(), pts.size());
}

TEST(KdTree, WarmStartedSearchGivesTheSameDistance) {
  std::mt19937 rng(6);
  const Points pts = RandomCloud(rng, 3000, 1.0);
  const KdTree tree(pts);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  std::uniform_int_distribution<std::size_t> any(0, pts.size() - 1);
  for (int q = 0; q < 500; ++q) {
    const Eigen::Vector3d query(u(rng), u(rng), u(rng));
    for (double bound : {0.02, 0.2, 5.0}) {
      const Neighbor expected = BruteClosest(pts, query, bound);
      // Good hint (the answer), random hint (often outside the bound), invalid hint.
      for (std::size_t hint :
           {expected.found ? expected.index : std::size_t{0}, any(rng), pts.size() + 7}) {
        const Neighbor got = tree.FindClosest(query, bound, hint);
        ASSERT_EQ(got.found, expected.found);
        if (expected.found) {
          EXPECT_DOUBLE_EQ(got.squared_distance, expected.squared_distance);
        }
      }
    }
  }
}

// CountWithin against brute force: radii from empty to everything, the at_most cap, a point
// exactly on the radius (counted), duplicates, and a large tree built in parallel.
TEST(KdTree, CountWithinMatchesBruteForce) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> coordinate(-1.5, 1.5);
  Points dense = RandomCloud(rng, 30000, 1.0);
  const Points base = RandomCloud(rng, 40, 1.0);
  Points duplicated;
  for (int copy = 0; copy < 4; ++copy)
    duplicated.insert(duplicated.end(), base.begin(), base.end());
  for (const Points* pts : {&dense, &duplicated}) {
    const KdTree tree(*pts);
    for (int q = 0; q < 200; ++q) {
      const Eigen::Vector3d query =
          q % 2 == 0 ? (*pts)[static_cast<std::size_t>(q) % pts->size()]
                     : Eigen::Vector3d(coordinate(rng), coordinate(rng), coordinate(rng));
      for (const double radius : {0.0, 0.01, 0.05, 0.2, 5.0}) {
        std::size_t expected = 0;
        for (const auto& p : *pts) expected += (p - query).squaredNorm() <= radius * radius;
        for (const std::size_t at_most : {std::size_t{1}, std::size_t{3}, pts->size()}) {
          EXPECT_EQ(tree.CountWithin(query, radius, at_most), std::min(expected, at_most))
              << "radius " << radius << ", at most " << at_most;
        }
      }
    }
  }
  const Points pair = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0)};
  const KdTree tree(pair);
  EXPECT_EQ(tree.CountWithin(Eigen::Vector3d(0, 0, 0), 1.0, 5), 2u);  // on the radius: counted
  EXPECT_EQ(tree.CountWithin(Eigen::Vector3d(0, 0, 0), 0.999, 5), 1u);
  EXPECT_EQ(tree.CountWithin(Eigen::Vector3d(0, 0, 0), -1.0, 5), 0u);
  EXPECT_EQ(KdTree(Points()).CountWithin(Eigen::Vector3d::Zero(), 1.0, 5), 0u);
}

// The closest point and the bound on every other point's distance, against brute force: the
// second smallest squared distance within the bound, else the bound² (duplicates included,
// where the second closest lies at the same distance, and hints on and off the answer).
TEST(KdTree, OthersBoundMatchesBruteForce) {
  std::mt19937 rng(8);
  Points dense = RandomCloud(rng, 5000, 1.0);
  const Points base = RandomCloud(rng, 50, 1.0);
  Points duplicated;
  for (int copy = 0; copy < 3; ++copy)
    duplicated.insert(duplicated.end(), base.begin(), base.end());
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (const Points* pts : {&dense, &duplicated}) {
    const KdTree tree(*pts);
    for (int q = 0; q < 300; ++q) {
      const Eigen::Vector3d query(u(rng), u(rng), u(rng));
      for (const double bound : {0.01, 0.08, 0.5, std::numeric_limits<double>::infinity()}) {
        const Neighbor expected = BruteClosest(*pts, query, bound);
        double second_sq = bound * bound;
        for (std::size_t i = 0; i < pts->size(); ++i) {
          const double d = ((*pts)[i] - query).squaredNorm();
          if (expected.found && i == expected.index) continue;
          second_sq = std::min(second_sq, d);
        }
        for (const std::size_t hint : {std::numeric_limits<std::size_t>::max(), expected.index,
                                       static_cast<std::size_t>(q) % pts->size()}) {
          double others_sq = -1.0;
          const Neighbor got = tree.FindClosest(query, bound, hint, &others_sq);
          ASSERT_EQ(got.found, expected.found) << "bound " << bound;
          EXPECT_DOUBLE_EQ(others_sq, second_sq) << "bound " << bound << ", hint " << hint;
          if (!expected.found) continue;
          EXPECT_DOUBLE_EQ(got.squared_distance, expected.squared_distance);
          EXPECT_LE(got.squared_distance, others_sq);
        }
      }
    }
  }
  double others_sq = 0.0;
  EXPECT_FALSE(KdTree(Points()).FindClosest(Eigen::Vector3d::Zero(), 1.0, 0, &others_sq).found);
  EXPECT_DOUBLE_EQ(others_sq, 1.0);
}
