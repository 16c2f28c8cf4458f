// Normals, tangents and point spacing against analytic values.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "registration/CloudGeometry.hpp"

using namespace rovermap::registration;

TEST(CloudGeometry, PlaneNormalsAreThePlaneNormal) {
  const Eigen::Vector3d n = Eigen::Vector3d(0.2, -0.3, 1.0).normalized();
  const Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j)
      pts.push_back(0.1 * i * u + 0.1 * j * v + Eigen::Vector3d(1, 2, 3));
  const KdTree tree(pts);
  for (const auto& normal : EstimateNormals(pts, tree, 10))
    EXPECT_NEAR(std::abs(normal.dot(n)), 1.0, 1e-9);
}

TEST(CloudGeometry, SphereNormalsAreRadial) {
  std::mt19937 rng(1);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 5000; ++i)
    pts.push_back(Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized());
  const KdTree tree(pts);
  const auto normals = EstimateNormals(pts, tree, 12);
  for (std::size_t i = 0; i < pts.size(); ++i) EXPECT_GT(std::abs(normals[i].dot(pts[i])), 0.98);
}

TEST(CloudGeometry, DegenerateNeighbourhoodHasNoNormal) {
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 20; ++i) line.emplace_back(0.1 * i, 0.0, 0.0);
  const KdTree tree(line);
  for (const auto& normal : EstimateNormals(line, tree, 5)) EXPECT_TRUE(normal.isZero());
}

TEST(CloudGeometry, HelixTangentsFollowTheCurveAndChainsAreSeparate) {
  PointCloud cloud;
  const double step = 0.01;
  for (int chain = 0; chain < 2; ++chain)
    for (int i = 0; i < 300; ++i) {
      const double s = i * step;
      cloud.points.emplace_back(std::cos(s) + 3 * chain, std::sin(s), 0.2 * s);
      cloud.chain_ids.push_back(chain);
    }
  const auto tangents = EstimateTangents(cloud);
  for (std::size_t k = 0; k < cloud.size(); ++k) {
    const double s = static_cast<double>(k % 300) * step;
    const Eigen::Vector3d expected = Eigen::Vector3d(-std::sin(s), std::cos(s), 0.2).normalized();
    // Central differences: O(step²) error; one-sided at chain ends: O(step).
    EXPECT_GT(std::abs(tangents[k].dot(expected)), 1.0 - 1e-4) << k;
  }
  PointCloud single;
  single.points = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1)};
  single.chain_ids = {0, 1};
  for (const auto& t : EstimateTangents(single)) EXPECT_TRUE(t.isZero());
}

TEST(CloudGeometry, MedianSpacingOfAGrid) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 50; ++i)
    for (int j = 0; j < 50; ++j) pts.emplace_back(0.05 * i, 0.05 * j, 0.0);
  // Duplicates do not hide the spacing.
  const std::size_t n = pts.size();
  for (std::size_t k = 0; k < n; k += 3) pts.push_back(pts[k]);
  const KdTree tree(pts);
  EXPECT_NEAR(MedianNeighborSpacing(pts, tree), 0.05, 1e-12);
  // Every point twice: each one's nearest neighbour is its duplicate (the search then looks
  // further than the nearest two).
  std::vector<Eigen::Vector3d> doubled(pts.begin(), pts.begin() + static_cast<long>(n));
  doubled.insert(doubled.end(), pts.begin(), pts.begin() + static_cast<long>(n));
  const KdTree doubled_tree(doubled);
  EXPECT_NEAR(MedianNeighborSpacing(doubled, doubled_tree), 0.05, 1e-12);
  const std::vector<Eigen::Vector3d> same(10, Eigen::Vector3d(1, 1, 1));
  const KdTree same_tree(same);
  EXPECT_EQ(MedianNeighborSpacing(same, same_tree), 0.0);
}
