#pragma once
// ROS 1 bags for the tests, written with rosbag's own API: messages from rovermap's types, and
// a whole sequence directory as the bag a stereo rover would have recorded.

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/NavSatFix.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "io/BagOptions.hpp"
#include "io/CameraModel.hpp"
#include "io/Georeference.hpp"
#include "io/Sequence.hpp"
#include "registration/PointCloud.hpp"

namespace rovermap::testing {

// rosbag takes no message at time 0, where the bundled sequences start.
constexpr double kBagTimeOffset = 1000.0;

inline sensor_msgs::CameraInfo CameraInfoMsg(const io::CameraModel& camera, double tx) {
  sensor_msgs::CameraInfo info;
  info.width = camera.width;
  info.height = camera.height;
  info.K = {camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {camera.fx, 0, camera.cx, tx, 0, camera.fy, camera.cy, 0, 0, 0, 1, 0};
  return info;
}

// `grey` in `encoding` (mono8, rgb8, bgr8 or mono16 little-endian; any other name is written
// as mono8 bytes under that name), with a padded step.
inline sensor_msgs::Image ImageMsg(const cv::Mat& grey, const std::string& encoding, double t) {
  sensor_msgs::Image msg;
  msg.header.stamp = ros::Time(t);
  msg.width = grey.cols;
  msg.height = grey.rows;
  msg.encoding = encoding;
  const int bytes = encoding == "mono16" ? 2 : (encoding == "rgb8" || encoding == "bgr8") ? 3 : 1;
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

// `grey` compressed by OpenCV: extension ".png" or ".jpg".
inline sensor_msgs::CompressedImage CompressedMsg(const cv::Mat& grey, const std::string& extension,
                                                  double t) {
  sensor_msgs::CompressedImage msg;
  msg.header.stamp = ros::Time(t);
  msg.format = extension == ".png" ? "mono8; png compressed " : "mono8; jpeg compressed ";
  cv::imencode(extension, grey, msg.data);
  return msg;
}

inline geometry_msgs::Pose PoseOf(const Eigen::Isometry3d& T) {
  geometry_msgs::Pose pose;
  const Eigen::Quaterniond q(T.linear());
  pose.position.x = T.translation().x();
  pose.position.y = T.translation().y();
  pose.position.z = T.translation().z();
  pose.orientation.x = q.x();
  pose.orientation.y = q.y();
  pose.orientation.z = q.z();
  pose.orientation.w = q.w();
  return pose;
}

inline nav_msgs::Odometry OdometryMsg(const Eigen::Isometry3d& T_world_body, double t) {
  nav_msgs::Odometry msg;
  msg.header.stamp = ros::Time(t);
  msg.header.frame_id = "odom";
  msg.child_frame_id = "base_link";
  msg.pose.pose = PoseOf(T_world_body);
  return msg;
}

inline geometry_msgs::PoseStamped PoseMsg(const Eigen::Isometry3d& T_world_body, double t) {
  geometry_msgs::PoseStamped msg;
  msg.header.stamp = ros::Time(t);
  msg.pose = PoseOf(T_world_body);
  return msg;
}

inline geometry_msgs::TransformStamped TransformMsg(const std::string& parent,
                                                    const std::string& child,
                                                    const Eigen::Isometry3d& T_parent_child,
                                                    double t) {
  geometry_msgs::TransformStamped msg;
  msg.header.stamp = ros::Time(t);
  msg.header.frame_id = parent;
  msg.child_frame_id = child;
  const geometry_msgs::Pose pose = PoseOf(T_parent_child);
  msg.transform.translation.x = pose.position.x;
  msg.transform.translation.y = pose.position.y;
  msg.transform.translation.z = pose.position.z;
  msg.transform.rotation = pose.orientation;
  return msg;
}

inline sensor_msgs::NavSatFix FixMsg(double latitude, double longitude, double altitude, double t,
                                     std::int8_t status = sensor_msgs::NavSatStatus::STATUS_FIX) {
  sensor_msgs::NavSatFix msg;
  msg.header.stamp = ros::Time(t);
  msg.status.status = status;
  msg.latitude = latitude;
  msg.longitude = longitude;
  msg.altitude = altitude;
  return msg;
}

// The points of `cloud` as a PointCloud2: an intensity field first and 4 spare bytes after
// z, so that x, y, z sit at offsets other than 0, 4, 8 within a wider point_step; one NaN
// point (no return) after every 10th point.
inline sensor_msgs::PointCloud2 CloudMsg(const registration::PointCloud& cloud, bool float64,
                                         double t) {
  sensor_msgs::PointCloud2 msg;
  msg.header.stamp = ros::Time(t);
  const std::uint32_t size = float64 ? 8 : 4;
  const std::uint8_t type =
      float64 ? sensor_msgs::PointField::FLOAT64 : sensor_msgs::PointField::FLOAT32;
  sensor_msgs::PointField intensity;
  intensity.name = "intensity";
  intensity.offset = 0;
  intensity.datatype = sensor_msgs::PointField::FLOAT32;
  intensity.count = 1;
  msg.fields.push_back(intensity);
  for (int axis = 0; axis < 3; ++axis) {
    sensor_msgs::PointField f;
    f.name = std::string(1, static_cast<char>('x' + axis));
    f.offset = 4 + axis * size;
    f.datatype = type;
    f.count = 1;
    msg.fields.push_back(f);
  }
  msg.point_step = 4 + 3 * size + 4;
  std::vector<Eigen::Vector3d> points;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    points.push_back(cloud.points[i]);
    if (i % 10 == 9) points.push_back(Eigen::Vector3d::Constant(std::nan("")));
  }
  msg.height = 1;
  msg.width = static_cast<std::uint32_t>(points.size());
  msg.row_step = msg.width * msg.point_step;
  msg.is_dense = false;
  msg.data.assign(static_cast<std::size_t>(msg.row_step), 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::uint8_t* point = &msg.data[i * msg.point_step];
    for (int axis = 0; axis < 3; ++axis) {
      if (float64) {
        const double v = points[i][axis];
        std::memcpy(point + 4 + axis * size, &v, size);
      } else {
        const float v = static_cast<float>(points[i][axis]);
        std::memcpy(point + 4 + axis * size, &v, size);
      }
    }
  }
  return msg;
}

/// How WriteSequenceBag records a sequence.
struct BagRecording {
  /// Stereo images: Image encodings used in turn (left, right, left, ...), or "png"/"jpeg"
  /// for CompressedImage.
  std::vector<std::string> encodings = {"mono8"};
  bool cloud_float64 = false;    ///< cloud sequences: PointCloud2 of float64 coordinates
  bool odometry_on_tf = false;   ///< /tf odom -> base_link instead of /odom
  double right_delay_s = 0.001;  ///< right image stamp after the left one
  /// Frame k's right delay instead, when set.
  std::function<double(std::size_t k)> right_delay_of_frame;
  /// Changes frame k's left or right CompressedImage before it is written (e.g. cuts it).
  std::function<void(std::size_t k, bool left, sensor_msgs::CompressedImage* image)>
      edit_compressed;
  std::string groundtruth_topic;  ///< PoseStamped of groundtruth.tum, when set
  std::size_t truth_frames = std::numeric_limits<std::size_t>::max();  ///< of the first frames
  bool tf_static = true;  ///< base_link -> mast -> stereo_left on /tf_static
  bool navsat = true;     ///< the origin as a NavSatFix (after one without a fix)
  /// > 0: also a NavSatFix of the true body position with every frame, with a diagonal
  /// covariance of this σ (position_covariance_type 2).
  double navsat_track_sigma_m = 0.0;
  /// Changes the camera info just before writing (e.g. to make it unrectified).
  std::function<void(sensor_msgs::CameraInfo* left, sensor_msgs::CameraInfo* right)> edit_info;
};

/// The bag a rover would have recorded of `sequence` on io::BagOptions' default topics,
/// stamps shifted by kBagTimeOffset, in time order.
inline std::filesystem::path WriteSequenceBag(const std::filesystem::path& sequence,
                                              const std::filesystem::path& file,
                                              const BagRecording& how = {}) {
  const io::SequenceReader reader(sequence);
  const io::SequenceInfo& info = reader.info();
  const io::BagOptions topics;
  rosbag::Bag bag(file.string(), rosbag::bagmode::Write);
  const double start = kBagTimeOffset - 1.0;
  const ros::Time start_time(start);
  if (info.camera) {
    const io::CameraModel& camera = *info.camera;
    sensor_msgs::CameraInfo left = CameraInfoMsg(camera, 0.0);
    sensor_msgs::CameraInfo right = CameraInfoMsg(camera, -camera.fx * camera.baseline_m);
    if (how.edit_info) how.edit_info(&left, &right);
    bag.write(topics.left_info_topic, start_time, left);
    bag.write(topics.right_info_topic, start_time, right);
  }
  if (how.tf_static) {
    // Two hops, the second given child -> parent's inverse way round, as a mast would be.
    Eigen::Isometry3d T_body_mast = Eigen::Isometry3d::Identity();
    T_body_mast.translation() = Eigen::Vector3d(0.1, 0.0, 0.5);
    tf2_msgs::TFMessage statics;
    statics.transforms.push_back(TransformMsg("base_link", "mast", T_body_mast, start));
    geometry_msgs::TransformStamped mast_sensor = TransformMsg(
        "/mast", topics.sensor_frame, T_body_mast.inverse() * info.T_body_sensor, start);
    if (info.body_sensor_quaternion) {  // the mast does not rotate: sequence.yaml's own
      const Eigen::Quaterniond& q = *info.body_sensor_quaternion;
      mast_sensor.transform.rotation.x = q.x();
      mast_sensor.transform.rotation.y = q.y();
      mast_sensor.transform.rotation.z = q.z();
      mast_sensor.transform.rotation.w = q.w();
    }
    statics.transforms.push_back(mast_sensor);
    bag.write("/tf_static", start_time, statics);
  }
  if (how.navsat) {
    bag.write(topics.navsat_topic, start_time, FixMsg(0.0, 0.0, 0.0, start, -1));  // no fix yet
    bag.write(topics.navsat_topic, start_time + ros::Duration(0.1),
              FixMsg(info.origin.latitude_deg, info.origin.longitude_deg, info.origin.altitude_m,
                     start + 0.1));
  }
  for (std::size_t k = 0; k < reader.frame_count(); ++k) {
    const io::Frame frame = reader.Read(k);
    const double t = frame.timestamp + kBagTimeOffset;
    const ros::Time time(t);
    if (how.odometry_on_tf) {
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(TransformMsg("map", "odom", Eigen::Isometry3d::Identity(), t));
      tf.transforms.push_back(TransformMsg("odom", "base_link", frame.T_world_body_odom, t));
      bag.write("/tf", time, tf);
    } else {
      bag.write(topics.odometry_topic, time, OdometryMsg(frame.T_world_body_odom, t));
    }
    if (!how.groundtruth_topic.empty() && frame.T_world_body_truth && k < how.truth_frames) {
      bag.write(how.groundtruth_topic, time, PoseMsg(*frame.T_world_body_truth, t));
    }
    if (how.navsat_track_sigma_m > 0.0 && frame.T_world_body_truth) {
      const Eigen::Vector3d p = frame.T_world_body_truth->translation();
      const Eigen::Vector3d geo = io::Georeference(info.origin).EnuToGeodetic(p.x(), p.y(), p.z());
      sensor_msgs::NavSatFix fix = FixMsg(geo.x(), geo.y(), geo.z(), t);
      for (std::size_t i = 0; i < 9; i += 4) {
        fix.position_covariance[i] = how.navsat_track_sigma_m * how.navsat_track_sigma_m;
      }
      fix.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN;
      bag.write(topics.navsat_topic, time, fix);
    }
    if (info.sensor_type == io::SensorType::kCloud) {
      bag.write(topics.cloud_topic, time, CloudMsg(frame.cloud, how.cloud_float64, t));
      continue;
    }
    const double t_right =
        t + (how.right_delay_of_frame ? how.right_delay_of_frame(k) : how.right_delay_s);
    for (const bool left : {true, false}) {
      const std::string& encoding = how.encodings[(2 * k + (left ? 0 : 1)) % how.encodings.size()];
      const cv::Mat& grey = left ? frame.left : frame.right;
      const double stamp = left ? t : t_right;
      const std::string& topic = left ? topics.left_image_topic : topics.right_image_topic;
      if (encoding == "png" || encoding == "jpeg") {
        sensor_msgs::CompressedImage image =
            CompressedMsg(grey, encoding == "png" ? ".png" : ".jpg", stamp);
        if (how.edit_compressed) how.edit_compressed(k, left, &image);
        bag.write(topic, ros::Time(stamp), image);
      } else {
        bag.write(topic, ros::Time(stamp), ImageMsg(grey, encoding, stamp));
      }
    }
  }
  bag.close();
  return file;
}

}  // namespace rovermap::testing
