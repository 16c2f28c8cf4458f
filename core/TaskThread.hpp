#pragma once
// One thread kept for a run, which runs the tasks handed to it in turn.

#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <thread>
#include <type_traits>
#include <utility>

namespace rovermap::core {

/// Runs the tasks given to Submit one after another, in order, on a thread of its own that lives
/// as long as this object. Why not std::async per task: a thread started per frame enters
/// OpenMP's parallel regions with a team of its own, which libgomp starts anew each time, and
/// gets a malloc arena whose large blocks are mapped and faulted in again every frame
/// (docs/benchmarks.md, "Serve"). The destructor runs the tasks still queued, then joins.
class TaskThread {
 public:
  TaskThread() : thread_([this] { Loop(); }) {}
  TaskThread(const TaskThread&) = delete;
  TaskThread& operator=(const TaskThread&) = delete;
  ~TaskThread() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_one();
    thread_.join();
  }

  /// Queues `task`; its result (or what it threw) comes through the future.
  template <class F>
  std::future<std::invoke_result_t<F>> Submit(F task) {
    using Result = std::invoke_result_t<F>;
    // std::function needs a copyable callable: the packaged task is shared.
    auto packaged = std::make_shared<std::packaged_task<Result()>>(std::move(task));
    std::future<Result> result = packaged->get_future();
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      tasks_.emplace_back([packaged] { (*packaged)(); });
    }
    wake_.notify_one();
    return result;
  }

 private:
  void Loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [this] { return stop_ || !tasks_.empty(); });
      if (tasks_.empty()) return;  // stopping, nothing left to run
      std::function<void()> task = std::move(tasks_.front());
      tasks_.pop_front();
      lock.unlock();
      task();  // a packaged task: what it throws goes into its future
      lock.lock();
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> tasks_;  // guarded by mutex_
  bool stop_ = false;                        // guarded by mutex_
  std::thread thread_;                       // last: starts once the rest is built
};

}  // namespace rovermap::core
