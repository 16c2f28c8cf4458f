#pragma once
// A stereo recording in a ROS 1 bag, read as a FrameSource: left and right sensor_msgs/Image,
// their sensor_msgs/CameraInfo, and nav_msgs/Odometry. Only built with ROVERMAP_WITH_ROSBAG;
// no ROS header shows here.

#include <Eigen/Geometry>
#include <filesystem>
#include <memory>
#include <string>

#include "io/Frame.hpp"
#include "io/FrameSource.hpp"
#include "io/Georeference.hpp"

namespace rovermap::io {

/// What a bag does not say, and where in it the stereo pair is.
struct BagOptions {
  std::string left_image_topic = "/stereo/left/image_raw";
  std::string right_image_topic = "/stereo/right/image_raw";
  std::string left_info_topic = "/stereo/left/camera_info";
  std::string right_info_topic = "/stereo/right/camera_info";
  std::string odometry_topic = "/odom";
  /// Left and right images whose header stamps differ by at most this are a pair [s].
  double pair_tolerance_s = 0.005;
  Eigen::Isometry3d T_body_sensor = Eigen::Isometry3d::Identity();
  GeodeticOrigin origin;
  std::string body = "earth";
};

/// Opens a bag and pairs its images; then Next() reads the pairs in time order.
///
/// Opening reads the camera info (fx, fy, cx, cy from the left projection P, baseline
/// -P[0,3]/fx from the right one), every odometry message, and the header stamps of every
/// image. Frame k is the k-th pair (by left stamp) that falls within the odometry's time span;
/// its timestamp is the left stamp and its pose the odometry interpolated there (position
/// linearly, rotation by slerp). Images may be mono8, rgb8, bgr8 (made grey) or mono16 (high
/// byte kept). A bag has no ground truth here.
class BagSource : public IndexedFrameSource {
 public:
  /// @throw IoError naming the bag if it cannot be read, or lacks camera info, odometry or
  ///        image pairs.
  explicit BagSource(const std::filesystem::path& bag_file, const BagOptions& options = {});
  ~BagSource() override;
  BagSource(const BagSource&) = delete;
  BagSource& operator=(const BagSource&) = delete;

 private:
  /// @throw IoError naming the bag, topic and stamp if an image cannot be decoded or does not
  ///        have the camera's size.
  void LoadFrame(Frame* frame) const override;

  struct Bag;  // the open rosbag::Bag and where each pair's messages are in it

  std::unique_ptr<Bag> bag_;
};

}  // namespace rovermap::io
