#pragma once
// Slope, roughness, step height and traversability over the rover's footprint, from a DEM's
// heights and σ (docs/terrain.md). A square footprint lets every cell's plane fit come from
// prefix sums of the weighted moments: the same cost whatever the footprint's size.

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "terrain/TerrainOptions.hpp"

namespace rovermap::terrain {

/// A north-up DEM raster: row-major, row 0 north, NaN = no height.
struct GridView {
  int width = 0;          ///< [cells] columns, west to east
  int height = 0;         ///< [cells] rows, north to south
  double cell_x_m = 0.0;  ///< [m] column spacing
  double cell_y_m = 0.0;  ///< [m] row spacing
  const float* elevation_m = nullptr;
  /// Each height's σ [m]; nullptr when the DEM has none (the footprint's residual scatter
  /// then stands for the heights' noise).
  const float* stddev_m = nullptr;
};

/// Thrown for options or a grid the layers cannot be computed for.
class TerrainError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// One value per DEM cell, on the DEM's grid; NaN where unknown (the footprint holds fewer
/// heights than options.min_coverage asks, or too few to fit a plane).
struct TerrainLayers {
  int width = 0;
  int height = 0;
  std::vector<float> slope_deg;        ///< of the footprint's least-squares plane
  std::vector<float> slope_sigma_deg;  ///< its 1σ, from the heights' σ
  std::vector<float> roughness_m;      ///< RMS residual of that plane
  std::vector<float> step_m;           ///< highest minus lowest height within the footprint
  /// 0 = hazard … 1 = benign: 1 − the largest of (value + kσ) / limit over slope, step and
  /// roughness, clipped to [0, 1] (k = options.uncertainty_sigmas).
  std::vector<float> traversability;
  /// 1 where a limit lies within kσ of its layer's value (the decision is not sure), else 0.
  std::vector<float> uncertain;
  bool has_sigma = false;           ///< the heights' σ weighted the fits
  std::size_t known = 0;            ///< cells with layers [count]
  std::size_t hazard = 0;           ///< known cells beyond a limit (value ≥ limit) [count]
  std::size_t uncertain_cells = 0;  ///< known cells marked uncertain [count]
  std::size_t benign = 0;           ///< traversability > 0 [count]
  int footprint_cols = 0;           ///< [cells] footprint side along a row
  int footprint_rows = 0;           ///< [cells] footprint side along a column
};

/// Checks `options`; empty when usable, else what is wrong, naming the terrain.* key.
std::string CheckOptions(const TerrainOptions& options);

/// The layers of `grid`.
/// @throw TerrainError if the options are not usable, the grid's spacing is not positive, or
///        the footprint is smaller than two cells or larger than the grid.
TerrainLayers ComputeTerrain(const GridView& grid, const TerrainOptions& options);

}  // namespace rovermap::terrain
