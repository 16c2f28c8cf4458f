// Range-aware voxels (registration::RangeVoxelDownsample) against a brute-force grouping of the
// points by (level, cell), and the merged point, covariance and normal computed by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include "registration/RangeVoxels.hpp"

using rovermap::registration::PointCloud;
using rovermap::registration::RangeVoxelDownsample;
using rovermap::registration::RangeVoxels;

namespace {

// The edge the documentation promises: min_edge · 2^round(log2(angle · range / min_edge)).
double Edge(double range, double angle, double min_edge) {
  const double target = angle * range / min_edge;
  return target > 1.0 ? min_edge * std::exp2(std::round(std::log2(target))) : min_edge;
}

using Key = std::tuple<long long, long long, long long, long long>;  // edge [µm], cell

Key KeyOf(const Eigen::Vector3d& p, const Eigen::Vector3d& origin, double angle, double min_edge) {
  const double edge = Edge((p - origin).norm(), angle, min_edge);
  return {std::llround(edge * 1e6), static_cast<long long>(std::floor(p.x() / edge)),
          static_cast<long long>(std::floor(p.y() / edge)),
          static_cast<long long>(std::floor(p.z() / edge))};
}

// Ground as a camera 1.5 m up samples it (fx 300 px, 240 × 90 pixels below the horizon): dense
// near the rig, sparse far from it, with a little relief.
PointCloud Ground(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> relief(0.0, 0.01);
  PointCloud cloud;
  for (int v = 4; v < 94; ++v) {
    for (int u = -120; u < 120; ++u) {
      const double range = 1.5 * 300.0 / v;  // forward distance of row v
      cloud.points.emplace_back(range, range * u / 300.0, relief(rng));
      cloud.normals.emplace_back(Eigen::Vector3d::UnitZ());
      cloud.covariances.push_back(Eigen::Matrix3d::Identity() * 1e-4 * range * range);
    }
  }
  return cloud;
}

}  // namespace

TEST(RangeVoxels, GroupsThePointsAsTheirRangeBandsCellsDo) {
  const PointCloud cloud = Ground(1);
  const Eigen::Vector3d origin(0, 0, 1.5);
  const double angle = 4.0 / 300.0, min_edge = 0.001;
  const RangeVoxels v = RangeVoxelDownsample(cloud, origin, angle, min_edge);
  ASSERT_EQ(v.voxel_of.size(), cloud.size());
  // Same voxel if and only if same brute-force key.
  std::map<Key, std::uint32_t> voxel_of_key;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Key key = KeyOf(cloud.points[i], origin, angle, min_edge);
    const auto [it, inserted] = voxel_of_key.emplace(key, v.voxel_of[i]);
    EXPECT_EQ(it->second, v.voxel_of[i]) << "point " << i;
  }
  EXPECT_EQ(voxel_of_key.size(), v.cloud.size());
  // The edge grows with range, within √2 of angle · range.
  for (std::size_t i = 0; i < cloud.size(); i += 97) {
    const double range = (cloud.points[i] - origin).norm();
    const double edge = Edge(range, angle, min_edge);
    EXPECT_LE(edge, std::sqrt(2.0) * angle * range + 1e-12);
    EXPECT_GE(edge, angle * range / std::sqrt(2.0) - 1e-12);
    EXPECT_LE((cloud.points[i] - v.cloud.points[v.voxel_of[i]]).norm(), std::sqrt(3.0) * edge);
  }
  EXPECT_LT(v.cloud.size(), cloud.size() / 2);
}

TEST(RangeVoxels, AVoxelIsTheMeanOfItsPointsWithTheirScatterAndMeanNormal) {
  // Four points in one 4 mm voxel (range ~1 m, angle 4e-3), with distinct covariances, and a
  // far point alone in its own.
  PointCloud cloud;
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  const std::vector<Eigen::Vector3d> near = {{1.0001, 0.0001, 0.0001},
                                             {1.0031, 0.0001, 0.0002},
                                             {1.0001, 0.0033, 0.0001},
                                             {1.0021, 0.0021, 0.0035}};
  for (std::size_t k = 0; k < near.size(); ++k) {
    cloud.points.push_back(near[k]);
    cloud.covariances.push_back(Eigen::Matrix3d::Identity() * 1e-6 * static_cast<double>(k + 1));
    cloud.normals.push_back(Eigen::Vector3d(0.1 * static_cast<double>(k), 0, 1).normalized());
  }
  cloud.points.emplace_back(30.0, 0.0, 0.0);
  cloud.covariances.push_back(Eigen::Matrix3d::Identity());
  cloud.normals.push_back(Eigen::Vector3d::UnitX());
  const RangeVoxels v = RangeVoxelDownsample(cloud, origin, 4e-3, 0.001);
  ASSERT_EQ(v.cloud.size(), 2u);
  EXPECT_EQ(v.voxel_of, (std::vector<std::uint32_t>{0, 0, 0, 0, 1}));

  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < 4; ++k) {
    mean += near[k] / 4.0;
    cov += cloud.covariances[k] / 4.0;
    normal += cloud.normals[k];
  }
  for (std::size_t k = 0; k < 4; ++k) cov += (near[k] - mean) * (near[k] - mean).transpose() / 4.0;
  EXPECT_LT((v.cloud.points[0] - mean).norm(), 1e-12);
  EXPECT_LT((v.cloud.covariances[0] - cov).norm(), 1e-15);
  EXPECT_LT((v.cloud.normals[0] - normal.normalized()).norm(), 1e-12);
  // The lone point is itself, covariance unchanged.
  EXPECT_EQ(v.cloud.points[1], cloud.points[4]);
  EXPECT_EQ(v.cloud.covariances[1], cloud.covariances[4]);
  EXPECT_EQ(v.cloud.normals[1], cloud.normals[4]);
}

TEST(RangeVoxels, OppositeNormalsKeepTheFirstPointsInsteadOfCancelling) {
  PointCloud cloud;
  cloud.points = {{1.0001, 0.0001, 0.0001}, {1.0002, 0.0002, 0.0001}};
  cloud.normals = {Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY()};
  const RangeVoxels v = RangeVoxelDownsample(cloud, Eigen::Vector3d::Zero(), 4e-3, 0.001);
  ASSERT_EQ(v.cloud.size(), 1u);
  EXPECT_EQ(v.cloud.normals[0], Eigen::Vector3d::UnitY());
  EXPECT_FALSE(v.cloud.HasCovariances());
}

TEST(RangeVoxels, LeftOutPointsGoIntoNoVoxel) {
  const PointCloud cloud = Ground(2);
  std::vector<unsigned char> keep(cloud.size(), 1);
  for (std::size_t i = 0; i < keep.size(); i += 3) keep[i] = 0;
  const Eigen::Vector3d origin(0, 0, 1.5);
  const RangeVoxels v = RangeVoxelDownsample(cloud, origin, 0.01, 0.001, &keep);
  // The kept points alone give the same voxels, in the same order.
  PointCloud kept;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!keep[i]) continue;
    kept.points.push_back(cloud.points[i]);
    kept.normals.push_back(cloud.normals[i]);
    kept.covariances.push_back(cloud.covariances[i]);
  }
  const RangeVoxels w = RangeVoxelDownsample(kept, origin, 0.01, 0.001);
  ASSERT_EQ(v.cloud.size(), w.cloud.size());
  for (std::size_t k = 0; k < v.cloud.size(); ++k) {
    EXPECT_LT((v.cloud.points[k] - w.cloud.points[k]).norm(), 1e-12);
    EXPECT_LT((v.cloud.covariances[k] - w.cloud.covariances[k]).norm(), 1e-12);
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!keep[i]) {
      EXPECT_EQ(v.voxel_of[i], RangeVoxels::kNoVoxel);
    }
  }
}

TEST(RangeVoxels, NoAngleKeepsEveryPoint) {
  PointCloud cloud = Ground(3);
  cloud.chain_ids.assign(cloud.size(), 7);
  const RangeVoxels v = RangeVoxelDownsample(cloud, Eigen::Vector3d::Zero(), 0.0);
  EXPECT_EQ(v.cloud.points, cloud.points);
  EXPECT_TRUE(v.cloud.chain_ids.empty());
  for (std::size_t i = 0; i < cloud.size(); ++i) EXPECT_EQ(v.voxel_of[i], i);
  EXPECT_TRUE(RangeVoxelDownsample(PointCloud{}, Eigen::Vector3d::Zero(), 0.01).cloud.empty());
}
