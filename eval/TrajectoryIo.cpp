#include "eval/TrajectoryIo.hpp"

#include <Eigen/SVD>
#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "io/Tum.hpp"

namespace rovermap::eval {
namespace {

constexpr std::size_t kTumColumns = 8;
constexpr std::size_t kKittiColumns = 12;

std::string Where(const std::filesystem::path& path, std::size_t line) {
  return path.string() + ":" + std::to_string(line) + ": ";
}

// The numbers of one line (comment and CR stripped); throws on a non-numeric or non-finite one
// with io::ReadTum's wording.
std::vector<double> ParseNumbers(const std::string& text, const std::string& where) {
  std::vector<double> values;
  std::istringstream tokens(text);
  for (std::string token; tokens >> token;) {
    double value = 0.0;
    const char* first = token.data();
    const char* last = token.data() + token.size();
    if (token.size() > 1 && token[0] == '+') ++first;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || ptr != last || !std::isfinite(value))
      throw io::IoError(where + "not a finite number '" + token + "'");
    values.push_back(value);
  }
  return values;
}

// Calls visit(values, where) for every line holding numbers until it returns false.
template <typename Visit>
void ForEachDataLine(const std::string& contents, const std::filesystem::path& path, Visit visit) {
  std::istringstream lines(contents);
  std::size_t line_number = 0;
  for (std::string line; std::getline(lines, line);) {
    ++line_number;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    const std::string where = Where(path, line_number);
    const std::vector<double> values = ParseNumbers(line, where);
    if (!values.empty() && !visit(values, where)) return;
  }
}

// The format of the first data line (8 numbers: TUM, 12: KITTI); TUM for a file without one.
TrajectoryFormat DetectFormat(const std::string& contents, const std::filesystem::path& path) {
  TrajectoryFormat format = TrajectoryFormat::kTum;
  ForEachDataLine(contents, path, [&](const std::vector<double>& values, const std::string& where) {
    if (values.size() == kKittiColumns)
      format = TrajectoryFormat::kKitti;
    else if (values.size() != kTumColumns)
      throw io::IoError(where + std::to_string(values.size()) +
                        " numbers: expected 8 (TUM) or 12 (KITTI)");
    return false;
  });
  return format;
}

Eigen::Isometry3d KittiPose(const std::vector<double>& v, const std::string& where) {
  Eigen::Matrix3d R;
  R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
  const double orthogonality =
      (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthogonality > 1e-3 || R.determinant() <= 0.0)
    throw io::IoError(where + "the 3x3 part is not a rotation matrix");
  // Nearest rotation in the Frobenius norm: U Vᵀ of the SVD (det > 0 checked above).
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixU() * svd.matrixV().transpose();
  T.translation() = Eigen::Vector3d(v[3], v[7], v[11]);
  return T;
}

}  // namespace

std::string ToString(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kAuto:
      return "auto";
    case TrajectoryFormat::kTum:
      return "tum";
    case TrajectoryFormat::kKitti:
      return "kitti";
  }
  return "auto";
}

TrajectoryFormat ParseTrajectoryFormat(const std::string& text) {
  for (TrajectoryFormat f :
       {TrajectoryFormat::kAuto, TrajectoryFormat::kTum, TrajectoryFormat::kKitti})
    if (ToString(f) == text) return f;
  throw std::invalid_argument("unknown trajectory format '" + text + "' (auto|tum|kitti)");
}

Trajectory ReadTrajectory(const std::filesystem::path& path, TrajectoryFormat format) {
  return ParseTrajectory(io::ReadWholeFile(path), path, format);
}

Trajectory ParseTrajectory(std::string_view text, const std::filesystem::path& path,
                           TrajectoryFormat format) {
  const std::string contents(text);
  Trajectory trajectory;
  trajectory.file = path.string();
  trajectory.format = format == TrajectoryFormat::kAuto ? DetectFormat(contents, path) : format;
  if (trajectory.format == TrajectoryFormat::kTum) {
    for (const io::StampedPose& pose : io::ParseTum(contents, path)) {
      trajectory.timestamps_s.push_back(pose.timestamp);
      trajectory.poses.push_back(pose.T_world_body);
    }
  } else {
    ForEachDataLine(contents, path,
                    [&](const std::vector<double>& values, const std::string& where) {
                      if (values.size() != kKittiColumns)
                        throw io::IoError(where + std::to_string(values.size()) +
                                          " numbers: expected 12 (KITTI: row-major 3x4 [R | t])");
                      trajectory.poses.push_back(KittiPose(values, where));
                      return true;
                    });
  }
  if (trajectory.poses.empty()) throw io::IoError(path.string() + ": no poses in the file");
  return trajectory;
}

}  // namespace rovermap::eval
