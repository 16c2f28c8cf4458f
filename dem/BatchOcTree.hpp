#pragma once
// An octomap::OcTree that takes a frame's ray updates as one batch: the keys are cast with
// OctoMap's own ray traversal (computeRayKeys), packed into Morton codes, sorted and made unique
// in flat buffers kept from frame to frame, and merged into the tree in one depth-first walk.
// Consecutive keys share most of their path, so a voxel costs a few levels of descent instead
// of two full ones (OccupancyOcTreeBase::updateNode searches, then descends again), and the
// inner nodes on the touched paths are brought up to date on the way back up: the inner
// occupancy is always current, without walking the whole tree.

#include <octomap/OcTree.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace rovermap::dem {

/// What one InsertDiscretized did.
struct BatchCounts {
  std::size_t endpoints = 0;              ///< distinct endpoint voxels
  std::size_t dropped_out_of_bounds = 0;  ///< points outside the tree's key range
  std::size_t free_voxels = 0;            ///< voxels updated as free
  std::size_t occupied_voxels = 0;        ///< voxels updated as occupied
};

class BatchOcTree : public octomap::OcTree {
 public:
  /// @param resolution [m] leaf edge.
  explicit BatchOcTree(double resolution);

  /// The updates of OccupancyOcTreeBase::insertPointCloud(points, origin, max_range,
  /// lazy_eval = true, discretize = true) — endpoints discretized to their voxel centres, free
  /// space along each ray (truncated at `max_range` [m], < 0 for none), endpoints occupied and
  /// winning over free, each voxel updated once with the same log-odds, clamping and early
  /// abort — followed by updateInnerOccupancy over the touched paths. Points (or a truncated
  /// ray's end) outside the tree's key range are left out, where OctoMap would print or
  /// overflow; nothing is inserted if `origin` is outside it. Never throws but std::bad_alloc.
  BatchCounts InsertDiscretized(const std::vector<octomap::point3d>& points,
                                const octomap::point3d& origin, double max_range);

 private:
  void CastRay(const octomap::point3d& origin, const octomap::point3d& end);
  void Apply();

  // Buffers reused by every frame (cleared, never shrunk). Keys are Morton codes (bit 3b of
  // key.k[0], 3b + 1 of k[1], 3b + 2 of k[2]), so that ascending order is depth-first order.
  std::vector<std::uint64_t> endpoints_;
  std::vector<std::uint64_t> free_;
  std::vector<std::uint64_t> updates_;  // code << 1 | occupied, ascending
  std::vector<std::uint64_t> scratch_;
  std::vector<std::uint64_t> recent_;  // direct-mapped filter of keys just added to free_
};

}  // namespace rovermap::dem
