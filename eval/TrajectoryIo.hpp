#pragma once
// Trajectory files for `rovermap eval`: TUM (`timestamp tx ty tz qx qy qz qw`, docs/design.md
// §4) and KITTI odometry poses (12 numbers per line: the row-major 3×4 matrix [R | t] of
// T_world_body).

#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace rovermap::eval {

enum class TrajectoryFormat { kAuto, kTum, kKitti };

/// "auto", "tum", "kitti".
std::string ToString(TrajectoryFormat format);
/// @throw std::invalid_argument naming the text if it is none of "auto", "tum", "kitti".
TrajectoryFormat ParseTrajectoryFormat(const std::string& text);

/// Poses T_world_body in file order; `timestamps_s` has one entry per pose for TUM files and is
/// empty for KITTI files (those associate by index).
struct Trajectory {
  std::string file;                                  ///< where it was read from (for messages)
  TrajectoryFormat format = TrajectoryFormat::kTum;  ///< as read (never kAuto)
  std::vector<double> timestamps_s;                  ///< [s], strictly increasing, or empty
  std::vector<Eigen::Isometry3d> poses;              ///< T_world_body
  bool has_timestamps() const { return !timestamps_s.empty(); }
  std::size_t size() const { return poses.size(); }
};

/// Reads a trajectory. Lines: whitespace-separated numbers, `#` comments (whole line or
/// trailing), blank lines ignored, LF or CRLF. kAuto picks the format from the first data line
/// (8 numbers: TUM, 12: KITTI). TUM quaternions are normalised; KITTI rotations (printed with
/// 7 digits) are projected onto the nearest rotation. TUM files are parsed by io::ParseTum.
/// @throw io::IoError "FILE:LINE: reason" if the file is missing or unreadable, has no pose, a
///        line has the wrong count of numbers or a non-numeric or non-finite value, a quaternion's
///        norm differs from 1 by more than 1e-3, a KITTI matrix is not a rotation within 1e-3
///        (‖RᵀR − I‖∞, det R > 0), or TUM timestamps are not strictly increasing.
Trajectory ReadTrajectory(const std::filesystem::path& path,
                          TrajectoryFormat format = TrajectoryFormat::kAuto);

/// ReadTrajectory on text already read; `path` only names the file in messages. Same errors.
Trajectory ParseTrajectory(std::string_view contents, const std::filesystem::path& path,
                           TrajectoryFormat format = TrajectoryFormat::kAuto);

}  // namespace rovermap::eval
