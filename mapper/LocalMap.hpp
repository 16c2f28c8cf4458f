#pragma once
// The registration reference of `mapper.reference: local_map`: the last K registered frames,
// kept in the world frame and voxel-thinned, handed out as one indexed cloud in the frame of
// the last one.

#include <Eigen/Geometry>
#include <cstddef>
#include <deque>
#include <iterator>
#include <memory>
#include <vector>

#include "registration/Icp.hpp"
#include "registration/PointCloud.hpp"

namespace rovermap::mapper {

class LocalMap {
 public:
  /// Keeps at most `max_frames` (>= 1) frames.
  explicit LocalMap(std::size_t max_frames) : max_frames_(max_frames < 1 ? 1 : max_frames) {}

  /// Adds a registered frame: body-frame `cloud` (points, normals and covariances when
  /// present) at `T_world_body`, thinned to one point per voxel of `voxel_m` (<= 0: all). The
  /// oldest frame goes when more than max_frames are held.
  void Add(const registration::PointCloud& cloud, const Eigen::Isometry3d& T_world_body,
           double voxel_m);

  /// Every held point moved into the frame at `T_world_ref` (by T_world_ref⁻¹), thinned again
  /// to one point per voxel of `voxel_m` (<= 0: all), indexed with `options`.
  std::unique_ptr<registration::IndexedCloud> Build(
      const Eigen::Isometry3d& T_world_ref, double voxel_m,
      const registration::RegistrationOptions& options) const;

  std::size_t frames() const { return frames_.size(); }
  /// The held frames (world frame), oldest first, and their restoration (service/Checkpoint).
  const std::deque<registration::PointCloud>& clouds() const { return frames_; }
  void Restore(std::vector<registration::PointCloud> clouds) {
    frames_.assign(std::make_move_iterator(clouds.begin()), std::make_move_iterator(clouds.end()));
  }
  std::size_t points() const;
  bool empty() const { return frames_.empty(); }

 private:
  std::size_t max_frames_;
  std::deque<registration::PointCloud> frames_;  // world frame
};

/// The points of `cloud` at `indices` (with their attributes), moved by `T`.
registration::PointCloud TransformSubset(const registration::PointCloud& cloud,
                                         const std::vector<std::size_t>& indices,
                                         const Eigen::Isometry3d& T);

}  // namespace rovermap::mapper
