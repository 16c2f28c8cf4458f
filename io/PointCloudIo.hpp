#pragma once

#include <filesystem>
#include <string_view>

#include "registration/PointCloud.hpp"

namespace rovermap::io {

/// Reads a point cloud, choosing the format by extension (.xyz or .ply, case-insensitive).
/// Throws IoError (message starts with the path; text errors add ":LINE") on any problem:
/// missing/unreadable/empty file, unknown extension, malformed data, no points, or a
/// non-finite coordinate or normal.
registration::PointCloud ReadPointCloud(const std::filesystem::path& path);

/// Whitespace-separated text, one point per line: `x y z` or `x y z nx ny nz` (every line the
/// same). `#` starts a comment (whole line or trailing); LF or CRLF. Blank lines separate chains
/// (curves): chain_ids is always filled, starting at 0 and incremented once per run of blank
/// lines between two points. Comment-only lines are transparent: they do not separate chains.
registration::PointCloud ReadXyz(const std::filesystem::path& path);

/// ReadXyz on bytes already read; `path` only names the file in messages. Same errors.
registration::PointCloud ParseXyz(std::string_view data, const std::filesystem::path& path);

/// What the PLY reader does with a non-finite (NaN, ±inf) coordinate or normal.
enum class NonFinite {
  kReject,  ///< an IoError naming the file and the line or vertex: a scan given to `register`
  /// Kept as read, for the caller to drop and count: a sensor's frame (an organised cloud holds
  /// NaN where a pixel had no return), whose finite points are still good (docs/design.md §9).
  kKeep,
};

/// PLY (ascii, binary_little_endian or binary_big_endian 1.0; LF or CRLF). Reads x, y, z of the
/// `vertex` element (any scalar type), plus nx, ny, nz when all three are present; every other
/// property and element is skipped. chain_ids is left empty.
registration::PointCloud ReadPly(const std::filesystem::path& path,
                                 NonFinite non_finite = NonFinite::kReject);

/// ReadPly on bytes already read; `path` only names the file in messages. Same errors; never
/// allocates more than the data can hold, whatever counts the header claims.
registration::PointCloud ParsePly(std::string_view data, const std::filesystem::path& path,
                                  NonFinite non_finite = NonFinite::kReject);

/// Writes a PLY with `double` x y z (and nx ny nz when the cloud has normals), binary little
/// endian or ascii. Atomic: written to `<path>.tmp-XXXXXX`, then renamed over `path`.
/// Throws IoError if the file cannot be written, std::invalid_argument if an optional
/// attribute is neither empty nor as long as the points.
void WritePly(const std::filesystem::path& path, const registration::PointCloud& cloud,
              bool binary = true);

/// Writes the .xyz format read by ReadXyz (shortest round-trip decimal text, LF endings), with a
/// blank line wherever chain_ids changes. Atomic like WritePly; same errors.
/// Reading back preserves points, normals and the chain partition; chain ids are renumbered
/// 0, 1, 2, ... in file order.
void WriteXyz(const std::filesystem::path& path, const registration::PointCloud& cloud);

}  // namespace rovermap::io
