#pragma once
// Small hand-made DEM GeoTIFFs (docs/design.md §6 layout: Float32 bands elevation, sigma, count;
// nodata NaN) for the mosaic tests, and ones lacking what a DEM must have.

#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <array>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace rovermap::testing {

struct Cell {
  float z;
  float sigma;
  float count;
};
using Surface = std::function<Cell(double x, double y)>;

inline std::array<double, 6> NorthUp(double x0, double y0, double cell) {
  return {x0, cell, 0.0, y0, 0.0, -cell};
}

inline Surface Constant(float z, float sigma, float count) {
  return [=](double, double) { return Cell{z, sigma, count}; };
}

/// A GeoTIFF of `bands` (at most 3) Float32 bands whose cell centres (x, y) in `crs` hold
/// f(x, y). Without a `geotransform` or with an empty `crs` the file has none (f is then
/// evaluated at pixel coordinates).
inline void WriteDem(const std::filesystem::path& path, int width, int height,
                     const std::optional<std::array<double, 6>>& geotransform,
                     const std::string& crs, const Surface& f, int bands = 3) {
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds = driver->Create(path.c_str(), width, height, bands, GDT_Float32, nullptr);
  ASSERT_NE(ds, nullptr);
  std::array<double, 6> g = geotransform.value_or(std::array<double, 6>{0, 1, 0, 0, 0, 1});
  if (geotransform) ds->SetGeoTransform(g.data());
  OGRSpatialReference srs;
  if (!crs.empty()) {
    srs.SetFromUserInput(crs.c_str());
    ds->SetSpatialRef(&srs);
  }
  std::vector<std::vector<float>> data(bands, std::vector<float>(width * height));
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const double u = c + 0.5;
      const double v = r + 0.5;
      const Cell cell = f(g[0] + u * g[1] + v * g[2], g[3] + u * g[4] + v * g[5]);
      const float values[3] = {cell.z, cell.sigma, cell.count};
      for (int b = 0; b < bands; ++b) data[b][r * width + c] = values[b];
    }
  }
  for (int b = 0; b < bands; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b + 1);
    band->SetNoDataValue(std::numeric_limits<double>::quiet_NaN());
    ASSERT_EQ(band->RasterIO(GF_Write, 0, 0, width, height, data[b].data(), width, height,
                             GDT_Float32, 0, 0, nullptr),
              CE_None);
  }
  GDALClose(ds);
}

}  // namespace rovermap::testing
