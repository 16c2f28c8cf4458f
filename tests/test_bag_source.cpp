// io::BagSource: a ROS 1 bag written with rosbag's own API from a sequence directory yields
// the directory's frames (raw, PNG and JPEG images; PointCloud2 clouds); odometry (from a topic
// or /tf) and ground truth are interpolated at the frame stamps; unpaired images and frames
// outside the poses are skipped and counted; T_body_sensor comes from /tf_static and the origin
// from the first NavSatFix; opening copies no image or cloud; bad bags and images are IoErrors
// naming the bag.
#include <gtest/gtest.h>
#include <rosbag/bag.h>

#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <new>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "config/Config.hpp"
#include "io/BagSource.hpp"
#include "io/IoError.hpp"
#include "io/PointCloudIo.hpp"
#include "io/Sequence.hpp"
#include "mapper/Mapper.hpp"
#include "mapper/ReadAhead.hpp"
#include "tests/support/BagWriting.hpp"
#include "tests/support/ErrorText.hpp"
#include "tests/support/SameImage.hpp"
#include "tests/support/ScratchDir.hpp"

namespace {
// Bytes allocated with operator new in this executable: what opening a bag copies. (Allocation
// only counted; malloc does the work, so the sanitizers still see every block.)
std::atomic<std::size_t> g_new_bytes{0};

void* CountedMalloc(std::size_t size) {
  g_new_bytes.fetch_add(size, std::memory_order_relaxed);
  return std::malloc(size == 0 ? 1 : size);
}
}  // namespace

// Every operator new and delete whose block the others may free (the sanitizers' own would
// otherwise pair with these: std::stable_sort's nothrow new with the sized delete). GCC takes
// operator new for its own when it inlines a delete and calls the free() a mismatch
// (-Wmismatched-new-delete); here both are malloc's.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  if (void* p = CountedMalloc(size)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t size, const std::nothrow_t& /*tag*/) noexcept {
  return CountedMalloc(size);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t /*size*/) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t& /*tag*/) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace rovermap::io {
namespace {

namespace fs = std::filesystem;

using rovermap::testing::BagRecording;
using rovermap::testing::CameraInfoMsg;
using rovermap::testing::Contains;
using rovermap::testing::ImageMsg;
using rovermap::testing::kBagTimeOffset;
using rovermap::testing::OdometryMsg;
using rovermap::testing::WriteSequenceBag;

const fs::path kData = ROVERMAP_DATASETS_DIR;
const fs::path kTinyStereo = kData / "sim_tiny_stereo";
const fs::path kTinyCloud = kData / "sim_tiny_cloud";

std::string ErrorOf(const std::function<void()>& f) {
  return rovermap::testing::ErrorOf<IoError>(f);
}

using rovermap::testing::SameImage;

fs::path Bag(const std::string& name, const BagRecording& how = {},
             const fs::path& sequence = kTinyStereo) {
  return WriteSequenceBag(sequence, rovermap::testing::ScratchDir() / name, how);
}

double TranslationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

double RotationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.linear() - b.linear()).norm();
}

TEST(BagSource, YieldsTheFramesOfTheSequenceDirectoryItWasWrittenFrom) {
  BagRecording how;
  how.encodings = {"mono8", "rgb8", "bgr8", "mono16"};
  const fs::path file = Bag("tiny.bag", how);
  SequenceReader reader(kTinyStereo);
  BagOptions options;
  options.T_body_sensor = reader.info().T_body_sensor;
  BagSource source(file, options);

  const CameraModel& want = *reader.info().camera;
  const CameraModel& got = *source.info().camera;
  EXPECT_EQ(got.width, want.width);
  EXPECT_EQ(got.height, want.height);
  EXPECT_EQ(got.fx, want.fx);
  EXPECT_EQ(got.fy, want.fy);
  EXPECT_EQ(got.cx, want.cx);
  EXPECT_EQ(got.cy, want.cy);
  EXPECT_NEAR(got.baseline_m, want.baseline_m, 1e-12);
  EXPECT_EQ(source.info().sensor_type, SensorType::kStereo);
  EXPECT_EQ(source.info().directory, file);
  EXPECT_NEAR(source.info().frame_rate_hz, reader.info().frame_rate_hz, 1e-9);
  EXPECT_FALSE(source.has_groundtruth());
  EXPECT_EQ(source.skipped().unpaired_images, 0u);
  EXPECT_EQ(source.skipped().outside_pose_span, 0u);

  ASSERT_EQ(source.frame_count(), reader.frame_count());
  Frame a;
  Frame b;
  std::size_t n = 0;
  while (reader.Next(&a)) {
    SCOPED_TRACE("frame " + std::to_string(n));
    EXPECT_EQ(source.next_index(), n);
    ASSERT_TRUE(source.Next(&b));
    EXPECT_EQ(b.index, a.index);
    EXPECT_NEAR(b.timestamp, a.timestamp + kBagTimeOffset, 1e-9);
    EXPECT_LT(TranslationError(b.T_world_body_odom, a.T_world_body_odom), 1e-9);
    EXPECT_LT(RotationError(b.T_world_body_odom, a.T_world_body_odom), 1e-9);
    EXPECT_TRUE(b.T_world_body_odom.matrix() == source.odometry()[n].T_world_body.matrix());
    EXPECT_TRUE(SameImage(b.left, a.left));
    EXPECT_TRUE(SameImage(b.right, a.right));
    EXPECT_TRUE(SameImage(source.Read(n).right, a.right));  // random access
    ++n;
  }
  EXPECT_FALSE(source.Next(&b));
  EXPECT_THROW(source.Read(n), std::out_of_range);
}

TEST(BagSource, CompressedImagesPngBitIdenticalJpegClose) {
  SequenceReader reader(kTinyStereo);
  BagRecording how;
  how.encodings = {"png"};
  BagSource png(Bag("png.bag", how));
  how.encodings = {"jpeg"};
  BagSource jpeg(Bag("jpeg.bag", how));
  ASSERT_EQ(png.frame_count(), reader.frame_count());
  ASSERT_EQ(jpeg.frame_count(), reader.frame_count());
  for (std::size_t k = 0; k < reader.frame_count(); ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const Frame want = reader.Read(k);
    const Frame lossless = png.Read(k);
    EXPECT_TRUE(SameImage(lossless.left, want.left));
    EXPECT_TRUE(SameImage(lossless.right, want.right));
    const Frame lossy = jpeg.Read(k);
    ASSERT_EQ(lossy.left.size(), want.left.size());
    ASSERT_EQ(lossy.right.type(), CV_8UC1);
    // JPEG at OpenCV's default quality (95): a grey level or two on average.
    const double mean_error = cv::norm(lossy.left, want.left, cv::NORM_L1) / want.left.total();
    EXPECT_LT(mean_error, 3.0);
    EXPECT_FALSE(SameImage(lossy.left, want.left));  // it did go through JPEG
  }
}

TEST(BagSource, PointCloud2OfFloat32AndFloat64GivesThePointsNaNsIncluded) {
  SequenceReader reader(kTinyCloud);
  for (const bool float64 : {false, true}) {
    SCOPED_TRACE(float64 ? "float64" : "float32");
    BagRecording how;
    how.cloud_float64 = float64;
    const fs::path file = Bag(float64 ? "f64.bag" : "f32.bag", how, kTinyCloud);
    BagOptions options;
    options.sensor_type = SensorType::kCloud;
    BagSource source(file, options);
    EXPECT_EQ(source.info().sensor_type, SensorType::kCloud);
    ASSERT_TRUE(source.info().camera.has_value());  // the bag has camera info for the model
    EXPECT_EQ(source.info().camera->fx, reader.info().camera->fx);
    ASSERT_EQ(source.frame_count(), reader.frame_count());
    for (std::size_t k = 0; k < reader.frame_count(); ++k) {
      const Frame want = reader.Read(k);
      const Frame got = source.Read(k);
      // The bag's clouds have a NaN point after every 10th of the PLY's: kept, for the mapper to
      // drop and count.
      ASSERT_EQ(got.cloud.size(), want.cloud.size() + want.cloud.size() / 10) << k;
      std::size_t nan = 0;
      for (std::size_t i = 0; i < want.cloud.size(); ++i) {
        while (!got.cloud.points[i + nan].allFinite()) ++nan;
        // The PLY holds doubles: float64 carries them exactly, float32 to its precision.
        const Eigen::Vector3d error = got.cloud.points[i + nan] - want.cloud.points[i];
        if (float64) {
          ASSERT_EQ(error.norm(), 0.0) << k << " " << i;
        } else {
          ASSERT_LT(error.lpNorm<Eigen::Infinity>(), 1e-6 * want.cloud.points[i].norm() + 1e-12)
              << k << " " << i;
        }
      }
    }
  }
}

// The registered trajectory of `source` through mapper::ReadAhead, as replay runs it.
std::vector<Eigen::Isometry3d> Replay(FrameSource* source) {
  const config::Config c;
  mapper::Mapper m(source->info(),
                   {c.mapper, c.registration, c.stereo, c.dem, c.octomap, c.terrain});
  mapper::ReadAhead ahead(source, &m);
  mapper::ReadAhead::Item item;
  while (ahead.Next(&item)) {
    EXPECT_TRUE(item.frame.has_value()) << item.error;
    if (item.frame) m.ProcessPrepared(*item.frame, std::move(item.prepared), item.load_ms);
  }
  std::vector<Eigen::Isometry3d> trajectory;
  for (const mapper::FrameResult& r : m.results()) trajectory.push_back(r.step.T_world_body);
  return trajectory;
}

// What opening `file` allocates beyond what rosbag's own opening does (its buffers and index).
std::size_t AllocatedOpening(const fs::path& file, const BagOptions& options = {}) {
  std::size_t before = g_new_bytes;
  {
    rosbag::Bag bag;
    bag.open(file.string(), rosbag::bagmode::Read);
  }
  const std::size_t rosbag_alone = g_new_bytes - before;
  before = g_new_bytes;
  const BagSource source(file, options);
  return g_new_bytes - before - rosbag_alone;
}

TEST(BagSource, OpeningCopiesNoImageOrCloud) {
  // Opening reads each image's and cloud's header: rosbag skips over their data instead of
  // deserialising it, so opening allocates as much whatever the data's size. (Deserialising
  // every one, it allocated 230 kB more for the rgb8 images than for the mono8 ones, 79 kB more
  // for the float64 clouds than for the float32 ones.)
  BagRecording mono8;
  BagRecording rgb8;
  rgb8.encodings = {"rgb8"};
  const std::size_t small = AllocatedOpening(Bag("mono8.bag", mono8));
  const std::size_t large = AllocatedOpening(Bag("rgb8.bag", rgb8));
  EXPECT_LT(large, small + 1000);

  BagOptions options;
  options.sensor_type = SensorType::kCloud;
  BagRecording float64;
  float64.cloud_float64 = true;
  const std::size_t small_clouds = AllocatedOpening(Bag("f32.bag", {}, kTinyCloud), options);
  const std::size_t large_clouds = AllocatedOpening(Bag("f64.bag", float64, kTinyCloud), options);
  EXPECT_LT(large_clouds, small_clouds + 1000);
}

TEST(BagSource, ReplaysToTheTrajectoryOfTheSequenceDirectory) {
  SequenceReader reader(kTinyStereo);
  BagOptions options;
  options.T_body_sensor = reader.info().T_body_sensor;
  options.origin = reader.info().origin;
  BagSource source(Bag("tiny.bag"), options);
  const std::vector<Eigen::Isometry3d> want = Replay(&reader);
  const std::vector<Eigen::Isometry3d> got = Replay(&source);
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < want.size(); ++k) {
    EXPECT_LT(TranslationError(got[k], want[k]), 1e-9) << k;
    EXPECT_LT(RotationError(got[k], want[k]), 1e-9) << k;
  }
}

TEST(BagSource, OdometryFromTfBetweenTwoNamedFrames) {
  BagRecording how;
  how.odometry_on_tf = true;  // with a map -> odom transform in every message beside it
  const fs::path file = Bag("tf.bag", how);
  SequenceReader reader(kTinyStereo);
  BagOptions options;
  options.odometry_from_tf = true;
  options.odometry_parent_frame = "/odom";  // tf's leading slash is no different frame
  BagSource source(file, options);
  ASSERT_EQ(source.frame_count(), reader.frame_count());
  for (std::size_t k = 0; k < reader.frame_count(); ++k) {
    const Eigen::Isometry3d& want = reader.odometry()[k].T_world_body;
    EXPECT_LT(TranslationError(source.odometry()[k].T_world_body, want), 1e-9) << k;
    EXPECT_LT(RotationError(source.odometry()[k].T_world_body, want), 1e-9) << k;
  }
  // From /odom, which this bag does not have, it is a missing topic.
  EXPECT_TRUE(Contains(ErrorOf([&] { BagSource topic(file); }), "no topic /odom"));
  options.odometry_child_frame = "wheels";
  const std::string message = ErrorOf([&] { BagSource wrong(file, options); });
  EXPECT_TRUE(Contains(
      message, "no /tf transform /odom -> wheels (/tf has: map -> odom, odom -> base_link)"))
      << message;
}

TEST(BagSource, InterpolatesOdometryAndGroundTruthAtTheImageStamps) {
  // Odometry at 10 Hz and ground truth (PoseStamped) at 4 Hz, both at constant velocity and yaw
  // rate, images between their samples: linear interpolation and slerp are exact on such a
  // motion.
  const fs::path file = rovermap::testing::ScratchDir() / "interp.bag";
  const BagOptions topics;
  CameraModel camera;
  camera.width = 8;
  camera.height = 6;
  camera.fx = camera.fy = 10.0;
  camera.cx = 4.0;
  camera.cy = 3.0;
  camera.baseline_m = 0.1;
  const Eigen::Vector3d velocity(0.3, -0.1, 0.02);
  const double yaw_rate = 0.4;
  auto pose_at = [&](double t, double scale) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = scale * velocity * (t - 10.0);
    T.linear() =
        Eigen::AngleAxisd(scale * yaw_rate * (t - 10.0), Eigen::Vector3d::UnitZ()).matrix();
    return T;
  };
  const double truth_scale = 1.1;  // the truth moves a little faster than odometry says
  const cv::Mat grey(camera.height, camera.width, CV_8UC1, cv::Scalar(7));
  const std::vector<double> image_times = {9.9, 10.0, 10.25, 10.33, 10.9, 11.0, 11.5};
  {
    rosbag::Bag bag(file.string(), rosbag::bagmode::Write);
    bag.write(topics.left_info_topic, ros::Time(9.0), CameraInfoMsg(camera, 0.0));
    bag.write(topics.right_info_topic, ros::Time(9.0), CameraInfoMsg(camera, -1.0));
    for (int k = 0; k <= 10; ++k) {
      const double t = 10.0 + 0.1 * k;
      bag.write(topics.odometry_topic, ros::Time(t), OdometryMsg(pose_at(t, 1.0), t));
    }
    for (int k = 0; k <= 4; ++k) {
      const double t = 10.0 + 0.25 * k;
      bag.write("/truth", ros::Time(t), rovermap::testing::PoseMsg(pose_at(t, truth_scale), t));
    }
    for (const double t : image_times) {
      bag.write(topics.left_image_topic, ros::Time(t), ImageMsg(grey, "mono8", t));
      bag.write(topics.right_image_topic, ros::Time(t), ImageMsg(grey, "mono8", t));
    }
  }
  BagOptions options;
  options.groundtruth_topic = "/truth";
  BagSource source(file, options);
  // 9.9 is before the poses, 11.5 after them: not frames.
  ASSERT_EQ(source.frame_count(), 5u);
  EXPECT_EQ(source.skipped().outside_pose_span, 2u);
  ASSERT_TRUE(source.has_groundtruth());
  for (std::size_t k = 0; k < source.frame_count(); ++k) {
    const double t = image_times[k + 1];
    EXPECT_NEAR(source.odometry()[k].timestamp, t, 1e-9);
    EXPECT_NEAR(source.groundtruth()[k].timestamp, t, 1e-9);
    const Eigen::Isometry3d odom = pose_at(t, 1.0);
    const Eigen::Isometry3d truth = pose_at(t, truth_scale);
    EXPECT_LT(TranslationError(source.odometry()[k].T_world_body, odom), 1e-9) << k;
    EXPECT_LT(RotationError(source.odometry()[k].T_world_body, odom), 1e-9) << k;
    EXPECT_LT(TranslationError(source.groundtruth()[k].T_world_body, truth), 1e-9) << k;
    EXPECT_LT(RotationError(source.groundtruth()[k].T_world_body, truth), 1e-9) << k;
    const Frame frame = source.Read(k);
    ASSERT_TRUE(frame.T_world_body_truth.has_value());
    EXPECT_TRUE(frame.T_world_body_truth->matrix() ==
                source.groundtruth()[k].T_world_body.matrix());
  }
}

TEST(BagSource, UnsynchronisedImagesAreSkippedAndCounted) {
  // Three frames, the rights 1 ms late. With a 0.5 ms tolerance none pair up.
  BagOptions options;
  options.pair_tolerance_s = 0.0005;
  const fs::path file = Bag("late.bag");
  const std::string message = ErrorOf([&] { BagSource source(file, options); });
  EXPECT_TRUE(Contains(message, "no left/right image pair within")) << message;

  // Frame 1's right image 40 ms late: its left and right have no partner in 5 ms.
  BagRecording how;
  how.right_delay_of_frame = [](std::size_t k) { return k == 1 ? 0.040 : 0.001; };
  const fs::path bag_file = Bag("one_late.bag", how);
  BagSource source(bag_file);
  ASSERT_EQ(source.frame_count(), 2u);
  EXPECT_EQ(source.skipped().unpaired_images, 2u);
  EXPECT_EQ(source.skipped().outside_pose_span, 0u);
  EXPECT_NEAR(source.odometry()[1].timestamp, kBagTimeOffset + 1.0, 1e-9);  // frame 2's stamp
}

TEST(BagSource, OriginFromTheFirstNavSatFixUnlessGiven) {
  const fs::path file = Bag("fix.bag");
  const GeodeticOrigin want = SequenceReader(kTinyStereo).info().origin;
  BagOptions options;
  options.default_origin = {1.0, 2.0, 3.0};
  {
    BagSource source(file, options);  // the first message has no fix: the second one counts
    EXPECT_EQ(source.info().origin.latitude_deg, want.latitude_deg);
    EXPECT_EQ(source.info().origin.longitude_deg, want.longitude_deg);
    EXPECT_EQ(source.info().origin.altitude_m, want.altitude_m);
  }
  options.origin = GeodeticOrigin{-33.0, 151.0, 20.0};
  EXPECT_EQ(BagSource(file, options).info().origin.latitude_deg, -33.0);
  options.origin.reset();
  options.navsat_topic = "/gps/fix";  // not in the bag: the default
  EXPECT_EQ(BagSource(file, options).info().origin.latitude_deg, 1.0);
}

TEST(BagSource, TBodySensorFromTfStaticOverTwoHops) {
  const fs::path file = Bag("static.bag");
  const Eigen::Isometry3d want = SequenceReader(kTinyStereo).info().T_body_sensor;
  BagOptions options;
  options.T_body_sensor_from_tf_static = true;
  const Eigen::Isometry3d got = BagSource(file, options).info().T_body_sensor;
  EXPECT_LT(TranslationError(got, want), 1e-12);
  EXPECT_LT(RotationError(got, want), 1e-12);
  // Without it, the configured transform.
  EXPECT_TRUE(BagSource(file).info().T_body_sensor.matrix().isIdentity());
  options.sensor_frame = "thermal";
  const std::string message = ErrorOf([&] { BagSource source(file, options); });
  EXPECT_TRUE(Contains(message, "/tf_static does not connect base_link to thermal")) << message;
  EXPECT_TRUE(Contains(message, "base_link -> mast, mast -> stereo_left")) << message;
}

TEST(BagSource, AnUndecodableImageIsAnIoErrorAndTheNextFrameFollows) {
  // Frame 1's left image: a PNG cut short, which only decoding finds.
  BagRecording how;
  how.encodings = {"png", "mono8"};
  how.edit_compressed = [](std::size_t k, bool, sensor_msgs::CompressedImage* image) {
    if (k == 1) image->data.resize(image->data.size() / 3);
  };
  const fs::path file = Bag("cut.bag", how);
  BagSource source(file);
  Frame frame;
  ASSERT_TRUE(source.Next(&frame));
  const std::string message = ErrorOf([&] { source.Next(&frame); });
  EXPECT_TRUE(Contains(message, file.string())) << message;
  EXPECT_TRUE(Contains(message, "/stereo/left/image_rect at 1000.500000000")) << message;
  EXPECT_TRUE(Contains(message, "cannot decode the mono8; png compressed  image")) << message;
  ASSERT_TRUE(source.Next(&frame));
  EXPECT_EQ(frame.index, 2u);
  EXPECT_FALSE(source.Next(&frame));
}

TEST(BagSource, ABagWithoutWhatItNeedsIsAnIoErrorNamingIt) {
  const fs::path dir = rovermap::testing::ScratchDir();
  EXPECT_TRUE(Contains(ErrorOf([&] { BagSource source(dir / "none.bag"); }), "none.bag"));

  const fs::path file = Bag("tiny.bag");
  BagOptions options;
  options.right_info_topic = "/elsewhere/camera_info";
  const std::string no_info = ErrorOf([&] { BagSource source(file, options); });
  EXPECT_TRUE(Contains(no_info,
                       "tiny.bag: no topic /elsewhere/camera_info (the bag has: /fix "
                       "(sensor_msgs/NavSatFix), /odom (nav_msgs/Odometry), "
                       "/stereo/left/camera_info (sensor_msgs/CameraInfo)"))
      << no_info;

  options = BagOptions();
  options.left_image_topic = options.odometry_topic;
  const std::string wrong_type = ErrorOf([&] { BagSource source(file, options); });
  EXPECT_TRUE(Contains(wrong_type,
                       "/odom is nav_msgs/Odometry, not sensor_msgs/CompressedImage or "
                       "sensor_msgs/Image"))
      << wrong_type;

  options = BagOptions();
  options.groundtruth_topic = "/vicon";
  EXPECT_TRUE(Contains(ErrorOf([&] { BagSource source(file, options); }), "no topic /vicon"));
}

// What the pipeline cannot use is refused when the bag is opened, naming the bag and the cause.
TEST(BagSource, UnsupportedEncodingsAndUnrectifiedCalibrationsFailOnOpening) {
  BagRecording how;
  how.encodings = {"mono8", "mono8", "bayer_rggb8", "mono8"};
  const fs::path bayer = Bag("bayer.bag", how);
  const std::string encoding = ErrorOf([&] { BagSource source(bayer); });
  EXPECT_TRUE(Contains(encoding, bayer.string() + ": /stereo/left/image_rect at 1000.500000000: "
                                                  "unsupported image encoding 'bayer_rggb8'"))
      << encoding;

  struct Case {
    std::string name;
    std::function<void(sensor_msgs::CameraInfo*, sensor_msgs::CameraInfo*)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"skew", [](auto* left, auto*) { left->P[1] = 0.5; },
       "/stereo/left/camera_info: projection P is not that of a rectified camera"},
      {"zero_baseline", [](auto*, auto* right) { right->P[3] = 0.0; },
       "/stereo/right/camera_info: projection P gives no positive baseline"},
      {"sizes", [](auto*, auto* right) { right->width += 2; },
       "left and right camera info differ in image size (160x120 and 162x120)"},
      {"intrinsics", [](auto*, auto* right) { right->P[2] += 3.0; },
       "left and right projections P differ in fx, fy, cx or cy"},
  };
  for (const Case& c : cases) {
    BagRecording edited;
    edited.edit_info = c.edit;
    const fs::path file = Bag(c.name + ".bag", edited);
    const std::string message = ErrorOf([&] { BagSource source(file); });
    EXPECT_TRUE(Contains(message, file.string() + ": ")) << c.name;
    EXPECT_TRUE(Contains(message, c.message)) << c.name;
  }
}

}  // namespace
}  // namespace rovermap::io
