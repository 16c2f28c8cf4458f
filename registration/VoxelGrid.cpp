#include "registration/VoxelGrid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace rovermap::registration {
namespace {

std::size_t Hash(const Eigen::Vector3i& c) {
  // Teschner et al. 2003 spatial hash, widened to 64 bits.
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.x())) * 73856093ull) ^
         (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.y())) * 19349663ull) ^
         (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.z())) * 83492791ull);
}

// SplitMix64's finaliser: a fixed pseudo-random rank of a point index.
std::uint64_t MixIndex(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

std::size_t TableSize(std::size_t cells) {
  std::size_t size = 16;
  while (size < 2 * cells) size *= 2;
  return size;
}

int ClampedFloor(double v) {
  const double f = std::floor(v);
  if (!(f > std::numeric_limits<int>::min())) return std::numeric_limits<int>::min();
  if (!(f < std::numeric_limits<int>::max())) return std::numeric_limits<int>::max();
  return static_cast<int>(f);
}

}  // namespace

VoxelGrid::VoxelGrid(double edge_m, std::size_t expected_cells)
    : edge_(edge_m), table_(TableSize(expected_cells)) {}

Eigen::Vector3i VoxelGrid::Cell(const Eigen::Vector3d& p) const {
  return Eigen::Vector3i(ClampedFloor(p.x() / edge_), ClampedFloor(p.y() / edge_),
                         ClampedFloor(p.z() / edge_));
}

std::size_t VoxelGrid::Insert(const Eigen::Vector3d& p) {
  if (2 * (cells_ + 1) > table_.size()) Grow();
  const Eigen::Vector3i cell = Cell(p);
  const std::size_t mask = table_.size() - 1;
  for (std::size_t h = Hash(cell) & mask;; h = (h + 1) & mask) {
    Slot& s = table_[h];
    if (s.id == kEmpty) {
      s.cell = cell;
      s.id = static_cast<std::uint32_t>(cells_++);
      return s.id;
    }
    if (s.cell == cell) return s.id;
  }
}

void VoxelGrid::Grow() { Rehash(table_.size() * 2); }

void VoxelGrid::Reserve(std::size_t cells) {
  const std::size_t size = TableSize(cells);
  if (size > table_.size()) Rehash(size);
}

void VoxelGrid::Rehash(std::size_t size) {
  std::vector<Slot> old(size);
  old.swap(table_);
  const std::size_t mask = table_.size() - 1;
  for (const Slot& s : old) {
    if (s.id == kEmpty) continue;
    std::size_t h = Hash(s.cell) & mask;
    while (table_[h].id != kEmpty) h = (h + 1) & mask;
    table_[h] = s;
  }
}

std::vector<std::size_t> VoxelSample(const std::vector<Eigen::Vector3d>& points, double edge_m,
                                     VoxelChoice choice) {
  std::vector<std::size_t> sample;
  if (!(edge_m > 0.0)) {
    sample.resize(points.size());
    std::iota(sample.begin(), sample.end(), std::size_t{0});
    return sample;
  }
  VoxelGrid grid(edge_m, points.size() / 4 + 1);
  std::vector<std::uint64_t> rank;  // kAnyMember: the kept point's hash
  // Size the table from the first eighth's fill once: growing it step by step rehashes the
  // whole table each time, a large share of sampling a scan at its own spacing
  // (docs/benchmarks.md, "Figures behind the matcher's code").
  const std::size_t probe_end = points.size() / 8;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (i == probe_end && i > 0) grid.Reserve(grid.size() * 10);  // 8 eighths and a margin
    if (!points[i].allFinite()) continue;
    const std::size_t id = grid.Insert(points[i]);
    if (choice == VoxelChoice::kFirst) {
      if (id == sample.size()) sample.push_back(i);
      continue;
    }
    const std::uint64_t r = MixIndex(i);
    if (id == sample.size()) {
      sample.push_back(i);
      rank.push_back(r);
    } else if (r < rank[id]) {
      sample[id] = i;
      rank[id] = r;
    }
  }
  if (choice == VoxelChoice::kAnyMember) {
    // Ascending without a sort: mark the kept indices, then read them in order.
    std::vector<unsigned char> kept(points.size(), 0);
    for (const std::size_t i : sample) kept[i] = 1;
    std::size_t k = 0;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (kept[i]) sample[k++] = i;
  }
  return sample;
}

}  // namespace rovermap::registration
