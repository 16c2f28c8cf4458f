#include "io/BagRules.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>
#include <utility>

#include "io/IoError.hpp"
#include "io/Rpy.hpp"

namespace rovermap::io::bag {

const char* const kTfTopic = "/tf";
const char* const kTfStaticTopic = "/tf_static";

const TypeNames& Ros1Types() {
  static const TypeNames names{"sensor_msgs/Image",      "sensor_msgs/CompressedImage",
                               "sensor_msgs/CameraInfo", "sensor_msgs/PointCloud2",
                               "nav_msgs/Odometry",      "geometry_msgs/PoseStamped",
                               "tf2_msgs/TFMessage",     "sensor_msgs/NavSatFix"};
  return names;
}

const TypeNames& Ros2Types() {
  static const TypeNames names{"sensor_msgs/msg/Image",      "sensor_msgs/msg/CompressedImage",
                               "sensor_msgs/msg/CameraInfo", "sensor_msgs/msg/PointCloud2",
                               "nav_msgs/msg/Odometry",      "geometry_msgs/msg/PoseStamped",
                               "tf2_msgs/msg/TFMessage",     "sensor_msgs/msg/NavSatFix"};
  return names;
}

double Stamp::ToSec() const {
  const std::int64_t ns = sec * 1000000000 + nsec;
  // Below 2^53 both are exact doubles: one division, rounded once, to the nearest.
  if (std::llabs(ns) < (std::int64_t{1} << 53)) return static_cast<double>(ns) / 1e9;
  // Beyond, the decimal text, read as ReadTum reads it.
  const std::uint64_t magnitude =
      ns < 0 ? 0 - static_cast<std::uint64_t>(ns) : static_cast<std::uint64_t>(ns);
  char text[48];
  const int length = std::snprintf(text, sizeof(text), "%s%llu.%09llu", ns < 0 ? "-" : "",
                                   static_cast<unsigned long long>(magnitude / 1000000000),
                                   static_cast<unsigned long long>(magnitude % 1000000000));
  double t = 0.0;
  std::from_chars(text, text + length, t);
  return t;
}

std::string StampText(const Stamp& t) {
  char buffer[48];
  std::snprintf(buffer, sizeof(buffer), "%lld.%09u", static_cast<long long>(t.sec), t.nsec);
  return buffer;
}

std::string FrameWhat(const std::filesystem::path& bag_file, const std::string& topic,
                      const Stamp& stamp) {
  return bag_file.string() + ": " + topic + " at " + StampText(stamp);
}

namespace {

// tf names frames with or without a leading slash.
std::string FrameName(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

// The pose `p` at `stamp`: its rotation made from its quaternion, which it keeps, so that an
// imported sequence's TUM files hold that very quaternion and read back to this rotation.
// @throw IoError naming `what` unless the quaternion is a unit one (within 1e-3).
StampedPose ToPose(const Stamp& stamp, const PoseValue& p, const std::string& what) {
  const Eigen::Quaterniond q(p.orientation[3], p.orientation[0], p.orientation[1],
                             p.orientation[2]);
  if (!(std::abs(q.norm() - 1.0) <= 1e-3)) {
    throw IoError(what + ": orientation is not a unit quaternion");
  }
  StampedPose pose;
  pose.timestamp = stamp.ToSec();
  pose.T_world_body.translation() = Eigen::Vector3d(p.position[0], p.position[1], p.position[2]);
  pose.T_world_body.linear() = RotationFromQuaternion(q);
  pose.quaternion = q;
  return pose;
}

// Position linearly, rotation by slerp, between the samples around `t` (within their span).
StampedPose Interpolate(const std::vector<StampedPose>& samples, double t) {
  auto after = std::upper_bound(samples.begin(), samples.end(), t,
                                [](double v, const StampedPose& s) { return v < s.timestamp; });
  if (after == samples.begin()) ++after;  // t is the first sample's time
  const StampedPose& a = *(after - 1);
  if (after == samples.end() || a.timestamp == t) return a;
  const StampedPose& b = *after;
  const double alpha = (t - a.timestamp) / (b.timestamp - a.timestamp);
  StampedPose pose;
  pose.timestamp = t;
  pose.T_world_body.translation() =
      a.T_world_body.translation() +
      alpha * (b.T_world_body.translation() - a.T_world_body.translation());
  const Eigen::Quaterniond qa(a.T_world_body.linear());
  const Eigen::Quaterniond qb(b.T_world_body.linear());
  pose.quaternion = qa.slerp(alpha, qb);
  pose.T_world_body.linear() = RotationFromQuaternion(*pose.quaternion);
  return pose;
}

bool Covers(const std::vector<StampedPose>& samples, double t) {
  return !samples.empty() && t >= samples.front().timestamp && t <= samples.back().timestamp;
}

bool IsSupportedEncoding(const std::string& encoding) {
  return encoding == "mono8" || encoding == "rgb8" || encoding == "bgr8" || encoding == "mono16";
}

// A CompressedImage's format ("png", "jpeg", "bgr8; jpeg compressed bgr8") names its codec.
bool IsSupportedFormat(const std::string& format) {
  return format.find("png") != std::string::npos || format.find("jpeg") != std::string::npos ||
         format.find("jpg") != std::string::npos;
}

// Byte offsets of x, y, z in a PointCloud2's points, and whether they are float64.
struct CloudLayout {
  std::array<std::uint32_t, 3> offset{};
  bool float64 = false;
};

// @throw IoError naming `what` unless the cloud has float32 or float64 x, y, z fields inside
//        its point_step and data for all its points.
CloudLayout CheckCloud(const PointCloudMsg& msg, const std::string& what) {
  CloudLayout layout;
  const char* names[3] = {"x", "y", "z"};
  std::optional<std::uint8_t> datatype;
  for (int axis = 0; axis < 3; ++axis) {
    const auto field = std::find_if(msg.fields.begin(), msg.fields.end(),
                                    [&](const PointFieldMsg& f) { return f.name == names[axis]; });
    if (field == msg.fields.end()) {
      throw IoError(what + ": the point cloud has no '" + names[axis] + "' field");
    }
    if (field->datatype != kFloat32 && field->datatype != kFloat64) {
      throw IoError(what + ": field '" + names[axis] + "' has datatype " +
                    std::to_string(field->datatype) + " (float32 = 7 or float64 = 8 expected)");
    }
    if (datatype && *datatype != field->datatype) {
      throw IoError(what + ": x, y and z fields differ in datatype");
    }
    datatype = field->datatype;
    layout.offset[axis] = field->offset;
  }
  layout.float64 = *datatype == kFloat64;
  const std::uint32_t size = layout.float64 ? 8 : 4;
  for (const std::uint32_t offset : layout.offset) {
    if (offset + size > msg.point_step) {
      throw IoError(what + ": a coordinate field lies beyond point_step " +
                    std::to_string(msg.point_step));
    }
  }
  if (msg.is_bigendian) throw IoError(what + ": big-endian point clouds are not supported");
  const std::size_t row_bytes = static_cast<std::size_t>(msg.width) * msg.point_step;
  if (msg.row_step < row_bytes ||
      msg.data.size < static_cast<std::size_t>(msg.row_step) * msg.height) {
    throw IoError(what + ": point data does not fit its size (" + std::to_string(msg.width) + "x" +
                  std::to_string(msg.height) + " points, step " + std::to_string(msg.point_step) +
                  ", " + std::to_string(msg.data.size) + " bytes)");
  }
  return layout;
}

// The rectified pair of `left` and `right`. @throw IoError naming `name` and the topic unless
// both projections have the rectified form [f 0 c Tx; 0 f c 0; 0 0 1 0], share intrinsics and
// image size, the left has Tx = 0 and the right a positive baseline.
CameraModel StereoCamera(const CameraInfoMsg& left, const CameraInfoMsg& right,
                         const std::string& name, const BagOptions& o) {
  auto check_form = [&](const CameraInfoMsg& info, const std::string& topic) {
    const auto& P = info.P;
    const bool rectified = P[0] > 0.0 && P[5] > 0.0 && P[1] == 0.0 && P[4] == 0.0 && P[8] == 0.0 &&
                           P[9] == 0.0 && P[10] == 1.0 && P[7] == 0.0 && P[11] == 0.0;
    if (!rectified) {
      throw IoError(name + ": " + topic +
                    ": projection P is not that of a rectified camera ([fx 0 cx Tx; 0 fy cy 0; "
                    "0 0 1 0] with fx, fy > 0): rovermap needs rectified images");
    }
    if (info.width == 0 || info.height == 0) {
      throw IoError(name + ": " + topic + ": camera info has no image size");
    }
  };
  check_form(left, o.left_info_topic);
  check_form(right, o.right_info_topic);
  if (right.width != left.width || right.height != left.height) {
    throw IoError(name + ": left and right camera info differ in image size (" +
                  std::to_string(left.width) + "x" + std::to_string(left.height) + " and " +
                  std::to_string(right.width) + "x" + std::to_string(right.height) +
                  "): not a rectified pair");
  }
  auto same = [](double a, double b) {
    return std::abs(a - b) <= 1e-6 * std::max(1.0, std::abs(a));
  };
  if (!same(left.P[0], right.P[0]) || !same(left.P[5], right.P[5]) ||
      !same(left.P[2], right.P[2]) || !same(left.P[6], right.P[6])) {
    throw IoError(name +
                  ": left and right projections P differ in fx, fy, cx or cy: not a "
                  "rectified pair");
  }
  if (left.P[3] != 0.0) {
    throw IoError(name + ": " + o.left_info_topic + ": the left projection has Tx = P[0,3] = " +
                  std::to_string(left.P[3]) + " (0 for the left camera of a rectified pair)");
  }
  CameraModel camera;
  camera.width = static_cast<int>(left.width);
  camera.height = static_cast<int>(left.height);
  camera.fx = left.P[0];
  camera.fy = left.P[5];
  camera.cx = left.P[2];
  camera.cy = left.P[6];
  camera.baseline_m = 0.0 - right.P[3] / right.P[0];  // 0.0 -: no "-0" in messages
  if (!(camera.baseline_m > 0.0)) {
    throw IoError(name + ": " + o.right_info_topic +
                  ": projection P gives no positive baseline (-P[0,3]/fx = " +
                  std::to_string(camera.baseline_m) + " m): not a rectified stereo pair");
  }
  return camera;
}

// One static transform: T_parent_child as tf gives it, a translation and a unit quaternion.
struct StaticEdge {
  std::string parent;
  std::string child;
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
};

// A rigid transform kept as a quaternion: chained that way, a chain whose other links do not
// rotate ends with the sensor link's own quaternion, bit for bit (sequence.yaml's form).
struct QuaternionTransform {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  QuaternionTransform operator*(const QuaternionTransform& b) const {
    return {q * b.q, t + RotationFromQuaternion(q) * b.t};
  }
  QuaternionTransform Inverse() const {
    const Eigen::Quaterniond q_inverse = q.conjugate();
    return {q_inverse, -(RotationFromQuaternion(q_inverse) * t)};
  }
};

// T_from_to over the static transforms, walked either way.
std::optional<QuaternionTransform> Chain(const std::vector<StaticEdge>& edges,
                                         const std::string& from, const std::string& to) {
  std::map<std::string, QuaternionTransform> reached = {{from, QuaternionTransform()}};
  std::vector<std::string> frontier = {from};
  while (!frontier.empty()) {
    const std::string frame = frontier.back();
    frontier.pop_back();
    const QuaternionTransform T_from_frame = reached.at(frame);
    for (const StaticEdge& e : edges) {
      std::string next;
      QuaternionTransform T_frame_next{e.q, e.t};
      if (e.parent == frame) {
        next = e.child;
      } else if (e.child == frame) {
        next = e.parent;
        T_frame_next = T_frame_next.Inverse();
      } else {
        continue;
      }
      if (reached.count(next) != 0) continue;
      reached[next] = T_from_frame * T_frame_next;
      frontier.push_back(next);
    }
  }
  const auto it = reached.find(to);
  if (it == reached.end()) return std::nullopt;
  return it->second;
}

// T_body_sensor over the static transforms. @throw IoError naming `name` if they do not
// connect the two frames.
QuaternionTransform StaticBodySensor(const std::vector<StaticEdge>& statics, const BagOptions& o,
                                     const std::string& name) {
  const std::optional<QuaternionTransform> T =
      Chain(statics, FrameName(o.body_frame), FrameName(o.sensor_frame));
  if (T) return *T;
  std::string seen;
  for (const StaticEdge& e : statics)
    seen += (seen.empty() ? "" : ", ") + e.parent + " -> " + e.child;
  throw IoError(name + ": /tf_static does not connect " + o.body_frame + " to " + o.sensor_frame +
                " (it has: " + (seen.empty() ? "nothing" : seen) + ")");
}

// Each left (by stamp) with the nearest unused right within `tolerance_s`.
std::vector<std::pair<MessageRef, MessageRef>> PairImages(const std::vector<MessageRef>& lefts,
                                                          const std::vector<MessageRef>& rights,
                                                          double tolerance_s) {
  std::vector<std::pair<MessageRef, MessageRef>> pairs;
  std::size_t j = 0;
  for (const MessageRef& left : lefts) {
    const double t = left.stamp.ToSec();
    while (j < rights.size() && rights[j].stamp.ToSec() < t - tolerance_s) ++j;
    if (j == rights.size()) break;
    if (j + 1 < rights.size() &&
        std::abs(rights[j + 1].stamp.ToSec() - t) < std::abs(rights[j].stamp.ToSec() - t)) {
      ++j;
    }
    if (std::abs(rights[j].stamp.ToSec() - t) > tolerance_s) continue;
    pairs.emplace_back(left, rights[j]);
    ++j;
  }
  return pairs;
}

}  // namespace

// What one pass over a bag's messages finds.
struct BagContents::Collected {
  std::optional<CameraInfoMsg> left_info;
  std::optional<CameraInfoMsg> right_info;
  std::vector<StampedPose> odom;   // by time
  std::vector<StampedPose> truth;  // by time
  std::vector<StaticEdge> statics;
  std::set<std::string> tf_pairs;  // "parent -> child" on /tf other than the odometry's
  std::optional<GeodeticOrigin> fix;
  std::vector<GnssFix> gnss;      // every usable NavSatFix
  std::vector<MessageRef> lefts;  // stereo images, or clouds (in lefts), by stamp
  std::vector<MessageRef> rights;
};

BagContents::BagContents(const std::filesystem::path& bag_file, const BagOptions& options,
                         const TypeNames& types)
    : file_(bag_file),
      name_(bag_file.string()),
      options_(options),
      types_(types),
      c_(std::make_unique<Collected>()) {}

BagContents::~BagContents() = default;

std::vector<std::string> BagContents::TopicsToRead(
    const std::map<std::string, std::string>& types) const {
  const BagOptions& o = options_;
  std::vector<std::string> topics;
  auto want = [&](const std::string& topic, const std::set<std::string>& allowed) {
    const auto it = types.find(topic);
    if (it == types.end()) {
      std::string list;
      for (const auto& [t, type] : types)
        list += (list.empty() ? "" : ", ") + t + " (" + type + ")";
      throw IoError(name_ + ": no topic " + topic +
                    " (the bag has: " + (list.empty() ? std::string("no topics") : list) + ")");
    }
    if (allowed.count(it->second) == 0) {
      std::string list;
      for (const std::string& a : allowed) list += (list.empty() ? "" : " or ") + a;
      throw IoError(name_ + ": " + topic + " is " + it->second + ", not " + list);
    }
    topics.push_back(topic);
  };
  const bool stereo = o.sensor_type == SensorType::kStereo;
  if (stereo) {
    want(o.left_image_topic, {types_.image, types_.compressed});
    want(o.right_image_topic, {types_.image, types_.compressed});
  } else {
    want(o.cloud_topic, {types_.cloud});
  }
  // Clouds take a camera (their stereo error model) only when the bag has both.
  if (stereo || (types.count(o.left_info_topic) != 0 && types.count(o.right_info_topic) != 0)) {
    want(o.left_info_topic, {types_.info});
    want(o.right_info_topic, {types_.info});
  }
  want(o.odometry_from_tf ? kTfTopic : o.odometry_topic,
       {o.odometry_from_tf ? types_.tf : types_.odometry});
  if (!o.groundtruth_topic.empty()) want(o.groundtruth_topic, {types_.odometry, types_.pose});
  if (o.T_body_sensor_from_tf_static) want(kTfStaticTopic, {types_.tf});
  if (types.count(o.navsat_topic) != 0) want(o.navsat_topic, {types_.navsat});
  return topics;
}

Role BagContents::RoleOf(const std::string& topic) const {
  const BagOptions& o = options_;
  const bool stereo = o.sensor_type == SensorType::kStereo;
  if (stereo && (topic == o.left_image_topic || topic == o.right_image_topic)) return Role::kImage;
  if (!stereo && topic == o.cloud_topic) return Role::kCloud;
  if (topic == o.left_info_topic || topic == o.right_info_topic) {
    // The first camera info on each topic is the one used.
    const auto& slot = topic == o.left_info_topic ? c_->left_info : c_->right_info;
    return slot ? Role::kNone : Role::kCameraInfo;
  }
  if (topic == kTfStaticTopic || (o.odometry_from_tf && topic == kTfTopic)) return Role::kTf;
  if (topic == o.odometry_topic && !o.odometry_from_tf) return Role::kOdometry;
  if (topic == o.groundtruth_topic) return Role::kGroundTruth;
  if (topic == o.navsat_topic) return Role::kNavSat;
  return Role::kNone;
}

std::string BagContents::WrongType(const std::string& topic, const std::string& actual,
                                   const std::string& expected) const {
  return name_ + ": " + topic + " has a " + actual + " message, not " + expected;
}

std::string BagContents::Where(const std::string& topic, const Stamp& stamp) const {
  return FrameWhat(file_, topic, stamp);
}

void BagContents::AddImage(const std::string& topic, const ImageMsg& msg, std::size_t id) {
  if (!IsSupportedEncoding(msg.encoding)) {
    throw IoError(Where(topic, msg.stamp) + ": unsupported image encoding '" + msg.encoding +
                  "' (mono8, rgb8, bgr8, mono16)");
  }
  (topic == options_.left_image_topic ? c_->lefts : c_->rights).push_back({id, msg.stamp});
}

void BagContents::AddImage(const std::string& topic, const CompressedImageMsg& msg,
                           std::size_t id) {
  if (!IsSupportedFormat(msg.format)) {
    throw IoError(Where(topic, msg.stamp) + ": unsupported compressed image format '" + msg.format +
                  "' (png, jpeg)");
  }
  (topic == options_.left_image_topic ? c_->lefts : c_->rights).push_back({id, msg.stamp});
}

void BagContents::AddCloud(const PointCloudMsg& msg, std::size_t id) {
  CheckCloud(msg, Where(options_.cloud_topic, msg.stamp));
  c_->lefts.push_back({id, msg.stamp});
}

void BagContents::AddCameraInfo(const std::string& topic, const CameraInfoMsg& msg) {
  auto& slot = topic == options_.left_info_topic ? c_->left_info : c_->right_info;
  if (!slot) slot = msg;
}

void BagContents::AddTransforms(const std::string& topic,
                                const std::vector<TransformMsg>& transforms) {
  const std::string odom_parent = FrameName(options_.odometry_parent_frame);
  const std::string odom_child = FrameName(options_.odometry_child_frame);
  for (const TransformMsg& t : transforms) {
    const std::string parent = FrameName(t.parent);
    const std::string child = FrameName(t.child);
    const StampedPose T_parent_child = ToPose(t.stamp, t.transform, Where(topic, t.stamp));
    if (topic == kTfStaticTopic) {
      c_->statics.push_back(
          {parent, child, T_parent_child.T_world_body.translation(), *T_parent_child.quaternion});
    } else if (parent == odom_parent && child == odom_child) {
      c_->odom.push_back(T_parent_child);
    } else {
      c_->tf_pairs.insert(parent + " -> " + child);
    }
  }
}

void BagContents::AddOdometry(const PoseMsg& msg) {
  c_->odom.push_back(ToPose(msg.stamp, msg.pose, Where(options_.odometry_topic, msg.stamp)));
}

void BagContents::AddGroundTruth(const PoseMsg& msg) {
  c_->truth.push_back(ToPose(msg.stamp, msg.pose, Where(options_.groundtruth_topic, msg.stamp)));
}

void BagContents::AddNavSatFix(const NavSatFixMsg& msg) {
  const bool usable = msg.status >= kStatusFix && std::isfinite(msg.latitude) &&
                      std::isfinite(msg.longitude) && std::isfinite(msg.altitude) &&
                      std::abs(msg.latitude) <= 90.0 && std::abs(msg.longitude) <= 180.0;
  if (!usable) return;
  if (!c_->fix) c_->fix = GeodeticOrigin{msg.latitude, msg.longitude, msg.altitude};
  GnssFix f;
  f.timestamp = msg.stamp.ToSec();
  f.latitude_deg = msg.latitude;
  f.longitude_deg = msg.longitude;
  f.altitude_m = msg.altitude;
  // The receiver's own covariance (east, north, up on the diagonal) when it gives one.
  const auto& c = msg.position_covariance;
  const bool known = msg.covariance_type > 0 && std::isfinite(c[0]) && std::isfinite(c[4]) &&
                     std::isfinite(c[8]) && c[0] > 0.0 && c[4] > 0.0 && c[8] > 0.0;
  f.sigma_enu_m = known ? Eigen::Vector3d(std::sqrt(c[0]), std::sqrt(c[4]), std::sqrt(c[8]))
                        : Eigen::Vector3d::Constant(options_.navsat_sigma_m);
  c_->gnss.push_back(f);
}

namespace {

using Collected = BagContents::Collected;

// The stereo camera of the two CameraInfo, if the bag has both. @throw IoError naming `name` if
// a stereo bag lacks one, or the odometry or the ground truth `o` asks for is missing.
std::optional<CameraModel> CheckContents(const Collected& c, const BagOptions& o,
                                         const TypeNames& types, const std::string& name) {
  std::optional<CameraModel> camera;
  if (c.left_info && c.right_info) {
    camera = StereoCamera(*c.left_info, *c.right_info, name, o);
  } else if (o.sensor_type == SensorType::kStereo) {
    throw IoError(name + ": no " + types.info + " on " +
                  (c.left_info ? o.right_info_topic : o.left_info_topic));
  }
  if (c.odom.empty() && o.odometry_from_tf) {
    std::string seen;
    for (const std::string& pair : c.tf_pairs) seen += (seen.empty() ? "" : ", ") + pair;
    throw IoError(name + ": no /tf transform " + o.odometry_parent_frame + " -> " +
                  o.odometry_child_frame + " (/tf has: " + (seen.empty() ? "nothing" : seen) + ")");
  }
  if (c.odom.empty()) throw IoError(name + ": no " + types.odometry + " on " + o.odometry_topic);
  if (!o.groundtruth_topic.empty() && c.truth.empty()) {
    throw IoError(name + ": no ground truth pose on " + o.groundtruth_topic);
  }
  return camera;
}

// Frames: pairs or clouds with a pose from each trajectory without extrapolating.
// @throw IoError naming `name` if no frame has both.
BagPlan PlanFrames(const Collected& c, const BagOptions& o, const std::string& name) {
  const bool stereo = o.sensor_type == SensorType::kStereo;
  const bool has_truth = !o.groundtruth_topic.empty();
  BagPlan plan;
  std::vector<std::pair<MessageRef, MessageRef>> candidates;
  if (stereo) {
    candidates = PairImages(c.lefts, c.rights, o.pair_tolerance_s);
    plan.skipped.unpaired_images = c.lefts.size() + c.rights.size() - 2 * candidates.size();
  } else {
    for (const MessageRef& cloud : c.lefts) candidates.emplace_back(cloud, cloud);
  }
  for (const auto& candidate : candidates) {
    const double t = candidate.first.stamp.ToSec();
    if (!Covers(c.odom, t) || (has_truth && !Covers(c.truth, t))) {
      ++plan.skipped.outside_pose_span;
      continue;
    }
    plan.frames.push_back(candidate);
    plan.odometry.push_back(Interpolate(c.odom, t));
    if (has_truth) plan.groundtruth.push_back(Interpolate(c.truth, t));
  }
  if (plan.odometry.empty()) {
    const std::string what =
        stereo ? "left/right image pair within " + std::to_string(o.pair_tolerance_s) +
                     " s of each other (" + o.left_image_topic + ", " + o.right_image_topic + ")"
               : "point cloud on " + o.cloud_topic;
    throw IoError(name + ": no " + what + " within the time span of the odometry" +
                  (has_truth ? " and the ground truth" : ""));
  }
  return plan;
}

// The sequence's description: sensor, camera, T_body_sensor, origin and frame rate.
// @throw IoError naming the bag if /tf_static does not connect the body to the sensor.
SequenceInfo Describe(const std::filesystem::path& bag_file, const Collected& c,
                      const BagOptions& o, const std::optional<CameraModel>& camera,
                      const std::vector<StampedPose>& odometry) {
  SequenceInfo info;
  info.directory = bag_file;
  info.sensor_type = o.sensor_type;
  info.camera = camera;
  // T_body_sensor's rotation from a quaternion, the form sequence.yaml keeps: an imported
  // sequence then reads back this very rotation, and replays as the bag does.
  const QuaternionTransform T_body_sensor =
      o.T_body_sensor_from_tf_static
          ? StaticBodySensor(c.statics, o, bag_file.string())
          : QuaternionTransform{Eigen::Quaterniond(o.T_body_sensor.linear()),
                                o.T_body_sensor.translation()};
  // Links each unit within 1e-3 can chain to a norm sequence.yaml would refuse.
  const Eigen::Quaterniond q = std::abs(T_body_sensor.q.norm() - 1.0) <= 1e-6
                                   ? T_body_sensor.q
                                   : T_body_sensor.q.normalized();
  info.body_sensor_quaternion = q;
  info.T_body_sensor.linear() = RotationFromQuaternion(q);
  info.T_body_sensor.translation() = T_body_sensor.t;
  info.origin = o.origin ? *o.origin : c.fix ? *c.fix : o.default_origin;
  info.body = o.body;
  const double span = odometry.back().timestamp - odometry.front().timestamp;
  info.frame_rate_hz =
      odometry.size() > 1 && span > 0.0 ? static_cast<double>(odometry.size() - 1) / span : 0.0;
  return info;
}

}  // namespace

BagPlan BagContents::Finish() {
  Collected& c = *c_;
  auto by_time = [](const StampedPose& a, const StampedPose& b) {
    return a.timestamp < b.timestamp;
  };
  std::stable_sort(c.odom.begin(), c.odom.end(), by_time);
  std::stable_sort(c.truth.begin(), c.truth.end(), by_time);
  auto by_stamp = [](const MessageRef& a, const MessageRef& b) { return a.stamp < b.stamp; };
  std::stable_sort(c.lefts.begin(), c.lefts.end(), by_stamp);
  std::stable_sort(c.rights.begin(), c.rights.end(), by_stamp);
  const std::optional<CameraModel> camera = CheckContents(c, options_, types_, name_);
  BagPlan plan = PlanFrames(c, options_, name_);
  plan.info = Describe(file_, c, options_, camera, plan.odometry);
  // Fixes by time, one per stamp (a receiver that repeats a stamp gives the pose graph nothing
  // new).
  plan.gnss = c.gnss;
  std::stable_sort(plan.gnss.begin(), plan.gnss.end(),
                   [](const GnssFix& a, const GnssFix& b) { return a.timestamp < b.timestamp; });
  plan.gnss.erase(
      std::unique(plan.gnss.begin(), plan.gnss.end(),
                  [](const GnssFix& a, const GnssFix& b) { return a.timestamp == b.timestamp; }),
      plan.gnss.end());
  return plan;
}

BagFrameSource::BagFrameSource(std::filesystem::path bag_file, BagOptions options)
    : file_(std::move(bag_file)), options_(std::move(options)) {}

void BagFrameSource::Adopt(BagPlan plan) {
  frames_ = std::move(plan.frames);
  odometry_ = std::move(plan.odometry);
  groundtruth_ = std::move(plan.groundtruth);
  gnss_ = std::move(plan.gnss);
  skipped_ = plan.skipped;
  info_ = std::move(plan.info);
}

void BagFrameSource::LoadFrame(Frame* frame) const {
  frame->file = file_;
  const auto& [first, second] = frames_[frame->index];
  const std::lock_guard<std::mutex> lock(mutex_);
  if (info_.sensor_type == SensorType::kCloud) {
    frame->cloud = ReadCloud(first);
    return;
  }
  frame->left = ReadImage(options_.left_image_topic, first);
  CheckImageSize(frame->left, *info_.camera,
                 FrameWhat(file_, options_.left_image_topic, first.stamp));
  frame->right = ReadImage(options_.right_image_topic, second);
  CheckImageSize(frame->right, *info_.camera,
                 FrameWhat(file_, options_.right_image_topic, second.stamp));
}

cv::Mat ToGrey(const ImageMsg& msg, const std::string& what) {
  const int width = static_cast<int>(msg.width);
  const int height = static_cast<int>(msg.height);
  if (!IsSupportedEncoding(msg.encoding)) {
    throw IoError(what + ": unsupported image encoding '" + msg.encoding +
                  "' (mono8, rgb8, bgr8, mono16)");
  }
  const int channels = msg.encoding == "rgb8" || msg.encoding == "bgr8" ? 3 : 1;
  const int depth_bytes = msg.encoding == "mono16" ? 2 : 1;
  const std::size_t row_bytes = static_cast<std::size_t>(width) * channels * depth_bytes;
  if (width <= 0 || height <= 0 || msg.step < row_bytes ||
      msg.data.size < static_cast<std::size_t>(msg.step) * msg.height) {
    throw IoError(what + ": image data does not fit its size (" + std::to_string(width) + "x" +
                  std::to_string(height) + ", step " + std::to_string(msg.step) + ", " +
                  std::to_string(msg.data.size) + " bytes)");
  }
  cv::Mat grey(height, width, CV_8UC1);
  // cv::Mat cannot take const data; the views below are only read.
  auto* data = const_cast<std::uint8_t*>(msg.data.data);
  if (msg.encoding == "mono8") {
    cv::Mat(height, width, CV_8UC1, data, msg.step).copyTo(grey);
  } else if (channels == 3) {
    cv::cvtColor(cv::Mat(height, width, CV_8UC3, data, msg.step), grey,
                 msg.encoding == "rgb8" ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
  } else {
    // mono16: the high byte, whichever order the bytes are in.
    const int high = msg.is_bigendian ? 0 : 1;
    for (int r = 0; r < height; ++r) {
      const std::uint8_t* in = msg.data.data + static_cast<std::size_t>(r) * msg.step;
      auto* out = grey.ptr<std::uint8_t>(r);
      for (int c = 0; c < width; ++c) out[c] = in[2 * c + high];
    }
  }
  return grey;
}

cv::Mat ToGrey(const CompressedImageMsg& msg, const std::string& what) {
  // A header over the bytes, as cv::imdecode would make of a std::vector (empty when empty).
  const cv::Mat bytes = msg.data.size == 0
                            ? cv::Mat()
                            : cv::Mat(1, static_cast<int>(msg.data.size), CV_8UC1,
                                      const_cast<std::uint8_t*>(msg.data.data));  // only read
  const cv::Mat grey = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
  if (grey.empty()) throw IoError(what + ": cannot decode the " + msg.format + " image");
  return grey;
}

void CheckImageSize(const cv::Mat& grey, const CameraModel& camera, const std::string& what) {
  if (grey.cols != camera.width || grey.rows != camera.height) {
    throw IoError(what + ": image is " + std::to_string(grey.cols) + "x" +
                  std::to_string(grey.rows) + ", the camera info says " +
                  std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
}

// Every point of a cloud, non-finite ones (no return) included: the mapper drops and counts
// them, as for a sequence's PLY frames (docs/design.md §9).
registration::PointCloud ToCloud(const PointCloudMsg& msg, const std::string& what) {
  const CloudLayout layout = CheckCloud(msg, what);
  registration::PointCloud cloud;
  cloud.points.reserve(static_cast<std::size_t>(msg.width) * msg.height);
  for (std::uint32_t row = 0; row < msg.height; ++row) {
    for (std::uint32_t col = 0; col < msg.width; ++col) {
      const std::uint8_t* point = msg.data.data + static_cast<std::size_t>(row) * msg.row_step +
                                  static_cast<std::size_t>(col) * msg.point_step;
      Eigen::Vector3d p;
      for (int axis = 0; axis < 3; ++axis) {
        if (layout.float64) {
          double v = 0.0;
          std::memcpy(&v, point + layout.offset[axis], sizeof(v));
          p[axis] = v;
        } else {
          float v = 0.0F;
          std::memcpy(&v, point + layout.offset[axis], sizeof(v));
          p[axis] = v;
        }
      }
      cloud.points.push_back(p);
    }
  }
  return cloud;
}

}  // namespace rovermap::io::bag
