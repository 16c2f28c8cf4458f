// libFuzzer target: io::mcap::McapReader on an MCAP file in memory, its messages decoded.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tests/fuzz/FuzzEntries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  rovermap::fuzz::Mcap(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
