#pragma once
// CDR (XCDR1, OMG DDS-XTypes §7.4.3.5): the serialisation of ROS 2 messages in bags. A
// 4-byte encapsulation header says the byte order (00 00 big-endian, 00 01 little-endian);
// each primitive is aligned to its size (8 at most) counted from the end of that header.
// Decodes exactly the messages rovermap reads, into io/BagMessages.hpp; views point into `data`.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "io/BagMessages.hpp"

namespace rovermap::io::cdr {

/// Reads one CDR buffer front to back. Every read is bounds-checked.
class CdrReader {
 public:
  /// @throw IoError naming `what` if the encapsulation header is missing or not plain CDR.
  CdrReader(bag::ByteView data, std::string what);
  /// The same on the first bytes `head` of a buffer of `size` bytes: reads are checked against
  /// `size`, as on the whole buffer. @throw HeadTooShort if a read lies beyond `head`.
  CdrReader(bag::ByteView head, std::size_t size, std::string what);

  std::uint8_t U8(const char* field);
  std::uint16_t U16(const char* field);
  std::uint32_t U32(const char* field);
  double F64(const char* field);
  /// A string (uint32 length counting the terminating NUL, then the bytes).
  std::string String(const char* field);
  /// A sequence<uint8>: a view of its bytes (data null when they lie beyond the head read).
  bag::ByteView Bytes(const char* field);
  /// A sequence's element count; @throw IoError if fewer than `count * min_size` bytes remain.
  std::uint32_t Count(const char* field, std::size_t min_size);
  /// Skips `count` primitives of `size` bytes (aligned to `size`).
  void Skip(std::size_t count, std::size_t size, const char* field);

 private:
  /// Where `size` bytes aligned to `align` start; moves past them. @throw IoError naming `what`
  /// if they lie beyond the buffer.
  std::size_t Reserve(std::size_t size, std::size_t align, const char* field);
  const std::uint8_t* Take(std::size_t size, std::size_t align, const char* field);
  template <typename T>
  T Read(const char* field);

  bag::ByteView data_;    // the buffer, or its first bytes
  std::size_t size_ = 0;  // the buffer's
  std::string what_;
  std::size_t pos_ = 4;  // after the encapsulation header
  bool little_ = true;
};

/// Thrown by a CdrReader of a buffer's first bytes when they end before the fields asked for.
struct HeadTooShort {};

/// @throw IoError naming `what` (the bag, topic and record) if the buffer is shorter than its
///        declared lengths or its header is not CDR.
bag::ImageMsg DecodeImage(bag::ByteView data, const std::string& what);
bag::CompressedImageMsg DecodeCompressedImage(bag::ByteView data, const std::string& what);
bag::CameraInfoMsg DecodeCameraInfo(bag::ByteView data, const std::string& what);
bag::PointCloudMsg DecodePointCloud(bag::ByteView data, const std::string& what);
bag::PoseMsg DecodeOdometry(bag::ByteView data, const std::string& what);
bag::PoseMsg DecodePoseStamped(bag::ByteView data, const std::string& what);
std::vector<bag::TransformMsg> DecodeTfMessage(bag::ByteView data, const std::string& what);
bag::NavSatFixMsg DecodeNavSatFix(bag::ByteView data, const std::string& what);

/// An image's or cloud's fields but its pixels or points, from the first bytes `head` of a
/// message of `size` bytes (what opening a bag needs): every length is checked against `size`,
/// as the decoders above do; data.size is the data's length and data.data null.
/// @return nullopt if the fields before the data run past `head` (read more of the message).
/// @throw IoError naming `what` as the decoders above.
std::optional<bag::ImageMsg> DecodeImageHead(bag::ByteView head, std::size_t size,
                                             const std::string& what);
std::optional<bag::CompressedImageMsg> DecodeCompressedImageHead(bag::ByteView head,
                                                                 std::size_t size,
                                                                 const std::string& what);
std::optional<bag::PointCloudMsg> DecodePointCloudHead(bag::ByteView head, std::size_t size,
                                                       const std::string& what);

}  // namespace rovermap::io::cdr
