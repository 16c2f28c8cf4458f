#include "eval/DemComparison.hpp"

#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <system_error>

#include "io/IoError.hpp"

namespace rovermap::eval {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

nlohmann::json Number(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

struct GdalCloser {
  void operator()(GDALDataset* dataset) const { GDALClose(dataset); }
};

std::vector<float> ReadBand(GDALDataset& dataset, int band_index, const std::string& file) {
  GDALRasterBand* band = dataset.GetRasterBand(band_index);
  const int width = dataset.GetRasterXSize(), height = dataset.GetRasterYSize();
  std::vector<float> values(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  if (band->RasterIO(GF_Read, 0, 0, width, height, values.data(), width, height, GDT_Float32, 0,
                     0) != CE_None)
    throw io::IoError(file + ": cannot read band " + std::to_string(band_index) + ": " +
                      CPLGetLastErrorMsg());
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  if (has_nodata && !std::isnan(nodata)) {
    const float nodata_float = static_cast<float>(nodata);
    for (float& v : values)
      if (v == nodata_float) v = std::numeric_limits<float>::quiet_NaN();
  }
  return values;
}

// Index of the cell of `grid` containing (x, y), or -1 outside.
long CellAt(const DemRaster& grid, double x, double y) {
  const auto& g = grid.geotransform;
  const double col = std::floor((x - g[0]) / g[1]);
  const double row = std::floor((y - g[3]) / g[5]);
  if (!(col >= 0 && row >= 0 && col < grid.width && row < grid.height)) return -1;
  return static_cast<long>(row) * grid.width + static_cast<long>(col);
}

// Centre of cell `k` of `grid`.
std::pair<double, double> CellCentre(const DemRaster& grid, std::size_t k) {
  const auto& g = grid.geotransform;
  const double col = static_cast<double>(k % static_cast<std::size_t>(grid.width)) + 0.5;
  const double row = static_cast<double>(k / static_cast<std::size_t>(grid.width)) + 0.5;
  return {g[0] + col * g[1], g[3] + row * g[5]};
}

std::string CrsName(const DemRaster& raster) {
  if (raster.crs_wkt.empty()) return "no CRS";
  OGRSpatialReference srs;
  if (srs.importFromWkt(raster.crs_wkt.c_str()) != OGRERR_NONE) return "an unreadable CRS";
  const char* name = srs.GetName();
  return name ? "'" + std::string(name) + "'" : "an unnamed CRS";
}

// Linear interpolation between order statistics (numpy's default percentile).
double Percentile(std::vector<double> values, double fraction) {
  std::sort(values.begin(), values.end());
  const double position = fraction * static_cast<double>(values.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(position));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (position - static_cast<double>(lo)) * (values[hi] - values[lo]);
}

}  // namespace

DemRaster ReadDemRaster(const std::filesystem::path& path) {
  static std::once_flag registered;
  std::call_once(registered, [] { GDALAllRegister(); });
  DemRaster raster;
  raster.file = path.string();
  CPLPushErrorHandler(CPLQuietErrorHandler);  // library code never prints; the message is ours
  CPLErrorReset();
  std::unique_ptr<GDALDataset, GdalCloser> dataset(
      GDALDataset::Open(raster.file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  CPLPopErrorHandler();
  if (!dataset) {
    std::error_code error;
    const std::string reason =
        !std::filesystem::exists(path, error)
            ? "no such file"
            : "not a raster GDAL can read (" + std::string(CPLGetLastErrorMsg()) + ")";
    throw io::IoError(raster.file + ": " + reason);
  }
  if (dataset->GetRasterCount() < 1) throw io::IoError(raster.file + ": has no raster band");
  if (dataset->GetGeoTransform(raster.geotransform.data()) != CE_None)
    throw io::IoError(raster.file + ": has no georeferencing (geotransform)");
  const auto& g = raster.geotransform;
  if (g[2] != 0.0 || g[4] != 0.0 || g[1] == 0.0 || g[5] == 0.0)
    throw io::IoError(raster.file + ": rotated or degenerate grids are not supported");
  raster.width = dataset->GetRasterXSize();
  raster.height = dataset->GetRasterYSize();
  if (const char* wkt = dataset->GetProjectionRef(); wkt) raster.crs_wkt = wkt;
  CPLPushErrorHandler(CPLQuietErrorHandler);
  try {
    raster.elevation = ReadBand(*dataset, 1, raster.file);
    if (dataset->GetRasterCount() >= 2) raster.sigma = ReadBand(*dataset, 2, raster.file);
  } catch (...) {
    CPLPopErrorHandler();
    throw;
  }
  CPLPopErrorHandler();
  return raster;
}

bool SameCrs(const DemRaster& a, const DemRaster& b) {
  if (a.crs_wkt.empty() || b.crs_wkt.empty()) return a.crs_wkt.empty() && b.crs_wkt.empty();
  OGRSpatialReference srs_a, srs_b;
  if (srs_a.importFromWkt(a.crs_wkt.c_str()) != OGRERR_NONE ||
      srs_b.importFromWkt(b.crs_wkt.c_str()) != OGRERR_NONE)
    return false;
  return srs_a.IsSame(&srs_b);
}

std::string ToString(DemStatus status) {
  switch (status) {
    case DemStatus::kOk:
      return "ok";
    case DemStatus::kCrsMismatch:
      return "crs_mismatch";
    case DemStatus::kNoReferenceData:
      return "no_reference_data";
    case DemStatus::kNoOverlap:
      return "no_overlap";
  }
  return "ok";
}

DemComparison CompareDems(const DemRaster& dem, const DemRaster& reference) {
  DemComparison c;
  c.rmse_m = c.bias_m = c.p95_abs_m = c.max_abs_m = c.coverage = c.within_2sigma = kNaN;
  if (!SameCrs(dem, reference)) {
    c.status = DemStatus::kCrsMismatch;
    c.message = "different coordinate reference systems: " + dem.file + " has " + CrsName(dem) +
                ", " + reference.file + " has " + CrsName(reference) +
                " (reproject one, e.g. with gdalwarp -t_srs)";
    return c;
  }
  // The comparison grid: the coarser one; the finer raster is averaged into its cells.
  c.on_reference_grid = reference.cell_area_m2() >= dem.cell_area_m2();
  const DemRaster& grid = c.on_reference_grid ? reference : dem;
  const DemRaster& fine = c.on_reference_grid ? dem : reference;
  c.width = grid.width;
  c.height = grid.height;
  c.cell_size_m = std::sqrt(grid.cell_area_m2());
  c.north_row_first = grid.geotransform[5] < 0.0;
  const std::size_t cells = grid.elevation.size();
  std::vector<double> sum(cells, 0.0), sigma_sum(cells, 0.0);
  std::vector<std::size_t> count(cells, 0), sigma_count(cells, 0);
  const bool fine_has_sigma = c.on_reference_grid && !dem.sigma.empty();
  for (std::size_t k = 0; k < fine.elevation.size(); ++k) {
    if (!std::isfinite(fine.elevation[k])) continue;
    const auto [x, y] = CellCentre(fine, k);
    const long cell = CellAt(grid, x, y);
    if (cell < 0) continue;
    sum[cell] += fine.elevation[k];
    ++count[cell];
    if (fine_has_sigma && std::isfinite(fine.sigma[k])) {
      sigma_sum[cell] += fine.sigma[k];
      ++sigma_count[cell];
    }
  }
  // DEM elevation and σ on the comparison grid.
  std::vector<double> dem_value(cells, kNaN), dem_sigma(cells, kNaN), reference_value(cells, kNaN);
  for (std::size_t k = 0; k < cells; ++k) {
    const double averaged = count[k] > 0 ? sum[k] / static_cast<double>(count[k]) : kNaN;
    if (c.on_reference_grid) {
      dem_value[k] = averaged;
      reference_value[k] = reference.elevation[k];
      if (sigma_count[k] > 0) dem_sigma[k] = sigma_sum[k] / static_cast<double>(sigma_count[k]);
    } else {
      dem_value[k] = dem.elevation[k];
      reference_value[k] = averaged;
      if (!dem.sigma.empty()) dem_sigma[k] = dem.sigma[k];
    }
  }

  // Coverage on the reference's own cells.
  std::size_t reference_cells = 0, mapped = 0;
  for (std::size_t k = 0; k < reference.elevation.size(); ++k) {
    if (!std::isfinite(reference.elevation[k])) continue;
    ++reference_cells;
    const auto [x, y] = CellCentre(reference, k);
    const long cell = c.on_reference_grid ? static_cast<long>(k) : CellAt(grid, x, y);
    if (cell >= 0 && std::isfinite(dem_value[cell])) ++mapped;
  }
  if (reference_cells == 0) {
    c.status = DemStatus::kNoReferenceData;
    c.message = reference.file + ": no cell with data";
    return c;
  }
  c.coverage = static_cast<double>(mapped) / static_cast<double>(reference_cells);

  c.error_m.assign(cells, std::numeric_limits<float>::quiet_NaN());
  std::vector<double> abs_errors;
  double sum_errors = 0.0, sum_squares = 0.0;
  std::size_t within = 0;
  for (std::size_t k = 0; k < cells; ++k) {
    if (!std::isfinite(dem_value[k]) || !std::isfinite(reference_value[k])) continue;
    const double e = dem_value[k] - reference_value[k];
    c.error_m[k] = static_cast<float>(e);
    abs_errors.push_back(std::abs(e));
    sum_errors += e;
    sum_squares += e * e;
    if (std::isfinite(dem_sigma[k])) {
      ++c.sigma_cells;
      if (std::abs(e) <= 2.0 * dem_sigma[k]) ++within;
    }
  }
  c.cells = abs_errors.size();
  if (c.cells == 0) {
    c.status = DemStatus::kNoOverlap;
    c.message = "no cell where both " + dem.file + " and " + reference.file + " have data";
    return c;
  }
  const double n = static_cast<double>(c.cells);
  c.rmse_m = std::sqrt(sum_squares / n);
  c.bias_m = sum_errors / n;
  c.p95_abs_m = Percentile(abs_errors, 0.95);
  c.max_abs_m = *std::max_element(abs_errors.begin(), abs_errors.end());
  if (c.sigma_cells > 0)
    c.within_2sigma = static_cast<double>(within) / static_cast<double>(c.sigma_cells);
  return c;
}

nlohmann::json ToJson(const DemComparison& c) {
  nlohmann::json out;
  out["status"] = ToString(c.status);
  if (!c.message.empty()) out["message"] = c.message;
  out["rmse_m"] = Number(c.rmse_m);
  out["bias_m"] = Number(c.bias_m);
  out["p95_abs_m"] = Number(c.p95_abs_m);
  out["max_abs_m"] = Number(c.max_abs_m);
  out["coverage"] = Number(c.coverage);
  out["within_2sigma"] = Number(c.within_2sigma);
  out["cells"] = c.cells;
  out["sigma_cells"] = c.sigma_cells;
  out["grid"] = c.on_reference_grid ? "reference" : "dem";
  out["cell_size_m"] = c.cell_size_m;
  return out;
}

}  // namespace rovermap::eval
