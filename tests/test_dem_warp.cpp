// mapper/DemWarp: the chain's DEM moved onto a solved pose graph's poses (what `serve`
// publishes). Property checks against known corrections: a plane moved rigidly stays the moved
// plane, each cell follows its own frame, the pose share of σ is traded, nothing moves without
// a solved graph.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "io/DemLayers.hpp"
#include "mapper/DemWarp.hpp"
#include "tests/support/Poses.hpp"

namespace {

using rovermap::io::DemLayers;
using rovermap::mapper::DemWarpStats;
using rovermap::mapper::FrameResult;
using rovermap::mapper::GraphOutcome;
using rovermap::mapper::WarpDemToGraph;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

constexpr double kCell = 0.1;  // [m]

double Plane(double x, double y) { return 1.0 + 0.05 * x - 0.02 * y; }

// A 60 × 40-cell DEM of Plane from cell (10, 20), σ 5 cm; columns < split made by frame 0,
// the others by frame 1.
DemLayers PlaneDem(int split = 60) {
  DemLayers d;
  d.min = {10, 20};
  d.width = 60;
  d.height = 40;
  d.max = {d.min.x + d.width - 1, d.min.y + d.height - 1};
  d.cell_size_m = kCell;
  for (int row = 0; row < d.height; ++row) {
    for (int col = 0; col < d.width; ++col) {
      const double x = (d.min.x + col + 0.5) * kCell, y = (d.max.y - row + 0.5) * kCell;
      d.elevation_m.push_back(static_cast<float>(Plane(x, y)));
      d.stddev_m.push_back(0.05f);
      d.count.push_back(3.0f);
      d.frame.push_back(col < split ? 0u : 1u);
    }
  }
  d.valid_cells = d.elevation_m.size();
  return d;
}

const auto& Pose = rovermap::testing::PlanarPose;
const auto& Diagonal = rovermap::testing::DiagonalCovariance;

// Two frames, chained at `chain` and solved at correction[k] · chain[k].
struct Solved {
  std::vector<FrameResult> results;
  GraphOutcome graph;
};

Solved TwoFrames(const std::vector<Eigen::Isometry3d>& correction, const Matrix6d& chain_cov,
                 const Matrix6d& graph_cov) {
  Solved r;
  r.graph.solution.solved = true;
  for (std::size_t k = 0; k < 2; ++k) {
    FrameResult f;
    f.index = k;
    f.step.index = k;
    f.step.T_world_body = Pose(2.0 + 3.0 * k, 3.0, 10.0 * k);
    f.step.covariance = chain_cov;
    r.results.push_back(f);
    r.graph.solution.T_world_body.push_back(correction[k] * f.step.T_world_body);
    r.graph.solution.covariance.push_back(graph_cov);
  }
  return r;
}

// The moved DEM's height at the centre of cell (cx, cy); NaN if not published.
double HeightAt(const DemLayers& d, std::int64_t cx, std::int64_t cy) {
  if (cx < d.min.x || cx > d.max.x || cy < d.min.y || cy > d.max.y)
    return std::numeric_limits<double>::quiet_NaN();
  return d.elevation_m[static_cast<std::size_t>(d.max.y - cy) * d.width + (cx - d.min.x)];
}

// Correction C moves world points p to C p; the moved plane's height at q is that of the plane
// at C⁻¹ q, moved up by C's lift there.
double MovedPlane(const Eigen::Isometry3d& C, double x, double y) {
  // Solve for the source (x0, y0) with the z of the moved point irrelevant to x, y (C has only
  // yaw and a shift here): x, y = R (x0, y0) + t.
  const Eigen::Vector3d src = C.inverse() * Eigen::Vector3d(x, y, 0.0);
  return Plane(src.x(), src.y()) + C.translation().z();
}

TEST(DemWarp, AShiftByWholeAndPartCellsKeepsThePlaneExactlyInside) {
  const DemLayers dem = PlaneDem();
  Eigen::Isometry3d C = Eigen::Isometry3d::Identity();
  C.translation() = Eigen::Vector3d(0.537, -0.284, 0.12);
  const Solved run = TwoFrames({C, C}, Diagonal(1e-3, 0.1), Diagonal(1e-3, 0.1));
  DemWarpStats stats;
  const DemLayers moved = WarpDemToGraph(dem, run.results, run.graph, &stats);
  EXPECT_EQ(stats.cells_in, dem.valid_cells);
  EXPECT_EQ(stats.cells_moved, dem.valid_cells);
  EXPECT_NEAR(stats.median_shift_m, std::hypot(0.537, 0.284), 1e-9);
  // Inside (two cells from the edges), bilinear weights reproduce a plane exactly.
  int checked = 0;
  for (std::int64_t cy = moved.min.y + 2; cy <= moved.max.y - 2; ++cy) {
    for (std::int64_t cx = moved.min.x + 2; cx <= moved.max.x - 2; ++cx) {
      const double z = HeightAt(moved, cx, cy);
      ASSERT_TRUE(std::isfinite(z)) << cx << " " << cy;
      EXPECT_NEAR(z, MovedPlane(C, (cx + 0.5) * kCell, (cy + 0.5) * kCell), 1e-5);
      ++checked;
    }
  }
  EXPECT_GT(checked, 1500);
  // The footprint moved with it: about as many cells, 5 whole and 3 part cells east and south.
  EXPECT_NEAR(static_cast<double>(moved.valid_cells), static_cast<double>(dem.valid_cells),
              0.05 * dem.valid_cells);
  EXPECT_EQ(moved.min.x, dem.min.x + 5);
  EXPECT_EQ(moved.max.y, dem.max.y - 2);
}

TEST(DemWarp, EachCellFollowsItsOwnFramesCorrection) {
  // Frame 0 made the western half, frame 1 the eastern; the graph moves frame 1 one metre
  // north and turns it 1° about its position, frame 0 not at all.
  const DemLayers dem = PlaneDem(30);
  const Eigen::Isometry3d T1 = Pose(5.0, 3.0, 10.0);
  const Eigen::Isometry3d turn = Pose(0.0, 1.0, 1.0);
  const Eigen::Isometry3d C1 = Pose(0, 0, 0) * T1 * turn * T1.inverse();
  const Solved run =
      TwoFrames({Eigen::Isometry3d::Identity(), C1}, Diagonal(1e-3, 0.1), Diagonal(1e-3, 0.1));
  const DemLayers moved = WarpDemToGraph(dem, run.results, run.graph);
  // The western half in place (but where the eastern one, moved 1.7 cells west and turned, now
  // overlaps it), the eastern half where the correction put it.
  for (std::int64_t cy = dem.min.y + 2; cy <= dem.max.y - 2; ++cy) {
    for (std::int64_t cx = dem.min.x + 2; cx < dem.min.x + 26; ++cx) {  // clear of the east
      EXPECT_NEAR(HeightAt(moved, cx, cy), Plane((cx + 0.5) * kCell, (cy + 0.5) * kCell), 1e-5)
          << cx << " " << cy;
    }
  }
  int checked = 0;
  for (std::int64_t cy = dem.max.y + 3; cy <= dem.max.y + 9; ++cy) {  // north of the old edge
    for (std::int64_t cx = dem.min.x + 34; cx <= dem.max.x - 4; ++cx) {
      const double z = HeightAt(moved, cx, cy);
      if (!std::isfinite(z)) continue;
      // Rotated by 1°: bilinear weights of a turned lattice are not exact, within 0.2 mm.
      EXPECT_NEAR(z, MovedPlane(C1, (cx + 0.5) * kCell, (cy + 0.5) * kCell), 2e-4);
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(DemWarp, ThePoseShareOfSigmaIsTradedForTheGraphs) {
  // z σ 0.3 m in the chain, 0.1 m in the graph, no attitude error: the cell's variance loses
  // 0.09 − 0.01 m², floored at the variance scaled by the ratio of the shares.
  DemLayers dem = PlaneDem();
  for (float& s : dem.stddev_m) s = static_cast<float>(std::sqrt(0.3 * 0.3 + 0.02 * 0.02));
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  const Solved tighter = TwoFrames({I, I}, Diagonal(0.0, 0.3), Diagonal(0.0, 0.1));
  const DemLayers a = WarpDemToGraph(dem, tighter.results, tighter.graph);
  const double expected = std::sqrt(0.3 * 0.3 + 0.02 * 0.02 - 0.09 + 0.01);
  EXPECT_NEAR(a.stddev_m[a.width * 20 + 30], expected, 1e-5);
  // A cell whose σ is less than the chain's share (the fusion averaged it over frames): scaled.
  for (float& s : dem.stddev_m) s = 0.15f;
  const DemLayers b = WarpDemToGraph(dem, tighter.results, tighter.graph);
  EXPECT_NEAR(b.stddev_m[b.width * 20 + 30], 0.15 * 0.1 / 0.3, 1e-5);
  // A graph less certain than the chain (a GNSS outage after a reference match): σ grows.
  const Solved looser = TwoFrames({I, I}, Diagonal(0.0, 0.1), Diagonal(0.0, 0.3));
  const DemLayers c = WarpDemToGraph(dem, looser.results, looser.graph);
  EXPECT_NEAR(c.stddev_m[c.width * 20 + 30], std::sqrt(0.15 * 0.15 + 0.09 - 0.01), 1e-5);
  // Heights unchanged by an identity correction.
  EXPECT_NEAR(HeightAt(a, 40, 40), HeightAt(dem, 40, 40), 1e-6);
}

TEST(DemWarp, AttitudeUncertaintyGrowsWithTheLeverArm) {
  // Only a roll σ: the share is (dy σ)², zero under the body, growing away from it.
  DemLayers dem = PlaneDem();
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  Matrix6d roll = Matrix6d::Zero();
  roll(0, 0) = 0.01 * 0.01;
  const Solved run = TwoFrames({I, I}, Matrix6d::Zero(), roll);
  const DemLayers moved = WarpDemToGraph(dem, run.results, run.graph);
  // Frame 0 is at (2, 3), yaw 0: row of y = 3 has no lever arm, y = 4.95 has 1.95 m.
  const auto sigma_at = [&](std::int64_t cx, std::int64_t cy) {
    return moved
        .stddev_m[static_cast<std::size_t>(moved.max.y - cy) * moved.width + (cx - moved.min.x)];
  };
  EXPECT_NEAR(sigma_at(20, 30), std::hypot(0.05, 0.01 * 0.05), 1e-6);  // (2.05, 3.05)
  EXPECT_NEAR(sigma_at(20, 49), std::sqrt(0.05 * 0.05 + std::pow(0.01 * 1.95, 2)), 1e-5);
}

TEST(DemWarp, CorrectionsThatTearTheMapApartKeepTheChainsDem) {
  // Frame 1's correction throws its half 7 km away: the raster would be millions of times the
  // chain's; the chain's DEM is kept and the stats say why.
  const DemLayers dem = PlaneDem(30);
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() = Eigen::Vector3d(5000.0, 5000.0, 0.0);
  const Solved run =
      TwoFrames({Eigen::Isometry3d::Identity(), far}, Diagonal(1e-3, 0.1), Diagonal(1e-3, 0.1));
  DemWarpStats stats;
  const DemLayers kept = WarpDemToGraph(dem, run.results, run.graph, &stats);
  EXPECT_EQ(kept.elevation_m, dem.elevation_m);
  EXPECT_EQ(stats.cells_moved, 0u);
  EXPECT_NE(stats.refused.find("more than 4 times the chain's"), std::string::npos)
      << stats.refused;
}

TEST(DemWarp, NothingMovesWithoutASolvedGraphOrTheFramesLayer) {
  const DemLayers dem = PlaneDem();
  Eigen::Isometry3d C = Eigen::Isometry3d::Identity();
  C.translation() = Eigen::Vector3d(1.0, 0.0, 0.0);
  Solved run = TwoFrames({C, C}, Diagonal(1e-3, 0.1), Diagonal(1e-3, 0.1));
  run.graph.solution.solved = false;
  const DemLayers a = WarpDemToGraph(dem, run.results, run.graph);
  EXPECT_EQ(a.min.x, dem.min.x);
  EXPECT_EQ(a.elevation_m, dem.elevation_m);
  run.graph.solution.solved = true;
  DemLayers no_frames = dem;
  no_frames.frame.clear();  // a DEM read from a file
  const DemLayers b = WarpDemToGraph(no_frames, run.results, run.graph);
  EXPECT_EQ(b.elevation_m, dem.elevation_m);
  // A frame the results do not hold keeps its place.
  DemLayers unknown = dem;
  for (auto& f : unknown.frame) f = 7;
  DemWarpStats stats;
  const DemLayers c = WarpDemToGraph(unknown, run.results, run.graph, &stats);
  EXPECT_EQ(stats.cells_moved, 0u);
  EXPECT_EQ(c.min.x, dem.min.x);
  EXPECT_NEAR(HeightAt(c, 40, 40), HeightAt(dem, 40, 40), 1e-6);
}

}  // namespace
