#include "mapper/ReadAhead.hpp"

#include <chrono>
#include <string>
#include <utility>

#include "core/Stopwatch.hpp"
#include "io/IoError.hpp"

namespace rovermap::mapper {

ReadAhead::ReadAhead(io::FrameSource* source, const Mapper* mapper)
    : source_(source), mapper_(mapper), next_(source->next_index()) {
  if (next_ < source_->frame_count())
    pending_ = thread_.Submit([this, index = next_] { return Fetch(index); });
}

ReadAhead::Item ReadAhead::Fetch(std::size_t index) {
  Item item;
  item.index = index;
  const auto start = std::chrono::steady_clock::now();
  io::Frame frame;
  try {
    if (!source_->Next(&frame)) {
      item.error = "no frame " + std::to_string(index) + " in the recording";
      return item;
    }
  } catch (const io::IoError& e) {
    item.error = e.what();  // the source has moved past it
    return item;
  }
  item.load_ms = core::MsSince(start);
  item.prepared = mapper_->Prepare(frame);
  item.frame = std::move(frame);
  return item;
}

bool ReadAhead::Next(Item* item) {
  if (!pending_.valid()) return false;
  *item = pending_.get();  // rethrows what Fetch threw
  ++next_;
  if (next_ < source_->frame_count())
    pending_ = thread_.Submit([this, index = next_] { return Fetch(index); });
  return true;
}

}  // namespace rovermap::mapper
