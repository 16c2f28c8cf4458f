#pragma once
// What a recording's frames hold. Header-only, so that config/ can name it without linking io.

namespace rovermap::io {

enum class SensorType { kStereo, kCloud };

}  // namespace rovermap::io
