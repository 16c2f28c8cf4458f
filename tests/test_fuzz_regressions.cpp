// The fuzz targets' inputs replayed in the normal suite (no clang needed): every seed of
// tests/fuzz/corpus/<target>/ parses, every input a fuzzer found (tests/fuzz/regressions/
// <target>/) is parsed or rejected with the parser's typed error. Then the bounds that keep a
// small input from making the program allocate without limit.
#include <cpl_string.h>
#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>
#include <vector>

#include "config/Config.hpp"
#include "config/ConfigError.hpp"
#include "io/GeoTiff.hpp"
#include "io/IoError.hpp"
#include "io/PointCloudIo.hpp"
#include "io/SequenceYaml.hpp"
#include "tests/fuzz/FuzzEntries.hpp"
#include "tests/support/ErrorText.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap::fuzz {
namespace {

namespace fs = std::filesystem;

const fs::path kFuzzDir = fs::path(ROVERMAP_SOURCE_DIR) / "tests" / "fuzz";

struct Target {
  const char* name;  // tests/fuzz/fuzz_<name>.cpp
  Outcome (*entry)(std::string_view);
};

const Target kTargets[] = {{"ply", Ply},
                           {"xyz", Xyz},
                           {"tum", Tum},
                           {"kitti", Kitti},
                           {"sequence_yaml", SequenceYaml},
                           {"config", ConfigFile},
                           {"set", SetOverrides},
                           {"odom", Odom},
                           {"geotiff", GeoTiff},
                           {"cdr", Cdr},
                           {"mcap", Mcap}};

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::vector<fs::path> FilesIn(const fs::path& dir) {
  std::vector<fs::path> files;
  if (!fs::is_directory(dir)) return files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  return files;
}

class FuzzInputs : public ::testing::TestWithParam<Target> {};

TEST_P(FuzzInputs, EveryTargetHasAFuzzerAndSeeds) {
  EXPECT_TRUE(fs::exists(kFuzzDir / (std::string("fuzz_") + GetParam().name + ".cpp")));
  EXPECT_FALSE(FilesIn(kFuzzDir / "corpus" / GetParam().name).empty());
}

// The seeds are cut from real files (datasets/, config/, the test fixtures): all valid.
TEST_P(FuzzInputs, SeedsParse) {
  for (const fs::path& file : FilesIn(kFuzzDir / "corpus" / GetParam().name)) {
    EXPECT_EQ(GetParam().entry(ReadBytes(file)), Outcome::kParsed) << file;
  }
}

// Anything else (another exception, a crash, a sanitizer report, an OOM) fails the test.
TEST_P(FuzzInputs, FindingsAreParsedOrRejected) {
  for (const fs::path& file : FilesIn(kFuzzDir / "regressions" / GetParam().name)) {
    SCOPED_TRACE(file.string());
    EXPECT_NO_THROW(GetParam().entry(ReadBytes(file)));
  }
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzInputs, ::testing::ValuesIn(kTargets),
                         [](const auto& info) { return std::string(info.param.name); });

// ---- bounds on what an input can make the program allocate --------------------------------

using rovermap::testing::Contains;
using rovermap::testing::ErrorOf;

constexpr const char* kTrillion = "1000000000000";

TEST(FuzzBounds, AsciiPlyClaimingATrillionVertices) {
  const std::string ply = "ply\nformat ascii 1.0\nelement vertex " + std::string(kTrillion) +
                          "\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
                          "1 2 3\n4 5 6\n";
  const std::string message = ErrorOf<io::IoError>([&] { io::ParsePly(ply, "huge.ply"); });
  EXPECT_TRUE(Contains(message, "huge.ply:9: expected 1000000000000 vertices, found 2"));
}

TEST(FuzzBounds, BinaryPlyClaimingATrillionVertices) {
  for (const char* format : {"binary_little_endian", "binary_big_endian"}) {
    const std::string ply = "ply\nformat " + std::string(format) + " 1.0\nelement vertex " +
                            kTrillion +
                            "\nproperty double x\nproperty double y\nproperty double z\n"
                            "end_header\n" +
                            std::string(48, '\0');
    const std::string message = ErrorOf<io::IoError>([&] { io::ParsePly(ply, "huge.ply"); });
    EXPECT_TRUE(Contains(
        message, "huge.ply: truncated binary data: expected 1000000000000 vertices, found 2"));
  }
}

std::string SequenceYamlWithCamera(const std::string& width, const std::string& height) {
  return "sensor:\n"
         "  type: stereo\n"
         "  T_body_sensor: {translation: [0, 0, 1], rotation_rpy_deg: [-90, 0, -90]}\n"
         "camera:\n"
         "  width: " +
         width +
         "\n"
         "  height: " +
         height +
         "\n"
         "  fx: 500\n  fy: 500\n  cx: 320\n  cy: 240\n  baseline: 0.2\n"
         "origin: {latitude: 10, longitude: 20, altitude: 0}\n"
         "frame_rate: 10\n";
}

TEST(FuzzBounds, SequenceYamlImageOfAMillionByAMillion) {
  const std::string message = ErrorOf<io::IoError>([] {
    io::ParseSequenceYaml(SequenceYamlWithCamera("1000000", "1000000"), "seq/sequence.yaml");
  });
  EXPECT_TRUE(Contains(message,
                       "seq/sequence.yaml:5: camera: 1000000 x 1000000 = "
                       "1000000000000 pixels, more than 1073741824"));
  // One side past OpenCV's limit is named on its own line.
  EXPECT_TRUE(Contains(ErrorOf<io::IoError>([] {
                         io::ParseSequenceYaml(SequenceYamlWithCamera("640", "2000000"),
                                               "seq/sequence.yaml");
                       }),
                       "seq/sequence.yaml:6: camera.height: must be <= 1048576 px (got 2000000)"));
  // The largest image OpenCV reads is still accepted.
  EXPECT_NO_THROW(io::ParseSequenceYaml(SequenceYamlWithCamera("32768", "32768"), "s.yaml"));
}

TEST(FuzzBounds, FrameCountThatOverflows) {
  // Past int: refused as such, with the file, line and key.
  EXPECT_TRUE(
      Contains(ErrorOf<config::ConfigError>([] {
                 config::ParseConfig("sim:\n  frames: 99999999999999999999\n", "c.yaml", {});
               }),
               "c.yaml:2: sim.frames: too large for an integer (got 99999999999999999999)"));
  EXPECT_TRUE(Contains(ErrorOf<config::ConfigError>([] {
                         config::ParseConfig("sim:\n  frames: 4294967297\n", "c.yaml", {});
                       }),
                       "c.yaml:2: sim.frames: too large for an integer (got 4294967297)"));
  // Within int, but more than `simulate` may hold in memory.
  EXPECT_TRUE(Contains(ErrorOf<config::ConfigError>(
                           [] { config::LoadConfig(std::nullopt, {"sim.frames=2147483647"}); }),
                       "sim.frames: must be in [1, 100000] (got 2147483647)"));
  // A simulated image as large as the sequence.yaml bound allows, and no larger.
  EXPECT_TRUE(Contains(
      ErrorOf<config::ConfigError>([] {
        config::LoadConfig(std::nullopt, {"sim.image_width=1000000", "sim.image_height=1000000"});
      }),
      "sim.image_height: sim.image_width x sim.image_height = 1000000000000 "
      "pixels, more than 1073741824"));
}

// A sparse GeoTIFF of a few kB whose one band would take 37 GiB as Float32.
TEST(FuzzBounds, GeoTiffClaimingTenBillionPixels) {
  GDALAllRegister();
  const fs::path path = rovermap::testing::ScratchDir() / "huge.tif";
  char** options = CSLSetNameValue(nullptr, "SPARSE_OK", "TRUE");
  options = CSLSetNameValue(options, "TILED", "YES");
  options = CSLSetNameValue(options, "BLOCKXSIZE", "4096");
  options = CSLSetNameValue(options, "BLOCKYSIZE", "4096");
  options = CSLSetNameValue(options, "BIGTIFF", "YES");
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds = driver->Create(path.c_str(), 100000, 100000, 1, GDT_Float32, options);
  CSLDestroy(options);
  ASSERT_NE(ds, nullptr);
  double transform[6] = {500000.0, 0.05, 0.0, 4000000.0, 0.0, -0.05};
  ds->SetGeoTransform(transform);
  GDALClose(ds);
  ASSERT_LT(fs::file_size(path), 64u * 1024u);

  const std::string message = ErrorOf<io::IoError>([&] { io::ReadDemGeoTiff(path); });
  EXPECT_TRUE(Contains(message, path.string() + ": 100000 x 100000 pixels, 1 band(s): reading "
                                                "needs 38211 MiB, more than the 1024 MiB"));
}

}  // namespace
}  // namespace rovermap::fuzz
