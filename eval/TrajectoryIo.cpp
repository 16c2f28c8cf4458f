#include "eval/TrajectoryIo.hpp"

#include <Eigen/SVD>
#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"

namespace rovermap::eval {
namespace {

constexpr int kTumColumns = 8;
constexpr int kKittiColumns = 12;

std::string Where(const std::filesystem::path& path, std::size_t line) {
  return path.string() + ":" + std::to_string(line) + ": ";
}

// The numbers of one line (comment and CR stripped); throws on a non-numeric or non-finite one.
std::vector<double> ParseNumbers(const std::string& text, const std::string& where) {
  std::vector<double> values;
  std::istringstream tokens(text);
  for (std::string token; tokens >> token;) {
    double value = 0.0;
    const char* first = token.data();
    const char* last = token.data() + token.size();
    if (token.size() > 1 && token[0] == '+') ++first;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || ptr != last)
      throw io::IoError(where + "non-numeric value '" + token + "'");
    if (!std::isfinite(value)) throw io::IoError(where + "non-finite value '" + token + "'");
    values.push_back(value);
  }
  return values;
}

Eigen::Isometry3d TumPose(const std::vector<double>& v, const std::string& where) {
  Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // file order x y z w (DESIGN.md §3)
  if (std::abs(q.norm() - 1.0) > 1e-3)
    throw io::IoError(where + "quaternion norm " + std::to_string(q.norm()) + " is not 1");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
  return T;
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
  const std::string contents = io::ReadWholeFile(path);
  Trajectory trajectory;
  trajectory.file = path.string();
  std::istringstream lines(contents);
  std::size_t line_number = 0;
  for (std::string line; std::getline(lines, line);) {
    ++line_number;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    const std::string where = Where(path, line_number);
    const std::vector<double> values = ParseNumbers(line, where);
    if (values.empty()) continue;
    const int columns = static_cast<int>(values.size());
    if (format == TrajectoryFormat::kAuto) {
      if (columns == kTumColumns)
        format = TrajectoryFormat::kTum;
      else if (columns == kKittiColumns)
        format = TrajectoryFormat::kKitti;
      else
        throw io::IoError(where + std::to_string(columns) +
                          " numbers: expected 8 (TUM) or 12 (KITTI)");
    }
    if (format == TrajectoryFormat::kTum) {
      if (columns != kTumColumns)
        throw io::IoError(where + std::to_string(columns) +
                          " numbers: expected 8 (TUM: timestamp tx ty tz qx qy qz qw)");
      if (!trajectory.timestamps_s.empty() && values[0] <= trajectory.timestamps_s.back())
        throw io::IoError(where + "timestamp " + std::to_string(values[0]) +
                          " is not after the previous one");
      trajectory.timestamps_s.push_back(values[0]);
      trajectory.poses.push_back(TumPose(values, where));
    } else {
      if (columns != kKittiColumns)
        throw io::IoError(where + std::to_string(columns) +
                          " numbers: expected 12 (KITTI: row-major 3x4 [R | t])");
      trajectory.poses.push_back(KittiPose(values, where));
    }
  }
  if (trajectory.poses.empty()) throw io::IoError(path.string() + ": no poses in the file");
  trajectory.format = format;
  return trajectory;
}

}  // namespace rovermap::eval
