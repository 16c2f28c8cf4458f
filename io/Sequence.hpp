#pragma once
// A recorded sequence directory (docs/design.md §4), validated when opened and then read one frame
// at a time: the poses of every frame are held (a few hundred bytes each), the images and point
// clouds never more than one frame's worth.

#include <Eigen/Geometry>
#include <cstddef>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "io/CameraModel.hpp"
#include "io/Frame.hpp"
#include "io/FrameSource.hpp"
#include "io/Tum.hpp"

namespace rovermap::io {

/// Reads sequence.yaml (io/SequenceYaml, the YAML reader of the input formats) and converts it.
/// @throw IoError "DIR/sequence.yaml:LINE: KEY: reason" on any problem (see
///        ReadSequenceYaml).
SequenceInfo ReadSequenceInfo(const std::filesystem::path& sequence_dir);

/// File names of frame `index` inside frames/: "000042.left.png", "000042.right.png",
/// "000042.ply".
std::string FrameStem(std::size_t index);

/// "000042.left.png" -> 42 and "left.png"; the kinds are left.png, right.png, ply, and an
/// inbox's odom and gt (docs/design.md §7). False for other names (dot-names among them).
bool ParseFrameFileName(const std::string& name, std::size_t* index, std::string* kind);

/// An 8-bit grey image that must have the camera's size. @throw IoError naming the file.
cv::Mat ReadStereoImage(const std::filesystem::path& file, const CameraModel& camera);

/// Reads the images (stereo: `stem`.left.png and .right.png) or the points (`stem`.ply) of a
/// frame into `frame` (its poses are left alone). @throw IoError naming the file.
void ReadFrameData(const std::filesystem::path& stem, const SequenceInfo& info, Frame* frame);

/// Writes `dir`/sequence.yaml for `info` (quaternion form, full precision; `camera:` when
/// info has one, `body:` when not earth), its first line the comment "# `header`".
/// @throw IoError naming the file if it cannot be written.
void WriteSequenceYaml(const std::filesystem::path& dir, const SequenceInfo& info,
                       const std::string& header);

/// Writes the images (`stem`.left.png and .right.png) or the points (`stem`.ply) of `frame`, as
/// ReadFrameData reads them, each file atomically. @throw IoError naming the file.
void WriteFrameData(const std::filesystem::path& stem, const SequenceInfo& info,
                    const Frame& frame);

/// Opens and validates a sequence; then Next() reads frames in index order (groundtruth() is
/// empty when the sequence has no groundtruth.tum).
///
/// Opening checks everything but the frame contents: sequence.yaml (keys, calibration),
/// odometry.tum and groundtruth.tum (8 columns, unit quaternions, strictly increasing
/// timestamps), that groundtruth.tum has as many lines as odometry.tum with the same
/// timestamps (within 1 µs), and that frames/ holds exactly frames 0 … N−1 for the N poses of
/// odometry.tum (both images for stereo, the PLY for cloud) and no others.
class SequenceReader : public IndexedFrameSource {
 public:
  /// @throw IoError naming the file (and line) at fault.
  explicit SequenceReader(const std::filesystem::path& sequence_dir);

  /// Starts again at frame 0.
  void Rewind() { next_ = 0; }

 private:
  /// @throw IoError naming the file if an image or PLY cannot be read or decoded, or an image
  ///        does not have the camera's size.
  void LoadFrame(Frame* frame) const override;
};

}  // namespace rovermap::io
