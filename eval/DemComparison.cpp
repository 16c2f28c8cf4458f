#include "eval/DemComparison.hpp"

#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace rovermap::eval {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

nlohmann::json Number(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

double CellArea(const io::DemRaster& grid) {
  return std::abs(grid.geotransform[1] * grid.geotransform[5]);
}

// Index of the cell of `grid` containing (x, y), or -1 outside.
long CellAt(const io::DemRaster& grid, double x, double y) {
  const auto& g = grid.geotransform;
  const double col = std::floor((x - g[0]) / g[1]);
  const double row = std::floor((y - g[3]) / g[5]);
  if (!(col >= 0 && row >= 0 && col < grid.width && row < grid.height)) return -1;
  return static_cast<long>(row) * grid.width + static_cast<long>(col);
}

// Centre of cell `k` of `grid`.
std::pair<double, double> CellCentre(const io::DemRaster& grid, std::size_t k) {
  const auto& g = grid.geotransform;
  const double col = static_cast<double>(k % static_cast<std::size_t>(grid.width)) + 0.5;
  const double row = static_cast<double>(k / static_cast<std::size_t>(grid.width)) + 0.5;
  return {g[0] + col * g[1], g[3] + row * g[5]};
}

std::string CrsName(const io::DemRaster& raster) {
  if (raster.wkt.empty()) return "no CRS";
  OGRSpatialReference srs;
  if (srs.importFromWkt(raster.wkt.c_str()) != OGRERR_NONE) return "an unreadable CRS";
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

bool SameCrs(const io::DemRaster& a, const io::DemRaster& b) {
  if (a.wkt.empty() || b.wkt.empty()) return a.wkt.empty() && b.wkt.empty();
  OGRSpatialReference srs_a, srs_b;
  if (srs_a.importFromWkt(a.wkt.c_str()) != OGRERR_NONE ||
      srs_b.importFromWkt(b.wkt.c_str()) != OGRERR_NONE)
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

DemComparison CompareDems(const io::DemRaster& dem, const io::DemRaster& reference) {
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
  c.on_reference_grid = CellArea(reference) >= CellArea(dem);
  const io::DemRaster& grid = c.on_reference_grid ? reference : dem;
  const io::DemRaster& fine = c.on_reference_grid ? dem : reference;
  c.width = grid.width;
  c.height = grid.height;
  c.cell_size_m = std::sqrt(CellArea(grid));
  c.north_row_first = grid.geotransform[5] < 0.0;
  const std::size_t cells = grid.elevation_m.size();
  std::vector<double> sum(cells, 0.0), sigma_sum(cells, 0.0);
  std::vector<std::size_t> count(cells, 0), sigma_count(cells, 0);
  const bool fine_has_sigma = c.on_reference_grid && !dem.stddev_m.empty();
  for (std::size_t k = 0; k < fine.elevation_m.size(); ++k) {
    if (!std::isfinite(fine.elevation_m[k])) continue;
    const auto [x, y] = CellCentre(fine, k);
    const long cell = CellAt(grid, x, y);
    if (cell < 0) continue;
    sum[cell] += fine.elevation_m[k];
    ++count[cell];
    if (fine_has_sigma && std::isfinite(fine.stddev_m[k])) {
      sigma_sum[cell] += fine.stddev_m[k];
      ++sigma_count[cell];
    }
  }
  // DEM elevation and σ on the comparison grid.
  std::vector<double> dem_value(cells, kNaN), dem_sigma(cells, kNaN), reference_value(cells, kNaN);
  for (std::size_t k = 0; k < cells; ++k) {
    const double averaged = count[k] > 0 ? sum[k] / static_cast<double>(count[k]) : kNaN;
    if (c.on_reference_grid) {
      dem_value[k] = averaged;
      reference_value[k] = reference.elevation_m[k];
      if (sigma_count[k] > 0) dem_sigma[k] = sigma_sum[k] / static_cast<double>(sigma_count[k]);
    } else {
      dem_value[k] = dem.elevation_m[k];
      reference_value[k] = averaged;
      if (!dem.stddev_m.empty()) dem_sigma[k] = dem.stddev_m[k];
    }
  }

  // Coverage on the reference's own cells.
  std::size_t reference_cells = 0, mapped = 0;
  for (std::size_t k = 0; k < reference.elevation_m.size(); ++k) {
    if (!std::isfinite(reference.elevation_m[k])) continue;
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

  c.cell_x_m = std::abs(grid.geotransform[1]);
  c.cell_y_m = std::abs(grid.geotransform[5]);
  c.dem_m.assign(dem_value.begin(), dem_value.end());
  c.dem_sigma_m.assign(dem_sigma.begin(), dem_sigma.end());
  c.reference_m.assign(reference_value.begin(), reference_value.end());
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

TerrainAgreement CompareTerrain(const DemComparison& c, const terrain::TerrainOptions& options) {
  TerrainAgreement a;
  if (c.status != DemStatus::kOk) {
    a.reason = "the DEMs were not compared";
    return a;
  }
  // The DEM with its σ where every height has one; the reference as the truth.
  bool dem_sigma = c.dem_m.size() == c.dem_sigma_m.size();
  for (std::size_t k = 0; dem_sigma && k < c.dem_m.size(); ++k)
    dem_sigma = std::isnan(c.dem_m[k]) || std::isfinite(c.dem_sigma_m[k]);
  const std::vector<float> reference_sigma(c.reference_m.size(), 0.001f);
  terrain::TerrainLayers got, want;
  try {
    got = terrain::ComputeTerrain({c.width, c.height, c.cell_x_m, c.cell_y_m, c.dem_m.data(),
                                   dem_sigma ? c.dem_sigma_m.data() : nullptr},
                                  options);
    want = terrain::ComputeTerrain(
        {c.width, c.height, c.cell_x_m, c.cell_y_m, c.reference_m.data(), reference_sigma.data()},
        options);
  } catch (const terrain::TerrainError& e) {
    a.reason = e.what();
    return a;
  }
  a.computed = true;
  for (std::size_t k = 0; k < got.traversability.size(); ++k) {
    if (std::isnan(got.traversability[k]) || std::isnan(want.traversability[k])) continue;
    ++a.cells;
    if (want.traversability[k] == 0.0f) {
      ++a.true_hazard;
      a.found += got.traversability[k] == 0.0f;
    } else {
      ++a.true_benign;
      a.marked_hazard += got.traversability[k] == 0.0f && got.uncertain[k] == 0.0f;
      a.marked_uncertain += got.uncertain[k] > 0.0f;
    }
  }
  return a;
}

nlohmann::json ToJson(const TerrainAgreement& a) {
  nlohmann::json out;
  out["computed"] = a.computed;
  if (!a.computed) {
    out["reason"] = a.reason;
    return out;
  }
  const auto fraction = [](std::size_t part, std::size_t whole) {
    return whole > 0 ? Number(static_cast<double>(part) / static_cast<double>(whole)) : nullptr;
  };
  out["cells"] = a.cells;
  out["true_hazard_cells"] = a.true_hazard;
  out["found"] = a.found;
  out["found_fraction"] = fraction(a.found, a.true_hazard);
  out["true_benign_cells"] = a.true_benign;
  out["marked_hazard"] = a.marked_hazard;
  out["marked_hazard_fraction"] = fraction(a.marked_hazard, a.true_benign);
  out["marked_uncertain"] = a.marked_uncertain;
  out["marked_uncertain_fraction"] = fraction(a.marked_uncertain, a.true_benign);
  return out;
}

}  // namespace rovermap::eval
