#pragma once
// Morton codes of OctoMap keys (dem::BatchOcTree): the three 16-bit key coordinates interleaved,
// bit 3b of key.k[0], 3b + 1 of k[1], 3b + 2 of k[2], so that ascending order is the tree's
// depth-first order.

#include <octomap/OcTreeKey.h>

#include <cstdint>

namespace rovermap::dem::morton {

constexpr unsigned kDepth = 16;  // octomap::OcTree: 16 levels, 16-bit keys

// The 16 bits of `x` spread to every third bit.
inline std::uint64_t Spread(std::uint64_t x) {
  x = (x | x << 16) & 0x0000FF0000FFULL;
  x = (x | x << 8) & 0x00F00F00F00FULL;
  x = (x | x << 4) & 0x0C30C30C30C3ULL;
  return (x | x << 2) & 0x249249249249ULL;
}

inline std::uint16_t Compact(std::uint64_t x) {
  x &= 0x249249249249ULL;
  x = (x | x >> 2) & 0x0C30C30C30C3ULL;
  x = (x | x >> 4) & 0x00F00F00F00FULL;
  x = (x | x >> 8) & 0x0000FF0000FFULL;
  return static_cast<std::uint16_t>((x | x >> 16) & 0xFFFFULL);
}

inline std::uint64_t Morton(const octomap::OcTreeKey& k) {
  return Spread(k.k[0]) | Spread(k.k[1]) << 1 | Spread(k.k[2]) << 2;
}

inline octomap::OcTreeKey FromMorton(std::uint64_t m) {
  return octomap::OcTreeKey(Compact(m), Compact(m >> 1), Compact(m >> 2));
}

// The child index below `depth` (0 = root) on the way to `m`: OctoMap's computeChildIdx.
inline unsigned ChildIndex(std::uint64_t m, unsigned depth) {
  return static_cast<unsigned>(m >> (3 * (kDepth - 1 - depth))) & 7U;
}

// The deepest node two distinct keys' paths share.
inline unsigned CommonDepth(std::uint64_t a, std::uint64_t b) {
  const unsigned highest_bit = 63U - static_cast<unsigned>(__builtin_clzll(a ^ b));
  return kDepth - 1 - highest_bit / 3;
}

}  // namespace rovermap::dem::morton
