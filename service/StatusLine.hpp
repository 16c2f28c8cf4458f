#pragma once
// A frame's outcome in words, as the per-frame lines of `replay` and `serve` and the Python
// FrameResult's repr say it.

#include <string>

#include "mapper/Mapper.hpp"

namespace rovermap::mapper {

/// "status (reason: detail)": the reason only when there is one beyond the first frame's, the
/// detail only when there is one.
std::string StatusLine(const FrameResult& result);

}  // namespace rovermap::mapper
