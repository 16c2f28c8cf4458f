#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace rovermap::registration {

/// Dense ids for the occupied cells of a cubic voxel grid: an open-addressing hash of the
/// integer cell coordinates, faster than the std::unordered_map it replaced in stereo's
/// downsampling on frames in row order (docs/benchmarks.md, "Figures behind the matcher's
/// code").
class VoxelGrid {
 public:
  /// `edge_m` > 0 [m]; `expected_cells` sizes the table (it grows when needed).
  VoxelGrid(double edge_m, std::size_t expected_cells);

  /// Id (0, 1, 2, ... in order of first touch) of the cell holding `p`.
  std::size_t Insert(const Eigen::Vector3d& p);
  /// Integer coordinates of the cell holding `p` (clamped to the int32 range).
  Eigen::Vector3i Cell(const Eigen::Vector3d& p) const;

  /// Makes room for `cells` cells in all without growing again (never shrinks).
  void Reserve(std::size_t cells);

  std::size_t size() const { return cells_; }
  double edge() const { return edge_; }

 private:
  struct Slot {
    Eigen::Vector3i cell;
    std::uint32_t id = kEmpty;
  };
  static constexpr std::uint32_t kEmpty = 0xffffffffu;

  void Grow();
  void Rehash(std::size_t table_size);

  double edge_;
  std::vector<Slot> table_;  // power-of-two size, at most half full
  std::size_t cells_ = 0;
};

/// Which point of a voxel VoxelSample keeps.
enum class VoxelChoice {
  /// A member picked by a fixed hash of its index, whatever its position or input order: its
  /// noise is distributed like any point's. The sample for registration.
  kAnyMember,
  /// The first in input order (LocalMap lists its newest frame first to keep the latest view).
  /// Biased on a noisy cloud in image order: a voxel's first point comes from the farthest
  /// pixel row that reached it, so its range noise pulls it towards the camera.
  kFirst,
};

/// One representative per occupied voxel of edge `edge_m` (see VoxelChoice), so the sample is
/// spread evenly whatever the input density (stereo clouds are far denser near the camera).
/// Indices into `points`, ascending; non-finite points are skipped. `edge_m` <= 0: all points.
std::vector<std::size_t> VoxelSample(const std::vector<Eigen::Vector3d>& points, double edge_m,
                                     VoxelChoice choice = VoxelChoice::kAnyMember);

}  // namespace rovermap::registration
