#pragma once
// The pipeline over one recording's frames with another dead reckoning: the same points (loaded
// once; stereo is the costly part) registered from seeds of different quality, so that what the
// seed leaves in the result can be measured (bench_seed, tests/test_seed_robustness.cpp).

#include <Eigen/Geometry>
#include <filesystem>
#include <vector>

#include "io/Frame.hpp"
#include "io/Tum.hpp"
#include "mapper/FrameLoader.hpp"
#include "mapper/Mapper.hpp"

namespace rovermap::mapper {

/// A sequence's frames, loaded once: metadata (no images) and points.
struct PreloadedSequence {
  io::SequenceInfo info;
  std::vector<io::Frame> frames;       ///< index, timestamp, odometry, truth; images released
  std::vector<LoadedFrame> loaded;     ///< LoadFrame's result per frame
  std::vector<io::StampedPose> truth;  ///< groundtruth.tum (empty without one)
};

/// Reads and loads the first `max_frames` frames (0 = all) of a sequence directory.
/// @throw io::IoError naming the file, as SequenceReader.
PreloadedSequence Preload(const std::filesystem::path& sequence_dir, const PipelineOptions& options,
                          std::size_t max_frames = 0);

/// The chained poses (T_world_body, one per frame) and per-frame results of a fresh Mapper over
/// `sequence`, each frame's dead reckoning replaced by `odometry[i]` (as many as frames).
/// @throw std::invalid_argument if the counts differ.
std::vector<FrameResult> RunWithOdometry(const PreloadedSequence& sequence,
                                         const std::vector<Eigen::Isometry3d>& odometry,
                                         const PipelineOptions& options);

/// The sequence's own dead reckoning (odometry.tum), one pose per frame.
std::vector<Eigen::Isometry3d> OdometryOf(const PreloadedSequence& sequence);

/// What a run chained: T_world_body per frame, and the increments whose yaw was kept from dead
/// reckoning (there, the seed's heading error goes straight into the result) and the frames that
/// fell back to it whole (registration rejected, or a bad frame).
struct ChainedRun {
  std::vector<Eigen::Isometry3d> poses;
  int yaw_from_odometry = 0;
  int fell_back = 0;
};
ChainedRun Chained(const std::vector<FrameResult>& results);

}  // namespace rovermap::mapper
