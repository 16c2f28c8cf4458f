#include "io/BagSource.hpp"

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <utility>

#include "io/IoError.hpp"

namespace rovermap::io {
namespace {

namespace fs = std::filesystem;

// Where one image is: the time it was recorded at (what a View queries by) and its header
// stamp (what tells it from others recorded at the same time).
struct ImageRef {
  ros::Time recorded;
  ros::Time stamp;
};

struct OdomSample {
  double t = 0.0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
};

std::string StampText(const ros::Time& t) {
  char buffer[48];
  std::snprintf(buffer, sizeof(buffer), "%u.%09u", t.sec, t.nsec);
  return buffer;
}

// Position linearly, rotation by slerp, between the samples around `t` (within their span).
Eigen::Isometry3d Interpolate(const std::vector<OdomSample>& odom, double t) {
  auto after = std::upper_bound(odom.begin(), odom.end(), t,
                                [](double v, const OdomSample& s) { return v < s.t; });
  if (after == odom.begin()) ++after;  // t is the first sample's time
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const OdomSample& a = *(after - 1);
  if (after == odom.end() || a.t == t) {
    T.translation() = a.p;
    T.linear() = a.q.toRotationMatrix();
    return T;
  }
  const OdomSample& b = *after;
  const double alpha = (t - a.t) / (b.t - a.t);
  T.translation() = a.p + alpha * (b.p - a.p);
  T.linear() = a.q.slerp(alpha, b.q).normalized().toRotationMatrix();
  return T;
}

// An 8-bit grey copy of `msg`. @throw IoError naming `what` if it cannot be.
cv::Mat ToGrey(const sensor_msgs::Image& msg, const std::string& what) {
  const int width = static_cast<int>(msg.width);
  const int height = static_cast<int>(msg.height);
  int channels = 0;
  int depth_bytes = 1;
  if (msg.encoding == "mono8") {
    channels = 1;
  } else if (msg.encoding == "rgb8" || msg.encoding == "bgr8") {
    channels = 3;
  } else if (msg.encoding == "mono16") {
    channels = 1;
    depth_bytes = 2;
  } else {
    throw IoError(what + ": unsupported image encoding '" + msg.encoding +
                  "' (mono8, rgb8, bgr8, mono16)");
  }
  const std::size_t row_bytes = static_cast<std::size_t>(width) * channels * depth_bytes;
  if (width <= 0 || height <= 0 || msg.step < row_bytes ||
      msg.data.size() < static_cast<std::size_t>(msg.step) * msg.height) {
    throw IoError(what + ": image data does not fit its size (" + std::to_string(width) + "x" +
                  std::to_string(height) + ", step " + std::to_string(msg.step) + ", " +
                  std::to_string(msg.data.size()) + " bytes)");
  }
  cv::Mat grey(height, width, CV_8UC1);
  // cv::Mat cannot take const data; the views below are only read.
  auto* data = const_cast<std::uint8_t*>(msg.data.data());
  if (msg.encoding == "mono8") {
    cv::Mat(height, width, CV_8UC1, data, msg.step).copyTo(grey);
  } else if (channels == 3) {
    cv::cvtColor(cv::Mat(height, width, CV_8UC3, data, msg.step), grey,
                 msg.encoding == "rgb8" ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
  } else {
    // mono16: the high byte, whichever order the bytes are in.
    const int high = msg.is_bigendian ? 0 : 1;
    for (int r = 0; r < height; ++r) {
      const std::uint8_t* in = msg.data.data() + static_cast<std::size_t>(r) * msg.step;
      auto* out = grey.ptr<std::uint8_t>(r);
      for (int c = 0; c < width; ++c) out[c] = in[2 * c + high];
    }
  }
  return grey;
}

}  // namespace

struct BagSource::Bag {
  fs::path file;
  BagOptions options;
  std::mutex mutex;  // rosbag::Bag reads are not thread-safe; Read() is const
  rosbag::Bag bag;
  std::vector<std::pair<ImageRef, ImageRef>> pairs;  // frame k's left and right

  // The image `ref` on `topic`, grey. @throw IoError naming the bag, topic and stamp.
  cv::Mat ReadImage(const std::string& topic, const ImageRef& ref, const CameraModel& camera) {
    const std::string what = file.string() + ": " + topic + " at " + StampText(ref.stamp);
    sensor_msgs::Image::ConstPtr image;
    try {
      rosbag::View view(bag, rosbag::TopicQuery(topic), ref.recorded, ref.recorded);
      for (const rosbag::MessageInstance& m : view) {
        sensor_msgs::Image::ConstPtr candidate = m.instantiate<sensor_msgs::Image>();
        if (candidate && candidate->header.stamp == ref.stamp) {
          image = candidate;
          break;
        }
      }
    } catch (const rosbag::BagException& e) {
      throw IoError(what + ": " + e.what());
    }
    if (!image) throw IoError(what + ": image not found again at its recording time");
    cv::Mat grey = ToGrey(*image, what);
    if (grey.cols != camera.width || grey.rows != camera.height) {
      throw IoError(what + ": image is " + std::to_string(grey.cols) + "x" +
                    std::to_string(grey.rows) + ", the camera info says " +
                    std::to_string(camera.width) + "x" + std::to_string(camera.height));
    }
    return grey;
  }
};

BagSource::BagSource(const fs::path& bag_file, const BagOptions& options)
    : bag_(std::make_unique<Bag>()) {
  bag_->file = bag_file;
  bag_->options = options;
  const std::string name = bag_file.string();
  const BagOptions& o = options;

  std::optional<sensor_msgs::CameraInfo> left_info;
  std::optional<sensor_msgs::CameraInfo> right_info;
  std::vector<OdomSample> odom;
  std::vector<ImageRef> lefts;
  std::vector<ImageRef> rights;
  try {
    bag_->bag.open(name, rosbag::bagmode::Read);
    const std::vector<std::string> topics = {o.left_image_topic, o.right_image_topic,
                                             o.left_info_topic, o.right_info_topic,
                                             o.odometry_topic};
    rosbag::View view(bag_->bag, rosbag::TopicQuery(topics));
    for (const rosbag::MessageInstance& m : view) {
      const std::string& topic = m.getTopic();
      if (topic == o.left_image_topic || topic == o.right_image_topic) {
        // The whole image is decoded once here, for its stamp; none is kept.
        const sensor_msgs::Image::ConstPtr image = m.instantiate<sensor_msgs::Image>();
        if (!image) throw IoError(name + ": " + topic + " is not sensor_msgs/Image");
        (topic == o.left_image_topic ? lefts : rights)
            .push_back({m.getTime(), image->header.stamp});
      } else if (topic == o.odometry_topic) {
        const nav_msgs::Odometry::ConstPtr msg = m.instantiate<nav_msgs::Odometry>();
        if (!msg) throw IoError(name + ": " + topic + " is not nav_msgs/Odometry");
        const auto& p = msg->pose.pose.position;
        const auto& q = msg->pose.pose.orientation;
        const Eigen::Quaterniond rotation(q.w, q.x, q.y, q.z);
        if (std::abs(rotation.norm() - 1.0) > 1e-3) {
          throw IoError(name + ": " + topic + " at " + StampText(msg->header.stamp) +
                        ": orientation is not a unit quaternion");
        }
        odom.push_back({msg->header.stamp.toSec(), {p.x, p.y, p.z}, rotation.normalized()});
      } else {
        const sensor_msgs::CameraInfo::ConstPtr msg = m.instantiate<sensor_msgs::CameraInfo>();
        if (!msg) throw IoError(name + ": " + topic + " is not sensor_msgs/CameraInfo");
        auto& slot = topic == o.left_info_topic ? left_info : right_info;
        if (!slot) slot = *msg;
      }
    }
  } catch (const rosbag::BagException& e) {
    throw IoError(name + ": " + e.what());
  }

  if (!left_info) throw IoError(name + ": no sensor_msgs/CameraInfo on " + o.left_info_topic);
  if (!right_info) throw IoError(name + ": no sensor_msgs/CameraInfo on " + o.right_info_topic);
  CameraModel camera;
  camera.width = static_cast<int>(left_info->width);
  camera.height = static_cast<int>(left_info->height);
  camera.fx = left_info->P[0];
  camera.fy = left_info->P[5];
  camera.cx = left_info->P[2];
  camera.cy = left_info->P[6];
  const double right_fx = right_info->P[0];
  camera.baseline_m = right_fx > 0.0 ? -right_info->P[3] / right_fx : 0.0;
  if (!(camera.fx > 0.0 && camera.fy > 0.0 && camera.width > 0 && camera.height > 0)) {
    throw IoError(name + ": " + o.left_info_topic +
                  ": needs a projection P with fx, fy > 0 and a width and height");
  }
  if (!(camera.baseline_m > 0.0)) {
    throw IoError(name + ": " + o.right_info_topic +
                  ": projection P gives no positive baseline (-P[0,3]/fx)");
  }
  if (right_info->width != left_info->width || right_info->height != left_info->height) {
    throw IoError(name + ": left and right camera info differ in image size");
  }

  std::stable_sort(odom.begin(), odom.end(),
                   [](const OdomSample& a, const OdomSample& b) { return a.t < b.t; });
  if (odom.empty()) throw IoError(name + ": no nav_msgs/Odometry on " + o.odometry_topic);

  // Pairs: each left with the nearest unused right within the tolerance.
  auto by_stamp = [](const ImageRef& a, const ImageRef& b) { return a.stamp < b.stamp; };
  std::stable_sort(lefts.begin(), lefts.end(), by_stamp);
  std::stable_sort(rights.begin(), rights.end(), by_stamp);
  std::size_t j = 0;
  for (const ImageRef& left : lefts) {
    const double t = left.stamp.toSec();
    while (j < rights.size() && rights[j].stamp.toSec() < t - o.pair_tolerance_s) ++j;
    if (j == rights.size()) break;
    if (j + 1 < rights.size() &&
        std::abs(rights[j + 1].stamp.toSec() - t) < std::abs(rights[j].stamp.toSec() - t)) {
      ++j;
    }
    if (std::abs(rights[j].stamp.toSec() - t) > o.pair_tolerance_s) continue;
    // Only where odometry gives a pose without extrapolating.
    if (t >= odom.front().t && t <= odom.back().t) {
      bag_->pairs.emplace_back(left, rights[j]);
      StampedPose pose;
      pose.timestamp = t;
      pose.T_world_body = Interpolate(odom, t);
      odometry_.push_back(pose);
    }
    ++j;
  }
  if (odometry_.empty()) {
    throw IoError(name + ": no left/right image pair within " + std::to_string(o.pair_tolerance_s) +
                  " s of each other and within the odometry's time span (" + o.left_image_topic +
                  ", " + o.right_image_topic + ")");
  }

  info_.directory = bag_file;
  info_.sensor_type = SensorType::kStereo;
  info_.camera = camera;
  info_.T_body_sensor = o.T_body_sensor;
  info_.origin = o.origin;
  info_.body = o.body;
  const double span = odometry_.back().timestamp - odometry_.front().timestamp;
  info_.frame_rate_hz =
      odometry_.size() > 1 && span > 0.0 ? static_cast<double>(odometry_.size() - 1) / span : 0.0;
}

BagSource::~BagSource() = default;

void BagSource::LoadFrame(Frame* frame) const {
  frame->file = bag_->file;
  const auto& [left, right] = bag_->pairs[frame->index];
  const std::lock_guard<std::mutex> lock(bag_->mutex);
  frame->left = bag_->ReadImage(bag_->options.left_image_topic, left, *info_.camera);
  frame->right = bag_->ReadImage(bag_->options.right_image_topic, right, *info_.camera);
}

}  // namespace rovermap::io
