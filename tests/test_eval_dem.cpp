// DEM comparison (`rovermap eval --dem --reference`) on small GeoTIFFs built here with GDAL,
// with known errors: resampling to the coarser grid, nodata, coverage, σ honesty, CRS check.
#include <cpl_conv.h>
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "eval/DemComparison.hpp"
#include "eval/EvalPlots.hpp"
#include "io/GeoTiff.hpp"
#include "io/IoError.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap::eval {
namespace {

namespace fs = std::filesystem;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

struct Grid {
  double x0 = 500000.0, y0 = 4000000.0;  // top-left corner (UTM metres)
  double cell = 1.0;                     // [m]
  int width = 0, height = 0;
  int epsg = 32633;
  std::function<float(int col, int row)> elevation;
  std::function<float(int col, int row)> sigma;  // empty: one band
  double nodata = std::numeric_limits<double>::quiet_NaN();
};

fs::path WriteGeoTiff(const std::string& name, const Grid& g) {
  GDALAllRegister();
  const fs::path dir = rovermap::testing::ScratchDir();
  fs::create_directories(dir);
  const fs::path path = dir / name;
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds =
      driver->Create(path.c_str(), g.width, g.height, g.sigma ? 2 : 1, GDT_Float32, nullptr);
  double transform[6] = {g.x0, g.cell, 0.0, g.y0, 0.0, -g.cell};
  ds->SetGeoTransform(transform);
  if (g.epsg > 0) {
    OGRSpatialReference srs;
    srs.importFromEPSG(g.epsg);
    char* wkt = nullptr;
    srs.exportToWkt(&wkt);
    ds->SetProjection(wkt);
    CPLFree(wkt);
  }
  for (int band = 1; band <= (g.sigma ? 2 : 1); ++band) {
    std::vector<float> values;
    for (int row = 0; row < g.height; ++row)
      for (int col = 0; col < g.width; ++col)
        values.push_back(band == 1 ? g.elevation(col, row) : g.sigma(col, row));
    GDALRasterBand* b = ds->GetRasterBand(band);
    b->SetNoDataValue(g.nodata);
    EXPECT_EQ(b->RasterIO(GF_Write, 0, 0, g.width, g.height, values.data(), g.width, g.height,
                          GDT_Float32, 0, 0),
              CE_None);
  }
  GDALClose(ds);
  return path;
}

float Terrain(int col, int row) { return static_cast<float>(col + 0.1 * row); }

// Reference: 10 × 10 cells of 1 m, one nodata (−9999) cell. DEM: 0.5 m cells over the same
// area, mapped in the northern half only (rows 0–4 of the reference), each reference cell's four
// DEM cells at truth + e ± 0.05 (two each, so they average to truth + e): e = 0.1 in the western
// half, 0.3 in the eastern half; σ = 0.1 everywhere.
TEST(CompareDems, FinerDemIsAveragedIntoTheReferenceGrid) {
  Grid ref;
  ref.width = ref.height = 10;
  ref.nodata = -9999.0;
  ref.elevation = [](int col, int row) {
    return col == 7 && row == 8 ? -9999.0f : Terrain(col, row);
  };
  Grid dem;
  dem.cell = 0.5;
  dem.width = dem.height = 20;
  dem.elevation = [](int col, int row) {
    if (row >= 10) return kNaN;
    const float e = col < 10 ? 0.1f : 0.3f;
    const float wiggle = (col + row) % 2 == 0 ? 0.05f : -0.05f;
    return Terrain(col / 2, row / 2) + e + wiggle;
  };
  dem.sigma = [](int, int) { return 0.1f; };
  const io::DemRaster reference_raster = io::ReadDemGeoTiff(WriteGeoTiff("ref.tif", ref));
  const io::DemRaster dem_raster = io::ReadDemGeoTiff(WriteGeoTiff("dem.tif", dem));
  EXPECT_TRUE(std::isnan(reference_raster.elevation_m[8 * 10 + 7]));  // nodata → NaN
  EXPECT_EQ(dem_raster.stddev_m.size(), 400u);

  const DemComparison c = CompareDems(dem_raster, reference_raster);
  ASSERT_EQ(c.status, DemStatus::kOk) << c.message;
  EXPECT_TRUE(c.on_reference_grid);
  EXPECT_DOUBLE_EQ(c.cell_size_m, 1.0);
  EXPECT_EQ(c.cells, 50u);                       // 5 rows × 10 columns
  EXPECT_NEAR(c.bias_m, 0.2, 1e-5);              // (25 × 0.1 + 25 × 0.3) / 50
  EXPECT_NEAR(c.rmse_m, std::sqrt(0.05), 1e-5);  // sqrt((0.01 + 0.09) / 2)
  EXPECT_NEAR(c.p95_abs_m, 0.3, 1e-5);           // order statistics 46 and 47 are both 0.3
  EXPECT_NEAR(c.max_abs_m, 0.3, 1e-5);
  EXPECT_NEAR(c.coverage, 50.0 / 99.0, 1e-12);  // 99 reference cells with data
  EXPECT_EQ(c.sigma_cells, 50u);
  EXPECT_NEAR(c.within_2sigma, 0.5, 1e-12);  // |0.1| <= 0.2, |0.3| > 0.2
  ASSERT_EQ(c.error_m.size(), 100u);
  EXPECT_NEAR(c.error_m[0], 0.1, 1e-5);
  EXPECT_NEAR(c.error_m[9], 0.3, 1e-5);
  EXPECT_TRUE(std::isnan(c.error_m[99]));
  const nlohmann::json j = ToJson(c);
  for (const char* key : {"rmse_m", "bias_m", "p95_abs_m", "coverage", "within_2sigma", "cells"})
    EXPECT_TRUE(j.contains(key)) << key;
}

// Same 1 m grid, 4 × 5 cells, error k = 1..20 in cell k: p95 between the 19th and 20th order
// statistics (position 0.95 × 19 = 18.05 → 19.05).
TEST(CompareDems, SameGridHandComputedStatistics) {
  Grid ref;
  ref.width = 5;
  ref.height = 4;
  ref.elevation = [](int, int) { return 100.0f; };
  Grid dem = ref;
  dem.elevation = [](int col, int row) { return 100.0f + static_cast<float>(row * 5 + col + 1); };
  dem.sigma = [](int, int) { return 5.0f; };
  const DemComparison c = CompareDems(io::ReadDemGeoTiff(WriteGeoTiff("dem20.tif", dem)),
                                      io::ReadDemGeoTiff(WriteGeoTiff("ref20.tif", ref)));
  ASSERT_EQ(c.status, DemStatus::kOk) << c.message;
  EXPECT_EQ(c.cells, 20u);
  EXPECT_DOUBLE_EQ(c.bias_m, 10.5);
  EXPECT_DOUBLE_EQ(c.rmse_m, std::sqrt(2870.0 / 20.0));  // Σk² = 20·21·41 / 6
  EXPECT_NEAR(c.p95_abs_m, 19.05, 1e-12);
  EXPECT_DOUBLE_EQ(c.coverage, 1.0);
  EXPECT_DOUBLE_EQ(c.within_2sigma, 0.5);  // k <= 10
}

// A coarser DEM: the finer reference is averaged into the DEM's cells; coverage still counts the
// reference's own cells, including those outside the DEM's extent.
TEST(CompareDems, FinerReferenceIsAveragedIntoTheDemGrid) {
  Grid ref;
  ref.cell = 0.5;
  ref.width = 8;
  ref.height = 4;  // 4 m × 2 m
  ref.elevation = [](int col, int) { return static_cast<float>(col); };
  Grid dem;
  dem.cell = 1.0;
  dem.width = 2;
  dem.height = 2;  // the western 2 m × 2 m
  // Reference means per DEM cell: columns 0,1 → 0.5 and 2,3 → 2.5; DEM 1 m above that.
  dem.elevation = [](int col, int) { return col == 0 ? 1.5f : 3.5f; };
  const DemComparison c = CompareDems(io::ReadDemGeoTiff(WriteGeoTiff("dem_coarse.tif", dem)),
                                      io::ReadDemGeoTiff(WriteGeoTiff("ref_fine.tif", ref)));
  ASSERT_EQ(c.status, DemStatus::kOk) << c.message;
  EXPECT_FALSE(c.on_reference_grid);
  EXPECT_EQ(c.cells, 4u);
  EXPECT_NEAR(c.bias_m, 1.0, 1e-6);
  EXPECT_NEAR(c.rmse_m, 1.0, 1e-6);
  EXPECT_DOUBLE_EQ(c.coverage, 0.5);         // 16 of 32 reference cells lie under the DEM
  EXPECT_TRUE(std::isnan(c.within_2sigma));  // no band 2
  EXPECT_TRUE(ToJson(c)["within_2sigma"].is_null());
}

TEST(CompareDems, DifferentCrsIsAClearError) {
  Grid ref;
  ref.width = ref.height = 3;
  ref.elevation = Terrain;
  Grid dem = ref;
  dem.epsg = 32634;
  const DemComparison c = CompareDems(io::ReadDemGeoTiff(WriteGeoTiff("dem34.tif", dem)),
                                      io::ReadDemGeoTiff(WriteGeoTiff("ref33.tif", ref)));
  EXPECT_EQ(c.status, DemStatus::kCrsMismatch);
  EXPECT_NE(c.message.find("dem34.tif"), std::string::npos) << c.message;
  EXPECT_NE(c.message.find("ref33.tif"), std::string::npos) << c.message;
  EXPECT_NE(c.message.find("zone 34N"), std::string::npos) << c.message;
  dem.epsg = 0;  // no CRS at all against a CRS
  EXPECT_EQ(CompareDems(io::ReadDemGeoTiff(WriteGeoTiff("dem_nocrs.tif", dem)),
                        io::ReadDemGeoTiff(WriteGeoTiff("ref33.tif", ref)))
                .status,
            DemStatus::kCrsMismatch);
}

TEST(CompareDems, NoOverlapAndBadFiles) {
  Grid ref;
  ref.width = ref.height = 3;
  ref.elevation = Terrain;
  Grid far = ref;
  far.x0 += 1000.0;
  const DemComparison c = CompareDems(io::ReadDemGeoTiff(WriteGeoTiff("far.tif", far)),
                                      io::ReadDemGeoTiff(WriteGeoTiff("ref3.tif", ref)));
  EXPECT_EQ(c.status, DemStatus::kNoOverlap);
  EXPECT_DOUBLE_EQ(c.coverage, 0.0);

  const fs::path text = rovermap::testing::ScratchDir() / "not_a.tif";
  std::ofstream(text) << "hello\n";
  for (const fs::path& bad : {text, text.parent_path() / "missing.tif"}) {
    try {
      io::ReadDemGeoTiff(bad);
      ADD_FAILURE() << "expected an IoError for " << bad;
    } catch (const io::IoError& e) {
      EXPECT_NE(std::string(e.what()).find(bad.filename().string()), std::string::npos) << e.what();
    }
  }
}

// dem_error.png shows the compared cells, not the whole reference: a 10 × 10-cell patch of a
// 400 × 400-cell reference fills most of the picture's map (drawn whole it was 0.06 % of it).
TEST(DemErrorPlot, IsCroppedToTheComparedCells) {
  DemComparison c;
  c.width = c.height = 400;
  c.cell_size_m = 0.05;
  c.cells = 100;
  c.rmse_m = c.p95_abs_m = c.max_abs_m = 0.01;
  c.bias_m = 0.0;
  c.coverage = 100.0 / 160000.0;
  c.error_m.assign(400 * 400, std::numeric_limits<float>::quiet_NaN());
  for (int r = 200; r < 210; ++r)
    for (int col = 300; col < 310; ++col) c.error_m[r * 400 + col] = (r + col) % 2 ? 0.01f : -0.01f;
  const std::filesystem::path png = rovermap::testing::ScratchDir() / "dem_error_crop.png";
  WriteDemErrorPlot(png, c);
  const cv::Mat img = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  std::size_t coloured = 0, grey = 0;
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
      if (p == cv::Vec3b(200, 200, 200)) ++grey;
      if (p == cv::Vec3b(0, 0, 255) || p == cv::Vec3b(255, 0, 0)) ++coloured;
    }
  }
  // Patch plus a 2-cell margin each side: 100 of 196 cells compared.
  EXPECT_GT(coloured, grey) << coloured << " coloured, " << grey << " grey pixels";
  EXPECT_GT(coloured, 100000u);
}

}  // namespace
}  // namespace rovermap::eval
