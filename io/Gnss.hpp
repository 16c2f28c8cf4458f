#pragma once
// GNSS fixes beside a sequence: gnss.csv (docs/design.md §4, docs/graph.md), one fix per line,
//   timestamp,latitude,longitude,altitude,sigma_east,sigma_north,sigma_up
// in seconds (the clock of odometry.tum), degrees, metres (ellipsoidal height) and metres (1σ).

#include <Eigen/Core>
#include <filesystem>
#include <string_view>
#include <vector>

namespace rovermap::io {

/// One fix of the receiver's antenna.
struct GnssFix {
  double timestamp = 0.0;      ///< [s]
  double latitude_deg = 0.0;   ///< [deg] in [-90, 90]
  double longitude_deg = 0.0;  ///< [deg] in [-180, 180]
  double altitude_m = 0.0;     ///< [m] ellipsoidal height
  /// [m] 1σ east, north, up (a NavSatFix's position_covariance diagonal, square-rooted); > 0.
  Eigen::Vector3d sigma_enu_m = Eigen::Vector3d::Ones();
  int line = 0;  ///< 1-based line in the file it was read from (0 if not read)
};

/// The header line gnss.csv starts with.
inline constexpr std::string_view kGnssCsvHeader =
    "timestamp,latitude,longitude,altitude,sigma_east,sigma_north,sigma_up";

/// Reads gnss.csv: the header line, then 7 comma-separated numbers per line; `#` comments and
/// blank lines ignored, LF or CRLF.
/// @throw IoError "FILE:LINE: reason" if the file is unreadable, the header is not
///        kGnssCsvHeader, a line does not hold 7 finite numbers, a latitude or longitude is out
///        of range, a σ is not > 0, or the timestamps are not strictly increasing.
std::vector<GnssFix> ReadGnssCsv(const std::filesystem::path& path);

/// ReadGnssCsv on text already read; `path` only names the file in messages.
std::vector<GnssFix> ParseGnssCsv(std::string_view text, const std::filesystem::path& path);

/// Writes gnss.csv atomically (full double precision). @throw IoError if it cannot be written.
void WriteGnssCsv(const std::filesystem::path& path, const std::vector<GnssFix>& fixes);

}  // namespace rovermap::io
