// The local map: frames kept in the world frame, the oldest dropped, handed out in the frame of
// the reference pose and voxel-thinned.
#include <gtest/gtest.h>

#include "mapper/LocalMap.hpp"

using namespace rovermap;

namespace {

registration::PointCloud Grid(double spacing, int n) {
  registration::PointCloud c;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      c.points.emplace_back(i * spacing, j * spacing, 0.0);
      c.normals.emplace_back(0, 0, 1);
    }
  return c;
}

Eigen::Isometry3d Shift(double x, double yaw = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, 0, 0);
  return T;
}

}  // namespace

TEST(LocalMap, KeepsTheLastFramesInTheReferenceFrame) {
  mapper::LocalMap map(2);
  const registration::RegistrationOptions options;
  map.Add(Grid(0.1, 10), Shift(0.0), 0.0);
  map.Add(Grid(0.1, 10), Shift(100.0), 0.0);
  map.Add(Grid(0.1, 10), Shift(200.0, 0.3), 0.0);
  EXPECT_EQ(map.frames(), 2u);
  EXPECT_EQ(map.points(), 200u);
  const auto cloud = map.Build(Shift(200.0, 0.3), 0.0, options);
  ASSERT_EQ(cloud->cloud().size(), 200u);
  // The newest frame comes first, back in its own body frame.
  EXPECT_TRUE(cloud->cloud().points[0].isApprox(Eigen::Vector3d(0, 0, 0)));
  EXPECT_TRUE(cloud->cloud().points[11].isApprox(Eigen::Vector3d(0.1, 0.1, 0)));
  EXPECT_TRUE(cloud->cloud().normals[11].isApprox(Eigen::Vector3d(0, 0, 1)));
  // The frame at x = 100 is 100 m behind (rotated by the reference's yaw). Frame 0 is gone.
  const Eigen::Vector3d older =
      Shift(200.0, 0.3).inverse() * Shift(100.0) * Eigen::Vector3d(0, 0, 0);
  EXPECT_TRUE(cloud->cloud().points[100].isApprox(older));
}

TEST(LocalMap, VoxelThinning) {
  mapper::LocalMap map(3);
  const registration::RegistrationOptions options;
  map.Add(Grid(0.01, 100), Shift(0.0), 0.05);  // 1 m square at 1 cm -> 20×20 voxels of 5 cm
  EXPECT_EQ(map.points(), 400u);
  map.Add(Grid(0.01, 100), Shift(0.0), 0.05);  // the same ground again
  EXPECT_EQ(map.points(), 800u);
  EXPECT_EQ(map.Build(Shift(0.0), 0.05, options)->cloud().size(), 400u);
  EXPECT_EQ(map.Build(Shift(0.0), 0.0, options)->cloud().size(), 800u);
}
