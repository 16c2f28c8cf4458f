#include "io/Cdr.hpp"

#include <cstring>
#include <utility>

#include "io/IoError.hpp"

namespace rovermap::io::cdr {

using bag::ByteView;

CdrReader::CdrReader(ByteView data, std::string what)
    : CdrReader(data, data.size, std::move(what)) {}

CdrReader::CdrReader(ByteView head, std::size_t size, std::string what)
    : data_(head), size_(size), what_(std::move(what)) {
  if (size_ < 4) {
    throw IoError(what_ + ": CDR data of " + std::to_string(size_) +
                  " bytes has no 4-byte encapsulation header");
  }
  if (data_.size < 4) throw HeadTooShort();
  const std::uint8_t kind = data_.data[1];
  if (data_.data[0] != 0 || kind > 1) {
    throw IoError(what_ + ": encapsulation " + std::to_string(data_.data[0]) + " " +
                  std::to_string(kind) +
                  " is not plain CDR (00 00 big-endian, 00 01 little-endian)");
  }
  little_ = kind == 1;
}

std::size_t CdrReader::Reserve(std::size_t size, std::size_t align, const char* field) {
  const std::size_t body = pos_ - 4;  // alignment counts from the end of the header
  const std::size_t start = pos_ + (align > 1 ? (align - body % align) % align : 0);
  if (start > size_ || size > size_ - start) {
    throw IoError(what_ + ": CDR data ends at byte " + std::to_string(size_) + ", '" + field +
                  "' needs " + std::to_string(size) + " bytes at byte " + std::to_string(start));
  }
  pos_ = start + size;
  return start;
}

const std::uint8_t* CdrReader::Take(std::size_t size, std::size_t align, const char* field) {
  const std::size_t start = Reserve(size, align, field);
  if (pos_ > data_.size) throw HeadTooShort();
  return data_.data + start;
}

template <typename T>
T CdrReader::Read(const char* field) {
  const std::uint8_t* p = Take(sizeof(T), sizeof(T), field);
  std::uint8_t bytes[sizeof(T)];
  for (std::size_t i = 0; i < sizeof(T); ++i) bytes[i] = little_ ? p[i] : p[sizeof(T) - 1 - i];
  T value;
  std::memcpy(&value, bytes, sizeof(T));  // the host is little-endian (x86-64, arm64)
  return value;
}

std::uint8_t CdrReader::U8(const char* field) { return Read<std::uint8_t>(field); }
std::uint16_t CdrReader::U16(const char* field) { return Read<std::uint16_t>(field); }
std::uint32_t CdrReader::U32(const char* field) { return Read<std::uint32_t>(field); }
double CdrReader::F64(const char* field) { return Read<double>(field); }

std::string CdrReader::String(const char* field) {
  const std::uint32_t length = U32(field);
  const auto* p = reinterpret_cast<const char*>(Take(length, 1, field));
  // The length counts the NUL; some writers give 0 for an empty string.
  const std::size_t n = length > 0 && p[length - 1] == '\0' ? length - 1 : length;
  return std::string(p, n);
}

ByteView CdrReader::Bytes(const char* field) {
  const std::uint32_t length = U32(field);
  const std::size_t start = Reserve(length, 1, field);
  return {pos_ <= data_.size ? data_.data + start : nullptr, length};
}

std::uint32_t CdrReader::Count(const char* field, std::size_t min_size) {
  const std::uint32_t count = U32(field);
  if (static_cast<std::size_t>(count) * min_size > size_ - pos_) {
    throw IoError(what_ + ": CDR data ends at byte " + std::to_string(size_) + ", '" + field +
                  "' declares " + std::to_string(count) + " elements at byte " +
                  std::to_string(pos_));
  }
  return count;
}

void CdrReader::Skip(std::size_t count, std::size_t size, const char* field) {
  if (count == 0) return;
  Take(size, size, field);  // aligns the first element
  Take((count - 1) * size, 1, field);
}

namespace {

// std_msgs/Header: builtin_interfaces/Time (int32 sec, uint32 nanosec), frame_id.
bag::Stamp ReadHeader(CdrReader& r, std::string* frame_id = nullptr) {
  bag::Stamp stamp;
  stamp.sec = static_cast<std::int32_t>(r.U32("header.stamp.sec"));
  stamp.nsec = r.U32("header.stamp.nanosec");
  std::string frame = r.String("header.frame_id");
  if (frame_id) *frame_id = std::move(frame);
  return stamp;
}

// geometry_msgs/Point or Vector3, then Quaternion: both are a Pose's layout.
bag::PoseValue ReadPose(CdrReader& r) {
  bag::PoseValue pose;
  for (double& v : pose.position) v = r.F64("position");
  for (double& v : pose.orientation) v = r.F64("orientation");
  return pose;
}

bag::ImageMsg ImageFields(CdrReader& r) {
  bag::ImageMsg msg;
  msg.stamp = ReadHeader(r);
  msg.height = r.U32("height");
  msg.width = r.U32("width");
  msg.encoding = r.String("encoding");
  msg.is_bigendian = r.U8("is_bigendian") != 0;
  msg.step = r.U32("step");
  msg.data = r.Bytes("data");
  return msg;
}

bag::CompressedImageMsg CompressedImageFields(CdrReader& r) {
  bag::CompressedImageMsg msg;
  msg.stamp = ReadHeader(r);
  msg.format = r.String("format");
  msg.data = r.Bytes("data");
  return msg;
}

bag::PointCloudMsg PointCloudFields(CdrReader& r) {
  bag::PointCloudMsg msg;
  msg.stamp = ReadHeader(r);
  msg.height = r.U32("height");
  msg.width = r.U32("width");
  const std::uint32_t fields = r.Count("fields", 13);  // name length, offset, datatype, count
  for (std::uint32_t i = 0; i < fields; ++i) {
    bag::PointFieldMsg f;
    f.name = r.String("fields.name");
    f.offset = r.U32("fields.offset");
    f.datatype = r.U8("fields.datatype");
    r.U32("fields.count");
    msg.fields.push_back(std::move(f));
  }
  msg.is_bigendian = r.U8("is_bigendian") != 0;
  msg.point_step = r.U32("point_step");
  msg.row_step = r.U32("row_step");
  msg.data = r.Bytes("data");
  return msg;
}

template <typename Msg>
Msg Decode(ByteView data, const std::string& what, Msg (*fields)(CdrReader&)) {
  CdrReader r(data, what);
  return fields(r);
}

// `fields` of the first bytes `head` of a message of `size` bytes, the data's address left out.
template <typename Msg>
std::optional<Msg> DecodeHead(ByteView head, std::size_t size, const std::string& what,
                              Msg (*fields)(CdrReader&)) {
  try {
    CdrReader r(head, size, what);
    Msg msg = fields(r);
    msg.data.data = nullptr;
    return msg;
  } catch (const HeadTooShort&) {
    return std::nullopt;
  }
}

}  // namespace

bag::ImageMsg DecodeImage(ByteView data, const std::string& what) {
  return Decode(data, what, &ImageFields);
}

bag::CompressedImageMsg DecodeCompressedImage(ByteView data, const std::string& what) {
  return Decode(data, what, &CompressedImageFields);
}

bag::PointCloudMsg DecodePointCloud(ByteView data, const std::string& what) {
  return Decode(data, what, &PointCloudFields);
}

std::optional<bag::ImageMsg> DecodeImageHead(ByteView head, std::size_t size,
                                             const std::string& what) {
  return DecodeHead(head, size, what, &ImageFields);
}

std::optional<bag::CompressedImageMsg> DecodeCompressedImageHead(ByteView head, std::size_t size,
                                                                 const std::string& what) {
  return DecodeHead(head, size, what, &CompressedImageFields);
}

std::optional<bag::PointCloudMsg> DecodePointCloudHead(ByteView head, std::size_t size,
                                                       const std::string& what) {
  return DecodeHead(head, size, what, &PointCloudFields);
}

bag::CameraInfoMsg DecodeCameraInfo(ByteView data, const std::string& what) {
  CdrReader r(data, what);
  bag::CameraInfoMsg msg;
  ReadHeader(r);
  msg.height = r.U32("height");
  msg.width = r.U32("width");
  r.String("distortion_model");
  r.Skip(r.Count("d", 8), 8, "d");
  r.Skip(9, 8, "k");
  r.Skip(9, 8, "r");
  for (double& v : msg.P) v = r.F64("p");
  return msg;
}

bag::PoseMsg DecodeOdometry(ByteView data, const std::string& what) {
  CdrReader r(data, what);
  bag::PoseMsg msg;
  msg.stamp = ReadHeader(r);
  r.String("child_frame_id");
  msg.pose = ReadPose(r);
  return msg;
}

bag::PoseMsg DecodePoseStamped(ByteView data, const std::string& what) {
  CdrReader r(data, what);
  bag::PoseMsg msg;
  msg.stamp = ReadHeader(r);
  msg.pose = ReadPose(r);
  return msg;
}

std::vector<bag::TransformMsg> DecodeTfMessage(ByteView data, const std::string& what) {
  CdrReader r(data, what);
  // A TransformStamped holds at least its stamp, two string lengths and seven doubles.
  const std::uint32_t count = r.Count("transforms", 16 + 56);
  std::vector<bag::TransformMsg> transforms;
  for (std::uint32_t i = 0; i < count; ++i) {
    bag::TransformMsg t;
    t.stamp = ReadHeader(r, &t.parent);
    t.child = r.String("child_frame_id");
    t.transform = ReadPose(r);
    transforms.push_back(std::move(t));
  }
  return transforms;
}

bag::NavSatFixMsg DecodeNavSatFix(ByteView data, const std::string& what) {
  CdrReader r(data, what);
  bag::NavSatFixMsg msg;
  msg.stamp = ReadHeader(r);
  msg.status = static_cast<std::int8_t>(r.U8("status.status"));
  r.U16("status.service");
  msg.latitude = r.F64("latitude");
  msg.longitude = r.F64("longitude");
  msg.altitude = r.F64("altitude");
  for (double& v : msg.position_covariance) v = r.F64("position_covariance");
  msg.covariance_type = r.U8("position_covariance_type");
  return msg;
}

}  // namespace rovermap::io::cdr
