#pragma once
// The rover's own recent ground as height posts, for the matches against a reference DEM
// (ReferenceMatch): every frame's points binned in its body frame (0.25 m bins, before the pose
// is known), placed in the world by its chained pose, and merged over a window of frames at a
// post spacing. Kept apart from the DEM: the DEM fuses a revisit into the cells of the first
// pass, and its publication rules leave out the far, sparse ground a match needs.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <deque>
#include <limits>
#include <vector>

#include "registration/PointCloud.hpp"

namespace rovermap::mapper {

/// One height post (world frame): the frames' bins over it, their height the weighted median
/// of the bins' (robust to a frame's stray bin), their x, y the weighted mean.
struct Post {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  std::size_t points = 0;
  /// [m] σ of the height from the points' own variances; NaN when the cloud carries none.
  double sigma_m = std::numeric_limits<double>::quiet_NaN();
};

/// A frame's points binned in its body frame: per bin the inverse-variance weighted mean of its
/// points within 3σ of their weighted median (a stereo outlier or a far point's error does not
/// move a post), the summed weight [1/m²] and the points kept.
struct FrameBins {
  std::vector<Eigen::Vector3d> mean;
  std::vector<double> weight;  ///< Σ 1/σ_z²; the point count when `weighted` is false
  std::vector<std::size_t> count;
  bool weighted = false;  ///< the points carried covariances
};

/// Bins `points_body` (those `keep` marks, all when empty) in 0.25 m squares of body x, y,
/// weighing each point by 1/σ_z² from its covariance (alike when the cloud has none). Never
/// throws.
FrameBins BinFrame(const registration::PointCloud& points_body,
                   const std::vector<unsigned char>& keep);

/// The index of the pose in `poses` nearest `centre` (world x, y) horizontally; 0 when empty.
std::size_t NearestPose(const std::vector<Eigen::Isometry3d>& poses, const Eigen::Vector2d& centre);

/// The last frames' bins, placed in the world.
class PatchAccumulator {
 public:
  /// Adds frame `frame` (frames in increasing order) with its chained pose.
  void Add(std::size_t frame, const Eigen::Isometry3d& T_world_body, const FrameBins& bins);
  /// Add for every frame of a run in turn (frame 0 first), keeping the path walked and only the
  /// frames of its last `window_m`. @return the window's first frame.
  std::size_t Advance(std::size_t frame, const Eigen::Isometry3d& T_world_body,
                      const FrameBins& bins, double window_m);
  /// [m] the chained path from frame 0 to the last frame Advance took.
  double path_m() const { return path_m_.empty() ? 0.0 : path_m_.back(); }
  /// Forgets the frames before `frame`.
  void DropBefore(std::size_t frame);
  /// The posts of frames [first, last] on the world lattice of `spacing_m` (multiples of it),
  /// each from at least `min_points` points and, where the points had variances, of σ at most
  /// `max_sigma_m` (far stereo ground, metres off, places nothing). Never throws.
  std::vector<Post> Window(std::size_t first, std::size_t last, double spacing_m,
                           double max_sigma_m = std::numeric_limits<double>::infinity(),
                           std::size_t min_points = 3) const;

 private:
  friend struct CheckpointAccess;  // service/Checkpoint: kept across a daemon's restart
  struct Placed {
    std::size_t frame = 0;
    std::vector<Eigen::Vector3d> centroid;  // world
    std::vector<double> weight;
    std::vector<std::size_t> count;
    bool weighted = false;
  };
  std::deque<Placed> frames_;
  std::vector<double> path_m_;  // per frame Advance took
  Eigen::Vector3d last_position_ = Eigen::Vector3d::Zero();
};

}  // namespace rovermap::mapper
