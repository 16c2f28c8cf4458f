// `rovermap import RECORDING --out SEQ`: a recording (a ROS bag) as a sequence directory
// (docs/design.md §4), written into a temporary sibling and renamed into place, so that a failure
// leaves no half-written SEQ.
#include <stdlib.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/Commands.hpp"
#include "config/Config.hpp"
#include "io/FileUtil.hpp"
#include "io/FrameSource.hpp"
#include "io/IoError.hpp"
#include "io/Sequence.hpp"
#include "io/Tum.hpp"
#include "mapper/FrameLoader.hpp"

namespace rovermap::apps {
namespace {

namespace fs = std::filesystem;

// A new empty directory beside `out`, named after it with a leading dot.
fs::path MakeSiblingDirectory(const fs::path& out, const std::string& kind) {
  fs::path parent = out.parent_path();
  if (parent.empty()) parent = ".";
  std::error_code error;
  fs::create_directories(parent, error);
  if (error) throw io::IoError(parent.string() + ": cannot create (" + error.message() + ")");
  std::string name = (parent / ("." + out.filename().string() + "." + kind + "-XXXXXX")).string();
  if (::mkdtemp(name.data()) == nullptr) {
    throw io::IoError(out.string() + ": cannot create a temporary directory beside it (" +
                      std::strerror(errno) + ")");
  }
  return name;
}

// The frames of `source` into `dir`; unreadable ones are left out (the rest renumbered).
// @return how many were left out.
std::size_t WriteSequence(io::FrameSource* source, const fs::path& dir,
                          std::size_t* dropped_nonfinite) {
  std::error_code error;
  fs::create_directories(dir / "frames", error);
  if (error) throw io::IoError((dir / "frames").string() + ": cannot create: " + error.message());
  io::SequenceInfo info = source->info();
  std::vector<io::StampedPose> odometry;
  std::vector<io::StampedPose> truth;
  std::size_t unreadable = 0;
  const bool tty = isatty(2) != 0;
  for (;;) {
    io::Frame frame;
    try {
      if (!source->Next(&frame)) break;
    } catch (const io::IoError& e) {
      std::cerr << (tty ? "\n" : "") << "import: frame left out: " << e.what() << "\n";
      ++unreadable;
      continue;
    }
    // A sequence's PLY holds the finite points (docs/design.md §4); the rest are counted.
    *dropped_nonfinite += mapper::DropNonFinite(&frame.cloud);
    io::WriteFrameData(dir / "frames" / io::FrameStem(odometry.size()), info, frame);
    odometry.push_back(source->odometry()[frame.index]);
    if (source->has_groundtruth()) truth.push_back(source->groundtruth()[frame.index]);
    if (tty || source->next_index() == source->frame_count()) {
      std::cerr << (tty ? "\r" : "") << "import: frame " << source->next_index() << "/"
                << source->frame_count() << (tty ? "" : "\n") << std::flush;
    }
  }
  if (tty) std::cerr << "\n";
  if (odometry.empty()) {
    throw io::IoError(info.directory.string() + ": no frame could be read");
  }
  const double span = odometry.back().timestamp - odometry.front().timestamp;
  // sequence.yaml needs a rate > 0; a single frame has none of its own.
  info.frame_rate_hz = odometry.size() > 1 && span > 0.0
                           ? static_cast<double>(odometry.size() - 1) / span
                           : (info.frame_rate_hz > 0.0 ? info.frame_rate_hz : 1.0);
  io::WriteSequenceYaml(dir, info,
                        "Imported by rovermap import from " + info.directory.filename().string() +
                            ": docs/design.md section 4.");
  io::WriteTum(dir / "odometry.tum", odometry);
  if (!truth.empty()) io::WriteTum(dir / "groundtruth.tum", truth);
  if (!source->gnss().empty()) io::WriteGnssCsv(dir / "gnss.csv", source->gnss());
  io::SyncDirectory(dir);
  return unreadable;
}

}  // namespace

CLI::App* AddImportCommand(CLI::App* app, ImportArgs* args) {
  CLI::App* cmd = app->add_subcommand(
      "import",
      "Write a recording (a ROS 1 or ROS 2 bag; options under bag. in the config) as a "
      "sequence directory");
  cmd->add_option("recording", args->recording,
                  "ROS 1 bag (.bag), ROS 2 bag (rosbag2 directory, .mcap or .db3) or sequence "
                  "directory")
      ->required();
  cmd->add_option("--out", args->out, "Sequence directory to write (created)")->required();
  cmd->add_flag("--force", args->force, "Replace a non-empty SEQ");
  AddConfigOptions(cmd, &args->config);
  cmd->footer(
      "Writes sequence.yaml, frames/, odometry.tum, groundtruth.tum (when the recording has\n"
      "ground truth) and gnss.csv (NavSatFix fixes) into a temporary directory beside SEQ, then\n"
      "renames it to SEQ: a failure\n"
      "leaves no SEQ. Prints a JSON summary on stdout; progress on stderr.\n"
      "Exit status: 0 written, 1 bad recording or cannot write, 2 usage or config error.\n");
  return cmd;
}

int RunImport(const ImportArgs& args) {
  const config::Config cfg = LoadConfigArgs(args.config);
  fs::path out(args.out);
  if (!out.has_filename()) out = out.parent_path();  // "seq/": its sibling is beside "seq"
  CheckOutputDirectory(out, args.force, "replace it");
  const std::unique_ptr<io::FrameSource> source = OpenRecording(args.recording, cfg, "import");

  const fs::path temp = MakeSiblingDirectory(out, "import");
  std::size_t unreadable = 0;
  std::size_t dropped_nonfinite = 0;
  try {
    unreadable = WriteSequence(source.get(), temp, &dropped_nonfinite);
    // An existing SEQ (empty, or --force) moves aside first, so SEQ is never half old, half new.
    std::error_code error;
    if (fs::exists(out, error)) {
      const fs::path old = MakeSiblingDirectory(out, "old");
      fs::rename(out, old / "sequence");
      fs::rename(temp, out);
      fs::remove_all(old, error);
    } else {
      fs::rename(temp, out);
    }
  } catch (const fs::filesystem_error& e) {
    std::error_code ignored;
    fs::remove_all(temp, ignored);
    throw io::IoError(out.string() + ": cannot put the sequence in place (" + e.what() + ")");
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(temp, ignored);
    throw;
  }

  const io::SkippedFrames skipped = source->skipped();
  const std::size_t frames = source->frame_count() - unreadable;
  const nlohmann::json summary = {
      {"out", args.out},
      {"recording", args.recording},
      {"frames", frames},
      {"sensor", source->info().sensor_type == io::SensorType::kCloud ? "cloud" : "stereo"},
      {"groundtruth", source->has_groundtruth()},
      {"gnss_fixes", source->gnss().size()},
      {"dropped_nonfinite", dropped_nonfinite},
      {"skipped",
       {{"outside_pose_span", skipped.outside_pose_span},
        {"unpaired_images", skipped.unpaired_images},
        {"unreadable", unreadable}}}};
  std::cout << summary.dump(2) << "\n";
  return kExitOk;
}

}  // namespace rovermap::apps
