#pragma once
// Slope, roughness, step height and traversability over the rover's footprint, from a DEM's
// heights and σ (docs/terrain.md). A square footprint lets every cell's plane fit come from
// prefix sums of the weighted moments: the same cost whatever the footprint's size.

#include <cstddef>
#include <cstdint>
#include <functional>
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
  /// Where cell (0, 0) lies in the map's own cell grid [cells]: layers are computed in tiles of
  /// `terrain.tile_cells` aligned to that grid, so that a map which grows keeps its tiles (and
  /// their values) where they were (TerrainCache). 0 for a DEM on its own.
  std::int64_t origin_col = 0;  ///< increasing east
  std::int64_t origin_row = 0;  ///< increasing south
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

/// A grid's size, for ComputeTerrainByRows.
struct GridShape {
  int width = 0;
  int height = 0;
  double cell_x_m = 0.0;
  double cell_y_m = 0.0;
  bool has_sigma = false;
};
/// Fills `elevation_m` (and `stddev_m` when the grid has σ) with grid rows [row0, row0 + rows),
/// every column, row-major, NaN for no height.
using ReadRows = std::function<void(int row0, int rows, std::vector<float>* elevation_m,
                                    std::vector<float>* stddev_m)>;
/// Receives the layers of grid rows [row0, row0 + layers.height), every column.
using WriteRows = std::function<void(int row0, const TerrainLayers& layers)>;

/// ComputeTerrain for a grid too large to hold: one row of tiles at a time, read with the
/// footprint's halo above and below, so memory is bounded by the grid's width × a tile's
/// height. The layers written are ComputeTerrain's on the whole grid, to the bit.
/// @return the counts and footprint (the layer vectors empty).
/// @throw TerrainError as ComputeTerrain; what `read` and `write` throw.
TerrainLayers ComputeTerrainByRows(const GridShape& shape, const TerrainOptions& options,
                                   const ReadRows& read, const WriteRows& write);

}  // namespace rovermap::terrain
