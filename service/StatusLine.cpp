#include "service/StatusLine.hpp"

namespace rovermap::mapper {

std::string StatusLine(const FrameResult& result) {
  std::string line = ToString(result.status);
  if (result.fallback_reason != FallbackReason::kNone &&
      result.fallback_reason != FallbackReason::kFirstFrame) {
    line += std::string(" (") + ToString(result.fallback_reason);
    if (!result.detail.empty()) line += ": " + result.detail;
    line += ")";
  }
  return line;
}

}  // namespace rovermap::mapper
