#include "service/OutputPublisher.hpp"

#include <chrono>
#include <utility>

#include "core/Stopwatch.hpp"
#include "service/Outputs.hpp"

namespace rovermap::mapper {

OutputPublisher::~OutputPublisher() {
  if (thread_.joinable()) thread_.join();
}

void OutputPublisher::Publish(std::filesystem::path out_dir, OutputState state, RunInfo run,
                              eval::EvalOptions eval_options,
                              std::function<void(const std::string&)> after_file) {
  Wait();
  finished_ = false;
  thread_ = std::thread([this, out_dir = std::move(out_dir), state = std::move(state),
                         run = std::move(run), eval_options = std::move(eval_options),
                         after_file = std::move(after_file)]() mutable {
    const auto start = std::chrono::steady_clock::now();
    try {
      MoveDemWithGraph(&state);  // serve's DEM onto the graph's poses, here beside the mapper
      WriteOutputs(out_dir, state, std::move(run), eval_options, after_file, &terrain_cache_);
    } catch (...) {
      error_ = std::current_exception();
    }
    last_write_ms_ = core::MsSince(start);
    finished_ = true;
  });
}

void OutputPublisher::Poll() {
  if (thread_.joinable() && finished_.load()) Wait();
}

void OutputPublisher::Wait() {
  if (thread_.joinable()) thread_.join();
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

}  // namespace rovermap::mapper
