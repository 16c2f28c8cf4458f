#pragma once
// The rules of reading a bag, one set for every container (ROS 1 bags, ROS 2 MCAP and SQLite):
// which topics are read and what for, the checks on images, clouds and calibration, stereo
// pairing, pose interpolation, what is skipped, and the error messages. A container reader only
// lists its topics, decodes messages into io/BagMessages.hpp and feeds them here.

#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "io/BagMessages.hpp"
#include "io/BagOptions.hpp"
#include "io/FrameSource.hpp"
#include "io/Gnss.hpp"
#include "registration/PointCloud.hpp"

namespace rovermap::io::bag {

/// The message type names of one ROS generation.
struct TypeNames {
  std::string image;
  std::string compressed;
  std::string info;
  std::string cloud;
  std::string odometry;
  std::string pose;
  std::string tf;
  std::string navsat;
};
const TypeNames& Ros1Types();  ///< "sensor_msgs/Image", ...
const TypeNames& Ros2Types();  ///< "sensor_msgs/msg/Image", ...

extern const char* const kTfTopic;
extern const char* const kTfStaticTopic;

/// "sec.nanosec", as the messages name a stamp.
std::string StampText(const Stamp& stamp);

/// One image or cloud: its header stamp and the reader's own handle to find it again.
struct MessageRef {
  std::size_t id = 0;
  Stamp stamp;
};

/// What a topic's messages are read for.
enum class Role { kNone, kImage, kCloud, kCameraInfo, kTf, kOdometry, kGroundTruth, kNavSat };

/// What opening a bag found: each frame's messages (left and right image, or the cloud twice),
/// poses, what was skipped, and the sequence's description.
struct BagPlan {
  std::vector<std::pair<MessageRef, MessageRef>> frames;
  std::vector<GnssFix> gnss;  ///< every NavSatFix with a fix, by time
  std::vector<StampedPose> odometry;
  std::vector<StampedPose> groundtruth;  ///< empty, or one per frame
  SkippedFrames skipped;
  SequenceInfo info;
};

/// Collects a bag's messages in one pass and plans its frames (docs/bags.md). Messages may come
/// in any order.
class BagContents {
 public:
  BagContents(const std::filesystem::path& bag_file, const BagOptions& options,
              const TypeNames& types);
  ~BagContents();
  BagContents(const BagContents&) = delete;
  BagContents& operator=(const BagContents&) = delete;

  /// The topics to read, given every topic of the bag and its type.
  /// @throw IoError naming the bag if one is missing (listing what the bag has) or of another
  ///        type.
  std::vector<std::string> TopicsToRead(const std::map<std::string, std::string>& types) const;

  /// What the messages on `topic` are for now (kNone: not wanted, or no longer).
  Role RoleOf(const std::string& topic) const;

  /// "bag: topic has a <actual> message, not <expected>" (a topic recorded with two types).
  std::string WrongType(const std::string& topic, const std::string& actual,
                        const std::string& expected) const;
  /// "bag: topic at stamp", the start of a message's error.
  std::string Where(const std::string& topic, const Stamp& stamp) const;

  /// @throw IoError naming the bag, topic and stamp if the encoding or format is not read.
  void AddImage(const std::string& topic, const ImageMsg& msg, std::size_t id);
  void AddImage(const std::string& topic, const CompressedImageMsg& msg, std::size_t id);
  /// @throw IoError naming the bag, topic and stamp if the point layout is not read.
  void AddCloud(const PointCloudMsg& msg, std::size_t id);
  void AddCameraInfo(const std::string& topic, const CameraInfoMsg& msg);
  /// @throw IoError naming the bag, topic and stamp if a rotation is not a unit quaternion.
  void AddTransforms(const std::string& topic, const std::vector<TransformMsg>& transforms);
  void AddOdometry(const PoseMsg& msg);
  void AddGroundTruth(const PoseMsg& msg);
  void AddNavSatFix(const NavSatFixMsg& msg);

  /// The frames of what was added.
  /// @throw IoError naming the bag if calibration, odometry or ground truth is missing or
  ///        unfit, /tf_static does not connect body and sensor, or no frame has poses.
  BagPlan Finish();

  struct Collected;  // what has been added (BagRules.cpp)

 private:
  std::filesystem::path file_;
  std::string name_;
  BagOptions options_;
  TypeNames types_;
  std::unique_ptr<Collected> c_;
};

/// A bag as a FrameSource, whatever its container: it keeps the plan (each frame's messages and
/// poses) and reads a frame's images or cloud through the container's ReadImage and ReadCloud,
/// one read at a time (the readers keep a read position).
class BagFrameSource : public IndexedFrameSource {
 public:
  SkippedFrames skipped() const override { return skipped_; }

 protected:
  BagFrameSource(std::filesystem::path bag_file, BagOptions options);
  /// Takes the frames, poses, skips and description of `plan`.
  void Adopt(BagPlan plan);

  /// The image `ref` on `topic`, 8-bit grey. @throw IoError naming the bag, topic and stamp.
  virtual cv::Mat ReadImage(const std::string& topic, const MessageRef& ref) const = 0;
  /// The cloud `ref`. @throw IoError naming the bag, topic and stamp.
  virtual registration::PointCloud ReadCloud(const MessageRef& ref) const = 0;

  const std::filesystem::path& file() const { return file_; }
  const BagOptions& options() const { return options_; }

 private:
  /// @throw IoError naming the bag, topic and stamp if an image or cloud cannot be decoded or an
  ///        image does not have the camera's size.
  void LoadFrame(Frame* frame) const final;

  std::filesystem::path file_;
  BagOptions options_;
  std::vector<std::pair<MessageRef, MessageRef>> frames_;  // left and right, or the cloud twice
  SkippedFrames skipped_;
  mutable std::mutex mutex_;
};

/// "bag: topic at stamp", for errors about one frame's message.
std::string FrameWhat(const std::filesystem::path& bag_file, const std::string& topic,
                      const Stamp& stamp);

/// An 8-bit grey copy of the image. @throw IoError naming `what` if it cannot be.
cv::Mat ToGrey(const ImageMsg& msg, const std::string& what);
/// PNG or JPEG, made 8-bit grey (a 16-bit PNG keeps its high byte, as mono16 does).
cv::Mat ToGrey(const CompressedImageMsg& msg, const std::string& what);
/// @throw IoError naming `what` unless `grey` has the camera's size.
void CheckImageSize(const cv::Mat& grey, const CameraModel& camera, const std::string& what);

/// Every point of a cloud, non-finite ones included. @throw IoError naming `what` if the
/// layout is not read or the data does not fit.
registration::PointCloud ToCloud(const PointCloudMsg& msg, const std::string& what);

}  // namespace rovermap::io::bag
