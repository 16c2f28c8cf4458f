// terrain::ComputeTerrain (docs/terrain.md): the layers on analytic surfaces, against a
// per-cell least-squares fit written the obvious way, the σ's coverage, and bad grids.

#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstring>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

#include "eval/DemComparison.hpp"
#include "io/GeoTiff.hpp"
#include "io/TerrainOutputs.hpp"
#include "terrain/TerrainCache.hpp"
#include "terrain/TerrainLayers.hpp"
#include "tests/support/CommandFixture.hpp"
#include "tests/support/DemWriting.hpp"

namespace rovermap::terrain {
namespace {

constexpr double kDeg = M_PI / 180.0;
const float kNaN = std::numeric_limits<float>::quiet_NaN();

// A grid of heights f(x, y) at cell centres (x east, y north [m], row 0 north), with σ.
struct Grid {
  int width = 0, height = 0;
  double dx = 0.0, dy = 0.0;
  std::vector<float> z, sigma;
  GridView View(bool with_sigma = true) const {
    return {width, height, dx, dy, z.data(), with_sigma ? sigma.data() : nullptr};
  }
  std::size_t Index(int r, int c) const { return static_cast<std::size_t>(r) * width + c; }
};

Grid MakeGrid(int width, int height, double dx, double dy,
              const std::function<double(double, double)>& f, float sigma) {
  Grid g{width, height, dx, dy, {}, {}};
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      g.z.push_back(static_cast<float>(f(c * dx, -r * dy)));
      g.sigma.push_back(sigma);
    }
  }
  return g;
}

TerrainOptions Options(double footprint_m) {
  TerrainOptions o;
  o.footprint_m = footprint_m;
  return o;
}

// The reference: each cell's footprint gathered and fitted with Eigen, the obvious way.
struct BruteForce {
  double slope_deg = NAN, roughness_m = NAN, step_m = NAN;
};
BruteForce FitAt(const Grid& g, int r, int c, int hx, int hy, bool weighted) {
  std::vector<Eigen::Vector3d> rows;
  std::vector<double> w, z;
  double lo = INFINITY, hi = -INFINITY;
  for (int i = std::max(0, r - hy); i <= std::min(g.height - 1, r + hy); ++i) {
    for (int j = std::max(0, c - hx); j <= std::min(g.width - 1, c + hx); ++j) {
      const float h = g.z[g.Index(i, j)];
      if (std::isnan(h)) continue;
      rows.emplace_back(1.0, (j - c) * g.dx, (i - r) * g.dy);
      w.push_back(weighted ? 1.0 / (double(g.sigma[g.Index(i, j)]) * g.sigma[g.Index(i, j)]) : 1.0);
      z.push_back(h);
      lo = std::min(lo, double(h));
      hi = std::max(hi, double(h));
    }
  }
  BruteForce out;
  if (rows.size() < 3) return out;
  Eigen::MatrixXd A(rows.size(), 3);
  Eigen::VectorXd b(rows.size()), sw(rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    A.row(k) = rows[k].transpose();
    b(k) = z[k];
    sw(k) = std::sqrt(w[k]);
  }
  const Eigen::Vector3d beta =
      (sw.asDiagonal() * A).colPivHouseholderQr().solve(sw.asDiagonal() * b);
  const Eigen::VectorXd res = b - A * beta;
  double rss = 0.0, sum_w = 0.0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    rss += w[k] * res(k) * res(k);
    sum_w += w[k];
  }
  out.slope_deg = std::atan(beta.tail<2>().norm()) / kDeg;
  out.roughness_m = std::sqrt(rss / sum_w);
  out.step_m = hi - lo;
  return out;
}

TEST(TerrainLayers, PlanesOfKnownSlopeOnUtmAndPlanetaryGrids) {
  struct Case {
    double dx, dy, footprint_m, slope_deg, azimuth_deg;
  };
  // 5 cm cells (a rover's DEM in UTM), 1 m × 1.2 m posts (an orbital product in a planetary
  // local projection, metres either way).
  for (const Case k : {Case{0.05, 0.05, 0.6, 5.0, 30.0}, Case{0.05, 0.05, 0.6, 25.0, 200.0},
                       Case{1.0, 1.2, 9.0, 12.0, 100.0}, Case{1.0, 1.2, 9.0, 35.0, 300.0}}) {
    const double g = std::tan(k.slope_deg * kDeg);
    const double gx = g * std::cos(k.azimuth_deg * kDeg), gy = g * std::sin(k.azimuth_deg * kDeg);
    const Grid grid = MakeGrid(
        60, 50, k.dx, k.dy, [&](double x, double y) { return 100.0 + gx * x + gy * y; }, 0.01f);
    const TerrainLayers t = ComputeTerrain(grid.View(), Options(k.footprint_m));
    const int hx = (t.footprint_cols - 1) / 2, hy = (t.footprint_rows - 1) / 2;
    for (int r = hy; r < grid.height - hy; ++r) {
      for (int c = hx; c < grid.width - hx; ++c) {
        const std::size_t i = grid.Index(r, c);
        ASSERT_NEAR(t.slope_deg[i], k.slope_deg, 0.05) << k.dx << " m cells, r " << r << " c " << c;
        // A plane's step over the whole footprint: its rise across the rectangle's corners.
        const double step = std::abs(gx) * 2 * hx * k.dx + std::abs(gy) * 2 * hy * k.dy;
        ASSERT_NEAR(t.step_m[i], step, std::max(1e-3, 0.05 * step));
        ASSERT_LT(t.roughness_m[i], 1e-3);
      }
    }
  }
}

TEST(TerrainLayers, PrefixSumsGiveThePerCellFitOnRoughGroundWithHoles) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Grid grid = MakeGrid(
      90, 70, 0.05, 0.05,
      [&](double x, double y) { return 0.3 * x - 0.1 * y + 0.05 * std::sin(7 * x) + noise(rng); },
      0.0f);
  for (std::size_t i = 0; i < grid.z.size(); ++i) {
    grid.sigma[i] = static_cast<float>(0.005 + 0.03 * u(rng));
    if (u(rng) < 0.15) grid.z[i] = kNaN;  // holes
  }
  for (bool weighted : {true, false}) {
    TerrainOptions o = Options(0.5);
    o.min_coverage = 0.3;
    o.tile_cells = 32;  // several tiles: their halos must give the same sums
    const TerrainLayers t = ComputeTerrain(grid.View(weighted), o);
    const int hx = (t.footprint_cols - 1) / 2, hy = (t.footprint_rows - 1) / 2;
    int compared = 0;
    for (int r = 0; r < grid.height; ++r) {
      for (int c = 0; c < grid.width; ++c) {
        const std::size_t i = grid.Index(r, c);
        if (std::isnan(t.slope_deg[i])) continue;
        const BruteForce b = FitAt(grid, r, c, hx, hy, weighted);
        ASSERT_NEAR(t.slope_deg[i], b.slope_deg, 1e-3) << r << " " << c;
        ASSERT_NEAR(t.roughness_m[i], b.roughness_m, 1e-5) << r << " " << c;
        ASSERT_NEAR(t.step_m[i], b.step_m, 1e-5) << r << " " << c;
        ++compared;
      }
    }
    EXPECT_GT(compared, grid.width * grid.height * 8 / 10);
  }
}

TEST(TerrainLayers, TilesDoNotChangeTheLayers) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  const Grid grid = MakeGrid(
      150, 110, 0.05, 0.05, [&](double x, double y) { return 0.1 * x * y + noise(rng); }, 0.01f);
  TerrainOptions small = Options(0.6), large = Options(0.6);
  small.tile_cells = 16;
  large.tile_cells = 4096;
  const TerrainLayers a = ComputeTerrain(grid.View(), small);
  const TerrainLayers b = ComputeTerrain(grid.View(), large);
  ASSERT_EQ(a.slope_deg.size(), b.slope_deg.size());
  const auto same = [](float x, float y, float tolerance) {
    return (std::isnan(x) && std::isnan(y)) || std::abs(x - y) <= tolerance;
  };
  for (std::size_t i = 0; i < a.slope_deg.size(); ++i) {
    ASSERT_TRUE(same(a.slope_deg[i], b.slope_deg[i], 1e-4f)) << i;
    ASSERT_TRUE(same(a.roughness_m[i], b.roughness_m[i], 1e-6f)) << i;
    ASSERT_TRUE(same(a.step_m[i], b.step_m[i], 0.0f)) << i;
    ASSERT_TRUE(same(a.uncertain[i], b.uncertain[i], 0.0f)) << i;
  }
  EXPECT_EQ(a.known, b.known);
  EXPECT_EQ(a.hazard, b.hazard);
}

// A map as serve publishes it again and again: it grows (west and south), gains ground and
// changes in places. Through a TerrainCache each publication equals a full computation on its
// grid, to the bit, and only the tiles whose footprints saw a change are computed anew.
TEST(TerrainCache, EqualsAFullComputationAsTheMapGrowsAndComputesOnlyChangedTiles) {
  constexpr double kCell = 0.05;
  // Heights of global cell (col, row), rows counting south; `bumped` cells raised by 10 cm.
  std::vector<std::pair<std::int64_t, std::int64_t>> bumped;
  const auto height = [&](std::int64_t col, std::int64_t row) {
    const double x = col * kCell, y = -row * kCell;
    double z = 0.2 * std::sin(0.9 * x) * std::cos(0.6 * y) + 0.004 * std::sin(37.0 * x + 11.0 * y);
    for (const auto& [c, r] : bumped) z += (c == col && r == row) ? 0.1 : 0.0;
    return static_cast<float>(z);
  };
  struct Map {
    std::int64_t col0, row0;
    int width, height;
    std::vector<float> z, sigma;
    GridView View(bool with_sigma = true) const {
      GridView g{width, height, kCell, kCell, z.data(), with_sigma ? sigma.data() : nullptr};
      g.origin_col = col0;
      g.origin_row = row0;
      return g;
    }
  };
  // Data on [data_c0, data_c1) × [data_r0, data_r1), in a grid of exactly those bounds.
  const auto make = [&](std::int64_t c0, std::int64_t c1, std::int64_t r0, std::int64_t r1) {
    Map m{c0, r0, static_cast<int>(c1 - c0), static_cast<int>(r1 - r0), {}, {}};
    for (std::int64_t r = r0; r < r1; ++r) {
      for (std::int64_t c = c0; c < c1; ++c) {
        // A hole pattern, fixed to the ground, so that coverage varies.
        const bool hole = (c * 7 + r * 3) % 23 == 0;
        m.z.push_back(hole ? kNaN : height(c, r));
        m.sigma.push_back(hole ? kNaN : 0.01f + 0.0001f * static_cast<float>((c + 2 * r) % 13));
      }
    }
    return m;
  };
  const auto bits_equal = [](const std::vector<float>& a, const std::vector<float>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (std::isnan(a[i]) != std::isnan(b[i])) return false;
      if (!std::isnan(a[i]) && std::memcmp(&a[i], &b[i], sizeof(float)) != 0) return false;
    }
    return true;
  };
  TerrainOptions o = Options(0.6);  // 13 × 13 cells: a halo of 6
  o.tile_cells = 64;
  TerrainCache cache;
  const auto publish = [&](const Map& m, bool with_sigma = true) {
    const TerrainLayers& got = cache.Update(m.View(with_sigma), o);
    const TerrainLayers full = ComputeTerrain(m.View(with_sigma), o);
    EXPECT_TRUE(bits_equal(got.slope_deg, full.slope_deg));
    EXPECT_TRUE(bits_equal(got.slope_sigma_deg, full.slope_sigma_deg));
    EXPECT_TRUE(bits_equal(got.roughness_m, full.roughness_m));
    EXPECT_TRUE(bits_equal(got.step_m, full.step_m));
    EXPECT_TRUE(bits_equal(got.traversability, full.traversability));
    EXPECT_TRUE(bits_equal(got.uncertain, full.uncertain));
    EXPECT_EQ(got.known, full.known);
    EXPECT_EQ(got.hazard, full.hazard);
    EXPECT_EQ(got.uncertain_cells, full.uncertain_cells);
    EXPECT_GT(got.known, 1000u);
    return cache.tiles_computed();
  };

  // Global columns [-40, 160) and rows [-30, 90): tiles -1..2 × -1..1, 12 tiles.
  const Map first = make(-40, 160, -30, 90);
  EXPECT_EQ(publish(first), 12u);
  EXPECT_EQ(cache.tiles(), 12u);
  EXPECT_EQ(publish(first), 0u);  // nothing changed

  // The map grows west (to -120) and south (to 150): the old tiles whose footprints reach the
  // new ground (the western and southern edges, and those the old grid did not hold whole) are
  // computed; the others are copied.
  const Map grown = make(-120, 160, -30, 150);
  // Tiles -2..2 × -1..2; copied: columns 0..2 of rows -1 and 0 (their footprints lie within
  // the old ground, which did not change).
  EXPECT_EQ(publish(grown), 20u - 6u);
  EXPECT_EQ(cache.tiles(), 20u);

  // One cell changes in the middle of tile (1, 0): that tile alone.
  bumped = {{100, 30}};
  EXPECT_EQ(publish(make(-120, 160, -30, 150)), 1u);
  // One near the corner of four tiles (64, 64): the four whose footprints reach it.
  bumped.push_back({62, 66});
  EXPECT_EQ(publish(make(-120, 160, -30, 150)), 4u);

  // Other options, or heights without σ: every tile.
  const Map last = make(-120, 160, -30, 150);
  o.max_step_m = 0.12;
  EXPECT_EQ(publish(last), cache.tiles());
  EXPECT_EQ(publish(last, false), cache.tiles());
  EXPECT_EQ(publish(last, false), 0u);

  // A grid that reaches farther without more ground (NaN around it) gives the same values for
  // the same cells, also in the tiles the old grid held only in part.
  Map padded{last.col0 - 50, last.row0 - 20, last.width + 90, last.height + 70, {}, {}};
  padded.z.assign(static_cast<std::size_t>(padded.width) * padded.height, kNaN);
  padded.sigma = padded.z;
  for (int r = 0; r < last.height; ++r) {
    for (int c = 0; c < last.width; ++c) {
      const std::size_t to = static_cast<std::size_t>(r + 20) * padded.width + (c + 50);
      padded.z[to] = last.z[static_cast<std::size_t>(r) * last.width + c];
      padded.sigma[to] = last.sigma[static_cast<std::size_t>(r) * last.width + c];
    }
  }
  const TerrainLayers small = ComputeTerrain(last.View(), o);
  const TerrainLayers large = ComputeTerrain(padded.View(), o);
  for (int r = 0; r < last.height; ++r) {
    for (int c = 0; c < last.width; ++c) {
      const float a = small.roughness_m[static_cast<std::size_t>(r) * last.width + c];
      const float b = large.roughness_m[static_cast<std::size_t>(r + 20) * padded.width + c + 50];
      ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0)
          << r << " " << c;
    }
  }
}

TEST(TerrainLayers, SinusoidRoughnessAndStep) {
  // Ripples of 3 cm amplitude and 0.1 m wavelength across a 1.05 m footprint: the plane is
  // flat, the residual the sinusoid's RMS (A/√2) and the step its full height (2A).
  const double amplitude = 0.03, wavelength = 0.1;
  const Grid grid = MakeGrid(
      120, 80, 0.005, 0.005,
      [&](double x, double) { return amplitude * std::sin(2 * M_PI * x / wavelength); }, 0.001f);
  // 0.3 m footprint: 61 cells, three wavelengths, centred on a crest (x = 3.25 wavelengths):
  // the ripples are even about the centre, so no plane tilt takes up part of them.
  const TerrainLayers t = ComputeTerrain(grid.View(), Options(0.3));
  const std::size_t centre = grid.Index(40, 65);
  EXPECT_NEAR(t.roughness_m[centre], amplitude / std::sqrt(2.0), 0.05 * amplitude / std::sqrt(2.0));
  EXPECT_NEAR(t.step_m[centre], 2 * amplitude, std::max(1e-3, 0.05 * 2 * amplitude));
  EXPECT_LT(t.slope_deg[centre], 1.0);
}

TEST(TerrainLayers, AStepIsAHazardExactlyWhereTheFootprintReachesIt) {
  // A 0.2 m ledge along x = 1.5 m, on flat ground; precise heights (1 mm).
  const Grid grid = MakeGrid(
      60, 40, 0.05, 0.05, [](double x, double) { return x >= 1.5 - 1e-9 ? 0.2 : 0.0; }, 0.001f);
  TerrainOptions o = Options(0.5);  // 11 cells
  o.max_step_m = 0.15;
  o.max_slope_deg = 80.0;  // the ledge tilts the fitted plane: judge it by its step alone
  o.max_roughness_m = 1.0;
  const TerrainLayers t = ComputeTerrain(grid.View(), o);
  const int h = (t.footprint_cols - 1) / 2;
  const int ledge = 30;  // first column at 0.2 m
  for (int r = 0; r < grid.height; ++r) {
    for (int c = 0; c < grid.width; ++c) {
      const std::size_t i = grid.Index(r, c);
      if (std::isnan(t.traversability[i])) continue;
      const bool reaches = c - h <= ledge - 1 && c + h >= ledge;
      ASSERT_NEAR(t.step_m[i], reaches ? 0.2 : 0.0, 1e-6) << c;
      ASSERT_EQ(t.traversability[i] == 0.0f, reaches) << c;
      ASSERT_EQ(t.uncertain[i], 0.0f) << c;
    }
  }
  EXPECT_GT(t.hazard, 0u);
}

TEST(TerrainLayers, SlopeSigmaCoversTheTruthAndALimitWithinTwoSigmaIsUncertain) {
  // A 10° plane with heights of known noise, that noise as the DEM's σ: the true slope lies
  // within 2σ of the fitted one for about 95 % of the cells.
  const double slope = 10.0, sigma = 0.02;
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, sigma);
  const double g = std::tan(slope * kDeg);
  const Grid grid = MakeGrid(
      400, 400, 0.05, 0.05,
      [&](double x, double y) { return g * (0.6 * x + 0.8 * y) + noise(rng); },
      static_cast<float>(sigma));
  TerrainOptions o = Options(0.6);
  o.max_step_m = o.max_roughness_m = 10.0;
  const TerrainLayers t = ComputeTerrain(grid.View(), o);
  std::size_t within = 0, cells = 0;
  double sigma_sum = 0.0;
  // Footprints 13 cells apart do not overlap: independent samples.
  for (int r = 6; r < grid.height - 6; r += 13) {
    for (int c = 6; c < grid.width - 6; c += 13) {
      const std::size_t i = grid.Index(r, c);
      ++cells;
      sigma_sum += t.slope_sigma_deg[i];
      if (std::abs(t.slope_deg[i] - slope) <= 2.0 * t.slope_sigma_deg[i]) ++within;
    }
  }
  const double fraction = double(within) / double(cells);
  EXPECT_GT(fraction, 0.92) << cells << " footprints, mean σ " << sigma_sum / cells << "°";
  EXPECT_LT(fraction, 0.98) << cells << " footprints, mean σ " << sigma_sum / cells << "°";

  // The limit within 2σ of the slope: uncertain, and not benign; far from it: decided.
  const std::size_t centre = grid.Index(200, 200);
  const double fitted = t.slope_deg[centre], s = t.slope_sigma_deg[centre];
  for (const auto& [limit, uncertain] :
       {std::pair{fitted + 0.5 * s, true}, std::pair{fitted - 0.5 * s, true},
        std::pair{fitted + 8 * s, false}, std::pair{fitted - 8 * s, false}}) {
    o.max_slope_deg = limit;
    const TerrainLayers u = ComputeTerrain(grid.View(), o);
    EXPECT_EQ(u.uncertain[centre], uncertain ? 1.0f : 0.0f) << "limit " << limit;
    if (uncertain || limit < fitted) {
      EXPECT_EQ(u.traversability[centre], 0.0f) << "limit " << limit;
    } else {
      EXPECT_GT(u.traversability[centre], 0.0f) << "limit " << limit;
    }
  }
}

TEST(TerrainLayers, SharedErrorsInSigmaDoNotMakeSmoothGroundUncertain) {
  // A DEM's σ also holds errors its cells share (a pose's): heights scattered by 2 mm whose σ
  // says 5 cm. The layers judge the noise by the scatter the cells show.
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.002);
  const Grid grid = MakeGrid(
      80, 80, 0.05, 0.05, [&](double x, double) { return 0.05 * x + noise(rng); }, 0.05f);
  const TerrainLayers t = ComputeTerrain(grid.View(), Options(0.6));
  const std::size_t centre = grid.Index(40, 40);
  EXPECT_EQ(t.uncertain[centre], 0.0f);
  EXPECT_GT(t.traversability[centre], 0.5f);
  EXPECT_LT(t.slope_sigma_deg[centre], 0.2f);
}

TEST(TerrainLayers, WithoutSigmaTheResidualsStandForTheNoise) {
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 0.01);
  const Grid grid = MakeGrid(
      80, 80, 0.05, 0.05, [&](double x, double) { return 0.2 * x + noise(rng); }, 0.0f);
  const TerrainLayers with_none = ComputeTerrain(grid.View(false), Options(0.6));
  EXPECT_FALSE(with_none.has_sigma);
  const std::size_t centre = grid.Index(40, 40);
  EXPECT_NEAR(with_none.slope_deg[centre], std::atan(0.2) / kDeg, 1.5);
  EXPECT_GT(with_none.slope_sigma_deg[centre], 0.05f);
  EXPECT_NEAR(with_none.roughness_m[centre], 0.01, 0.003);
}

TEST(TerrainLayers, UnknownWhereTheFootprintIsNotCovered) {
  Grid grid = MakeGrid(
      40, 40, 0.05, 0.05, [](double, double) { return 1.0; }, 0.01f);
  for (int r = 0; r < 40; ++r)
    for (int c = 20; c < 40; ++c) grid.z[grid.Index(r, c)] = kNaN;
  TerrainOptions o = Options(0.6);
  o.min_coverage = 0.5;
  const TerrainLayers t = ComputeTerrain(grid.View(), o);
  // 13 × 13 footprint: column 19 (the data's last) sees 7 columns of heights, column 20 six,
  // less than half of 13.
  EXPECT_FALSE(std::isnan(t.traversability[grid.Index(20, 19)]));
  EXPECT_TRUE(std::isnan(t.traversability[grid.Index(20, 20)]));
  EXPECT_TRUE(std::isnan(t.slope_deg[grid.Index(20, 30)]));

  const Grid empty = MakeGrid(
      30, 30, 0.05, 0.05, [](double, double) { return NAN; }, 0.01f);
  const TerrainLayers none = ComputeTerrain(empty.View(), o);
  EXPECT_EQ(none.known, 0u);
  EXPECT_EQ(none.benign, 0u);
}

TEST(TerrainLayers, BadFootprintsAndOptionsNameTheirKey) {
  const Grid grid = MakeGrid(
      30, 20, 0.05, 0.05, [](double, double) { return 0.0; }, 0.01f);
  const auto message = [&](const TerrainOptions& o) -> std::string {
    try {
      ComputeTerrain(grid.View(), o);
    } catch (const TerrainError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message(Options(0.09)).find("smaller than two cells"), std::string::npos);
  EXPECT_NE(message(Options(0.09)).find("terrain.footprint_m"), std::string::npos);
  EXPECT_NE(message(Options(1.2)).find("larger than the DEM"), std::string::npos);  // 20 rows
  EXPECT_EQ(message(Options(0.1)), "");  // two cells: a 3 × 3 footprint
  TerrainOptions o = Options(0.5);
  o.max_slope_deg = 95.0;
  EXPECT_NE(message(o).find("terrain.max_slope_deg"), std::string::npos);
  o = Options(0.5);
  o.min_coverage = 0.0;
  EXPECT_NE(message(o).find("terrain.min_coverage"), std::string::npos);
  GridView no_spacing = grid.View();
  no_spacing.cell_y_m = 0.0;
  EXPECT_THROW(ComputeTerrain(no_spacing, Options(0.5)), TerrainError);
}

// ---- eval::CompareTerrain: a DEM's hazards against a reference's ----------------------------

io::DemRaster Raster(const Grid& g, bool with_sigma) {
  io::DemRaster r;
  r.file = "mem";
  r.width = g.width;
  r.height = g.height;
  r.geotransform = {0.0, g.dx, 0.0, 0.0, 0.0, -g.dy};
  r.elevation_m = g.z;
  if (with_sigma) r.stddev_m = g.sigma;
  return r;
}

TEST(TerrainAgreement, ADemThatMissesARockMissesItsHazard) {
  const auto ground = [](bool rock) {
    return [rock](double x, double y) {
      return 0.02 * x + (rock && x > 1.0 && x < 1.3 && y < -1.0 && y > -1.3 ? 0.3 : 0.0);
    };
  };
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0.0, 0.005);
  const Grid truth = MakeGrid(60, 60, 0.05, 0.05, ground(true), 0.0f);
  const Grid seen = MakeGrid(
      60, 60, 0.05, 0.05, [&](double x, double y) { return ground(true)(x, y) + noise(rng); },
      0.005f);
  const Grid blind = MakeGrid(60, 60, 0.05, 0.05, ground(false), 0.005f);
  const eval::DemComparison good = eval::CompareDems(Raster(seen, true), Raster(truth, false));
  const eval::TerrainAgreement a = eval::CompareTerrain(good, TerrainOptions{});
  ASSERT_TRUE(a.computed) << a.reason;
  EXPECT_EQ(a.true_hazard, 17u * 17u);  // the rock's 5 × 5 cells widened by the 13-cell footprint
  EXPECT_EQ(a.found, a.true_hazard);
  EXPECT_EQ(a.marked_hazard, 0u);
  const eval::TerrainAgreement b = eval::CompareTerrain(
      eval::CompareDems(Raster(blind, true), Raster(truth, false)), TerrainOptions{});
  EXPECT_EQ(b.found, 0u);
  EXPECT_EQ(b.true_hazard, a.true_hazard);
  TerrainOptions huge;
  huge.footprint_m = 10.0;
  const eval::TerrainAgreement c = eval::CompareTerrain(good, huge);
  EXPECT_FALSE(c.computed);
  EXPECT_NE(c.reason.find("larger than the DEM"), std::string::npos);
}

// ---- `rovermap terrain DEM.tif --out DIR` ----------------------------------------------------

std::vector<float> ReadBand(const std::filesystem::path& path, int band, int* width = nullptr) {
  GDALAllRegister();
  GDALDataset* ds = GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY);
  EXPECT_NE(ds, nullptr) << path;
  if (ds == nullptr) return {};
  const int w = ds->GetRasterXSize(), h = ds->GetRasterYSize();
  if (width != nullptr) *width = w;
  std::vector<float> data(static_cast<std::size_t>(w) * h);
  EXPECT_EQ(ds->GetRasterBand(band)->RasterIO(GF_Read, 0, 0, w, h, data.data(), w, h, GDT_Float32,
                                              0, 0, nullptr),
            CE_None);
  GDALClose(ds);
  return data;
}

class TerrainCommand : public testing::CommandFixture {
 protected:
  // 8 m × 6 m of 5 cm cells in UTM 32N: a 3° slope with a 0.3 m box (a rock) at 6–6.5 m east,
  // 3–3.5 m south of the top edge; 1 cm σ.
  std::filesystem::path WriteRockDem(int bands = 3, const std::string& crs = "EPSG:32632") {
    const auto path = dir_ / "dem.tif";
    const double x0 = 500000.0, y0 = 5200000.0;
    testing::WriteDem(
        path, 160, 120, testing::NorthUp(x0, y0, 0.05), crs,
        [=](double x, double y) {
          const double u = x - x0, v = y0 - y;
          const bool rock = u > 6.0 && u < 6.5 && v > 3.0 && v < 3.5;
          return testing::Cell{static_cast<float>(0.05 * u + (rock ? 0.3 : 0.0)), 0.01f, 5.0f};
        },
        bands);
    return path;
  }
};

// The layers of a DEM too large to hold, a row of tiles at a time (rovermap terrain, the
// mosaic's): the same values as the whole DEM's in memory, to the bit, with holes and with a
// tile row much smaller than the DEM.
TEST_F(TerrainCommand, TileRowsGiveTheWholeDemsLayersToTheBit) {
  const auto path = dir_ / "wavy.tif";
  testing::WriteDem(path, 300, 230, testing::NorthUp(500000.0, 5200000.0, 0.05), "EPSG:32632",
                    [](double x, double y) {
                      const bool hole = std::fmod(std::abs(x * 7.3 + y * 3.1), 1.3) < 0.05;
                      const float z = static_cast<float>(
                          0.3 * std::sin(0.9 * x) * std::cos(1.1 * y) + 0.01 * std::sin(40.0 * x));
                      return testing::Cell{hole ? kNaN : z, 0.01f, 3.0f};
                    });
  TerrainOptions o = Options(0.6);
  o.tile_cells = 40;  // 6 tile rows, each read with the halo of the next
  const io::TiledTerrain t =
      io::WriteTerrainTiled(path, dir_ / "terrain.tif", dir_ / "terrain.png", o);
  const io::DemRaster raster = io::ReadDemGeoTiff(path);
  const TerrainLayers whole = ComputeTerrain(io::GridViewOf(raster), o);
  EXPECT_EQ(t.counts.known, whole.known);
  EXPECT_EQ(t.counts.hazard, whole.hazard);
  EXPECT_EQ(t.counts.uncertain_cells, whole.uncertain_cells);
  EXPECT_EQ(t.counts.benign, whole.benign);
  EXPECT_TRUE(t.counts.has_sigma);
  std::size_t heights = 0;
  for (float z : raster.elevation_m) heights += std::isnan(z) ? 0 : 1;
  EXPECT_EQ(t.height_cells, heights);
  EXPECT_LT(heights, raster.elevation_m.size());  // the holes are there
  const std::vector<float>* layers[] = {&whole.slope_deg,      &whole.slope_sigma_deg,
                                        &whole.roughness_m,    &whole.step_m,
                                        &whole.traversability, &whole.uncertain};
  for (int band = 1; band <= 6; ++band) {
    const std::vector<float> tiled = ReadBand(dir_ / "terrain.tif", band);
    const std::vector<float>& expected = *layers[band - 1];
    ASSERT_EQ(tiled.size(), expected.size());
    for (std::size_t i = 0; i < tiled.size(); ++i) {
      ASSERT_TRUE((std::isnan(tiled[i]) && std::isnan(expected[i])) ||
                  std::memcmp(&tiled[i], &expected[i], sizeof(float)) == 0)
          << "band " << band << " cell " << i;
    }
  }
  EXPECT_TRUE(std::filesystem::exists(dir_ / "terrain.png"));
  for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".terrain.tif."), std::string::npos)
        << "a staging file was left: " << entry.path();
  }
}

TEST_F(TerrainCommand, WritesTheLayersOnTheDemsGridWithTheRockAsAHazard) {
  const auto dem = WriteRockDem();
  const auto out = dir_ / "out";
  const testing::CommandResult r = Rovermap("terrain " + dem.string() + " --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["sigma"], "band 2");  // dem.tif's layout, without band descriptions
  EXPECT_GT(summary["hazard_cells"].get<int>(), 0);
  EXPECT_GT(summary["benign_cells"].get<int>(), 100 * 80);
  ASSERT_TRUE(std::filesystem::exists(out / "terrain.png"));

  const io::DemRaster in = io::ReadDemGeoTiff(dem),
                      layers = io::ReadDemGeoTiff(out / "terrain.tif");
  EXPECT_EQ(layers.width, in.width);
  EXPECT_EQ(layers.height, in.height);
  EXPECT_EQ(layers.geotransform, in.geotransform);
  EXPECT_EQ(layers.epsg, 32632);
  EXPECT_EQ(layers.layout, "COG");
  EXPECT_EQ(layers.band_descriptions,
            (std::vector<std::string>{"slope_deg", "slope_stddev_deg", "roughness_m", "step_m",
                                      "traversability", "uncertain"}));
  // Slope 2.86° on the open ground; the rock's footprint (its box widened by half the 13-cell
  // footprint) a hazard, the ground away from it benign.
  const std::vector<float> slope = ReadBand(out / "terrain.tif", 1);
  const std::vector<float> trav = ReadBand(out / "terrain.tif", 5);
  const auto at = [](int row, int col) { return static_cast<std::size_t>(row) * 160 + col; };
  EXPECT_NEAR(slope[at(20, 20)], std::atan(0.05) * 180 / M_PI, 0.05);
  EXPECT_EQ(trav[at(65, 125)], 0.0f);  // on the rock
  EXPECT_EQ(trav[at(65, 116)], 0.0f);  // 4 cells west of it: its footprint holds the rock
  EXPECT_GT(trav[at(65, 100)], 0.5f);  // 20 cells west
  EXPECT_GT(trav[at(20, 20)], 0.5f);
}

TEST_F(TerrainCommand, ADemWithoutSigmaIsReadAndSaysSo) {
  const auto dem = WriteRockDem(1);
  const testing::CommandResult r =
      Rovermap("terrain " + dem.string() + " --out " + (dir_ / "out").string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["sigma"], "none: from the fits' residuals");
}

TEST_F(TerrainCommand, BadDemsAndFootprintsAreClearErrorsAndWriteNothing) {
  const auto out = dir_ / "out";
  const auto expect_error = [&](const std::string& args, int status, const std::string& words) {
    const testing::CommandResult r = Rovermap(args + " --out " + out.string());
    EXPECT_EQ(r.status, status) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(words), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out / "terrain.tif")) << args;
  };
  const auto dem = WriteRockDem();
  expect_error("terrain " + dem.string() + " --set terrain.footprint_m=50", 2,
               "terrain.footprint_m 50");
  expect_error("terrain " + dem.string() + " --set terrain.footprint_m=0.05", 2,
               "smaller than two cells");
  expect_error("terrain " + (dir_ / "none.tif").string(), 1, "none.tif");

  const auto empty = dir_ / "empty.tif";
  testing::WriteDem(empty, 40, 40, testing::NorthUp(0, 0, 0.05), "EPSG:32632",
                    testing::Constant(NAN, NAN, 0));
  expect_error("terrain " + empty.string(), 1, "empty.tif: the DEM holds no height");

  const auto degrees = dir_ / "degrees.tif";
  testing::WriteDem(degrees, 40, 40, testing::NorthUp(8.0, 49.0, 1e-6), "EPSG:4326",
                    testing::Constant(1, 0.01f, 1));
  expect_error("terrain " + degrees.string(), 1, "geographic");

  const auto rotated = dir_ / "rotated.tif";
  testing::WriteDem(rotated, 40, 40, std::array<double, 6>{0, 0.05, 0.01, 0, 0.01, -0.05},
                    "EPSG:32632", testing::Constant(1, 0.01f, 1));
  expect_error("terrain " + rotated.string(), 1, "rotated");
}

// ---- terrain.tif and terrain.png from `rovermap replay` --------------------------------------

TEST_F(TerrainCommand, ReplayWritesTheLayersOrSaysWhyNotAndLeavesNoStaleOnes) {
  const std::string tiny = std::string(ROVERMAP_DATASETS_DIR) + "/sim_tiny_cloud";
  const auto out = dir_ / "replay";
  testing::CommandResult r = Rovermap("replay " + tiny + " --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.err;
  nlohmann::json terrain = nlohmann::json::parse(r.out)["terrain"];
  EXPECT_TRUE(terrain["written"].get<bool>());
  EXPECT_GT(terrain["known_cells"].get<int>(), 500);  // 859 on its five frames
  EXPECT_EQ(terrain["footprint_cells"], nlohmann::json::array({13, 13}));
  const io::DemRaster dem = io::ReadDemGeoTiff(out / "dem.tif");
  const io::DemRaster layers = io::ReadDemGeoTiff(out / "terrain.tif");
  EXPECT_EQ(layers.geotransform, dem.geotransform);
  EXPECT_EQ(layers.wkt, dem.wkt);
  ASSERT_TRUE(std::filesystem::exists(out / "terrain.png"));

  // A footprint larger than the map: the replay goes on, says why, and the layers of the run
  // before are not left behind as if they were this one's.
  r = Rovermap("replay " + tiny + " --out " + out.string() +
               " --force --set terrain.footprint_m=100");
  ASSERT_EQ(r.status, 0) << r.err;
  terrain = nlohmann::json::parse(r.out)["terrain"];
  EXPECT_FALSE(terrain["written"].get<bool>());
  EXPECT_NE(terrain["reason"].get<std::string>().find("larger than the DEM"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(out / "terrain.tif"));
  EXPECT_FALSE(std::filesystem::exists(out / "terrain.png"));

  // Off: none written, and the summary says so.
  const auto off = dir_ / "off";
  r = Rovermap("replay " + tiny + " --out " + off.string() + " --set terrain.enabled=false");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(nlohmann::json::parse(r.out)["terrain"]["enabled"].get<bool>());
  EXPECT_FALSE(std::filesystem::exists(off / "terrain.tif"));
  EXPECT_TRUE(std::filesystem::exists(off / "dem.tif"));
}

}  // namespace
}  // namespace rovermap::terrain
