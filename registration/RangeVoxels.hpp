#pragma once
// Range-aware voxels: a frame's points merged into cubes whose edge grows with the range from
// the sensor, so that a stereo frame's dense near ground and its sparse far ground end up
// about equally sampled (issue 32: registration does not need 260 000 points a KITTI frame).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "registration/PointCloud.hpp"

namespace rovermap::registration {

/// The merged cloud and, for every input point, the index of the voxel it went into.
struct RangeVoxels {
  static constexpr std::uint32_t kNoVoxel = 0xffffffffu;
  PointCloud cloud;
  std::vector<std::uint32_t> voxel_of;  ///< one per input point (kNoVoxel: left out)
};

/// Merges `cloud` into cubes of edge about `angle_rad` × range from `origin` (the same frame as
/// the points), rounded to a power of two times `min_edge_m` (so each range band is one grid;
/// the edge is within a factor √2 of the target), never below `min_edge_m`. Each voxel becomes
/// one point (points whose `keep` entry is 0 go into none; voxel_of is then
/// kNoVoxel): the mean of its points; the mean of their covariances (a merged point stands for
/// one measurement, not for their sum: neighbouring stereo pixels share their errors) plus the
/// points' scatter about their mean (it stands for a patch that a point of another frame may
/// pair with anywhere); the normalised sum of their normals. Chain ids are dropped. `angle_rad` <=
/// 0 returns the cloud as it is (voxel_of = 0, 1, 2, ...). Never throws on data.
RangeVoxels RangeVoxelDownsample(const PointCloud& cloud, const Eigen::Vector3d& origin,
                                 double angle_rad, double min_edge_m = 0.001,
                                 const std::vector<unsigned char>* keep = nullptr);

}  // namespace rovermap::registration
