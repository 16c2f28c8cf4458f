#pragma once
// The daemon's state to and from disk (docs/design.md §7): after `kill -9` or a power loss at any
// instant, a restart resumes with nothing lost and without registering a frame twice.
//
// Two files in one directory:
//  - `state.bin`, a snapshot of the whole mapper (pose chain and per-frame results, the DEM's
//    tiles, the OctoMap with its log-odds, the registration reference) and of the daemon's
//    queue, written every few frames through a temporary file, a flush and a rename;
//  - `journal.bin`, one record per frame processed since that snapshot (the frame's result:
//    the increment it chained and why), appended and flushed before the frame counts as done.
//    Each record carries its length and a CRC-32, so a record torn by a kill is recognised and
//    dropped.
// Restoring loads the snapshot and re-applies the journalled frames (Mapper::Reapply: their
// points are read and fused again at the recorded pose, not registered), so the state equals
// the one the interrupted run had reached. A kill between the rename and the journal's reset
// leaves records the snapshot already holds: they are recognised by their frame and skipped.
// The files are in the machine's byte order, for the machine that wrote them.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "mapper/GraphRun.hpp"
#include "mapper/Mapper.hpp"

namespace rovermap::mapper {

/// A checkpoint that cannot be used: another configuration or sequence, or damaged files.
class CheckpointError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What the daemon keeps beside the mapper.
struct DaemonState {
  std::size_t next_index = 0;         ///< the next frame index to take
  std::vector<std::size_t> missing;   ///< indices declared missing without any pose
  std::vector<std::size_t> rejected;  ///< indices moved to the inbox's rejected/
};

/// Called at named points of the writing ("journal:partial", "checkpoint:written",
/// "checkpoint:renamed"), so that a test can kill the process there.
using FaultHook = std::function<void(std::string_view point)>;

class Checkpoint {
 public:
  /// `directory` is created if missing. `fingerprint`: whatever must not change across a
  /// restart (the configuration, sequence.yaml); a checkpoint made with another is refused.
  /// @throw io::IoError if the directory cannot be created.
  Checkpoint(std::filesystem::path directory, std::string fingerprint, FaultHook hook = {});

  /// True if a snapshot or journal exists.
  bool Exists() const;

  /// Restores the saved state into `mapper` (fresh, built with the same options and sequence):
  /// the snapshot, then every journalled frame after it, re-applied with its files from
  /// `read_frame(index)` (not called for bad frames). A torn last record is dropped. With
  /// `graph` (fresh, the same options and reference), its tracks are restored too and every
  /// re-applied frame is given to its AfterFrame, as the interrupted run gave it; `log` gets
  /// the lines that makes.
  /// @return the daemon's state; default (frame 0) when there is no checkpoint.
  /// @throw CheckpointError for another fingerprint or damaged files; ReapplyError or
  ///        io::IoError if a journalled frame cannot be re-applied.
  DaemonState Restore(Mapper* mapper, const std::function<io::Frame(std::size_t index)>& read_frame,
                      GraphRun* graph = nullptr,
                      const std::function<void(const std::string&)>& log = {});

  /// Journals one step of the daemon: `frame` (nullptr for an index declared missing without
  /// a pose) and the daemon's state after it. Flushed to disk before it returns.
  /// @throw io::IoError naming the journal; the record cut short is cut off, so the journal
  ///        ends with the previous record and a later append follows it.
  void Append(const FrameResult* frame, const DaemonState& after);

  /// Writes a snapshot of `mapper`, `state` and `graph`'s tracks (the pose graph's sources:
  /// their matches and the ground they keep), then empties the journal.
  /// @throw io::IoError naming the file.
  void Save(const Mapper& mapper, const DaemonState& state, const GraphRun* graph = nullptr);

  /// Journal records since the last snapshot [count].
  std::size_t journal_records() const { return journal_records_; }
  /// Journal records Restore re-applied (those the snapshot did not hold) [count].
  std::size_t reapplied() const { return reapplied_; }
  /// Size of the last snapshot written or read [bytes].
  std::size_t snapshot_bytes() const { return snapshot_bytes_; }
  const std::filesystem::path& directory() const { return directory_; }

 private:
  /// @throw CheckpointError naming `file` if `found` is not this configuration's fingerprint.
  void CheckFingerprint(const std::string& found, const std::filesystem::path& file) const;
  void Fault(std::string_view point) const {
    if (hook_) hook_(point);
  }
  std::filesystem::path directory_;
  std::string fingerprint_;
  FaultHook hook_;
  std::size_t journal_records_ = 0;
  std::size_t reapplied_ = 0;
  std::size_t snapshot_bytes_ = 0;
};

/// A FrameResult as the snapshot and the journal hold it.
std::string EncodeFrameResult(const FrameResult& result);
/// EncodeFrameResult's inverse. @throw CheckpointError if `bytes` is not exactly one.
FrameResult DecodeFrameResult(std::string_view bytes);

/// CRC-32 (IEEE 802.3, as zlib's crc32) of `data`.
std::uint32_t Crc32(std::string_view data);

}  // namespace rovermap::mapper
