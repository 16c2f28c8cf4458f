// Isolated points of a frame: brute force agrees with the tree, and points off the surface
// along their ray are found while the surface (also at grazing incidence) is kept.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mapper/OutlierFilter.hpp"

using namespace rovermap;

namespace {

// A camera 1.5 m above the plane z = 0 looking forward and down, one ray per 0.2° in azimuth
// and elevation: the spacing grows with range and with grazing incidence.
std::vector<Eigen::Vector3d> GroundScan(const Eigen::Vector3d& sensor) {
  std::vector<Eigen::Vector3d> points;
  for (double el = -60.0; el <= -8.0; el += 0.2) {
    for (double az = -30.0; az <= 30.0; az += 0.2) {
      const double e = el * M_PI / 180.0, a = az * M_PI / 180.0;
      const Eigen::Vector3d ray(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      points.push_back(sensor + ray * (-sensor.z() / ray.z()));
    }
  }
  return points;
}

}  // namespace

TEST(OutlierFilter, FindsPointsMovedAlongTheirRayAndKeepsTheSurface) {
  const Eigen::Vector3d sensor(0, 0, 1.5);
  std::vector<Eigen::Vector3d> points = GroundScan(sensor);
  std::mt19937 rng(4);
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  std::uniform_real_distribution<double> scale(0.5, 0.85);
  std::vector<bool> outlier(points.size(), false);
  for (int k = 0; k < 200; ++k) {  // ~1 % of the points, moved 15-50 % nearer along the ray
    const std::size_t i = pick(rng);
    if (outlier[i]) continue;
    outlier[i] = true;
    points[i] = sensor + (points[i] - sensor) * scale(rng);
  }
  const registration::KdTree tree(points);
  const mapper::OutlierMask mask = mapper::FindIsolatedPoints(points, tree, sensor, 3.0, 2);
  std::size_t found = 0, false_alarms = 0, outliers = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    outliers += outlier[i];
    if (!mask.keep[i]) (outlier[i] ? found : false_alarms)++;
  }
  EXPECT_NEAR(mask.angular_spacing_rad, 0.2 * M_PI / 180.0, 0.05 * M_PI / 180.0);
  // Measured: every moved point found, no surface point dropped (edges included).
  EXPECT_EQ(found, outliers);
  EXPECT_EQ(false_alarms, 0u);
  EXPECT_EQ(mask.removed, found + false_alarms);
}

TEST(OutlierFilter, MatchesBruteForce) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  std::vector<Eigen::Vector3d> points(3000);
  for (auto& p : points)
    p = Eigen::Vector3d(u(rng), u(rng), 0.2 * u(rng)) + Eigen::Vector3d(8, 0, 0);
  const Eigen::Vector3d sensor(0, 0, 1);
  const registration::KdTree tree(points);
  const mapper::OutlierMask mask = mapper::FindIsolatedPoints(points, tree, sensor, 2.0, 3);
  const double alpha = mask.angular_spacing_rad;
  ASSERT_GT(alpha, 0.0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double radius = 2.0 * alpha * (points[i] - sensor).norm();
    int within = 0;
    for (std::size_t j = 0; j < points.size(); ++j)
      if (j != i && (points[j] - points[i]).norm() <= radius) ++within;
    EXPECT_EQ(mask.keep[i] != 0, within >= 3) << i;
  }
}

TEST(OutlierFilter, OffKeepsEverything) {
  const std::vector<Eigen::Vector3d> points = {{1, 0, 0}, {5, 5, 5}, {1.01, 0, 0}};
  const registration::KdTree tree(points);
  EXPECT_EQ(mapper::FindIsolatedPoints(points, tree, {0, 0, 0}, 0.0, 2).removed, 0u);
  EXPECT_EQ(mapper::FindIsolatedPoints(points, tree, {0, 0, 0}, 3.0, 0).removed, 0u);
  const std::vector<Eigen::Vector3d> none;
  const registration::KdTree empty(none);
  EXPECT_TRUE(mapper::FindIsolatedPoints(none, empty, {0, 0, 0}, 3.0, 2).keep.empty());
}
