#include "terrain/TerrainCache.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "terrain/TerrainTiles.hpp"

namespace rovermap::terrain {
namespace {

bool SameOptions(const TerrainOptions& a, const TerrainOptions& b) {
  return a.footprint_m == b.footprint_m && a.max_slope_deg == b.max_slope_deg &&
         a.max_step_m == b.max_step_m && a.max_roughness_m == b.max_roughness_m &&
         a.min_coverage == b.min_coverage && a.uncertainty_sigmas == b.uncertainty_sigmas &&
         a.tile_cells == b.tile_cells;
}

// A cell as the layers read it: no height, or its height's and σ's bits.
struct Cell {
  bool known = false;
  std::uint32_t z = 0, s = 0;
  bool operator==(const Cell& o) const {
    return known == o.known && (!known || (z == o.z && s == o.s));
  }
};

Cell Bits(float z, float s) {
  Cell cell;
  if (!std::isfinite(z)) return cell;
  cell.known = true;
  std::memcpy(&cell.z, &z, sizeof z);
  std::memcpy(&cell.s, &s, sizeof s);
  return cell;
}

// A grid in global cell coordinates: a cell outside it has no height.
struct Placed {
  std::int64_t row0, col0;
  int rows, cols;
  const float* z;
  const float* s;  // nullptr: no σ
  Cell At(std::int64_t row, std::int64_t col) const {
    const std::int64_t r = row - row0, c = col - col0;
    if (r < 0 || r >= rows || c < 0 || c >= cols) return {};
    const std::size_t i =
        static_cast<std::size_t>(r) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(c);
    return Bits(z[i], s != nullptr ? s[i] : 0.0f);
  }
  bool Holds(std::int64_t row_begin, std::int64_t row_end, std::int64_t col_begin,
             std::int64_t col_end) const {
    return row_begin >= row0 && row_end <= row0 + rows && col_begin >= col0 &&
           col_end <= col0 + cols;
  }
};

// Whether the cells [row_begin, row_end) × [col_begin, col_end) read the same in both grids:
// rows held whole by both are compared as bytes (a NaN with another payload counts as a
// change: a tile computed for nothing, never one missed), the others cell by cell.
bool SameCells(const Placed& a, const Placed& b, std::int64_t row_begin, std::int64_t row_end,
               std::int64_t col_begin, std::int64_t col_end) {
  const std::size_t n = static_cast<std::size_t>(col_end - col_begin);
  for (std::int64_t r = row_begin; r < row_end; ++r) {
    if (a.Holds(r, r + 1, col_begin, col_end) && b.Holds(r, r + 1, col_begin, col_end)) {
      const auto at = [&](const Placed& p) {
        return static_cast<std::size_t>(r - p.row0) * static_cast<std::size_t>(p.cols) +
               static_cast<std::size_t>(col_begin - p.col0);
      };
      if (std::memcmp(a.z + at(a), b.z + at(b), n * sizeof(float)) != 0) return false;
      if (a.s != nullptr && std::memcmp(a.s + at(a), b.s + at(b), n * sizeof(float)) != 0)
        return false;
      continue;
    }
    for (std::int64_t c = col_begin; c < col_end; ++c) {
      if (!(a.At(r, c) == b.At(r, c))) return false;
    }
  }
  return true;
}

}  // namespace

void TerrainCache::Clear() {
  valid_ = false;
  elevation_m_ = {};
  stddev_m_ = {};
  layers_ = TerrainLayers();
  spare_ = TerrainLayers();
}

const TerrainLayers& TerrainCache::Update(const GridView& grid, const TerrainOptions& options) {
  const TileLayout layout = LayoutFor(grid, options);  // throws before anything changes
  const bool reusable = valid_ && SameOptions(options, options_) && grid.cell_x_m == cell_x_m_ &&
                        grid.cell_y_m == cell_y_m_ &&
                        (grid.stddev_m != nullptr) == !stddev_m_.empty();
  // The same grid as last time: the layers are updated in place, tile by tile. Otherwise into
  // the spare set (the one before last: its pages are already the process's).
  const bool in_place = reusable && grid.origin_col == origin_col_ &&
                        grid.origin_row == origin_row_ && grid.width == width_ &&
                        grid.height == height_;
  TerrainLayers& out = in_place ? layers_ : spare_;
  if (!in_place) {
    const std::size_t cells = static_cast<std::size_t>(grid.width) * grid.height;
    for (const auto layer : kLayerFields) {
      (out.*layer).assign(cells, std::numeric_limits<float>::quiet_NaN());
    }
    out.width = grid.width;
    out.height = grid.height;
    out.has_sigma = grid.stddev_m != nullptr;
    out.footprint_cols = 2 * layout.hx + 1;
    out.footprint_rows = 2 * layout.hy + 1;
  }
  const Placed now{grid.origin_row, grid.origin_col,  grid.height,
                   grid.width,      grid.elevation_m, grid.stddev_m};
  const Placed before{
      origin_row_, origin_col_,         height_,
      width_,      elevation_m_.data(), stddev_m_.empty() ? nullptr : stddev_m_.data()};

  const int tiles_x = static_cast<int>(layout.cols.size());
  const int tiles = static_cast<int>(layout.rows.size()) * tiles_x;
  std::vector<char> computed(static_cast<std::size_t>(tiles), 0);
#pragma omp parallel for schedule(dynamic)
  for (int t = 0; t < tiles; ++t) {
    const TileSpan& rows = layout.rows[t / tiles_x];
    const TileSpan& cols = layout.cols[t % tiles_x];
    // Global rows and columns of the tile's cells in this grid, and of their footprints.
    const std::int64_t r0 = grid.origin_row + rows.begin, r1 = grid.origin_row + rows.end;
    const std::int64_t c0 = grid.origin_col + cols.begin, c1 = grid.origin_col + cols.end;
    if (reusable && before.Holds(r0, r1, c0, c1) &&
        SameCells(now, before, r0 - layout.hy, r1 + layout.hy, c0 - layout.hx, c1 + layout.hx)) {
      if (in_place) continue;
      for (const auto layer : kLayerFields) {
        for (std::int64_t r = r0; r < r1; ++r) {
          const std::size_t src = static_cast<std::size_t>(r - origin_row_) * width_ +
                                  static_cast<std::size_t>(c0 - origin_col_);
          const std::size_t dst = static_cast<std::size_t>(r - grid.origin_row) * grid.width +
                                  static_cast<std::size_t>(cols.begin);
          std::copy_n((layers_.*layer).data() + src, c1 - c0, (out.*layer).data() + dst);
        }
      }
      continue;
    }
    if (in_place) {  // the tile's cells as EmptyLayers leaves them: ComputeTile skips unknowns
      for (const auto layer : kLayerFields) {
        for (int r = rows.begin; r < rows.end; ++r) {
          std::fill_n((out.*layer).data() + static_cast<std::size_t>(r) * grid.width + cols.begin,
                      cols.end - cols.begin, std::numeric_limits<float>::quiet_NaN());
        }
      }
    }
    ComputeTile(grid, options, layout, rows, cols, &out);
    computed[static_cast<std::size_t>(t)] = 1;
  }
  CountLayers(options, &out);

  tiles_ = static_cast<std::size_t>(tiles);
  tiles_computed_ = static_cast<std::size_t>(std::count(computed.begin(), computed.end(), 1));
  const std::size_t cells = static_cast<std::size_t>(grid.width) * grid.height;
  elevation_m_.assign(grid.elevation_m, grid.elevation_m + cells);
  if (grid.stddev_m != nullptr) {
    stddev_m_.assign(grid.stddev_m, grid.stddev_m + cells);
  } else {
    stddev_m_.clear();
  }
  options_ = options;
  cell_x_m_ = grid.cell_x_m;
  cell_y_m_ = grid.cell_y_m;
  width_ = grid.width;
  height_ = grid.height;
  origin_col_ = grid.origin_col;
  origin_row_ = grid.origin_row;
  if (!in_place) std::swap(layers_, spare_);
  valid_ = true;
  return layers_;
}

}  // namespace rovermap::terrain
