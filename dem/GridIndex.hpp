#pragma once
// Indexing of the sparse tiled elevation grid: world (x east, y north) [m] -> global cell ->
// (tile, local cell). The grid has no fixed extent: any cell index in ±kMaxCellIndex is valid
// and tiles are allocated by the grid store on first touch.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>

namespace rovermap::dem {

/// Size of the cells and tiles. Cell (i, j) covers [i·s, (i+1)·s) × [j·s, (j+1)·s), s =
/// cell_size_m; tile (u, v) holds cells [u·n, (u+1)·n) × [v·n, (v+1)·n), n = tile_cells.
struct GridGeometry {
  double cell_size_m = 0.05;  ///< edge of a square cell [m]
  int tile_cells = 256;       ///< cells along a tile edge [count]; a tile has tile_cells² cells
};

/// Checks a geometry before use.
/// @throw std::invalid_argument naming the field ("cell_size_m: must be finite and > 0 (got
///        0)") if cell_size_m is not finite or <= 0, or tile_cells < 1.
void Validate(const GridGeometry& geometry);

/// Largest |cell index| on either axis: far beyond any map, small enough that every index and
/// its neighbours are exact as doubles and tile·tile_cells + local never overflows.
inline constexpr std::int64_t kMaxCellIndex = std::int64_t{1} << 52;

/// Global cell index: floor(x / cell_size_m), floor(y / cell_size_m).
struct CellIndex {
  std::int64_t x = 0;
  std::int64_t y = 0;
};

/// Tile index: floor(cell / tile_cells) per axis.
struct TileIndex {
  std::int64_t x = 0;
  std::int64_t y = 0;
};

/// Cell within its tile, 0 <= x, y < tile_cells (also for negative cells).
struct LocalIndex {
  int x = 0;
  int y = 0;
};

inline bool operator==(CellIndex a, CellIndex b) { return a.x == b.x && a.y == b.y; }
inline bool operator!=(CellIndex a, CellIndex b) { return !(a == b); }
inline bool operator==(TileIndex a, TileIndex b) { return a.x == b.x && a.y == b.y; }
inline bool operator!=(TileIndex a, TileIndex b) { return !(a == b); }
inline bool operator==(LocalIndex a, LocalIndex b) { return a.x == b.x && a.y == b.y; }
inline bool operator!=(LocalIndex a, LocalIndex b) { return !(a == b); }

/// Hash for std::unordered_map<TileIndex, T, TileIndexHash>. Distinct for all tiles with |x|,
/// |y| < 2^31 (a bijective mix of the packed 32-bit halves), so neighbouring tiles never share
/// a hash; the high bits are folded in beyond that. Never fails.
struct TileIndexHash {
  std::size_t operator()(TileIndex tile) const noexcept;
};

/// Maps between world coordinates, cells and tiles for one validated geometry. Cheap to copy;
/// all queries are O(1), never throw and never allocate.
class GridIndex {
 public:
  /// @throw std::invalid_argument (see Validate) if `geometry` is invalid.
  explicit GridIndex(const GridGeometry& geometry);

  const GridGeometry& geometry() const { return geometry_; }

  /// The cell holding world point (x_m, y_m). A coordinate on a cell edge belongs to the cell
  /// on its positive side (edge i·s is in cell i), also for negative coordinates; edges are the
  /// doubles CellOrigin returns, so WorldToCell(CellOrigin(c)) == c.
  /// @return std::nullopt if a coordinate is NaN or infinite, or its cell index would exceed
  ///         ±kMaxCellIndex.
  std::optional<CellIndex> WorldToCell(double x_m, double y_m) const;

  /// Centre of `cell` [m]. WorldToCell(CellCenter(c)) == c for |index| < 2^49; beyond that a
  /// cell is only a few ulps wide. Cells outside ±kMaxCellIndex give inexact but finite values.
  Eigen::Vector2d CellCenter(CellIndex cell) const;

  /// South-west (minimum x, minimum y) corner of `cell` [m]: the start of its half-open extent.
  Eigen::Vector2d CellOrigin(CellIndex cell) const;

  /// The tile holding `cell` (floor division). Defined for every int64 index.
  TileIndex CellToTile(CellIndex cell) const;

  /// `cell`'s position in its tile, in [0, tile_cells). Defined for every int64 index.
  LocalIndex CellToLocal(CellIndex cell) const;

  /// Inverse of (CellToTile, CellToLocal): tile·tile_cells + local. A local index outside
  /// [0, tile_cells) simply addresses a cell of a neighbouring tile. The result wraps (two's
  /// complement) if it leaves the int64 range, which no tile of a ±kMaxCellIndex cell reaches.
  CellIndex TileLocalToCell(TileIndex tile, LocalIndex local) const;

  /// South-west corner of `tile` [m]: CellOrigin of its first cell (bit-identical).
  Eigen::Vector2d TileOrigin(TileIndex tile) const;

  /// Row-major offset of `local` in a tile's cell array: y·tile_cells + x (rows run south to
  /// north). Not range-checked: `local` must be in [0, tile_cells).
  std::size_t LinearIndex(LocalIndex local) const {
    return static_cast<std::size_t>(local.y) * static_cast<std::size_t>(geometry_.tile_cells) +
           static_cast<std::size_t>(local.x);
  }

 private:
  GridGeometry geometry_;
};

/// Bounding box (inclusive min and max cell index) of the cells touched so far, for writers
/// that need the raster extent. Starts empty.
class CellBounds {
 public:
  /// Grows the box to include `cell`. Never fails.
  void Extend(CellIndex cell);
  /// Grows the box to include `other` (no-op if `other` is empty). Never fails.
  void Extend(const CellBounds& other);

  bool Empty() const { return min_.x > max_.x; }
  /// False when empty.
  bool Contains(CellIndex cell) const;

  /// Smallest x and y index touched. @throw std::logic_error if Empty().
  CellIndex Min() const;
  /// Largest x and y index touched. @throw std::logic_error if Empty().
  CellIndex Max() const;

  /// Columns (max.x − min.x + 1) and rows (max.y − min.y + 1); 0 when empty. Exact for cells
  /// within ±kMaxCellIndex (as WorldToCell returns).
  std::int64_t WidthCells() const { return Empty() ? 0 : max_.x - min_.x + 1; }
  std::int64_t HeightCells() const { return Empty() ? 0 : max_.y - min_.y + 1; }

 private:
  // Empty is min > max, so the first Extend needs no special case.
  CellIndex min_{std::numeric_limits<std::int64_t>::max(),
                 std::numeric_limits<std::int64_t>::max()};
  CellIndex max_{std::numeric_limits<std::int64_t>::min(),
                 std::numeric_limits<std::int64_t>::min()};
};

}  // namespace rovermap::dem
