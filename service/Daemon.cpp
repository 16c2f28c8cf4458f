#include "service/Daemon.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>
#include <system_error>
#include <utility>

#include "core/Stopwatch.hpp"
#include "io/DirectoryWatcher.hpp"
#include "io/FileUtil.hpp"
#include "io/IoError.hpp"
#include "service/DriftReport.hpp"
#include "service/Outputs.hpp"
#include "service/StatusLine.hpp"

namespace rovermap::mapper {
namespace {

namespace fs = std::filesystem;

using core::MsBetween;

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

bool Contains(const std::vector<std::size_t>& v, std::size_t x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

}  // namespace

Daemon::Daemon(DaemonSetup setup) : setup_(std::move(setup)), inbox_(setup_.inbox) {
  std::error_code ec;
  fs::create_directories(setup_.out, ec);
  if (ec) throw io::IoError(setup_.out.string() + ": cannot create (" + ec.message() + ")");
  const fs::path lock = setup_.out / "serve.lock";
  lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (lock_fd_ < 0) {
    throw io::IoError(lock.string() + ": cannot open (" + std::strerror(errno) + ")");
  }
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    char pid[32] = {0};
    const ssize_t n = ::pread(lock_fd_, pid, sizeof(pid) - 1, 0);
    ::close(lock_fd_);
    lock_fd_ = -1;
    std::string holder(pid, n > 0 ? static_cast<std::size_t>(n) : 0);
    holder.erase(holder.find_last_not_of(" \n") + 1);
    throw DaemonBusyError(setup_.out.string() + ": already served by rovermap serve (pid " +
                          (holder.empty() ? "unknown" : holder) + ", lock " + lock.string() + ")");
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(lock_fd_, 0) != 0 || ::pwrite(lock_fd_, pid.data(), pid.size(), 0) < 0) {
    throw io::IoError(lock.string() + ": cannot write the pid (" + std::strerror(errno) + ")");
  }
  // With the lock held no other daemon writes here: temporaries are a killed publication's.
  for (const fs::path& temp : io::RemoveTemporaryFiles(setup_.out)) {
    Log("serve: removed " + temp.string() + ", left by an interrupted publication");
  }
}

Daemon::~Daemon() {
  if (ahead_) ahead_->second.wait();     // it reads the inbox with the mapper's options
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the flock
}

bool Daemon::WaitForSequence(const std::atomic<int>& stop) {
  const ServeOptions& o = setup_.serve;
  // sequence.yaml comes first; a daemon may be started before the rover's producer.
  {
    io::DirectoryWatcher watcher(inbox_.directory(), o.use_inotify);
    bool said = false;
    while (!fs::exists(inbox_.sequence_yaml())) {
      if (stop.load() != 0) return false;
      if (!said) Log("serve: waiting for " + inbox_.sequence_yaml().string());
      said = true;
      watcher.Wait(watcher.watching() ? std::min(o.poll_interval_s, 0.2) : o.poll_interval_s);
    }
  }
  sequence_ = io::ReadSequenceInfo(inbox_.directory());
  sequence_text_ = io::ReadWholeFile(inbox_.sequence_yaml());
  mapper_ = std::make_unique<Mapper>(sequence_, setup_.pipeline);
  if (!setup_.reference_dem.empty()) {
    const ReferenceOptions& r = setup_.graph.reference;
    try {
      reference_ =
          std::make_unique<io::ReferenceDem>(setup_.reference_dem, mapper_->georeference(),
                                             io::ReferenceDemOptions{r.sigma_band, r.sigma_m});
    } catch (const io::IoError& e) {
      if (r.required) throw ReferenceRequiredError(e.what());
      reference_unusable_ = e.what();
      Log("serve: reference DEM left out (reference.required is false): " + reference_unusable_);
    }
  }
  graph_run_ = std::make_unique<GraphRun>(setup_.graph, reference_.get());
  return true;
}

void Daemon::Resume() {
  // The reference DEM is part of what the checkpoint was made with: its matches are kept.
  std::string fingerprint = setup_.config_text + "\n--- sequence.yaml\n" + sequence_text_;
  if (!setup_.reference_dem.empty()) {
    std::error_code ignored;
    const fs::path canonical = fs::weakly_canonical(setup_.reference_dem, ignored);
    fingerprint +=
        "\n--- reference DEM\n" + (canonical.empty() ? setup_.reference_dem : canonical).string();
  }
  checkpoint_ =
      std::make_unique<Checkpoint>(setup_.out / "checkpoint", std::move(fingerprint), setup_.fault);
  // The snapshot, then the journalled frames re-applied (not registered again).
  if (checkpoint_->Exists()) {
    const auto start = Clock::now();
    const std::map<std::size_t, io::InboxFrameFiles> files = inbox_.Scan();
    state_ = checkpoint_->Restore(
        mapper_.get(),
        [&](std::size_t index) {
          const auto it = files.find(index);
          if (it == files.end()) {
            throw io::IoError(
                (inbox_.frames_dir() / io::FrameStem(index)).string() +
                ".*: journalled frame no longer in the inbox; the checkpoint needs it");
          }
          return inbox_.Read(index, it->second, sequence_);
        },
        graph_run_.get(), [this](const std::string& line) { Log(line); });
    restart_ms_ = MsBetween(start, Clock::now());
    if (!mapper_->results().empty()) last_timestamp_ = mapper_->results().back().timestamp;
    std::ostringstream line;
    line << "serve: resumed at frame " << state_.next_index << " (" << checkpoint_->reapplied()
         << " journalled steps re-applied) in " << std::fixed << std::setprecision(0) << restart_ms_
         << " ms";
    Log(line.str());
    since_checkpoint_ = static_cast<int>(checkpoint_->journal_records());
    // Rejections a kill interrupted: the reason is already there, move the rest.
    for (const auto& [index, present] : files) {
      if (index < state_.next_index && Contains(state_.rejected, index)) {
        inbox_.Reject(index, "rejected (see drift.csv and the daemon's log)");
      }
    }
  }
}

void Daemon::Run(const std::atomic<int>& stop) {
  const ServeOptions& o = setup_.serve;
  io::DirectoryWatcher watcher(inbox_.frames_dir(), o.use_inotify);
  WriteStatus("running", 0);
  while (stop.load() == 0) {
    const std::map<std::size_t, io::InboxFrameFiles> files = inbox_.Scan();
    waiting_ = 0;
    for (const auto& [index, present] : files) {
      if (index >= state_.next_index && present.Complete(sequence_.sensor_type)) ++waiting_;
    }
    publisher_.Poll();  // a publication that failed stops the daemon (Run's @throw)
    if (Step(files)) continue;
    // Idle (the queue ran dry or waits on a gap): whoever monitors sees the latest, the maps
    // included: the frames since the last publication need not wait for publish_every more.
    if (unwritten_frames_ > 0) Publish();
    if (status_stale_) WriteStatus("running", waiting_);
    double wait_s = watcher.watching() ? std::min(o.poll_interval_s, 0.2) : o.poll_interval_s;
    if (gap_since_) {
      const double left_s = o.gap_timeout_s - MsBetween(*gap_since_, Clock::now()) / 1000.0;
      wait_s = std::clamp(left_s, 0.0, wait_s);
    }
    watcher.Wait(wait_s);
  }
  // Signalled: the frame in hand is done; publish and checkpoint what there is.
  if (since_checkpoint_ > 0 || !fs::exists(checkpoint_->directory() / "state.bin")) {
    checkpoint_->Save(*mapper_, state_, graph_run_.get());
    since_checkpoint_ = 0;
  }
  // Outputs written after the last frame (a queue that ran dry is published at once) from the
  // fixes there are now are current: publishing them again would solve the graph and write the
  // same files once more.
  if (published_through_ != state_.next_index || published_gnss_ != GnssCsvSignature()) Publish();
  publisher_.Wait();
  WriteStatus("stopped", waiting_);
  Log("serve: stopped after frame " + std::to_string(state_.next_index) + " (" +
      std::to_string(processed_) + " frames this run, " + std::to_string(read_ahead_) +
      " of them read and prepared ahead)");
}

// One move of the queue: the frame expected next, or the frames a timed-out gap declares missing.
bool Daemon::Step(const FrameFiles& files) {
  RejectLate(files);
  if (RejectMisnumbered(files)) return true;
  const std::size_t next = state_.next_index;
  const auto it = files.find(next);
  if (it != files.end() && it->second.Complete(sequence_.sensor_type)) {
    gap_since_.reset();
    const auto following = files.find(next + 1);
    ProcessIndex(next, it->second,
                 following != files.end() && following->second.Complete(sequence_.sensor_type)
                     ? &following->second
                     : nullptr);
    return true;
  }
  if (!GapTimedOut(files)) return false;
  DeclareGapMissing(files);
  return true;
}

// A ready frame numbered far beyond the queue is misnumbered: waiting it out would declare
// every index between missing (10^12 of them for a stray 999999999999.ply).
bool Daemon::RejectMisnumbered(const FrameFiles& files) {
  const std::size_t next = state_.next_index;
  const std::size_t limit = next + static_cast<std::size_t>(setup_.serve.max_gap_frames);
  bool rejected = false;
  for (auto far = files.upper_bound(limit); far != files.end(); ++far) {
    if (!far->second.Complete(sequence_.sensor_type)) continue;
    inbox_.Reject(far->first, "index " + std::to_string(far->first) + " is more than " +
                                  std::to_string(setup_.serve.max_gap_frames) +
                                  " beyond the next frame expected, " + std::to_string(next) +
                                  " (serve.max_gap_frames): misnumbered");
    Log("serve: frame " + std::to_string(far->first) + " rejected: misnumbered, " +
        std::to_string(next) + " expected next");
    rejected = true;
  }
  return rejected;
}

Daemon::FrameFiles::const_iterator Daemon::FirstReadyAfter(const FrameFiles& files,
                                                           std::size_t index) const {
  return std::find_if(files.upper_bound(index), files.end(), [&](const auto& entry) {
    return entry.second.Complete(sequence_.sensor_type);
  });
}

// The queue is held only by a later frame that is ready; the gap's clock starts then.
bool Daemon::GapTimedOut(const FrameFiles& files) {
  const std::size_t next = state_.next_index;
  if (FirstReadyAfter(files, next) == files.end()) {
    gap_since_.reset();
    return false;
  }
  if (!gap_since_) {
    gap_since_ = Clock::now();
    Log("serve: frame " + std::to_string(next) + " holds the queue; declared missing after " +
        std::to_string(setup_.serve.gap_timeout_s) + " s");
  }
  if (MsBetween(*gap_since_, Clock::now()) < 1000.0 * setup_.serve.gap_timeout_s) return false;
  gap_since_.reset();
  return true;
}

// Every index up to the first ready frame has waited as long: a run of missing frames costs
// one timeout, not one each.
void Daemon::DeclareGapMissing(const FrameFiles& files) {
  const std::size_t next = state_.next_index;
  const auto ready = FirstReadyAfter(files, next);
  // Indices of which nothing came are journalled once per run (the journal holds the
  // daemon's whole state with each record, so one record each would grow as the run squared).
  std::optional<std::size_t> run_start;
  const auto journal_run = [&](std::size_t end) {
    if (!run_start) return;
    checkpoint_->Append(nullptr, state_);
    Log("serve: " +
        (end - *run_start == 1
             ? "frame " + std::to_string(*run_start)
             : "frames " + std::to_string(*run_start) + " to " + std::to_string(end - 1)) +
        " missing: nothing came within " + std::to_string(setup_.serve.gap_timeout_s) +
        " s (serve.gap_timeout_s); not in the trajectory");
    run_start.reset();
  };
  for (std::size_t index = next; index < ready->first; ++index) {
    const auto present = files.find(index);
    if (present == files.end()) {
      if (!run_start) run_start = index;
      state_.missing.push_back(index);
      ++state_.next_index;
      continue;
    }
    journal_run(index);
    DeclareMissing(index, present->second);
  }
  journal_run(ready->first);
}

Daemon::ReadFrame Daemon::ReadAndPrepare(std::size_t index,
                                         const io::InboxFrameFiles& files) const {
  ReadFrame read;
  const auto start = Clock::now();
  try {
    read.frame = inbox_.Read(index, files, sequence_);
  } catch (const io::IoError& e) {
    read.unreadable = e.what();
    return read;
  }
  read.load_ms = MsBetween(start, Clock::now());
  read.prepared = mapper_->Prepare(read.frame);
  return read;
}

void Daemon::ProcessIndex(std::size_t index, const io::InboxFrameFiles& files,
                          const io::InboxFrameFiles* following) {
  const auto start = Clock::now();
  ReadFrame read;
  if (ahead_ && ahead_->first == index) {
    read = ahead_->second.get();  // rethrows what ReadAndPrepare threw
    ++read_ahead_;
  } else {
    if (ahead_) ahead_->second.wait();  // another frame's (the queue moved otherwise): dropped
    read = ReadAndPrepare(index, files);
  }
  ahead_.reset();
  if (following != nullptr) {
    // The files are copied: the scan's map is gone when the task reads them.
    ahead_.emplace(index + 1, reader_.Submit([this, next = index + 1, files = *following] {
      return ReadAndPrepare(next, files);
    }));
  }
  io::Frame& frame = read.frame;
  const std::optional<std::string>& unreadable = read.unreadable;
  // Without a usable odometry line the frame has no pose at all.
  std::optional<std::string> no_pose;
  if (unreadable) {
    try {
      frame = inbox_.ReadPoses(index, files);
    } catch (const io::IoError& e) {
      no_pose = e.what();
    }
  }
  if (!no_pose && frame.timestamp <= last_timestamp_) {
    std::ostringstream why;
    why << (inbox_.frames_dir() / io::FrameStem(index)).string() << ".odom: timestamp "
        << std::setprecision(17) << frame.timestamp << " is not after the previous frame's "
        << last_timestamp_;
    no_pose = why.str();
  }
  if (no_pose) {
    state_.rejected.push_back(index);
    ++state_.next_index;
    checkpoint_->Append(nullptr, state_);
    inbox_.Reject(index, *no_pose);
    Log("serve: frame " + std::to_string(index) + " rejected, not in the trajectory: " + *no_pose);
    return;
  }
  // The graph's matches take the frame's own points (mapper/Patches).
  FrameBins bins;
  if (!unreadable && graph_run_->wants_bins() && read.prepared.loaded.ok) {
    bins = BinFrame(read.prepared.Fused(), read.prepared.isolated.keep);
  }
  const FrameResult result =
      unreadable
          ? mapper_->SkipFrame(index, frame.timestamp, frame.T_world_body_odom,
                               FallbackReason::kBadFrame, *unreadable, frame.T_world_body_truth)
          : mapper_->ProcessPrepared(frame, std::move(read.prepared), read.load_ms);
  for (const std::string& line : graph_run_->AfterFrame(*mapper_, bins, "serve")) Log(line);
  Fault("frame:processed");
  last_timestamp_ = frame.timestamp;
  const bool bad = result.status == FrameStatus::kBadFrame;
  if (bad) state_.rejected.push_back(index);
  ++state_.next_index;
  Commit(&result, bad ? result.detail : std::string());
  busy_ms_ += MsBetween(start, Clock::now());
}

void Daemon::DeclareMissing(std::size_t index, const io::InboxFrameFiles& files) {
  const std::string why = "missing: frame " + std::to_string(index) + " incomplete after " +
                          std::to_string(setup_.serve.gap_timeout_s) + " s (serve.gap_timeout_s)";
  // Its odometry line, if it came, still places it in the trajectory.
  std::optional<io::Frame> poses;
  if (files.odom) {
    try {
      poses = inbox_.ReadPoses(index, files);
      if (poses->timestamp <= last_timestamp_) poses.reset();
    } catch (const io::IoError&) {
      poses.reset();
    }
  }
  if (poses) {
    const FrameResult result =
        mapper_->SkipFrame(index, poses->timestamp, poses->T_world_body_odom,
                           FallbackReason::kMissing, why, poses->T_world_body_truth);
    // As every frame with a pose (and a restart's re-applied ones): the tracks' path goes on.
    for (const std::string& line : graph_run_->AfterFrame(*mapper_, {}, "serve")) Log(line);
    last_timestamp_ = poses->timestamp;
    state_.rejected.push_back(index);
    ++state_.next_index;
    Commit(&result, why);
    return;
  }
  state_.missing.push_back(index);
  ++state_.next_index;
  checkpoint_->Append(nullptr, state_);
  inbox_.Reject(index, why);
  Log("serve: frame " + std::to_string(index) + " " + why + "; not in the trajectory");
}

// Journal first (the frame is done once it is on disk), then the side effects a restart can
// redo: the rejected files, the snapshot, the outputs.
void Daemon::Commit(const FrameResult* result, const std::string& reject_reason) {
  checkpoint_->Append(result, state_);
  if (!reject_reason.empty()) inbox_.Reject(result->index, reject_reason);
  ++processed_;
  last_frame_time_ = UtcNow();
  std::ostringstream line;
  line << "serve: frame " << result->index << " " << StatusLine(*result);
  line << std::fixed << std::setprecision(0) << ", " << result->time.load_ms + result->time.total_ms
       << " ms, " << (waiting_ > 0 ? waiting_ - 1 : 0) << " waiting";
  Log(line.str());
  std::ostringstream writes;
  writes << std::fixed << std::setprecision(0);
  since_checkpoint_ms_ += result->time.load_ms + result->time.total_ms;
  if (SnapshotDue(setup_.serve, ++since_checkpoint_, since_checkpoint_ms_, last_snapshot_ms_)) {
    const auto start = Clock::now();
    checkpoint_->Save(*mapper_, state_, graph_run_.get());
    last_snapshot_ms_ = MsBetween(start, Clock::now());
    since_checkpoint_ = 0;
    since_checkpoint_ms_ = 0.0;
    writes << ", checkpoint " << last_snapshot_ms_ << " ms ("
           << checkpoint_->snapshot_bytes() / 1000000.0 << " MB)";
  }
  ++unwritten_frames_;
  unwritten_ms_ += result->time.load_ms + result->time.total_ms;
  if (++since_publish_ >= setup_.serve.publish_every) {
    // What the last publication cost: its hand-over here and its writing beside the frames.
    const double last_write_ms = publisher_.last_write_ms();
    const bool write = PublicationDue(setup_.serve, unwritten_frames_, unwritten_ms_,
                                      last_handover_ms_ + last_write_ms);
    const auto start = Clock::now();
    Publish(write);
    if (write) {
      last_handover_ms_ = MsBetween(start, Clock::now());
      writes << ", outputs handed to the publisher in " << last_handover_ms_ << " ms";
      if (last_write_ms > 0.0)
        writes << " (the last publication wrote for " << last_write_ms << " ms)";
    }
  }
  if (!writes.str().empty())
    Log("serve: after frame " + std::to_string(result->index) + writes.str());
  // While frames are queued, status.json at most every status_interval_s: a rewrite per frame
  // is a file created and renamed per frame, for a monitor that polls far less often.
  status_stale_ = true;
  if (!writes.str().empty() ||
      MsBetween(status_written_, Clock::now()) >= 1000.0 * setup_.serve.status_interval_s) {
    WriteStatus("running", waiting_ > 0 ? waiting_ - 1 : 0);
  }
}

void Daemon::RejectLate(const FrameFiles& files) {
  for (const auto& [index, present] : files) {
    if (index >= state_.next_index) break;
    if (Contains(state_.missing, index)) {
      inbox_.Reject(index, "arrived after frame " + std::to_string(index) +
                               " was declared missing (serve.gap_timeout_s)");
      Log("serve: frame " + std::to_string(index) + " arrived late, rejected");
    } else if (Contains(state_.rejected, index) && (present.left || present.right || present.ply)) {
      inbox_.Reject(index, "rejected (see drift.csv and the daemon's log)");
    }
  }
}

std::optional<GraphOutcome> Daemon::SolveAndLogGraph() {
  solved_gnss_ = GnssCsvSignature();  // before the fixes are read: a later change is seen
  std::optional<GraphOutcome> graph;
  try {
    graph =
        graph_run_->Solve(*mapper_, InboxFixes(), reference_unusable_,
                          static_cast<std::size_t>(std::max(setup_.serve.graph_window_frames, 0)));
  } catch (const std::invalid_argument& e) {
    Log(std::string("serve: pose graph not solved: ") + e.what());
  }
  if (!graph || !graph->solution.solved) return graph;
  const graph::PoseGraphResult& g = graph->solution;
  std::ostringstream line;
  line << "serve: pose graph over " << mapper_->results().size() << " frames";
  if (g.first_solved_frame > 0) line << " (frames " << g.first_solved_frame << "- solved)";
  if (graph->whole_for_loop_from) {
    line << " (whole: a revisit reaches frame " << *graph->whole_for_loop_from
         << ", before the window)";
  }
  line << ": " << g.fixes_used << " of " << graph->fixes << " GNSS fixes, " << g.poses_used
       << " reference matches, " << g.loops_used << " revisits used, " << std::fixed
       << std::setprecision(0) << g.solve_ms << " ms";
  Log(line.str());
  return graph;
}

void Daemon::Publish(bool write) {
  if (mapper_->results().empty()) return;
  // The pose graph over every frame so far, with what its sources found (docs/graph.md): the
  // published trajectory is its own, and so are the DEM's and the OctoMap's places (moved with
  // it, not fused again: mapper/DemWarp, dem::BatchOcTree::MovedCopy). No frame since the last
  // solve (a dry queue right after one that was not written): that solve's outcome, not a second
  // one.
  std::optional<GraphOutcome> graph =
      since_publish_ == 0 && unwritten_graph_ ? std::move(unwritten_graph_) : SolveAndLogGraph();
  since_publish_ = 0;
  unwritten_graph_.reset();
  if (!write) {
    unwritten_graph_ = std::move(graph);
    return;
  }
  unwritten_frames_ = 0;
  unwritten_ms_ = 0.0;
  published_through_ = state_.next_index;
  published_gnss_ = solved_gnss_;
  RunInfo run;
  run.sequence = setup_.inbox.string();
  // Frames per second over the frames' own processing time: the daemon idles between frames.
  run.wall_ms = ProcessingMs(mapper_->results());
  run.extra["serve"] = {{"missing_frames", state_.missing},
                        {"rejected_frames", state_.rejected},
                        {"next_frame", state_.next_index},
                        {"restart_ms", restart_ms_}};
  OutputState state(*mapper_, std::move(graph), /*move_maps=*/true);
  // The state is taken here, between frames; the files are written beside the next frames.
  publisher_.Publish(setup_.out, std::move(state), std::move(run), setup_.eval,
                     [this](const std::string& file) { Fault("publish:" + file); });
}

std::vector<io::GnssFix> Daemon::InboxFixes() {
  const fs::path path = inbox_.directory() / "gnss.csv";
  std::error_code error;
  if (!fs::exists(path, error)) return fixes_;
  try {
    fixes_ = io::ReadGnssCsv(path);
    fixes_error_.clear();
  } catch (const io::IoError& e) {
    // Being appended to: a line cut short now is whole at the next publication.
    if (e.what() != fixes_error_)
      Log(std::string("serve: ") + e.what() + " (the fixes read before are kept)");
    fixes_error_ = e.what();
  }
  return fixes_;
}

std::string Daemon::GnssCsvSignature() const {
  std::error_code error;
  const fs::path path = inbox_.directory() / "gnss.csv";
  const std::uintmax_t size = fs::file_size(path, error);
  if (error) return "";
  const auto time = fs::last_write_time(path, error);
  if (error) return "";
  return std::to_string(size) + "@" + std::to_string(time.time_since_epoch().count());
}

void Daemon::WriteStatus(const char* state, std::size_t waiting) {
  std::size_t fallbacks = 0;
  for (const FrameResult& r : mapper_->results()) {
    fallbacks += r.status == FrameStatus::kFallback || r.status == FrameStatus::kBadFrame ? 1 : 0;
  }
  const nlohmann::json status = {
      {"state", state},
      {"pid", ::getpid()},
      {"inbox", setup_.inbox.string()},
      {"last_frame", mapper_->results().empty() ? nlohmann::json(nullptr)
                                                : nlohmann::json(mapper_->results().back().index)},
      {"next_frame", state_.next_index},
      {"frames_done", mapper_->results().size()},
      {"frames_waiting", waiting},
      {"frames_per_second",
       busy_ms_ > 0.0 ? 1000.0 * static_cast<double>(processed_) / busy_ms_ : 0.0},
      {"fallbacks", fallbacks},
      {"rejected", state_.rejected.size()},
      {"missing", state_.missing},
      {"last_frame_time",
       last_frame_time_.empty() ? nlohmann::json(nullptr) : nlohmann::json(last_frame_time_)},
      {"restart_ms", restart_ms_},
      {"updated", UtcNow()}};
  // Rewritten after every frame and only for watching: not worth a flush to disk each time.
  io::WriteFileAtomically(setup_.out / "status.json", status.dump(2) + "\n", /*flush=*/false);
  status_stale_ = false;
  status_written_ = Clock::now();
}

}  // namespace rovermap::mapper
