#include "mapper/OctoMapWorker.hpp"

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <chrono>
#include <utility>

#include "core/Stopwatch.hpp"
#include "dem/OcTreeBytes.hpp"

namespace rovermap::mapper {

OctoMapWorker::OctoMapWorker(const dem::OctoMapOptions& options)
    : fusion_(options), thread_([this] { Loop(); }) {}

OctoMapWorker::~OctoMapWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void OctoMapWorker::Insert(std::vector<Eigen::Vector3d> points_world,
                           const Eigen::Vector3d& sensor_origin_world, std::uint32_t frame) {
  if (!fusion_.enabled()) return;
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return !queued_.has_value(); });
  queued_ = Job{std::move(points_world), sensor_origin_world, frame, {}};
  changed_.notify_all();
}

const dem::OctoMapFusion& OctoMapWorker::Fusion() const {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return !queued_.has_value() && !busy_; });
  return fusion_;
}

dem::OctoMapFusion& OctoMapWorker::MutableFusion() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return !queued_.has_value() && !busy_; });
  return fusion_;
}

double OctoMapWorker::last_insert_ms() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_insert_ms_;
}

std::shared_future<std::optional<OctoMapWorker::TreeBytes>> OctoMapWorker::SerialiseWhenQueuedIn(
    bool with_ot, std::shared_ptr<const Corrections> corrections) const {
  std::promise<std::optional<TreeBytes>> promise;
  std::shared_future<std::optional<TreeBytes>> bytes = promise.get_future().share();
  if (!fusion_.enabled()) {
    promise.set_value(std::nullopt);
    return bytes;
  }
  std::promise<std::pair<std::shared_ptr<dem::MovedVoxels>, double>> moved;
  if (corrections) {
    bytes = std::async(std::launch::deferred, [voxels = moved.get_future(), with_ot]() mutable {
              auto [moved_voxels, read_ms] = voxels.get();
              const auto start = std::chrono::steady_clock::now();
              TreeBytes out;
              dem::OcTreeMoveStats stats;
              const std::unique_ptr<dem::BatchOcTree> tree =
                  dem::BatchOcTree::Build(std::move(*moved_voxels), &stats);
              moved_voxels.reset();
              out.moved = stats;
              out.move_ms = read_ms + core::MsSince(start);
              out.bt = dem::BinaryOcTreeBytes(*tree);
              if (with_ot) out.ot = dem::FullOcTreeBytes(*tree);
              return std::optional<TreeBytes>(std::move(out));
            }).share();
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // After the frame still queued, or as a job of its own after the one being inserted.
    if (!queued_) queued_ = Job{{}, Eigen::Vector3d::Zero(), 0, {}};
    queued_->serialise.push_back(
        {with_ot, std::move(corrections), std::move(promise), std::move(moved)});
  }
  changed_.notify_all();
  return bytes;
}

void OctoMapWorker::Serialise(std::vector<Job::Request>* requests) const {
  for (Job::Request& request : *requests) {
    try {
      if (request.corrections) {
        const auto start = std::chrono::steady_clock::now();
        auto voxels = std::make_shared<dem::MovedVoxels>(
            fusion_.tree()->MoveVoxels(dem::BatchOcTree::CorrectionsByFrame(*request.corrections)));
        request.moved.set_value({std::move(voxels), core::MsSince(start)});
        continue;
      }
      TreeBytes bytes;
      bytes.bt = dem::BinaryOcTreeBytes(*fusion_.tree());
      if (request.with_ot) bytes.ot = dem::FullOcTreeBytes(*fusion_.tree());
      request.promise.set_value(std::move(bytes));
    } catch (...) {  // std::bad_alloc: the writer's get() rethrows it
      if (request.corrections) {
        request.moved.set_exception(std::current_exception());
      } else {
        request.promise.set_exception(std::current_exception());
      }
    }
  }
}

namespace {

// glibc keeps the memory the threads free in their arenas; over a long traverse the OcTree's
// many small allocations and the frames' buffers leave it fragmented, and the resident memory
// grew with it. Handing it back every 25 insertions keeps a long loop's resident memory flat
// after the first lap at no per-frame cost (docs/benchmarks.md, "Serve"); after every insertion
// the DEM fusion paid for the pages faulted back in (docs/benchmarks.md, "Figures behind the frame
// pipeline's code").
constexpr long kTrimEveryInsertions = 25;

void ReturnFreedMemory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

}  // namespace

void OctoMapWorker::Loop() {
  long insertions = 0;
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this] { return stop_ || queued_.has_value(); });
      if (!queued_) return;  // stopping with nothing left
      job = std::move(*queued_);
      queued_.reset();
      busy_ = true;
    }
    changed_.notify_all();  // a producer may queue the next frame meanwhile
    const auto start = std::chrono::steady_clock::now();
    if (!job.points.empty()) fusion_.InsertFrame(job.points, job.origin, job.frame);
    const double ms = core::MsSince(start);
    Serialise(&job.serialise);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
      if (!job.points.empty()) last_insert_ms_ = ms;
    }
    changed_.notify_all();
    if (!job.points.empty() && ++insertions % kTrimEveryInsertions == 0) {
      job.points = {};  // this frame's buffer goes back too
      ReturnFreedMemory();
    }
  }
}

}  // namespace rovermap::mapper
