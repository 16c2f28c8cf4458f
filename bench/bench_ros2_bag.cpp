// bench_ros2_bag: reading a large ROS 2 bag against the same frames from a sequence directory
// (and, in a build with ROS 1 bag support, a ROS 1 bag).
//
//   bench_ros2_bag [--repeat N] [--replay-frames M] [--work DIR]
//
// Builds, under DIR (default a scratch folder, removed at the end), a sequence directory of
// KITTI's excerpt (datasets/kitti_stereo51, 51 frames of 1226×370) repeated N times (default 22:
// 1122 frames) with shifted stamps, and from it an MCAP bag of raw mono8 images (uncompressed
// chunks, about 1 GB at N = 22), an MCAP bag of PNG CompressedImages (zstd chunks), a rosbag2
// SQLite bag of raw images and (ROVERMAP_WITH_ROSBAG) a ROS 1 bag of raw images. For each
// source: the time to open it, to its first frame, and to read every frame (FrameSource::Next,
// images decoded); then the mapper's frames per second over the first M frames (default 20) as
// replay runs them (mapper::ReadAhead, outputs not written).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bench/BenchUtil.hpp"
#include "config/Config.hpp"
#include "io/Ros2Bag.hpp"
#include "io/Sequence.hpp"
#include "mapper/Mapper.hpp"
#include "mapper/ReadAhead.hpp"
#include "tests/support/Ros2BagWriting.hpp"
#ifdef ROVERMAP_WITH_ROSBAG
#include "io/BagSource.hpp"
#include "tests/support/BagWriting.hpp"
#endif

namespace fs = std::filesystem;
using namespace rovermap;

namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// KITTI's excerpt `repeat` times in one sequence directory: the PNGs copied, the stamps and
// poses of repeat r shifted by r times the excerpt's duration plus a frame.
fs::path RepeatedSequence(const fs::path& kitti, int repeat, const fs::path& out) {
  fs::create_directories(out / "frames");
  fs::copy_file(kitti / "sequence.yaml", out / "sequence.yaml");
  const io::SequenceReader reader(kitti);
  const std::size_t n = reader.frame_count();
  const double period = reader.odometry().back().timestamp + 0.1;
  for (const char* tum : {"odometry.tum", "groundtruth.tum"}) {
    std::ofstream copy(out / tum);
    std::ifstream in(kitti / tum);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);)
      if (!line.empty() && line[0] != '#') lines.push_back(line);
    for (int r = 0; r < repeat; ++r) {
      for (const std::string& line : lines) {
        const std::size_t space = line.find(' ');
        char stamp[32];
        std::snprintf(stamp, sizeof(stamp), "%.9f", std::stod(line.substr(0, space)) + r * period);
        copy << stamp << line.substr(space) << "\n";
      }
    }
  }
  for (int r = 0; r < repeat; ++r) {
    for (std::size_t k = 0; k < n; ++k) {
      char from[32];
      char to[32];
      std::snprintf(from, sizeof(from), "%06zu", k);
      std::snprintf(to, sizeof(to), "%06zu", r * n + k);
      for (const char* side : {".left.png", ".right.png"}) {
        fs::copy_file(kitti / "frames" / (from + std::string(side)),
                      out / "frames" / (to + std::string(side)));
      }
    }
  }
  return out;
}

double MegaBytes(const fs::path& path) {
  if (!fs::is_directory(path)) return static_cast<double>(fs::file_size(path)) / 1e6;
  std::uintmax_t total = 0;
  for (const auto& e : fs::recursive_directory_iterator(path))
    if (e.is_regular_file()) total += e.file_size();
  return static_cast<double>(total) / 1e6;
}

struct Source {
  std::string name;
  fs::path path;
  std::function<std::unique_ptr<io::FrameSource>()> open;
};

void ReadAll(const Source& s) {
  const Clock::time_point start = Clock::now();
  std::unique_ptr<io::FrameSource> source = s.open();
  const double open_s = SecondsSince(start);
  io::Frame frame;
  source->Next(&frame);
  const double first_s = SecondsSince(start);
  std::size_t frames = 1;
  while (source->Next(&frame)) ++frames;
  const double all_s = SecondsSince(start) - first_s;
  std::printf("| %s | %.0f | %.3f | %.3f | %zu | %.1f |\n", s.name.c_str(), MegaBytes(s.path),
              open_s, first_s, frames, static_cast<double>(frames - 1) / all_s);
}

void Replay(const Source& s, std::size_t frames) {
  std::unique_ptr<io::FrameSource> source = s.open();
  const config::Config c;
  mapper::Mapper m(source->info(),
                   {c.mapper, c.registration, c.stereo, c.dem, c.octomap, c.terrain});
  const Clock::time_point start = Clock::now();
  std::size_t done = 0;
  {
    mapper::ReadAhead ahead(source.get(), &m);
    mapper::ReadAhead::Item item;
    while (done < frames && ahead.Next(&item)) {
      if (item.frame) m.ProcessPrepared(*item.frame, std::move(item.prepared), item.load_ms);
      ++done;
    }
  }
  std::printf("| %s | %zu | %.2f |\n", s.name.c_str(), done,
              static_cast<double>(done) / SecondsSince(start));
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 22;
  std::size_t replay_frames = 20;
  fs::path work;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--repeat") {
      repeat = std::stoi(bench::OptionValue(argc, argv, &i));
    } else if (arg == "--replay-frames") {
      replay_frames = std::stoul(bench::OptionValue(argc, argv, &i));
    } else if (arg == "--work") {
      work = bench::OptionValue(argc, argv, &i);
    } else {
      std::fprintf(stderr, "usage: bench_ros2_bag [--repeat N] [--replay-frames M] [--work DIR]\n");
      return 2;
    }
  }
  const bool scratch = work.empty();
  if (scratch) work = fs::temp_directory_path() / ("bench_ros2_bag." + std::to_string(getpid()));
  fs::remove_all(work);
  fs::create_directories(work);

  const Clock::time_point build = Clock::now();
  const fs::path sequence =
      RepeatedSequence(fs::path(ROVERMAP_DATASETS_DIR) / "kitti_stereo51", repeat, work / "seq");
  testing::Ros2Recording raw;
  raw.mcap.compression = "";
  raw.mcap.chunk_bytes = 4 << 20;
  const fs::path raw_mcap = testing::WriteSequenceRos2Bag(sequence, work / "raw.mcap", raw);
  testing::Ros2Recording png;
  png.encodings = {"png"};
  png.mcap.chunk_bytes = 4 << 20;
  const fs::path png_mcap = testing::WriteSequenceRos2Bag(sequence, work / "png.mcap", png);
  const fs::path db3 = testing::WriteSequenceRos2Bag(sequence, work / "raw.db3", raw);
#ifdef ROVERMAP_WITH_ROSBAG
  testing::BagRecording ros1_how;
  ros1_how.groundtruth_topic = "/groundtruth";
  const fs::path ros1 = testing::WriteSequenceBag(sequence, work / "raw.bag", ros1_how);
#endif
  std::fprintf(stderr, "bench_ros2_bag: inputs written in %.0f s\n", SecondsSince(build));

  io::BagOptions options;
  options.T_body_sensor_from_tf_static = true;
  options.groundtruth_topic = "/groundtruth";
  auto bag = [&](const fs::path& p) {
    return [p, options] {
      return std::unique_ptr<io::FrameSource>(std::make_unique<io::Ros2BagSource>(p, options));
    };
  };
  std::vector<Source> sources = {
      {"sequence directory (PNG files)", sequence,
       [&] {
         return std::unique_ptr<io::FrameSource>(std::make_unique<io::SequenceReader>(sequence));
       }},
      {"MCAP, raw mono8, uncompressed chunks", raw_mcap, bag(raw_mcap)},
      {"MCAP, PNG CompressedImage, zstd chunks", png_mcap, bag(png_mcap)},
      {"rosbag2 SQLite, raw mono8", db3, bag(db3)},
  };
#ifdef ROVERMAP_WITH_ROSBAG
  io::BagOptions ros1_options = options;
  sources.push_back({"ROS 1 bag, raw mono8", ros1, [ros1, ros1_options] {
                       return std::unique_ptr<io::FrameSource>(
                           std::make_unique<io::BagSource>(ros1, ros1_options));
                     }});
#endif

  std::printf("KITTI excerpt x %d: %d frames of 1226x370 stereo (load average %s)\n\n", repeat,
              repeat * 51, bench::LoadAverage().c_str());
  std::printf(
      "| source | size [MB] | open [s] | to first frame [s] | frames | read [frames/s] |\n");
  std::printf("| --- | ---: | ---: | ---: | ---: | ---: |\n");
  for (const Source& s : sources) ReadAll(s);
  std::printf("\nThe mapper over the first %zu frames (replay's loop, outputs not written):\n\n",
              replay_frames);
  std::printf("| source | frames | replay [frames/s] |\n| --- | ---: | ---: |\n");
  for (const Source& s : sources) Replay(s, replay_frames);
  if (scratch) fs::remove_all(work);
  return 0;
}
