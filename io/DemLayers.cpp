#include "io/DemLayers.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "io/IoError.hpp"

namespace rovermap::io {

Eigen::Vector2d DemLayers::WorldToGrid(double x_m, double y_m) const {
  // The same rotation as ElevationMap::WorldToGrid (its cos_ and sin_ of grid_rotation_rad).
  const double c = std::cos(grid_rotation_rad);
  const double s = std::sin(grid_rotation_rad);
  return {c * x_m - s * y_m, s * x_m + c * y_m};
}

DemLayers RasteriseDem(const dem::ElevationMap& map) {
  DemLayers layers;
  layers.cell_size_m = map.options().cell_size_m;
  layers.grid_rotation_rad = map.options().grid_rotation_rad;
  if (!map.bounds().Empty()) {
    layers.min = map.bounds().Min();
    layers.max = map.bounds().Max();
  }
  const dem::CellIndex min = layers.min;
  const dem::CellIndex max = layers.max;
  const std::int64_t width64 = max.x - min.x + 1;
  const std::int64_t height64 = max.y - min.y + 1;
  if (width64 * height64 > (std::int64_t{1} << 31) || width64 > (1 << 30) || height64 > (1 << 30)) {
    throw IoError("raster of " + std::to_string(width64) + " x " + std::to_string(height64) +
                  " cells is too large");
  }
  layers.width = static_cast<int>(width64);
  layers.height = static_cast<int>(height64);
  const auto pixels = static_cast<std::size_t>(width64) * static_cast<std::size_t>(height64);
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  layers.elevation_m.assign(pixels, kNaN);
  layers.stddev_m.assign(pixels, kNaN);
  layers.count.assign(pixels, 0.0f);
  layers.frame.assign(pixels, 0);

  // Tile rows straight into the raster.
  const dem::GridIndex& index = map.index();
  const int n = index.geometry().tile_cells;
  for (const dem::TileIndex t : map.TileIndices()) {
    const dem::Tile* tile = map.FindTile(t);
    if (tile == nullptr || tile->filled == 0) continue;
    for (int ly = 0; ly < n; ++ly) {
      const dem::CellIndex row_start = index.TileLocalToCell(t, {0, ly});
      if (row_start.y < min.y || row_start.y > max.y) continue;
      const auto row = static_cast<std::size_t>(max.y - row_start.y);
      for (int lx = 0; lx < n; ++lx) {
        const dem::CellValue& v = tile->cells[index.LinearIndex({lx, ly})].value;
        const std::int64_t cx = row_start.x + lx;
        if (v.count == 0 || cx < min.x || cx > max.x || !map.Published({cx, row_start.y}, v))
          continue;
        const std::size_t o =
            row * static_cast<std::size_t>(width64) + static_cast<std::size_t>(cx - min.x);
        layers.elevation_m[o] = v.elevation_m;
        layers.stddev_m[o] = std::sqrt(std::max(0.0f, v.variance_m2));
        layers.count[o] = static_cast<float>(v.count);
        layers.frame[o] = v.first_frame;
        ++layers.valid_cells;
      }
    }
  }
  return layers;
}

}  // namespace rovermap::io
