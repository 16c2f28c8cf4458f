#pragma once

#include <stdexcept>

namespace rovermap::io {

/// Bad, missing or unwritable input/output file. The message starts with the file path and,
/// for text formats, the 1-based line number: "data/a.xyz:12: non-numeric value 'abc'".
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace rovermap::io
