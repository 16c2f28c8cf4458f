#pragma once
// The layers of a map published again and again (serve): a tile is computed anew only when the
// heights or σ within its cells' footprints changed since the last publication; the others
// are copied. The result is ComputeTerrain's, bit for bit (docs/terrain.md, "In serve").

#include <cstddef>
#include <cstdint>
#include <vector>

#include "terrain/TerrainLayers.hpp"
#include "terrain/TerrainOptions.hpp"

namespace rovermap::terrain {

class TerrainCache {
 public:
  /// The layers of `grid`, equal to ComputeTerrain(grid, options). `grid.origin_*` must place
  /// it in the same global cell grid as the grids before it (a DEM's cell indices).
  /// @throw TerrainError as ComputeTerrain; the cache then stays as it was.
  const TerrainLayers& Update(const GridView& grid, const TerrainOptions& options);

  std::size_t tiles() const { return tiles_; }                    ///< of the last Update
  std::size_t tiles_computed() const { return tiles_computed_; }  ///< of those, computed anew
  /// Forgets the last grid: the next Update computes every tile.
  void Clear();

 private:
  bool valid_ = false;
  TerrainOptions options_;
  double cell_x_m_ = 0.0, cell_y_m_ = 0.0;
  int width_ = 0, height_ = 0;
  std::int64_t origin_col_ = 0, origin_row_ = 0;
  std::vector<float> elevation_m_, stddev_m_;  // the last grid's (empty σ: it had none)
  TerrainLayers layers_;
  TerrainLayers spare_;  // the layers before last, for their memory
  std::size_t tiles_ = 0, tiles_computed_ = 0;
};

}  // namespace rovermap::terrain
