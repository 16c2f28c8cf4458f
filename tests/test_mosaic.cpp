// mosaic/: inverse-variance fusion of small hand-made GeoTIFFs, associativity, inputs on other
// origins, rotations and UTM zones, tiling, the disagreement band, co-registration, and the
// command's errors.
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>

#include "config/Config.hpp"
#include "dem/ElevationMap.hpp"
#include "io/GeoTiff.hpp"
#include "io/Georeference.hpp"
#include "io/IoError.hpp"
#include "mosaic/Coregister.hpp"
#include "mosaic/Mosaic.hpp"
#include "tests/support/CommandFixture.hpp"
#include "tests/support/DemDifference.hpp"
#include "tests/support/DemWriting.hpp"

namespace rovermap {
namespace {

namespace fs = std::filesystem;
using testing::Cell;
using testing::CommandFixture;
using testing::CommandResult;
using testing::Constant;
using testing::NorthUp;
using testing::Slurp;
using testing::Surface;
using testing::WriteDem;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// (x, y) from one EPSG CRS into another, x easting first.
std::unique_ptr<OGRCoordinateTransformation> EpsgTransform(int from_epsg, int to_epsg) {
  OGRSpatialReference from;
  OGRSpatialReference to;
  from.importFromEPSG(from_epsg);
  to.importFromEPSG(to_epsg);
  from.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  to.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return std::unique_ptr<OGRCoordinateTransformation>(
      OGRCreateCoordinateTransformation(&from, &to));
}

// A plane: bilinear resampling reproduces it exactly.
Surface Plane(float sigma) {
  return [=](double x, double y) {
    return Cell{static_cast<float>(0.02 * (x - 500000.0) - 0.01 * (y - 4000000.0) + 5.0), sigma,
                1.0f};
  };
}

// Relief with slopes in every direction: bumps of a few metres.
double Relief(double easting, double northing) {
  const double x = easting - 500000.0;
  const double y = northing - 4000000.0;
  return 0.6 * std::sin(x / 3.1) * std::cos(y / 2.3) + 0.3 * std::sin((x + 2 * y) / 4.7) + 0.02 * x;
}

mosaic::MosaicOptions NoCoregistration() {
  mosaic::MosaicOptions options;
  options.coregister = false;
  return options;
}

// Calls f(c, x, y) for each cell of `m` with an elevation: its index and its centre.
template <typename F>
void ForEachCell(const io::DemRaster& m, F f) {
  for (int row = 0; row < m.height; ++row) {
    for (int col = 0; col < m.width; ++col) {
      const std::size_t c = static_cast<std::size_t>(row) * m.width + col;
      if (std::isnan(m.elevation_m[c])) continue;
      f(c, m.geotransform[0] + (col + 0.5) * m.geotransform[1],
        m.geotransform[3] + (row + 0.5) * m.geotransform[5]);
    }
  }
}

class MosaicTest : public CommandFixture {
 protected:
  mosaic::MosaicResult Build(const std::vector<fs::path>& inputs, const std::string& out,
                             const mosaic::MosaicOptions& options, bool report = false) {
    return mosaic::BuildMosaic(inputs, dir_ / out, report ? dir_ / "mosaic.json" : fs::path(),
                               options, registration::RegistrationOptions{});
  }
  io::DemRaster Read(const std::string& name) { return io::ReadDemGeoTiff(dir_ / name); }
  // Band 4 (ReadDemGeoTiff reads three).
  std::vector<float> Disagreement(const std::string& name) {
    GDALDataset* ds = GDALDataset::Open((dir_ / name).c_str(), GDAL_OF_RASTER);
    EXPECT_NE(ds, nullptr);
    EXPECT_EQ(ds->GetRasterCount(), 4);
    const int w = ds->GetRasterXSize();
    const int h = ds->GetRasterYSize();
    std::vector<float> band(static_cast<std::size_t>(w) * h);
    EXPECT_EQ(ds->GetRasterBand(4)->RasterIO(GF_Read, 0, 0, w, h, band.data(), w, h, GDT_Float32, 0,
                                             0, nullptr),
              CE_None);
    GDALClose(ds);
    return band;
  }
  // Cell (col, row) of the mosaic at output coordinates (x, y).
  static std::size_t At(const io::DemRaster& r, double x, double y) {
    const int col = static_cast<int>(std::floor((x - r.geotransform[0]) / r.geotransform[1]));
    const int row = static_cast<int>(std::floor((y - r.geotransform[3]) / r.geotransform[5]));
    return static_cast<std::size_t>(row) * r.width + col;
  }
};

TEST_F(MosaicTest, InverseVarianceByHand) {
  const std::string crs = "EPSG:32633";
  WriteDem(dir_ / "a.tif", 4, 4, NorthUp(500000, 4000004, 1.0), crs, Constant(1.0f, 0.1f, 2));
  WriteDem(dir_ / "b.tif", 4, 4, NorthUp(500002, 4000004, 1.0), crs, Constant(2.0f, 0.2f, 3));
  const mosaic::MosaicResult result =
      Build({dir_ / "a.tif", dir_ / "b.tif"}, "m.tif", NoCoregistration());
  EXPECT_EQ(result.width, 6);
  EXPECT_EQ(result.height, 4);
  const io::DemRaster m = Read("m.tif");
  const std::vector<float> d = Disagreement("m.tif");
  EXPECT_EQ(m.layout, "COG");
  EXPECT_EQ(m.epsg, 32633);
  for (int row = 0; row < 4; ++row) {
    // A alone.
    EXPECT_FLOAT_EQ(m.elevation_m[row * 6 + 0], 1.0f);
    EXPECT_FLOAT_EQ(m.stddev_m[row * 6 + 1], 0.1f);
    EXPECT_FLOAT_EQ(m.count[row * 6 + 1], 2.0f);
    EXPECT_FLOAT_EQ(d[row * 6 + 1], 0.0f);
    // Both: w = 100 and 25; z = (100·1 + 25·2) / 125 = 1.2; σ = 125^-1/2; count 5. A is
    // 0.2 m off, within 3·sqrt(0.01 + 0.008) = 0.40 m; B is 0.8 m off, beyond
    // 3·sqrt(0.04 + 0.008) = 0.66 m: one disagreeing input.
    for (int col = 2; col < 4; ++col) {
      EXPECT_NEAR(m.elevation_m[row * 6 + col], 1.2, 1e-6);
      EXPECT_NEAR(m.stddev_m[row * 6 + col], 1.0 / std::sqrt(125.0), 1e-7);
      EXPECT_FLOAT_EQ(m.count[row * 6 + col], 5.0f);
      EXPECT_FLOAT_EQ(d[row * 6 + col], 1.0f);
    }
    // B alone.
    EXPECT_FLOAT_EQ(m.elevation_m[row * 6 + 5], 2.0f);
    EXPECT_FLOAT_EQ(m.count[row * 6 + 5], 3.0f);
  }
}

TEST_F(MosaicTest, PartialMosaicsEqualTheWhole) {
  const std::string crs = "EPSG:32633";
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.02);
  auto noisy = [&](float sigma) {
    return [&, sigma](double x, double y) {
      return Cell{static_cast<float>(Relief(x, y) + noise(rng)), sigma, 4.0f};
    };
  };
  WriteDem(dir_ / "a.tif", 40, 30, NorthUp(500000, 4000030, 0.5), crs, noisy(0.03f));
  WriteDem(dir_ / "b.tif", 36, 30, NorthUp(500008, 4000025, 0.5), crs, noisy(0.05f));
  // C off the lattice by 0.15 m and coarser: resampled, not copied.
  WriteDem(dir_ / "c.tif", 20, 20, NorthUp(500005.15, 4000018.15, 0.7), crs, noisy(0.04f));
  const auto options = NoCoregistration();
  Build({dir_ / "a.tif", dir_ / "b.tif", dir_ / "c.tif"}, "abc.tif", options);
  Build({dir_ / "a.tif", dir_ / "b.tif"}, "ab.tif", options);
  Build({dir_ / "ab.tif", dir_ / "c.tif"}, "ab_c.tif", options);
  Build({dir_ / "b.tif", dir_ / "c.tif"}, "bc.tif", options);
  Build({dir_ / "a.tif", dir_ / "bc.tif"}, "a_bc.tif", options);
  const io::DemRaster whole = Read("abc.tif");
  const std::vector<float> whole_d = Disagreement("abc.tif");
  for (const std::string name : {"ab_c.tif", "a_bc.tif"}) {
    SCOPED_TRACE(name);
    const io::DemRaster parts = Read(name);
    const std::vector<float> parts_d = Disagreement(name);
    ASSERT_EQ(parts.width, whole.width);
    ASSERT_EQ(parts.height, whole.height);
    EXPECT_EQ(parts.geotransform, whole.geotransform);
    const testing::DemDifference d = testing::CompareDemCells(whole, parts);
    EXPECT_EQ(d.nan_mismatches, 0u);
    EXPECT_EQ(d.count_mismatches, 0u);
    for (std::size_t c = 0; c < whole.elevation_m.size(); ++c) {
      if (!std::isnan(whole.elevation_m[c])) {
        EXPECT_EQ(whole_d[c], parts_d[c]) << c;
      }
    }
    EXPECT_GT(d.cells, 1000u);
    // Float32 storage of the partial mosaic: a few ulps of a ~5 m height and of σ.
    EXPECT_LT(d.worst_z_m, 2e-6);
    EXPECT_LT(d.worst_sigma_relative, 1e-6);
    RecordProperty(name + "_worst_z", std::to_string(d.worst_z_m));
  }
}

TEST_F(MosaicTest, DisagreeingGroupsCountAsOneInputEach) {
  // The documented limit of band 4's associativity. A and B say 0 m, C and D 0.5 m (σ 5 cm).
  // At once: z = 0.25 m, σ = 2.5 cm; each input is 0.25 m off, beyond 3·sqrt(0.05² + 0.025²)
  // = 0.17 m: 4. Grouped as (A+B)+(C+D): each pair agrees (0), and each pair, 0.25 m off the
  // fused value with σ 3.5 cm, disagrees as one input: 2. Heights, σ and counts are equal.
  const std::string crs = "EPSG:32633";
  for (const char* name : {"a", "b", "c", "d"}) {
    const float z = (name[0] == 'a' || name[0] == 'b') ? 0.0f : 0.5f;
    WriteDem(dir_ / (std::string(name) + ".tif"), 4, 4, NorthUp(500000, 4000004, 1.0), crs,
             Constant(z, 0.05f, 1));
  }
  const auto options = NoCoregistration();
  Build({dir_ / "a.tif", dir_ / "b.tif", dir_ / "c.tif", dir_ / "d.tif"}, "all.tif", options);
  Build({dir_ / "a.tif", dir_ / "b.tif"}, "ab.tif", options);
  Build({dir_ / "c.tif", dir_ / "d.tif"}, "cd.tif", options);
  Build({dir_ / "ab.tif", dir_ / "cd.tif"}, "grouped.tif", options);
  const io::DemRaster all = Read("all.tif");
  const io::DemRaster grouped = Read("grouped.tif");
  const std::vector<float> d_all = Disagreement("all.tif");
  const std::vector<float> d_grouped = Disagreement("grouped.tif");
  for (std::size_t c = 0; c < 16; ++c) {
    EXPECT_NEAR(all.elevation_m[c], 0.25, 1e-6);
    EXPECT_NEAR(grouped.elevation_m[c], 0.25, 1e-6);
    EXPECT_NEAR(grouped.stddev_m[c], all.stddev_m[c], 1e-8);
    EXPECT_EQ(grouped.count[c], 4.0f);
    EXPECT_EQ(d_all[c], 4.0f);
    EXPECT_EQ(d_grouped[c], 2.0f);
  }
}

TEST_F(MosaicTest, OtherOriginsAndRotationsLandOnTheCommonGrid) {
  const std::string crs = "EPSG:32633";
  WriteDem(dir_ / "a.tif", 40, 40, NorthUp(500000, 4000040, 1.0), crs, Plane(0.05f));
  // B: another origin, its grid rotated by 20 degrees, cells of 0.8 m.
  const double angle = 20.0 * M_PI / 180.0;
  const double s = 0.8;
  const std::array<double, 6> gb = {500030.0,  s * std::cos(angle), s * std::sin(angle),
                                    4000030.0, s * std::sin(angle), -s * std::cos(angle)};
  WriteDem(dir_ / "b.tif", 30, 30, gb, crs, Plane(0.05f));
  // Bilinear resampling reproduces a plane except in the outermost cell of an input, where it
  // has one neighbour fewer: those are skipped. 0 outside, 1 interior, 2 edge.
  auto where = [](double u, double v, double n) {
    if (u < 0 || v < 0 || u > n || v > n) return 0;
    return u >= 1 && v >= 1 && u <= n - 1 && v <= n - 1 ? 1 : 2;
  };
  auto where_a = [&](double x, double y) { return where(x - 500000, 4000040 - y, 40); };
  auto where_b = [&](double x, double y) {
    // Inverse of gb (a rotation by `angle` with the y axis flipped).
    const double dx = x - gb[0];
    const double dy = y - gb[3];
    const double det = gb[1] * gb[5] - gb[2] * gb[4];
    return where((gb[5] * dx - gb[2] * dy) / det, (-gb[4] * dx + gb[1] * dy) / det, 30);
  };
  const mosaic::MosaicResult result =
      Build({dir_ / "a.tif", dir_ / "b.tif"}, "m.tif", NoCoregistration());
  EXPECT_NEAR(result.cell_size_m, 0.8, 1e-12);  // the finest input's
  const io::DemRaster m = Read("m.tif");
  std::size_t checked = 0;
  std::size_t both = 0;
  ForEachCell(m, [&](std::size_t c, double x, double y) {
    if (where_a(x, y) == 2 || where_b(x, y) == 2) return;
    EXPECT_NEAR(m.elevation_m[c], Plane(0)(x, y).z, 2e-5) << c;
    both += m.count[c] == 2.0f;
    ++checked;
  });
  EXPECT_GT(checked, 2000u);
  EXPECT_GT(both, 100u);
  // The rotated square reaches beyond A's east edge (x 500040): its corner at x ≈ 500062.5.
  EXPECT_GT(m.geotransform[0] + m.width * m.geotransform[1], 500060.0);
}

TEST_F(MosaicTest, AnotherUtmZoneIsReprojected) {
  // Near 12° E, the edge of zones 32 and 33: A in zone 33, B in zone 32, the same plane
  // (defined in zone-33 coordinates) sampled at B's cells.
  const auto to33 = EpsgTransform(32632, 32633);
  const auto to32 = EpsgTransform(32633, 32632);
  // A's corner in zone 33 (easting 264 km: 45° N, 12° E), and B's corner: nearby, seen from
  // zone 32.
  const double ax = 264000.0;
  const double ay = 5000040.0;
  double bx = ax + 20.0;
  double by = ay - 5.0;
  ASSERT_TRUE(to32->Transform(1, &bx, &by));
  bx = std::round(bx);
  by = std::round(by);
  // Heights near 5 m (Float32 keeps them to a micrometre).
  auto plane_33 = [&](double x, double y) {
    return Cell{static_cast<float>(0.02 * (x - ax) - 0.01 * (y - ay) + 5.0), 0.05f, 1.0f};
  };
  auto plane_from_32 = [&](double x, double y) {
    double u = x;
    double v = y;
    to33->Transform(1, &u, &v);
    return plane_33(u, v);
  };
  WriteDem(dir_ / "a.tif", 40, 40, NorthUp(ax, ay, 1.0), "EPSG:32633", plane_33);
  WriteDem(dir_ / "b.tif", 40, 40, NorthUp(bx, by, 1.0), "EPSG:32632", plane_from_32);
  const mosaic::MosaicResult result =
      Build({dir_ / "a.tif", dir_ / "b.tif"}, "m.tif", NoCoregistration());
  const io::DemRaster m = Read("m.tif");
  EXPECT_EQ(m.epsg, 32633);
  // Within an input's footprint but less than a cell from its edge.
  auto near_edge = [&](double x, double y) {
    auto edge = [](double u, double v) {
      const bool inside = u >= 0 && v >= 0 && u <= 40 && v <= 40;
      return inside && (u < 1 || v < 1 || u > 39 || v > 39);
    };
    double u = x;
    double v = y;
    to32->Transform(1, &u, &v);
    return edge(x - ax, ay - y) || edge(u - bx, by - v);
  };
  std::size_t both = 0;
  std::size_t b_only = 0;
  double worst = 0.0;
  ForEachCell(m, [&](std::size_t c, double x, double y) {
    // Bilinear resampling reproduces the plane but in an input's outermost cells.
    if (near_edge(x, y)) return;
    worst = std::max(worst, std::abs(double(m.elevation_m[c]) - plane_33(x, y).z));
    both += m.count[c] == 2.0f;
    b_only += x > ax + 41.0;
  });
  // The zone change rotates B's grid by the convergence difference (about 4 degrees here)
  // and bends it slightly: bilinear resampling of the plane stays within a tenth of a mm.
  EXPECT_LT(worst, 1e-4);
  EXPECT_GT(both, 300u);
  EXPECT_GT(b_only, 300u);
}

TEST_F(MosaicTest, TilesGiveTheSameAsOneTile) {
  const std::string crs = "EPSG:32633";
  auto relief = [](float sigma) {
    return [sigma](double x, double y) { return Cell{float(Relief(x, y)), sigma, 2.0f}; };
  };
  WriteDem(dir_ / "a.tif", 70, 50, NorthUp(500000, 4000050, 0.5), crs, relief(0.03f));
  WriteDem(dir_ / "b.tif", 60, 60, NorthUp(500012.3, 4000041.1, 0.6), crs, relief(0.05f));
  auto options = NoCoregistration();
  options.tile_cells = 4096;
  EXPECT_EQ(Build({dir_ / "a.tif", dir_ / "b.tif"}, "one.tif", options).tiles, 1);
  options.tile_cells = 16;
  EXPECT_GT(Build({dir_ / "a.tif", dir_ / "b.tif"}, "tiled.tif", options).tiles, 20);
  const io::DemRaster one = Read("one.tif");
  const io::DemRaster tiled = Read("tiled.tif");
  ASSERT_EQ(one.elevation_m.size(), tiled.elevation_m.size());
  for (std::size_t c = 0; c < one.elevation_m.size(); ++c) {
    ASSERT_EQ(std::isnan(one.elevation_m[c]), std::isnan(tiled.elevation_m[c])) << c;
    if (std::isnan(one.elevation_m[c])) continue;
    EXPECT_NEAR(one.elevation_m[c], tiled.elevation_m[c], 1e-6) << c;
    EXPECT_NEAR(one.stddev_m[c], tiled.stddev_m[c], 1e-8) << c;
    EXPECT_EQ(one.count[c], tiled.count[c]) << c;
  }
  const std::vector<float> d_one = Disagreement("one.tif");
  const std::vector<float> d_tiled = Disagreement("tiled.tif");
  for (std::size_t c = 0; c < d_one.size(); ++c) {
    if (std::isnan(d_one[c]) && std::isnan(d_tiled[c])) continue;
    EXPECT_EQ(d_one[c], d_tiled[c]) << c;
  }
}

TEST_F(MosaicTest, DisagreementCountsAPlantedOffset) {
  // Five inputs on one grid; the third is 0.3 m high over a 10 m square. There the fused value
  // moves 0.06 m: the four others stay within 3·sqrt(0.05² + 0.05²/5) = 0.16 m, the third
  // (0.24 m off) does not.
  const std::string crs = "EPSG:32633";
  std::vector<fs::path> inputs;
  for (int k = 0; k < 5; ++k) {
    const fs::path file = dir_ / ("in" + std::to_string(k) + ".tif");
    WriteDem(file, 40, 40, NorthUp(500000, 4000040, 1.0), crs, [k](double x, double y) {
      const bool patch = k == 2 && x > 500010 && x < 500020 && y > 4000010 && y < 4000020;
      return Cell{float(Relief(x, y) + (patch ? 0.3 : 0.0)), 0.05f, 1.0f};
    });
    inputs.push_back(file);
  }
  Build(inputs, "m.tif", NoCoregistration());
  const io::DemRaster m = Read("m.tif");
  const std::vector<float> d = Disagreement("m.tif");
  EXPECT_FLOAT_EQ(d[At(m, 500015.5, 4000015.5)], 1.0f);
  EXPECT_FLOAT_EQ(d[At(m, 500030.5, 4000030.5)], 0.0f);
  std::size_t flagged = 0;
  for (float v : d) flagged += v > 0.0f;
  EXPECT_EQ(flagged, 100u);  // the 10 x 10 cells of the patch
  EXPECT_FLOAT_EQ(m.count[At(m, 500015.5, 4000015.5)], 5.0f);
}

TEST_F(MosaicTest, CoregistrationCorrectsAKnownShift) {
  // Truth: Relief. A covers x in [0, 30] m, B x in [12, 42] m, B displaced by +0.2 m east and
  // +0.1 m up (what B shows at p is the truth at p − (0.2, 0)), both with 2 cm noise.
  const std::string crs = "EPSG:32633";
  const double x0 = 500000.0;
  const double y0 = 4000000.0;
  auto truth = [&](double x, double y) { return Relief(x, y); };
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.02);
  WriteDem(dir_ / "a.tif", 120, 120, NorthUp(x0, y0 + 30, 0.25), crs, [&](double x, double y) {
    return Cell{float(truth(x, y) + noise(rng)), 0.02f, 3.0f};
  });
  WriteDem(dir_ / "b.tif", 120, 120, NorthUp(x0 + 12, y0 + 30, 0.25), crs, [&](double x, double y) {
    return Cell{float(truth(x - 0.2, y) + 0.1 + noise(rng)), 0.02f, 3.0f};
  });
  auto rmse = [&](const std::string& name) {
    const io::DemRaster m = Read(name);
    double sum = 0.0;
    std::size_t n = 0;
    ForEachCell(m, [&](std::size_t c, double x, double y) {
      const double e = m.elevation_m[c] - truth(x, y);
      sum += e * e;
      ++n;
    });
    return std::sqrt(sum / n);
  };
  Build({dir_ / "a.tif", dir_ / "b.tif"}, "plain.tif", NoCoregistration());
  mosaic::MosaicOptions options;  // coregister: true
  const mosaic::MosaicResult result =
      Build({dir_ / "a.tif", dir_ / "b.tif"}, "coreg.tif", options, /*report=*/true);
  ASSERT_EQ(result.inputs.size(), 2u);
  const mosaic::InputReport& b = result.inputs[1];
  EXPECT_TRUE(b.applied) << b.status;
  EXPECT_EQ(b.overlap_cells, 72u * 120u);
  // Measured: (-0.2031, -0.0039, -0.1005) m and 0.015 degrees (noise-free DEMs: 0.3 mm).
  EXPECT_NEAR(b.translation_m.x(), -0.2, 0.008);
  EXPECT_NEAR(b.translation_m.y(), 0.0, 0.008);
  EXPECT_NEAR(b.translation_m.z(), -0.1, 0.002);
  EXPECT_LT(b.rotation_deg.norm(), 0.03);
  // Measured: RMS 0.102 -> 0.026 m (the noise of two DEMs: 0.028), 5414 -> 8 cells beyond 3σ.
  EXPECT_LT(b.rms_after_m, 0.03);
  EXPECT_LT(b.disagreement_after * 50, b.disagreement_before);
  const double plain = rmse("plain.tif");
  const double coregistered = rmse("coreg.tif");
  RecordProperty("translation_x", std::to_string(b.translation_m.x()));
  RecordProperty("translation_y", std::to_string(b.translation_m.y()));
  RecordProperty("translation_z", std::to_string(b.translation_m.z()));
  RecordProperty("rotation_deg", std::to_string(b.rotation_deg.norm()));
  RecordProperty("rms_after_m", std::to_string(b.rms_after_m));
  RecordProperty("disagreement_after", std::to_string(b.disagreement_after));
  RecordProperty("rmse_plain", std::to_string(plain));
  RecordProperty("rmse_coregistered", std::to_string(coregistered));
  // Measured: 0.064 -> 0.016 m.
  EXPECT_LT(coregistered, 0.35 * plain);
  const nlohmann::json report = nlohmann::json::parse(Slurp(dir_ / "mosaic.json"));
  EXPECT_EQ(report["inputs"][1]["status"], "registered");
  EXPECT_EQ(report["inputs"][0]["status"], "reference");
}

TEST_F(MosaicTest, ACorrectionBeyondTheLimitsIsRefusedAndTheInputPlacedAsItIs) {
  // The known shift of CoregistrationCorrectsAKnownShift (0.2 m east, 0.1 m up; found with the
  // RMS over the overlap 0.102 -> 0.026 m), judged by stricter limits.
  const std::string crs = "EPSG:32633";
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.02);
  WriteDem(dir_ / "a.tif", 120, 120, NorthUp(500000, 4000030, 0.25), crs, [&](double x, double y) {
    return Cell{float(Relief(x, y) + noise(rng)), 0.02f, 3.0f};
  });
  WriteDem(dir_ / "b.tif", 120, 120, NorthUp(500012, 4000030, 0.25), crs, [&](double x, double y) {
    return Cell{float(Relief(x - 0.2, y) + 0.1 + noise(rng)), 0.02f, 3.0f};
  });
  const std::vector<fs::path> inputs = {dir_ / "a.tif", dir_ / "b.tif"};
  Build(inputs, "plain.tif", NoCoregistration());
  const io::DemRaster plain = Read("plain.tif");
  struct Case {
    std::function<void(mosaic::MosaicOptions*)> set;
    std::string reason;
  };
  const std::vector<Case> cases = {
      {[](mosaic::MosaicOptions* o) { o->max_correction_m = 0.1; },
       "m exceeds mosaic.max_correction_m 0.10"},
      {[](mosaic::MosaicOptions* o) { o->max_correction_deg = 0.0; },
       "deg exceeds mosaic.max_correction_deg 0.00"},
      {[](mosaic::MosaicOptions* o) { o->min_improvement = 0.1; }, "m RMS (needs < 0.10x)"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.reason);
    mosaic::MosaicOptions options;
    c.set(&options);
    const mosaic::MosaicResult result = Build(inputs, "refused.tif", options, /*report=*/true);
    const mosaic::InputReport& b = result.inputs[1];
    EXPECT_EQ(b.status, "refused");
    EXPECT_FALSE(b.applied);
    EXPECT_NE(b.reason.find(c.reason), std::string::npos) << b.reason;
    // The correction found is still reported, with its figures.
    EXPECT_NEAR(b.translation_m.x(), -0.2, 0.01);
    EXPECT_LT(b.rms_after_m, 0.03);
    const nlohmann::json report = nlohmann::json::parse(Slurp(dir_ / "mosaic.json"));
    EXPECT_EQ(report["inputs"][1]["reason"], b.reason);
    // Placed as it is: the mosaic is the one without co-registration.
    const testing::DemDifference d = testing::CompareDemCells(plain, Read("refused.tif"));
    EXPECT_EQ(d.nan_mismatches, 0u);
    EXPECT_EQ(d.worst_z_m, 0.0);
    fs::remove(dir_ / "refused.tif");
  }
}

TEST_F(MosaicTest, APlaneIsRefusedAsIllConditioned) {
  // Two DEMs of one plane, B displaced by 0.3 m east and 0.1 m up: the overlap constrains its
  // height and tilt, never where along the plane it lies.
  const std::string crs = "EPSG:32633";
  const Surface plane = Plane(0.02f);
  WriteDem(dir_ / "a.tif", 60, 60, NorthUp(500000, 4000030, 0.5), crs, plane);
  WriteDem(dir_ / "b.tif", 60, 60, NorthUp(500012, 4000030, 0.5), crs, [&](double x, double y) {
    Cell c = plane(x - 0.3, y);
    c.z += 0.1f;
    return c;
  });
  const mosaic::MosaicResult result =
      Build({dir_ / "a.tif", dir_ / "b.tif"}, "m.tif", mosaic::MosaicOptions{}, /*report=*/true);
  const mosaic::InputReport& b = result.inputs[1];
  EXPECT_TRUE(b.overlaps);
  EXPECT_FALSE(b.applied);
  EXPECT_EQ(b.status, "refused");
  EXPECT_EQ(b.unconstrained, "yaw x y");
  EXPECT_EQ(b.reason, "ill-conditioned: yaw x y not constrained by the overlap") << b.reason;
  const nlohmann::json report = nlohmann::json::parse(Slurp(dir_ / "mosaic.json"));
  EXPECT_EQ(report["inputs"][1]["status"], "refused");
  EXPECT_EQ(report["inputs"][1]["reason"], b.reason);
  EXPECT_EQ(report["inputs"][1]["unconstrained"], "yaw x y");
}

// ---- the gates, alone -------------------------------------------------------------------

// The information of a point-to-plane match over a grid of points on z = f(x, y) (2 cm σ).
mosaic::detail::Matrix6d GridInformation(const std::function<double(double, double)>& f) {
  mosaic::detail::Matrix6d information = mosaic::detail::Matrix6d::Zero();
  constexpr double h = 0.01;
  for (double x = -5.0; x <= 5.0; x += 0.25) {
    for (double y = -5.0; y <= 5.0; y += 0.25) {
      const Eigen::Vector3d p(x, y, f(x, y));
      const Eigen::Vector3d n = Eigen::Vector3d((f(x - h, y) - f(x + h, y)) / (2 * h),
                                                (f(x, y - h) - f(x, y + h)) / (2 * h), 1.0)
                                    .normalized();
      Eigen::Matrix<double, 6, 1> j;
      j << p.cross(n), n;
      information += j * j.transpose() / (0.02 * 0.02);
    }
  }
  return information;
}

TEST(CoregisterGates, APlaneConstrainsHeightAndTiltOnly) {
  using mosaic::detail::ConstrainDirections;
  const auto plane = ConstrainDirections(
      GridInformation([](double x, double y) { return 0.02 * x - 0.01 * y; }), 7.0, 2e-5);
  EXPECT_EQ(plane.unconstrained, mosaic::detail::kHorizontal);
  EXPECT_LT(plane.conditioning, 1e-12);
  // Kept directions pass a step unchanged, the others are dropped.
  Eigen::Matrix<double, 6, 1> step;
  step << 0.0, 0.0, 0.05, 0.3, 0.2, 0.1;  // yaw, x, y (along the plane) and z
  const Eigen::Matrix<double, 6, 1> kept = plane.projector * step;
  // Yaw about z is a turn about the normal (dropped) and a hair of tilt (kept: 2.5e-5 rad).
  EXPECT_NEAR(kept(2), 0.0, 1e-4);
  // Of the shift (0.3, 0.2, 0.1), the part along the plane's normal is kept…
  const Eigen::Vector3d n = Eigen::Vector3d(-0.02, 0.01, 1.0).normalized();
  EXPECT_NEAR(kept.tail<3>().dot(n), step.tail<3>().dot(n), 1e-9);
  EXPECT_NEAR(kept.tail<3>().cross(n).norm(), 0.0, 1e-9);  // … and nothing along it

  const auto relief = ConstrainDirections(
      GridInformation([](double x, double y) { return Relief(500000 + x, 4000000 + y); }), 7.0,
      2e-5);
  EXPECT_EQ(relief.unconstrained, 0u);
  EXPECT_GT(relief.conditioning, 1e-4);
  EXPECT_TRUE(relief.projector.isIdentity(1e-9));

  EXPECT_EQ(ConstrainDirections(mosaic::detail::Matrix6d::Zero(), 7.0, 2e-5).unconstrained, 0x3fu);
}

TEST(CoregisterGates, EachReasonNamesItsFiguresAndKey) {
  using mosaic::detail::JudgeCorrection;
  const mosaic::MosaicOptions o;  // 0.8x, 2 m, 5 deg
  EXPECT_EQ(JudgeCorrection(0, 0.102, 0.026, 0.5, 3.0, o), "");
  EXPECT_EQ(JudgeCorrection(registration::kYaw | registration::kX, 0.102, 0.026, 0.5, 3.0, o),
            "ill-conditioned: yaw x not constrained by the overlap");
  // Roll and pitch alone are held at zero, not refused.
  EXPECT_EQ(JudgeCorrection(registration::kRoll | registration::kPitch, 0.102, 0.026, 0.5, 3.0, o),
            "");
  EXPECT_EQ(JudgeCorrection(0, 0.102, 0.091, 0.5, 3.0, o),
            "disagreement only 0.1020 -> 0.0910 m RMS (needs < 0.80x)");
  EXPECT_EQ(JudgeCorrection(0, 0.102, 0.026, 2.5, 3.0, o),
            "correction 2.50 m exceeds mosaic.max_correction_m 2.00");
  EXPECT_EQ(JudgeCorrection(0, 0.102, 0.026, 0.5, 5.2, o),
            "correction 5.20 deg exceeds mosaic.max_correction_deg 5.00");
  // Every failed test is named, in that order.
  EXPECT_EQ(JudgeCorrection(registration::kY, 0.102, 0.2, 4.1, 83.7, o),
            "ill-conditioned: y not constrained by the overlap; disagreement only 0.1020 -> "
            "0.2000 m RMS (needs < 0.80x); correction 4.10 m exceeds mosaic.max_correction_m "
            "2.00; correction 83.70 deg exceeds mosaic.max_correction_deg 5.00");
  // A NaN figure never passes.
  EXPECT_NE(JudgeCorrection(0, 0.102, std::nan(""), 0.5, 3.0, o), "");
}

TEST_F(MosaicTest, AnInputWithoutOverlapIsPlacedAndFlagged) {
  const std::string crs = "EPSG:32633";
  WriteDem(dir_ / "a.tif", 20, 20, NorthUp(500000, 4000020, 1.0), crs, Plane(0.05f));
  WriteDem(dir_ / "b.tif", 20, 20, NorthUp(500100, 4000020, 1.0), crs, Plane(0.05f));
  const mosaic::MosaicResult result =
      Build({dir_ / "a.tif", dir_ / "b.tif"}, "m.tif", mosaic::MosaicOptions{}, true);
  EXPECT_EQ(result.inputs[1].status, "no_overlap");
  EXPECT_FALSE(result.inputs[1].applied);
  EXPECT_EQ(result.valid_cells, 800u);
}

TEST_F(MosaicTest, CommandWritesTheMosaicAndRefusesToOverwrite) {
  WriteDem(dir_ / "a.tif", 20, 20, NorthUp(500000, 4000020, 1.0), "EPSG:32633", Plane(0.05f));
  const std::string a = (dir_ / "a.tif").string();
  const std::string out = (dir_ / "m.tif").string();
  CommandResult r = Rovermap("mosaic " + a + " --out " + out);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "m.json"));
  EXPECT_NE(r.out.find("\"valid_cells\": 400"), std::string::npos) << r.out;
  // 1 m cells: the 0.6 m footprint is smaller than two of them, so no layers, and why.
  EXPECT_FALSE(fs::exists(dir_ / "m_terrain.tif"));
  EXPECT_NE(r.err.find("no terrain layers: terrain.footprint_m"), std::string::npos) << r.err;
  r = Rovermap("mosaic " + a + " --out " + out);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--force"), std::string::npos) << r.err;
  r = Rovermap("mosaic " + a + " --out " + out +
               " --force --set mosaic.tile_cells=16 --set terrain.footprint_m=5");
  EXPECT_EQ(r.status, 0) << r.err;
  // With a footprint of the rover's size on these cells: NAME_terrain.tif and .png beside it.
  ASSERT_TRUE(fs::exists(dir_ / "m_terrain.tif")) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "m_terrain.png"));
  EXPECT_NE(r.err.find("terrain layers in m_terrain.tif and m_terrain.png"), std::string::npos)
      << r.err;
  const io::DemRaster layers = io::ReadDemGeoTiff(dir_ / "m_terrain.tif");
  EXPECT_EQ(layers.width, 20);
  EXPECT_EQ(layers.band_descriptions.front(), "slope_deg");
}

// Each mosaic's report is named after it: a second mosaic of another name in the same folder
// is neither refused for the first one's report nor replaces it.
TEST_F(MosaicTest, TwoMosaicsInOneFolderEachHaveTheirOwnReport) {
  WriteDem(dir_ / "a.tif", 20, 20, NorthUp(500000, 4000020, 1.0), "EPSG:32633", Plane(0.05f));
  WriteDem(dir_ / "b.tif", 10, 20, NorthUp(500000, 4000020, 1.0), "EPSG:32633", Plane(0.05f));
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  CommandResult r =
      Rovermap("mosaic " + (dir_ / "a.tif").string() + " --out " + (out / "first.tif").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string first_report = Slurp(out / "first.json");
  EXPECT_EQ(first_report, r.out);
  r = Rovermap("mosaic " + (dir_ / "b.tif").string() + " --out " + (out / "second.tif").string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(Slurp(out / "second.json"), r.out);
  EXPECT_EQ(Slurp(out / "first.json"), first_report);
  EXPECT_NE(first_report, r.out);
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(out)) files.push_back(entry.path().filename());
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files,
            (std::vector<std::string>{"first.json", "first.tif", "second.json", "second.tif"}));
  // An output named .json would be its own report.
  r = Rovermap("mosaic " + (dir_ / "a.tif").string() + " --out " + (out / "m.json").string());
  EXPECT_EQ(r.status, 2);
  EXPECT_FALSE(fs::exists(out / "m.json"));
}

class MosaicErrorTest : public MosaicTest {
 protected:
  // `rovermap mosaic INPUT`: exit 1, `message` on stderr, nothing written.
  void ExpectIoError(const std::string& input, const std::string& message) {
    const CommandResult r =
        Rovermap("mosaic " + (dir_ / input).string() + " --out " + (dir_ / "m.tif").string());
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    ExpectNoOutput({input});
  }
  // Nothing but the inputs is left in the folder.
  void ExpectNoOutput(const std::vector<std::string>& inputs) {
    for (const auto& entry : fs::directory_iterator(dir_)) {
      const std::string name = entry.path().filename().string();
      if (name == "stdout" || name == "stderr") continue;
      EXPECT_NE(std::find(inputs.begin(), inputs.end(), name), inputs.end()) << name;
    }
  }
};

TEST_F(MosaicErrorTest, MissingInputIsAnIoError) {
  WriteDem(dir_ / "a.tif", 8, 8, NorthUp(500000, 4000008, 1.0), "EPSG:32633", Plane(0.05f));
  const CommandResult r =
      Rovermap("mosaic " + (dir_ / "a.tif").string() + " " + (dir_ / "nope.tif").string() +
               " --out " + (dir_ / "m.tif").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("nope.tif"), std::string::npos) << r.err;
  ExpectNoOutput({"a.tif"});
}

TEST_F(MosaicErrorTest, OneBandTifIsAnIoError) {
  WriteDem(dir_ / "one.tif", 8, 8, NorthUp(500000, 4000008, 1.0), "EPSG:32633", Plane(0.05f), 1);
  ExpectIoError("one.tif", "one.tif: has 1 band(s)");
}

TEST_F(MosaicErrorTest, NotAGeoTiffIsAnIoError) {
  Write("text.tif", "not a raster\n");
  ExpectIoError("text.tif", "text.tif: not a GeoTIFF");
}

TEST_F(MosaicErrorTest, BadKeysAreConfigErrors) {
  WriteDem(dir_ / "a.tif", 8, 8, NorthUp(500000, 4000008, 1.0), "EPSG:32633", Plane(0.05f));
  const std::string base =
      "mosaic " + (dir_ / "a.tif").string() + " --out " + (dir_ / "m.tif").string() + " --set ";
  for (const std::string set :
       {"mosaic.nope=1", "mosaic.cell_size_m=-1", "mosaic.disagreement_sigma=.nan",
        "mosaic.min_information=1", "mosaic.min_improvement=0", "mosaic.max_correction_m=-1",
        "mosaic.max_correction_deg=.nan", "mosaic.tilt_sigma_deg=-0.1", "mosaic.tile_cells=0",
        "mosaic.crs=EPSG:999999", "mosaic.crs=EPSG:4326"}) {
    SCOPED_TRACE(set);
    const CommandResult r = Rovermap(base + set);
    EXPECT_EQ(r.status, 2) << r.err;
    const std::string key = set.substr(0, set.find('='));
    EXPECT_NE(r.err.find(key), std::string::npos) << r.err;
    ExpectNoOutput({"a.tif"});
  }
}

}  // namespace
}  // namespace rovermap

namespace rovermap {
namespace {

TEST(MosaicConfig, CrsTextRoundTripsThroughTheDump) {
  const config::Config cfg = config::ParseConfig(
      "mosaic:\n  crs: \"EPSG:32633\"\n  cell_size_m: 0.5\n  coregister: false\n", "test.yaml",
      {"mosaic.tile_cells=64"});
  EXPECT_EQ(cfg.mosaic.crs, "EPSG:32633");
  EXPECT_EQ(cfg.mosaic.tile_cells, 64);
  config::Config odd;
  odd.mosaic.crs = "+proj=tmerc +lat_0=0 \"quoted\" \\ back\nslash";
  const config::Config back = config::ParseConfig(config::DumpYaml(odd), "dump.yaml", {});
  EXPECT_EQ(back.mosaic.crs, odd.mosaic.crs);
}

}  // namespace
}  // namespace rovermap

namespace rovermap {
namespace {

// Two replay-style dem.tif files (io::WriteDemGeoTiff from an ElevationMap on each origin's
// grid, rotated by its meridian convergence): origins on either side of the zone 32/33 edge at
// 12° E, 3 m apart in altitude. The true terrain is a plane in zone 33.
class MosaicOfReplayDems : public MosaicTest {
 protected:
  static constexpr double kLat = 45.0;
  // Ellipsoidal height of the truth at zone-33 (E, N).
  static double Truth(double e, double n) { return 100.0 + 0.05 * (e - kE0) + 0.02 * (n - kN0); }
  static constexpr double kE0 = 264000.0;
  static constexpr double kN0 = 4986000.0;

  // Ellipsoidal height of a relief at zone-33 (E, N).
  static double Relief33(double e, double n) {
    return 100.0 + Relief(e - kE0 + 500000.0, n - kN0 + 4000000.0);
  }

  // A traverse's dem.tif on its own origin: `truth` (zone-33 coordinates), seen displaced by
  // `shift` (zone-33 east, north, up: what it shows at p is the truth at p - shift).
  template <typename F>
  void WriteTraverse(const fs::path& path, double lon_deg, double altitude_m, F truth,
                     double cell_m = 0.5, const Eigen::Vector3d& shift = Eigen::Vector3d::Zero()) {
    const io::Georeference georef(io::GeodeticOrigin{kLat, lon_deg, altitude_m});
    const auto ct = EpsgTransform(georef.epsg(), 32633);
    dem::ElevationMapOptions options;
    options.cell_size_m = cell_m;
    options.grid_rotation_rad = georef.convergence_rad();
    dem::ElevationMap map(options);
    for (double y = -20.0; y <= 20.0; y += cell_m / 2) {
      for (double x = -20.0; x <= 20.0; x += cell_m / 2) {
        const std::optional<dem::CellIndex> cell = map.WorldToCell(x, y);
        ASSERT_TRUE(cell);
        const Eigen::Vector2d centre = map.CellCenterWorld(*cell);
        Eigen::Vector2d p = georef.EnuToProjectedExact(centre.x(), centre.y());
        ASSERT_TRUE(ct->Transform(1, &p.x(), &p.y()));
        const double h = truth(p.x() - shift.x(), p.y() - shift.y()) + shift.z();
        map.SetCell(*cell, h - altitude_m, 0.01 * 0.01);
      }
    }
    io::WriteDemGeoTiff(path, map, georef);
  }
};

TEST_F(MosaicOfReplayDems, OriginsInTwoZonesAndAltitudesAgree) {
  WriteTraverse(dir_ / "a.tif", 11.9999, 100.0, Truth);  // zone 32
  WriteTraverse(dir_ / "b.tif", 12.0002, 103.0, Truth);  // zone 33, 16 m east, 3 m higher origin
  auto options = NoCoregistration();
  options.crs = "EPSG:32633";
  Build({dir_ / "a.tif", dir_ / "b.tif"}, "m.tif", options);
  const io::DemRaster m = Read("m.tif");
  const std::vector<float> d = Disagreement("m.tif");
  EXPECT_EQ(m.epsg, 32633);
  std::size_t both = 0;
  double worst = 0.0;
  ForEachCell(m, [&](std::size_t c, double e, double n) {
    // Heights above the first input's origin altitude (100 m).
    worst = std::max(worst, std::abs(m.elevation_m[c] - (Truth(e, n) - 100.0)));
    if (m.count[c] > 3.5f) {
      ++both;
      EXPECT_EQ(d[c], 0.0f) << c;
    }
  });
  // Half a cell's worth of slope (0.054 per metre) at the outermost cells, where bilinear
  // resampling has one neighbour fewer; without the altitude shift B would be 3 m off.
  EXPECT_LT(worst, 0.02);  // measured 0.013 m
  EXPECT_GT(both, 1000u);
}

TEST_F(MosaicOfReplayDems, CoregistrationAcrossZones) {
  // The output is in A's zone 32; B, in zone 33, is displaced by (0.2, 0, 0.1) m in zone-33
  // coordinates: its correction is found in zone 32 and carried back into zone 33.
  WriteTraverse(dir_ / "a.tif", 11.9999, 100.0, Relief33, 0.25);
  WriteTraverse(dir_ / "b.tif", 12.0002, 103.0, Relief33, 0.25, Eigen::Vector3d(0.2, 0.0, 0.1));
  const auto to33 = EpsgTransform(32632, 32633);
  auto rmse = [&](const std::string& name) {
    const io::DemRaster m = Read(name);
    EXPECT_EQ(m.epsg, 32632);
    double sum = 0.0;
    std::size_t n = 0;
    ForEachCell(m, [&](std::size_t c, double x, double y) {
      to33->Transform(1, &x, &y);
      const double e = m.elevation_m[c] - (Relief33(x, y) - 100.0);
      sum += e * e;
      ++n;
    });
    return std::sqrt(sum / n);
  };
  Build({dir_ / "a.tif", dir_ / "b.tif"}, "plain.tif", NoCoregistration());
  const mosaic::MosaicResult result =
      Build({dir_ / "a.tif", dir_ / "b.tif"}, "coreg.tif", mosaic::MosaicOptions{});
  const mosaic::InputReport& b = result.inputs[1];
  EXPECT_TRUE(b.applied) << b.status;
  // Zone 32's grid is turned by 4.24 degrees (the convergence at 12° E, 45° N, twice) against
  // zone 33's: the 0.2 m east shift reads as (-0.1995, -0.0148) m there. Measured:
  // (-0.1996, -0.0149, -0.1000) m; RMS over the overlap 0.098 -> 0.0009 m.
  RecordProperty("translation_x", std::to_string(b.translation_m.x()));
  RecordProperty("translation_y", std::to_string(b.translation_m.y()));
  RecordProperty("translation_z", std::to_string(b.translation_m.z()));
  RecordProperty("rms_after_m", std::to_string(b.rms_after_m));
  EXPECT_NEAR(b.translation_m.x(), -0.1995, 0.002);
  EXPECT_NEAR(b.translation_m.y(), -0.0148, 0.002);
  EXPECT_NEAR(b.translation_m.z(), -0.1, 0.002);
  EXPECT_LT(b.rms_after_m, 0.005);
  const double plain = rmse("plain.tif");
  const double coregistered = rmse("coreg.tif");
  RecordProperty("rmse_plain", std::to_string(plain));
  RecordProperty("rmse_coregistered", std::to_string(coregistered));
  EXPECT_LT(coregistered, 0.1 * plain);  // measured 0.064 -> 0.0014 m
}

}  // namespace
}  // namespace rovermap
