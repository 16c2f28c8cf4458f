#pragma once
// ROS 2 bags for the tests, written without ROS: CDR serialisation (either byte order), an MCAP
// writer (chunks none/lz4/zstd, with or without the summary and its chunk indexes), a rosbag2
// SQLite writer, and a whole sequence directory as the bag a stereo rover would have recorded.

#include <lz4frame.h>
#include <sqlite3.h>
#include <zlib.h>
#include <zstd.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "io/BagOptions.hpp"
#include "io/Georeference.hpp"
#include "io/Sequence.hpp"
#include "registration/PointCloud.hpp"

namespace rovermap::testing {

using Bytes = std::vector<std::uint8_t>;

/// builtin_interfaces/Time of `t` [s], rounded as ros::Time(double) rounds.
inline std::pair<std::int32_t, std::uint32_t> Ros2Time(double t) {
  auto sec = static_cast<std::int64_t>(std::floor(t));
  auto nsec = static_cast<std::int64_t>(std::llround((t - static_cast<double>(sec)) * 1e9));
  if (nsec >= 1000000000) {
    ++sec;
    nsec -= 1000000000;
  }
  return {static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(nsec)};
}

inline std::uint64_t Nanoseconds(double t) {
  const auto [sec, nsec] = Ros2Time(t);
  return static_cast<std::uint64_t>(sec) * 1000000000ULL + nsec;
}

/// XCDR1 serialisation: the encapsulation header, then aligned primitives.
class CdrWriter {
 public:
  explicit CdrWriter(bool big_endian = false) : big_(big_endian) {
    out_ = {0, static_cast<std::uint8_t>(big_endian ? 0 : 1), 0, 0};
  }
  template <typename T>
  void Put(T v) {
    Align(sizeof(T));
    std::uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));
    for (std::size_t i = 0; i < sizeof(T); ++i) out_.push_back(bytes[big_ ? sizeof(T) - 1 - i : i]);
  }
  void String(const std::string& s) {
    Put<std::uint32_t>(static_cast<std::uint32_t>(s.size() + 1));
    out_.insert(out_.end(), s.begin(), s.end());
    out_.push_back(0);
  }
  void Sequence(const Bytes& data) {
    Put<std::uint32_t>(static_cast<std::uint32_t>(data.size()));
    out_.insert(out_.end(), data.begin(), data.end());
  }
  void Header(double t, const std::string& frame_id = "") {
    const auto [sec, nsec] = Ros2Time(t);
    Put<std::int32_t>(sec);
    Put<std::uint32_t>(nsec);
    String(frame_id);
  }
  void Pose(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
    for (int i = 0; i < 3; ++i) Put<double>(t[i]);
    Quaternion(q);
  }
  void Quaternion(const Eigen::Quaterniond& q) {
    for (const double v : {q.x(), q.y(), q.z(), q.w()}) Put<double>(v);
  }
  const Bytes& bytes() const { return out_; }

 private:
  void Align(std::size_t n) {
    while ((out_.size() - 4) % n != 0) out_.push_back(0);
  }
  bool big_;
  Bytes out_;
};

/// A pose as a TUM line gives it: the quaternion as written, not recomputed from a matrix (which
/// can differ in its last bit), so that a bag carries a sequence's poses exactly.
struct TumPose {
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
};

/// The poses of a TUM file, line by line (comments and blank lines skipped).
inline std::vector<TumPose> ReadTumPoses(const std::filesystem::path& path) {
  std::vector<TumPose> poses;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double v[8] = {};
    for (double& x : v) fields >> x;
    poses.push_back(
        {Eigen::Vector3d(v[1], v[2], v[3]), Eigen::Quaterniond(v[7], v[4], v[5], v[6])});
  }
  return poses;
}

/// Message layouts (ROS 2 Humble), fields rovermap does not read zero.
struct Cdr {
  bool big_endian = false;

  Bytes CameraInfo(const io::CameraModel& camera, double tx, double t,
                   std::function<void(std::array<double, 12>*)> edit_p = {}) const {
    CdrWriter w(big_endian);
    w.Header(t, "stereo");
    w.Put<std::uint32_t>(static_cast<std::uint32_t>(camera.height));
    w.Put<std::uint32_t>(static_cast<std::uint32_t>(camera.width));
    w.String("plumb_bob");
    w.Put<std::uint32_t>(5);
    for (int i = 0; i < 5; ++i) w.Put<double>(0.0);
    for (const double v : {camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0})
      w.Put<double>(v);
    for (const double v : {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}) w.Put<double>(v);
    std::array<double, 12> P = {camera.fx, 0, camera.cx, tx, 0, camera.fy,
                                camera.cy, 0, 0,         0,  1, 0};
    if (edit_p) edit_p(&P);
    for (const double v : P) w.Put<double>(v);
    for (int i = 0; i < 6; ++i) w.Put<std::uint32_t>(0);  // binning x, y, roi x, y, h, w
    w.Put<std::uint8_t>(0);                               // roi.do_rectify
    return w.bytes();
  }

  /// `grey` as mono8, rgb8, bgr8 or mono16 (little-endian), with a padded step.
  Bytes Image(const cv::Mat& grey, const std::string& encoding, double t) const {
    CdrWriter w(big_endian);
    w.Header(t, "stereo");
    const int bytes = encoding == "mono16" ? 2 : (encoding == "rgb8" || encoding == "bgr8") ? 3 : 1;
    const std::uint32_t step = static_cast<std::uint32_t>(grey.cols * bytes + 4);
    w.Put<std::uint32_t>(static_cast<std::uint32_t>(grey.rows));
    w.Put<std::uint32_t>(static_cast<std::uint32_t>(grey.cols));
    w.String(encoding);
    w.Put<std::uint8_t>(0);
    w.Put<std::uint32_t>(step);
    Bytes data(static_cast<std::size_t>(step) * grey.rows, 0);
    for (int r = 0; r < grey.rows; ++r) {
      for (int c = 0; c < grey.cols; ++c) {
        const std::uint8_t v = grey.at<std::uint8_t>(r, c);
        std::uint8_t* out = &data[static_cast<std::size_t>(r) * step + c * bytes];
        if (bytes == 2) {
          out[0] = 0x5a;  // low byte: dropped
          out[1] = v;
        } else {
          for (int k = 0; k < bytes; ++k) out[k] = v;
        }
      }
    }
    w.Sequence(data);
    return w.bytes();
  }

  Bytes Compressed(const cv::Mat& grey, const std::string& extension, double t) const {
    CdrWriter w(big_endian);
    w.Header(t, "stereo");
    w.String(extension == ".png" ? "mono8; png compressed " : "mono8; jpeg compressed ");
    Bytes data;
    cv::imencode(extension, grey, data);
    w.Sequence(data);
    return w.bytes();
  }

  Bytes Odometry(const TumPose& pose, double t) const {
    CdrWriter w(big_endian);
    w.Header(t, "odom");
    w.String("base_link");
    w.Pose(pose.t, pose.q);
    for (int i = 0; i < 36; ++i) w.Put<double>(0.0);      // pose covariance
    for (int i = 0; i < 6 + 36; ++i) w.Put<double>(0.0);  // twist and its covariance
    return w.bytes();
  }

  Bytes PoseStamped(const TumPose& pose, double t) const {
    CdrWriter w(big_endian);
    w.Header(t, "map");
    w.Pose(pose.t, pose.q);
    return w.bytes();
  }

  struct Transform {
    std::string parent;
    std::string child;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    std::optional<Eigen::Quaterniond> q;  ///< this rotation as it is, when set
  };
  Bytes Tf(const std::vector<Transform>& transforms, double t) const {
    CdrWriter w(big_endian);
    w.Put<std::uint32_t>(static_cast<std::uint32_t>(transforms.size()));
    for (const Transform& x : transforms) {
      w.Header(t, x.parent);
      w.String(x.child);
      for (int i = 0; i < 3; ++i) w.Put<double>(x.T.translation()[i]);
      w.Quaternion(x.q ? *x.q : Eigen::Quaterniond(x.T.linear()));
    }
    return w.bytes();
  }

  /// `sigma_m` > 0: a diagonal covariance of that σ (position_covariance_type 2, diagonal
  /// known); else none (type 0, unknown).
  Bytes NavSatFix(double latitude, double longitude, double altitude, double t, std::int8_t status,
                  double sigma_m = 0.0) const {
    CdrWriter w(big_endian);
    w.Header(t, "gps");
    w.Put<std::int8_t>(status);
    w.Put<std::uint16_t>(1);
    for (const double v : {latitude, longitude, altitude}) w.Put<double>(v);
    for (int i = 0; i < 9; ++i) w.Put<double>(i % 4 == 0 ? sigma_m * sigma_m : 0.0);
    w.Put<std::uint8_t>(sigma_m > 0.0 ? 2 : 0);
    return w.bytes();
  }

  /// x, y, z after a float32 intensity, 4 spare bytes after z; a NaN point after every 10th.
  Bytes PointCloud(const registration::PointCloud& cloud, bool float64, double t) const {
    CdrWriter w(big_endian);
    w.Header(t, "lidar");
    std::vector<Eigen::Vector3d> points;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      points.push_back(cloud.points[i]);
      if (i % 10 == 9) points.push_back(Eigen::Vector3d::Constant(std::nan("")));
    }
    const std::uint32_t size = float64 ? 8 : 4;
    const std::uint32_t point_step = 4 + 3 * size + 4;
    w.Put<std::uint32_t>(1);
    w.Put<std::uint32_t>(static_cast<std::uint32_t>(points.size()));
    w.Put<std::uint32_t>(4);
    const char* names[4] = {"intensity", "x", "y", "z"};
    for (int f = 0; f < 4; ++f) {
      w.String(names[f]);
      w.Put<std::uint32_t>(f == 0 ? 0 : 4 + (f - 1) * size);
      w.Put<std::uint8_t>(f == 0 || !float64 ? 7 : 8);
      w.Put<std::uint32_t>(1);
    }
    w.Put<std::uint8_t>(0);  // is_bigendian: the point data is little-endian
    w.Put<std::uint32_t>(point_step);
    w.Put<std::uint32_t>(point_step * static_cast<std::uint32_t>(points.size()));
    Bytes data(static_cast<std::size_t>(point_step) * points.size(), 0);
    for (std::size_t i = 0; i < points.size(); ++i) {
      for (int axis = 0; axis < 3; ++axis) {
        std::uint8_t* out = &data[i * point_step + 4 + axis * size];
        if (float64) {
          const double v = points[i][axis];
          std::memcpy(out, &v, 8);
        } else {
          const float v = static_cast<float>(points[i][axis]);
          std::memcpy(out, &v, 4);
        }
      }
    }
    w.Sequence(data);
    w.Put<std::uint8_t>(0);  // is_dense
    return w.bytes();
  }
};

/// Where a test bag's messages go: an MCAP or SQLite file.
class Ros2Writer {
 public:
  virtual ~Ros2Writer() = default;
  virtual void Write(const std::string& topic, const std::string& type, std::uint64_t time_ns,
                     const Bytes& data) = 0;
  virtual void Close() = 0;
};

/// How McapWriter lays a file out.
struct McapLayout {
  std::string compression = "zstd";  ///< "", "lz4", "zstd" (or any name, written as is)
  bool chunked = true;
  bool summary = true;  ///< schemas, channels and chunk indexes after the data
  std::size_t chunk_bytes = 256 * 1024;
  bool crc = true;               ///< the chunks' CRC32 (0 = none)
  std::string encoding = "cdr";  ///< channels' message_encoding
};

class McapWriter : public Ros2Writer {
 public:
  McapWriter(const std::filesystem::path& file, McapLayout layout)
      : out_(file, std::ios::binary), layout_(std::move(layout)) {
    Raw(Magic());
    Bytes header;
    Str(&header, "ros2");
    Str(&header, "rovermap-tests");
    Record(&file_, 0x01, header);
  }

  void Write(const std::string& topic, const std::string& type, std::uint64_t time_ns,
             const Bytes& data) override {
    Bytes* target = layout_.chunked ? &chunk_ : &file_;
    auto channel = channels_.find(topic);
    if (channel == channels_.end()) {
      const auto id = static_cast<std::uint16_t>(channels_.size() + 1);
      channel = channels_.emplace(topic, std::make_pair(id, type)).first;
      Record(target, 0x03, SchemaBody(id, type));
      Record(target, 0x04, ChannelBody(id, topic));
    }
    const std::uint16_t id = channel->second.first;
    Bytes body;
    U<std::uint16_t>(&body, id);
    U<std::uint32_t>(&body, 0);
    U<std::uint64_t>(&body, time_ns);
    U<std::uint64_t>(&body, time_ns);
    body.insert(body.end(), data.begin(), data.end());
    if (layout_.chunked) {
      if (chunk_start_ == 0 || time_ns < chunk_start_) chunk_start_ = time_ns;
      chunk_end_ = std::max(chunk_end_, time_ns);
      chunk_channels_.insert(id);
    }
    Record(target, 0x05, body);
    if (layout_.chunked && chunk_.size() >= layout_.chunk_bytes) Flush();
  }

  void Close() override {
    if (layout_.chunked) Flush();
    Bytes data_end;
    U<std::uint32_t>(&data_end, 0);
    Record(&file_, 0x0F, data_end);
    std::uint64_t summary_start = 0;
    if (layout_.summary) {
      summary_start = Offset();
      for (const auto& [topic, channel] : channels_) {
        Record(&file_, 0x03, SchemaBody(channel.first, channel.second));
        Record(&file_, 0x04, ChannelBody(channel.first, topic));
      }
      for (const Bytes& index : chunk_indexes_) Record(&file_, 0x08, index);
    }
    Bytes footer;
    U<std::uint64_t>(&footer, summary_start);
    U<std::uint64_t>(&footer, 0);
    U<std::uint32_t>(&footer, 0);
    Record(&file_, 0x02, footer);
    Raw(Magic());
    out_.write(reinterpret_cast<const char*>(file_.data()),
               static_cast<std::streamsize>(file_.size()));
    out_.close();
  }

 private:
  static Bytes Magic() { return {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'}; }
  template <typename T>
  static void U(Bytes* b, T v) {
    for (std::size_t i = 0; i < sizeof(T); ++i)
      b->push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  static void Str(Bytes* b, const std::string& s) {
    U<std::uint32_t>(b, static_cast<std::uint32_t>(s.size()));
    b->insert(b->end(), s.begin(), s.end());
  }
  static void Record(Bytes* b, std::uint8_t opcode, const Bytes& body) {
    b->push_back(opcode);
    U<std::uint64_t>(b, body.size());
    b->insert(b->end(), body.begin(), body.end());
  }
  void Raw(const Bytes& bytes) { file_.insert(file_.end(), bytes.begin(), bytes.end()); }
  std::uint64_t Offset() const { return file_.size(); }

  static Bytes SchemaBody(std::uint16_t id, const std::string& type) {
    Bytes b;
    U<std::uint16_t>(&b, id);
    Str(&b, type);
    Str(&b, "ros2msg");
    Str(&b, "");  // the definition text: rovermap reads only the name
    return b;
  }
  Bytes ChannelBody(std::uint16_t id, const std::string& topic) const {
    Bytes b;
    U<std::uint16_t>(&b, id);
    U<std::uint16_t>(&b, id);
    Str(&b, topic);
    Str(&b, layout_.encoding);
    U<std::uint32_t>(&b, 0);  // metadata: empty map
    return b;
  }

  Bytes Compress(const Bytes& in) const {
    if (layout_.compression == "zstd") {
      Bytes out(ZSTD_compressBound(in.size()));
      out.resize(ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 1));
      return out;
    }
    if (layout_.compression == "lz4") {
      Bytes out(LZ4F_compressFrameBound(in.size(), nullptr));
      out.resize(LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), nullptr));
      return out;
    }
    return in;  // none, or a name the reader should refuse
  }

  void Flush() {
    if (chunk_.empty()) return;
    const std::uint64_t start = Offset();
    const Bytes records = Compress(chunk_);
    Bytes body;
    U<std::uint64_t>(&body, chunk_start_);
    U<std::uint64_t>(&body, chunk_end_);
    U<std::uint64_t>(&body, chunk_.size());
    U<std::uint32_t>(&body, layout_.crc ? static_cast<std::uint32_t>(crc32(
                                              0L, chunk_.data(), static_cast<uInt>(chunk_.size())))
                                        : 0);
    Str(&body, layout_.compression);
    U<std::uint64_t>(&body, records.size());
    body.insert(body.end(), records.begin(), records.end());
    Record(&file_, 0x06, body);
    const std::uint64_t length = Offset() - start;
    Bytes index;
    U<std::uint64_t>(&index, chunk_start_);
    U<std::uint64_t>(&index, chunk_end_);
    U<std::uint64_t>(&index, start);
    U<std::uint64_t>(&index, length);
    // Message index offsets: the channels in the chunk (this writer writes no message index).
    U<std::uint32_t>(&index, static_cast<std::uint32_t>(chunk_channels_.size() * 10));
    for (const std::uint16_t id : chunk_channels_) {
      U<std::uint16_t>(&index, id);
      U<std::uint64_t>(&index, 0);
    }
    U<std::uint64_t>(&index, 0);
    Str(&index, layout_.compression);
    U<std::uint64_t>(&index, records.size());
    U<std::uint64_t>(&index, chunk_.size());
    chunk_indexes_.push_back(index);
    chunk_.clear();
    chunk_channels_.clear();
    chunk_start_ = 0;
    chunk_end_ = 0;
  }

  std::ofstream out_;
  McapLayout layout_;
  Bytes file_;  // written whole at Close (test bags are small)
  Bytes chunk_;
  std::uint64_t chunk_start_ = 0;
  std::uint64_t chunk_end_ = 0;
  std::set<std::uint16_t> chunk_channels_;
  std::map<std::string, std::pair<std::uint16_t, std::string>> channels_;
  std::vector<Bytes> chunk_indexes_;
};

/// The rosbag2 SQLite storage (schema of rosbag2 Humble and later).
class SqliteWriter : public Ros2Writer {
 public:
  explicit SqliteWriter(const std::filesystem::path& file) {
    std::filesystem::remove(file);
    if (sqlite3_open(file.string().c_str(), &db_) != SQLITE_OK) {
      throw std::runtime_error("cannot create " + file.string());
    }
    Exec(
        "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
        "INSERT INTO schema VALUES (4, 'humble');"
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
        "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
        "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
        "timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
        "CREATE INDEX timestamp_idx ON messages (timestamp ASC);"
        "BEGIN;");
  }
  ~SqliteWriter() override { sqlite3_close(db_); }

  void Write(const std::string& topic, const std::string& type, std::uint64_t time_ns,
             const Bytes& data) override {
    auto it = topics_.find(topic);
    if (it == topics_.end()) {
      const auto id = static_cast<std::int64_t>(topics_.size() + 1);
      it = topics_.emplace(topic, id).first;
      Exec("INSERT INTO topics VALUES (" + std::to_string(id) + ", '" + topic + "', '" + type +
           "', 'cdr', '');");
    }
    sqlite3_stmt* s = nullptr;
    sqlite3_prepare_v2(db_, "INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)", -1,
                       &s, nullptr);
    sqlite3_bind_int64(s, 1, it->second);
    sqlite3_bind_int64(s, 2, static_cast<std::int64_t>(time_ns));
    sqlite3_bind_blob(s, 3, data.data(), static_cast<int>(data.size()), SQLITE_TRANSIENT);
    const int rc = sqlite3_step(s);
    sqlite3_finalize(s);
    if (rc != SQLITE_DONE) throw std::runtime_error("cannot insert a message");
  }

  void Close() override { Exec("COMMIT;"); }

 private:
  void Exec(const std::string& sql) {
    char* error = nullptr;
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
      const std::string message = error ? error : "?";
      sqlite3_free(error);
      throw std::runtime_error("sqlite: " + message);
    }
  }
  sqlite3* db_ = nullptr;
  std::map<std::string, std::int64_t> topics_;
};

/// rosbag2's metadata.yaml for the files of a bag directory.
inline void WriteRos2Metadata(const std::filesystem::path& directory,
                              const std::vector<std::string>& files, const std::string& storage) {
  std::ofstream out(directory / "metadata.yaml");
  out << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: " << storage
      << "\n  duration:\n    nanoseconds: 0\n  starting_time:\n    nanoseconds_since_epoch: 0\n"
      << "  message_count: 0\n  topics_with_message_count: []\n  compression_format: \"\"\n"
      << "  compression_mode: \"\"\n  relative_file_paths:\n";
  for (const std::string& f : files) out << "    - " << f << "\n";
}

/// How WriteSequenceRos2Bag records a sequence.
struct Ros2Recording {
  McapLayout mcap;              ///< for *.mcap files
  bool big_endian = false;      ///< CDR byte order of every message
  double time_offset_s = 0.0;   ///< added to the sequence's stamps
  std::size_t first_frame = 0;  ///< frames from this one (a split bag's later file)
  std::size_t frames = std::numeric_limits<std::size_t>::max();  ///< up to this one (excluded)
  bool calibration = true;  ///< camera info, /tf_static and NavSatFix before the frames
  /// Stereo images: encodings in turn (left, right, left, ...), or "png"/"jpeg".
  std::vector<std::string> encodings = {"mono8"};
  bool cloud_float64 = false;
  bool odometry_on_tf = false;                     ///< /tf odom -> base_link instead of /odom
  std::string groundtruth_topic = "/groundtruth";  ///< PoseStamped; empty: none
  bool tf_static = true;  ///< base_link -> mast -> stereo_left on /tf_static
  bool navsat = true;     ///< the origin as a NavSatFix (after one without a fix)
  /// > 0: a NavSatFix of the true body position with every frame, of this σ (and its
  /// covariance), `navsat_offset_m` east of the truth (a datum the fixes disagree with).
  double navsat_track_sigma_m = 0.0;
  double navsat_offset_m = 0.0;
  /// Changes a message just before it is written (topic, its CDR bytes).
  std::function<void(const std::string& topic, Bytes* data)> edit;
};

/// The ROS 2 bag a rover would have recorded of `sequence` on io::BagOptions' default topics,
/// in time order: `file` is *.mcap or *.db3.
inline std::filesystem::path WriteSequenceRos2Bag(const std::filesystem::path& sequence,
                                                  const std::filesystem::path& file,
                                                  const Ros2Recording& how = {}) {
  const io::SequenceReader reader(sequence);
  const io::SequenceInfo& info = reader.info();
  const io::BagOptions topics;
  const Cdr cdr{how.big_endian};
  const std::vector<TumPose> odometry = ReadTumPoses(sequence / "odometry.tum");
  const std::vector<TumPose> truth = ReadTumPoses(sequence / "groundtruth.tum");
  std::unique_ptr<Ros2Writer> writer;
  if (file.extension() == ".db3") {
    writer = std::make_unique<SqliteWriter>(file);
  } else {
    writer = std::make_unique<McapWriter>(file, how.mcap);
  }
  auto write = [&](const std::string& topic, const std::string& type, double t, Bytes data) {
    if (how.edit) how.edit(topic, &data);
    writer->Write(topic, type, Nanoseconds(t), data);
  };
  const double start = how.time_offset_s;  // before the first frame (or at it, from 0)
  if (info.camera && how.calibration) {
    const io::CameraModel& camera = *info.camera;
    write(topics.left_info_topic, "sensor_msgs/msg/CameraInfo", start,
          cdr.CameraInfo(camera, 0.0, start));
    write(topics.right_info_topic, "sensor_msgs/msg/CameraInfo", start,
          cdr.CameraInfo(camera, -camera.fx * camera.baseline_m, start));
  }
  if (how.tf_static && how.calibration) {
    Eigen::Isometry3d T_body_mast = Eigen::Isometry3d::Identity();
    T_body_mast.translation() = Eigen::Vector3d(0.1, 0.0, 0.5);
    Cdr::Transform mast_sensor{"/mast", topics.sensor_frame,
                               T_body_mast.inverse() * info.T_body_sensor,
                               info.body_sensor_quaternion};
    write("/tf_static", "tf2_msgs/msg/TFMessage", start,
          cdr.Tf({{"base_link", "mast", T_body_mast, std::nullopt}, mast_sensor}, start));
  }
  if (how.navsat && how.calibration) {
    write(topics.navsat_topic, "sensor_msgs/msg/NavSatFix", start,
          cdr.NavSatFix(0.0, 0.0, 0.0, start, -1));  // no fix yet
    write(topics.navsat_topic, "sensor_msgs/msg/NavSatFix", start,
          cdr.NavSatFix(info.origin.latitude_deg, info.origin.longitude_deg, info.origin.altitude_m,
                        start, 0));
  }
  for (std::size_t k = how.first_frame; k < std::min(how.frames, reader.frame_count()); ++k) {
    const io::Frame frame = reader.Read(k);
    const double t = frame.timestamp + how.time_offset_s;
    if (how.odometry_on_tf) {
      write("/tf", "tf2_msgs/msg/TFMessage", t,
            cdr.Tf({{"map", "odom", Eigen::Isometry3d::Identity(), std::nullopt},
                    {"odom", "base_link", frame.T_world_body_odom, odometry.at(k).q}},
                   t));
    } else {
      write(topics.odometry_topic, "nav_msgs/msg/Odometry", t, cdr.Odometry(odometry.at(k), t));
    }
    if (!how.groundtruth_topic.empty() && k < truth.size()) {
      write(how.groundtruth_topic, "geometry_msgs/msg/PoseStamped", t,
            cdr.PoseStamped(truth[k], t));
    }
    if (how.navsat_track_sigma_m > 0.0 && k < truth.size()) {
      const io::Georeference georef(info.origin);
      const Eigen::Vector3d p = truth[k].t + Eigen::Vector3d(how.navsat_offset_m, 0.0, 0.0);
      const Eigen::Vector3d geo = georef.EnuToGeodetic(p.x(), p.y(), p.z());
      write(topics.navsat_topic, "sensor_msgs/msg/NavSatFix", t,
            cdr.NavSatFix(geo.x(), geo.y(), geo.z(), t, 0, how.navsat_track_sigma_m));
    }
    if (info.sensor_type == io::SensorType::kCloud) {
      write(topics.cloud_topic, "sensor_msgs/msg/PointCloud2", t,
            cdr.PointCloud(frame.cloud, how.cloud_float64, t));
      continue;
    }
    for (const bool left : {true, false}) {
      const std::string& encoding = how.encodings[(2 * k + (left ? 0 : 1)) % how.encodings.size()];
      const cv::Mat& grey = left ? frame.left : frame.right;
      const double stamp = left ? t : t + 0.001;
      const std::string& topic = left ? topics.left_image_topic : topics.right_image_topic;
      if (encoding == "png" || encoding == "jpeg") {
        write(topic, "sensor_msgs/msg/CompressedImage", stamp,
              cdr.Compressed(grey, encoding == "png" ? ".png" : ".jpg", stamp));
      } else {
        write(topic, "sensor_msgs/msg/Image", stamp, cdr.Image(grey, encoding, stamp));
      }
    }
  }
  writer->Close();
  return file;
}

}  // namespace rovermap::testing
