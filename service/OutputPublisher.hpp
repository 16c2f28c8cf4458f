#pragma once
// The daemon's publications on a thread of their own. Encoding dem.tif and the two PNGs is most
// of a publication and needs nothing but an OutputState, so the mapper goes on with the next
// frames meanwhile (the second core is mostly idle: the OctoMap's thread uses part of it). One
// publication at a time: the next waits for the last, so memory holds at most two states.

#include <atomic>
#include <exception>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>

#include "eval/EvalOptions.hpp"
#include "service/DriftReport.hpp"
#include "service/OutputState.hpp"
#include "terrain/TerrainCache.hpp"

namespace rovermap::mapper {

class OutputPublisher {
 public:
  OutputPublisher() = default;
  /// Waits for the publication in hand; an error it ends with is dropped (call Wait first).
  ~OutputPublisher();
  OutputPublisher(const OutputPublisher&) = delete;
  OutputPublisher& operator=(const OutputPublisher&) = delete;

  /// Writes `state` into `out_dir` (WriteOutputs) on the publisher's thread, after waiting for
  /// the previous publication. `after_file` is called on that thread.
  /// @throw what the previous publication threw (io::IoError naming the file), once.
  void Publish(std::filesystem::path out_dir, OutputState state, RunInfo run,
               eval::EvalOptions eval_options,
               std::function<void(const std::string&)> after_file = {});
  /// Waits until the last publication is on disk.
  /// @throw what it threw (io::IoError naming the file), once.
  void Wait();
  /// If the last publication has finished, joins it. Never blocks.
  /// @throw what it threw, once.
  void Poll();
  /// How long the last finished publication took to write [ms] (0 before the first).
  double last_write_ms() const { return last_write_ms_; }

 private:
  std::thread thread_;
  std::atomic<bool> finished_{false};  // the thread's last act
  std::exception_ptr error_;           // written by the thread, read after joining it
  double last_write_ms_ = 0.0;
  // The last publication's terrain layers: the next computes only the tiles that changed. Only
  // the publication thread touches it, one publication at a time.
  terrain::TerrainCache terrain_cache_;
};

}  // namespace rovermap::mapper
