// bench_replay: the mapping pipeline as `rovermap replay` runs it, on simulated sequences.
//
//   bench_replay [--frames N] [--long N] [--kitti DIR] [--no-octomap]
//
// Table 1: frames per second and the per-stage medians on the default stereo traverse (480×360)
// and on a cloud traverse (about 20k points a frame). Table 2: a long cloud traverse (default
// 500 frames): per-frame cost and resident memory over its first and last tenth, so that growth
// with the sequence's length shows. With --kitti DIR, also the real KITTI excerpt
// (datasets/kitti_stereo51). Frames are read from disk, as replay does; outputs are not written.
#include <malloc.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench/BenchUtil.hpp"
#include "config/Config.hpp"
#include "core/Stopwatch.hpp"
#include "io/Sequence.hpp"
#include "mapper/Mapper.hpp"
#include "mapper/ReadAhead.hpp"
#include "sim/Simulator.hpp"

namespace fs = std::filesystem;
using namespace rovermap;

namespace {

using Clock = std::chrono::steady_clock;
using core::MsSince;


// Resident set size now [MB] (/proc/self/statm: pages).
double RssMb() {
  std::ifstream in("/proc/self/statm");
  long pages = 0, resident = 0;
  in >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1048576.0;
}

struct FrameCost {
  double total_ms = 0.0;  // load + process
  double rss_mb = 0.0;    // after the frame
  mapper::StageTimes stages;
};

// Where the resident memory is, after some frame: the maps' own bytes, the per-frame results,
// and the rest (the frames in hand, the trees, the allocator's free lists).
struct MemorySplit {
  std::size_t frames = 0;
  double rss_mb = 0.0;
  double dem_mb = 0.0;      // ElevationMap::MemoryBytes: the tiles' layers
  double octomap_mb = 0.0;  // OcTree::memoryUsage: nodes and child arrays
  double results_mb = 0.0;  // the FrameResult per frame that replay and serve keep for the report
  double heap_used_mb = 0.0;  // mallinfo2: bytes in use in malloc's arenas (all threads)
  double heap_free_mb = 0.0;  // free in the arenas, not returned to the system
  std::size_t dem_cells = 0;
  std::size_t octomap_leaves = 0;
  double rest_mb() const { return rss_mb - dem_mb - octomap_mb - results_mb; }
};

MemorySplit SplitMemory(const mapper::Mapper& mapper) {
  constexpr double kMb = 1048576.0;
  MemorySplit m;
  m.frames = mapper.results().size();
  m.dem_mb = static_cast<double>(mapper.elevation_map().MemoryBytes()) / kMb;
  m.dem_cells = mapper.elevation_map().CellCount();
  if (const octomap::OcTree* tree = mapper.octomap().tree()) {
    m.octomap_mb = static_cast<double>(tree->memoryUsage()) / kMb;
    m.octomap_leaves = tree->getNumLeafNodes();
  }
  m.results_mb =
      static_cast<double>(mapper.results().capacity() * sizeof(mapper::FrameResult)) / kMb;
  const struct mallinfo2 heap = mallinfo2();
  m.heap_used_mb = static_cast<double>(heap.uordblks + heap.hblkhd) / kMb;
  m.heap_free_mb = static_cast<double>(heap.fordblks) / kMb;
  m.rss_mb = RssMb();
  return m;
}

// Replays `sequence` as replay does (frame k+1 read and prepared by mapper::ReadAhead while
// frame k is processed), timing every frame; `splits`, when given, gets the memory split after
// every `split_every` frames and at the end. `read_ahead` false: read, then ProcessFrame, one
// by one.
std::vector<FrameCost> Run(const fs::path& sequence, const mapper::PipelineOptions& options,
                           double* wall_ms, std::vector<MemorySplit>* splits = nullptr,
                           std::size_t split_every = 0, bool read_ahead = true) {
  io::SequenceReader reader(sequence);
  mapper::Mapper mapper(reader.info(), options);
  std::vector<FrameCost> costs;
  const auto start = Clock::now();
  auto t0 = Clock::now();
  auto record = [&](const mapper::FrameResult& r) {
    costs.push_back({MsSince(t0), RssMb(), r.time});
    if (splits != nullptr && split_every > 0 && costs.size() % split_every == 0)
      splits->push_back(SplitMemory(mapper));
    t0 = Clock::now();
  };
  if (read_ahead) {
    mapper::ReadAhead ahead(&reader, &mapper);
    mapper::ReadAhead::Item item;
    while (ahead.Next(&item)) {
      if (!item.frame) throw std::runtime_error(item.error);  // simulated: never unreadable
      record(mapper.ProcessPrepared(*item.frame, std::move(item.prepared), item.load_ms));
    }
  } else {
    io::Frame frame;
    for (;;) {
      const auto load_start = Clock::now();
      if (!reader.Next(&frame)) break;
      record(mapper.ProcessFrame(frame, MsSince(load_start)));
    }
  }
  *wall_ms = MsSince(start);
  if (splits != nullptr && (splits->empty() || splits->back().frames != costs.size()))
    splits->push_back(SplitMemory(mapper));
  return costs;
}

template <typename F>
double MedianOf(const std::vector<FrameCost>& costs, std::size_t from, std::size_t to, F&& f) {
  std::vector<double> v;
  for (std::size_t k = from; k < to && k < costs.size(); ++k) v.push_back(f(costs[k]));
  return bench::Median(v);
}

void PrintRow(const std::string& name, const std::vector<FrameCost>& c, double wall_ms) {
  const std::size_t n = c.size();
  const auto median = [&](auto f) { return MedianOf(c, 1, n, f); };  // frame 0 registers nothing
  std::printf("%-34s %6zu %7.2f %7.1f %7.1f %7.1f %8.1f %7.1f %8.1f %8.1f\n", name.c_str(), n,
              1000.0 * static_cast<double>(n) / wall_ms,
              median([](const FrameCost& f) { return f.stages.load_ms; }),
              median([](const FrameCost& f) { return f.stages.stereo_ms; }),
              median([](const FrameCost& f) { return f.stages.prepare_ms; }),
              median([](const FrameCost& f) { return f.stages.register_ms; }),
              median([](const FrameCost& f) { return f.stages.fuse_dem_ms; }),
              median([](const FrameCost& f) { return f.stages.fuse_octomap_ms; }),
              median([](const FrameCost& f) { return f.total_ms; }));
}

fs::path Simulate(const fs::path& dir, const sim::SimOptions& o) {
  sim::Simulator(o).WriteSequence(dir, {});
  return dir;
}

}  // namespace

int main(int argc, char** argv) {
  bench::WaitPassivelyUnlessTold(argv);
  int frames = 30;
  int long_frames = 500;
  std::string kitti;
  bool octomap = true;
  bool long_only = false;    // skip the short sequences
  bool exact_poses = false;  // the long loop without odometry errors, increments from odometry
  int split_every = 250;     // memory split every N frames of the long loop (a lap)
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--frames")
        frames = std::stoi(bench::OptionValue(argc, argv, &i));
      else if (arg == "--long")
        long_frames = std::stoi(bench::OptionValue(argc, argv, &i));
      else if (arg == "--kitti")
        kitti = bench::OptionValue(argc, argv, &i);
      else if (arg == "--no-octomap")
        octomap = false;
      else if (arg == "--long-only")
        long_only = true;
      else if (arg == "--exact-poses")
        exact_poses = true;
      else if (arg == "--split-every")
        split_every = std::stoi(bench::OptionValue(argc, argv, &i));
      else
        throw std::invalid_argument("unknown option " + arg);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr,
                 "bench_replay: %s\nusage: bench_replay [--frames N] [--long N] "
                 "[--kitti DIR] [--no-octomap] [--long-only] [--exact-poses] "
                 "[--split-every N]\n",
                 e.what());
    return 2;
  }
  const config::Config defaults;
  mapper::PipelineOptions options{defaults.mapper, defaults.registration, defaults.stereo,
                                  defaults.dem, defaults.octomap, defaults.terrain};
  options.octomap.enabled = octomap;
  const fs::path scratch =
      fs::temp_directory_path() / ("rovermap_bench_replay." + std::to_string(getpid()));
  fs::create_directories(scratch);
  std::printf("# bench_replay: defaults, OctoMap %s; load average %s\n", octomap ? "on" : "off",
              bench::LoadAverage().c_str());
  std::printf(
      "# per-frame medians [ms], frame 0 excluded; fps = frames / wall time (reading "
      "included)\n");
  std::printf("%-34s %6s %7s %7s %7s %7s %8s %7s %8s %8s\n", "sequence", "frames", "fps", "load",
              "stereo", "prep", "register", "dem", "octomap", "frame");

  sim::SimOptions stereo;
  stereo.frames = frames;
  double wall = 0.0;
  std::vector<FrameCost> costs;
  sim::SimOptions cloud = stereo;
  cloud.sensor = sim::SensorKind::kCloud;
  cloud.cloud_stride_px = 3;  // about 19k points a frame
  if (!long_only) {
    const fs::path stereo_dir = Simulate(scratch / "stereo", stereo);
    costs = Run(stereo_dir, options, &wall);
    PrintRow("sim stereo 480x360", costs, wall);
    costs = Run(stereo_dir, options, &wall, nullptr, 0, /*read_ahead=*/false);
    PrintRow("  the same, frames one by one", costs, wall);

    const fs::path cloud_dir = Simulate(scratch / "cloud", cloud);
    costs = Run(cloud_dir, options, &wall);
    PrintRow("sim cloud (stride 3)", costs, wall);
    costs = Run(cloud_dir, options, &wall, nullptr, 0, /*read_ahead=*/false);
    PrintRow("  the same, frames one by one", costs, wall);

    if (!kitti.empty()) {
      costs = Run(kitti, options, &wall);
      PrintRow("KITTI stereo 1226x370", costs, wall);
    }
  }

  // A long traverse: does a frame cost more, or the process hold more, as the sequence grows?
  sim::SimOptions longer = cloud;
  longer.frames = long_frames;
  longer.path = sim::PathShape::kLoop;
  longer.terrain_size_m = 60.0;
  std::vector<MemorySplit> splits;
  if (exact_poses) {
    // Odometry without error and every increment taken from it: each lap maps the first
    // lap's ground, so what still grows is the maps' own.
    longer.odom_scale_error = longer.odom_slip_mean = longer.odom_slip_sigma = 0.0;
    longer.heading_bias_deg_s = longer.heading_random_walk_deg_rt_s = 0.0;
    options.mapper.min_inlier_ratio = 1.0;
  }
  costs = Run(Simulate(scratch / "long", longer), options, &wall, &splits,
              static_cast<std::size_t>(split_every));
  PrintRow("sim cloud, " + std::to_string(long_frames) + " frames (loop)", costs, wall);
  const std::size_t n = costs.size(), tenth = std::max<std::size_t>(1, n / 10);
  const auto frame_ms = [](const FrameCost& f) { return f.total_ms; };
  std::printf("\n%-34s %12s %12s\n", "long cloud traverse", "first 10 %", "last 10 %");
  std::printf("%-34s %12.1f %12.1f\n", "frame [ms], median", MedianOf(costs, 1, tenth, frame_ms),
              MedianOf(costs, n - tenth, n, frame_ms));
  const auto stage = [&](const char* name, double mapper::StageTimes::*field) {
    const auto f = [field](const FrameCost& c) { return c.stages.*field; };
    std::printf("%-34s %12.1f %12.1f\n", name, MedianOf(costs, 1, tenth, f),
                MedianOf(costs, n - tenth, n, f));
  };
  stage("  register [ms]", &mapper::StageTimes::register_ms);
  stage("  prepare [ms]", &mapper::StageTimes::prepare_ms);
  stage("  fuse DEM [ms]", &mapper::StageTimes::fuse_dem_ms);
  stage("  hand to the OctoMap [ms]", &mapper::StageTimes::fuse_octomap_ms);
  std::printf("%-34s %12.1f %12.1f\n", "resident memory [MB], at the end", costs[tenth - 1].rss_mb,
              costs.back().rss_mb);
  std::printf("\n%-12s %9s %9s %9s %9s %9s %9s %9s %10s %12s\n", "after frame", "RSS MB",
              "DEM MB", "OcTree MB", "results", "rest MB", "heap used", "heap free", "DEM cells",
              "OcTree leaves");
  for (const MemorySplit& m : splits) {
    std::printf("%-12zu %9.1f %9.1f %9.1f %9.1f %9.1f %9.1f %9.1f %10zu %12zu\n", m.frames,
                m.rss_mb, m.dem_mb, m.octomap_mb, m.results_mb, m.rest_mb(), m.heap_used_mb,
                m.heap_free_mb, m.dem_cells, m.octomap_leaves);
  }
  std::printf("# load average after: %s\n", bench::LoadAverage().c_str());
  fs::remove_all(scratch);
  return 0;
}
