#pragma once
// TUM trajectory files: `timestamp tx ty tz qx qy qz qw` (docs/design.md §3, §4).

#include <Eigen/Geometry>
#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

namespace rovermap::io {

/// One pose of a trajectory: T_world_body at `timestamp`.
struct StampedPose {
  double timestamp = 0.0;  ///< [s]
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  int line = 0;  ///< 1-based line in the file it was read from (0 if not read)
  /// The quaternion T_world_body's rotation was made from (RotationFromQuaternion), when it was
  /// (a TUM line, a bag's pose): WriteTum writes it as it is, so that the file reads back to this
  /// very rotation (a quaternion recomputed from the matrix can differ in its last bit).
  std::optional<Eigen::Quaterniond> quaternion;
};

/// The poses of `stamped`, without their stamps.
inline std::vector<Eigen::Isometry3d> PosesOf(const std::vector<StampedPose>& stamped) {
  std::vector<Eigen::Isometry3d> out;
  out.reserve(stamped.size());
  for (const StampedPose& p : stamped) out.push_back(p.T_world_body);
  return out;
}

/// Reads a TUM file: 8 space/tab separated numbers per line, `#` comments (whole line or
/// trailing), blank lines ignored, LF or CRLF.
/// @throw IoError "FILE:LINE: reason" if the file is missing or unreadable, a line does not have
///        exactly 8 finite numbers, a quaternion's norm differs from 1 by more than 1e-3, or the
///        timestamps are not strictly increasing. An empty file gives an empty vector.
std::vector<StampedPose> ReadTum(const std::filesystem::path& path);

/// ReadTum on text already read; `path` only names the file in messages.
/// @throw IoError "PATH:LINE: reason" as ReadTum.
std::vector<StampedPose> ParseTum(std::string_view text, const std::filesystem::path& path);

/// Writes a TUM file (full double precision, qw >= 0), atomically: each pose's `quaternion` as it
/// is while it still gives T_world_body's rotation, else one normalised from the matrix (so a
/// pose read by ReadTum is written with the quaternion it was read with).
/// @throw IoError if it cannot be written.
void WriteTum(const std::filesystem::path& path, const std::vector<StampedPose>& poses);

}  // namespace rovermap::io
