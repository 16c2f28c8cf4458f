#pragma once
// DEM accuracy against a reference terrain (`rovermap eval --dem A.tif --reference B.tif`,
// docs/design.md §8): both grids compared where both have data, on the coarser of the two grids.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/GeoTiff.hpp"  // DemRaster, ReadDemGeoTiff: band 1 elevation, band 2 its σ
#include "terrain/TerrainLayers.hpp"

namespace rovermap::eval {

/// True if both have no CRS, or both have one and GDAL finds them the same.
bool SameCrs(const io::DemRaster& a, const io::DemRaster& b);

enum class DemStatus { kOk, kCrsMismatch, kNoReferenceData, kNoOverlap };
std::string ToString(DemStatus status);

struct DemComparison {
  DemStatus status = DemStatus::kOk;
  std::string message;     ///< why the status is not kOk
  double rmse_m = 0.0;     ///< sqrt(mean(e²)), e = DEM − reference [m]
  double bias_m = 0.0;     ///< mean(e) [m]: positive = the DEM lies above the reference
  double p95_abs_m = 0.0;  ///< 95th percentile of |e| (linear between order statistics) [m]
  double max_abs_m = 0.0;  ///< [m]
  /// Fraction of the reference's cells with data (on its own grid) whose centre falls in a
  /// comparison cell where the DEM has data.
  double coverage = 0.0;
  /// Fraction of the compared cells with a stated σ (band 2) where |e| <= 2σ; NaN without σ.
  double within_2sigma = 0.0;
  std::size_t cells = 0;        ///< compared cells
  std::size_t sigma_cells = 0;  ///< compared cells with a finite σ
  /// The comparison grid: the coarser raster's (the reference's when equal), the finer one
  /// averaged into it (mean of its cells whose centres fall in each cell, σ likewise).
  bool on_reference_grid = true;
  double cell_size_m = 0.0;  ///< sqrt of the comparison cell area
  int width = 0;
  int height = 0;
  bool north_row_first = true;  ///< row 0 is the northern edge (geotransform[5] < 0)
  std::vector<float> error_m;   ///< e per comparison cell, row-major, NaN where not compared
  /// Both on the comparison grid (row-major, NaN where no data): the DEM's heights and σ and the
  /// reference's heights, for the terrain layers' agreement; the grid's column and row spacing.
  std::vector<float> dem_m, dem_sigma_m, reference_m;
  double cell_x_m = 0.0, cell_y_m = 0.0;
};

/// How the terrain layers of the DEM (docs/terrain.md) agree with those of the reference,
/// taken as the truth (1 mm σ), on the comparison grid, over the cells where both have layers.
struct TerrainAgreement {
  bool computed = false;
  std::string reason;                ///< why not (a footprint larger than the grid, ...)
  std::size_t cells = 0;             ///< cells with layers in both
  std::size_t true_hazard = 0;       ///< the reference's traversability 0
  std::size_t found = 0;             ///< of those, the DEM's 0 too (a hazard or uncertain)
  std::size_t true_benign = 0;       ///< the reference's traversability > 0
  std::size_t marked_hazard = 0;     ///< of those, the DEM's a hazard beyond doubt
  std::size_t marked_uncertain = 0;  ///< of those, the DEM's uncertain
};

/// The layers of both grids of `comparison` (status kOk) with `options`. Never throws.
TerrainAgreement CompareTerrain(const DemComparison& comparison,
                                const terrain::TerrainOptions& options);
nlohmann::json ToJson(const TerrainAgreement& agreement);

/// Compares `dem` with `reference`. Never throws; a CRS mismatch, a reference without data or no
/// cell with both gives that status and a message naming both files.
DemComparison CompareDems(const io::DemRaster& dem, const io::DemRaster& reference);

/// rmse_m, bias_m, p95_abs_m, coverage, within_2sigma, cells (docs/design.md §8) and the rest;
/// NaN → null.
nlohmann::json ToJson(const DemComparison& comparison);

}  // namespace rovermap::eval
