#include <gtest/gtest.h>

#include <GeographicLib/UTMUPS.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "dem/ElevationMap.hpp"
#include "io/GeoTiff.hpp"
#include "io/Georeference.hpp"
#include "io/IoError.hpp"
#include "io/MapPreview.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap::io {
namespace {

namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  const fs::path dir = rovermap::testing::ScratchDir() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// A map in the georeference's grid, cell `cell_m`, holding z = f(x, y) at every cell centre of
// the world box [x0, x1] × [y0, y1].
template <typename F>
dem::ElevationMap FillBox(const Georeference& georef, double cell_m, double x0, double x1,
                          double y0, double y1, F f) {
  dem::ElevationMapOptions options;
  options.min_agreeing_neighbors = 0;  // cells are checked one by one
  options.cell_size_m = cell_m;
  options.grid_rotation_rad = georef.convergence_rad();
  dem::ElevationMap map(options);
  std::vector<Eigen::Vector3d> points;
  for (double x = x0; x <= x1; x += cell_m / 2)
    for (double y = y0; y <= y1; y += cell_m / 2) {
      const auto cell = map.WorldToCell(x, y);
      const Eigen::Vector2d c = map.CellCenterWorld(*cell);
      map.SetCell(*cell, f(c.x(), c.y()), 1e-4);
    }
  return map;
}

// Projected centre of `cell`'s pixel according to the file's geotransform.
Eigen::Vector2d PixelCentre(const DemRaster& raster, const dem::ElevationMap& map,
                            dem::CellIndex cell) {
  const double col = static_cast<double>(cell.x - map.bounds().Min().x) + 0.5;
  const double row = static_cast<double>(map.bounds().Max().y - cell.y) + 0.5;
  const auto& gt = raster.geotransform;
  return {gt[0] + col * gt[1] + row * gt[2], gt[3] + col * gt[4] + row * gt[5]};
}

TEST(Georeference, UtmZoneAndConvergence) {
  const Georeference graz({47.07, 15.44, 350.0});
  EXPECT_EQ(graz.epsg(), 32633);
  EXPECT_EQ(graz.utm_zone(), 33);
  const Georeference cape({-33.92, 18.42, 10.0});
  EXPECT_EQ(cape.epsg(), 32734);
  EXPECT_FALSE(cape.north());
  // East of the central meridian in the north: grid north is east of true north (γ > 0).
  const Georeference east({47.3, 17.8, 0.0});
  EXPECT_GT(east.convergence_rad(), 0.0);
  EXPECT_NEAR(east.convergence_rad(), (17.8 - 15.0) * std::sin(47.3 * M_PI / 180) * M_PI / 180,
              2e-4);
  EXPECT_NE(east.wkt().find("32633"), std::string::npos);
  EXPECT_THROW(Georeference({91.0, 0.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(Georeference({0.0, std::nan(""), 0.0}), std::invalid_argument);
  EXPECT_EQ(ParseBody("mars"), Body::kMars);
  EXPECT_THROW(ParseBody("venus"), std::invalid_argument);
}

// The affine grid -> UTM model against GeographicLib's exact ENU -> geodetic -> UTM chain: a
// quarter of the default 5 cm cell within 1 km of the origin, at several places on Earth.
TEST(Georeference, AffineGridMatchesGeographicLibWithinAQuarterCell) {
  const GeodeticOrigin origins[] = {{47.3, 17.8, 400.0},
                                    {-33.92, 18.42, 10.0},
                                    {64.1, -21.0, 50.0},
                                    {0.5, 36.0, 1500.0},
                                    {-77.8, 166.7, 0.0}};
  for (const GeodeticOrigin& origin : origins) {
    const Georeference georef(origin);
    dem::ElevationMapOptions options;
    options.min_agreeing_neighbors = 0;  // cells are checked one by one
    options.grid_rotation_rad = georef.convergence_rad();
    const dem::ElevationMap map(options);
    double worst = 0.0;
    for (double x = -1000.0; x <= 1000.0; x += 100.0) {
      for (double y = -1000.0; y <= 1000.0; y += 100.0) {
        const Eigen::Vector2d affine = georef.GridToProjected(map.WorldToGrid(x, y));
        const Eigen::Vector2d exact = georef.EnuToProjectedExact(x, y);
        worst = std::max(worst, (affine - exact).norm());
      }
    }
    EXPECT_LT(worst, 0.0125) << origin.latitude_deg << " " << origin.longitude_deg;
  }
}

TEST(GeoTiff, RampRisingNorthReadsBackRisingNorth) {
  const Georeference georef({47.3, 17.8, 400.0});
  const auto ramp = [](double, double y) { return 0.1 * y; };
  const dem::ElevationMap map = FillBox(georef, 0.1, -20.0, 20.0, -10.0, 30.0, ramp);
  const fs::path path = TempDir("ramp") / "dem.tif";
  const GeoTiffInfo info = WriteDemGeoTiff(path, map, georef);
  const DemRaster raster = ReadDemGeoTiff(path);

  EXPECT_EQ(raster.width, info.width);
  EXPECT_EQ(raster.height, info.height);
  EXPECT_EQ(raster.epsg, 32633);
  EXPECT_EQ(raster.band_types, (std::vector<std::string>{"Float32", "Float32", "Float32"}));
  EXPECT_EQ(raster.band_descriptions[0], "elevation");
  for (int b = 0; b < 3; ++b) {
    EXPECT_TRUE(raster.has_nodata[b]);
    EXPECT_TRUE(std::isnan(raster.nodata[b]));
  }
  EXPECT_EQ(raster.layout, "COG");
  EXPECT_EQ(raster.compression, "DEFLATE");
  // North-up, square pixels of k·s, no rotation terms.
  const auto& gt = raster.geotransform;
  EXPECT_NEAR(gt[1], 0.1 * georef.scale_factor(), 1e-12);
  EXPECT_NEAR(gt[5], -0.1 * georef.scale_factor(), 1e-12);
  EXPECT_EQ(gt[2], 0.0);
  EXPECT_EQ(gt[4], 0.0);
  for (int b = 0; b < 6; ++b) EXPECT_EQ(gt[b], info.geotransform[b]);

  // Down each column (north to south) the ramp only falls.
  int checked = 0;
  for (int col = 0; col < raster.width; col += 37) {
    float previous = std::numeric_limits<float>::infinity();
    for (int row = 0; row < raster.height; ++row) {
      const float z = raster.ElevationAt(col, row);
      if (std::isnan(z)) continue;
      EXPECT_LT(z, previous);
      previous = z;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
  // Where GeographicLib puts an ENU point, the file holds the ramp's height there.
  for (double x = -15.0; x <= 15.0; x += 5.0) {
    for (double y = -5.0; y <= 25.0; y += 5.0) {
      const Eigen::Vector2d en = georef.EnuToProjectedExact(x + 0.013, y + 0.027);
      const int col = static_cast<int>(std::floor((en.x() - gt[0]) / gt[1]));
      const int row = static_cast<int>(std::floor((en.y() - gt[3]) / gt[5]));
      // Within a cell of slope 0.1: half a cell diagonal of height error at most.
      EXPECT_NEAR(raster.ElevationAt(col, row), ramp(x, y + 0.027), 0.1 * 0.1 * 0.71 + 1e-4);
    }
  }
  // Stddev and count bands.
  const std::size_t some = static_cast<std::size_t>(raster.height / 2) * raster.width +
                           static_cast<std::size_t>(raster.width / 2);
  EXPECT_NEAR(raster.stddev_m[some], 0.01, 1e-6);
  EXPECT_EQ(raster.count[some], 3.0f);  // SetCell's default count: min_support
}

TEST(GeoTiff, CornerCellsAgreeWithGeographicLib) {
  struct Case {
    GeodeticOrigin origin;
    Body body;
    double cell_m;
    double half_extent_m;
  };
  const Case cases[] = {{{47.3, 17.8, 400.0}, Body::kEarth, 0.05, 25.0},
                        {{47.3, 17.8, 400.0}, Body::kEarth, 0.5, 300.0},
                        {{-33.92, 18.42, 10.0}, Body::kEarth, 0.25, 150.0},
                        {{-43.5, 24.6, 0.0}, Body::kMoon, 0.25, 150.0},
                        {{18.4, 77.5, -2500.0}, Body::kMars, 0.25, 150.0}};
  int n = 0;
  for (const Case& c : cases) {
    const Georeference georef(c.origin, c.body);
    const double e = c.half_extent_m;
    const auto flat = [](double, double) { return 1.0; };
    // Only a frame of cells, to keep the raster small but its extent wide.
    dem::ElevationMapOptions options;
    options.min_agreeing_neighbors = 0;  // cells are checked one by one
    options.cell_size_m = c.cell_m;
    options.grid_rotation_rad = georef.convergence_rad();
    dem::ElevationMap map(options);
    std::vector<dem::CellIndex> corners;
    for (const Eigen::Vector2d& p :
         {Eigen::Vector2d(-e, -e), Eigen::Vector2d(e, -e), Eigen::Vector2d(-e, e),
          Eigen::Vector2d(e, e), Eigen::Vector2d(0.0, 0.0)}) {
      const auto cell = map.WorldToCell(p.x(), p.y());
      map.SetCell(*cell, flat(p.x(), p.y()), 0.0);
      corners.push_back(*cell);
    }
    const fs::path path = TempDir("corners" + std::to_string(n++)) / "dem.tif";
    WriteDemGeoTiff(path, map, georef);
    const DemRaster raster = ReadDemGeoTiff(path);
    if (c.body == Body::kEarth) {
      EXPECT_EQ(raster.epsg, georef.epsg());
    } else {
      EXPECT_EQ(raster.epsg, 0);
      const std::string radius = c.body == Body::kMoon ? "1737400" : "3396190";
      EXPECT_NE(raster.wkt.find(radius), std::string::npos) << raster.wkt;
      EXPECT_NE(raster.wkt.find("Transverse"), std::string::npos) << raster.wkt;
    }
    for (const dem::CellIndex cell : corners) {
      const Eigen::Vector2d world = map.CellCenterWorld(cell);
      const Eigen::Vector2d exact = georef.EnuToProjectedExact(world.x(), world.y());
      const Eigen::Vector2d file = PixelCentre(raster, map, cell);
      EXPECT_LT((file - exact).norm(), 0.25 * c.cell_m)
          << "cell " << cell.x << "," << cell.y << " case " << n;
      const int col = static_cast<int>(cell.x - map.bounds().Min().x);
      const int row = static_cast<int>(map.bounds().Max().y - cell.y);
      EXPECT_EQ(raster.ElevationAt(col, row), 1.0f);
    }
    if (c.body == Body::kEarth) {
      // And the origin itself is where UTMUPS puts the geodetic origin.
      double x = 0, y = 0;
      int zone = 0;
      bool north = true;
      GeographicLib::UTMUPS::Forward(c.origin.latitude_deg, c.origin.longitude_deg, zone, north, x,
                                     y);
      EXPECT_NEAR(georef.origin_projected().x(), x, 1e-6);
      EXPECT_NEAR(georef.origin_projected().y(), y, 1e-6);
    }
  }
}

TEST(GeoTiff, EmptyMapAndNaNCells) {
  const Georeference georef({10.0, 10.0, 0.0});
  dem::ElevationMapOptions options;
  options.min_agreeing_neighbors = 0;  // cells are checked one by one
  options.grid_rotation_rad = georef.convergence_rad();
  dem::ElevationMap map(options);
  const fs::path dir = TempDir("empty");
  const GeoTiffInfo empty = WriteDemGeoTiff(dir / "dem.tif", map, georef);
  EXPECT_EQ(empty.width, 1);
  EXPECT_EQ(empty.valid_cells, 0u);
  EXPECT_TRUE(std::isnan(ReadDemGeoTiff(dir / "dem.tif").elevation_m[0]));
  map.SetCell({0, 0}, 2.0, 0.04);
  map.SetCell({3, 2}, 3.0, 0.09);
  const GeoTiffInfo two = WriteDemGeoTiff(dir / "dem.tif", map, georef);
  EXPECT_EQ(two.width, 4);
  EXPECT_EQ(two.height, 3);
  EXPECT_EQ(two.valid_cells, 2u);
  const DemRaster raster = ReadDemGeoTiff(dir / "dem.tif");
  EXPECT_EQ(raster.ElevationAt(0, 2), 2.0f);  // cell (0, 0): west, south row
  EXPECT_EQ(raster.ElevationAt(3, 0), 3.0f);  // cell (3, 2): east, north row
  EXPECT_TRUE(std::isnan(raster.ElevationAt(1, 1)));
  EXPECT_NEAR(raster.stddev_m[2 * 4 + 0], 0.2, 1e-6);
  EXPECT_TRUE(std::isnan(raster.stddev_m[1 * 4 + 1]));
  EXPECT_EQ(raster.count[1 * 4 + 1], 0.0f);
  for (const auto& entry : fs::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().filename(), "dem.tif");  // no temporaries left
  }
}

TEST(GeoTiff, CloudOptimizedWithPredictorAndOverviews) {
  const Georeference georef({47.3, 17.8, 400.0});
  dem::ElevationMapOptions options;
  options.min_agreeing_neighbors = 0;  // cells are checked one by one
  options.grid_rotation_rad = georef.convergence_rad();
  dem::ElevationMap map(options);
  map.SetCell({0, 0}, 1.0, 0.0);
  map.SetCell({1099, 599}, 2.0, 0.0);  // a 1100 × 600 raster, more than two 512-pixel tiles
  const fs::path path = TempDir("cog") / "dem.tif";
  WriteDemGeoTiff(path, map, georef);
  const DemRaster raster = ReadDemGeoTiff(path);
  EXPECT_EQ(raster.width, 1100);
  EXPECT_EQ(raster.height, 600);
  EXPECT_EQ(raster.layout, "COG");
  EXPECT_EQ(raster.compression, "DEFLATE");
  EXPECT_EQ(raster.predictor, "3");
  EXPECT_GE(raster.overview_count, 1);
  EXPECT_EQ(raster.ElevationAt(0, 599), 1.0f);
  EXPECT_EQ(raster.ElevationAt(1099, 0), 2.0f);
}

TEST(GeoTiff, ErrorsNameTheFileAndLeaveNothing) {
  const Georeference georef({47.3, 17.8, 0.0});
  dem::ElevationMap unrotated;  // grid_rotation 0 but γ ≈ 2°
  EXPECT_THROW(WriteDemGeoTiff(TempDir("err") / "dem.tif", unrotated, georef),
               std::invalid_argument);
  dem::ElevationMapOptions options;
  options.min_agreeing_neighbors = 0;  // cells are checked one by one
  options.grid_rotation_rad = georef.convergence_rad();
  dem::ElevationMap map(options);
  map.SetCell({0, 0}, 1.0, 0.0);
  const fs::path bad = TempDir("err") / "missing" / "dem.tif";
  try {
    WriteDemGeoTiff(bad, map, georef);
    ADD_FAILURE() << "expected IoError";
  } catch (const IoError& error) {
    EXPECT_NE(std::string(error.what()).find(bad.string()), std::string::npos) << error.what();
  }
  EXPECT_THROW(ReadDemGeoTiff(TempDir("err") / "absent.tif"), IoError);
  const fs::path junk = TempDir("err") / "junk.tif";
  { std::ofstream(junk) << "not a tiff"; }
  EXPECT_THROW(ReadDemGeoTiff(junk), IoError);
}

TEST(MapPreview, WritesAnAnnotatedPng) {
  const Georeference georef({47.3, 17.8, 400.0});
  const auto bumps = [](double x, double y) { return std::sin(x / 3) * std::cos(y / 4); };
  const dem::ElevationMap map = FillBox(georef, 0.1, -10.0, 10.0, -10.0, 10.0, bumps);
  const fs::path dir = TempDir("preview");
  std::vector<Eigen::Vector3d> trajectory;
  for (int i = 0; i < 50; ++i) trajectory.emplace_back(-8.0 + 0.3 * i, std::sin(i * 0.2) * 5, 0);
  WriteDemPreview(dir / "dem.png", map, trajectory);
  const cv::Mat image = cv::imread((dir / "dem.png").string());
  ASSERT_FALSE(image.empty());
  EXPECT_GT(image.cols, 200);  // map plus colour bar
  EXPECT_GT(image.rows, 200);
  // Empty maps still give a picture.
  WriteDemPreview(dir / "empty.png", dem::ElevationMap{});
  EXPECT_FALSE(cv::imread((dir / "empty.png").string()).empty());
  EXPECT_THROW(WriteDemPreview(dir / "missing" / "dem.png", map), IoError);
}

// Where the registered path follows the truth, the truth must still show: it is drawn first and
// wider, so a band of its colour runs along both sides of the path drawn over it.
TEST(MapPreview, AWidePathDrawnFirstShowsAroundTheNarrowOneOverIt) {
  const Georeference georef({47.3, 17.8, 400.0});
  const dem::ElevationMap map =
      FillBox(georef, 0.1, -10.0, 10.0, -10.0, 10.0, [](double, double) { return 0.0; });
  std::vector<Eigen::Vector3d> path;
  for (int i = 0; i < 50; ++i) path.emplace_back(-8.0 + 0.3 * i, 0.2 * i - 4.0, 0.0);
  const auto green_pixels = [&](int truth_width_px) {
    PreviewTrajectory truth{"ground truth", {40, 200, 40}, path, truth_width_px};
    PreviewTrajectory registered{"registered", {255, 255, 255}, path};
    const fs::path file = TempDir("halo") / "dem.png";
    WriteDemPreview(file, map, {truth, registered});
    const cv::Mat image = cv::imread(file.string());
    int n = 0;
    for (int r = 0; r < image.rows; ++r) {
      for (int c = 0; c < image.cols; ++c) {
        const cv::Vec3b p = image.at<cv::Vec3b>(r, c);  // BGR
        n += p[1] > 150 && p[0] < 90 && p[2] < 90 ? 1 : 0;
      }
    }
    return n;
  };
  const int hidden = green_pixels(2);  // as wide as the path over it: covered, but the legend
  const int shown = green_pixels(8);
  EXPECT_GT(shown, 10 * hidden) << hidden << " " << shown;  // measured: 95 and 1495
}

// A few wrong cells must not set the colour range: a 1 m ramp with three 10 m spikes still
// spans the colour map (its top end red), and the bar names the clipped maximum.
TEST(MapPreview, AFewSpikesDoNotSetTheColourRange) {
  const Georeference georef({47.3, 17.8, 400.0});
  const auto ramp_with_spikes = [](double x, double y) {
    for (const auto& [sx, sy] : {std::pair{-5.0, -5.0}, {0.0, 3.0}, {6.0, -2.0}}) {
      if (std::abs(x - sx) < 0.15 && std::abs(y - sy) < 0.15) return 10.0;
    }
    return (x + 10.0) / 20.0;
  };
  const dem::ElevationMap map = FillBox(georef, 0.1, -10.0, 10.0, -10.0, 10.0, ramp_with_spikes);
  const auto red_pixels = [&](double quantile) {
    MapPreviewOptions options;
    options.colour_quantile = quantile;
    const fs::path file = TempDir("spikes") / "dem.png";
    WriteDemPreview(file, map, std::vector<PreviewTrajectory>{}, options);
    const cv::Mat image = cv::imread(file.string());
    // In the map (20 px margin, 201 cells drawn 2 px each), not the colour bar beside it.
    EXPECT_GE(std::min(image.rows, image.cols), 20 + 402);
    int n = 0;
    for (int r = 20; r < std::min(image.rows, 20 + 402); ++r) {
      for (int c = 20; c < std::min(image.cols, 20 + 402); ++c) {
        const cv::Vec3b p = image.at<cv::Vec3b>(r, c);  // BGR: turbo's upper end
        n += p[2] > 150 && p[1] < 140 && p[0] < 80 ? 1 : 0;
      }
    }
    return n;
  };
  const int extremes = red_pixels(0.0);  // the spikes alone reach the top colours
  const int quantiles = red_pixels(MapPreviewOptions{}.colour_quantile);
  EXPECT_GT(quantiles, 20 * std::max(extremes, 1)) << extremes << " " << quantiles;  // 0, 36604
}

}  // namespace
}  // namespace rovermap::io
