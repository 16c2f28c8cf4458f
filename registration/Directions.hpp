#pragma once
// The six directions of a rigid correction [rx ry rz tx ty tz] (RegistrationResult's order), as
// bits: what the mapper takes from dead reckoning and what co-registration leaves uncorrected.

#include <string>

namespace rovermap::registration {

/// Rotations about x, y, z of the frame the correction is in (roll, pitch, yaw), then
/// translations along them.
enum Direction : unsigned {
  kRoll = 1u << 0,
  kPitch = 1u << 1,
  kYaw = 1u << 2,
  kX = 1u << 3,
  kY = 1u << 4,
  kZ = 1u << 5,
};

/// "x y yaw" for a mask of Direction bits, in the order roll pitch yaw x y z; "" for none.
inline std::string DirectionNames(unsigned mask) {
  static const char* const kNames[6] = {"roll", "pitch", "yaw", "x", "y", "z"};
  std::string names;
  for (int i = 0; i < 6; ++i) {
    if ((mask & (1u << i)) == 0) continue;
    if (!names.empty()) names += ' ';
    names += kNames[i];
  }
  return names;
}

}  // namespace rovermap::registration
