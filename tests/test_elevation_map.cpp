#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "dem/ElevationMap.hpp"

namespace rovermap::dem {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Points on z = f(x, y) at random positions in [x0, x1] × [y0, y1].
template <typename F>
std::vector<Eigen::Vector3d> Sample(F f, double x0, double x1, double y0, double y1, int n,
                                    unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(x0, x1), uy(y0, y1);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < n; ++i) {
    const double x = ux(rng), y = uy(rng);
    points.emplace_back(x, y, f(x, y));
  }
  return points;
}

FrameContext Frame(std::uint32_t frame) {
  FrameContext ctx;
  ctx.frame = frame;
  return ctx;
}

TEST(ElevationMap, EmptyMapIsNaN) {
  ElevationMap map;
  EXPECT_TRUE(std::isnan(map.HeightAt(0.0, 0.0)));
  EXPECT_TRUE(std::isnan(map.VarianceAt(1.0, -3.0)));
  EXPECT_TRUE(std::isnan(map.HeightAt(kNaN, 0.0)));
  EXPECT_FALSE(map.Cell({0, 0}).has_value());
  const CellValue empty;
  EXPECT_TRUE(empty.Empty());
  EXPECT_TRUE(std::isnan(empty.elevation_m) && std::isnan(empty.variance_m2));
  EXPECT_TRUE(std::isnan(empty.min_m) && std::isnan(empty.max_m));
  EXPECT_EQ(map.TileCount(), 0u);
  EXPECT_EQ(map.CellCount(), 0u);
  EXPECT_TRUE(map.bounds().Empty());
}

TEST(ElevationMap, RejectsBadOptions) {
  ElevationMapOptions options;
  options.cell_size_m = 0.0;
  EXPECT_THROW(ElevationMap{options}, std::invalid_argument);
  options = {};
  options.mahalanobis_gate = -1.0;
  EXPECT_THROW(ElevationMap{options}, std::invalid_argument);
  options = {};
  options.default_point_stddev_m = kNaN;
  EXPECT_THROW(ElevationMap{options}, std::invalid_argument);
}

TEST(ElevationMap, PlaneGivesTheExactPlaneAndShrinkingVariance) {
  ElevationMap map;
  const auto points = Sample([](double, double) { return 1.25; }, -2.0, 3.0, -1.0, 4.0, 50000);
  const FusionStats stats = map.FuseFrame(points, {}, Frame(0));
  EXPECT_EQ(stats.points, points.size());
  EXPECT_EQ(stats.fused, points.size());
  const double r = 0.02 * 0.02;
  std::size_t cells = 0, total = 0;
  map.ForEachCell([&](CellIndex, const CellValue& v) {
    ++cells;
    total += v.count;
    EXPECT_EQ(v.elevation_m, 1.25f);
    EXPECT_EQ(v.min_m, 1.25f);
    EXPECT_EQ(v.max_m, 1.25f);
    EXPECT_NEAR(v.variance_m2, r / v.count, 1e-6 * r);  // Kalman: r / n for n equal readings
  });
  EXPECT_EQ(cells, map.CellCount());
  EXPECT_EQ(total, points.size());
  EXPECT_EQ(map.HeightAt(0.5, 0.5), 1.25);
  EXPECT_TRUE(std::isnan(map.HeightAt(10.0, 10.0)));
}

TEST(ElevationMap, SlopeSampledAtCellCentresIsExact) {
  ElevationMap map;
  const auto slope = [](double x, double y) { return 0.3 * x - 0.2 * y + 2.0; };
  std::vector<Eigen::Vector3d> points;
  for (int i = -40; i < 40; ++i) {
    for (int j = -30; j < 30; ++j) {
      const Eigen::Vector2d c = map.index().CellCenter({i, j});
      for (int k = 0; k < 3; ++k) points.emplace_back(c.x(), c.y(), slope(c.x(), c.y()));
    }
  }
  map.FuseFrame(points, {}, Frame(0));
  EXPECT_EQ(map.CellCount(), 80u * 60u);
  for (int i = -40; i < 40; ++i) {
    for (int j = -30; j < 30; ++j) {
      const Eigen::Vector2d c = map.index().CellCenter({i, j});
      const auto v = map.Cell({i, j});
      ASSERT_TRUE(v.has_value());
      EXPECT_EQ(v->elevation_m, static_cast<float>(slope(c.x(), c.y())));
      EXPECT_EQ(v->count, 3u);
    }
  }
}

TEST(ElevationMap, GateRejectsOutliersAgainstEarlierFrames) {
  ElevationMap map;
  const auto ground = [](double, double) { return 0.0; };
  map.FuseFrame(Sample(ground, 0.0, 2.0, 0.0, 2.0, 20000, 1), {}, Frame(0));
  // Frame 1: the same ground plus 200 spikes 0.5 m up and down (25 sigma).
  auto points = Sample(ground, 0.0, 2.0, 0.0, 2.0, 20000, 2);
  const auto spikes = Sample([](double, double) { return 0.5; }, 0.0, 2.0, 0.0, 2.0, 100, 3);
  const auto pits = Sample([](double, double) { return -0.5; }, 0.0, 2.0, 0.0, 2.0, 100, 4);
  points.insert(points.end(), spikes.begin(), spikes.end());
  points.insert(points.end(), pits.begin(), pits.end());
  const FusionStats stats = map.FuseFrame(points, {}, Frame(1));
  // A spike can only pass by landing in a cell no frame-0 point reached (1600 cells, 20000
  // points: practically never).
  EXPECT_GE(stats.rejected_outliers, 195u);
  EXPECT_EQ(stats.points, stats.fused + stats.replaced + stats.below_in_frame +
                              stats.rejected_outliers + stats.dropped_nonfinite +
                              stats.dropped_out_of_grid);
  map.ForEachCell([](CellIndex, const CellValue& v) {
    EXPECT_EQ(v.elevation_m, 0.0f);
    EXPECT_EQ(v.max_m, 0.0f);
  });
}

TEST(ElevationMap, SmallNoiseIsFusedNotGated) {
  ElevationMap map;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::size_t fused = 0, total = 0;
  for (std::uint32_t frame = 0; frame < 5; ++frame) {
    auto points =
        Sample([&](double, double) { return 0.5 + noise(rng); }, 0, 1, 0, 1, 4000, frame + 10);
    const FusionStats stats = map.FuseFrame(points, {}, Frame(frame));
    fused += stats.fused;
    total += stats.points;
  }
  // 3-sigma gate on σ² + r: at most a few per mille rejected.
  EXPECT_GT(static_cast<double>(fused) / static_cast<double>(total), 0.99);
  double sum = 0.0;
  std::size_t n = 0;
  map.ForEachCell([&](CellIndex, const CellValue& v) {
    sum += v.elevation_m;
    ++n;
  });
  EXPECT_NEAR(sum / static_cast<double>(n), 0.5, 0.002);
}

TEST(ElevationMap, InFrameDisagreementHigherPointWins) {
  ElevationMap map;
  FusionStats stats;
  EXPECT_TRUE(map.FusePoint({0.01, 0.01, 0.0}, 1e-4, 3, &stats));
  EXPECT_FALSE(map.FusePoint({0.02, 0.02, -0.5}, 1e-4, 3, &stats));  // lower: dropped
  EXPECT_EQ(stats.below_in_frame, 1u);
  EXPECT_TRUE(map.FusePoint({0.03, 0.03, 0.4}, 1e-4, 3, &stats));  // higher: wins
  EXPECT_EQ(stats.replaced, 1u);
  const auto v = map.Cell({0, 0});
  ASSERT_TRUE(v.has_value());
  EXPECT_EQ(v->elevation_m, 0.4f);
  EXPECT_EQ(v->count, 1u);
  EXPECT_EQ(v->min_m, -0.5f);  // the spread of the cell is kept
  EXPECT_EQ(v->max_m, 0.4f);
  EXPECT_EQ(v->last_frame, 3u);
  // A later frame disagreeing is an outlier, higher or not.
  EXPECT_FALSE(map.FusePoint({0.03, 0.03, 1.4}, 1e-4, 4, &stats));
  EXPECT_EQ(stats.rejected_outliers, 1u);
  EXPECT_EQ(map.Cell({0, 0})->elevation_m, 0.4f);
}

TEST(ElevationMap, NonFiniteInputIsCountedAndIgnored) {
  ElevationMap map;
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector3d> points = {{kNaN, 0, 0}, {0, kNaN, 0},    {0, 0, kNaN}, {inf, 0, 0},
                                         {0, 0, -inf}, {0.1, 0.1, 2.0}, {1e300, 0, 0}};
  const FusionStats stats = map.FuseFrame(points, {}, Frame(0));
  EXPECT_EQ(stats.points, 7u);
  EXPECT_EQ(stats.dropped_nonfinite, 5u);
  EXPECT_EQ(stats.dropped_out_of_grid, 1u);
  EXPECT_EQ(stats.fused, 1u);
  EXPECT_EQ(map.CellCount(), 1u);
  EXPECT_EQ(map.TileCount(), 1u);
  EXPECT_EQ(map.HeightAt(0.1, 0.1), 2.0);
  // A non-finite covariance drops its point as well.
  std::vector<Eigen::Matrix3d> covariances(2, Eigen::Matrix3d::Identity() * 1e-4);
  covariances[1](2, 2) = kNaN;
  const FusionStats s2 = map.FuseFrame({{5, 5, 1}, {6, 6, 1}}, covariances, Frame(1));
  EXPECT_EQ(s2.dropped_nonfinite, 1u);
  EXPECT_EQ(s2.fused, 1u);
}

TEST(ElevationMap, TilesOnlyWherePointsFell) {
  ElevationMap map;  // 0.05 m × 256 = 12.8 m tiles
  const auto flat = [](double, double) { return 0.0; };
  auto a = Sample(flat, 1.0, 2.0, 1.0, 2.0, 1000, 1);          // tile (0, 0)
  auto b = Sample(flat, -101.0, -100.5, 50.0, 51.0, 1000, 2);  // tile (-8, 3)
  a.insert(a.end(), b.begin(), b.end());
  const FusionStats stats = map.FuseFrame(a, {}, Frame(0));
  EXPECT_EQ(stats.new_tiles, 2u);
  ASSERT_EQ(map.TileCount(), 2u);
  std::set<std::pair<std::int64_t, std::int64_t>> tiles;
  for (const TileIndex t : map.TileIndices()) tiles.insert({t.x, t.y});
  EXPECT_EQ(tiles, (std::set<std::pair<std::int64_t, std::int64_t>>{{0, 0}, {-8, 3}}));
  ASSERT_NE(map.FindTile({-8, 3}), nullptr);
  EXPECT_TRUE(std::isnan(map.FindTile({-8, 3})->cells[0].value.elevation_m));  // untouched
  EXPECT_EQ(map.FindTile({-7, 3}), nullptr);
  EXPECT_EQ(map.bounds().Min().x, map.index().WorldToCell(-101.0, 0)->x);
}

TEST(ElevationMap, MemoryFollowsAreaNotPoints) {
  ElevationMap map;
  const auto flat = [](double, double) { return 0.0; };
  for (std::uint32_t f = 0; f < 20; ++f)
    map.FuseFrame(Sample(flat, 0, 5, 0, 5, 20000, f), {}, Frame(f));
  const std::size_t bytes = map.MemoryBytes();
  EXPECT_EQ(map.TileCount(), 1u);
  for (std::uint32_t f = 20; f < 40; ++f)
    map.FuseFrame(Sample(flat, 0, 5, 0, 5, 20000, f), {}, Frame(f));
  EXPECT_EQ(map.MemoryBytes(), bytes);
  // A 1 km straight traverse, 4 m wide: about 80 tiles, not a dense 1 km² grid.
  ElevationMap traverse;
  for (int k = 0; k < 500; ++k) {
    const double x0 = 2.0 * k;
    traverse.FuseFrame(Sample(flat, x0, x0 + 2.0, -2.0, 2.0, 2000, static_cast<unsigned>(k)), {},
                       Frame(static_cast<std::uint32_t>(k)));
  }
  EXPECT_LE(traverse.TileCount(), 2u * (1000 / 12 + 2));
}

TEST(ElevationMap, CovarianceProjectionAndPoseUncertainty) {
  ElevationMap map;
  // Height variance from a sensor-frame covariance: r3ᵀ Σ r3.
  Eigen::Matrix3d sigma = Eigen::Vector3d(0.01, 0.04, 0.09).asDiagonal();
  FrameContext ctx = Frame(0);
  map.FuseFrame({{0.01, 0.01, 0.0}}, {sigma}, ctx);
  EXPECT_NEAR(map.VarianceAt(0.01, 0.01), 0.09, 1e-7);
  // Sensor z forward, world z = −sensor y (rotation about x by +90°): variance of sensor y.
  ctx.R_world_cov = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  map.FuseFrame({{1.01, 0.01, 0.0}}, {sigma}, ctx);
  EXPECT_NEAR(map.VarianceAt(1.01, 0.01), 0.04, 1e-7);
  // Pose: 0.01 rad² of pitch (ry) and 1e-4 m² in tz: a point dx ahead gets dx²·0.01 + 1e-4.
  Eigen::Matrix<double, 6, 6> pose = Eigen::Matrix<double, 6, 6>::Zero();
  pose(1, 1) = 0.01;
  pose(5, 5) = 1e-4;
  FrameContext posed = Frame(1);
  posed.pose_covariance = pose;
  map.FuseFrame({{3.01, 0.01, 0.0}, {0.01, 2.01, 0.0}}, {}, posed);
  EXPECT_NEAR(map.VarianceAt(3.01, 0.01), 0.0004 + 3.01 * 3.01 * 0.01 + 1e-4, 1e-8);
  // Pitch hardly moves a point beside the sensor.
  EXPECT_NEAR(map.VarianceAt(0.01, 2.01), 0.0004 + 0.01 * 0.01 * 0.01 + 1e-4, 1e-9);
}

TEST(ElevationMap, RotatedGridRoundTrips) {
  ElevationMapOptions options;
  options.grid_rotation_rad = 0.3;
  ElevationMap map(options);
  const Eigen::Vector2d g = map.WorldToGrid(3.0, -2.0);
  const Eigen::Vector2d w = map.GridToWorld(g);
  EXPECT_NEAR(w.x(), 3.0, 1e-12);
  EXPECT_NEAR(w.y(), -2.0, 1e-12);
  EXPECT_NEAR(g.norm(), std::hypot(3.0, 2.0), 1e-12);
  for (std::int64_t i = -5; i < 5; ++i) {
    const CellIndex c{i * 7, -i * 3};
    const Eigen::Vector2d centre = map.CellCenterWorld(c);
    EXPECT_EQ(*map.WorldToCell(centre.x(), centre.y()), c);
  }
  map.FusePoint({1.0, 1.0, 0.7}, 1e-4, 0);
  EXPECT_EQ(map.HeightAt(1.0, 1.0), 0.7f);
}

TEST(ElevationMap, MovedMapsKeepWorking) {
  ElevationMap a;
  a.FusePoint({0.01, 0.01, 1.0}, 1e-4, 0);
  ElevationMap b = std::move(a);
  EXPECT_EQ(b.HeightAt(0.01, 0.01), 1.0);
  b.FusePoint({0.02, 0.02, 1.0}, 1e-4, 0);
  EXPECT_EQ(b.Cell({0, 0})->count, 2u);
  a = ElevationMap{};  // the moved-from map is reusable
  a.FusePoint({0.01, 0.01, 3.0}, 1e-4, 0);
  EXPECT_EQ(a.HeightAt(0.01, 0.01), 3.0);
  EXPECT_EQ(b.HeightAt(0.01, 0.01), 1.0);
}

TEST(ElevationMap, SetCellWritesAndClears) {
  ElevationMap map;
  map.SetCell({3, 4}, 1.5, 0.01, 2);
  ASSERT_TRUE(map.Cell({3, 4}).has_value());
  EXPECT_EQ(map.Cell({3, 4})->count, 2u);
  EXPECT_EQ(map.CellCount(), 1u);
  map.SetCell({3, 4}, kNaN, 0.0);
  EXPECT_FALSE(map.Cell({3, 4}).has_value());
  EXPECT_EQ(map.CellCount(), 0u);
}

}  // namespace
}  // namespace rovermap::dem
