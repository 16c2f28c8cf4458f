#pragma once
// What a recording's frames hold.

namespace rovermap::io {

enum class SensorType { kStereo, kCloud };

}  // namespace rovermap::io
