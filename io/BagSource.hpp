#pragma once
// A recording in a ROS 1 bag, read as a FrameSource: stereo pairs (sensor_msgs/Image or
// CompressedImage with their CameraInfo) or point clouds (sensor_msgs/PointCloud2), dead
// reckoning from nav_msgs/Odometry or /tf, optional ground truth, T_body_sensor from /tf_static
// and the origin from a NavSatFix. Only built with ROVERMAP_WITH_ROSBAG; no ROS header shows
// here.

#include <filesystem>
#include <memory>
#include <string>

#include "io/BagOptions.hpp"
#include "io/BagRules.hpp"
#include "io/Frame.hpp"
#include "io/FrameSource.hpp"

namespace rovermap::io {

/// Opens a bag and finds its frames; then Next() reads them in time order.
///
/// Opening reads every message on the topics of `options` once: the camera info (fx, fy, cx,
/// cy from the left projection P, baseline -P[0,3]/fx from the right one), the poses, and the
/// header stamps of every image or cloud (checking encodings and point layouts; their data is
/// skipped over, not deserialised: an image is when its frame is read). Frame k is the
/// k-th pair (by left stamp) or cloud that falls within the odometry's time span (and the
/// ground truth's, when there is one); its timestamp is that stamp and its poses are
/// interpolated there (position linearly, rotation by slerp). Images may be mono8, rgb8, bgr8
/// (made grey), mono16 (high byte kept) or PNG/JPEG CompressedImage; clouds need float32 or
/// float64 x, y, z fields (non-finite points are kept, for the mapper to drop and count). skipped()
/// counts what gave no frame.
class BagSource : public bag::BagFrameSource {
 public:
  /// @throw IoError naming the bag if it cannot be read (missing, truncated, unindexed), lacks a
  ///        topic (the message lists the topics and types it has), holds a topic of the wrong
  ///        type, an unsupported image encoding or point layout, a calibration that is not a
  ///        rectified stereo pair, or no frame within the poses' time span.
  explicit BagSource(const std::filesystem::path& bag_file, const BagOptions& options = {});
  ~BagSource() override;
  BagSource(const BagSource&) = delete;
  BagSource& operator=(const BagSource&) = delete;

 private:
  cv::Mat ReadImage(const std::string& topic, const bag::MessageRef& ref) const override;
  registration::PointCloud ReadCloud(const bag::MessageRef& ref) const override;

  struct Bag;  // the open rosbag::Bag and when each image or cloud was recorded

  std::unique_ptr<Bag> bag_;
};

}  // namespace rovermap::io
