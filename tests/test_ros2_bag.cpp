// io::Ros2BagSource: ROS 2 bags written by the tests (tests/support/Ros2BagWriting.hpp) from a
// sequence directory, in MCAP (zstd, lz4 and uncompressed chunks; indexed, unindexed and
// unchunked) and SQLite, with CDR of either byte order, yield the directory's frames, poses,
// calibration, T_body_sensor and origin; images are decoded only when their frame is read; bad
// bags are IoErrors naming the file and, where it applies, the topic and the record.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "io/BagRules.hpp"
#include "io/Cdr.hpp"
#include "io/FrameSource.hpp"
#include "io/IoError.hpp"
#include "io/Ros2Bag.hpp"
#include "io/Sequence.hpp"
#include "tests/support/CommandFixture.hpp"
#include "tests/support/ErrorText.hpp"
#include "tests/support/Ros2BagWriting.hpp"
#include "tests/support/SameImage.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap::io {
namespace {

namespace fs = std::filesystem;

using rovermap::testing::Bytes;
using rovermap::testing::Contains;
using rovermap::testing::Ros2Recording;
using rovermap::testing::WriteSequenceRos2Bag;

const fs::path kData = ROVERMAP_DATASETS_DIR;
const fs::path kTinyStereo = kData / "sim_tiny_stereo";
const fs::path kTinyCloud = kData / "sim_tiny_cloud";

std::string ErrorOf(const std::function<void()>& f) {
  return rovermap::testing::ErrorOf<IoError>(f);
}

using rovermap::testing::SameImage;

class Ros2Bag : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = rovermap::testing::ScratchDir(); }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path Write(const std::string& name, const Ros2Recording& how = {},
                 const fs::path& sequence = kTinyStereo) {
    return WriteSequenceRos2Bag(sequence, dir_ / name, how);
  }

  // The bag's options for the sequence: T_body_sensor from /tf_static, ground truth.
  static BagOptions Options() {
    BagOptions options;
    options.T_body_sensor_from_tf_static = true;
    options.groundtruth_topic = "/groundtruth";
    return options;
  }

  // Every frame, pose and image of `source` equals the sequence directory's, bit for bit.
  static void ExpectTheSequence(FrameSource& source, const fs::path& sequence = kTinyStereo) {
    SequenceReader reader(sequence);
    const SequenceInfo& want = reader.info();
    const SequenceInfo& got = source.info();
    ASSERT_EQ(got.camera.has_value(), want.camera.has_value());
    if (want.camera) {
      EXPECT_EQ(got.camera->fx, want.camera->fx);
      EXPECT_EQ(got.camera->cy, want.camera->cy);
      EXPECT_EQ(got.camera->width, want.camera->width);
      EXPECT_NEAR(got.camera->baseline_m, want.camera->baseline_m, 1e-12);
    }
    EXPECT_TRUE(got.T_body_sensor.linear() == want.T_body_sensor.linear());
    EXPECT_TRUE(got.T_body_sensor.translation().isApprox(want.T_body_sensor.translation(), 1e-15));
    EXPECT_EQ(got.origin.latitude_deg, want.origin.latitude_deg);  // from the NavSatFix
    EXPECT_EQ(got.origin.altitude_m, want.origin.altitude_m);
    EXPECT_EQ(source.skipped().unpaired_images, 0u);
    ASSERT_EQ(source.frame_count(), reader.frame_count());
    ASSERT_TRUE(source.has_groundtruth());
    Frame a;
    Frame b;
    while (reader.Next(&a)) {
      SCOPED_TRACE("frame " + std::to_string(a.index));
      ASSERT_TRUE(source.Next(&b));
      EXPECT_EQ(b.timestamp, a.timestamp);
      EXPECT_TRUE(b.T_world_body_odom.matrix() == a.T_world_body_odom.matrix());
      EXPECT_TRUE(b.T_world_body_truth->matrix() == a.T_world_body_truth->matrix());
      if (want.sensor_type == SensorType::kStereo) {
        EXPECT_TRUE(SameImage(b.left, a.left));
        EXPECT_TRUE(SameImage(b.right, a.right));
      } else {
        EXPECT_EQ(b.cloud.size(), a.cloud.size() + a.cloud.size() / 10);  // NaNs kept
      }
    }
    EXPECT_FALSE(source.Next(&b));
  }

  // The first IoError opening `bag` with the sequence's options.
  static std::string OpenError(const fs::path& bag, BagOptions options = Options()) {
    return ErrorOf([&] { Ros2BagSource source(bag, options); });
  }

  fs::path dir_;
};

TEST(BagStamp, IsTheDoubleItsDecimalTextReadsAs) {
  // As a TUM file's 9-decimal stamp reads: an imported sequence's stamps are the bag's. The
  // old sec + 1e-9 * nsec missed 0.3, 0.7, 1.7, 0.123456789 and 7.123456789 by an ulp.
  for (const std::int64_t sec : {0, 1, 7, 1000, 1700000000}) {
    for (const std::uint32_t nsec :
         {0u, 1u, 123456789u, 300000000u, 333333333u, 500000001u, 700000000u, 999999999u}) {
      const bag::Stamp stamp{sec, nsec};
      const std::string text = bag::StampText(stamp);
      EXPECT_EQ(stamp.ToSec(), std::strtod(text.c_str(), nullptr)) << text;
    }
  }
  EXPECT_EQ((bag::Stamp{-1, 500000000}.ToSec()), -0.5);  // ROS 2's sec is signed
}

TEST(CdrHead, GivesTheFieldsButTheDataFromTheFirstBytesAndChecksLengthsAgainstTheWhole) {
  const cv::Mat grey(120, 160, CV_8UC1, cv::Scalar(7));
  for (const bool big_endian : {false, true}) {
    SCOPED_TRACE(big_endian ? "big-endian" : "little-endian");
    const rovermap::testing::Cdr cdr{big_endian};
    const Bytes image = cdr.Image(grey, "bgr8", 1.5);
    const bag::ByteView whole{image.data(), image.size()};
    const bag::ImageMsg want = cdr::DecodeImage(whole, "image");
    const std::optional<bag::ImageMsg> got =
        cdr::DecodeImageHead({image.data(), 64}, image.size(), "image");
    ASSERT_TRUE(got);
    EXPECT_EQ(got->stamp, want.stamp);
    EXPECT_EQ(got->encoding, "bgr8");
    EXPECT_EQ(got->width, want.width);
    EXPECT_EQ(got->step, want.step);
    EXPECT_EQ(got->data.size, want.data.size);
    EXPECT_EQ(got->data.data, nullptr);
    // Cut inside the encoding: read more. A whole message shorter than its data: the error the
    // whole decoding gives.
    EXPECT_FALSE(cdr::DecodeImageHead({image.data(), 30}, image.size(), "image"));
    const std::string error = ErrorOf([&] {
      cdr::DecodeImageHead({image.data(), 64}, image.size() - 1, "image");
    });
    EXPECT_EQ(error, ErrorOf([&] { cdr::DecodeImage({image.data(), image.size() - 1}, "image"); }));
    EXPECT_TRUE(Contains(error, "'data' needs")) << error;

    registration::PointCloud points;
    points.points.assign(5, Eigen::Vector3d(1.0, 2.0, 3.0));
    const Bytes cloud = cdr.PointCloud(points, true, 2.0);
    EXPECT_FALSE(cdr::DecodePointCloudHead({cloud.data(), 40}, cloud.size(), "cloud"));
    const std::optional<bag::PointCloudMsg> head =
        cdr::DecodePointCloudHead({cloud.data(), cloud.size()}, cloud.size(), "cloud");
    ASSERT_TRUE(head);
    const bag::PointCloudMsg whole_cloud = cdr::DecodePointCloud({cloud.data(), cloud.size()}, "");
    ASSERT_EQ(head->fields.size(), whole_cloud.fields.size());
    EXPECT_EQ(head->fields.back().name, whole_cloud.fields.back().name);
    EXPECT_EQ(head->point_step, whole_cloud.point_step);
    EXPECT_EQ(head->data.size, 5u * head->point_step);
  }
}

TEST_F(Ros2Bag, McapOfEveryLayoutYieldsTheSequenceDirectoryBitForBit) {
  struct Case {
    const char* name;
    std::string compression;
    bool chunked;
    bool summary;
    bool big_endian;
    std::vector<std::string> encodings;
  };
  const std::vector<Case> cases = {
      {"zstd_indexed.mcap", "zstd", true, true, false, {"mono8", "rgb8"}},
      {"lz4_indexed_be.mcap", "lz4", true, true, true, {"bgr8", "mono16"}},
      {"none_unindexed.mcap", "", true, false, false, {"png"}},
      {"unchunked.mcap", "", false, true, true, {"mono8"}},
      {"unchunked_unindexed.mcap", "", false, false, false, {"mono8"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Ros2Recording how;
    how.mcap.compression = c.compression;
    how.mcap.chunked = c.chunked;
    how.mcap.summary = c.summary;
    how.mcap.chunk_bytes = 20000;  // several chunks
    how.big_endian = c.big_endian;
    how.encodings = c.encodings;
    Ros2BagSource source(Write(c.name, how), Options());
    ExpectTheSequence(source);
  }
}

TEST_F(Ros2Bag, SqliteFileAndBagDirectoryYieldTheSequence) {
  Ros2Recording how;
  how.encodings = {"png", "mono8"};
  how.big_endian = true;
  const fs::path db3 = Write("tiny.db3", how);
  Ros2BagSource source(db3, Options());
  ExpectTheSequence(source);

  // A rosbag2 directory: metadata.yaml names the file; OpenFrameSource knows it by that.
  const fs::path bag = dir_ / "bag";
  fs::create_directory(bag);
  fs::rename(db3, bag / "bag_0.db3");
  rovermap::testing::WriteRos2Metadata(bag, {"bag_0.db3"}, "sqlite3");
  std::unique_ptr<FrameSource> opened = OpenFrameSource(bag, Options());
  ASSERT_NE(dynamic_cast<Ros2BagSource*>(opened.get()), nullptr);
  ExpectTheSequence(*opened);
  EXPECT_EQ(opened->info().directory, bag);
}

TEST_F(Ros2Bag, ASplitBagDirectoryIsReadAsOneBagInTheOrderOfItsFiles) {
  // rosbag2 splits a long recording into files; metadata.yaml lists them in order. Here the
  // calibration and the first two frames are in an MCAP file, the last frame in a SQLite one.
  const fs::path bag = dir_ / "split";
  fs::create_directory(bag);
  Ros2Recording first;
  first.frames = 2;
  Write("split/split_0.mcap", first);
  Ros2Recording second;
  second.first_frame = 2;
  second.calibration = false;
  Write("split/split_1.db3", second);
  rovermap::testing::WriteRos2Metadata(bag, {"split_0.mcap", "split_1.db3"}, "mcap");
  Ros2BagSource source(bag, Options());
  ExpectTheSequence(source);
}

TEST_F(Ros2Bag, OpenFrameSourceTellsTheFormsApart) {
  const fs::path mcap = Write("tiny.mcap");
  EXPECT_TRUE(IsRos2Bag(mcap));
  EXPECT_NE(dynamic_cast<Ros2BagSource*>(OpenFrameSource(mcap, Options()).get()), nullptr);
  EXPECT_FALSE(IsRos2Bag(kTinyStereo));  // a sequence directory has no metadata.yaml
  EXPECT_EQ(dynamic_cast<Ros2BagSource*>(OpenFrameSource(kTinyStereo).get()), nullptr);
}

TEST_F(Ros2Bag, OdometryFromTfAndCloudsOfBothPrecisions) {
  Ros2Recording how;
  how.odometry_on_tf = true;
  BagOptions options = Options();
  options.odometry_from_tf = true;
  Ros2BagSource on_tf(Write("tf.mcap", how), options);
  ExpectTheSequence(on_tf);

  for (const bool float64 : {false, true}) {
    SCOPED_TRACE(float64 ? "float64" : "float32");
    Ros2Recording cloud;
    cloud.cloud_float64 = float64;
    options = Options();
    options.sensor_type = SensorType::kCloud;
    Ros2BagSource source(Write(float64 ? "f64.db3" : "f32.mcap", cloud, kTinyCloud), options);
    ExpectTheSequence(source, kTinyCloud);
    const Frame want = SequenceReader(kTinyCloud).Read(1);
    const Frame got = source.Read(1);
    // The first point: float64 exactly, float32 to its precision.
    const double error = (got.cloud.points[0] - want.cloud.points[0]).norm();
    EXPECT_LE(error, float64 ? 0.0 : 1e-6 * want.cloud.points[0].norm());
  }
}

TEST_F(Ros2Bag, ImagesAreDecodedWhenTheirFrameIsReadNotAtOpening) {
  // Frame 2's left PNG is garbage inside a well-formed message: opening (which reads stamps)
  // passes; reading frame 2 fails naming the bag, topic and stamp; the other frames read.
  Ros2Recording how;
  how.encodings = {"png"};
  int left_images = 0;
  how.edit = [&](const std::string& topic, Bytes* data) {
    if (topic == "/stereo/left/image_rect" && left_images++ == 2) {
      for (std::size_t i = data->size() - 40; i < data->size(); ++i) (*data)[i] = 0;
    }
  };
  const fs::path file = Write("lazy.mcap", how);
  Ros2BagSource source(file, Options());
  ASSERT_EQ(source.frame_count(), 3u);
  EXPECT_NO_THROW(source.Read(0));
  const std::string error = ErrorOf([&] { source.Read(2); });
  EXPECT_TRUE(Contains(error, file.string() + ": /stereo/left/image_rect at 1.000000000"));
  EXPECT_TRUE(Contains(error, "cannot decode"));
  EXPECT_NO_THROW(source.Read(1));
}

TEST_F(Ros2Bag, SqliteOpeningReadsOnlyTheHeadersOfImages) {
  // Frame 2's left image is raw, its pixels 0xA5, stored over overflow pages of their own;
  // one of those pages then points past the end of the file. Opening reads each image's first
  // bytes only (stamp, encoding, size) and passes; reading frame 2 meets the broken page.
  Ros2Recording how;
  int left_images = 0;
  how.edit = [&](const std::string& topic, Bytes* data) {
    if (topic == "/stereo/left/image_rect" && left_images++ == 2) {
      std::fill(data->end() - 160 * 120, data->end(), std::uint8_t{0xA5});
    }
  };
  const fs::path file = Write("lazy.db3", how);
  std::string bytes = rovermap::testing::Slurp(file);
  const std::size_t page = (static_cast<std::uint8_t>(bytes[16]) << 8) |
                           static_cast<std::uint8_t>(bytes[17]);  // 4096 by default
  std::size_t last = 0;  // the last overflow page of pixels that has a next one
  for (std::size_t at = 0; at + page <= bytes.size(); at += page) {
    const bool pixels = bytes.find_first_not_of('\xA5', at + 4) >= at + page;
    if (pixels && bytes.substr(at, 4) != std::string(4, '\0')) last = at;
  }
  ASSERT_NE(last, 0u);
  bytes.replace(last, 4, "\x7F\xFF\xFF\xF0");  // its next page: past the end
  std::ofstream(file, std::ios::binary) << bytes;

  Ros2BagSource source(file, Options());
  ASSERT_EQ(source.frame_count(), 3u);
  EXPECT_NO_THROW(source.Read(0));
  EXPECT_NO_THROW(source.Read(1));
  const std::string error = ErrorOf([&] { source.Read(2); });
  EXPECT_TRUE(Contains(error, file.string() + ": message id ")) << error;
  EXPECT_TRUE(Contains(error, "cannot read the database")) << error;
}

TEST_F(Ros2Bag, BadContainersAreIoErrorsNamingTheFileAndRecord) {
  Ros2Recording none;
  none.mcap.compression = "";
  const fs::path good = Write("good.mcap", none);
  const std::string bytes = rovermap::testing::Slurp(good);

  // Cut in the middle: the reader cannot find the footer, scans, and meets the cut record.
  const fs::path cut = dir_ / "cut.mcap";
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  std::string error = OpenError(cut);
  EXPECT_TRUE(Contains(error, cut.string() + ": truncated: the record at byte"));

  // One byte changed inside an uncompressed chunk's records: the CRC32 says so.
  std::string flipped = bytes;
  const std::size_t at = flipped.find("/stereo/left/camera_info");
  ASSERT_NE(at, std::string::npos);
  flipped[at + 1] = 'X';
  const fs::path crc = dir_ / "crc.mcap";
  std::ofstream(crc, std::ios::binary) << flipped;
  error = OpenError(crc);
  EXPECT_TRUE(Contains(error, crc.string() + ": chunk at byte "));
  EXPECT_TRUE(Contains(error, "CRC32 of its records is 0x"));

  Ros2Recording brotli;
  brotli.mcap.compression = "brotli";
  const fs::path unknown = Write("brotli.mcap", brotli);
  EXPECT_TRUE(Contains(OpenError(unknown), unknown.string() + ": chunk at byte "));
  EXPECT_TRUE(Contains(OpenError(unknown), "unknown compression 'brotli' (none, lz4, zstd)"));

  const fs::path not_mcap = dir_ / "not.mcap";
  std::ofstream(not_mcap) << "hello";
  EXPECT_TRUE(Contains(OpenError(not_mcap), not_mcap.string() + ": not an MCAP file"));
  const fs::path not_db3 = dir_ / "not.db3";
  std::ofstream(not_db3) << std::string(4096, 'x');
  EXPECT_TRUE(Contains(OpenError(not_db3), not_db3.string() + ": "));

  Ros2Recording json;
  json.mcap.encoding = "json";
  const fs::path wrong_encoding = Write("json.mcap", json);
  EXPECT_TRUE(Contains(OpenError(wrong_encoding),
                       wrong_encoding.string() + ": /stereo/left/camera_info (chunk at byte "));
  EXPECT_TRUE(Contains(OpenError(wrong_encoding), "message encoding 'json' (only cdr is read)"));
}

TEST_F(Ros2Bag, BadMessagesAreIoErrorsNamingTheTopicAndRecord) {
  // A CDR buffer shorter than its declared lengths: the odometry cut after its header.
  Ros2Recording cut;
  cut.edit = [](const std::string& topic, Bytes* data) {
    if (topic == "/odom") data->resize(30);
  };
  for (const char* name : {"short.mcap", "short.db3"}) {
    const fs::path file = Write(name, cut);
    const std::string error = OpenError(file);
    EXPECT_TRUE(Contains(error, file.string() + ": /odom ("));
    EXPECT_TRUE(
        Contains(error, name == std::string("short.db3") ? "message id " : "record at byte "));
    EXPECT_TRUE(Contains(error, "CDR data ends at byte 30"));
  }
  // An image whose declared data length runs past the buffer.
  Ros2Recording long_image;
  long_image.edit = [](const std::string& topic, Bytes* data) {
    if (topic == "/stereo/right/image_rect") data->resize(data->size() - 1);
  };
  const fs::path file = Write("long.db3", long_image);
  EXPECT_TRUE(Contains(OpenError(file), "/stereo/right/image_rect (message id "));
  EXPECT_TRUE(Contains(OpenError(file), "'data' needs"));

  // A topic missing, and one of a type rovermap does not read.
  const fs::path tiny = Write("tiny.mcap");
  BagOptions options = Options();
  options.odometry_topic = "/wheel_odom";
  EXPECT_TRUE(Contains(OpenError(tiny, options), tiny.string() +
                                                     ": no topic /wheel_odom (the bag has: /fix "
                                                     "(sensor_msgs/msg/NavSatFix), /groundtruth"));
  options = Options();
  options.groundtruth_topic = "/fix";
  EXPECT_TRUE(Contains(OpenError(tiny, options),
                       tiny.string() + ": /fix is sensor_msgs/msg/NavSatFix, not "
                                       "geometry_msgs/msg/PoseStamped or nav_msgs/msg/Odometry"));
}

TEST_F(Ros2Bag, AMetadataYamlNamingMissingFilesIsAnIoErrorNamingIt) {
  const fs::path bag = dir_ / "bag";
  fs::create_directory(bag);
  Write("bag/bag_0.mcap");
  rovermap::testing::WriteRos2Metadata(bag, {"bag_0.mcap", "bag_1.mcap"}, "mcap");
  const std::string error = OpenError(bag);
  EXPECT_TRUE(Contains(error, (bag / "metadata.yaml").string() + ":"));
  EXPECT_TRUE(Contains(error, "names bag_1.mcap, which is not in " + bag.string()));

  std::ofstream(bag / "metadata.yaml") << "rosbag2_bagfile_information:\n  compression_mode: FILE\n"
                                          "  relative_file_paths: [bag_0.mcap.zstd]\n";
  EXPECT_TRUE(Contains(OpenError(bag), "rosbag2 compression (compression_mode FILE) is not read"));
}

}  // namespace
}  // namespace rovermap::io
