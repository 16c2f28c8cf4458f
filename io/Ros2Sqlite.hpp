#pragma once
// The rosbag2 SQLite storage (a .db3 file): tables topics(id, name, type,
// serialization_format, ...) and messages(id, topic_id, timestamp, data), read with Debian's
// libsqlite3, read-only.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "io/BagMessages.hpp"

struct sqlite3;

namespace rovermap::io::ros2 {

struct SqliteTopic {
  std::int64_t id = 0;
  std::string name;
  std::string type;                  ///< "sensor_msgs/msg/Image"
  std::string serialization_format;  ///< "cdr"
};

class SqliteBag {
 public:
  /// @throw IoError naming the file if it is not an SQLite database with rosbag2's tables.
  explicit SqliteBag(const std::filesystem::path& file);
  ~SqliteBag();
  SqliteBag(const SqliteBag&) = delete;
  SqliteBag& operator=(const SqliteBag&) = delete;

  const std::vector<SqliteTopic>& topics() const { return topics_; }

  /// Calls `visit(message id, topic id, data, size)` for each message on `topic_ids`, by
  /// timestamp: `data` is the whole message of `size` bytes or, on `head_topic_ids`, at most its
  /// first `head_bytes` (the rest is not read: incremental BLOB I/O), valid during the call.
  /// @throw IoError naming the file (and the message) if the database cannot be read (e.g. it
  ///        is truncated).
  void ForEachMessage(const std::set<std::int64_t>& topic_ids,
                      const std::set<std::int64_t>& head_topic_ids, std::size_t head_bytes,
                      const std::function<void(std::int64_t id, std::int64_t topic_id,
                                               bag::ByteView data, std::size_t size)>& visit) const;

  /// The data of message `id`. @throw IoError naming the file and the message.
  std::vector<std::uint8_t> ReadMessage(std::int64_t id) const;

 private:
  std::string name_;
  sqlite3* db_ = nullptr;
  std::vector<SqliteTopic> topics_;
};

}  // namespace rovermap::io::ros2
