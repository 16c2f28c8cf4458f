// `rovermap replay RECORDING --out DIR`: the whole pipeline over a recorded sequence directory
// or ROS bag.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "apps/Commands.hpp"
#include "config/Config.hpp"
#include "core/Stopwatch.hpp"
#include "io/FileUtil.hpp"
#include "io/FrameSource.hpp"
#include "io/IoError.hpp"
#include "io/ReferenceDem.hpp"
#include "mapper/GnssGraph.hpp"
#include "mapper/GraphRun.hpp"
#include "mapper/Mapper.hpp"
#include "mapper/ReadAhead.hpp"
#include "service/DriftReport.hpp"
#include "service/Outputs.hpp"
#include "service/StatusLine.hpp"

namespace rovermap::apps {
namespace {

using Clock = std::chrono::steady_clock;
using core::MsSince;

// Progress on stderr: a rewritten line on a terminal, one line per frame otherwise.
class Progress {
 public:
  explicit Progress(std::size_t total) : total_(total), tty_(isatty(2) != 0) {}

  void Frame(const mapper::FrameResult& r, double elapsed_ms) {
    const double done = static_cast<double>(r.index + 1);
    const double fps = elapsed_ms > 0.0 ? 1000.0 * done / elapsed_ms : 0.0;
    const double eta_s = fps > 0.0 ? (static_cast<double>(total_) - done) / fps : 0.0;
    std::ostringstream line;
    line << "replay: frame " << r.index + 1 << "/" << total_ << " " << std::fixed
         << std::setprecision(1) << fps << " frames/s, ETA " << std::setprecision(0) << eta_s
         << " s, " << mapper::StatusLine(r);
    if (tty_) {
      std::cerr << "\r" << std::left << std::setw(static_cast<int>(width_)) << line.str()
                << std::flush;
      width_ = std::max(width_, line.str().size());
    } else {
      std::cerr << line.str() << "\n";
    }
  }

  void Done() {
    if (tty_) std::cerr << "\n";
  }

 private:
  std::size_t total_;
  bool tty_;
  std::size_t width_ = 0;
};

// The figures a rover engineer looks at first, on stderr after the run.
void ReportHeadline(const nlohmann::json& s, const std::filesystem::path& out) {
  std::ostringstream line;
  line << std::fixed << std::setprecision(1) << "replay: " << s["frames"].get<std::size_t>()
       << " frames (" << s["registered"].get<std::size_t>() << " registered, "
       << s["partial"].get<std::size_t>() << " of them partly from dead reckoning; "
       << s["fallbacks"].get<std::size_t>() << " fallbacks, " << s["bad_frames"].get<std::size_t>()
       << " bad frames), " << s["distance_m"].get<double>() << " m, "
       << s["frames_per_second"].get<double>() << " frames/s\n";
  if (s.contains("metrics")) {
    auto ate = [&](const char* which, const char* key) {
      const auto& v = s["metrics"][which][key];
      return v.is_number() ? v.get<double>() : std::nan("");
    };
    line << std::setprecision(3) << "replay: position error against the ground truth (ATE, "
         << "aligned at the first pose / SE(3)-aligned): registered "
         << ate("registered", "ate_rmse_origin_m") << " / " << ate("registered", "ate_rmse_m")
         << " m, dead reckoning " << ate("odometry", "ate_rmse_origin_m") << " / "
         << ate("odometry", "ate_rmse_m") << " m\n";
  }
  const bool graph = s.contains("graph") && s["graph"].value("solved", false);
  line << "replay: outputs in " << out.string()
       << ": dem.tif dem.png terrain.tif terrain.png map.bt trajectory.tum "
       << (graph ? "trajectory_f2f.tum " : "") << "odometry.tum drift.csv drift.png summary.json\n";
  std::cerr << line.str();
}

}  // namespace

mapper::PipelineOptions PipelineFrom(const config::Config& cfg) {
  return {cfg.mapper, cfg.registration, cfg.stereo, cfg.dem, cfg.octomap, cfg.terrain};
}

mapper::GraphSetup GraphSetupFrom(const config::Config& cfg) {
  return {cfg.graph, cfg.reference, cfg.revisit, cfg.registration, cfg.mapper};
}

CLI::App* AddReplayCommand(CLI::App* app, ReplayArgs* args) {
  CLI::App* cmd = app->add_subcommand(
      "replay",
      "Run the mapping pipeline over a recorded sequence or ROS bag: registered trajectory, DEM, "
      "OctoMap and drift report");
  cmd->add_option("sequence", args->sequence,
                  "Sequence directory (docs/design.md section 4), ROS 1 bag (.bag) or ROS 2 bag "
                  "(rosbag2 directory, .mcap or .db3); bag options under bag. in the config")
      ->required();
  cmd->add_option("--out", args->out, "Output directory (created)")->required();
  cmd->add_flag("--force", args->force, "Write into a non-empty DIR (its outputs are replaced)");
  cmd->add_option("--reference-dem", args->reference_dem,
                  "Reference DEM (any GeoTIFF GDAL reads, any CRS; band 2 its sigma) the rover's "
                  "DEM is matched against for the pose graph; keys under reference.");
  AddConfigOptions(cmd, &args->config);
  cmd->footer(
      "Writes dem.tif, map.bt, trajectory.tum, odometry.tum, drift.csv, summary.json, dem.png,\n"
      "drift.png, terrain.tif and terrain.png (terrain.enabled) into DIR, each atomically; prints "
      "summary.json on stdout; progress on stderr.\n"
      "Exit status: 0 done (bad frames are skipped and reported), 1 bad sequence or bag, or\n"
      "cannot write, 2 usage or config error.\n");
  return cmd;
}

int RunReplay(const ReplayArgs& args) {
  const auto start = Clock::now();
  const config::Config cfg = LoadConfigArgs(args.config);
  const std::filesystem::path out(args.out);
  CheckOutputDirectory(out, args.force, "overwrite its outputs");
  for (const std::filesystem::path& temp : io::RemoveTemporaryFiles(out)) {
    std::cerr << "replay: removed " << temp.string() << ", left by an interrupted write\n";
  }
  // Opening validates the whole recording (calibration, poses, frame files) before any output.
  const std::unique_ptr<io::FrameSource> source = OpenRecording(args.sequence, cfg, "replay");
  std::unique_ptr<mapper::Mapper> mapper;
  try {
    mapper = std::make_unique<mapper::Mapper>(source->info(), PipelineFrom(cfg));
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError(e.what());
  }

  // The reference DEM: unusable (unreadable, another body, not under the traverse) is reported
  // and left out, unless reference.required.
  std::unique_ptr<io::ReferenceDem> reference;
  std::string reference_unusable;
  if (!args.reference_dem.empty()) {
    try {
      mapper::Validate(cfg.reference);
    } catch (const std::invalid_argument& e) {
      throw config::ConfigError(e.what());
    }
    try {
      reference = std::make_unique<io::ReferenceDem>(
          args.reference_dem, mapper->georeference(),
          io::ReferenceDemOptions{cfg.reference.sigma_band, cfg.reference.sigma_m});
      reference_unusable = mapper::CoverageProblem(*reference, source->odometry());
      if (!reference_unusable.empty()) {
        if (cfg.reference.required) throw io::IoError(reference_unusable);
        reference.reset();
      }
    } catch (const io::IoError& e) {
      if (cfg.reference.required) throw;
      reference_unusable = e.what();
      reference.reset();
    }
    if (!reference) {
      std::cerr << "replay: reference DEM left out (reference.required is false): "
                << reference_unusable << "\n";
    }
  }

  // The graph's sources: the reference's matches and the revisits (loop factors), looked for
  // after each frame.
  std::unique_ptr<mapper::GraphRun> graph_run;
  try {
    graph_run = std::make_unique<mapper::GraphRun>(GraphSetupFrom(cfg), reference.get());
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError(e.what());
  }

  Progress progress(source->frame_count());
  // Frame k+1 is read and prepared (stereo, index, outlier flags) while frame k is registered
  // and fused: on the 2-core machine that fills the cores the matcher leaves idle.
  mapper::ReadAhead ahead(source.get(), mapper.get());
  mapper::ReadAhead::Item item;
  while (ahead.Next(&item)) {
    if (!item.frame) {
      // An unreadable frame never aborts a replay: dead reckoning carries the pose over it.
      const io::StampedPose& odom = source->odometry()[item.index];
      std::optional<Eigen::Isometry3d> truth;
      if (source->has_groundtruth()) truth = source->groundtruth()[item.index].T_world_body;
      const mapper::FrameResult r =
          mapper->SkipFrame(item.index, odom.timestamp, odom.T_world_body,
                            mapper::FallbackReason::kBadFrame, item.error, truth);
      progress.Frame(r, MsSince(start));
      for (const std::string& line : graph_run->AfterFrame(*mapper, {}, "replay"))
        std::cerr << line << "\n";
      continue;
    }
    // The reference DEM's matches and the revisits take the frame's own points (mapper/Patches).
    mapper::FrameBins bins;
    if (graph_run->wants_bins() && item.prepared.loaded.ok) {
      bins = mapper::BinFrame(item.prepared.Fused(), item.prepared.isolated.keep);
    }
    const mapper::FrameResult r =
        mapper->ProcessPrepared(*item.frame, std::move(item.prepared), item.load_ms);
    progress.Frame(r, MsSince(start));
    for (const std::string& line : graph_run->AfterFrame(*mapper, bins, "replay"))
      std::cerr << line << "\n";
  }
  progress.Done();

  // The pose graph over the frames with the GNSS fixes; when it moves the trajectory, the maps
  // are fused again from its poses (a second pass over the recording).
  std::optional<mapper::GraphOutcome> graph;
  try {
    graph = graph_run->Solve(*mapper, source->gnss(), reference_unusable);
  } catch (const std::invalid_argument& e) {
    throw config::ConfigError(e.what());
  }
  if (graph &&
      (graph->fixes > 0 || !graph->reference_matches.empty() || !graph->revisits.empty())) {
    const graph::PoseGraphResult& g = graph->solution;
    std::size_t refused = 0;
    for (const long f : graph->reference_factor) refused += f < 0 ? 1 : 0;
    std::cerr << "replay: pose graph: " << g.fixes_used << " of " << graph->fixes
              << " GNSS fixes used (" << g.fixes_rejected << " rejected, " << graph->unmatched
              << " without a frame), " << g.poses_used << " of " << graph->reference_matches.size()
              << " reference matches used (" << g.poses_rejected << " rejected, " << refused
              << " refused), " << g.loops_used << " of " << graph->revisits.size()
              << " revisits used, " << std::fixed << std::setprecision(0) << g.solve_ms << " ms"
              << (g.solved ? "" : "; kept the frame-to-frame trajectory: " + g.message) << "\n";
    if (g.solved) {
      graph->frames_refused = mapper::RefuseFrames(
          *source, mapper.get(), g.T_world_body, g.covariance, [&](std::size_t k, std::size_t n) {
            if (k == n || k % 10 == 0)
              std::cerr << "replay: fusing the maps again from the pose graph, frame " << k << "/"
                        << n << "\n";
          });
      graph->maps = mapper::GraphOutcome::Maps::kFusedAgain;
    }
  }

  std::filesystem::create_directories(out);
  mapper::RunInfo run;
  run.sequence = args.sequence;
  run.wall_ms = MsSince(start);
  mapper::OutputState state(*mapper);
  state.graph = std::move(graph);
  const nlohmann::json summary = mapper::WriteOutputs(out, state, run, cfg.eval);
  std::cout << summary.dump(2) << "\n";
  ReportHeadline(summary, out);
  return kExitOk;
}

}  // namespace rovermap::apps
