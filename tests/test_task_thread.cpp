// core::TaskThread: the tasks run in order, all on one thread that outlives them, their results
// and exceptions come through their futures, and the queue is drained before it stops.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/TaskThread.hpp"

using rovermap::core::TaskThread;

TEST(TaskThread, RunsTheTasksInOrderOnOneThreadNotTheCallers) {
  TaskThread worker;
  std::vector<int> order;  // written by the worker only
  std::vector<std::future<std::thread::id>> ids;
  for (int k = 0; k < 20; ++k) {
    ids.push_back(worker.Submit([k, &order] {
      order.push_back(k);
      return std::this_thread::get_id();
    }));
  }
  const std::thread::id first = ids.front().get();
  EXPECT_NE(first, std::this_thread::get_id());
  for (std::size_t k = 1; k < ids.size(); ++k) EXPECT_EQ(ids[k].get(), first) << k;
  std::vector<int> expected(20);
  for (int k = 0; k < 20; ++k) expected[static_cast<std::size_t>(k)] = k;
  EXPECT_EQ(order, expected);
}

TEST(TaskThread, ResultsAndExceptionsComeThroughTheFutures) {
  TaskThread worker;
  std::future<std::string> ok = worker.Submit([] { return std::string("frame 7"); });
  std::future<int> bad = worker.Submit([]() -> int { throw std::runtime_error("unreadable"); });
  std::future<int> after = worker.Submit([] { return 42; });  // the thread survives a throw
  EXPECT_EQ(ok.get(), "frame 7");
  EXPECT_THROW(
      {
        try {
          bad.get();
        } catch (const std::runtime_error& e) {
          EXPECT_STREQ(e.what(), "unreadable");
          throw;
        }
      },
      std::runtime_error);
  EXPECT_EQ(after.get(), 42);
}

TEST(TaskThread, TheDestructorRunsWhatIsQueuedThenStops) {
  std::atomic<int> done{0};
  {
    TaskThread worker;
    for (int k = 0; k < 5; ++k) {
      worker.Submit([&done] {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        ++done;
      });  // futures dropped: nobody waits for them but the destructor
    }
  }
  EXPECT_EQ(done.load(), 5);
}
