// bench_publish: what `rovermap serve` adds to the frames' own work, output by output.
//
//   bench_publish [--frames N ...] [--runs R]
//
// After N frames of the simulated cloud traverse (the same frames as bench_replay's), the
// median time of each file WriteOutputs publishes (in its order) and of a checkpoint snapshot,
// over R repetitions: serve pays one publication every serve.publish_every frames and one
// snapshot every serve.checkpoint_every frames.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bench/BenchUtil.hpp"
#include "config/Config.hpp"
#include "core/Stopwatch.hpp"
#include "io/Sequence.hpp"
#include "mapper/Mapper.hpp"
#include "service/Checkpoint.hpp"
#include "service/Outputs.hpp"
#include "sim/Simulator.hpp"

namespace fs = std::filesystem;
using namespace rovermap;

namespace {

using Clock = std::chrono::steady_clock;
using rovermap::core::MsBetween;

}  // namespace

int main(int argc, char** argv) {
  bench::WaitPassivelyUnlessTold(argv);
  std::vector<int> frame_counts;
  int runs = 9;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--frames")
        frame_counts.push_back(std::stoi(bench::OptionValue(argc, argv, &i)));
      else if (arg == "--runs")
        runs = bench::ParseRuns(bench::OptionValue(argc, argv, &i));
      else
        throw std::invalid_argument("unknown option " + arg);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_publish: %s\nusage: bench_publish [--frames N ...] [--runs R]\n",
                 e.what());
    return 2;
  }
  if (frame_counts.empty()) frame_counts = {30, 200};
  const config::Config defaults;
  const mapper::PipelineOptions options{defaults.mapper, defaults.registration, defaults.stereo,
                                        defaults.dem, defaults.octomap, defaults.terrain};
  const fs::path scratch =
      fs::temp_directory_path() / ("rovermap_bench_publish." + std::to_string(getpid()));
  fs::create_directories(scratch / "out");
  std::printf(
      "# bench_publish: defaults, sim cloud loop (stride 3); medians of %d runs [ms]; "
      "load average %s\n",
      runs, bench::LoadAverage().c_str());

  for (const int n : frame_counts) {
    sim::SimOptions cloud;
    cloud.sensor = sim::SensorKind::kCloud;
    cloud.cloud_stride_px = 3;
    cloud.frames = n;
    cloud.path = sim::PathShape::kLoop;
    cloud.terrain_size_m = 60.0;
    const fs::path sequence = scratch / ("cloud" + std::to_string(n));
    sim::Simulator(cloud).WriteSequence(sequence, {});
    io::SequenceReader reader(sequence);
    mapper::Mapper mapper(reader.info(), options);
    io::Frame frame;
    std::vector<double> frame_ms;
    while (true) {
      const auto t0 = Clock::now();
      if (!reader.Next(&frame)) break;
      mapper.ProcessFrame(frame, 0.0);
      frame_ms.push_back(MsBetween(t0, Clock::now()));
    }

    // Each file's time: from the previous file's end (the call's start for the first).
    std::vector<std::string> order;
    std::map<std::string, std::vector<double>> times;
    mapper::Checkpoint checkpoint(scratch / "checkpoint", "bench");
    for (int r = 0; r < runs; ++r) {
      auto last = Clock::now();
      mapper::WriteOutputs(scratch / "out", mapper, {}, defaults.eval,
                           [&](const std::string& file) {
                             const auto now = Clock::now();
                             if (r == 0) order.push_back(file);
                             times[file].push_back(MsBetween(last, now));
                             last = now;
                           });
      const auto t0 = Clock::now();
      checkpoint.Save(mapper, {});
      times["checkpoint"].push_back(MsBetween(t0, Clock::now()));
    }
    order.push_back("checkpoint");

    double publication = 0.0;
    std::printf("\n%-26s %10s   (%d frames; frame median %.1f ms; snapshot %.1f MB)\n", "output",
                "median ms", n, bench::Median(frame_ms),
                static_cast<double>(checkpoint.snapshot_bytes()) / 1e6);
    for (const std::string& name : order) {
      const double ms = bench::Median(times[name]);
      if (name != "checkpoint") publication += ms;
      std::printf("%-26s %10.1f\n", name.c_str(), ms);
    }
    std::printf("%-26s %10.1f\n", "publication (sum)", publication);
  }
  std::printf("# load average after: %s\n", bench::LoadAverage().c_str());
  fs::remove_all(scratch);
  return 0;
}
