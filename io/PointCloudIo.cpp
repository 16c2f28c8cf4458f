#include "io/PointCloudIo.hpp"

#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "io/detail/TextParse.hpp"

namespace rovermap::io {
namespace {

using detail::Fail;
using detail::Quote;
using registration::PointCloud;

// Columns of an .xyz line: x y z, or x y z nx ny nz.
constexpr std::size_t kXyzColumns = 3;
constexpr std::size_t kXyzColumnsWithNormals = 6;

}  // namespace

PointCloud ParseXyz(std::string_view data, const std::filesystem::path& path) {
  if (data.empty()) Fail(path, 0, "empty file");

  PointCloud cloud;
  // A rough guess (typical lines are 25-40 bytes); the vectors still grow if it is low.
  cloud.points.reserve(data.size() / 24 + 1);

  detail::LineCursor cursor(data);
  std::vector<std::string_view> tokens;
  std::string_view line;
  std::size_t columns = 0;       // fixed by the first point line
  std::size_t columns_line = 0;  // where it was fixed, for the error message
  int chain = 0;
  bool gap = false;
  double values[kXyzColumnsWithNormals];

  while (cursor.Next(&line)) {
    const std::size_t line_no = cursor.LineNumber();
    const bool has_comment = line.find('#') != std::string_view::npos;
    detail::Tokenize(detail::StripComment(line), &tokens);
    if (tokens.empty()) {
      // A blank line ends the current chain; comment lines do not.
      if (!has_comment && !cloud.points.empty()) gap = true;
      continue;
    }
    if (columns == 0) {
      if (tokens.size() != kXyzColumns && tokens.size() != kXyzColumnsWithNormals) {
        Fail(path, line_no,
             "expected 3 or 6 columns (x y z [nx ny nz]), found " + std::to_string(tokens.size()));
      }
      columns = tokens.size();
      columns_line = line_no;
    } else if (tokens.size() != columns) {
      Fail(path, line_no,
           "expected " + std::to_string(columns) + " columns (as on line " +
               std::to_string(columns_line) + "), found " + std::to_string(tokens.size()));
    }
    for (std::size_t i = 0; i < columns; ++i) {
      switch (detail::ParseDouble(tokens[i], &values[i])) {
        case detail::NumberStatus::kOk:
          break;
        case detail::NumberStatus::kInvalid:
          Fail(path, line_no, "non-numeric value " + Quote(tokens[i]));
        case detail::NumberStatus::kOutOfRange:
          Fail(path, line_no, "value out of range " + Quote(tokens[i]));
      }
      if (!std::isfinite(values[i])) {
        Fail(path, line_no,
             std::string(i < kXyzColumns ? "non-finite coordinate " : "non-finite normal ") +
                 Quote(tokens[i]));
      }
    }
    if (gap) {
      ++chain;
      gap = false;
    }
    cloud.points.emplace_back(values[0], values[1], values[2]);
    if (columns == kXyzColumnsWithNormals)
      cloud.normals.emplace_back(values[3], values[4], values[5]);
    cloud.chain_ids.push_back(chain);
  }
  if (cloud.points.empty()) Fail(path, 0, "no points");
  return cloud;
}

namespace {

void CheckAttributeSizes(const PointCloud& cloud) {
  const std::size_t n = cloud.points.size();
  const auto check = [n](std::size_t size, const char* name) {
    if (size != 0 && size != n) {
      throw std::invalid_argument(std::string("PointCloud::") + name + " has " +
                                  std::to_string(size) + " entries for " + std::to_string(n) +
                                  " points");
    }
  };
  check(cloud.normals.size(), "normals");
  check(cloud.covariances.size(), "covariances");
  check(cloud.chain_ids.size(), "chain_ids");
}

// Shortest decimal text that reads back to the same double.
void AppendNumber(std::string* out, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out->append(buffer, result.ptr);
}

void AppendVectorText(std::string* out, const Eigen::Vector3d& v) {
  for (int i = 0; i < 3; ++i) {
    if (i > 0) out->push_back(' ');
    AppendNumber(out, v[i]);
  }
}

// Byte order made explicit so the output is little endian on any host.
void AppendFloat64Le(std::string* out, double value) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &value, sizeof(bits));
  for (int byte = 0; byte < 8; ++byte) {
    out->push_back(static_cast<char>((bits >> (8 * byte)) & 0xffu));
  }
}

}  // namespace

registration::PointCloud ReadXyz(const std::filesystem::path& path) {
  return ParseXyz(ReadWholeFile(path), path);
}

registration::PointCloud ReadPointCloud(const std::filesystem::path& path) {
  const std::string extension = detail::ToLower(path.extension().string());
  if (extension == ".xyz") return ReadXyz(path);
  if (extension == ".ply") return ReadPly(path);
  Fail(path, 0,
       "unsupported point file extension " + Quote(path.extension().string()) +
           " (expected .xyz or .ply)");
}

void WritePly(const std::filesystem::path& path, const registration::PointCloud& cloud,
              bool binary) {
  CheckAttributeSizes(cloud);
  const bool normals = cloud.HasNormals();
  std::string out;
  out += "ply\n";
  out += binary ? "format binary_little_endian 1.0\n" : "format ascii 1.0\n";
  out += "comment written by rovermap\n";
  out += "element vertex " + std::to_string(cloud.size()) + "\n";
  out += "property double x\nproperty double y\nproperty double z\n";
  if (normals) out += "property double nx\nproperty double ny\nproperty double nz\n";
  out += "end_header\n";

  const std::size_t n = cloud.size();
  if (binary) {
    out.reserve(out.size() + n * (normals ? 48 : 24));
    for (std::size_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) AppendFloat64Le(&out, cloud.points[i][k]);
      if (normals) {
        for (int k = 0; k < 3; ++k) AppendFloat64Le(&out, cloud.normals[i][k]);
      }
    }
  } else {
    out.reserve(out.size() + n * (normals ? 120 : 60));
    for (std::size_t i = 0; i < n; ++i) {
      AppendVectorText(&out, cloud.points[i]);
      if (normals) {
        out.push_back(' ');
        AppendVectorText(&out, cloud.normals[i]);
      }
      out.push_back('\n');
    }
  }
  WriteFileAtomically(path, out);
}

void WriteXyz(const std::filesystem::path& path, const registration::PointCloud& cloud) {
  CheckAttributeSizes(cloud);
  const bool normals = cloud.HasNormals();
  const bool chains = cloud.HasChains();
  std::string out;
  out.reserve(cloud.size() * (normals ? 120 : 60));
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (chains && i > 0 && cloud.chain_ids[i] != cloud.chain_ids[i - 1]) out.push_back('\n');
    AppendVectorText(&out, cloud.points[i]);
    if (normals) {
      out.push_back(' ');
      AppendVectorText(&out, cloud.normals[i]);
    }
    out.push_back('\n');
  }
  WriteFileAtomically(path, out);
}

}  // namespace rovermap::io
