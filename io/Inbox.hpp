#pragma once
// The daemon's inbox (docs/design.md §7): a sequence directory (§4) filled while the rover drives.
// sequence.yaml first, then per frame frames/NNNNNN.left.png + .right.png (stereo) or
// NNNNNN.ply (cloud), NNNNNN.odom (its one TUM odometry line) and optionally NNNNNN.gt (a
// ground-truth line). Producers write under a dot-name and rename in, so a file present is
// complete. Frames that cannot be used are moved to rejected/ beside a NNNNNN.reason file.

#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io/Sequence.hpp"
#include "io/Tum.hpp"

namespace rovermap::io {

/// Which files of one frame index are in frames/.
struct InboxFrameFiles {
  bool left = false;
  bool right = false;
  bool ply = false;
  bool odom = false;
  bool gt = false;
  /// Every file the sensor needs, and the odometry line.
  bool Complete(SensorType sensor) const {
    return odom && (sensor == SensorType::kStereo ? left && right : ply);
  }
};

/// The one pose of a frame's .odom or .gt file (its text); `path` only names it in messages.
/// @throw IoError "PATH:LINE: reason" as ParseTum, or "PATH: holds N poses" unless exactly one.
StampedPose ParseFramePose(std::string_view text, const std::filesystem::path& path);

class Inbox {
 public:
  /// `directory`: the inbox (need not exist yet).
  explicit Inbox(std::filesystem::path directory);

  const std::filesystem::path& directory() const { return directory_; }
  std::filesystem::path frames_dir() const { return directory_ / "frames"; }
  std::filesystem::path rejected_dir() const { return directory_ / "rejected"; }
  std::filesystem::path sequence_yaml() const { return directory_ / "sequence.yaml"; }

  /// The frame files present, by index (dot-names and other files ignored); a missing frames/
  /// is empty. @throw IoError naming frames/ if it exists but cannot be listed (EACCES).
  std::map<std::size_t, InboxFrameFiles> Scan() const;

  /// The frame's odometry line (and ground truth when `files.gt`).
  /// @throw IoError naming the file and line.
  Frame ReadPoses(std::size_t index, const InboxFrameFiles& files) const;
  /// ReadPoses, then the images or PLY as SequenceReader::Read reads them.
  /// @throw IoError naming the file.
  Frame Read(std::size_t index, const InboxFrameFiles& files, const SequenceInfo& info) const;

  /// Writes rejected/NNNNNN.reason (atomically), then moves every file of frame `index` there.
  /// Files already gone are skipped. @throw IoError naming the file that could not be moved.
  void Reject(std::size_t index, const std::string& reason) const;

 private:
  std::filesystem::path directory_;
};

}  // namespace rovermap::io
