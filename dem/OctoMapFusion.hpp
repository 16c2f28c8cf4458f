#pragma once
// Fusion of registered frames into an octomap::OcTree (Hornung et al. 2013): each frame's
// points are inserted with the sensor origin, so the rays between them carve free space.

#include <octomap/OcTree.h>

#include <Eigen/Core>
#include <cstddef>
#include <iosfwd>
#include <memory>
#include <vector>

#include "dem/OctoMapOptions.hpp"

namespace rovermap::dem {

/// What InsertFrame did.
struct OctoMapFrameStats {
  std::size_t points = 0;             ///< points given
  std::size_t inserted = 0;           ///< finite points passed to the tree
  std::size_t dropped_nonfinite = 0;  ///< NaN/inf points (never inserted)
  bool skipped = false;               ///< disabled, or the sensor origin was not finite
};

/// One OcTree fed frame by frame: discretized, lazily evaluated insertion (each voxel updated
/// once per frame); the inner occupancy is updated every 50 frames and when the tree is read.
class OctoMapFusion {
 public:
  /// @throw std::invalid_argument if `options` are invalid.
  explicit OctoMapFusion(const OctoMapOptions& options = {});

  const OctoMapOptions& options() const { return options_; }
  bool enabled() const { return tree_ != nullptr; }

  /// Inserts world points seen from `sensor_origin_world` [m]. Never throws.
  OctoMapFrameStats InsertFrame(const std::vector<Eigen::Vector3d>& points_world,
                                const Eigen::Vector3d& sensor_origin_world);

  /// The tree with its inner nodes up to date (brought up to date here, not per frame);
  /// nullptr when disabled. Not thread-safe against InsertFrame.
  const octomap::OcTree* tree() const;

  /// The whole state for a checkpoint (mapper/Checkpoint): the tree with its log-odds as they
  /// are (OctoMap's .ot format, inner nodes not brought up to date, so that a restored map goes
  /// on exactly as this one would) and the inner-update schedule. Nothing when disabled.
  /// @return false if the stream failed.
  bool Save(std::ostream& out) const;
  /// Replaces the state by one Save wrote with the same options.
  /// @throw std::runtime_error if the data are not such a state.
  void Restore(std::istream& in);

 private:
  OctoMapOptions options_;
  void UpdateInner() const;

  std::unique_ptr<octomap::OcTree> tree_;
  mutable bool inner_stale_ = false;
  mutable int frames_since_update_ = 0;
};

}  // namespace rovermap::dem
