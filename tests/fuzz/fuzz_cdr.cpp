// libFuzzer target: the CDR decoders of io/Cdr (ROS 2 messages; the first byte picks the type).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tests/fuzz/FuzzEntries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  rovermap::fuzz::Cdr(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
