#pragma once
// The published cells of an ElevationMap as north-up rasters: what dem.tif and dem.png are made
// of. Taken from the map in one pass, so that the files can be encoded on another thread while
// the map goes on changing (`rovermap serve` publishes in the background).

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "dem/ElevationMap.hpp"

namespace rovermap::io {

struct DemLayers {
  /// Grid cells covered, inclusive: pixel (col, row) is cell (min.x + col, max.y - row), row 0
  /// north. A map without cells gives the one pixel of cell (0, 0).
  dem::CellIndex min{0, 0};
  dem::CellIndex max{0, 0};
  int width = 1;                   ///< [px] columns, west to east
  int height = 1;                  ///< [px] rows, north to south
  double cell_size_m = 0.0;        ///< [m] grid cell edge
  double grid_rotation_rad = 0.0;  ///< [rad] the map's grid rotation (world to grid)
  /// Row-major layers; a cell that is not published has NaN elevation and σ and count 0.
  std::vector<float> elevation_m;
  std::vector<float> stddev_m;
  std::vector<float> count;
  /// Per pixel, the frame of the first point of the cell's estimate (CellValue::first_frame); 0
  /// where not published. What a solved pose graph moves the cell with when the DEM is not
  /// fused again (mapper/DemWarp): the first frame rather than the middle or the last one, as a
  /// cell a loop's two passes share holds the first pass's place (measured: docs/serve.md).
  std::vector<std::uint32_t> frame;
  std::size_t valid_cells = 0;  ///< published cells [count]

  /// World (x, y) [m] in the grid frame [m] (ElevationMap::WorldToGrid).
  Eigen::Vector2d WorldToGrid(double x_m, double y_m) const;
};

/// Rasterises `map`'s published cells (ElevationMap::Published) over its cell bounds.
/// @throw IoError if the raster would exceed 2^31 pixels.
DemLayers RasteriseDem(const dem::ElevationMap& map);

}  // namespace rovermap::io
