#pragma once
// The tiles ComputeTerrain and TerrainCache share: the footprint's half-sizes, the tiles'
// spans (aligned to the map's global cell grid) and the work on one tile. Internal to terrain/.

#include <array>
#include <cstdint>
#include <vector>

#include "terrain/TerrainLayers.hpp"

namespace rovermap::terrain {

/// Rows or columns [begin, end) of the grid, the tile's global index along that axis.
struct TileSpan {
  int begin = 0;
  int end = 0;
  std::int64_t index = 0;
};

/// The six layers of TerrainLayers, in terrain.tif's band order.
inline constexpr std::array<std::vector<float> TerrainLayers::*, 6> kLayerFields = {
    &TerrainLayers::slope_deg, &TerrainLayers::slope_sigma_deg, &TerrainLayers::roughness_m,
    &TerrainLayers::step_m,    &TerrainLayers::traversability,  &TerrainLayers::uncertain};

struct TileLayout {
  int hx = 0;                                   ///< [cells] footprint half-width along a row
  int hy = 0;                                   ///< [cells] footprint half-height along a column
  int tile = 0;                                 ///< [cells] a whole tile's side
  std::int64_t origin_row = 0, origin_col = 0;  ///< the grid's (GridView::origin_*)
  std::vector<TileSpan> rows, cols;             ///< each tile's part within the grid
};

/// @throw TerrainError as ComputeTerrain.
TileLayout LayoutFor(const GridView& grid, const TerrainOptions& options);
/// Layers of `grid`'s size, all NaN.
TerrainLayers EmptyLayers(const GridView& grid, const TileLayout& layout);
/// Writes the layers of the tile rows × cols into `out`; they depend on the heights within the
/// footprint of the tile's cells alone.
void ComputeTile(const GridView& grid, const TerrainOptions& options, const TileLayout& layout,
                 const TileSpan& rows, const TileSpan& cols, TerrainLayers* out);
/// Sets out's counts from its layers.
void CountLayers(const TerrainOptions& options, TerrainLayers* out);

}  // namespace rovermap::terrain
