#pragma once
// Cell-by-cell difference of two DEM rasters on the same grid (bands 1-3), for tests that
// expect them equal up to Float32 storage.

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "io/GeoTiff.hpp"

namespace rovermap::testing {

struct DemDifference {
  std::size_t cells = 0;              ///< cells with an elevation in `a`
  std::size_t nan_mismatches = 0;     ///< cells with an elevation in one raster only
  std::size_t count_mismatches = 0;   ///< cells whose band 3 differs
  double worst_z_m = 0.0;             ///< [m] largest |z_a − z_b|
  double worst_sigma_relative = 0.0;  ///< largest |σ_a − σ_b| / σ_a
};

/// `a` against `b`, cell by cell (same width and height: the caller checks).
inline DemDifference CompareDemCells(const io::DemRaster& a, const io::DemRaster& b) {
  DemDifference d;
  for (std::size_t c = 0; c < a.elevation_m.size() && c < b.elevation_m.size(); ++c) {
    if (std::isnan(a.elevation_m[c]) != std::isnan(b.elevation_m[c])) ++d.nan_mismatches;
    if (std::isnan(a.elevation_m[c]) || std::isnan(b.elevation_m[c])) continue;
    ++d.cells;
    d.worst_z_m =
        std::max(d.worst_z_m, std::abs(static_cast<double>(a.elevation_m[c]) - b.elevation_m[c]));
    d.worst_sigma_relative =
        std::max(d.worst_sigma_relative,
                 std::abs(static_cast<double>(a.stddev_m[c]) - b.stddev_m[c]) / a.stddev_m[c]);
    if (a.count[c] != b.count[c]) ++d.count_mismatches;
  }
  return d;
}

}  // namespace rovermap::testing
