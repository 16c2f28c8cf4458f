#include "io/FrameSource.hpp"

#include "io/Sequence.hpp"

namespace rovermap::io {

std::unique_ptr<FrameSource> OpenFrameSource(const std::filesystem::path& path) {
  return std::make_unique<SequenceReader>(path);
}

}  // namespace rovermap::io
