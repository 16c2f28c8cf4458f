#pragma once
// Fusion of registered frames into an octomap::OcTree (Hornung et al. 2013): each frame's
// points are inserted with the sensor origin, so the rays between them carve free space.

#include <octomap/OcTree.h>

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <vector>

#include "dem/BatchOcTree.hpp"
#include "dem/OctoMapOptions.hpp"

namespace rovermap::dem {

/// What InsertFrame did.
struct OctoMapFrameStats {
  std::size_t points = 0;                 ///< points given
  std::size_t inserted = 0;               ///< finite points passed to the tree
  std::size_t dropped_nonfinite = 0;      ///< NaN/inf points (never inserted)
  std::size_t dropped_out_of_bounds = 0;  ///< beyond the tree's keys (±3276.8 m at 0.1 m)
  std::size_t free_voxels = 0;            ///< voxels updated as free
  std::size_t occupied_voxels = 0;        ///< voxels updated as occupied
  bool skipped = false;                   ///< disabled, or the sensor origin was not finite
};

/// One OcTree fed frame by frame: discretized insertion (each voxel updated once per frame),
/// as OctoMap's insertPointCloud does it, in one ordered pass (dem::BatchOcTree) whose cost
/// does not grow with the tree; the inner occupancy is kept current on the touched paths.
class OctoMapFusion {
 public:
  /// @throw std::invalid_argument if `options` are invalid.
  explicit OctoMapFusion(const OctoMapOptions& options = {});

  const OctoMapOptions& options() const { return options_; }
  bool enabled() const { return tree_ != nullptr; }

  /// Inserts world points seen from `sensor_origin_world` [m], as frame `frame` (the tag its
  /// blocks of voxels follow when the map is moved: BatchOcTree::MovedCopy). Never throws.
  OctoMapFrameStats InsertFrame(const std::vector<Eigen::Vector3d>& points_world,
                                const Eigen::Vector3d& sensor_origin_world,
                                std::uint32_t frame = 0);

  /// The tree, inner nodes up to date; nullptr when disabled. Not thread-safe against
  /// InsertFrame.
  const BatchOcTree* tree() const { return tree_.get(); }

  /// The whole state for a checkpoint (service/Checkpoint): the tree with its log-odds (OctoMap's
  /// .ot format), after two words that earlier versions used for an inner-update schedule and
  /// that are now zero, followed by the blocks' frame tags (BatchOcTree::block_frames). Nothing
  /// when disabled.
  /// @return false if the stream failed.
  bool Save(std::ostream& out) const;
  /// Replaces the state by one Save wrote with the same options (or an earlier version, whose
  /// stale inner nodes are brought up to date here; without tags, its voxels stay in place when
  /// the map is moved).
  /// @throw std::runtime_error if the data are not such a state.
  void Restore(std::istream& in);

 private:
  OctoMapOptions options_;
  std::unique_ptr<BatchOcTree> tree_;
  std::vector<octomap::point3d> points_;  // the frame's finite points, reused
};

}  // namespace rovermap::dem
