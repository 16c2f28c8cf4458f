// `rovermap eval`: trajectory metrics (--estimate ... --groundtruth) or DEM accuracy (--dem
// --reference) as one JSON object (docs/design.md §8); a thin layer over eval/.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "apps/Commands.hpp"
#include "config/Config.hpp"
#include "eval/DemComparison.hpp"
#include "eval/EvalPlots.hpp"
#include "eval/TrajectoryIo.hpp"
#include "eval/TrajectoryMetrics.hpp"
#include "io/GeoTiff.hpp"
#include "io/IoError.hpp"

namespace rovermap::apps {
namespace {

namespace fs = std::filesystem;

fs::path PlotDirectory(const std::string& dir) {
  std::error_code error;
  fs::create_directories(dir, error);
  if (error || !fs::is_directory(dir, error))
    throw io::IoError(dir + ": cannot create the plot directory (" + error.message() + ")");
  return dir;
}

int RunTrajectories(const EvalArgs& args, const eval::EvalOptions& options) {
  const eval::TrajectoryFormat format = eval::ParseTrajectoryFormat(args.format);
  const eval::Trajectory groundtruth = eval::ReadTrajectory(args.groundtruth, format);
  std::vector<eval::Trajectory> estimates;
  for (const std::string& file : args.estimates)
    estimates.push_back(eval::ReadTrajectory(file, format));

  std::vector<eval::TrajectoryMetrics> metrics;
  nlohmann::json entries = nlohmann::json::array();
  int status = kExitOk;
  for (const eval::Trajectory& estimate : estimates) {
    metrics.push_back(eval::EvaluateTrajectory(estimate, groundtruth, options));
    const eval::TrajectoryMetrics& m = metrics.back();
    nlohmann::json entry = {{"file", estimate.file}, {"format", eval::ToString(estimate.format)}};
    const bool by_timestamp = estimate.has_timestamps() && groundtruth.has_timestamps();
    entry["association"] = by_timestamp ? "timestamp" : "index";
    entry.update(eval::ToJson(m));
    entries.push_back(entry);
    if (m.status != eval::MetricStatus::kOk) {
      std::cerr << "rovermap: eval: " << estimate.file << ": " << m.message << "\n";
      status = kExitFailure;
    }
  }
  nlohmann::json out = {{"groundtruth", groundtruth.file},
                        {"groundtruth_format", eval::ToString(groundtruth.format)},
                        {"options",
                         {{"association_tolerance_s", options.association_tolerance_s},
                          {"rpe_delta_m", options.rpe_delta_m},
                          {"segment_lengths_m", options.segment_lengths_m}}},
                        {"estimates", entries}};
  if (!args.plot_dir.empty()) {
    std::vector<eval::PlotEntry> plot_entries;
    for (std::size_t k = 0; k < metrics.size(); ++k)
      plot_entries.push_back({fs::path(estimates[k].file).filename().string(), &metrics[k]});
    const bool any = std::any_of(metrics.begin(), metrics.end(),
                                 [](const auto& m) { return m.status == eval::MetricStatus::kOk; });
    if (any) {
      const fs::path dir = PlotDirectory(args.plot_dir);
      eval::WriteTrajectoryPlot(dir / "trajectories.png", plot_entries);
      eval::WriteErrorPlot(dir / "error_vs_distance.png", plot_entries);
      out["plots"] = {(dir / "trajectories.png").string(),
                      (dir / "error_vs_distance.png").string()};
    }
  }
  std::cout << out.dump(2) << "\n";
  return status;
}

int RunDem(const EvalArgs& args, const terrain::TerrainOptions& terrain_options) {
  const io::DemRaster dem = io::ReadDemGeoTiff(args.dem);
  const io::DemRaster reference = io::ReadDemGeoTiff(args.reference);
  const eval::DemComparison comparison = eval::CompareDems(dem, reference);
  nlohmann::json out = {{"dem", dem.file}, {"reference", reference.file}};
  out.update(eval::ToJson(comparison));
  if (comparison.status != eval::DemStatus::kOk) {
    std::cerr << "rovermap: eval: " << comparison.message << "\n";
    std::cout << out.dump(2) << "\n";
    return kExitFailure;
  }
  // The planner's view: do both give the same hazards (docs/terrain.md)?
  out["terrain"] = eval::ToJson(eval::CompareTerrain(comparison, terrain_options));
  if (!args.plot_dir.empty()) {
    const fs::path png = PlotDirectory(args.plot_dir) / "dem_error.png";
    eval::WriteDemErrorPlot(png, comparison);
    out["plots"] = {png.string()};
  }
  std::cout << out.dump(2) << "\n";
  return kExitOk;
}

}  // namespace

CLI::App* AddEvalCommand(CLI::App* app, EvalArgs* args) {
  CLI::App* cmd = app->add_subcommand(
      "eval", "Trajectory metrics (ATE, RPE, KITTI segments) or DEM accuracy; prints JSON");
  cmd->add_option("--estimate", args->estimates,
                  "Estimated trajectory, TUM or KITTI (repeatable: one JSON entry each)")
      ->take_all();
  cmd->add_option("--groundtruth", args->groundtruth, "Ground-truth trajectory, TUM or KITTI");
  cmd->add_option("--format", args->format,
                  "Format of the trajectory files: auto (8 columns TUM, 12 KITTI), tum, kitti")
      ->check(CLI::IsMember({"auto", "tum", "kitti"}));
  cmd->add_option("--dem", args->dem, "DEM GeoTIFF to judge (band 1 elevation, band 2 sigma)");
  cmd->add_option("--reference", args->reference, "Reference terrain GeoTIFF (same CRS)");
  cmd->add_option("--plot", args->plot_dir,
                  "Write PNGs into this directory: trajectories.png and error_vs_distance.png, "
                  "or dem_error.png");
  AddConfigOptions(cmd, &args->config);
  cmd->footer(
      "Either --estimate FILE [--estimate FILE ...] --groundtruth FILE, or --dem A.tif\n"
      "--reference B.tif. Config keys: eval.association_tolerance_s, eval.rpe_delta_m,\n"
      "eval.segment_lengths_m.\n"
      "Exit status: 0 evaluated, 1 bad input file (named with its line) or nothing to compare\n"
      "(no associated poses, different CRS, no overlap), 2 usage or config error.\n");
  return cmd;
}

int RunEval(const EvalArgs& args) {
  const config::Config cfg =
      config::LoadConfig(args.config.config_file.empty()
                             ? std::nullopt
                             : std::optional<std::filesystem::path>(args.config.config_file),
                         args.config.overrides);
  const bool trajectories = !args.estimates.empty() || !args.groundtruth.empty();
  const bool dems = !args.dem.empty() || !args.reference.empty();
  if (trajectories && dems)
    throw UsageError(
        "eval: give trajectories (--estimate, --groundtruth) or DEMs (--dem, "
        "--reference), not both");
  if (trajectories) {
    if (args.estimates.empty()) throw UsageError("eval: --groundtruth needs --estimate FILE");
    if (args.groundtruth.empty()) throw UsageError("eval: --estimate needs --groundtruth FILE");
    return RunTrajectories(args, cfg.eval);
  }
  if (dems) {
    if (args.dem.empty()) throw UsageError("eval: --reference needs --dem FILE");
    if (args.reference.empty()) throw UsageError("eval: --dem needs --reference FILE");
    return RunDem(args, cfg.terrain);
  }
  throw UsageError("eval: give --estimate FILE --groundtruth FILE, or --dem FILE --reference FILE");
}

}  // namespace rovermap::apps
