#pragma once
// The parser entry points the fuzz targets drive, shared with test_fuzz_regressions.cpp so that
// a saved input replays through exactly the code the fuzzer ran. Each returns kParsed or
// kRejected (the parser's typed error); any other exception, crash or sanitizer report escapes.

#include <cpl_vsi.h>
#include <gdal.h>

#include <cstddef>
#include <cstdint>
#include <iterator>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "config/Config.hpp"
#include "config/ConfigError.hpp"
#include "eval/TrajectoryIo.hpp"
#include "io/Cdr.hpp"
#include "io/GeoTiff.hpp"
#include "io/Inbox.hpp"
#include "io/IoError.hpp"
#include "io/Mcap.hpp"
#include "io/PointCloudIo.hpp"
#include "io/SequenceYaml.hpp"
#include "io/Tum.hpp"

namespace rovermap::fuzz {

enum class Outcome { kParsed, kRejected };

// Runs `parse`; only the parser's documented error type counts as a rejection.
template <typename Error, typename Parse>
Outcome Run(const Parse& parse) {
  try {
    parse();
    return Outcome::kParsed;
  } catch (const Error&) {
    return Outcome::kRejected;
  }
}

inline Outcome Ply(std::string_view bytes) {
  return Run<io::IoError>([&] { io::ParsePly(bytes, "fuzz.ply"); });
}

inline Outcome Xyz(std::string_view bytes) {
  return Run<io::IoError>([&] { io::ParseXyz(bytes, "fuzz.xyz"); });
}

inline Outcome Tum(std::string_view bytes) {
  return Run<io::IoError>([&] { io::ParseTum(bytes, "fuzz.tum"); });
}

// `eval`'s trajectory reader with the format detected from the first line (12 numbers: KITTI,
// 8: TUM), as `--format auto` reads it.
inline Outcome Kitti(std::string_view bytes) {
  return Run<io::IoError>(
      [&] { eval::ParseTrajectory(bytes, "fuzz.txt", eval::TrajectoryFormat::kAuto); });
}

inline Outcome SequenceYaml(std::string_view bytes) {
  return Run<io::IoError>([&] { io::ParseSequenceYaml(bytes, "sequence.yaml"); });
}

inline Outcome ConfigFile(std::string_view bytes) {
  return Run<config::ConfigError>([&] { config::ParseConfig(bytes, "fuzz.yaml", {}); });
}

// `--set` values: one override per line (the last newline ends a line), applied in order as
// the command line does.
inline Outcome SetOverrides(std::string_view bytes) {
  std::vector<std::string> overrides;
  std::size_t start = 0;
  while (start < bytes.size()) {
    std::size_t end = bytes.find('\n', start);
    if (end == std::string_view::npos) end = bytes.size();
    overrides.emplace_back(bytes.substr(start, end - start));
    start = end + 1;
  }
  return Run<config::ConfigError>([&] { config::LoadConfig(std::nullopt, overrides); });
}

// The serve daemon's frames/NNNNNN.odom (and .gt): exactly one TUM line.
inline Outcome Odom(std::string_view bytes) {
  return Run<io::IoError>([&] { io::ParseFramePose(bytes, "000000.odom"); });
}

// `eval --dem`: the GeoTIFF reader on a GDAL in-memory file (no disk traffic per input).
inline Outcome GeoTiff(std::string_view bytes) {
  static const std::string kName = "/vsimem/rovermap_fuzz.tif";
  // GDAL's block cache (5 % of RAM by default) would count against -rss_limit_mb on top of what
  // the reader allocates, which is what this target bounds (ReadDemGeoTiff: 1 GiB).
  static const bool kCacheCapped = (GDALSetCacheMax64(std::int64_t{64} << 20), true);
  (void)kCacheCapped;
  std::vector<GByte> copy(bytes.begin(), bytes.end());  // GDAL wants a mutable buffer
  VSILFILE* file = VSIFileFromMemBuffer(kName.c_str(), copy.data(), copy.size(), FALSE);
  if (file == nullptr) return Outcome::kRejected;
  VSIFCloseL(file);
  struct Unlink {
    ~Unlink() { VSIUnlink(kName.c_str()); }
  } unlink;
  return Run<io::IoError>([&] { io::ReadDemGeoTiff(kName); });
}

// The CDR decoders of the ROS 2 messages rovermap reads, by type name.
struct CdrDecoder {
  const char* type;
  void (*decode)(io::bag::ByteView data);
};

// An image's or cloud's head decoder (what opening a SQLite bag reads) on the first half of the
// buffer, then the whole decoder on all of it. (The head's errors are the whole's.)
template <typename Head, typename Whole>
void HeadThenWhole(io::bag::ByteView d, Head head, Whole whole) {
  head(io::bag::ByteView{d.data, d.size / 2}, d.size, "fuzz");
  whole(d, "fuzz");
}

inline const CdrDecoder kCdrDecoders[] = {
    {"sensor_msgs/msg/Image",
     [](io::bag::ByteView d) { HeadThenWhole(d, io::cdr::DecodeImageHead, io::cdr::DecodeImage); }},
    {"sensor_msgs/msg/CompressedImage",
     [](io::bag::ByteView d) {
       HeadThenWhole(d, io::cdr::DecodeCompressedImageHead, io::cdr::DecodeCompressedImage);
     }},
    {"sensor_msgs/msg/CameraInfo",
     [](io::bag::ByteView d) { io::cdr::DecodeCameraInfo(d, "fuzz"); }},
    {"sensor_msgs/msg/PointCloud2",
     [](io::bag::ByteView d) {
       HeadThenWhole(d, io::cdr::DecodePointCloudHead, io::cdr::DecodePointCloud);
     }},
    {"nav_msgs/msg/Odometry", [](io::bag::ByteView d) { io::cdr::DecodeOdometry(d, "fuzz"); }},
    {"geometry_msgs/msg/PoseStamped",
     [](io::bag::ByteView d) { io::cdr::DecodePoseStamped(d, "fuzz"); }},
    {"tf2_msgs/msg/TFMessage", [](io::bag::ByteView d) { io::cdr::DecodeTfMessage(d, "fuzz"); }},
    {"sensor_msgs/msg/NavSatFix", [](io::bag::ByteView d) { io::cdr::DecodeNavSatFix(d, "fuzz"); }},
};

// One CDR message: the first byte picks the type (modulo their number), the rest is the buffer.
inline Outcome Cdr(std::string_view bytes) {
  if (bytes.empty()) return Outcome::kRejected;
  const CdrDecoder& decoder =
      kCdrDecoders[static_cast<unsigned char>(bytes[0]) % std::size(kCdrDecoders)];
  const auto* data = reinterpret_cast<const std::uint8_t*>(bytes.data()) + 1;
  return Run<io::IoError>([&] { decoder.decode({data, bytes.size() - 1}); });
}

// An MCAP file in memory: its channels, every message read front to back (or by the chunk
// indexes) and decoded by its schema when rovermap reads that type, then each read again by
// its location, as a bag's frames are.
inline Outcome Mcap(std::string_view bytes) {
  return Run<io::IoError>([&] {
    io::mcap::McapReader reader(std::string(bytes), "fuzz.mcap");
    std::set<std::uint16_t> ids;
    for (const auto& [id, channel] : reader.channels()) ids.insert(id);
    std::vector<io::mcap::Location> seen;
    reader.ForEachMessage(ids, [&](const io::mcap::Message& m) {
      const std::string& type = reader.channels().at(m.channel_id).schema_name;
      for (const CdrDecoder& decoder : kCdrDecoders) {
        if (type == decoder.type) decoder.decode(m.data);
      }
      seen.push_back(m.where);
    });
    for (const io::mcap::Location& where : seen) reader.ReadMessage(where);
  });
}

}  // namespace rovermap::fuzz
