#include "io/Ros2Sqlite.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <memory>
#include <system_error>

#include "io/IoError.hpp"

namespace rovermap::io::ros2 {
namespace {

using Statement = std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)>;

Statement Prepare(sqlite3* db, const std::string& sql, const std::string& name) {
  sqlite3_stmt* statement = nullptr;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr) != SQLITE_OK) {
    const std::string error = sqlite3_errmsg(db);
    sqlite3_finalize(statement);
    throw IoError(name + ": not a rosbag2 SQLite storage (" + error + ")");
  }
  return Statement(statement, &sqlite3_finalize);
}

// One step; false when done. @throw IoError naming `what` on an error.
bool Step(sqlite3* db, sqlite3_stmt* statement, const std::string& what) {
  const int rc = sqlite3_step(statement);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  throw IoError(what + ": cannot read the database (" + sqlite3_errmsg(db) + ")");
}

std::string Text(sqlite3_stmt* statement, int column) {
  const unsigned char* text = sqlite3_column_text(statement, column);
  return text ? reinterpret_cast<const char*>(text) : "";
}

}  // namespace

SqliteBag::SqliteBag(const std::filesystem::path& file) : name_(file.string()) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(file, error)) throw IoError(name_ + ": no such bag file");
  if (sqlite3_open_v2(name_.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    throw IoError(name_ + ": cannot open the SQLite file (" + message + ")");
  }
  try {
    const Statement topics =
        Prepare(db_, "SELECT id, name, type, serialization_format FROM topics ORDER BY id", name_);
    while (Step(db_, topics.get(), name_)) {
      topics_.push_back({sqlite3_column_int64(topics.get(), 0), Text(topics.get(), 1),
                         Text(topics.get(), 2), Text(topics.get(), 3)});
    }
  } catch (...) {
    sqlite3_close(db_);
    throw;
  }
}

SqliteBag::~SqliteBag() { sqlite3_close(db_); }

void SqliteBag::ForEachMessage(const std::set<std::int64_t>& topic_ids,
                               const std::set<std::int64_t>& head_topic_ids, std::size_t head_bytes,
                               const std::function<void(std::int64_t, std::int64_t, bag::ByteView,
                                                        std::size_t)>& visit) const {
  if (topic_ids.empty()) return;
  std::string ids;
  for (const std::int64_t id : topic_ids) ids += (ids.empty() ? "" : ",") + std::to_string(id);
  // The rows only: each message's data is read through one blob handle moved from row to row.
  const Statement messages =
      Prepare(db_,
              "SELECT rowid, id, topic_id FROM messages WHERE topic_id IN (" + ids +
                  ") ORDER BY timestamp, id",
              name_);
  std::unique_ptr<sqlite3_blob, decltype(&sqlite3_blob_close)> blob(nullptr, &sqlite3_blob_close);
  std::vector<std::uint8_t> data;
  while (Step(db_, messages.get(), name_)) {
    const sqlite3_int64 row = sqlite3_column_int64(messages.get(), 0);
    const std::int64_t id = sqlite3_column_int64(messages.get(), 1);
    const std::int64_t topic_id = sqlite3_column_int64(messages.get(), 2);
    int rc = SQLITE_OK;
    if (blob) {
      rc = sqlite3_blob_reopen(blob.get(), row);
    } else {
      sqlite3_blob* opened = nullptr;
      rc = sqlite3_blob_open(db_, "main", "messages", "data", row, 0, &opened);
      blob.reset(opened);
    }
    const auto size =
        static_cast<std::size_t>(rc == SQLITE_OK ? sqlite3_blob_bytes(blob.get()) : 0);
    data.resize(head_topic_ids.count(topic_id) != 0 ? std::min(size, head_bytes) : size);
    if (rc == SQLITE_OK) {
      rc = sqlite3_blob_read(blob.get(), data.data(), static_cast<int>(data.size()), 0);
    }
    if (rc != SQLITE_OK) {
      throw IoError(name_ + ": message id " + std::to_string(id) + ": cannot read the database (" +
                    sqlite3_errmsg(db_) + ")");
    }
    visit(id, topic_id, {data.data(), data.size()}, size);
  }
}

std::vector<std::uint8_t> SqliteBag::ReadMessage(std::int64_t id) const {
  const std::string what = name_ + ": message id " + std::to_string(id);
  const Statement message = Prepare(db_, "SELECT data FROM messages WHERE id = ?", name_);
  sqlite3_bind_int64(message.get(), 1, id);
  if (!Step(db_, message.get(), what)) throw IoError(what + ": not in the bag");
  const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(message.get(), 0));
  return std::vector<std::uint8_t>(data, data + sqlite3_column_bytes(message.get(), 0));
}

}  // namespace rovermap::io::ros2
