#include "io/BagSource.hpp"

#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/NavSatFix.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "io/BagRules.hpp"
#include "io/IoError.hpp"

namespace rovermap::io {
namespace {

namespace fs = std::filesystem;
using bag::Role;

// ROS 1 messages as the container-independent rules read them (io/BagRules.hpp).

bag::Stamp StampOf(const ros::Time& t) { return {t.sec, t.nsec}; }

bag::ImageMsg ToBag(const sensor_msgs::Image& m) {
  return {StampOf(m.header.stamp),       m.height, m.width, m.encoding, m.is_bigendian != 0, m.step,
          {m.data.data(), m.data.size()}};
}

bag::CompressedImageMsg ToBag(const sensor_msgs::CompressedImage& m) {
  return {StampOf(m.header.stamp), m.format, {m.data.data(), m.data.size()}};
}

bag::CameraInfoMsg ToBag(const sensor_msgs::CameraInfo& m) {
  bag::CameraInfoMsg info;
  info.height = m.height;
  info.width = m.width;
  std::copy(m.P.begin(), m.P.end(), info.P.begin());
  return info;
}

std::vector<bag::PointFieldMsg> ToBag(const std::vector<sensor_msgs::PointField>& fields) {
  std::vector<bag::PointFieldMsg> out;
  for (const sensor_msgs::PointField& f : fields) out.push_back({f.name, f.offset, f.datatype});
  return out;
}

bag::PointCloudMsg ToBag(const sensor_msgs::PointCloud2& m) {
  bag::PointCloudMsg cloud;
  cloud.stamp = StampOf(m.header.stamp);
  cloud.height = m.height;
  cloud.width = m.width;
  cloud.fields = ToBag(m.fields);
  cloud.is_bigendian = m.is_bigendian != 0;
  cloud.point_step = m.point_step;
  cloud.row_step = m.row_step;
  cloud.data = {m.data.data(), m.data.size()};
  return cloud;
}

bag::PoseValue ToBag(const geometry_msgs::Pose& p) {
  return {{p.position.x, p.position.y, p.position.z},
          {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w}};
}

std::vector<bag::TransformMsg> ToBag(const tf2_msgs::TFMessage& m) {
  std::vector<bag::TransformMsg> transforms;
  for (const geometry_msgs::TransformStamped& t : m.transforms) {
    const auto& v = t.transform.translation;
    const auto& q = t.transform.rotation;
    transforms.push_back({StampOf(t.header.stamp),
                          t.header.frame_id,
                          t.child_frame_id,
                          {{v.x, v.y, v.z}, {q.x, q.y, q.z, q.w}}});
  }
  return transforms;
}

bag::NavSatFixMsg ToBag(const sensor_msgs::NavSatFix& m) {
  bag::NavSatFixMsg msg{StampOf(m.header.stamp), m.status.status, m.latitude, m.longitude,
                        m.altitude};
  for (std::size_t i = 0; i < 9; ++i) msg.position_covariance[i] = m.position_covariance[i];
  msg.covariance_type = m.position_covariance_type;
  return msg;
}

// The message `m` as a T. @throw IoError naming the bag if it is not one (a topic recorded
// with two types).
template <typename T>
auto Instantiate(const rosbag::MessageInstance& m, const bag::BagContents& contents) {
  auto msg = m.instantiate<T>();
  if (!msg) {
    throw IoError(contents.WrongType(m.getTopic(), m.getDataType(),
                                     ros::message_traits::DataType<T>::value()));
  }
  return msg;
}

// What opening needs of an Image, CompressedImage or PointCloud2: every field but the data,
// whose length is kept (data.data null). rosbag deserialises it from the message's bytes as it
// would a `Message` (same MD5 sum and type, below), but skipping over the data instead of
// copying it.
template <typename Message, typename Msg>
struct Head {
  Msg msg;
};
using ImageHead = Head<sensor_msgs::Image, bag::ImageMsg>;
using CompressedImageHead = Head<sensor_msgs::CompressedImage, bag::CompressedImageMsg>;
using CloudHead = Head<sensor_msgs::PointCloud2, bag::PointCloudMsg>;

// The header's stamp (seq and frame_id read past).
template <typename Stream>
bag::Stamp ReadStamp(Stream& stream) {
  std_msgs::Header header;
  stream.next(header);
  return StampOf(header.stamp);
}

// A uint8[]'s length, its bytes skipped: past the message's end that throws the
// StreamOverrunException deserialising them would.
template <typename Stream>
bag::ByteView SkipData(Stream& stream) {
  std::uint32_t length = 0;
  stream.next(length);
  stream.advance(length);
  return {nullptr, length};
}

template <typename Stream>
void ReadHead(Stream& stream, bag::ImageMsg* m) {
  m->stamp = ReadStamp(stream);
  std::uint8_t is_bigendian = 0;
  stream.next(m->height);
  stream.next(m->width);
  stream.next(m->encoding);
  stream.next(is_bigendian);
  stream.next(m->step);
  m->is_bigendian = is_bigendian != 0;
  m->data = SkipData(stream);
}

template <typename Stream>
void ReadHead(Stream& stream, bag::CompressedImageMsg* m) {
  m->stamp = ReadStamp(stream);
  stream.next(m->format);
  m->data = SkipData(stream);
}

template <typename Stream>
void ReadHead(Stream& stream, bag::PointCloudMsg* m) {
  m->stamp = ReadStamp(stream);
  std::vector<sensor_msgs::PointField> fields;
  std::uint8_t is_bigendian = 0;
  stream.next(m->height);
  stream.next(m->width);
  stream.next(fields);
  stream.next(is_bigendian);
  stream.next(m->point_step);
  stream.next(m->row_step);
  m->fields = ToBag(fields);
  m->is_bigendian = is_bigendian != 0;
  m->data = SkipData(stream);  // is_dense, after the data, is not read
}

}  // namespace
}  // namespace rovermap::io

namespace ros {
namespace message_traits {
template <typename Message, typename Msg>
struct MD5Sum<rovermap::io::Head<Message, Msg>> : MD5Sum<Message> {};
template <typename Message, typename Msg>
struct DataType<rovermap::io::Head<Message, Msg>> : DataType<Message> {};
}  // namespace message_traits
namespace serialization {
template <typename Message, typename Msg>
struct Serializer<rovermap::io::Head<Message, Msg>> {
  template <typename Stream>
  static void read(Stream& stream, rovermap::io::Head<Message, Msg>& head) {
    rovermap::io::ReadHead(stream, &head.msg);
  }
};
}  // namespace serialization
}  // namespace ros

namespace rovermap::io {

struct BagSource::Bag {
  rosbag::Bag bag;
  std::vector<ros::Time> recorded;  // by MessageRef::id: when each image or cloud was recorded

  // The message on `topic` recorded at ref's recording time with stamp ref.stamp.
  // @throw IoError naming the bag, topic and stamp.
  template <typename Handle>
  void Find(const std::string& topic, const bag::MessageRef& ref, const std::string& what,
            Handle&& handle) {
    bool found = false;
    try {
      const ros::Time time = recorded.at(ref.id);
      rosbag::View view(bag, rosbag::TopicQuery(topic), time, time);
      for (const rosbag::MessageInstance& m : view) {
        found = handle(m);
        if (found) break;
      }
    } catch (const rosbag::BagException& e) {
      throw IoError(what + ": " + e.what());
    }
    if (!found) throw IoError(what + ": message not found again at its recording time");
  }
};

namespace {

// The topics of `bag` and their message types.
std::map<std::string, std::string> TopicTypes(rosbag::Bag& bag) {
  std::map<std::string, std::string> types;
  rosbag::View all(bag);
  for (const rosbag::ConnectionInfo* c : all.getConnections()) types.emplace(c->topic, c->datatype);
  return types;
}

// Feeds one message to `c` by its role. @throw IoError naming the bag, the topic and the stamp.
void Add(const rosbag::MessageInstance& m, bag::BagContents& c, std::vector<ros::Time>* recorded) {
  const std::string& topic = m.getTopic();
  switch (c.RoleOf(topic)) {
    // Images and clouds: their headers only; the data is deserialised when the frame is read.
    case Role::kImage:
      if (m.getDataType() == bag::Ros1Types().compressed) {
        c.AddImage(topic, Instantiate<CompressedImageHead>(m, c)->msg, recorded->size());
      } else {
        c.AddImage(topic, Instantiate<ImageHead>(m, c)->msg, recorded->size());
      }
      recorded->push_back(m.getTime());
      break;
    case Role::kCloud:
      c.AddCloud(Instantiate<CloudHead>(m, c)->msg, recorded->size());
      recorded->push_back(m.getTime());
      break;
    case Role::kCameraInfo:
      c.AddCameraInfo(topic, ToBag(*Instantiate<sensor_msgs::CameraInfo>(m, c)));
      break;
    case Role::kTf:
      c.AddTransforms(topic, ToBag(*Instantiate<tf2_msgs::TFMessage>(m, c)));
      break;
    case Role::kOdometry: {
      const auto msg = Instantiate<nav_msgs::Odometry>(m, c);
      c.AddOdometry({StampOf(msg->header.stamp), ToBag(msg->pose.pose)});
      break;
    }
    case Role::kGroundTruth:
      if (m.getDataType() == bag::Ros1Types().pose) {
        const auto msg = Instantiate<geometry_msgs::PoseStamped>(m, c);
        c.AddGroundTruth({StampOf(msg->header.stamp), ToBag(msg->pose)});
      } else {
        const auto msg = Instantiate<nav_msgs::Odometry>(m, c);
        c.AddGroundTruth({StampOf(msg->header.stamp), ToBag(msg->pose.pose)});
      }
      break;
    case Role::kNavSat:
      c.AddNavSatFix(ToBag(*Instantiate<sensor_msgs::NavSatFix>(m, c)));
      break;
    case Role::kNone:
      break;
  }
}

// Opens `bag` and reads the contents `c` asks for in one pass. @throw IoError naming `name` if
// the bag cannot be read (unindexed, truncated, not a ROS 1 bag) or lacks a topic it needs.
void OpenAndRead(rosbag::Bag& bag, bag::BagContents& c, std::vector<ros::Time>* recorded,
                 const std::string& name) {
  try {
    try {
      bag.open(name, rosbag::bagmode::Read);
    } catch (const rosbag::BagUnindexedException&) {
      throw IoError(name +
                    ": the bag is not indexed (its recording was cut off or not closed): "
                    "`rosbag reindex` it first");
    } catch (const rosbag::BagException& e) {
      throw IoError(name + ": cannot read the bag, truncated or not a ROS 1 bag (" + e.what() +
                    ")");
    }
    rosbag::View view(bag, rosbag::TopicQuery(c.TopicsToRead(TopicTypes(bag))));
    for (const rosbag::MessageInstance& m : view) Add(m, c, recorded);
  } catch (const rosbag::BagException& e) {
    throw IoError(name + ": cannot read the bag (" + e.what() + ")");
  }
}

}  // namespace

BagSource::BagSource(const fs::path& bag_file, const BagOptions& options)
    : BagFrameSource(bag_file, options), bag_(std::make_unique<Bag>()) {
  const std::string name = bag_file.string();
  std::error_code error;
  if (!fs::is_regular_file(bag_file, error)) throw IoError(name + ": no such bag file");
  bag::BagContents contents(bag_file, options, bag::Ros1Types());
  OpenAndRead(bag_->bag, contents, &bag_->recorded, name);
  Adopt(contents.Finish());
}

BagSource::~BagSource() = default;

cv::Mat BagSource::ReadImage(const std::string& topic, const bag::MessageRef& ref) const {
  const std::string what = bag::FrameWhat(file(), topic, ref.stamp);
  cv::Mat grey;
  bag_->Find(topic, ref, what, [&](const rosbag::MessageInstance& m) {
    if (m.getDataType() == bag::Ros1Types().compressed) {
      const auto msg = m.instantiate<sensor_msgs::CompressedImage>();
      if (!msg || StampOf(msg->header.stamp) != ref.stamp) return false;
      grey = bag::ToGrey(ToBag(*msg), what);
    } else {
      const auto msg = m.instantiate<sensor_msgs::Image>();
      if (!msg || StampOf(msg->header.stamp) != ref.stamp) return false;
      grey = bag::ToGrey(ToBag(*msg), what);
    }
    return true;
  });
  return grey;
}

registration::PointCloud BagSource::ReadCloud(const bag::MessageRef& ref) const {
  const std::string& topic = options().cloud_topic;
  const std::string what = bag::FrameWhat(file(), topic, ref.stamp);
  registration::PointCloud cloud;
  bag_->Find(topic, ref, what, [&](const rosbag::MessageInstance& m) {
    const auto msg = m.instantiate<sensor_msgs::PointCloud2>();
    if (!msg || StampOf(msg->header.stamp) != ref.stamp) return false;
    cloud = bag::ToCloud(ToBag(*msg), what);
    return true;
  });
  return cloud;
}

}  // namespace rovermap::io
