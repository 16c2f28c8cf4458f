#pragma once

// Internal helpers shared by the text readers of rovermap::io (not part of the public API).

#include <charconv>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "io/IoError.hpp"

namespace rovermap::io::detail {

/// "path:line: message", or "path: message" when line is 0.
[[noreturn]] inline void Fail(const std::filesystem::path& path, std::size_t line,
                              const std::string& message) {
  std::string text = path.string();
  if (line > 0) text += ":" + std::to_string(line);
  throw IoError(text + ": " + message);
}

/// Token quoted for an error message: printable, at most 40 characters (input may be binary).
inline std::string Quote(std::string_view token) {
  constexpr std::size_t kMax = 40;
  std::string out = "'";
  for (std::size_t i = 0; i < token.size() && i < kMax; ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    out += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '?';
  }
  if (token.size() > kMax) out += "...";
  return out + "'";
}

// '\r' counts as blank so CRLF files and trailing CRs need no special casing per token.
inline bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Walks a buffer line by line; LF and CRLF endings are both stripped, and a last line
/// without a newline is still returned.
class LineCursor {
 public:
  explicit LineCursor(std::string_view data, std::size_t offset = 0, std::size_t lines_before = 0)
      : data_(data), offset_(offset), line_number_(lines_before) {}

  bool Next(std::string_view* line) {
    if (offset_ >= data_.size()) return false;
    std::size_t end = data_.find('\n', offset_);
    std::size_t next = end + 1;
    if (end == std::string_view::npos) end = next = data_.size();
    std::size_t stop = end;
    if (stop > offset_ && data_[stop - 1] == '\r') --stop;
    *line = data_.substr(offset_, stop - offset_);
    offset_ = next;
    ++line_number_;
    return true;
  }

  /// 1-based number of the line last returned by Next (0 before the first call).
  std::size_t LineNumber() const { return line_number_; }
  /// Byte offset just past the line last returned (its terminator included).
  std::size_t Offset() const { return offset_; }

 private:
  std::string_view data_;
  std::size_t offset_;
  std::size_t line_number_;
};

/// Splits on blanks; `tokens` is reused across calls to avoid reallocating per line.
inline void Tokenize(std::string_view line, std::vector<std::string_view>* tokens) {
  tokens->clear();
  std::size_t i = 0;
  const std::size_t n = line.size();
  while (i < n) {
    while (i < n && IsBlank(line[i])) ++i;
    const std::size_t start = i;
    while (i < n && !IsBlank(line[i])) ++i;
    if (i > start) tokens->push_back(line.substr(start, i - start));
  }
}

/// Line with any '#' comment removed.
inline std::string_view StripComment(std::string_view line) {
  const std::size_t hash = line.find('#');
  return hash == std::string_view::npos ? line : line.substr(0, hash);
}

enum class NumberStatus { kOk, kInvalid, kOutOfRange };

/// Parses a whole token as a double ("1", "-2.5e-3", "+4", "nan", "inf" are all numbers;
/// the caller rejects non-finite values with its own message).
inline NumberStatus ParseDouble(std::string_view token, double* value) {
  const char* first = token.data();
  const char* last = first + token.size();
  // from_chars rejects a leading '+', which other tools do write.
  if (first != last && *first == '+' && last - first > 1 && first[1] != '-' && first[1] != '+') {
    ++first;
  }
  if (first == last) return NumberStatus::kInvalid;
  const auto [ptr, ec] = std::from_chars(first, last, *value, std::chars_format::general);
  if (ec == std::errc::result_out_of_range && ptr == last) return NumberStatus::kOutOfRange;
  if (ec != std::errc() || ptr != last) return NumberStatus::kInvalid;
  return NumberStatus::kOk;
}

/// Parses a whole token as a non-negative integer.
inline bool ParseUnsigned(std::string_view token, std::uint64_t* value) {
  const char* first = token.data();
  const char* last = first + token.size();
  if (first != last && *first == '+') ++first;
  if (first == last) return false;
  const auto [ptr, ec] = std::from_chars(first, last, *value);
  return ec == std::errc() && ptr == last;
}

/// Lower-cased ASCII copy (for case-insensitive keywords and extensions).
inline std::string ToLower(std::string_view text) {
  std::string out(text);
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

}  // namespace rovermap::io::detail
