#include "mapper/ReadAhead.hpp"

#include <chrono>
#include <string>
#include <utility>

#include "core/Stopwatch.hpp"
#include "io/IoError.hpp"

namespace rovermap::mapper {

ReadAhead::ReadAhead(io::FrameSource* source, const Mapper* mapper)
    : source_(source), mapper_(mapper), next_(source->next_index()), thread_([this] { Loop(); }) {
  if (next_ < source_->frame_count()) Request(next_);
}

ReadAhead::~ReadAhead() {
  if (pending_.valid()) pending_.wait();
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

void ReadAhead::Request(std::size_t index) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    promise_ = std::promise<Item>();
    pending_ = promise_.get_future();
    requested_ = index;
  }
  wake_.notify_one();
}

void ReadAhead::Loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || requested_.has_value(); });
    if (stop_) return;
    const std::size_t index = *requested_;
    requested_.reset();
    std::promise<Item> promise = std::move(promise_);
    lock.unlock();
    try {
      promise.set_value(Fetch(index));
    } catch (...) {
      promise.set_exception(std::current_exception());  // Next rethrows it
    }
    lock.lock();
  }
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
  if (next_ < source_->frame_count()) Request(next_);
  return true;
}

}  // namespace rovermap::mapper
