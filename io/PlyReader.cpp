// PLY reading for ReadPly (declared in io/PointCloudIo.hpp).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "io/PointCloudIo.hpp"
#include "io/detail/TextParse.hpp"

namespace rovermap::io {
namespace {

using detail::Fail;
using detail::Quote;
using registration::PointCloud;

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  // the item type for lists
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;  // lists only
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::size_t data_offset = 0;   // first byte after the end_header line
  std::size_t header_lines = 0;  // lines up to and including end_header
};

// The roles of the vertex properties we keep; kNone for everything else.
constexpr int kNone = -1;
constexpr int kRoleCount = 6;  // x y z nx ny nz
constexpr std::array<std::string_view, kRoleCount> kRoleNames = {"x", "y", "z", "nx", "ny", "nz"};

std::optional<PlyType> ParseType(std::string_view name) {
  if (name == "char" || name == "int8") return PlyType::kInt8;
  if (name == "uchar" || name == "uint8") return PlyType::kUint8;
  if (name == "short" || name == "int16") return PlyType::kInt16;
  if (name == "ushort" || name == "uint16") return PlyType::kUint16;
  if (name == "int" || name == "int32") return PlyType::kInt32;
  if (name == "uint" || name == "uint32") return PlyType::kUint32;
  if (name == "float" || name == "float32") return PlyType::kFloat32;
  if (name == "double" || name == "float64") return PlyType::kFloat64;
  return std::nullopt;
}

std::size_t TypeSize(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 8;
}

bool IsIntegral(PlyType type) { return type != PlyType::kFloat32 && type != PlyType::kFloat64; }

PlyHeader ParseHeader(const std::filesystem::path& path, std::string_view data) {
  detail::LineCursor cursor(data);
  std::string_view line;
  std::vector<std::string_view> tokens;

  cursor.Next(&line);
  detail::Tokenize(line, &tokens);
  if (tokens.size() != 1 || tokens[0] != "ply") {
    Fail(path, 1, "not a PLY file (first line is not 'ply')");
  }

  PlyHeader header;
  bool have_format = false;
  while (cursor.Next(&line)) {
    const std::size_t line_no = cursor.LineNumber();
    detail::Tokenize(line, &tokens);
    if (tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    if (keyword == "comment" || keyword == "obj_info") continue;

    if (keyword == "end_header") {
      if (!have_format) Fail(path, line_no, "PLY header has no 'format' line");
      header.data_offset = cursor.Offset();
      header.header_lines = line_no;
      return header;
    }
    if (keyword == "format") {
      if (have_format) Fail(path, line_no, "duplicate 'format' line");
      if (tokens.size() != 3) Fail(path, line_no, "expected 'format TYPE 1.0'");
      if (tokens[1] == "ascii") {
        header.format = PlyFormat::kAscii;
      } else if (tokens[1] == "binary_little_endian") {
        header.format = PlyFormat::kBinaryLittleEndian;
      } else if (tokens[1] == "binary_big_endian") {
        header.format = PlyFormat::kBinaryBigEndian;
      } else {
        Fail(path, line_no, "unknown PLY format " + Quote(tokens[1]));
      }
      if (tokens[2] != "1.0") Fail(path, line_no, "unsupported PLY version " + Quote(tokens[2]));
      have_format = true;
    } else if (keyword == "element") {
      if (tokens.size() != 3) Fail(path, line_no, "expected 'element NAME COUNT'");
      PlyElement element;
      element.name = std::string(tokens[1]);
      if (!detail::ParseUnsigned(tokens[2], &element.count)) {
        Fail(path, line_no, "invalid element count " + Quote(tokens[2]));
      }
      for (const PlyElement& other : header.elements) {
        if (other.name == element.name)
          Fail(path, line_no, "duplicate element " + Quote(tokens[1]));
      }
      header.elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header.elements.empty()) Fail(path, line_no, "property before any element");
      PlyProperty property;
      std::string_view name;
      if (tokens.size() >= 2 && tokens[1] == "list") {
        if (tokens.size() != 5)
          Fail(path, line_no, "expected 'property list COUNT_TYPE TYPE NAME'");
        const auto count_type = ParseType(tokens[2]);
        const auto item_type = ParseType(tokens[3]);
        if (!count_type) Fail(path, line_no, "unknown property type " + Quote(tokens[2]));
        if (!item_type) Fail(path, line_no, "unknown property type " + Quote(tokens[3]));
        if (!IsIntegral(*count_type)) {
          Fail(path, line_no, "list count type must be an integer type, not " + Quote(tokens[2]));
        }
        property.is_list = true;
        property.count_type = *count_type;
        property.type = *item_type;
        name = tokens[4];
      } else {
        if (tokens.size() != 3) Fail(path, line_no, "expected 'property TYPE NAME'");
        const auto type = ParseType(tokens[1]);
        if (!type) Fail(path, line_no, "unknown property type " + Quote(tokens[1]));
        property.type = *type;
        name = tokens[2];
      }
      property.name = std::string(name);
      PlyElement& element = header.elements.back();
      for (const PlyProperty& other : element.properties) {
        if (other.name == property.name) Fail(path, line_no, "duplicate property " + Quote(name));
      }
      element.properties.push_back(std::move(property));
    } else {
      Fail(path, line_no, "unknown PLY header keyword " + Quote(keyword));
    }
  }
  Fail(path, cursor.LineNumber(), "PLY header has no 'end_header' line");
}

// Which role (index into kRoleNames) each vertex property plays, and whether normals are read.
struct VertexLayout {
  std::vector<int> roles;
  bool has_normals = false;
};

VertexLayout MakeVertexLayout(const std::filesystem::path& path, const PlyElement& vertex) {
  std::array<int, kRoleCount> found;
  found.fill(kNone);
  for (std::size_t p = 0; p < vertex.properties.size(); ++p) {
    for (int r = 0; r < kRoleCount; ++r) {
      if (vertex.properties[p].name == kRoleNames[r]) found[r] = static_cast<int>(p);
    }
  }
  for (int r = 0; r < 3; ++r) {
    if (found[r] == kNone) {
      Fail(path, 0, "vertex element has no property " + Quote(kRoleNames[r]));
    }
    if (vertex.properties[found[r]].is_list) {
      Fail(path, 0, "vertex property " + Quote(kRoleNames[r]) + " is a list, not a scalar");
    }
  }
  VertexLayout layout;
  layout.has_normals = true;
  for (int r = 3; r < kRoleCount; ++r) {
    if (found[r] == kNone || vertex.properties[found[r]].is_list) layout.has_normals = false;
  }
  const int used_roles = layout.has_normals ? kRoleCount : 3;
  layout.roles.assign(vertex.properties.size(), kNone);
  for (int r = 0; r < used_roles; ++r) layout.roles[found[r]] = r;
  return layout;
}

void AddVertex(PointCloud* cloud, const double* values, bool has_normals) {
  cloud->points.emplace_back(values[0], values[1], values[2]);
  if (has_normals) cloud->normals.emplace_back(values[3], values[4], values[5]);
}

const char* NonFiniteWhat(int role) {
  return role < 3 ? "non-finite coordinate " : "non-finite normal ";
}

// ---- ascii ----------------------------------------------------------------------------------

PointCloud ReadAsciiBody(const std::filesystem::path& path, std::string_view data,
                         const PlyHeader& header, std::size_t vertex_index,
                         const VertexLayout& layout, NonFinite non_finite) {
  detail::LineCursor cursor(data, header.data_offset, header.header_lines);
  std::string_view line;
  // Next non-blank line; false at end of file.
  const auto next_line = [&]() {
    while (cursor.Next(&line)) {
      for (char c : line) {
        if (!detail::IsBlank(c)) return true;
      }
    }
    return false;
  };

  // Elements before the vertices: one line per instance, content not needed.
  for (std::size_t e = 0; e < vertex_index; ++e) {
    const PlyElement& element = header.elements[e];
    if (element.properties.empty()) continue;  // such instances occupy no text
    for (std::uint64_t i = 0; i < element.count; ++i) {
      if (!next_line()) {
        Fail(path, cursor.LineNumber(),
             "expected " + std::to_string(element.count) + " " + Quote(element.name) +
                 " elements, found " + std::to_string(i));
      }
    }
  }

  const PlyElement& vertex = header.elements[vertex_index];
  bool has_lists = false;
  for (const PlyProperty& property : vertex.properties) has_lists |= property.is_list;
  const std::string expected_values = std::to_string(vertex.properties.size());

  PointCloud cloud;
  // Never trust the header's count for allocation: a vertex line holds at least 6 bytes.
  const auto capacity = std::min<std::uint64_t>(vertex.count, data.size() / 6 + 1);
  cloud.points.reserve(capacity);
  if (layout.has_normals) cloud.normals.reserve(capacity);

  std::vector<std::string_view> tokens;
  double values[kRoleCount] = {};
  for (std::uint64_t i = 0; i < vertex.count; ++i) {
    if (!next_line()) {
      Fail(path, cursor.LineNumber(),
           "expected " + std::to_string(vertex.count) + " vertices, found " + std::to_string(i));
    }
    const std::size_t line_no = cursor.LineNumber();
    detail::Tokenize(line, &tokens);
    const auto wrong_count = [&]() {
      Fail(path, line_no,
           "expected " + (has_lists ? std::string("the header's") : expected_values) +
               " values for vertex " + std::to_string(i) + ", found " +
               std::to_string(tokens.size()));
    };
    std::size_t t = 0;
    for (std::size_t p = 0; p < vertex.properties.size(); ++p) {
      if (t >= tokens.size()) wrong_count();
      if (vertex.properties[p].is_list) {
        std::uint64_t length = 0;
        if (!detail::ParseUnsigned(tokens[t], &length)) {
          Fail(path, line_no, "invalid list length " + Quote(tokens[t]));
        }
        if (length > tokens.size() - t - 1) wrong_count();
        t += 1 + static_cast<std::size_t>(length);
        continue;
      }
      const int role = layout.roles[p];
      if (role != kNone) {
        double& value = values[role];
        switch (detail::ParseDouble(tokens[t], &value)) {
          case detail::NumberStatus::kOk:
            break;
          case detail::NumberStatus::kInvalid:
            Fail(path, line_no, "non-numeric value " + Quote(tokens[t]));
          case detail::NumberStatus::kOutOfRange:
            Fail(path, line_no, "value out of range " + Quote(tokens[t]));
        }
        if (non_finite == NonFinite::kReject && !std::isfinite(value)) {
          Fail(path, line_no, NonFiniteWhat(role) + Quote(tokens[t]));
        }
      }
      ++t;
    }
    if (t != tokens.size()) wrong_count();
    AddVertex(&cloud, values, layout.has_normals);
  }

  // Extra lines after a trailing vertex element mean the header undercounts the vertices.
  if (vertex_index + 1 == header.elements.size() && next_line()) {
    Fail(path, cursor.LineNumber(),
         "unexpected data after the " + std::to_string(vertex.count) +
             " vertices declared in the header");
  }
  return cloud;
}

// ---- binary ---------------------------------------------------------------------------------

class BinaryReader {
 public:
  BinaryReader(std::string_view data, std::size_t offset, bool big_endian)
      : data_(reinterpret_cast<const unsigned char*>(data.data())),
        size_(data.size()),
        offset_(offset),
        big_endian_(big_endian) {}

  std::size_t Remaining() const { return size_ - offset_; }

  // False (and nothing consumed) if fewer than `bytes` remain.
  bool Skip(std::uint64_t bytes) {
    if (bytes > Remaining()) return false;
    offset_ += static_cast<std::size_t>(bytes);
    return true;
  }

  // Reads one scalar as double; false if the data ends first.
  bool Read(PlyType type, double* value) {
    std::uint64_t bits = 0;
    if (!Load(TypeSize(type), &bits)) return false;
    switch (type) {
      case PlyType::kInt8:
        *value = static_cast<std::int8_t>(static_cast<std::uint8_t>(bits));
        break;
      case PlyType::kUint8:
        *value = static_cast<std::uint8_t>(bits);
        break;
      case PlyType::kInt16:
        *value = static_cast<std::int16_t>(static_cast<std::uint16_t>(bits));
        break;
      case PlyType::kUint16:
        *value = static_cast<std::uint16_t>(bits);
        break;
      case PlyType::kInt32:
        *value = static_cast<std::int32_t>(static_cast<std::uint32_t>(bits));
        break;
      case PlyType::kUint32:
        *value = static_cast<std::uint32_t>(bits);
        break;
      case PlyType::kFloat32: {
        const auto narrow = static_cast<std::uint32_t>(bits);
        float f = 0;
        std::memcpy(&f, &narrow, sizeof(f));
        *value = f;
        break;
      }
      case PlyType::kFloat64:
        std::memcpy(value, &bits, sizeof(*value));
        break;
    }
    return true;
  }

 private:
  // Assembles the bytes in the file's order, so the host's byte order never matters.
  bool Load(std::size_t bytes, std::uint64_t* bits) {
    if (bytes > Remaining()) return false;
    const unsigned char* p = data_ + offset_;
    std::uint64_t v = 0;
    for (std::size_t k = 0; k < bytes; ++k) {
      v = (v << 8) | p[big_endian_ ? k : bytes - 1 - k];
    }
    offset_ += bytes;
    *bits = v;
    return true;
  }

  const unsigned char* data_;
  std::size_t size_;
  std::size_t offset_;
  bool big_endian_;
};

// Skips one list property; false if the data ends first. A negative length is an error.
bool SkipList(const std::filesystem::path& path, BinaryReader* reader,
              const PlyProperty& property) {
  double raw_length = 0;  // exact: count types are integers of at most 32 bits
  if (!reader->Read(property.count_type, &raw_length)) return false;
  if (raw_length < 0) Fail(path, 0, "negative list length in property " + Quote(property.name));
  const auto length = static_cast<std::uint64_t>(raw_length);
  const std::size_t item_bytes = TypeSize(property.type);
  // Division keeps a huge length from overflowing the byte count.
  if (length > reader->Remaining() / item_bytes) return false;
  return reader->Skip(length * item_bytes);
}

PointCloud ReadBinaryBody(const std::filesystem::path& path, std::string_view data,
                          const PlyHeader& header, std::size_t vertex_index,
                          const VertexLayout& layout, NonFinite non_finite) {
  BinaryReader reader(data, header.data_offset, header.format == PlyFormat::kBinaryBigEndian);

  for (std::size_t e = 0; e < vertex_index; ++e) {
    const PlyElement& element = header.elements[e];
    const auto truncated = [&](std::uint64_t found) {
      Fail(path, 0,
           "truncated binary data: expected " + std::to_string(element.count) + " " +
               Quote(element.name) + " elements, found " + std::to_string(found));
    };
    bool fixed_size = true;
    std::uint64_t instance_bytes = 0;
    for (const PlyProperty& property : element.properties) {
      fixed_size &= !property.is_list;
      instance_bytes += TypeSize(property.type);
    }
    if (fixed_size) {
      // One bounds check for the whole element instead of a loop that could be 2^64 long.
      if (instance_bytes == 0) continue;
      if (element.count > reader.Remaining() / instance_bytes) {
        truncated(reader.Remaining() / instance_bytes);
      }
      reader.Skip(element.count * instance_bytes);
      continue;
    }
    // Every instance consumes at least one byte (a list length), so this loop ends with the data.
    for (std::uint64_t i = 0; i < element.count; ++i) {
      for (const PlyProperty& property : element.properties) {
        const bool ok = property.is_list ? SkipList(path, &reader, property)
                                         : reader.Skip(TypeSize(property.type));
        if (!ok) truncated(i);
      }
    }
  }

  const PlyElement& vertex = header.elements[vertex_index];
  std::uint64_t min_vertex_bytes = 0;
  for (const PlyProperty& property : vertex.properties) {
    min_vertex_bytes += TypeSize(property.is_list ? property.count_type : property.type);
  }
  const auto truncated = [&](std::uint64_t found) {
    Fail(path, 0,
         "truncated binary data: expected " + std::to_string(vertex.count) + " vertices, found " +
             std::to_string(found));
  };
  // Checked before allocating so that a lying header cannot request a huge buffer.
  if (vertex.count > reader.Remaining() / min_vertex_bytes) {
    truncated(reader.Remaining() / min_vertex_bytes);
  }

  PointCloud cloud;
  cloud.points.reserve(vertex.count);
  if (layout.has_normals) cloud.normals.reserve(vertex.count);
  double values[kRoleCount] = {};
  for (std::uint64_t i = 0; i < vertex.count; ++i) {
    for (std::size_t p = 0; p < vertex.properties.size(); ++p) {
      const PlyProperty& property = vertex.properties[p];
      if (property.is_list) {
        if (!SkipList(path, &reader, property)) truncated(i);
        continue;
      }
      const int role = layout.roles[p];
      if (role == kNone) {
        if (!reader.Skip(TypeSize(property.type))) truncated(i);
        continue;
      }
      double& value = values[role];
      if (!reader.Read(property.type, &value)) truncated(i);
      if (non_finite == NonFinite::kReject && !std::isfinite(value)) {
        Fail(path, 0,
             std::string(NonFiniteWhat(role)) + "in vertex " + std::to_string(i) + " (" +
                 std::string(kRoleNames[role]) + " = " + std::to_string(value) + ")");
      }
    }
    AddVertex(&cloud, values, layout.has_normals);
  }
  return cloud;
}

}  // namespace

registration::PointCloud ReadPly(const std::filesystem::path& path, NonFinite non_finite) {
  return ParsePly(ReadWholeFile(path), path, non_finite);
}

registration::PointCloud ParsePly(std::string_view data, const std::filesystem::path& path,
                                  NonFinite non_finite) {
  if (data.empty()) Fail(path, 0, "empty file");
  const PlyHeader header = ParseHeader(path, data);

  std::size_t vertex_index = header.elements.size();
  for (std::size_t e = 0; e < header.elements.size(); ++e) {
    if (header.elements[e].name == "vertex") vertex_index = e;
  }
  if (vertex_index == header.elements.size()) Fail(path, 0, "PLY has no 'vertex' element");
  const PlyElement& vertex = header.elements[vertex_index];
  const VertexLayout layout = MakeVertexLayout(path, vertex);
  if (vertex.count == 0) Fail(path, 0, "no points (the vertex element is empty)");

  // Elements after the vertices (faces, range grids) are never read.
  if (header.format == PlyFormat::kAscii) {
    return ReadAsciiBody(path, data, header, vertex_index, layout, non_finite);
  }
  return ReadBinaryBody(path, data, header, vertex_index, layout, non_finite);
}

}  // namespace rovermap::io
