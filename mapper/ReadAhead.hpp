#pragma once
// Reading and step 1 (load, stereo, index) of frame k+1 beside steps 2-8 of frame k, so that
// the cores the matcher leaves idle are used. One frame ahead only, so memory stays flat.

#include <cstddef>
#include <future>
#include <optional>
#include <string>

#include "core/TaskThread.hpp"
#include "io/FrameSource.hpp"
#include "mapper/Mapper.hpp"

namespace rovermap::mapper {

/// Reads the frames of `source` in order and prepares each with `mapper.Prepare` on a thread
/// of its own (one for the whole run: a thread per frame started its own OpenMP team and
/// malloc arena each time, whose large buffers were mapped and faulted in again every frame),
/// one frame ahead of the caller. Both must outlive it; the caller must not use
/// `source` meanwhile. Mapper::Prepare reads only what ProcessPrepared never changes, so the
/// caller may process frame k while frame k+1 is prepared.
class ReadAhead {
 public:
  struct Item {
    std::size_t index = 0;
    std::optional<io::Frame> frame;  ///< nullopt: its files could not be read (`error` says why)
    std::string error;
    PreparedFrame prepared;  ///< made from `frame`
    double load_ms = 0.0;    ///< reading the files
  };

  ReadAhead(io::FrameSource* source, const Mapper* mapper);
  ReadAhead(const ReadAhead&) = delete;
  ReadAhead& operator=(const ReadAhead&) = delete;
  /// Waits for the frame in flight, if any, and stops the thread (TaskThread's destructor).
  ~ReadAhead() = default;

  /// The next frame, and starts preparing the one after. False after the last frame.
  /// Rethrows what reading threw other than io::IoError (which becomes `error`).
  bool Next(Item* item);

 private:
  Item Fetch(std::size_t index);

  io::FrameSource* source_;
  const Mapper* mapper_;
  std::size_t next_ = 0;
  std::future<Item> pending_;  // the frame in flight
  core::TaskThread thread_;    // last: drained and joined before the rest goes
};

}  // namespace rovermap::mapper
