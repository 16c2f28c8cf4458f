// libFuzzer target: io::ParsePly (ascii, binary_little_endian, binary_big_endian).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tests/fuzz/FuzzEntries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  rovermap::fuzz::Ply(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
