#pragma once
// The frames of a recording, in order, whatever holds them: a sequence directory
// (SequenceReader), a ROS 1 bag (BagSource) or a ROS 2 bag (Ros2BagSource). Replay and
// mapper::ReadAhead see only this.

#include <cstddef>
#include <filesystem>
#include <memory>
#include <vector>

#include "io/BagOptions.hpp"
#include "io/Frame.hpp"
#include "io/Gnss.hpp"
#include "io/Tum.hpp"

namespace rovermap::io {

/// What a recording held that gave no frame; zero for a sequence directory.
struct SkippedFrames {
  std::size_t outside_pose_span = 0;  ///< stamps outside the odometry's (or truth's) time span
  std::size_t unpaired_images = 0;    ///< left or right images without a partner in tolerance
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  /// Sensor, calibration, T_body_sensor and origin of the recording.
  virtual const SequenceInfo& info() const = 0;
  virtual std::size_t frame_count() const = 0;
  /// Index of the frame the next Next() call reads (= frames read so far).
  virtual std::size_t next_index() const = 0;
  /// One pose per frame, frame k's at [k].
  virtual const std::vector<StampedPose>& odometry() const = 0;
  /// Empty, or one pose per frame like odometry().
  virtual const std::vector<StampedPose>& groundtruth() const = 0;
  bool has_groundtruth() const { return !groundtruth().empty(); }
  /// GNSS fixes by time (a sequence's gnss.csv, a bag's NavSatFix messages); empty if none.
  virtual const std::vector<GnssFix>& gnss() const;
  virtual SkippedFrames skipped() const { return {}; }

  /// Reads the next frame into `frame` (replacing its contents).
  /// @return false (and leaves `frame` alone) when every frame has been read.
  /// @throw IoError naming the file if a frame cannot be read or decoded. The source moves
  ///        past that frame, so a caller may skip it and go on.
  virtual bool Next(Frame* frame) = 0;

  /// Reads frame `index` (random access, e.g. to retry). Same errors as Next;
  /// std::out_of_range if index >= frame_count().
  virtual Frame Read(std::size_t index) const = 0;

 protected:
  FrameSource() = default;
  FrameSource(const FrameSource&) = default;
  FrameSource& operator=(const FrameSource&) = default;
};

/// A FrameSource that holds every frame's poses from the start and reads the rest of a frame
/// when asked: Read() sets a frame's index and poses and calls LoadFrame; Next() is
/// Read(next_index()) that moves on even when it throws.
class IndexedFrameSource : public FrameSource {
 public:
  const SequenceInfo& info() const override { return info_; }
  std::size_t frame_count() const override { return odometry_.size(); }
  std::size_t next_index() const override { return next_; }
  const std::vector<StampedPose>& odometry() const override { return odometry_; }
  const std::vector<StampedPose>& groundtruth() const override { return groundtruth_; }
  const std::vector<GnssFix>& gnss() const override { return gnss_; }
  bool Next(Frame* frame) final;
  Frame Read(std::size_t index) const final;

 protected:
  /// Reads the images or points of `frame`, whose index and poses are set.
  /// @throw IoError naming what cannot be read.
  virtual void LoadFrame(Frame* frame) const = 0;

  SequenceInfo info_;
  std::vector<StampedPose> odometry_;
  std::vector<StampedPose> groundtruth_;  ///< empty, or one per frame
  std::vector<GnssFix> gnss_;
  std::size_t next_ = 0;
};

/// Opens the recording at `path`: a ROS 2 bag (a directory with metadata.yaml, a *.mcap or a
/// *.db3 file), a ROS 1 bag (a file named *.bag), both read by `bag_options`, or a sequence
/// directory (docs/design.md §4).
/// @throw IoError naming the file (and line) at fault, or saying that this build has no bag
///        support (ROVERMAP_WITH_ROSBAG off).
std::unique_ptr<FrameSource> OpenFrameSource(const std::filesystem::path& path,
                                             const BagOptions& bag_options = {});

}  // namespace rovermap::io
