#pragma once
// `rovermap serve` (docs/design.md §7): frames taken from an inbox as they arrive, in index order,
// through the same Mapper as replay; the outputs of §6 published every few frames, status.json
// after every frame, and every frame journalled (service/Checkpoint) before it counts as done,
// so that a restart after `kill -9` resumes where the run stopped.

#include <atomic>
#include <chrono>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/TaskThread.hpp"
#include "eval/EvalOptions.hpp"
#include "io/Inbox.hpp"
#include "io/ReferenceDem.hpp"
#include "mapper/GraphRun.hpp"
#include "mapper/Mapper.hpp"
#include "mapper/ServeOptions.hpp"
#include "service/Checkpoint.hpp"
#include "service/OutputPublisher.hpp"

namespace rovermap::mapper {

/// The reference DEM given cannot be used and reference.required is set.
class ReferenceRequiredError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Another daemon holds the output directory's lock.
class DaemonBusyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct DaemonSetup {
  std::filesystem::path inbox;
  std::filesystem::path out;
  PipelineOptions pipeline;
  ServeOptions serve;
  eval::EvalOptions eval;
  /// The pose graph's sources (docs/graph.md): fixes from the inbox's gnss.csv, revisits, and
  /// the reference DEM at `reference_dem` (empty: none), solved at each publication.
  GraphSetup graph;
  std::filesystem::path reference_dem;
  /// The effective configuration as text: with sequence.yaml, what a checkpoint must have been
  /// made with.
  std::string config_text;
  /// One line per frame and per event (the command prints them on stderr).
  std::function<void(const std::string&)> log;
  /// Test hook: called at named points ("frame:processed", "publish:<file>", and Checkpoint's).
  FaultHook fault;
};

class Daemon {
 public:
  /// Creates OUT and takes its lock (OUT/serve.lock, flock), holding it until destroyed.
  /// @throw DaemonBusyError naming the pid of the daemon that holds it; io::IoError if OUT
  ///        cannot be created.
  explicit Daemon(DaemonSetup setup);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  /// Waits for the inbox's sequence.yaml and reads it, and opens the reference DEM (left out,
  /// logged, when unusable). @return false if `stop` turned non-zero first. @throw io::IoError
  /// for an unreadable or invalid sequence.yaml (naming file and line); std::invalid_argument
  /// for options the Mapper refuses; ReferenceRequiredError for an unusable reference DEM with
  /// reference.required.
  bool WaitForSequence(const std::atomic<int>& stop);
  /// Restores the checkpoint in OUT, if any (after WaitForSequence).
  /// @throw CheckpointError if it was made with another configuration or is damaged;
  ///        ReapplyError / io::IoError if a journalled frame cannot be re-applied.
  void Resume();
  /// Processes frames until `stop` turns non-zero; then the frame in hand is finished, the
  /// state checkpointed and the outputs published before it returns (after Resume).
  /// @throw io::IoError if OUT cannot be written or the inbox's frames/ cannot be listed.
  void Run(const std::atomic<int>& stop);

  /// How long restoring the checkpoint took [ms] (0 before Run, or without a checkpoint).
  double restart_ms() const { return restart_ms_; }

 private:
  using Clock = std::chrono::steady_clock;
  using FrameFiles = std::map<std::size_t, io::InboxFrameFiles>;
  bool Step(const FrameFiles& files);
  /// Rejects the ready frames beyond serve.max_gap_frames. @return whether there was one.
  bool RejectMisnumbered(const FrameFiles& files);
  FrameFiles::const_iterator FirstReadyAfter(const FrameFiles& files, std::size_t index) const;
  /// Whether the next frame, held up by a later ready one, has waited serve.gap_timeout_s.
  bool GapTimedOut(const FrameFiles& files);
  /// Declares every index before the first ready frame missing.
  void DeclareGapMissing(const FrameFiles& files);
  /// A frame read from the inbox and, when readable, prepared (Mapper::Prepare: stereo, index).
  struct ReadFrame {
    io::Frame frame;
    std::optional<std::string> unreadable;  ///< why inbox_.Read failed
    PreparedFrame prepared;
    double load_ms = 0.0;
  };
  ReadFrame ReadAndPrepare(std::size_t index, const io::InboxFrameFiles& files) const;
  /// The frame `index`: the one read ahead if that is it, else read now. `following`: the next
  /// index's files when they are complete, read and prepared in the background meanwhile (as
  /// replay's ReadAhead does), so that its stereo runs beside this frame's registration.
  void ProcessIndex(std::size_t index, const io::InboxFrameFiles& files,
                    const io::InboxFrameFiles* following);
  /// A frame of which some files came, declared missing.
  void DeclareMissing(std::size_t index, const io::InboxFrameFiles& files);
  void Commit(const FrameResult* result, const std::string& reject_reason);
  void RejectLate(const FrameFiles& files);
  /// Solves the pose graph (at publish_every frames, whatever the outputs do, so that the
  /// solves a windowed graph builds on do not depend on timing) and, with `write`, publishes.
  void Publish(bool write = true);
  /// The pose graph over every frame so far with what its sources found (logged when solved).
  std::optional<GraphOutcome> SolveAndLogGraph();
  /// The fixes of the inbox's gnss.csv (none without it; the last readable ones while it is
  /// being written and a line is broken).
  std::vector<io::GnssFix> InboxFixes();
  /// gnss.csv's size and modification time ("" without the file): whether the fixes changed.
  std::string GnssCsvSignature() const;
  void WriteStatus(const char* state, std::size_t waiting);
  void Log(const std::string& line) const {
    if (setup_.log) setup_.log(line);
  }
  void Fault(std::string_view point) const {
    if (setup_.fault) setup_.fault(point);
  }

  DaemonSetup setup_;
  io::Inbox inbox_;
  int lock_fd_ = -1;
  io::SequenceInfo sequence_;
  std::string sequence_text_;
  std::unique_ptr<Mapper> mapper_;
  std::unique_ptr<io::ReferenceDem> reference_;  // before graph_run_, which keeps a reference
  std::string reference_unusable_;
  std::unique_ptr<GraphRun> graph_run_;
  std::vector<io::GnssFix> fixes_;
  std::string fixes_error_;  // the last gnss.csv error logged
  std::unique_ptr<Checkpoint> checkpoint_;
  DaemonState state_;
  std::optional<Clock::time_point> gap_since_;
  int since_publish_ = 0;     // frames since the last solve (at publish_every)
  int unwritten_frames_ = 0;  // frames since the last publication written
  // When this run last wrote its outputs, state_.next_index and the gnss.csv its graph read: on
  // exit, whether they are current (fixes appended since need a publication, frames or not).
  std::optional<std::size_t> published_through_;
  std::string published_gnss_, solved_gnss_;
  double unwritten_ms_ = 0.0;                    // their processing time
  double last_handover_ms_ = 0.0;                // the last publication's share on this thread
  std::optional<GraphOutcome> unwritten_graph_;  // the last solve, when not yet written
  int since_checkpoint_ = 0;
  double since_checkpoint_ms_ = 0.0;  // the frames' processing time since the last snapshot
  double last_snapshot_ms_ = 0.0;
  std::size_t processed_ = 0;  // frames this session
  double busy_ms_ = 0.0;       // time spent on them
  double restart_ms_ = 0.0;
  double last_timestamp_ = -1e300;
  std::string last_frame_time_;  // UTC, ISO 8601
  std::size_t waiting_ = 0;
  bool status_stale_ = false;  // a frame done since status.json was written
  Clock::time_point status_written_{};
  // The frame after the one in hand, being read and prepared; destroyed (waited for) before the
  // mapper and the inbox it uses.
  std::optional<std::pair<std::size_t, std::future<ReadFrame>>> ahead_;
  std::size_t read_ahead_ = 0;  // frames this session that came from ahead_
  core::TaskThread reader_;     // reads ahead_; after what its tasks use, so joined before it
  OutputPublisher publisher_;   // last: destroyed (joined) first
};

}  // namespace rovermap::mapper
