#include "io/Mcap.hpp"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <system_error>

#include "io/IoError.hpp"

namespace rovermap::io::mcap {
namespace {

using bag::ByteView;

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
constexpr std::uint8_t kFooter = 0x02;
constexpr std::uint8_t kSchema = 0x03;
constexpr std::uint8_t kChannel = 0x04;
constexpr std::uint8_t kMessage = 0x05;
constexpr std::uint8_t kChunk = 0x06;
constexpr std::uint8_t kChunkIndex = 0x08;
constexpr std::uint8_t kDataEnd = 0x0F;
constexpr std::uint64_t kRecordHead = 9;   // opcode and content length
constexpr std::uint64_t kFooterBody = 20;  // summary_start, summary_offset_start, summary_crc
// A chunk's records are held in memory whole; rosbag2 writes chunks of a few MB.
constexpr std::uint64_t kMaxChunkRecords = std::uint64_t{1} << 30;

std::uint64_t LoadU64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}

std::string Hex(std::uint64_t v) {
  char buffer[24];
  std::snprintf(buffer, sizeof(buffer), "0x%llx", static_cast<unsigned long long>(v));
  return buffer;
}

// Little-endian fields of one record's content, bounds-checked.
class Cursor {
 public:
  Cursor(ByteView body, std::string what) : body_(body), what_(std::move(what)) {}

  template <typename T>
  T Read(const char* field) {
    const std::uint8_t* p = Take(sizeof(T), field);
    T value = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) value |= static_cast<T>(p[i]) << (8 * i);
    return value;
  }
  std::string String(const char* field) {
    const std::uint32_t length = Read<std::uint32_t>(field);
    return std::string(reinterpret_cast<const char*>(Take(length, field)), length);
  }
  /// A uint32 byte length and that many bytes (a map or byte array).
  ByteView Prefixed32(const char* field) {
    const std::uint32_t length = Read<std::uint32_t>(field);
    return {Take(length, field), length};
  }
  ByteView Prefixed64(const char* field) {
    const std::uint64_t length = Read<std::uint64_t>(field);
    return {Take(length, field), static_cast<std::size_t>(length)};
  }
  ByteView Rest() { return {body_.data + pos_, body_.size - pos_}; }
  bool AtEnd() const { return pos_ == body_.size; }

 private:
  const std::uint8_t* Take(std::uint64_t size, const char* field) {
    if (size > body_.size - pos_) {
      throw IoError(what_ + ": '" + field + "' needs " + std::to_string(size) +
                    " bytes, the record has " + std::to_string(body_.size - pos_) + " left");
    }
    const std::uint8_t* p = body_.data + pos_;
    pos_ += static_cast<std::size_t>(size);
    return p;
  }

  ByteView body_;
  std::string what_;
  std::size_t pos_ = 0;
};

// Calls `visit` with each record of a chunk's records. @throw IoError naming `what` if one
// overruns them.
template <typename Visit>
void ForEachRecord(ByteView records, const std::string& what, Visit&& visit) {
  std::uint64_t offset = 0;
  while (offset < records.size) {
    const std::uint64_t left = records.size - offset;
    std::uint64_t length = 0;
    if (left >= kRecordHead) length = LoadU64(records.data + offset + 1);
    if (left < kRecordHead || length > left - kRecordHead) {
      throw IoError(what + ": the record at byte " + std::to_string(offset) +
                    " of the chunk's records overruns them");
    }
    visit(records.data[offset],
          ByteView{records.data + offset + kRecordHead, static_cast<std::size_t>(length)}, offset);
    offset += kRecordHead + length;
  }
}

Message ParseMessage(ByteView body, const Location& where, const std::string& what) {
  Cursor c(body, what);
  Message m;
  m.channel_id = c.Read<std::uint16_t>("channel_id");
  c.Read<std::uint32_t>("sequence");
  m.log_time = c.Read<std::uint64_t>("log_time");
  c.Read<std::uint64_t>("publish_time");
  m.data = c.Rest();
  m.where = where;
  return m;
}

std::vector<std::uint8_t> Lz4Decompress(ByteView in, std::uint64_t size, const std::string& what) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(size));
  LZ4F_dctx* context = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION))) {
    throw IoError(what + ": cannot start lz4 decompression");
  }
  std::size_t in_pos = 0;
  std::size_t out_pos = 0;
  std::size_t status = 1;
  while (status != 0 && in_pos < in.size && out_pos <= out.size()) {
    std::size_t in_size = in.size - in_pos;
    std::size_t out_size = out.size() - out_pos;
    status = LZ4F_decompress(context, out.data() + out_pos, &out_size, in.data + in_pos, &in_size,
                             nullptr);
    if (LZ4F_isError(status)) {
      const std::string error = LZ4F_getErrorName(status);
      LZ4F_freeDecompressionContext(context);
      throw IoError(what + ": lz4 data is corrupt (" + error + ")");
    }
    in_pos += in_size;
    out_pos += out_size;
    if (in_size == 0 && out_size == 0) break;  // no progress: the output is full
  }
  LZ4F_freeDecompressionContext(context);
  if (status != 0 || out_pos != out.size()) {
    throw IoError(what + ": lz4 data gives " + std::to_string(out_pos) + " bytes" +
                  (status != 0 ? " and does not end" : "") + ", the chunk says " +
                  std::to_string(size));
  }
  return out;
}

std::vector<std::uint8_t> ZstdDecompress(ByteView in, std::uint64_t size, const std::string& what) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(size));
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), in.data, in.size);
  if (ZSTD_isError(n)) {
    throw IoError(what + ": zstd data is corrupt (" + ZSTD_getErrorName(n) + ")");
  }
  if (n != size) {
    throw IoError(what + ": zstd data gives " + std::to_string(n) + " bytes, the chunk says " +
                  std::to_string(size));
  }
  return out;
}

}  // namespace

std::string LocationText(const Location& where) {
  if (where.chunk == Location::kNoChunk) return "record at byte " + std::to_string(where.offset);
  return "chunk at byte " + std::to_string(where.chunk) + ", record at byte " +
         std::to_string(where.offset) + " of its records";
}

McapReader::McapReader(const std::filesystem::path& file) : name_(file.string()) {
  std::error_code error;
  size_ = std::filesystem::file_size(file, error);
  auto in = std::make_unique<std::ifstream>(file, std::ios::binary);
  if (error || !*in) throw IoError(name_ + ": cannot open the MCAP file");
  in_ = std::move(in);
  Open();
}

McapReader::McapReader(std::string bytes, std::string name) : name_(std::move(name)) {
  size_ = bytes.size();
  in_ = std::make_unique<std::istringstream>(std::move(bytes));
  Open();
}

void McapReader::Open() {
  std::uint8_t magic[8] = {};
  in_->read(reinterpret_cast<char*>(magic), 8);
  if (size_ < 8 || std::memcmp(magic, kMagic, 8) != 0) {
    throw IoError(name_ + ": not an MCAP file (no MCAP0 magic at its start)");
  }
  data_end_ = size_;
  if (!ReadSummary() || channels_.empty()) {
    // No summary, or one without channels: they are in the data section.
    Scan([&](std::uint8_t opcode, ByteView body, const Location& where) {
      AddSchemaOrChannel(opcode, body, where);
    });
  }
}

McapReader::~McapReader() = default;

bool McapReader::ReadSummary() {
  const std::uint64_t tail = kRecordHead + kFooterBody + 8;
  if (size_ < 8 + tail) return false;
  std::uint8_t magic[8] = {};
  in_->seekg(static_cast<std::streamoff>(size_ - 8));
  in_->read(reinterpret_cast<char*>(magic), 8);
  if (!*in_ || std::memcmp(magic, kMagic, 8) != 0) return false;  // cut off: scan it
  Record footer;
  const std::uint64_t footer_offset = size_ - tail;
  if (!ReadRecord(footer_offset, &footer) || footer.opcode != kFooter ||
      footer.body.size() != kFooterBody) {
    throw IoError(name_ + ": no footer record before the closing magic");
  }
  data_end_ = footer_offset;
  Cursor f({footer.body.data(), footer.body.size()}, name_ + ": footer");
  const std::uint64_t summary_start = f.Read<std::uint64_t>("summary_start");
  if (summary_start == 0) return false;
  if (summary_start < 8 || summary_start > footer_offset) {
    throw IoError(name_ + ": the footer's summary_start " + std::to_string(summary_start) +
                  " lies outside the file");
  }
  data_end_ = summary_start;
  Record record;
  for (std::uint64_t offset = summary_start; offset < footer_offset;
       offset += kRecordHead + record.body.size()) {
    ReadRecord(offset, &record);
    const Location where{Location::kNoChunk, offset};
    const ByteView body{record.body.data(), record.body.size()};
    if (record.opcode != kChunkIndex) {
      AddSchemaOrChannel(record.opcode, body, where);
      continue;
    }
    Cursor c(body, name_ + ": " + LocationText(where) + " (chunk index)");
    c.Read<std::uint64_t>("message_start_time");
    c.Read<std::uint64_t>("message_end_time");
    ChunkIndex index;
    index.offset = c.Read<std::uint64_t>("chunk_start_offset");
    c.Read<std::uint64_t>("chunk_length");
    const ByteView offsets = c.Prefixed32("message_index_offsets");
    for (std::size_t i = 0; i + 10 <= offsets.size; i += 10) {
      index.channels.insert(static_cast<std::uint16_t>(offsets.data[i] | offsets.data[i + 1] << 8));
    }
    chunks_.push_back(index);
  }
  std::sort(chunks_.begin(), chunks_.end(),
            [](const ChunkIndex& a, const ChunkIndex& b) { return a.offset < b.offset; });
  return true;
}

bool McapReader::ReadRecord(std::uint64_t offset, Record* record) {
  if (offset >= size_) return false;
  const std::uint64_t left = size_ - offset;
  std::uint8_t head[kRecordHead] = {};
  std::uint64_t length = 0;
  if (left >= kRecordHead) {
    in_->clear();
    in_->seekg(static_cast<std::streamoff>(offset));
    in_->read(reinterpret_cast<char*>(head), kRecordHead);
    length = LoadU64(head + 1);
  }
  if (left < kRecordHead || length > left - kRecordHead) {
    throw IoError(name_ + ": truncated: the record at byte " + std::to_string(offset) +
                  (left < kRecordHead ? " is cut off"
                                      : " (opcode " + Hex(head[0]) + ") declares " +
                                            std::to_string(length) + " bytes") +
                  ", the file ends " + std::to_string(left) + " bytes after it starts");
  }
  record->opcode = head[0];
  record->offset = offset;
  record->body.resize(static_cast<std::size_t>(length));
  in_->read(reinterpret_cast<char*>(record->body.data()), static_cast<std::streamsize>(length));
  if (!*in_) throw IoError(name_ + ": cannot read the record at byte " + std::to_string(offset));
  return true;
}

const std::vector<std::uint8_t>& McapReader::ChunkRecords(const Record& chunk) {
  if (cached_chunk_ == chunk.offset) return cached_records_;
  const std::string what = name_ + ": chunk at byte " + std::to_string(chunk.offset);
  Cursor c({chunk.body.data(), chunk.body.size()}, what);
  c.Read<std::uint64_t>("message_start_time");
  c.Read<std::uint64_t>("message_end_time");
  const std::uint64_t size = c.Read<std::uint64_t>("uncompressed_size");
  const std::uint32_t crc = c.Read<std::uint32_t>("uncompressed_crc");
  const std::string compression = c.String("compression");
  const ByteView records = c.Prefixed64("records");
  if (size > kMaxChunkRecords) {
    throw IoError(what + ": uncompressed size " + std::to_string(size) + " exceeds 1 GiB");
  }
  cached_chunk_ = Location::kNoChunk;
  if (compression.empty()) {
    if (records.size != size) {
      throw IoError(what + ": holds " + std::to_string(records.size) + " bytes of records, says " +
                    std::to_string(size));
    }
    cached_records_.assign(records.data, records.data + records.size);
  } else if (compression == "lz4") {
    cached_records_ = Lz4Decompress(records, size, what);
  } else if (compression == "zstd") {
    cached_records_ = ZstdDecompress(records, size, what);
  } else {
    throw IoError(what + ": unknown compression '" + compression + "' (none, lz4, zstd)");
  }
  if (crc != 0) {  // 0: the writer did not compute one
    const auto actual = static_cast<std::uint32_t>(
        crc32_z(crc32_z(0L, Z_NULL, 0), cached_records_.data(), cached_records_.size()));
    if (actual != crc) {
      throw IoError(what + ": CRC32 of its records is " + Hex(actual) + ", the chunk says " +
                    Hex(crc) + " (corrupt)");
    }
  }
  cached_chunk_ = chunk.offset;
  return cached_records_;
}

const std::vector<std::uint8_t>& McapReader::ChunkAt(std::uint64_t offset) {
  if (cached_chunk_ == offset) return cached_records_;
  Record chunk;
  if (!ReadRecord(offset, &chunk) || chunk.opcode != kChunk) {
    throw IoError(name_ + ": no chunk record at byte " + std::to_string(offset) +
                  " where the chunk index points");
  }
  return ChunkRecords(chunk);
}

void McapReader::Scan(const std::function<void(std::uint8_t, ByteView, const Location&)>& visit) {
  Record record;
  for (std::uint64_t offset = 8; offset < data_end_ && ReadRecord(offset, &record);
       offset += kRecordHead + record.body.size()) {
    if (record.opcode == kFooter || record.opcode == kDataEnd) break;
    if (record.opcode != kChunk) {
      visit(record.opcode, {record.body.data(), record.body.size()}, {Location::kNoChunk, offset});
      continue;
    }
    const std::vector<std::uint8_t>& records = ChunkRecords(record);
    ForEachRecord({records.data(), records.size()},
                  name_ + ": chunk at byte " + std::to_string(offset),
                  [&](std::uint8_t opcode, ByteView body, std::uint64_t inner) {
                    visit(opcode, body, {offset, inner});
                  });
  }
}

void McapReader::AddSchemaOrChannel(std::uint8_t opcode, ByteView body, const Location& where) {
  if (opcode != kSchema && opcode != kChannel) return;
  Cursor c(body,
           name_ + ": " + LocationText(where) + (opcode == kSchema ? " (schema)" : " (channel)"));
  const std::uint16_t id = c.Read<std::uint16_t>("id");
  if (opcode == kSchema) {
    schemas_.emplace(id, c.String("name"));
    return;
  }
  Channel channel;
  channel.id = id;
  const std::uint16_t schema_id = c.Read<std::uint16_t>("schema_id");
  channel.topic = c.String("topic");
  channel.message_encoding = c.String("message_encoding");
  // Schemas come before the channels that use them (spec: "Schema records must ...").
  const auto schema = schemas_.find(schema_id);
  if (schema != schemas_.end()) channel.schema_name = schema->second;
  channels_.emplace(id, std::move(channel));
}

void McapReader::ForEachMessage(const std::set<std::uint16_t>& channel_ids,
                                const std::function<void(const Message&)>& visit) {
  auto offer = [&](std::uint8_t opcode, ByteView body, const Location& where) {
    if (opcode != kMessage) return;
    const Message m = ParseMessage(body, where, name_ + ": " + LocationText(where));
    if (channel_ids.count(m.channel_id) != 0) visit(m);
  };
  if (!indexed()) {
    Scan(offer);
    return;
  }
  for (const ChunkIndex& chunk : chunks_) {
    const bool wanted = chunk.channels.empty() ||
                        std::any_of(chunk.channels.begin(), chunk.channels.end(),
                                    [&](std::uint16_t id) { return channel_ids.count(id) != 0; });
    if (!wanted) continue;  // the index says none of its messages is asked for
    const std::vector<std::uint8_t>& records = ChunkAt(chunk.offset);
    ForEachRecord({records.data(), records.size()},
                  name_ + ": chunk at byte " + std::to_string(chunk.offset),
                  [&](std::uint8_t opcode, ByteView body, std::uint64_t inner) {
                    offer(opcode, body, {chunk.offset, inner});
                  });
  }
}

Message McapReader::ReadMessage(const Location& where) {
  const std::string what = name_ + ": " + LocationText(where);
  if (where.chunk == Location::kNoChunk) {
    if (!ReadRecord(where.offset, &record_)) throw IoError(what + ": past the data section");
    if (record_.opcode == kMessage)
      return ParseMessage({record_.body.data(), record_.body.size()}, where, what);
    throw IoError(what + ": not a message record");
  }
  const std::vector<std::uint8_t>& records = ChunkAt(where.chunk);
  const std::uint64_t left = where.offset < records.size() ? records.size() - where.offset : 0;
  std::uint64_t length = 0;
  if (left >= kRecordHead) length = LoadU64(records.data() + where.offset + 1);
  if (left < kRecordHead || records[where.offset] != kMessage || length > left - kRecordHead) {
    throw IoError(what + ": not a message record");
  }
  return ParseMessage(
      {records.data() + where.offset + kRecordHead, static_cast<std::size_t>(length)}, where, what);
}

}  // namespace rovermap::io::mcap
