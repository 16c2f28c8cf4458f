// io::BagSource: a ROS 1 bag written with rosbag's own API from a sequence directory yields
// the directory's frames; odometry is interpolated at the image stamps; bad bags and images
// are IoErrors naming the bag.
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "config/Config.hpp"
#include "io/BagSource.hpp"
#include "io/IoError.hpp"
#include "io/Sequence.hpp"
#include "mapper/Mapper.hpp"
#include "mapper/ReadAhead.hpp"
#include "tests/support/ErrorText.hpp"
#include "tests/support/ScratchDir.hpp"

namespace rovermap::io {
namespace {

namespace fs = std::filesystem;

using rovermap::testing::Contains;

const fs::path kData = ROVERMAP_DATASETS_DIR;
// rosbag takes no message at time 0, where the sequences start.
constexpr double kTimeOffset = 1000.0;

std::string ErrorOf(const std::function<void()>& f) {
  return rovermap::testing::ErrorOf<IoError>(f);
}

sensor_msgs::CameraInfo Info(const CameraModel& camera, double tx) {
  sensor_msgs::CameraInfo info;
  info.width = camera.width;
  info.height = camera.height;
  info.P = {camera.fx, 0, camera.cx, tx, 0, camera.fy, camera.cy, 0, 0, 0, 1, 0};
  return info;
}

// `grey` in `encoding` (mono8, rgb8, bgr8 or mono16, little-endian), with a padded step.
sensor_msgs::Image Image(const cv::Mat& grey, const std::string& encoding, double t) {
  sensor_msgs::Image msg;
  msg.header.stamp = ros::Time(t);
  msg.width = grey.cols;
  msg.height = grey.rows;
  msg.encoding = encoding;
  const int bytes = encoding == "mono8" ? 1 : encoding == "mono16" ? 2 : 3;
  msg.step = grey.cols * bytes + 4;
  msg.data.assign(static_cast<std::size_t>(msg.step) * grey.rows, 0);
  for (int r = 0; r < grey.rows; ++r) {
    for (int c = 0; c < grey.cols; ++c) {
      const std::uint8_t v = grey.at<std::uint8_t>(r, c);
      std::uint8_t* out = &msg.data[static_cast<std::size_t>(r) * msg.step + c * bytes];
      if (bytes == 2) {
        out[0] = 0x5a;  // low byte: dropped
        out[1] = v;
      } else {
        for (int k = 0; k < bytes; ++k) out[k] = v;
      }
    }
  }
  return msg;
}

nav_msgs::Odometry Odometry(const Eigen::Isometry3d& T_world_body, double t) {
  nav_msgs::Odometry msg;
  msg.header.stamp = ros::Time(t);
  const Eigen::Quaterniond q(T_world_body.linear());
  msg.pose.pose.position.x = T_world_body.translation().x();
  msg.pose.pose.position.y = T_world_body.translation().y();
  msg.pose.pose.position.z = T_world_body.translation().z();
  msg.pose.pose.orientation.x = q.x();
  msg.pose.pose.orientation.y = q.y();
  msg.pose.pose.orientation.z = q.z();
  msg.pose.pose.orientation.w = q.w();
  return msg;
}

// A bag of `sequence` on the default topics: camera info once, each frame's images in the
// encodings of `encodings` in turn, left then right (the right one 1 ms after the left), and
// odometry at each left stamp, all written in time order.
fs::path WriteBag(const fs::path& sequence, const fs::path& file,
                  const std::vector<std::string>& encodings) {
  const SequenceReader reader(sequence);
  const BagOptions topics;
  const CameraModel& camera = *reader.info().camera;
  rosbag::Bag bag(file.string(), rosbag::bagmode::Write);
  const ros::Time start(kTimeOffset - 1.0);
  bag.write(topics.left_info_topic, start, Info(camera, 0.0));
  bag.write(topics.right_info_topic, start, Info(camera, -camera.fx * camera.baseline_m));
  for (std::size_t k = 0; k < reader.frame_count(); ++k) {
    const Frame frame = reader.Read(k);
    const double t = frame.timestamp + kTimeOffset;
    const std::string& left_encoding = encodings[(2 * k) % encodings.size()];
    const std::string& right_encoding = encodings[(2 * k + 1) % encodings.size()];
    bag.write(topics.odometry_topic, ros::Time(t), Odometry(frame.T_world_body_odom, t));
    bag.write(topics.left_image_topic, ros::Time(t), Image(frame.left, left_encoding, t));
    bag.write(topics.right_image_topic, ros::Time(t + 0.001),
              Image(frame.right, right_encoding, t + 0.001));
  }
  bag.close();
  return file;
}

bool SameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

TEST(BagSource, YieldsTheFramesOfTheSequenceDirectoryItWasWrittenFrom) {
  const fs::path sequence = kData / "sim_tiny_stereo";
  const fs::path file = WriteBag(sequence, rovermap::testing::ScratchDir() / "tiny.bag",
                                 {"mono8", "rgb8", "bgr8", "mono16"});
  SequenceReader reader(sequence);
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

  ASSERT_EQ(source.frame_count(), reader.frame_count());
  Frame a;
  Frame b;
  std::size_t n = 0;
  while (reader.Next(&a)) {
    SCOPED_TRACE("frame " + std::to_string(n));
    EXPECT_EQ(source.next_index(), n);
    ASSERT_TRUE(source.Next(&b));
    EXPECT_EQ(b.index, a.index);
    EXPECT_NEAR(b.timestamp, a.timestamp + kTimeOffset, 1e-9);
    EXPECT_LT((b.T_world_body_odom.translation() - a.T_world_body_odom.translation()).norm(), 1e-9);
    EXPECT_LT((b.T_world_body_odom.linear() - a.T_world_body_odom.linear()).norm(), 1e-9);
    EXPECT_TRUE(b.T_world_body_odom.matrix() == source.odometry()[n].T_world_body.matrix());
    EXPECT_TRUE(SameImage(b.left, a.left));
    EXPECT_TRUE(SameImage(b.right, a.right));
    EXPECT_TRUE(SameImage(source.Read(n).right, a.right));  // random access
    ++n;
  }
  EXPECT_FALSE(source.Next(&b));
  EXPECT_THROW(source.Read(n), std::out_of_range);
}

// The registered trajectory of `source` through mapper::ReadAhead, as replay runs it.
std::vector<Eigen::Isometry3d> Replay(FrameSource* source) {
  const config::Config c;
  mapper::Mapper m(source->info(), {c.mapper, c.registration, c.stereo, c.dem, c.octomap});
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

TEST(BagSource, ReplaysToTheTrajectoryOfTheSequenceDirectory) {
  const fs::path sequence = kData / "sim_tiny_stereo";
  const fs::path file = WriteBag(sequence, rovermap::testing::ScratchDir() / "tiny.bag", {"mono8"});
  SequenceReader reader(sequence);
  BagOptions options;
  options.T_body_sensor = reader.info().T_body_sensor;
  options.origin = reader.info().origin;
  BagSource source(file, options);
  const std::vector<Eigen::Isometry3d> want = Replay(&reader);
  const std::vector<Eigen::Isometry3d> got = Replay(&source);
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < want.size(); ++k) {
    EXPECT_LT((got[k].translation() - want[k].translation()).norm(), 1e-6) << k;
    EXPECT_LT((got[k].linear() - want[k].linear()).norm(), 1e-6) << k;
  }
}

TEST(BagSource, InterpolatesOdometryAtTheImageStamps) {
  // Odometry at 10 Hz at constant velocity and yaw rate, images between its samples: linear
  // interpolation and slerp are exact on such a motion.
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
  auto pose_at = [&](double t) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = velocity * (t - 10.0);
    T.linear() = Eigen::AngleAxisd(yaw_rate * (t - 10.0), Eigen::Vector3d::UnitZ()).matrix();
    return T;
  };
  const cv::Mat grey(camera.height, camera.width, CV_8UC1, cv::Scalar(7));
  const std::vector<double> image_times = {10.0, 10.25, 10.33, 10.9, 11.0, 11.5};
  {
    rosbag::Bag bag(file.string(), rosbag::bagmode::Write);
    bag.write(topics.left_info_topic, ros::Time(10.0), Info(camera, 0.0));
    bag.write(topics.right_info_topic, ros::Time(10.0), Info(camera, -1.0));
    for (int k = 0; k <= 10; ++k) {
      const double t = 10.0 + 0.1 * k;
      bag.write(topics.odometry_topic, ros::Time(t), Odometry(pose_at(t), t));
    }
    for (const double t : image_times) {
      bag.write(topics.left_image_topic, ros::Time(t), Image(grey, "mono8", t));
      bag.write(topics.right_image_topic, ros::Time(t), Image(grey, "mono8", t));
    }
  }
  BagSource source(file);
  ASSERT_EQ(source.frame_count(), 5u);  // 11.5 is past the odometry: not a frame
  for (std::size_t k = 0; k < source.frame_count(); ++k) {
    const StampedPose& got = source.odometry()[k];
    EXPECT_NEAR(got.timestamp, image_times[k], 1e-9);
    const Eigen::Isometry3d want = pose_at(image_times[k]);
    EXPECT_LT((got.T_world_body.translation() - want.translation()).norm(), 1e-9) << k;
    EXPECT_LT((got.T_world_body.linear() - want.linear()).norm(), 1e-9) << k;
  }
}

TEST(BagSource, AnUndecodableImageIsAnIoErrorAndTheNextFrameFollows) {
  const fs::path file =
      WriteBag(kData / "sim_tiny_stereo", rovermap::testing::ScratchDir() / "bayer.bag",
               {"mono8", "mono8", "bayer_rggb8", "mono8"});
  BagSource source(file);
  Frame frame;
  ASSERT_TRUE(source.Next(&frame));
  const std::string message = ErrorOf([&] { source.Next(&frame); });
  EXPECT_TRUE(Contains(message, file.string())) << message;
  EXPECT_TRUE(Contains(message, "/stereo/left/image_raw at 1000.500000000")) << message;
  EXPECT_TRUE(Contains(message, "unsupported image encoding 'bayer_rggb8'")) << message;
  ASSERT_TRUE(source.Next(&frame));
  EXPECT_EQ(frame.index, 2u);
  EXPECT_FALSE(source.Next(&frame));
}

TEST(BagSource, ABagWithoutWhatItNeedsIsAnIoErrorNamingIt) {
  const fs::path dir = rovermap::testing::ScratchDir();
  EXPECT_TRUE(Contains(ErrorOf([&] { BagSource source(dir / "none.bag"); }), "none.bag"));

  const fs::path file = WriteBag(kData / "sim_tiny_stereo", dir / "tiny.bag", {"mono8"});
  BagOptions options;
  options.right_info_topic = "/elsewhere/camera_info";
  const std::string no_info = ErrorOf([&] { BagSource source(file, options); });
  EXPECT_TRUE(Contains(no_info, "tiny.bag: no sensor_msgs/CameraInfo on /elsewhere/camera_info"))
      << no_info;

  options = BagOptions();
  options.odometry_topic = "/elsewhere/odom";
  EXPECT_TRUE(Contains(ErrorOf([&] { BagSource source(file, options); }),
                       "no nav_msgs/Odometry on /elsewhere/odom"));

  options = BagOptions();
  options.pair_tolerance_s = 0.0005;  // the right images are 1 ms late
  EXPECT_TRUE(
      Contains(ErrorOf([&] { BagSource source(file, options); }), "no left/right image pair"));

  options = BagOptions();
  options.left_image_topic = options.odometry_topic;
  EXPECT_TRUE(Contains(ErrorOf([&] { BagSource source(file, options); }),
                       "/odom is not sensor_msgs/Image"));
}

}  // namespace
}  // namespace rovermap::io
