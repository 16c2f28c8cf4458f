#pragma once
// A plain feature-based stereo visual odometry, the peer row of bench_seed: good features in
// the left image, their disparity by KLT into the right one, KLT into the next left image,
// PnP with RANSAC on the 3-D points. No keyframes, no bundle adjustment: what a team writes
// in an afternoon, to put registration's heading drift next to.

#include <Eigen/Geometry>
#include <filesystem>
#include <vector>

namespace rovermap::bench {

/// T_world_body per frame of a stereo sequence directory, chained from `T_world_body0`; a pair
/// PnP cannot solve (fewer than 12 inliers) repeats the last increment.
/// @throw io::IoError as SequenceReader; std::invalid_argument for a cloud sequence.
std::vector<Eigen::Isometry3d> StereoVisualOdometry(const std::filesystem::path& sequence_dir,
                                                    const Eigen::Isometry3d& T_world_body0,
                                                    std::size_t max_frames = 0);

}  // namespace rovermap::bench
