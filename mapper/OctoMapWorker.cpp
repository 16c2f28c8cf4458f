#include "mapper/OctoMapWorker.hpp"

#include <chrono>
#include <utility>

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
                           const Eigen::Vector3d& sensor_origin_world) {
  if (!fusion_.enabled()) return;
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return !queued_.has_value(); });
  queued_ = Job{std::move(points_world), sensor_origin_world};
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

void OctoMapWorker::Loop() {
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
    fusion_.InsertFrame(job.points, job.origin);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
      last_insert_ms_ = ms;
    }
    changed_.notify_all();
  }
}

}  // namespace rovermap::mapper
