#pragma once
// The messages rovermap reads from a bag, whatever the container (ROS 1 bag, ROS 2 MCAP or
// SQLite): only the fields it uses. Image and cloud data are views into the reader's buffer,
// valid while that buffer is.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace rovermap::io::bag {

/// A header stamp: ROS 1 has unsigned seconds, ROS 2 signed ones; both fit here.
struct Stamp {
  std::int64_t sec = 0;
  std::uint32_t nsec = 0;

  /// The double nearest sec.nanosec: the one a TUM file's 9-decimal stamp reads as, so that an
  /// imported sequence's stamps are the bag's (sec + 1e-9 * nsec, as ros::Time::toSec computes
  /// it, rounds twice and misses it by an ulp for about one stamp in twelve). |sec| < 2^32.
  double ToSec() const;
  friend bool operator==(const Stamp& a, const Stamp& b) {
    return a.sec == b.sec && a.nsec == b.nsec;
  }
  friend bool operator!=(const Stamp& a, const Stamp& b) { return !(a == b); }
  friend bool operator<(const Stamp& a, const Stamp& b) {
    return a.sec != b.sec ? a.sec < b.sec : a.nsec < b.nsec;
  }
};

struct ByteView {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

/// sensor_msgs Image.
struct ImageMsg {
  Stamp stamp;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string encoding;
  bool is_bigendian = false;
  std::uint32_t step = 0;
  ByteView data;
};

/// sensor_msgs CompressedImage.
struct CompressedImageMsg {
  Stamp stamp;
  std::string format;
  ByteView data;
};

/// sensor_msgs CameraInfo: image size and the projection P (row-major 3x4).
struct CameraInfoMsg {
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::array<double, 12> P{};
};

struct PointFieldMsg {
  std::string name;
  std::uint32_t offset = 0;
  std::uint8_t datatype = 0;
};

/// sensor_msgs PointCloud2.
struct PointCloudMsg {
  Stamp stamp;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::vector<PointFieldMsg> fields;
  bool is_bigendian = false;
  std::uint32_t point_step = 0;
  std::uint32_t row_step = 0;
  ByteView data;
};

/// A position and a quaternion (x, y, z, w as ROS orders them).
struct PoseValue {
  std::array<double, 3> position{};
  std::array<double, 4> orientation{0.0, 0.0, 0.0, 1.0};
};

/// nav_msgs Odometry's pose.pose or geometry_msgs PoseStamped's pose, with the header stamp.
struct PoseMsg {
  Stamp stamp;
  PoseValue pose;
};

/// One geometry_msgs TransformStamped of a tf2_msgs TFMessage: T_parent_child.
struct TransformMsg {
  Stamp stamp;
  std::string parent;
  std::string child;
  PoseValue transform;
};

/// sensor_msgs NavSatFix.
struct NavSatFixMsg {
  Stamp stamp;
  std::int8_t status = -1;
  double latitude = 0.0;
  double longitude = 0.0;
  double altitude = 0.0;
  /// [m²] row-major, east north up; read only when `covariance_type` > 0 (known or
  /// approximated).
  std::array<double, 9> position_covariance{};
  std::uint8_t covariance_type = 0;
};

/// sensor_msgs PointField datatypes rovermap reads.
constexpr std::uint8_t kFloat32 = 7;
constexpr std::uint8_t kFloat64 = 8;
/// sensor_msgs NavSatStatus: a fix at least.
constexpr std::int8_t kStatusFix = 0;

}  // namespace rovermap::io::bag
