#include "io/Tum.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>
#include <system_error>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "io/Rpy.hpp"

namespace rovermap::io {
namespace {

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r'; }

// The quaternion to write for `pose`, qw >= 0 (negating a quaternion gives the same matrix, to
// the bit: every term of it is a product of two components).
Eigen::Quaterniond TumQuaternion(const StampedPose& pose) {
  Eigen::Quaterniond q;
  if (pose.quaternion && RotationFromQuaternion(*pose.quaternion) == pose.T_world_body.linear()) {
    q = *pose.quaternion;
  } else {
    q = Eigen::Quaterniond(pose.T_world_body.linear()).normalized();
  }
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  return q;
}

}  // namespace

std::vector<StampedPose> ReadTum(const std::filesystem::path& path) {
  return ParseTum(ReadWholeFile(path), path);
}

std::vector<StampedPose> ParseTum(std::string_view text, const std::filesystem::path& path) {
  std::vector<StampedPose> poses;
  std::size_t start = 0;
  int line_number = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    ++line_number;
    std::string line(text.substr(start, end - start));
    start = end + 1;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);

    const std::string where = path.string() + ":" + std::to_string(line_number) + ": ";
    double v[8];
    int count = 0;
    std::size_t i = 0;
    while (true) {
      while (i < line.size() && IsSpace(line[i])) ++i;
      if (i >= line.size()) break;
      std::size_t j = i;
      while (j < line.size() && !IsSpace(line[j])) ++j;
      if (count == 8) {
        throw IoError(where + "more than 8 columns (expected timestamp tx ty tz qx qy qz qw)");
      }
      double value = 0.0;
      const char* first = line.data() + i;
      if (*first == '+') ++first;
      const auto [ptr, ec] = std::from_chars(first, line.data() + j, value);
      if (ec != std::errc() || ptr != line.data() + j || !std::isfinite(value)) {
        throw IoError(where + "not a finite number '" + line.substr(i, j - i) + "'");
      }
      v[count++] = value;
      i = j;
    }
    if (count == 0) continue;
    if (count != 8) {
      throw IoError(where + std::to_string(count) +
                    " columns, expected 8 (timestamp tx ty tz qx qy qz qw)");
    }
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    const double norm = q.norm();
    if (std::abs(norm - 1.0) > 1e-3) {
      throw IoError(where + "quaternion is not unit length (norm " + std::to_string(norm) + ")");
    }
    if (!poses.empty() && !(v[0] > poses.back().timestamp)) {
      throw IoError(where + "timestamp " + std::to_string(v[0]) +
                    " is not after the previous one (line " + std::to_string(poses.back().line) +
                    ", " + std::to_string(poses.back().timestamp) + ")");
    }
    StampedPose pose;
    pose.timestamp = v[0];
    pose.T_world_body.linear() = RotationFromQuaternion(q);
    pose.T_world_body.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    pose.line = line_number;
    pose.quaternion = q;
    poses.push_back(pose);
  }
  return poses;
}

void WriteTum(const std::filesystem::path& path, const std::vector<StampedPose>& poses) {
  std::string text = "# timestamp tx ty tz qx qy qz qw\n";
  char buffer[512];
  for (const StampedPose& pose : poses) {
    const Eigen::Quaterniond q = TumQuaternion(pose);
    const Eigen::Vector3d& t = pose.T_world_body.translation();
    std::snprintf(buffer, sizeof(buffer), "%.9f %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n",
                  pose.timestamp, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
    text += buffer;
  }
  WriteFileAtomically(path, text);
}

}  // namespace rovermap::io
