#pragma once
// An MCAP file (https://mcap.dev/spec, major version 0), read without a library: magic,
// records, chunks (none, lz4, zstd; their CRC32 checked), the summary section and its chunk
// indexes. An indexed file is read by its chunk indexes, skipping chunks without the asked
// channels; a file without a summary (or cut off before it) front to back.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <istream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "io/BagMessages.hpp"

namespace rovermap::io::mcap {

struct Channel {
  std::uint16_t id = 0;
  std::string topic;
  std::string message_encoding;  ///< "cdr" for ROS 2
  std::string schema_name;       ///< "sensor_msgs/msg/Image"; empty without a schema
};

/// Where a message is: a chunk's file offset and the message record's offset among the chunk's
/// records, or (chunk == kNoChunk) the record's file offset.
struct Location {
  static constexpr std::uint64_t kNoChunk = ~std::uint64_t{0};
  std::uint64_t chunk = kNoChunk;
  std::uint64_t offset = 0;
};

struct Message {
  std::uint16_t channel_id = 0;
  std::uint64_t log_time = 0;  ///< [ns]
  bag::ByteView data;          ///< valid until the reader reads again
  Location where;
};

/// "chunk at byte C, record at byte R of its records" or "record at byte R".
std::string LocationText(const Location& where);

class McapReader {
 public:
  /// Reads the magic, the footer and the summary (else scans the file for its channels).
  /// @throw IoError naming the file if it is not MCAP, is truncated inside a record, or a
  ///        record or chunk cannot be read (CRC mismatch, unknown compression).
  explicit McapReader(const std::filesystem::path& file);
  /// The same on `bytes` in memory, named `name` in errors (the fuzz target's way in).
  McapReader(std::string bytes, std::string name);
  ~McapReader();
  McapReader(const McapReader&) = delete;
  McapReader& operator=(const McapReader&) = delete;

  const std::map<std::uint16_t, Channel>& channels() const { return channels_; }
  /// Whether the summary has chunk indexes (messages are then found by them).
  bool indexed() const { return !chunks_.empty(); }

  /// Calls `visit` with each message on `channel_ids`, in file order.
  /// @throw IoError naming the file and the record that cannot be read.
  void ForEachMessage(const std::set<std::uint16_t>& channel_ids,
                      const std::function<void(const Message&)>& visit);

  /// The message at `where` again (its data valid until the next read).
  /// @throw IoError naming the file and record if it is not a message.
  Message ReadMessage(const Location& where);

 private:
  struct ChunkIndex {
    std::uint64_t offset = 0;
    std::set<std::uint16_t> channels;  // empty: not listed
  };
  struct Record {
    std::uint8_t opcode = 0;
    std::uint64_t offset = 0;  // of the opcode
    std::vector<std::uint8_t> body;
  };

  /// Checks the magic and reads the summary or scans for the channels.
  void Open();
  bool ReadSummary();
  /// The record at `offset`, or false at the end of the file.
  /// @throw IoError naming the file if the record is cut off.
  bool ReadRecord(std::uint64_t offset, Record* record);
  /// The records of the chunk record `chunk`, decompressed and CRC-checked (cached).
  const std::vector<std::uint8_t>& ChunkRecords(const Record& chunk);
  const std::vector<std::uint8_t>& ChunkAt(std::uint64_t offset);
  /// Walks the data section front to back; `visit` gets each record (chunks opened).
  void Scan(const std::function<void(std::uint8_t opcode, bag::ByteView body,
                                     const Location& where)>& visit);
  void AddSchemaOrChannel(std::uint8_t opcode, bag::ByteView body, const Location& where);

  std::string name_;
  std::unique_ptr<std::istream> in_;  // the file, or the bytes in memory
  std::uint64_t size_ = 0;
  std::uint64_t data_end_ = 0;  // where the data section's scan stops
  std::map<std::uint16_t, std::string> schemas_;
  std::map<std::uint16_t, Channel> channels_;
  std::vector<ChunkIndex> chunks_;
  std::uint64_t cached_chunk_ = Location::kNoChunk;
  std::vector<std::uint8_t> cached_records_;
  Record record_;  // the last top-level record read by ReadMessage
};

}  // namespace rovermap::io::mcap
