#include "io/Ros2Bag.hpp"

#include <yaml-cpp/yaml.h>

#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <system_error>
#include <utility>

#include "io/BagRules.hpp"
#include "io/Cdr.hpp"
#include "io/IoError.hpp"
#include "io/Mcap.hpp"
#include "io/Ros2Sqlite.hpp"

namespace rovermap::io {
namespace {

namespace fs = std::filesystem;
using bag::Role;

// One message as a storage file holds it; (a, b) find it again in that file.
struct Stored {
  const std::string& topic;
  const std::string& type;      // "sensor_msgs/msg/Image"
  const std::string& encoding;  // "cdr"
  bag::ByteView data;           // the message, or only its first bytes (see Storage::ForEach)
  std::size_t size = 0;         // the message's
  std::uint64_t a = 0;
  std::uint64_t b = 0;
};

// What is read of an image or cloud at opening: enough for its header and layout, usually.
constexpr std::size_t kHeadBytes = 1024;

// One storage file of a bag: MCAP or SQLite.
class Storage {
 public:
  explicit Storage(fs::path file) : file_(std::move(file)) {}
  virtual ~Storage() = default;
  Storage(const Storage&) = delete;
  Storage& operator=(const Storage&) = delete;

  const fs::path& file() const { return file_; }
  /// Each topic and its type (a topic's first channel when it has several).
  virtual std::map<std::string, std::string> Topics() const = 0;
  /// Each message on `topics`, in file order (MCAP) or by timestamp (SQLite). Those on
  /// `head_topics` may come as their first kHeadBytes only, when that saves reading the rest.
  virtual void ForEach(const std::set<std::string>& topics,
                       const std::set<std::string>& head_topics,
                       const std::function<void(const Stored&)>& visit) = 0;
  /// The data of the message at (a, b), valid during `use`.
  virtual void Read(std::uint64_t a, std::uint64_t b,
                    const std::function<void(bag::ByteView)>& use) = 0;
  /// Where (a, b) is, for messages: "record at byte 1234", "message id 7".
  virtual std::string RecordText(std::uint64_t a, std::uint64_t b) const = 0;

 private:
  fs::path file_;
};

class McapStorage : public Storage {
 public:
  explicit McapStorage(const fs::path& file) : Storage(file), reader_(file) {}

  std::map<std::string, std::string> Topics() const override {
    std::map<std::string, std::string> types;
    for (const auto& [id, c] : reader_.channels()) {
      types.emplace(c.topic, c.schema_name.empty() ? "(no schema)" : c.schema_name);
    }
    return types;
  }

  // Whole messages: a chunk is read and decompressed whole anyway.
  void ForEach(const std::set<std::string>& topics, const std::set<std::string>& /*head_topics*/,
               const std::function<void(const Stored&)>& visit) override {
    std::set<std::uint16_t> ids;
    for (const auto& [id, c] : reader_.channels()) {
      if (topics.count(c.topic) != 0) ids.insert(id);
    }
    reader_.ForEachMessage(ids, [&](const mcap::Message& m) {
      const mcap::Channel& c = reader_.channels().at(m.channel_id);
      visit({c.topic, c.schema_name, c.message_encoding, m.data, m.data.size, m.where.chunk,
             m.where.offset});
    });
  }

  void Read(std::uint64_t a, std::uint64_t b,
            const std::function<void(bag::ByteView)>& use) override {
    use(reader_.ReadMessage({a, b}).data);
  }

  std::string RecordText(std::uint64_t a, std::uint64_t b) const override {
    return mcap::LocationText({a, b});
  }

 private:
  mcap::McapReader reader_;
};

class SqliteStorage : public Storage {
 public:
  explicit SqliteStorage(const fs::path& file) : Storage(file), bag_(file) {
    for (const ros2::SqliteTopic& t : bag_.topics()) by_id_.emplace(t.id, t);
  }

  std::map<std::string, std::string> Topics() const override {
    std::map<std::string, std::string> types;
    for (const ros2::SqliteTopic& t : bag_.topics()) types.emplace(t.name, t.type);
    return types;
  }

  void ForEach(const std::set<std::string>& topics, const std::set<std::string>& head_topics,
               const std::function<void(const Stored&)>& visit) override {
    std::set<std::int64_t> ids;
    std::set<std::int64_t> head_ids;
    for (const ros2::SqliteTopic& t : bag_.topics()) {
      if (topics.count(t.name) != 0) ids.insert(t.id);
      if (head_topics.count(t.name) != 0) head_ids.insert(t.id);
    }
    bag_.ForEachMessage(
        ids, head_ids, kHeadBytes,
        [&](std::int64_t id, std::int64_t topic_id, bag::ByteView data, std::size_t size) {
          const ros2::SqliteTopic& t = by_id_.at(topic_id);
          visit({t.name, t.type, t.serialization_format, data, size, static_cast<std::uint64_t>(id),
                 0});
        });
  }

  void Read(std::uint64_t a, std::uint64_t /*b*/,
            const std::function<void(bag::ByteView)>& use) override {
    const std::vector<std::uint8_t> data = bag_.ReadMessage(static_cast<std::int64_t>(a));
    use({data.data(), data.size()});
  }

  std::string RecordText(std::uint64_t a, std::uint64_t /*b*/) const override {
    return "message id " + std::to_string(a);
  }

 private:
  ros2::SqliteBag bag_;
  std::map<std::int64_t, ros2::SqliteTopic> by_id_;
};

std::unique_ptr<Storage> OpenStorage(const fs::path& file) {
  if (file.extension() == ".mcap") return std::make_unique<McapStorage>(file);
  if (file.extension() == ".db3") return std::make_unique<SqliteStorage>(file);
  throw IoError(file.string() + ": neither an MCAP (.mcap) nor an SQLite (.db3) bag file");
}

// Where one image or cloud is, by bag::MessageRef::id.
struct Ref {
  std::size_t file = 0;
  std::uint64_t a = 0;
  std::uint64_t b = 0;
  bool compressed = false;
};

// "file: topic (record)": where a CDR buffer is.
std::string RecordWhat(const Storage& s, const std::string& topic, std::uint64_t a,
                       std::uint64_t b) {
  return s.file().string() + ": " + topic + " (" + s.RecordText(a, b) + ")";
}

// An image's or cloud's fields but its data, by `decode` (cdr::Decode*Head), from the bytes `m`
// holds, else (only when they are part of it) from the whole message read again.
template <typename Msg>
Msg DecodeHead(const Stored& m, Storage& s, const std::string& what,
               std::optional<Msg> (*decode)(bag::ByteView, std::size_t, const std::string&)) {
  std::optional<Msg> msg = decode(m.data, m.size, what);
  if (!msg) s.Read(m.a, m.b, [&](bag::ByteView data) { msg = decode(data, data.size, what); });
  return *msg;
}

// Feeds one message to `c` by its role, decoding its CDR (an image or cloud's but its data).
// @throw IoError naming the file, the topic and the record.
void Add(const Stored& m, std::size_t file, Storage& s, bag::BagContents& c,
         std::vector<Ref>* refs) {
  const bag::TypeNames& types = bag::Ros2Types();
  const Role role = c.RoleOf(m.topic);
  if (role == Role::kNone) return;
  const std::string what = RecordWhat(s, m.topic, m.a, m.b);
  if (m.encoding != "cdr") {
    throw IoError(what + ": message encoding '" + m.encoding + "' (only cdr is read)");
  }
  auto expect = [&](const std::string& type) {
    if (m.type != type) throw IoError(c.WrongType(m.topic, m.type, type));
  };
  switch (role) {
    case Role::kImage: {
      const bool compressed = m.type == types.compressed;
      if (compressed) {
        c.AddImage(m.topic, DecodeHead(m, s, what, &cdr::DecodeCompressedImageHead), refs->size());
      } else {
        expect(types.image);
        c.AddImage(m.topic, DecodeHead(m, s, what, &cdr::DecodeImageHead), refs->size());
      }
      refs->push_back({file, m.a, m.b, compressed});
      break;
    }
    case Role::kCloud:
      expect(types.cloud);
      c.AddCloud(DecodeHead(m, s, what, &cdr::DecodePointCloudHead), refs->size());
      refs->push_back({file, m.a, m.b, false});
      break;
    case Role::kCameraInfo:
      expect(types.info);
      c.AddCameraInfo(m.topic, cdr::DecodeCameraInfo(m.data, what));
      break;
    case Role::kTf:
      expect(types.tf);
      c.AddTransforms(m.topic, cdr::DecodeTfMessage(m.data, what));
      break;
    case Role::kOdometry:
      expect(types.odometry);
      c.AddOdometry(cdr::DecodeOdometry(m.data, what));
      break;
    case Role::kGroundTruth:
      if (m.type == types.pose) {
        c.AddGroundTruth(cdr::DecodePoseStamped(m.data, what));
      } else {
        expect(types.odometry);
        c.AddGroundTruth(cdr::DecodeOdometry(m.data, what));
      }
      break;
    case Role::kNavSat:
      expect(types.navsat);
      c.AddNavSatFix(cdr::DecodeNavSatFix(m.data, what));
      break;
    case Role::kNone:
      break;
  }
}

// rosbag2's metadata.yaml: the storage files, checked to be there.
std::vector<fs::path> MetadataFiles(const fs::path& directory) {
  const fs::path metadata = directory / "metadata.yaml";
  const std::string name = metadata.string();
  auto fail = [&](const YAML::Node& node, const std::string& reason) {
    const YAML::Mark mark = node.Mark();
    throw IoError(name + (mark.is_null() ? "" : ":" + std::to_string(mark.line + 1)) + ": " +
                  reason);
  };
  YAML::Node root;
  try {
    root = YAML::LoadFile(name);
  } catch (const YAML::Exception& e) {
    throw IoError(name + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  const YAML::Node info = root["rosbag2_bagfile_information"];
  if (!info || !info.IsMap()) fail(root, "no rosbag2_bagfile_information: not a rosbag2 bag");
  const YAML::Node compression = info["compression_mode"];
  if (compression && compression.IsScalar() && !compression.Scalar().empty() &&
      compression.Scalar() != "NONE") {
    fail(compression, "rosbag2 compression (compression_mode " + compression.Scalar() +
                          ") is not read: decompress the bag first (ros2 bag convert)");
  }
  const YAML::Node paths = info["relative_file_paths"];
  if (!paths || !paths.IsSequence() || paths.size() == 0) {
    fail(info, "relative_file_paths: expected a list of the bag's files");
  }
  std::vector<fs::path> files;
  for (const YAML::Node& path : paths) {
    if (!path.IsScalar()) fail(path, "relative_file_paths: expected file names");
    const fs::path file = directory / path.Scalar();
    std::error_code error;
    if (!fs::is_regular_file(file, error)) {
      fail(path, "names " + path.Scalar() + ", which is not in " + directory.string());
    }
    files.push_back(file);
  }
  return files;
}

}  // namespace

bool IsRos2Bag(const fs::path& path) {
  std::error_code error;
  if (fs::is_directory(path, error)) return fs::exists(path / "metadata.yaml", error);
  return path.extension() == ".mcap" || path.extension() == ".db3";
}

std::vector<fs::path> Ros2BagFiles(const fs::path& path) {
  std::error_code error;
  if (fs::is_directory(path, error)) return MetadataFiles(path);
  return {path};
}

struct Ros2BagSource::Bag {
  std::vector<std::unique_ptr<Storage>> files;
  std::vector<Ref> refs;  // by MessageRef::id
};

Ros2BagSource::Ros2BagSource(const fs::path& path, const BagOptions& options)
    : BagFrameSource(path, options), bag_(std::make_unique<Bag>()) {
  std::error_code error;
  if (!fs::exists(path, error)) throw IoError(path.string() + ": no such bag file");
  for (const fs::path& file : Ros2BagFiles(path)) bag_->files.push_back(OpenStorage(file));
  bag::BagContents contents(path, options, bag::Ros2Types());
  std::map<std::string, std::string> types;
  for (const auto& file : bag_->files) {
    for (const auto& [topic, type] : file->Topics()) types.emplace(topic, type);
  }
  const std::vector<std::string> wanted = contents.TopicsToRead(types);
  const std::set<std::string> topics(wanted.begin(), wanted.end());
  // Of images and clouds only the headers are read now; the data when their frame is.
  std::set<std::string> heads;
  for (const std::string& topic : wanted) {
    const Role role = contents.RoleOf(topic);
    if (role == Role::kImage || role == Role::kCloud) heads.insert(topic);
  }
  for (std::size_t i = 0; i < bag_->files.size(); ++i) {
    Storage& s = *bag_->files[i];
    s.ForEach(topics, heads, [&](const Stored& m) { Add(m, i, s, contents, &bag_->refs); });
  }
  Adopt(contents.Finish());
}

Ros2BagSource::~Ros2BagSource() = default;

cv::Mat Ros2BagSource::ReadImage(const std::string& topic, const bag::MessageRef& ref) const {
  const Ref& r = bag_->refs.at(ref.id);
  Storage& s = *bag_->files.at(r.file);
  const std::string what = bag::FrameWhat(file(), topic, ref.stamp);
  const std::string record = RecordWhat(s, topic, r.a, r.b);
  cv::Mat grey;
  s.Read(r.a, r.b, [&](bag::ByteView data) {
    grey = r.compressed ? bag::ToGrey(cdr::DecodeCompressedImage(data, record), what)
                        : bag::ToGrey(cdr::DecodeImage(data, record), what);
  });
  return grey;
}

registration::PointCloud Ros2BagSource::ReadCloud(const bag::MessageRef& ref) const {
  const Ref& r = bag_->refs.at(ref.id);
  Storage& s = *bag_->files.at(r.file);
  const std::string& topic = options().cloud_topic;
  registration::PointCloud cloud;
  s.Read(r.a, r.b, [&](bag::ByteView data) {
    cloud = bag::ToCloud(cdr::DecodePointCloud(data, RecordWhat(s, topic, r.a, r.b)),
                         bag::FrameWhat(file(), topic, ref.stamp));
  });
  return cloud;
}

}  // namespace rovermap::io
