#pragma once
// Where in a ROS 1 bag the frames, poses, calibration and origin are, and what the bag does not
// say. A plain struct: config/ fills it from the `bag.` keys (config sits above io), and
// io/BagSource reads by it.

#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "io/Georeference.hpp"  // GeodeticOrigin
#include "io/SensorType.hpp"

namespace rovermap::io {

struct BagOptions {
  /// Stereo: frames are left/right image pairs; cloud: frames are PointCloud2 messages.
  SensorType sensor_type = SensorType::kStereo;
  /// sensor_msgs/Image or sensor_msgs/CompressedImage (rectified images).
  std::string left_image_topic = "/stereo/left/image_rect";
  std::string right_image_topic = "/stereo/right/image_rect";
  /// sensor_msgs/CameraInfo: the rectified projections P (required for stereo, optional for
  /// clouds, where they give the stereo error model).
  std::string left_info_topic = "/stereo/left/camera_info";
  std::string right_info_topic = "/stereo/right/camera_info";
  /// sensor_msgs/PointCloud2 (cloud frames, points in the sensor frame).
  std::string cloud_topic = "/points";
  /// Left and right images whose header stamps differ by at most this are a pair [s].
  double pair_tolerance_s = 0.005;
  /// Dead reckoning: nav_msgs/Odometry on `odometry_topic`, or (odometry_from_tf) the /tf
  /// transforms from `odometry_parent_frame` to `odometry_child_frame`.
  std::string odometry_topic = "/odom";
  bool odometry_from_tf = false;
  std::string odometry_parent_frame = "odom";
  std::string odometry_child_frame = "base_link";
  /// nav_msgs/Odometry or geometry_msgs/PoseStamped; empty = no ground truth.
  std::string groundtruth_topic;
  /// sensor_msgs/NavSatFix: the origin when `origin` is not set, and the GNSS fixes of the
  /// pose graph (docs/graph.md).
  std::string navsat_topic = "/fix";
  /// [m] σ east, north and up of a fix whose covariance is unknown (position_covariance_type 0).
  double navsat_sigma_m = 5.0;
  /// T_body_sensor from /tf_static (body_frame -> sensor_frame, chained over static
  /// transforms), else `T_body_sensor`.
  bool T_body_sensor_from_tf_static = false;
  std::string body_frame = "base_link";
  std::string sensor_frame = "stereo_left";
  Eigen::Isometry3d T_body_sensor = Eigen::Isometry3d::Identity();
  /// The world origin when set; else the first NavSatFix with a fix, else `default_origin`.
  std::optional<GeodeticOrigin> origin;
  GeodeticOrigin default_origin;
  std::string body = "earth";  ///< earth|moon|mars
};

}  // namespace rovermap::io
