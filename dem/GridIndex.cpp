#include "dem/GridIndex.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace rovermap::dem {
namespace {

// Edge i of an axis: the one formula every edge, origin and boundary test uses, so that a
// coordinate equal to an edge always lands in the same cell.
double Edge(std::int64_t i, double cell_size_m) { return static_cast<double>(i) * cell_size_m; }

// floor(v / s) settled against the rounded edges: the quotient is itself rounded and can land
// on the neighbouring cell when v is within an ulp of an edge.
std::optional<std::int64_t> AxisToCell(double v, double s) {
  const double q = std::floor(v / s);
  // Also rejects NaN; the margin lets a quotient one off the limit still be settled.
  if (!(std::abs(q) <= static_cast<double>(kMaxCellIndex) + 2.0)) return std::nullopt;
  auto i = static_cast<std::int64_t>(q);
  constexpr std::int64_t kLimit = kMaxCellIndex + 4;  // keeps the loops finite and exact
  while (i > -kLimit && v < Edge(i, s)) --i;
  while (i < kLimit && v >= Edge(i + 1, s)) ++i;
  if (i < -kMaxCellIndex || i > kMaxCellIndex) return std::nullopt;
  return i;
}

std::int64_t FloorDiv(std::int64_t a, std::int64_t b) {  // b > 0
  std::int64_t q = a / b;
  if (a % b != 0 && a < 0) --q;
  return q;
}

// splitmix64's finaliser: a bijection on 64 bits that maps 0 to 0.
std::uint64_t Mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Bits of v beyond a signed 32-bit value; 0 whenever v fits in int32.
std::uint64_t HighBits(std::int64_t v) { return static_cast<std::uint64_t>((v >> 31) ^ (v >> 63)); }

}  // namespace

void Validate(const GridGeometry& geometry) {
  if (!std::isfinite(geometry.cell_size_m) || !(geometry.cell_size_m > 0.0)) {
    std::ostringstream msg;
    msg << "cell_size_m: must be finite and > 0 (got " << geometry.cell_size_m << ")";
    throw std::invalid_argument(msg.str());
  }
  if (geometry.tile_cells < 1) {
    throw std::invalid_argument("tile_cells: must be >= 1 (got " +
                                std::to_string(geometry.tile_cells) + ")");
  }
}

std::size_t TileIndexHash::operator()(TileIndex tile) const noexcept {
  // Packing the low 32 bits of each axis is injective for |x|, |y| < 2^31, where the high
  // part is 0 and Mix(0) == 0; Mix is a bijection, so those tiles never collide.
  const std::uint64_t packed =
      static_cast<std::uint32_t>(tile.x) |
      (static_cast<std::uint64_t>(static_cast<std::uint32_t>(tile.y)) << 32);
  const std::uint64_t high = Mix(HighBits(tile.x) + 0x9e3779b97f4a7c15ULL * HighBits(tile.y));
  return static_cast<std::size_t>(Mix(packed ^ high));
}

GridIndex::GridIndex(const GridGeometry& geometry) : geometry_(geometry) { Validate(geometry_); }

std::optional<CellIndex> GridIndex::WorldToCell(double x_m, double y_m) const {
  const auto x = AxisToCell(x_m, geometry_.cell_size_m);
  if (!x) return std::nullopt;
  const auto y = AxisToCell(y_m, geometry_.cell_size_m);
  if (!y) return std::nullopt;
  return CellIndex{*x, *y};
}

Eigen::Vector2d GridIndex::CellCenter(CellIndex cell) const {
  const double s = geometry_.cell_size_m;
  return {(static_cast<double>(cell.x) + 0.5) * s, (static_cast<double>(cell.y) + 0.5) * s};
}

Eigen::Vector2d GridIndex::CellOrigin(CellIndex cell) const {
  return {Edge(cell.x, geometry_.cell_size_m), Edge(cell.y, geometry_.cell_size_m)};
}

TileIndex GridIndex::CellToTile(CellIndex cell) const {
  return {FloorDiv(cell.x, geometry_.tile_cells), FloorDiv(cell.y, geometry_.tile_cells)};
}

LocalIndex GridIndex::CellToLocal(CellIndex cell) const {
  // The remainder, not cell − tile·n: tile·n can leave the int64 range near its ends.
  const std::int64_t n = geometry_.tile_cells;
  const auto axis = [n](std::int64_t c) {
    const std::int64_t r = c % n;
    return static_cast<int>(r < 0 ? r + n : r);
  };
  return {axis(cell.x), axis(cell.y)};
}

CellIndex GridIndex::TileLocalToCell(TileIndex tile, LocalIndex local) const {
  // Unsigned arithmetic: wraps instead of signed-overflow UB for absurd tiles.
  const auto n = static_cast<std::uint64_t>(geometry_.tile_cells);
  const auto axis = [n](std::int64_t t, int l) {
    return static_cast<std::int64_t>(static_cast<std::uint64_t>(t) * n +
                                     static_cast<std::uint64_t>(static_cast<std::int64_t>(l)));
  };
  return {axis(tile.x, local.x), axis(tile.y, local.y)};
}

Eigen::Vector2d GridIndex::TileOrigin(TileIndex tile) const {
  // t·n is exact in double for any tile of a ±kMaxCellIndex cell, so this equals Edge(t·n)
  // bit for bit without an int64 product that could overflow.
  const double n = geometry_.tile_cells;
  const double s = geometry_.cell_size_m;
  return {static_cast<double>(tile.x) * n * s, static_cast<double>(tile.y) * n * s};
}

void CellBounds::Extend(CellIndex cell) {
  min_.x = std::min(min_.x, cell.x);
  min_.y = std::min(min_.y, cell.y);
  max_.x = std::max(max_.x, cell.x);
  max_.y = std::max(max_.y, cell.y);
}

void CellBounds::Extend(const CellBounds& other) {
  if (other.Empty()) return;
  Extend(other.min_);
  Extend(other.max_);
}

bool CellBounds::Contains(CellIndex cell) const {
  return cell.x >= min_.x && cell.x <= max_.x && cell.y >= min_.y && cell.y <= max_.y;
}

CellIndex CellBounds::Min() const {
  if (Empty()) throw std::logic_error("CellBounds::Min: no cell added");
  return min_;
}

CellIndex CellBounds::Max() const {
  if (Empty()) throw std::logic_error("CellBounds::Max: no cell added");
  return max_;
}

}  // namespace rovermap::dem
