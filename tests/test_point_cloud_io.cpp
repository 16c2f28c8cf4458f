#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "io/IoError.hpp"
#include "io/PointCloudIo.hpp"
#include "registration/PointCloud.hpp"

namespace rovermap::io {
namespace {

namespace fs = std::filesystem;
using registration::PointCloud;

// ---- helpers ----------------------------------------------------------------------------------

class PointCloudIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ =
        fs::temp_directory_path() / (std::string("rovermap_io_") + info->test_suite_name() + "_" +
                                     info->name() + "_" + std::to_string(std::random_device{}()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  // Writes bytes exactly as given (no newline translation).
  fs::path Write(const std::string& name, const std::string& bytes) const {
    const fs::path path = dir_ / name;
    // Removing first: truncating a file in place makes ext4 flush it on close, which is slow.
    fs::remove(path);
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    EXPECT_TRUE(out.good()) << path;
    return path;
  }

  // The IoError message of `read(path)`; records a failure if nothing (or something else) is
  // thrown, and checks that the message starts with the path.
  static std::string ErrorOf(
      const fs::path& path,
      const std::function<PointCloud(const fs::path&)>& read = ReadPointCloud) {
    try {
      read(path);
    } catch (const IoError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind(path.string(), 0), 0u)
          << "message does not start with the path: " << message;
      return message;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "expected IoError, got: " << e.what();
      return {};
    }
    ADD_FAILURE() << "expected IoError for " << path;
    return {};
  }

  fs::path dir_;
};

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "in: " << (text)

// Expects "PATH:LINE:" at the start of the message.
#define EXPECT_AT_LINE(message, path, line) \
  EXPECT_EQ((message).rfind((path).string() + ":" + std::to_string(line) + ":", 0), 0u) << (message)

bool HostIsLittleEndian() {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

// Appends `value` in the requested byte order.
template <typename T>
void Put(std::string* out, T value, bool big_endian = false) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (big_endian == HostIsLittleEndian()) std::reverse(bytes, bytes + sizeof(T));
  out->append(reinterpret_cast<const char*>(bytes), sizeof(T));
}

void ExpectNear(const Eigen::Vector3d& actual, const Eigen::Vector3d& expected,
                double tolerance = 1e-12) {
  EXPECT_NEAR((actual - expected).norm(), 0.0, tolerance)
      << actual.transpose() << " vs " << expected.transpose();
}

fs::path BunnyPath(const std::string& name) {
  return fs::path(ROVERMAP_DATASETS_DIR) / "stanford_bunny" / name;
}

// ---- .xyz -------------------------------------------------------------------------------------

TEST_F(PointCloudIoTest, XyzCommentsCrlfAndWhitespace) {
  const fs::path path = Write("a.xyz",
                              "# x y z\r\n"
                              "1 2 3\r\n"
                              "  4.5\t-5e-1   +6 # trailing comment\r\n"
                              "7 8 9");  // no final newline
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.size(), 3u);
  ExpectNear(cloud.points[0], {1, 2, 3});
  ExpectNear(cloud.points[1], {4.5, -0.5, 6});
  ExpectNear(cloud.points[2], {7, 8, 9});
  EXPECT_FALSE(cloud.HasNormals());
  EXPECT_EQ(cloud.chain_ids, (std::vector<int>{0, 0, 0}));  // always filled for xyz
}

TEST_F(PointCloudIoTest, XyzBlankLinesSeparateChains) {
  const fs::path path = Write("chains.xyz",
                              "\n\n"  // leading blank lines start no chain
                              "0 0 0\n1 0 0\n"
                              "\n\n\n"  // several blank lines are one gap
                              "2 0 0\n"
                              " \t\r\n"  // whitespace-only is blank
                              "3 0 0\n"
                              "# a comment line does not split a chain\n"
                              "4 0 0\r\n"
                              "\r\n"
                              "5 0 0\n"
                              "\n\n");  // trailing blank lines change nothing
  const PointCloud cloud = ReadXyz(path);
  ASSERT_EQ(cloud.size(), 6u);
  EXPECT_TRUE(cloud.HasChains());
  EXPECT_EQ(cloud.chain_ids, (std::vector<int>{0, 0, 1, 2, 2, 3}));
  ExpectNear(cloud.points[5], {5, 0, 0});
}

TEST_F(PointCloudIoTest, XyzWithNormals) {
  const fs::path path = Write("n.xyz", "1 2 3 0 0 1\n4 5 6 0 1 0\n");
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.size(), 2u);
  ASSERT_TRUE(cloud.HasNormals());
  ExpectNear(cloud.points[1], {4, 5, 6});
  ExpectNear(cloud.normals[0], {0, 0, 1});
  ExpectNear(cloud.normals[1], {0, 1, 0});
}

TEST_F(PointCloudIoTest, ExtensionIsCaseInsensitive) {
  EXPECT_EQ(ReadPointCloud(Write("UPPER.XYZ", "1 2 3\n")).size(), 1u);
  EXPECT_EQ(ReadPointCloud(Write("mixed.PlY",
                                 "ply\nformat ascii 1.0\nelement vertex 1\n"
                                 "property float x\nproperty float y\n"
                                 "property float z\nend_header\n1 2 3\n"))
                .size(),
            1u);
}

TEST_F(PointCloudIoTest, XyzErrors) {
  {
    const fs::path path = Write("nonnumeric.xyz", "# c\n1 2 3\n1 abc 3\n");
    const std::string message = ErrorOf(path);
    EXPECT_AT_LINE(message, path, 3);
    EXPECT_CONTAINS(message, "non-numeric value 'abc'");
  }
  {
    const fs::path path = Write("partial.xyz", "1 2 3x\n");
    EXPECT_AT_LINE(ErrorOf(path), path, 1);
  }
  {
    const fs::path path = Write("columns.xyz", "1 2 3\r\n4 5 6 7\r\n");
    const std::string message = ErrorOf(path);
    EXPECT_AT_LINE(message, path, 2);
    EXPECT_CONTAINS(message, "expected 3 columns");
    EXPECT_CONTAINS(message, "found 4");
  }
  {
    const fs::path path = Write("mixed.xyz", "1 2 3 0 0 1\n4 5 6\n");
    EXPECT_AT_LINE(ErrorOf(path), path, 2);
  }
  {
    const fs::path path = Write("two.xyz", "\n1 2\n");
    const std::string message = ErrorOf(path);
    EXPECT_AT_LINE(message, path, 2);
    EXPECT_CONTAINS(message, "3 or 6 columns");
  }
  for (const std::string bad : {"nan", "NaN", "inf", "-inf", "infinity"}) {
    const fs::path path = Write("nonfinite.xyz", "1 2 3\n\n1 " + bad + " 3\n");
    const std::string message = ErrorOf(path);
    EXPECT_AT_LINE(message, path, 3);
    EXPECT_CONTAINS(message, "non-finite coordinate '" + bad + "'");
  }
  {
    const fs::path path = Write("nannormal.xyz", "1 2 3 0 0 nan\n");
    EXPECT_CONTAINS(ErrorOf(path), "non-finite normal");
  }
  {
    const fs::path path = Write("huge.xyz", "1 2 1e999\n");
    EXPECT_AT_LINE(ErrorOf(path), path, 1);
  }
  {
    const fs::path path = Write("empty.xyz", "");
    EXPECT_CONTAINS(ErrorOf(path), "empty file");
  }
  {
    const fs::path path = Write("comments.xyz", "# only\n\n  # comments\r\n");
    EXPECT_CONTAINS(ErrorOf(path), "no points");
  }
  {
    const fs::path path = Write("binary.xyz", std::string("\x01\xff\0\x7f 2 3\n", 9));
    EXPECT_CONTAINS(ErrorOf(path), "non-numeric value");
  }
}

TEST_F(PointCloudIoTest, FileErrors) {
  {
    const fs::path path = dir_ / "missing.xyz";
    const std::string message = ErrorOf(path);
    EXPECT_CONTAINS(message, "cannot open");
  }
  {
    const fs::path path = dir_ / "missing.ply";
    EXPECT_CONTAINS(ErrorOf(path), "cannot open");
  }
  {
    const fs::path path = dir_ / "folder.ply";
    fs::create_directories(path);
    EXPECT_CONTAINS(ErrorOf(path), "directory");
  }
  {
    const fs::path path = Write("cloud.pcd", "1 2 3\n");
    EXPECT_CONTAINS(ErrorOf(path), "unsupported point file extension '.pcd'");
  }
  {
    const fs::path path = Write("noextension", "1 2 3\n");
    EXPECT_CONTAINS(ErrorOf(path), "unsupported point file extension");
  }
}

// ---- ascii PLY --------------------------------------------------------------------------------

TEST_F(PointCloudIoTest, AsciiPlyCrlfWithOtherPropertiesAndElements) {
  const fs::path path = Write("a.ply",
                              "ply\r\n"
                              "format ascii 1.0\r\n"
                              "comment made by hand\r\n"
                              "obj_info num_cols 2\r\n"
                              "element camera 1\r\n"
                              "property float focal\r\n"
                              "element vertex 3\r\n"
                              "property uchar red\r\n"
                              "property float32 x\r\n"
                              "property float32 y\r\n"
                              "property list uchar int neighbours\r\n"
                              "property float32 z\r\n"
                              "property double nx\r\n"
                              "property double ny\r\n"
                              "property double nz\r\n"
                              "element face 1\r\n"
                              "property list uchar int vertex_indices\r\n"
                              "end_header\r\n"
                              "500\r\n"
                              "255 1 2 0 3 0 0 1 \r\n"
                              "0 -1.5 2.5e1 2 7 8 -3 0 1 0\r\n"
                              "7 0 0 1 9 1 1 0 0\r\n"
                              "3 0 1 2\r\n");
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.size(), 3u);
  ExpectNear(cloud.points[0], {1, 2, 3});
  ExpectNear(cloud.points[1], {-1.5, 25, -3});
  ExpectNear(cloud.points[2], {0, 0, 1});
  ASSERT_TRUE(cloud.HasNormals());
  ExpectNear(cloud.normals[1], {0, 1, 0});
  ExpectNear(cloud.normals[2], {1, 0, 0});
  EXPECT_FALSE(cloud.HasChains());
}

TEST_F(PointCloudIoTest, PlyNormalsOnlyWhenAllThreePresent) {
  const fs::path path = Write("partial_normals.ply",
                              "ply\nformat ascii 1.0\nelement vertex 1\n"
                              "property double x\nproperty double y\nproperty double z\n"
                              "property double nx\nproperty double ny\nend_header\n"
                              "1 2 3 0 1\n");
  const PointCloud cloud = ReadPly(path);
  ASSERT_EQ(cloud.size(), 1u);
  EXPECT_FALSE(cloud.HasNormals());
}

// Header with x y z floats and one extra vertex property, for the error cases below.
std::string AsciiHeader(int vertices, const std::string& after_vertex = "") {
  return "ply\nformat ascii 1.0\nelement vertex " + std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\n" + after_vertex + "end_header\n";
}

TEST_F(PointCloudIoTest, AsciiPlyErrors) {
  {
    const fs::path path = Write("nomagic.ply", "format ascii 1.0\nend_header\n");
    const std::string message = ErrorOf(path);
    EXPECT_AT_LINE(message, path, 1);
    EXPECT_CONTAINS(message, "not a PLY file");
  }
  {
    const fs::path path = Write("format.ply", "ply\nformat utf8 1.0\nend_header\n");
    const std::string message = ErrorOf(path);
    EXPECT_AT_LINE(message, path, 2);
    EXPECT_CONTAINS(message, "unknown PLY format 'utf8'");
  }
  {
    const fs::path path = Write("version.ply", "ply\nformat ascii 2.0\nend_header\n");
    EXPECT_AT_LINE(ErrorOf(path), path, 2);
  }
  {
    const fs::path path = Write("noformat.ply", "ply\nelement vertex 0\nend_header\n");
    EXPECT_CONTAINS(ErrorOf(path), "no 'format' line");
  }
  {
    const fs::path path = Write("type.ply",
                                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                "property quad y\nproperty float z\nend_header\n1 2 3\n");
    const std::string message = ErrorOf(path);
    EXPECT_AT_LINE(message, path, 5);
    EXPECT_CONTAINS(message, "unknown property type 'quad'");
  }
  {
    const fs::path path = Write("listtype.ply",
                                "ply\nformat ascii 1.0\nelement vertex 1\n"
                                "property list float int idx\nend_header\n");
    EXPECT_AT_LINE(ErrorOf(path), path, 4);
  }
  {
    const fs::path path = Write("keyword.ply", "ply\nformat ascii 1.0\nelemnt vertex 1\n");
    EXPECT_AT_LINE(ErrorOf(path), path, 3);
  }
  {
    const fs::path path = Write("noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\n");
    EXPECT_CONTAINS(ErrorOf(path), "no 'end_header'");
  }
  {
    const fs::path path = Write("novertex.ply",
                                "ply\nformat ascii 1.0\nelement face 1\n"
                                "property list uchar int vertex_indices\nend_header\n3 0 1 2\n");
    EXPECT_CONTAINS(ErrorOf(path), "no 'vertex' element");
  }
  {
    const fs::path path = Write("noz.ply",
                                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                "property float y\nend_header\n1 2\n");
    EXPECT_CONTAINS(ErrorOf(path), "no property 'z'");
  }
  {
    const fs::path path = Write("zero.ply", AsciiHeader(0));
    EXPECT_CONTAINS(ErrorOf(path), "no points");
  }
  {
    const fs::path path = Write("empty.ply", "");
    EXPECT_CONTAINS(ErrorOf(path), "empty file");
  }
  {
    // Header lines 1-7; vertices on lines 8-10.
    const fs::path path = Write("short.ply", AsciiHeader(5) + "1 2 3\n4 5 6\n7 8 9\n");
    const std::string message = ErrorOf(path);
    EXPECT_CONTAINS(message, "expected 5 vertices, found 3");
    EXPECT_AT_LINE(message, path, 10);
  }
  {
    // The count runs into the next element: its lines do not fit the vertex layout.
    const fs::path path =
        Write("overrun.ply",
              AsciiHeader(3, "element range_grid 2\nproperty list uchar int vertex_indices\n") +
                  "1 2 3\n4 5 6\n0\n1 1\n");
    const std::string message = ErrorOf(path);
    EXPECT_AT_LINE(message, path, 12);
    EXPECT_CONTAINS(message, "expected 3 values for vertex 2, found 1");
  }
  {
    const fs::path path = Write("undercount.ply", AsciiHeader(1) + "1 2 3\n4 5 6\n");
    const std::string message = ErrorOf(path);
    EXPECT_AT_LINE(message, path, 9);
    EXPECT_CONTAINS(message, "unexpected data after the 1 vertices");
  }
  {
    const fs::path path = Write("columns.ply", AsciiHeader(2) + "1 2 3\n4 5 6 7\n");
    EXPECT_AT_LINE(ErrorOf(path), path, 9);
  }
  {
    const fs::path path = Write("nonnumeric.ply", AsciiHeader(2) + "1 2 3\r\n4 five 6\r\n");
    const std::string message = ErrorOf(path);
    EXPECT_AT_LINE(message, path, 9);
    EXPECT_CONTAINS(message, "non-numeric value 'five'");
  }
  {
    const fs::path path = Write("nan.ply", AsciiHeader(2) + "1 2 3\nnan 5 6\n");
    const std::string message = ErrorOf(path);
    EXPECT_AT_LINE(message, path, 9);
    EXPECT_CONTAINS(message, "non-finite coordinate 'nan'");
  }
  {
    const fs::path path = Write("list.ply",
                                "ply\nformat ascii 1.0\nelement vertex 1\n"
                                "property list uchar int idx\nproperty float x\nproperty float y\n"
                                "property float z\nend_header\n9 1 2 3\n");
    EXPECT_AT_LINE(ErrorOf(path), path, 9);
  }
  {
    const fs::path path =
        Write("before.ply",
              "ply\nformat ascii 1.0\nelement face 4\nproperty uchar a\nelement vertex 1\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n1\n2\n");
    EXPECT_CONTAINS(ErrorOf(path), "expected 4 'face' elements, found 2");
  }
}

// ---- binary PLY -------------------------------------------------------------------------------

// A binary PLY with a list element before the vertices, an unused scalar and a list inside the
// vertex element, and a list element after: every skip path is exercised.
template <typename Real>
std::string BinaryPly(const std::vector<Eigen::Vector3d>& points, bool big_endian,
                      const std::string& real_name, bool normals) {
  std::string ply = "ply\n";
  ply += big_endian ? "format binary_big_endian 1.0\n" : "format binary_little_endian 1.0\n";
  ply += "comment test\nelement face 2\nproperty list uchar int vertex_indices\n";
  ply += "element vertex " + std::to_string(points.size()) + "\n";
  ply += "property " + real_name + " x\nproperty " + real_name + " y\n";
  ply += "property ushort intensity\nproperty list int short tags\n";
  ply += "property " + real_name + " z\n";
  if (normals) {
    ply += "property float nx\nproperty float ny\nproperty float nz\n";
  }
  ply += "element range_grid 3\nproperty list uchar int vertex_indices\nend_header\n";
  for (int face = 0; face < 2; ++face) {
    Put<std::uint8_t>(&ply, 3);
    for (int k = 0; k < 3; ++k) Put<std::int32_t>(&ply, k, big_endian);
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    Put<Real>(&ply, static_cast<Real>(points[i].x()), big_endian);
    Put<Real>(&ply, static_cast<Real>(points[i].y()), big_endian);
    Put<std::uint16_t>(&ply, 0xBEEF, big_endian);
    Put<std::int32_t>(&ply, static_cast<std::int32_t>(i % 3), big_endian);
    for (std::size_t k = 0; k < i % 3; ++k) Put<std::int16_t>(&ply, -7, big_endian);
    Put<Real>(&ply, static_cast<Real>(points[i].z()), big_endian);
    if (normals) {
      Put<float>(&ply, 0.0f, big_endian);
      Put<float>(&ply, 0.6f, big_endian);
      Put<float>(&ply, 0.8f, big_endian);
    }
  }
  for (int cell = 0; cell < 3; ++cell) {
    Put<std::uint8_t>(&ply, cell == 1 ? 1 : 0);
    if (cell == 1) Put<std::int32_t>(&ply, 0, big_endian);
  }
  return ply;
}

const std::vector<Eigen::Vector3d> kPoints = {
    {0.5, -1.25, 3.0}, {1e-3, 2.0, -0.0625}, {-100.0, 0.0, 7.5}, {3.0, 4.0, 5.0}};

TEST_F(PointCloudIoTest, BinaryLittleEndianFloat) {
  const PointCloud cloud =
      ReadPointCloud(Write("f.ply", BinaryPly<float>(kPoints, false, "float", true)));
  ASSERT_EQ(cloud.size(), kPoints.size());
  for (std::size_t i = 0; i < kPoints.size(); ++i) {
    ExpectNear(cloud.points[i], kPoints[i], 1e-6 * (1 + kPoints[i].norm()));
  }
  ASSERT_TRUE(cloud.HasNormals());
  ExpectNear(cloud.normals[3], {0, 0.6, 0.8}, 1e-7);
}

TEST_F(PointCloudIoTest, BinaryLittleEndianDouble) {
  const PointCloud cloud =
      ReadPointCloud(Write("d.ply", BinaryPly<double>(kPoints, false, "float64", false)));
  ASSERT_EQ(cloud.size(), kPoints.size());
  for (std::size_t i = 0; i < kPoints.size(); ++i) EXPECT_EQ(cloud.points[i], kPoints[i]);
  EXPECT_FALSE(cloud.HasNormals());
}

TEST_F(PointCloudIoTest, BinaryBigEndianDoubleAndIntegerCoordinates) {
  const PointCloud cloud =
      ReadPly(Write("be.ply", BinaryPly<double>(kPoints, true, "double", true)));
  ASSERT_EQ(cloud.size(), kPoints.size());
  for (std::size_t i = 0; i < kPoints.size(); ++i) EXPECT_EQ(cloud.points[i], kPoints[i]);

  const std::vector<Eigen::Vector3d> grid = {{-3, 4, 100}, {7, -8, 0}};
  const PointCloud shorts =
      ReadPly(Write("s.ply", BinaryPly<std::int16_t>(grid, true, "int16", false)));
  ASSERT_EQ(shorts.size(), 2u);
  EXPECT_EQ(shorts.points[0], grid[0]);
  EXPECT_EQ(shorts.points[1], grid[1]);
  const PointCloud chars =
      ReadPly(Write("c.ply", BinaryPly<std::int8_t>(grid, false, "char", false)));
  EXPECT_EQ(chars.points[1], grid[1]);
}

TEST_F(PointCloudIoTest, BinaryPlyErrors) {
  const std::string good = BinaryPly<float>(kPoints, false, "float", false);
  {
    // One byte short of the last vertex.
    const std::size_t tail = 7 + 1;  // the range_grid's 7 bytes, then 1 byte of the last vertex
    const fs::path path = Write("truncated.ply", good.substr(0, good.size() - tail));
    const std::string message = ErrorOf(path);
    EXPECT_CONTAINS(message, "truncated binary data");
    EXPECT_CONTAINS(message, "expected 4 vertices, found 3");
  }
  {
    // A header claiming far more vertices than any file could hold must not allocate them.
    std::string lying = good;
    lying.replace(lying.find("element vertex 4"), 16, "element vertex 18446744073709551615");
    const std::string message = ErrorOf(Write("huge.ply", lying));
    EXPECT_CONTAINS(message, "truncated binary data");
  }
  {
    std::string lying = good;
    lying.replace(lying.find("element face 2"), 14, "element face 9999999999");
    EXPECT_CONTAINS(ErrorOf(Write("faces.ply", lying)), "expected 9999999999 'face' elements");
  }
  {
    std::string ply =
        "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
        "property list char int idx\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n";
    Put<std::int8_t>(&ply, -2);
    for (int k = 0; k < 5; ++k) Put<float>(&ply, 1.0f);
    EXPECT_CONTAINS(ErrorOf(Write("negative.ply", ply)), "negative list length");
  }
  {
    std::string ply =
        "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
        "property double x\nproperty double y\nproperty double z\nend_header\n";
    Put<double>(&ply, 1.0);
    Put<double>(&ply, std::numeric_limits<double>::infinity());
    Put<double>(&ply, 1.0);
    const std::string message = ErrorOf(Write("inf.ply", ply));
    EXPECT_CONTAINS(message, "non-finite coordinate");
    EXPECT_CONTAINS(message, "vertex 0");
  }
  {
    const fs::path path = Write("binheader.ply",
                                "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
                                "property float x\nproperty float y\nproperty floaty z\n"
                                "end_header\n");
    EXPECT_AT_LINE(ErrorOf(path), path, 6);
  }
}

// Every prefix and many single-byte corruptions of valid files give a cloud or an IoError:
// never a crash, hang or read past the buffer (run under ASan via `make test-asan`).
// A sensor's frame keeps its non-finite points for the mapper to drop and count (kKeep); a scan
// given to `register` is refused (kReject, the default), ascii and binary alike.
TEST_F(PointCloudIoTest, PlyNonFiniteKeptOnlyWhenAsked) {
  const fs::path ascii = Write("nan.ply", AsciiHeader(3) + "1 2 3\nnan 5 6\n7 8 inf\n");
  std::string bytes =
      "ply\nformat binary_big_endian 1.0\nelement vertex 2\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n";
  for (const float v : {1.0f, std::numeric_limits<float>::quiet_NaN(), 3.0f, 4.0f, 5.0f, 6.0f}) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &v, sizeof(bits));
    for (int shift = 24; shift >= 0; shift -= 8) bytes.push_back(static_cast<char>(bits >> shift));
  }
  const fs::path binary = Write("nan_be.ply", bytes);
  for (const fs::path& path : {ascii, binary}) {
    EXPECT_CONTAINS(ErrorOf(path), "non-finite coordinate");
    const PointCloud cloud = ReadPly(path, NonFinite::kKeep);
    ASSERT_EQ(cloud.size(), path == ascii ? 3u : 2u);
    EXPECT_FALSE(cloud.points[path == ascii ? 1 : 0].allFinite());
    EXPECT_EQ(cloud.points.back(),
              path == ascii ? Eigen::Vector3d(7, 8, std::numeric_limits<double>::infinity())
                            : Eigen::Vector3d(4, 5, 6));
  }
}

TEST_F(PointCloudIoTest, TruncatedAndCorruptedFilesNeverCrash) {
  const std::vector<std::pair<std::string, std::string>> files = {
      {"b.ply", BinaryPly<float>(kPoints, false, "float", true)},
      {"be.ply", BinaryPly<double>(kPoints, true, "double", false)},
      {"a.ply", AsciiHeader(2, "element face 1\nproperty list uchar int v\n") +
                    "1 2 3\r\n4 5 6\r\n3 0 1 1\r\n"},
      {"c.xyz", "1 2 3\n\n4 5 6 # c\n"},
  };
  for (const auto& [name, bytes] : files) {
    for (std::size_t length = 0; length <= bytes.size(); ++length) {
      const fs::path path = Write(name, bytes.substr(0, length));
      try {
        ReadPointCloud(path);
      } catch (const IoError&) {
      }
    }
    std::uint32_t state = 12345;
    for (int trial = 0; trial < 400; ++trial) {
      std::string corrupted = bytes;
      state = state * 1664525u + 1013904223u;
      corrupted[state % corrupted.size()] = static_cast<char>(state >> 24);
      const fs::path path = Write(name, corrupted);
      try {
        ReadPointCloud(path);
      } catch (const IoError&) {
      }
    }
  }
}

// ---- the bundled Stanford bunny scans (CRLF ascii with a range_grid element) ------------------

TEST_F(PointCloudIoTest, ReadsBundledBunnyScans) {
  const PointCloud bun000 = ReadPointCloud(BunnyPath("bun000.ply"));
  EXPECT_EQ(bun000.size(), 40256u);
  const PointCloud bun045 = ReadPointCloud(BunnyPath("bun045.ply"));
  EXPECT_EQ(bun045.size(), 40097u);
  const PointCloud bun315 = ReadPointCloud(BunnyPath("bun315.ply"));
  EXPECT_EQ(bun315.size(), 35336u);

  EXPECT_FALSE(bun000.HasNormals());
  EXPECT_FALSE(bun000.HasChains());
  // First vertex line of bun000.ply: "-0.06325 0.0359793 0.0420873 \r".
  ExpectNear(bun000.points.front(), {-0.06325, 0.0359793, 0.0420873});
  // The bunny is about 0.15 m across.
  Eigen::Vector3d lo = bun000.points.front();
  Eigen::Vector3d hi = lo;
  for (const Eigen::Vector3d& p : bun000.points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  EXPECT_GT((hi - lo).maxCoeff(), 0.1);
  EXPECT_LT((hi - lo).maxCoeff(), 0.25);
}

TEST_F(PointCloudIoTest, BunnyWithInflatedVertexCountIsAnError) {
  std::ifstream in(BunnyPath("bun000.ply"), std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_EQ(bytes.rfind("ply\r\n", 0), 0u);
  const std::size_t at = bytes.find("element vertex 40256\r\n");
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, 20, "element vertex 40257");
  const fs::path path = Write("bun000_bad.ply", bytes);
  const std::string message = ErrorOf(path);
  EXPECT_CONTAINS(message, "for vertex 40256");
}

// ---- writing ----------------------------------------------------------------------------------

PointCloud MakeCloud(bool normals, bool chains) {
  PointCloud cloud;
  cloud.points = {{0.1, 0.2, 0.3}, {-1e-300, 5e300, 1.0 / 3.0}, {1, 2, 3}, {4, 5, 6}};
  if (normals) cloud.normals = {{0, 0, 1}, {0.6, 0.8, 0}, {1, 0, 0}, {0, -1, 0}};
  if (chains) cloud.chain_ids = {4, 4, 9, 2};
  return cloud;
}

std::size_t CountFiles(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST_F(PointCloudIoTest, PlyRoundTripBinaryAndAscii) {
  for (const bool binary : {true, false}) {
    for (const bool normals : {false, true}) {
      const PointCloud cloud = MakeCloud(normals, false);
      const fs::path path =
          dir_ / (std::string("out_") + (binary ? "b" : "a") + (normals ? "n" : "") + ".ply");
      WritePly(path, cloud, binary);
      const PointCloud back = ReadPointCloud(path);
      EXPECT_EQ(back.points, cloud.points);  // exact: float64 / shortest round-trip text
      EXPECT_EQ(back.normals, cloud.normals);
    }
  }
  EXPECT_EQ(CountFiles(dir_), 4u);  // no temporaries left behind
}

TEST_F(PointCloudIoTest, XyzRoundTripKeepsChains) {
  const PointCloud cloud = MakeCloud(true, true);
  const fs::path path = dir_ / "out.xyz";
  WriteXyz(path, cloud);
  const PointCloud back = ReadPointCloud(path);
  EXPECT_EQ(back.points, cloud.points);
  EXPECT_EQ(back.normals, cloud.normals);
  EXPECT_EQ(back.chain_ids, (std::vector<int>{0, 0, 1, 2}));  // same partition, renumbered

  WriteXyz(path, MakeCloud(false, false));  // overwrites atomically
  const PointCloud plain = ReadXyz(path);
  EXPECT_EQ(plain.points, cloud.points);
  EXPECT_FALSE(plain.HasNormals());
  EXPECT_EQ(plain.chain_ids, (std::vector<int>{0, 0, 0, 0}));
  EXPECT_EQ(CountFiles(dir_), 1u);
}

TEST_F(PointCloudIoTest, WriteErrors) {
  const fs::path path = dir_ / "no_such_dir" / "out.ply";
  try {
    WritePly(path, MakeCloud(false, false));
    ADD_FAILURE() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path.string(), 0), 0u) << e.what();
  }
  EXPECT_THROW(WriteXyz(dir_ / "no_such_dir" / "out.xyz", MakeCloud(false, false)), IoError);

  PointCloud bad = MakeCloud(true, false);
  bad.normals.pop_back();
  EXPECT_THROW(WritePly(dir_ / "bad.ply", bad), std::invalid_argument);
  EXPECT_THROW(WriteXyz(dir_ / "bad.xyz", bad), std::invalid_argument);
  EXPECT_EQ(CountFiles(dir_), 0u);
}

}  // namespace
}  // namespace rovermap::io
