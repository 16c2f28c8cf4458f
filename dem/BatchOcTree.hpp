#pragma once
// An octomap::OcTree that takes a frame's ray updates as one batch: the keys are cast with
// OctoMap's own ray traversal (computeRayKeys), packed into Morton codes, sorted and made unique
// in flat buffers kept from frame to frame, and merged into the tree in one depth-first walk.
// Consecutive keys share most of their path, so a voxel costs a few levels of descent instead
// of two full ones (OccupancyOcTreeBase::updateNode searches, then descends again), and the
// inner nodes on the touched paths are brought up to date on the way back up: the inner
// occupancy is always current, without walking the whole tree.

#include <octomap/OcTree.h>

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

namespace rovermap::dem {

/// What one InsertDiscretized did.
struct BatchCounts {
  std::size_t endpoints = 0;              ///< distinct endpoint voxels
  std::size_t dropped_out_of_bounds = 0;  ///< points outside the tree's key range
  std::size_t free_voxels = 0;            ///< voxels updated as free
  std::size_t occupied_voxels = 0;        ///< voxels updated as occupied
};

/// What MovedCopy did.
struct OcTreeMoveStats {
  std::size_t leaves_in = 0;     ///< voxels of the source tree (pruned leaves counted as voxels)
  std::size_t leaves_moved = 0;  ///< of them, in a block whose frame has a correction
  std::size_t leaves_out = 0;    ///< voxels of the moved tree
  std::size_t dropped = 0;       ///< moved outside the tree's key range
  double median_shift_m = 0.0;   ///< median move of the moved blocks' centres [m]
  double max_shift_m = 0.0;      ///< largest [m]
};

/// A tree's voxels moved (BatchOcTree::MoveVoxels) but not yet a tree (BatchOcTree::Build): the
/// part that reads the tree, on the thread that owns it, and the part that does not, which can
/// go on beside the next insertions.
struct MovedVoxels {
  // The source tree's resolution [m] and sensor model (probabilities), for the copy.
  double resolution = 0.0;
  double prob_hit = 0.0, prob_miss = 0.0, clamping_min = 0.0, clamping_max = 0.0, occupancy = 0.0;
  std::vector<std::pair<std::uint64_t, float>> leaves;  ///< Morton code, log-odds; any order
  std::vector<float> shifts;                            ///< per moved block [m]
  OcTreeMoveStats stats;                                ///< leaves_in, leaves_moved, dropped so far
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
  /// `frame` tags the blocks of 8 × 8 × 8 voxels this insertion updates (block_frames).
  BatchCounts InsertDiscretized(const std::vector<octomap::point3d>& points,
                                const octomap::point3d& origin, double max_range,
                                std::uint32_t frame = 0);

  /// Each block of 8 × 8 × 8 voxels (Morton code >> 9) tagged with the frame it follows when the
  /// map is moved (MovedCopy): the last frame that marked one of its voxels occupied (bit 31
  /// set), else the first that updated it. The last sighting of a surface is the nearest on a
  /// rover driving on (on a simulated 300 m loop, 0.955 of the moved occupied voxels lay within
  /// a voxel of the map fused again from the graph, 0.920 following the first); free space keeps
  /// its first frame (0.889 of it free in the fused map, 0.866 following the last). Blocks, not
  /// voxels: a tag costs a few bytes per 512 voxels, and a pose graph's correction varies over
  /// metres, not voxels.
  using BlockFrames = std::unordered_map<std::uint64_t, std::uint32_t>;
  static constexpr std::uint32_t kOccupiedTag = 1U << 31;
  static constexpr unsigned kBlockLevels = 3;  ///< a block is 2^3 voxels on a side
  const BlockFrames& block_frames() const { return block_frames_; }
  void SetBlockFrames(BlockFrames tags) { block_frames_ = std::move(tags); }

  /// The rigid correction of a frame's content (world frame, applied on the left), or nullptr
  /// where it stays.
  using FrameCorrection = std::function<const Eigen::Isometry3d*(std::uint32_t frame)>;
  /// The correction of frame f is `corrections[f]` (none past its end or where nullopt); the
  /// vector must outlive the function.
  static FrameCorrection CorrectionsByFrame(
      const std::vector<std::optional<Eigen::Isometry3d>>& corrections);
  /// A copy of the tree whose every voxel has moved with the correction of its block's frame:
  /// its centre is transformed and it lands in the voxel that holds the moved centre (nearest
  /// voxel; where two land in one, the higher log-odds wins, as an endpoint wins over free space
  /// within a frame). The copy has the same sensor model, its inner nodes up to date and no
  /// tags. Rotations leave a few voxels unfilled (nearest-voxel forward mapping), translations
  /// none. Never throws but std::bad_alloc.
  std::unique_ptr<BatchOcTree> MovedCopy(const FrameCorrection& correction,
                                         OcTreeMoveStats* stats = nullptr) const;
  /// MovedCopy in two steps: the voxels read and moved, then the tree built from them.
  MovedVoxels MoveVoxels(const FrameCorrection& correction) const;
  static std::unique_ptr<BatchOcTree> Build(MovedVoxels voxels, OcTreeMoveStats* stats = nullptr);

 private:
  void CastRay(const octomap::point3d& origin, const octomap::point3d& end);
  void Apply();
  void TagBlocks(std::uint32_t frame);
  // Makes each (Morton code, log-odds) of `leaves` (codes ascending and unique) a leaf of this
  // empty tree, and its inner nodes their children's maximum (updateInnerOccupancy).
  void SetLeaves(const std::vector<std::pair<std::uint64_t, float>>& leaves);

  // Buffers reused by every frame (cleared, never shrunk). Keys are Morton codes (bit 3b of
  // key.k[0], 3b + 1 of k[1], 3b + 2 of k[2]), so that ascending order is depth-first order.
  std::vector<std::uint64_t> endpoints_;
  std::vector<std::uint64_t> free_;
  std::vector<std::uint64_t> updates_;  // code << 1 | occupied, ascending
  std::vector<std::uint64_t> scratch_;
  std::vector<std::uint64_t> recent_;  // direct-mapped filter of keys just added to free_
  BlockFrames block_frames_;
};

}  // namespace rovermap::dem
